"""Reading motion topics from rosbags (ROS1 ``.bag``, ROS2 sqlite3 / mcap), no ROS needed."""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

from .._infra.atomic import atomic_path, check_replaceable
from .._infra.folders import CACHE_DIR_ENV, cache_dir, example_data_dirs
from .._infra.progress import progress_bar
from ..io._files import FileFormatError, load_netcdf
from ..io._schema import motion_dataset
from ._messages import (
    KINDS,
    SUPPORTED_TYPES,
    TF_TYPES,
    Messages,
    TfPair,
    check_messages,
    check_tf,
    decode_objects,
    decode_raw,
    ros1_type_name,
    split_tf,
)

if TYPE_CHECKING:
    import xarray as xr

# decoding goes at ~1 µs per message on the fast path and ~25 µs per message
# otherwise: from this many messages on, a load shows a progress bar
LARGE_TOPIC = 100_000
_READ_BATCH = 4096


class RosbagReader:
    """Reader for motion topics of a rosbag.

    Works as a context manager (``with RosbagReader(path) as reader: ...``),
    which keeps the bag open across calls; outside of one, each call opens
    and closes the bag itself.

    Parameters
    ----------
    bag_file : str or path-like
        A ROS1 ``.bag`` file, a ROS2 bag folder (with ``metadata.yaml``), or a
        single ROS2 ``.db3`` / ``.mcap`` storage file.

    Notes
    -----
    Readable message types: ``geometry_msgs/TransformStamped``,
    ``nav_msgs/Odometry`` and ``geometry_msgs/PoseStamped`` by topic
    (:meth:`load_messages`, :meth:`load_dataset`), and the tf tree of
    ``tf2_msgs/TFMessage`` on ``/tf`` and ``/tf_static`` (:meth:`load_tf`).
    Timestamps come from each message's header stamp, messages stay in
    recording order.
    """

    def __init__(self, bag_file: str | os.PathLike):
        self.bag_file = Path(bag_file)
        self._reader = None

    def __repr__(self) -> str:
        state = "open" if self._reader is not None else "closed"
        return f"RosbagReader({str(self.bag_file)!r}, {state})"

    def __enter__(self) -> RosbagReader:
        if self._reader is not None:
            raise RuntimeError(f"{self!r} is already open")
        self._reader = self._open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc_val: BaseException | None,
        exc_tb: TracebackType | None,
    ) -> None:
        reader, self._reader = self._reader, None
        if reader is not None:
            reader.close()

    def _open(self):
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        if not self.bag_file.exists():
            raise FileNotFoundError(f"rosbag {self.bag_file} does not exist")
        try:
            # bags without message definitions (old ROS2 ones) decode with Humble's
            reader = AnyReader(
                [self.bag_file], default_typestore=get_typestore(Stores.ROS2_HUMBLE)
            )
            reader.open()
        except Exception as err:  # rosbags raises many kinds for damaged files
            raise FileFormatError(
                f"{self.bag_file} is not a readable rosbag: {err}"
            ) from err
        return reader

    @contextmanager
    def _session(self) -> Iterator:
        if self._reader is not None:
            yield self._reader
            return
        reader = self._open()
        try:
            yield reader
        finally:
            reader.close()

    def get_topics_and_types(self) -> dict[str, str]:
        """Topics in the bag and their message types (ROS1 spelling).

        Returns
        -------
        dict
            ``{topic: "package/Type"}``, e.g. ``{"/t265/transform":
            "geometry_msgs/TransformStamped"}``.
        """
        with self._session() as reader:
            return {
                topic: ros1_type_name(info.msgtype)
                if info.msgtype
                else "(several types)"
                for topic, info in reader.topics.items()
            }

    def load_messages(self, topic: str, *, progress: bool | None = None) -> dict:
        """Load the messages of a topic as arrays.

        Parameters
        ----------
        topic : str
            Name of the topic.
        progress : bool, optional
            Show a progress bar (True), never (False) or for large topics
            only (None, the default).

        Returns
        -------
        dict
            ``timestamps`` (n,) header stamps in float seconds, ``position``
            (n, 3) and ``orientation`` (n, 4) w, x, y, z; for
            ``nav_msgs/Odometry`` also ``linear_velocity`` and
            ``angular_velocity`` (n, 3), as the message's twist. An empty
            topic gives arrays with n = 0.

        Raises
        ------
        ValueError
            If the topic is not in the bag (the message lists the topics) or
            its message type is not supported (the message lists those).
        rbm_nb.io.FileFormatError
            If the bag is damaged, including decoded values no bag should
            hold: a pose field partly NaN or infinite (all NaN is a sample
            without data), a non-unit quaternion, a stamp with 1e9 ns or
            more. The message names the topic and the message index.
        """
        messages, _ = self._read(topic, progress)
        out = {
            "timestamps": messages.timestamps,
            "position": messages.position,
            "orientation": messages.orientation,
        }
        linear, angular = messages.linear_velocity, messages.angular_velocity
        if linear is not None and angular is not None:  # both or neither
            out["linear_velocity"] = linear
            out["angular_velocity"] = angular
        return out

    def _read(self, topic: str, progress: bool | None) -> tuple[Messages, str]:
        with self._session() as reader:
            name = self._message_type(reader, topic)
            connections = [c for c in reader.connections if c.topic == topic]
            count = sum(c.msgcount for c in connections)
            raws = []
            try:
                with progress_bar(
                    count, topic, progress=progress, threshold=LARGE_TOPIC
                ) as bar:
                    for i, (_, _, raw) in enumerate(
                        reader.messages(connections=connections)
                    ):
                        raws.append(raw)
                        if i % _READ_BATCH == _READ_BATCH - 1:
                            bar.update(_READ_BATCH)
                    bar.update(len(raws) % _READ_BATCH)
                messages = decode_raw(raws, KINDS[name], reader.is2)
                if messages is None:  # layouts differ: rosbags decodes each message
                    typename = connections[0].msgtype
                    msgs = [reader.deserialize(raw, typename) for raw in raws]
                    messages = decode_objects(msgs, name)
            except Exception as err:  # rosbags raises many kinds for damaged bags
                raise FileFormatError(
                    f"{self.bag_file} is damaged: reading {topic!r} failed after "
                    f"{len(raws)} of {count} messages ({type(err).__name__}: {err})"
                ) from err
        check_messages(messages, f"{self.bag_file}, topic {topic!r}")
        return messages, name

    def _message_type(self, reader, topic: str) -> str:
        topics = reader.topics
        if topic not in topics:
            close = difflib.get_close_matches(topic, topics, n=3)
            hint = f" Did you mean {' or '.join(map(repr, close))}?" if close else ""
            raise ValueError(
                f"topic {topic!r} is not in {self.bag_file}.{hint} "
                f"Available topics: {sorted(topics)}"
            )
        msgtype = topics[topic].msgtype
        if msgtype is None:
            types = sorted(
                {
                    ros1_type_name(c.msgtype)
                    for c in reader.connections
                    if c.topic == topic
                }
            )
            raise ValueError(
                f"topic {topic!r} in {self.bag_file} mixes message types {types}"
            )
        name = ros1_type_name(msgtype)
        if name in TF_TYPES:
            raise ValueError(
                f"topic {topic!r} carries tf messages ({name}), several transforms each; "
                "read them with RosbagReader.load_tf, which splits them per "
                "parent/child pair"
            )
        if name not in KINDS:
            raise ValueError(
                f"topic {topic!r} has message type {name}, which RosbagReader cannot load; "
                f"supported types: {', '.join(SUPPORTED_TYPES)}"
            )
        return name

    def load_tf(
        self, topics: Sequence[str] | None = None, *, progress: bool | None = None
    ) -> dict:
        """Every transform of every tf message, split per parent/child pair.

        Parameters
        ----------
        topics : sequence of str, optional
            tf topics to read (type ``tf2_msgs/TFMessage``). Default: those of
            ``/tf`` and ``/tf_static`` that are in the bag. Topics whose name
            ends in ``_static`` hold static transforms.
        progress : bool, optional
            See :meth:`load_messages`.

        Returns
        -------
        dict
            ``{(frame_id, child_frame_id): TfPair}``. A ``TfPair`` has
            ``static`` (bool), ``stamps_ns`` (n,) int64 and ``timestamps`` (n,)
            float seconds, ``position`` (n, 3), ``orientation`` (n, 4) w, x, y,
            z and ``message_index`` (n,). Moving pairs are sorted by stamp
            (of equal stamps the last received is kept, as tf2 does); a
            static pair has one transform, the last one sent.

        Raises
        ------
        ValueError
            If a topic is missing or not a tf topic, no tf topic is in the
            bag, or a pair is both static and moving.
        rbm_nb.io.FileFormatError
            If the bag is damaged (the message names topic and message index).
        """
        with self._session() as reader:
            if topics is None:
                topics = [t for t in ("/tf", "/tf_static") if t in reader.topics]
                if not topics:
                    raise ValueError(
                        f"{self.bag_file} has no /tf or /tf_static topic; its topics: "
                        f"{sorted(reader.topics)}"
                    )
            elif isinstance(topics, str):
                topics = [topics]
            pairs: dict = {}
            for topic in topics:
                self._check_tf_topic(reader, topic)
                static = topic.endswith("_static")
                msgs = self._deserialize_all(reader, topic, progress)
                for key, (pair, nsec, index) in split_tf(msgs, static).items():
                    check_tf(pair, nsec, index, f"{self.bag_file}, topic {topic!r}")
                    if key in pairs and pairs[key].static != static:
                        raise ValueError(
                            f"{self.bag_file}: the transform {key[0]} -> {key[1]} is both "
                            "static and moving"
                        )
                    pairs[key] = (
                        pair if key not in pairs or static else _merge(pairs[key], pair)
                    )
        return pairs

    def _check_tf_topic(self, reader, topic: str) -> None:
        if topic not in reader.topics:
            raise ValueError(
                f"topic {topic!r} is not in {self.bag_file}; topics: {sorted(reader.topics)}"
            )
        msgtype = reader.topics[topic].msgtype
        if msgtype is None or ros1_type_name(msgtype) not in TF_TYPES:
            raise ValueError(
                f"topic {topic!r} has message type {msgtype and ros1_type_name(msgtype)}, "
                f"not a tf message type ({', '.join(TF_TYPES)})"
            )

    def _deserialize_all(self, reader, topic: str, progress) -> list:
        connections = [c for c in reader.connections if c.topic == topic]
        count = sum(c.msgcount for c in connections)
        msgs = []
        try:
            with progress_bar(
                count, topic, progress=progress, threshold=LARGE_TOPIC
            ) as bar:
                for connection, _, raw in reader.messages(connections=connections):
                    msgs.append(reader.deserialize(raw, connection.msgtype))
                    bar.update(1)
        except Exception as err:  # rosbags raises many kinds for damaged bags
            raise FileFormatError(
                f"{self.bag_file} is damaged: reading {topic!r} failed after "
                f"{len(msgs)} of {count} messages ({type(err).__name__}: {err})"
            ) from err
        return msgs

    def load_dataset(
        self, topic: str, cache: bool = False, *, progress: bool | None = None
    ) -> xr.Dataset:
        """Load the messages of a topic as an :class:`xarray.Dataset`.

        Parameters
        ----------
        topic : str
            Name of the topic.
        cache : bool, default False
            Keep the dataset in ``cache/<topic>.nc`` beside the bag (slashes in
            the topic become underscores) and read it from there next time;
            for a bag in the example-data folder (``RBM_NB_DATA_DIR``), in
            rbm_nb's cache folder instead (see :meth:`cache_file`). A cache
            made from another bag or from an older version of this bag is
            rebuilt.
        progress : bool, optional
            See :meth:`load_messages`.

        Returns
        -------
        xarray.Dataset
            ``position`` (time, cartesian_axis), ``orientation`` (time,
            quaternion_axis), for odometry ``linear_velocity`` and
            ``angular_velocity``; ``time`` is datetime64[ns], exact to the
            nanosecond of the header stamps. attrs name the bag, topic,
            message type and frame ids.

        Raises
        ------
        rbm_nb.io.FileFormatError
            If the bag or the cache file is damaged.
        """
        if not cache:
            return self._dataset(topic, progress)
        path = self.cache_file(topic)
        if path.exists():
            ds = load_netcdf(path, hint="delete it and it will be rebuilt from the bag")
            if ds.attrs.get("bag_fingerprint") == self._fingerprint():
                return ds
        try:
            return self._export(topic, path, progress)
        except OSError as err:
            raise _cache_error(err, path) from None

    def cache_file(self, topic: str) -> Path:
        """Where :meth:`load_dataset` caches ``topic``.

        ``cache/<topic>.nc`` beside the bag, as rigid-body-motion does; but
        never in the example-data folder, which holds only the registry's
        files: a bag there is cached under ``rosbag/<bag name>-<path hash>/``
        in :func:`rbm_nb._infra.folders.cache_dir` (``RBM_NB_CACHE_DIR``).
        """
        name = f"{topic.replace('/', '_')}.nc"
        folder = self.bag_file.parent.resolve()

        if any(folder == d or d in folder.parents for d in example_data_dirs()):
            import hashlib

            key = hashlib.sha1(str(self.bag_file.resolve()).encode()).hexdigest()[:12]
            return cache_dir() / "rosbag" / f"{self.bag_file.name}-{key}" / name
        return self.bag_file.parent / "cache" / name

    def export(self, topic: str, output_file: str | os.PathLike | None = None) -> Path:
        """Write the messages of a topic to a netCDF4 file.

        Parameters
        ----------
        topic : str
            Name of the topic.
        output_file : str or path-like, optional
            Path of the file; by default the bag's path with the extension
            ``.nc``. Written atomically: a failure leaves no file behind and
            an existing file unchanged. Values are stored losslessly
            (float64, zlib-compressed).

        Returns
        -------
        pathlib.Path
            The path written.

        Raises
        ------
        IsADirectoryError
            ``output_file`` is a folder (it is never replaced).
        """
        path = (
            self.bag_file.with_suffix(".nc")
            if output_file is None
            else Path(output_file)
        )
        check_replaceable(path)  # a folder there is the user's: refuse before reading
        self._export(topic, path, None)
        return path

    def _export(self, topic: str, path: Path, progress: bool | None):
        ds = self._dataset(topic, progress)
        encoding = {name: {"zlib": True, "complevel": 4} for name in ds.data_vars}
        with atomic_path(path) as tmp:
            ds.to_netcdf(tmp, engine="netcdf4", encoding=encoding)
        return ds

    def _dataset(self, topic: str, progress: bool | None):
        messages, msgtype = self._read(topic, progress)
        variables = {"position": messages.position, "orientation": messages.orientation}
        linear, angular = messages.linear_velocity, messages.angular_velocity
        if linear is not None and angular is not None:  # both or neither
            variables["linear_velocity"] = linear
            variables["angular_velocity"] = angular
        attrs = {
            "bag": self.bag_file.name,
            "topic": topic,
            "message_type": msgtype,
            "frame_id": messages.frame_id,
            "child_frame_id": messages.child_frame_id,
            "bag_fingerprint": self._fingerprint(),
        }
        return motion_dataset(
            messages.stamps_ns.astype("datetime64[ns]"), variables, attrs
        )

    def _fingerprint(self) -> str:
        """Name, sizes and modification times of the bag's files."""
        files = (
            sorted(self.bag_file.iterdir())
            if self.bag_file.is_dir()
            else [self.bag_file]
        )
        parts = [
            f"{f.name}:{f.stat().st_size}:{f.stat().st_mtime_ns}"
            for f in files
            if f.is_file()
        ]
        return ";".join(parts)


def _merge(a, b):
    """One moving pair from two tf topics: sorted by stamp, later topic wins."""
    import numpy as np

    stamps = np.concatenate([a.stamps_ns, b.stamps_ns])
    order = np.argsort(stamps, kind="stable")
    _, last = np.unique(stamps[order][::-1], return_index=True)
    keep = order[len(order) - 1 - last]
    return TfPair(
        a.frame_id, a.child_frame_id, a.static, stamps[keep],
        np.concatenate([a.position, b.position])[keep],
        np.concatenate([a.orientation, b.orientation])[keep],
        np.concatenate([a.message_index, b.message_index])[keep],
    )  # fmt: skip


def _cache_error(err: OSError, path: Path) -> OSError:
    """``err`` from writing a cache file, saying which setting chose the folder."""
    if err.errno is None or not os.environ.get(CACHE_DIR_ENV):
        return err
    folder = cache_dir()
    if folder != path and folder not in path.parents:
        return err
    return type(err)(
        err.errno,
        f"cannot write the cache of this bag in {CACHE_DIR_ENV}={str(folder)!r} "
        f"({err.strerror or err}); set {CACHE_DIR_ENV} to a writable folder, or "
        "pass cache=False",
        str(path),
    )
