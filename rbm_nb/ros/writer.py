"""Writing motion topics to rosbags (ROS1 ``.bag`` or a ROS2 bag folder), no ROS needed."""

from __future__ import annotations

import os
from collections.abc import Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .._door.xarray import dataset_variable
from .._engine.time import ns_keys
from .._infra.atomic import FolderKind, atomic_path, check_replaceable, scratch_target
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from ._messages import (
    TF_MESSAGE,
    TRANSFORM_STAMPED,
    encode_transform_stamped,
    register_tf_message,
    rosbags_type_name,
    tf_message,
)

if TYPE_CHECKING:
    import xarray as xr
    from rosbags.rosbag1 import Writer as Ros1Writer
    from rosbags.rosbag2 import Writer as Ros2Writer
    from rosbags.typesys.store import Typestore

STORAGES = ("sqlite3", "mcap")
_MAX_NAME_BYTES = 255  # of one file name, on the usual file systems
_SQLITE_MAX_PATH = 512  # SQLITE_MAX_PATHNAME, sqlite's limit on a file's path
_MAX_SEC = {False: 2**32, True: 2**31}  # ROS1 stamps are uint32 s, ROS2 int32 s


# what rosbag2 (and the rosbags library) put in a bag folder
_ROS2_STORAGE_SUFFIXES = (".db3", ".db3-shm", ".db3-wal", ".mcap", ".zstd")


def is_ros2_bag_folder(path: Path) -> bool:
    """Whether ``path`` is a ROS2 bag folder and nothing else.

    It must hold a ``metadata.yaml`` that describes a bag and otherwise only
    storage files: a folder with anything more (notes, a thesis) is the
    user's, and a writer must not replace it.
    """
    try:
        entries = list(os.scandir(path))
        metadata = (path / "metadata.yaml").read_text(errors="replace")
    except OSError:
        return False
    if "rosbag2_bagfile_information" not in metadata:
        return False
    return all(
        entry.name == "metadata.yaml"
        or (
            entry.is_file(follow_symlinks=False)
            and entry.name.endswith(_ROS2_STORAGE_SUFFIXES)
        )
        for entry in entries
    )


ROS2_BAG = FolderKind(
    "a ROS2 bag folder holding only metadata.yaml and storage files", is_ros2_bag_folder
)


class RosbagWriter:
    """Writer for motion topics to a rosbag.

    Use it as a context manager. Everything goes to a temporary file beside
    the target, which replaces the target only when the ``with`` block ends
    without an error: a failure never leaves a half-written bag, and an
    existing bag at the target is untouched until then.

    An existing ROS2 bag folder at the target is replaced (once the new one is
    complete); any other folder, and a file where a ROS2 bag folder would go,
    is refused with an error before anything is written.

    Parameters
    ----------
    bag_file : str or path-like
        A path ending in ``.bag`` makes a ROS1 bag; anything else a ROS2 bag
        folder.
    storage : {"sqlite3", "mcap"}, optional
        Storage of a ROS2 bag (default "sqlite3"); not for ROS1 bags.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "walk.bag"
    >>> with RosbagWriter(path) as writer:
    ...     writer.write_transform_stamped(
    ...         [1.0, 2.0], np.zeros((2, 3)), [[1, 0, 0, 0]] * 2, "/tf_walk", "world", "head"
    ...     )
    >>> path.exists()
    True
    """

    def __init__(self, bag_file: str | os.PathLike, *, storage: str | None = None):
        self.bag_file = Path(bag_file)
        self.ros2 = self.bag_file.suffix != ".bag"
        if storage is not None and not self.ros2:
            raise ValueError(
                f"storage is for ROS2 bags; {self.bag_file} (.bag) is a ROS1 bag"
            )
        if storage is not None and storage not in STORAGES:
            raise ValueError(f"storage must be one of {STORAGES}, got {storage!r}")
        self.storage = (storage or "sqlite3") if self.ros2 else None
        if self.ros2:
            self._check_path_length()
        # refuse a folder (or file) it must not replace now, not after the work
        check_replaceable(self.bag_file, ROS2_BAG if self.ros2 else None)
        self._atomic: AbstractContextManager[Path] | None = None
        self._writer: Ros1Writer | Ros2Writer | None = None
        self._typestore: Typestore | None = None
        self._connections: dict[tuple[str, str], Any] = {}

    def _check_path_length(self) -> None:
        """Refuse a ROS2 bag whose storage file the storage cannot open.

        The files inside are named after the folder (``<name>.mcap``, or
        ``<name>.db3`` plus up to 12 bytes sqlite adds for its journal), and
        sqlite opens no path longer than 512 bytes; while writing, the bag
        sits in a scratch folder beside the target.
        """
        name = self.bag_file.name
        inside = scratch_target(self.bag_file)
        if self.storage == "mcap":
            longest = [f"{name}.mcap"]
        else:
            longest = [f"{name}.db3-journal"]
        for entry in longest:
            size = len(os.fsencode(entry))
            if size > _MAX_NAME_BYTES:
                raise ValueError(
                    f"the ROS2 bag folder name {name!r} is too long ({len(os.fsencode(name))} "
                    f"bytes): the {self.storage} file {entry!r} inside would be {size} "
                    f"bytes, file systems allow {_MAX_NAME_BYTES}"
                )
        if self.storage == "sqlite3":
            path = len(os.fsencode(str(inside / longest[0])))
            if path > _SQLITE_MAX_PATH:
                raise ValueError(
                    f"the path of the ROS2 bag {str(self.bag_file)!r} is too long for "
                    f"sqlite3 storage: its database file would be at a path of "
                    f"{path} bytes while writing, sqlite opens at most "
                    f"{_SQLITE_MAX_PATH}; use a shorter name or folder, or "
                    "storage='mcap'"
                )

    def __repr__(self) -> str:
        state = "open" if self._writer is not None else "closed"
        return f"RosbagWriter({str(self.bag_file)!r}, {state})"

    def __enter__(self) -> RosbagWriter:
        from rosbags.typesys import Stores, get_typestore

        if self._writer is not None:
            raise RuntimeError(f"{self!r} is already open")
        self._typestore = get_typestore(
            Stores.ROS2_HUMBLE if self.ros2 else Stores.ROS1_NOETIC
        )
        register_tf_message(self._typestore)
        kind = ROS2_BAG if self.ros2 else None
        self._atomic = atomic = atomic_path(self.bag_file, folder_kind=kind)
        tmp = atomic.__enter__()
        try:
            self._writer = writer = self._make_writer(tmp)
            writer.open()
        except BaseException as err:
            self._writer = None
            atomic.__exit__(type(err), err, err.__traceback__)
            raise
        return self

    def _make_writer(self, path: Path) -> Ros1Writer | Ros2Writer:
        if not self.ros2:
            from rosbags.rosbag1 import Writer as Ros1Writer

            return Ros1Writer(path)
        from rosbags.rosbag2 import StoragePlugin
        from rosbags.rosbag2 import Writer as Ros2Writer

        plugin = StoragePlugin.MCAP if self.storage == "mcap" else StoragePlugin.SQLITE3
        return Ros2Writer(
            path, version=Ros2Writer.VERSION_LATEST, storage_plugin=plugin
        )

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc_val: BaseException | None,
        exc_tb: TracebackType | None,
    ) -> None:
        writer, atomic = self._writer, self._atomic
        if writer is None or atomic is None:
            raise RuntimeError(f"{self!r} is not open")
        self._writer = self._atomic = None
        self._connections = {}
        try:
            if exc_type is None:
                writer.close()
            else:
                writer.abort()
        except BaseException as err:
            atomic.__exit__(type(err), err, err.__traceback__)
            raise
        # commits the temporary bag on success, discards it otherwise
        atomic.__exit__(exc_type, exc_val, exc_tb)

    def _connection(self, topic: str, msgtype: str):
        key = (topic, msgtype)
        if key not in self._connections:
            self._connections[key] = self._check_open().add_connection(
                topic, rosbags_type_name(msgtype), typestore=self._store()
            )
        return self._connections[key]

    def write_transform_stamped(
        self,
        timestamps: npt.ArrayLike,
        translation: npt.ArrayLike,
        rotation: npt.ArrayLike,
        topic: str,
        frame: str,
        child_frame: str,
    ) -> None:
        """Write ``geometry_msgs/TransformStamped`` messages.

        Parameters
        ----------
        timestamps : array_like, shape (n,)
            Header stamps: float seconds since the epoch, or datetime64.
            Also used as the bag's record times.
        translation : array_like, shape (n, 3)
            Translations (x, y, z).
        rotation : array_like, shape (n, 4)
            Rotations as unit quaternions (w, x, y, z); written as they are.

            A row of ``translation`` or ``rotation`` that is all NaN is a
            sample without data (as in real eye-tracking recordings): it is
            written as NaN and read back bit for bit.
        topic : str
            Topic of the messages.
        frame : str
            Parent frame (``header.frame_id``).
        child_frame : str
            Child frame (``child_frame_id``).

        Raises
        ------
        ValueError
            If shapes do not match, a row is partly NaN or has an infinity,
            the stamps are not strictly increasing, a stamp is before 1970 or
            beyond what the bag format can hold, or a rotation is not a unit
            quaternion (within ``UNIT_QUATERNION_TOLERANCE``). The message
            names the topic and the row.
        RuntimeError
            If called outside the ``with`` block.

        Notes
        -----
        Rotations within the tolerance are written as given, bit for bit, so
        that a bag written from a recording reads back identical (recorded
        quaternions are often unit only to float32 precision); rbm_nb's
        transforms and interpolated lookups and ROS's tf normalise them when
        they use them, and a lookup at a frame's own times returns them as
        stored (as rigid-body-motion does).
        """
        self._check_open()
        if not isinstance(topic, str):
            raise ValueError(f"topic must be a str, got {topic!r}")
        if not topic:
            raise ValueError("topic must not be empty")
        stamps, translation, rotation = self._checked_rows(
            timestamps, translation, rotation, topic, frame, child_frame
        )
        rows = encode_transform_stamped(
            stamps, translation, rotation, frame, child_frame, self.ros2
        )
        connection = self._connection(topic, TRANSFORM_STAMPED)
        write = self._check_open().write
        for stamp, row in zip(stamps.tolist(), rows, strict=True):
            write(connection, stamp, row.tobytes())

    def _check_open(self) -> Ros1Writer | Ros2Writer:
        """The open bag writer; a RuntimeError outside the ``with`` block."""
        if self._writer is None:
            raise RuntimeError(
                "RosbagWriter writes inside a with block: "
                f"with RosbagWriter({str(self.bag_file)!r}) as writer: ..."
            )
        return self._writer

    def _store(self) -> Typestore:
        # set in __enter__ before the writer, so an open writer implies it
        if self._typestore is None:
            self._check_open()
            raise RuntimeError(f"{self!r} has no type store")
        return self._typestore

    def write_tf(
        self,
        timestamps: npt.ArrayLike,
        translation: npt.ArrayLike,
        rotation: npt.ArrayLike,
        frame: str,
        child_frame: str,
        *,
        static: bool = False,
    ) -> None:
        """Write transforms of one parent/child pair as tf messages.

        Each row becomes one ``tf2_msgs/TFMessage`` holding one transform, on
        ``/tf`` (or ``/tf_static`` with ``static=True``), as a tf broadcaster
        sends them. Several pairs may be written to the same bag.

        Parameters
        ----------
        timestamps : array_like, shape (n,)
            Header stamps: float seconds since the epoch, or datetime64;
            strictly increasing.
        translation : array_like, shape (n, 3)
        rotation : array_like, shape (n, 4)
            Unit quaternions w, x, y, z.
        frame, child_frame : str
            ``header.frame_id`` and ``child_frame_id``.
        static : bool, default False
            Write to ``/tf_static`` (then usually n = 1).

        Raises
        ------
        ValueError
            As :meth:`write_transform_stamped`.
        """
        self._check_open()
        topic = "/tf_static" if static else "/tf"
        stamps, translation, rotation = self._checked_rows(
            timestamps, translation, rotation, topic, frame, child_frame
        )
        connection = self._connection(topic, TF_MESSAGE)
        serialize = self._serializer()
        for i, stamp in enumerate(stamps.tolist()):
            msg = tf_message(
                self._store(), [stamp], [frame], [child_frame],
                translation[i : i + 1], rotation[i : i + 1],
            )  # fmt: skip
            self._check_open().write(connection, stamp, serialize(msg))

    def write_tf_message(
        self,
        transforms: Sequence[tuple[Any, str, str, npt.ArrayLike, npt.ArrayLike]],
        *,
        static: bool = False,
    ) -> None:
        """Write one tf message holding several transforms.

        Parameters
        ----------
        transforms : sequence of tuple
            ``(timestamp, frame, child_frame, translation, rotation)`` per
            transform: seconds or datetime64, two str, (3,) and (4,) w, x, y, z.
        static : bool, default False
            Write to ``/tf_static`` instead of ``/tf``.
        """
        self._check_open()
        topic = "/tf_static" if static else "/tf"
        if not transforms:
            raise ValueError(
                f"topic {topic!r}: a tf message needs at least one transform"
            )
        rows = []
        for k, item in enumerate(transforms):
            if len(item) != 5:
                raise ValueError(
                    f"topic {topic!r}: transform {k} must be (timestamp, frame, "
                    f"child_frame, translation, rotation), got {item!r}"
                )
            stamp, frame, child, t, r = item
            one_stamp, one_t, one_r = self._checked_rows(
                np.asarray([stamp]), np.asarray(t, float).reshape(1, -1),
                np.asarray(r, float).reshape(1, -1), topic, frame, child,
            )  # fmt: skip
            rows.append((int(one_stamp[0]), frame, child, one_t[0], one_r[0]))
        stamps, frames, children, ts, rs = zip(*rows, strict=True)
        msg = tf_message(self._store(), stamps, frames, children, ts, rs)
        self._check_open().write(
            self._connection(topic, TF_MESSAGE), max(stamps), self._serializer()(msg)
        )

    def _serializer(self):
        store = self._store()
        typename = "tf2_msgs/msg/TFMessage"
        if self.ros2:
            return lambda msg: bytes(store.serialize_cdr(msg, typename))
        return lambda msg: bytes(store.serialize_ros1(msg, typename))

    def _checked_rows(
        self, timestamps, translation, rotation, topic, frame, child
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        for name, value in (("frame", frame), ("child_frame", child)):
            if not isinstance(value, str):
                raise ValueError(
                    f"topic {topic!r}: {name} must be a str, got {value!r}"
                )
        stamps = self._stamps_ns(timestamps, topic)
        n = stamps.shape[0]
        translation = _rows(translation, "translation", n, 3, topic)
        rotation = _rows(rotation, "rotation", n, 4, topic)
        _check_unit(rotation, topic)
        return stamps, translation, rotation

    def write_transform_stamped_dataset(
        self,
        ds: xr.Dataset,
        topic: str,
        frame: str,
        child_frame: str,
        timestamps: str = "time",
        translation: str = "position",
        rotation: str = "orientation",
    ) -> None:
        """Write a dataset as ``geometry_msgs/TransformStamped`` messages.

        Parameters
        ----------
        ds : xarray.Dataset
            Dataset with timestamps, translation and rotation.
        topic, frame, child_frame : str
            As in :meth:`write_transform_stamped`.
        timestamps : str, default "time"
            Name of the coordinate with the timestamps (datetime64 or float s).
        translation : str, default "position"
            Name of the (time, 3) translation variable.
        rotation : str, default "orientation"
            Name of the (time, 4) rotation variable (w, x, y, z).
        """
        for argument, name in (
            ("timestamps", timestamps),
            ("translation", translation),
            ("rotation", rotation),
        ):
            dataset_variable(ds, name, argument)  # raises, naming what is missing
        time_dim = ds[timestamps].dims[0]
        translation, rotation = (
            ds[name].transpose(time_dim, ...).values for name in (translation, rotation)
        )
        self.write_transform_stamped(
            ds[timestamps].values, translation, rotation, topic, frame, child_frame
        )

    def _stamps_ns(self, timestamps, topic: str) -> np.ndarray:
        ns = self._stamps_ns_unchecked(timestamps)
        back = np.flatnonzero(np.diff(ns) <= 0)
        if back.size:
            i = int(back[0]) + 1
            raise ValueError(
                f"topic {topic!r}: timestamps must be strictly increasing; stamp {i} "
                f"({ns[i]} ns) is not after stamp {i - 1} ({ns[i - 1]} ns)"
            )
        return ns

    def _stamps_ns_unchecked(self, timestamps) -> np.ndarray:
        stamps = np.asarray(timestamps)
        if stamps.ndim != 1:
            raise ValueError(
                f"timestamps must be one-dimensional, got shape {stamps.shape}"
            )
        if np.issubdtype(stamps.dtype, np.datetime64):
            if np.isnat(stamps).any():
                raise ValueError(
                    f"timestamps contain NaT at index {int(np.flatnonzero(np.isnat(stamps))[0])}"
                )
            ns = ns_keys(stamps, "timestamps")
        else:
            try:
                seconds = stamps.astype(np.float64)
            except (TypeError, ValueError):
                raise ValueError(
                    f"timestamps must be float seconds or datetime64, got dtype {stamps.dtype}"
                ) from None
            if not np.isfinite(seconds).all():
                raise ValueError(
                    f"timestamps must be finite; index {int(np.flatnonzero(~np.isfinite(seconds))[0])} is not"
                )
            if seconds.size and seconds.max() >= _MAX_SEC[self.ros2]:
                raise ValueError(
                    "timestamps must be seconds since 1970 that the bag format can hold"
                )
            # nearest ns: reading back sec + nsec / 1e9 gives the same float
            sec = np.floor(seconds)
            ns = sec.astype(np.int64) * 1_000_000_000 + np.round(
                (seconds - sec) * 1e9
            ).astype(np.int64)
        if ns.size and (
            ns.min() < 0 or ns.max() // 1_000_000_000 >= _MAX_SEC[self.ros2]
        ):
            raise ValueError(
                "timestamps must lie between 1970 and the largest time the bag format can hold "
                f"({_MAX_SEC[self.ros2]} s)"
            )
        return ns


def _rows(values, name: str, n: int, width: int, topic: str) -> np.ndarray:
    """Rows that are all finite (data) or all NaN (no data at that sample)."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape != (n, width):
        raise ValueError(
            f"topic {topic!r}: {name} must have shape ({n}, {width}) to match "
            f"timestamps, got {arr.shape}"
        )
    finite = np.isfinite(arr).all(axis=1)
    missing = np.isnan(arr).all(axis=1)
    bad = np.flatnonzero(~(finite | missing))
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"topic {topic!r}: {name} row {i} is {arr[i].tolist()}; a row must be all "
            "finite, or all NaN for a sample without data"
        )
    return arr


def _check_unit(rotation: np.ndarray, topic: str) -> None:
    present = np.isfinite(rotation).all(axis=1)
    with np.errstate(over="ignore"):  # huge values give an inf norm, refused below
        norm_error = np.abs(np.linalg.norm(rotation[present], axis=1) - 1.0)
    if norm_error.size and norm_error.max() > UNIT_QUATERNION_TOLERANCE:
        i = int(
            np.flatnonzero(present)[np.argmax(norm_error > UNIT_QUATERNION_TOLERANCE)]
        )
        raise ValueError(
            f"topic {topic!r}: rotation must be unit quaternions (w, x, y, z); "
            f"row {i} has norm {np.linalg.norm(rotation[i]):.6g}"
        )
