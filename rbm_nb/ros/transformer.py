"""A tf2-style transform buffer that needs no ROS: ``rbm.ros.Transformer``.

The buffer keeps, for every child frame, its parent and either one static
transform or a time series of transforms (at most ``cache_time`` seconds of
it). Lookups build rbm_nb reference frames from that data (a private tree,
never the global registry) and evaluate the chain at the requested time with
rbm_nb's core: translations are interpolated linearly and rotations by squad,
frames that came from discrete reference frames hold their last value.

Conventions follow tf2:

* ``lookup_transform(target_frame, source_frame)`` is the transform that maps
  data given in ``source_frame`` into ``target_frame``;
* times are float seconds (datetime64 timestamps are converted to seconds
  since the Unix epoch by :func:`rbm_nb._engine.time.epoch_seconds`, the one
  time rule's door out to float callers: ~0.24 µs coarse at today's
  epochs, as tf2's own double seconds), and ``time=0`` means the latest
  time at which every frame on the chain has data;
* nothing is extrapolated: asking for a time outside a moving frame's data
  raises :class:`~rbm_nb.errors.ExtrapolationError`.

Results are tuples of floats, quaternions in ``w, x, y, z`` order, as in the
reference API. Their signs are the reference's too (q and -q are the same
rotation, but stored results are compared number by number):

* ``lookup_transform`` returns tf2's algebraic composition: the stored
  quaternions multiplied up the tree from source and target (tf2's
  ``TransformAccum``), between two samples on the hemisphere of the earlier
  one (tf2's slerp);
* ``transform_quaternion`` and ``transform_pose`` go, in the reference,
  through ``tf2_geometry_msgs.do_transform_pose``, which multiplies PyKDL
  frames and reads the quaternion back from the rotation matrix
  (``Rotation.GetQuaternion``): w > 0 when the trace exceeds 1e-12, else the
  component of the largest diagonal element is positive. The value here is
  the Hamilton product ``r * q`` with that sign.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Sequence
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

from .._door.at_times import latest_common_time, requested_at
from .._door.unpack import float_array
from .._door.validation import check_finite, normalize_quaternions
from .._engine import at_time as _at_time
from .._engine.time import epoch_seconds
from .._kernels import quaternion as kq
from ..core.frames import ReferenceFrame, resolve_frame
from ..errors import ExtrapolationError
from .tf_tree import load_tf_tree, time_span

__all__ = [
    "ConnectivityError",
    "FrameNotFoundError",
    "ExtrapolationError",
    "Transformer",
]

#: A time argument: float seconds (0 is "the latest"), or a datetime64.
Time: TypeAlias = "float | np.datetime64"
#: A result: the components of one vector or quaternion.
Floats: TypeAlias = tuple[float, ...]

#: tf2's default buffer length in seconds.
DEFAULT_CACHE_TIME = 10.0


class FrameNotFoundError(ValueError):
    """A frame name the buffer has never heard of (tf2's LookupException)."""


class ConnectivityError(ValueError):
    """Two frames that no chain of transforms connects (tf2's ConnectivityException)."""


class _Edge:
    """What the buffer knows about one child frame."""

    __slots__ = ("parent", "translation", "rotation", "times", "discrete")

    def __init__(self, parent, translation, rotation, times, discrete):
        self.parent = parent
        self.translation = translation  # (3,) static, (n, 3) moving
        self.rotation = rotation  # (4,) static, (n, 4) moving
        self.times = times  # None static, (n,) float seconds moving
        self.discrete = discrete


def _when(time, name: str = "time") -> float:
    """One time argument as tf2's float seconds, by the one time rule
    (:func:`~rbm_nb._engine.time.epoch_seconds`: NaN, inf and NaT refused)."""
    if np.asarray(time).dtype.kind not in "iufbMm":
        raise ValueError(
            f"{name} must be a number of seconds (or a datetime64), got {time!r}"
        )
    return float(epoch_seconds(time, name=name))


def _vector(value, size: int, name: str) -> np.ndarray:
    arr = float_array(value, name)
    if arr.shape != (size,):
        raise ValueError(f"{name} must have length {size}, got shape {arr.shape}")
    check_finite(arr, name)
    return arr


def _name(value, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise ValueError(f"{what} must be a non-empty frame name, got {value!r}")
    return value


class Transformer:
    """A buffer of transforms between named frames, queried like tf2.

    Parameters
    ----------
    cache_time : float, optional
        How many seconds of each moving frame's history to keep, counted back
        from its newest sample (tf2's default of 10 s if not given).

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.frames import ReferenceFrame
    >>> from rbm_nb.ros import Transformer
    >>> world = ReferenceFrame("world")
    >>> head = ReferenceFrame("head", parent=world, translation=[[0, 0, 0], [1, 0, 0]],
    ...                       timestamps=[0.0, 1.0])
    >>> tf = Transformer.from_reference_frame(world)
    >>> tf.lookup_transform("world", "head", time=0.25)
    ((0.25, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    >>> tf.transform_point((1.0, 2.0, 3.0), "world", "head")  # time 0: the latest
    (2.0, 2.0, 3.0)
    """

    def __init__(self, cache_time: float | None = None) -> None:
        if cache_time is None:
            cache_time = DEFAULT_CACHE_TIME
        cache_time = _when(cache_time, "cache_time")
        if cache_time < 0:
            raise ValueError(f"cache_time must be >= 0 seconds, got {cache_time}")
        self.cache_time = cache_time
        self._edges: dict[str, _Edge] = {}
        self._built: dict[str, ReferenceFrame] = {}

    def __repr__(self) -> str:
        moving = sum(e.times is not None for e in self._edges.values())
        return (
            f"<Transformer: {len(self.frames)} frames, {len(self._edges) - moving} static "
            f"and {moving} moving transforms, cache_time={self.cache_time:g} s>"
        )

    @property
    def frames(self) -> tuple[str, ...]:
        """Names of all frames the buffer knows, sorted."""
        names = set(self._edges)
        names.update(e.parent for e in self._edges.values())
        return tuple(sorted(names))

    # -- filling the buffer ------------------------------------------------

    @staticmethod
    def from_reference_frame(reference_frame: ReferenceFrame | str) -> Transformer:
        """A Transformer holding every transform of a reference frame's tree.

        Parameters
        ----------
        reference_frame : ReferenceFrame or str
            Any frame of the tree (or the name of a registered one); the whole
            tree from its root down is added.

        Returns
        -------
        Transformer
            Its cache time covers all timestamps of the tree (at least tf2's
            default of 10 s), so nothing is dropped.
        """
        root = resolve_frame(reference_frame, "reference_frame").root
        nodes = root.descendants
        names = [root.name] + [n.name for n in nodes]
        if any(not isinstance(n, str) or not n for n in names):
            raise ValueError(
                "every frame of the tree needs a name to go into a Transformer"
            )
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(
                f"frame names must be unique in the tree, repeated: {duplicates}"
            )
        spans = [
            epoch_seconds(n.timestamps, name="timestamps")[[0, -1]]
            for n in nodes
            if n.timestamps is not None
        ]
        cache_time = DEFAULT_CACHE_TIME
        if spans:
            ends = np.array(spans)
            cache_time = max(cache_time, float(ends[:, 1].max() - ends[:, 0].min()))
        transformer = Transformer(cache_time=cache_time)
        for node in nodes:
            if node.timestamps is None:
                transformer.set_transform_static(node)
            else:
                transformer.set_transforms(node)
        return transformer

    @staticmethod
    def from_bag(
        bag_file: str | os.PathLike,
        topics: Sequence[str] | None = None,
        cache_time: float | None = None,
    ) -> Transformer:
        """A Transformer holding a bag's whole tf tree (``/tf`` and ``/tf_static``).

        Parameters
        ----------
        bag_file : str or path-like
            A ROS1 ``.bag`` or a ROS2 bag folder.
        topics : sequence of str, optional
            tf topics (default: ``/tf`` and ``/tf_static`` where present).
        cache_time : float, optional
            Seconds of history to keep; default: the bag's whole time span
            (at least tf2's 10 s), so that nothing is dropped.

        Returns
        -------
        Transformer

        Raises
        ------
        ValueError
            If the bag has no tf topic, or its transforms do not form trees.
        rbm_nb.io.FileFormatError
            If the bag is damaged.
        """
        tree = load_tf_tree(bag_file, topics)
        if cache_time is None:
            cache_time = max(DEFAULT_CACHE_TIME, time_span(tree))
        transformer = Transformer(cache_time=cache_time)
        _fill_transformer(transformer, tree)
        return transformer

    def set_transform_static(self, reference_frame: ReferenceFrame | str) -> None:
        """Add the static transform of a reference frame wrt its parent.

        Parameters
        ----------
        reference_frame : ReferenceFrame or str
            A static frame with a parent (or the name of a registered one).
        """
        frame, parent = self._checked_frame(reference_frame)
        if frame.timestamps is not None:
            raise ValueError(
                f"frame {frame.name!r} is moving (it has timestamps); use set_transforms"
            )
        self._set_edge(
            frame.name, parent.name, np.array(frame.translation),
            np.array(frame.rotation), None, False,
        )  # fmt: skip

    def set_transforms(self, reference_frame: ReferenceFrame | str) -> None:
        """Add the transforms of a moving reference frame wrt its parent.

        Samples are merged with those already buffered for the frame (a new
        sample replaces an old one at the same time); samples older than
        ``cache_time`` before the newest are dropped.

        Parameters
        ----------
        reference_frame : ReferenceFrame or str
            A moving frame with a parent (or the name of a registered one).
        """
        frame, parent = self._checked_frame(reference_frame)
        if frame.timestamps is None:
            raise ValueError(
                f"frame {frame.name!r} is static (no timestamps); use set_transform_static"
            )
        self._set_edge(
            frame.name, parent.name, np.array(frame.translation),
            np.array(frame.rotation), epoch_seconds(frame.timestamps, name="timestamps"),
            frame.discrete,
        )  # fmt: skip

    def set_transform(
        self,
        translation: npt.ArrayLike,
        rotation: npt.ArrayLike,
        frame_id: str,
        child_frame_id: str,
        time: npt.ArrayLike | None = None,
    ) -> None:
        """Add raw transforms of ``child_frame_id`` wrt ``frame_id``.

        The counterpart of tf2's ``set_transform`` for data that does not come
        as a reference frame (e.g. ``/tf`` messages read from a rosbag).

        Parameters
        ----------
        translation : array_like, shape (3,) or (n, 3)
            Origin of the child frame in the parent frame.
        rotation : array_like, shape (4,) or (n, 4)
            Orientation of the child wrt the parent, ``w, x, y, z``.
        frame_id, child_frame_id : str
            Parent and child frame names.
        time : float or array_like, shape (n,), optional
            Seconds (or datetime64). None adds a static transform.
        """
        parent = _name(frame_id, "frame_id")
        child = _name(child_frame_id, "child_frame_id")
        if time is None:
            t0 = _vector(translation, 3, "translation")
            r0 = normalize_quaternions(_vector(rotation, 4, "rotation"), "rotation")
            self._set_edge(child, parent, t0, r0, None, False)
            return
        times = np.atleast_1d(epoch_seconds(time, name="time"))
        if times.ndim != 1 or not np.isfinite(times).all():
            raise ValueError(f"time must be finite seconds, shape (n,), got {time!r}")
        n = len(times)
        t = np.asarray(translation, dtype=np.float64).reshape(-1, 3) if n else None
        r = np.asarray(rotation, dtype=np.float64).reshape(-1, 4) if n else None
        if t is None or r is None or t.shape != (n, 3) or r.shape != (n, 4):
            raise ValueError(
                f"translation and rotation must have shapes ({n}, 3) and ({n}, 4) for "
                f"{n} times, got {np.shape(translation)} and {np.shape(rotation)}"
            )
        check_finite(t, "translation")
        order = np.argsort(times, kind="stable")
        self._set_edge(
            child,
            parent,
            t[order],
            normalize_quaternions(r[order], "rotation"),
            times[order],
            False,
        )

    def _checked_frame(self, reference_frame) -> tuple[ReferenceFrame, ReferenceFrame]:
        """The resolved frame and its parent, both with names."""
        frame = resolve_frame(reference_frame, "reference_frame")
        parent = frame.parent
        if parent is None:
            raise ValueError(
                f"frame {frame.name!r} has no parent: there is no transform to add"
            )
        _name(frame.name, "the frame's name")
        _name(parent.name, "the parent frame's name")
        return frame, parent

    def _set_edge(self, child, parent, t, r, times, discrete) -> None:
        if child == parent:
            raise ValueError(f"frame {child!r} cannot be its own parent")
        node = parent
        while node is not None:  # refuse cycles, as a tree must
            if node == child:
                raise ValueError(
                    f"making {parent!r} the parent of {child!r} would close a loop: "
                    f"{parent!r} is already below {child!r}"
                )
            edge = self._edges.get(node)
            node = None if edge is None else edge.parent
        old = self._edges.get(child)
        if (
            times is not None
            and old is not None
            and old.times is not None
            and old.parent == parent
        ):
            # newer samples win at equal times: keep the last occurrence
            all_times = np.concatenate([old.times, times])
            t = np.concatenate([old.translation, t])
            r = np.concatenate([old.rotation, r])
            _, last = np.unique(all_times[::-1], return_index=True)
            keep = len(all_times) - 1 - last
            all_times, t, r = all_times[keep], t[keep], r[keep]
            times = all_times
        elif times is not None:
            _, keep = np.unique(times[::-1], return_index=True)
            keep = len(times) - 1 - keep
            times, t, r = times[keep], t[keep], r[keep]
        if times is not None:
            recent = times >= times[-1] - self.cache_time
            times, t, r = times[recent], t[recent], r[recent]
        self._edges[child] = _Edge(parent, t, r, times, discrete)
        self._invalidate(child)

    def _invalidate(self, name: str) -> None:
        """Forget the built frame of ``name`` and everything below it."""
        frame = self._built.pop(name, None)
        if frame is not None:
            frame.parent = None  # detach, so the old object leaves the tree
        for child, edge in self._edges.items():
            if edge.parent == name:
                self._invalidate(child)

    # -- the private frame tree -------------------------------------------

    def _frame(self, name: str) -> ReferenceFrame:
        frame = self._built.get(name)
        if frame is not None:
            return frame
        edge = self._edges.get(name)
        if edge is None:
            frame = ReferenceFrame(name)
        else:
            frame = ReferenceFrame(
                name,
                parent=self._frame(edge.parent),
                translation=edge.translation,
                rotation=edge.rotation,
                timestamps=edge.times,
                discrete=edge.discrete,
            )
        self._built[name] = frame
        return frame

    def _known(self, name, what: str) -> ReferenceFrame:
        name = _name(name, what)
        known = self.frames
        if name not in known:
            close = difflib.get_close_matches(name, known, n=3)
            hint = f"; did you mean {' or '.join(map(repr, close))}?" if close else ""
            listing = (
                f" (frames: {', '.join(known)})" if known else " (the buffer is empty)"
            )
            raise FrameNotFoundError(
                f"{what} {name!r} does not exist in this Transformer{hint}{listing}"
            )
        return self._frame(name)

    def _lookup(self, target_frame, source_frame, time):
        target = self._known(target_frame, "target_frame")
        source = self._known(source_frame, "source_frame")
        # the buffer's frames are named by the (checked) names they were built from
        target_name, source_name = str(target_frame), str(source_frame)
        if target.root is not source.root:
            raise ConnectivityError(
                f"no chain of transforms connects {source.name!r} and {target.name!r} "
                f"(their trees have the roots {source.root.name!r} and {target.root.name!r})"
            )
        when = _when(time)
        if when == 0.0:
            latest = latest_common_time(source, target)
            if latest is None:  # all static: any time will do
                latest = 0.0
            when = float(latest)
        t, r, _ = _at_time.transform_at_times(
            source, target, requested_at(source, target, when)
        )
        r = np.asarray(r, dtype=np.float64)
        if np.dot(r, self._tf2_rotation(source_name, target_name, when)) < 0:
            r = -r
        return t, r

    def _chain_rotation(self, start: str, stop: str | None, when: float) -> np.ndarray:
        """tf2's accumulated rotation from ``start`` up to (not including) ``stop``."""
        acc = np.array([1.0, 0.0, 0.0, 0.0])
        node = start
        while node != stop and node in self._edges:
            edge = self._edges[node]
            q = edge.rotation
            if edge.times is not None:
                # at a sample: that sample; between two: tf2's slerp stays on
                # the earlier one's hemisphere
                i = int(np.searchsorted(edge.times, when, side="right")) - 1
                q = q[min(max(i, 0), len(q) - 1)]
            acc = _qmul(np.asarray(q, dtype=np.float64), acc)
            node = edge.parent
        return acc

    def _ancestors(self, name: str) -> list:
        chain = [name]
        while chain[-1] in self._edges:
            chain.append(self._edges[chain[-1]].parent)
        return chain

    def _tf2_rotation(self, source: str, target: str, when: float) -> np.ndarray:
        """The rotation tf2's lookupTransform composes, with tf2's sign (w, x, y, z)."""
        if source == target:
            return np.array([1.0, 0.0, 0.0, 0.0])
        if target in self._ancestors(source):  # target is above source
            return self._chain_rotation(source, target, when)
        if source in self._ancestors(target):  # source is above target
            return _qconj(self._chain_rotation(target, source, when))
        # both up to the root: conj(target_to_top) * source_to_top
        return _qmul(
            _qconj(self._chain_rotation(target, None, when)),
            self._chain_rotation(source, None, when),
        )

    # -- queries ------------------------------------------------------------

    def can_transform(
        self, target_frame: str, source_frame: str, time: Time = 0.0
    ) -> bool:
        """Whether ``lookup_transform`` would succeed.

        Parameters
        ----------
        target_frame, source_frame : str
        time : float, default 0.0
            Seconds; 0 means the latest common time.

        Returns
        -------
        bool
        """
        _name(target_frame, "target_frame")
        _name(source_frame, "source_frame")
        _when(time)
        try:
            self._lookup(target_frame, source_frame, time)
        except (FrameNotFoundError, ConnectivityError, ExtrapolationError):
            return False
        return True

    def lookup_transform(
        self, target_frame: str, source_frame: str, time: Time = 0.0
    ) -> tuple[Floats, Floats]:
        """The transform that maps data in ``source_frame`` into ``target_frame``.

        Parameters
        ----------
        target_frame : str
            Name of the frame to transform into.
        source_frame : str
            Name of the frame the data is given in.
        time : float, default 0.0
            Seconds; 0 means the latest time at which the whole chain has
            data.

        Returns
        -------
        t : tuple, len 3
            Origin of ``source_frame`` in ``target_frame``.
        r : tuple, len 4
            Orientation of ``source_frame`` wrt ``target_frame``, ``w, x, y, z``.

        Raises
        ------
        FrameNotFoundError, ConnectivityError, ExtrapolationError
            (all ValueErrors) for unknown frames, unconnected frames and
            times without data.
        """
        t, r = self._lookup(target_frame, source_frame, time)
        return tuple(map(float, t)), tuple(map(float, r))

    def _rotate(self, r, v):
        return kq.rotate_vectors(
            np.ascontiguousarray(r[None]), np.ascontiguousarray(v[None])
        )[0]

    def transform_point(
        self, p: npt.ArrayLike, target_frame: str, source_frame: str, time: Time = 0.0
    ) -> Floats:
        """A point given in ``source_frame``, expressed in ``target_frame``.

        Returns
        -------
        tuple, len 3
        """
        p = _vector(p, 3, "p")
        t, r = self._lookup(target_frame, source_frame, time)
        return tuple(map(float, self._rotate(r, p) + t))

    def transform_vector(
        self, v: npt.ArrayLike, target_frame: str, source_frame: str, time: Time = 0.0
    ) -> Floats:
        """A vector represented in ``source_frame``, represented in ``target_frame``.

        Only the rotation applies (a vector has no position).

        Returns
        -------
        tuple, len 3
        """
        v = _vector(v, 3, "v")
        _, r = self._lookup(target_frame, source_frame, time)
        return tuple(map(float, self._rotate(r, v)))

    def transform_quaternion(
        self, q: npt.ArrayLike, target_frame: str, source_frame: str, time: Time = 0.0
    ) -> Floats:
        """An orientation wrt ``source_frame``, expressed wrt ``target_frame``.

        Returns
        -------
        tuple, len 4
            ``w, x, y, z``: the Hamilton product of the looked-up rotation and
            ``q``, with the sign the reference returns (see the module notes).
        """
        q = normalize_quaternions(_vector(q, 4, "q"), "q")
        _, r = self._lookup(target_frame, source_frame, time)
        return tuple(map(float, _kdl_sign(_qmul(r, q))))

    def transform_pose(
        self,
        p: npt.ArrayLike,
        o: npt.ArrayLike,
        target_frame: str,
        source_frame: str,
        time: Time = 0.0,
    ) -> tuple[Floats, Floats]:
        """A pose (position and orientation) from ``source_frame`` to ``target_frame``.

        Parameters
        ----------
        p : iterable, len 3
            Position in the source frame.
        o : iterable, len 4
            Orientation wrt the source frame, ``w, x, y, z``.

        Returns
        -------
        pt : tuple, len 3
        ot : tuple, len 4
        """
        p = _vector(p, 3, "p")
        o = normalize_quaternions(_vector(o, 4, "o"), "o")
        t, r = self._lookup(target_frame, source_frame, time)
        return (
            tuple(map(float, self._rotate(r, p) + t)),
            tuple(map(float, _kdl_sign(_qmul(r, o)))),
        )


def _fill_transformer(transformer: Transformer, tree: dict) -> None:
    """Add every pair of ``tree`` (from :func:`load_tf_tree`) to a Transformer."""
    for child, pair in tree.items():
        if pair.static:
            transformer.set_transform(
                pair.position[-1], pair.orientation[-1], pair.frame_id, child
            )
        else:
            transformer.set_transform(
                pair.position,
                pair.orientation,
                pair.frame_id,
                child,
                time=pair.timestamps,
            )


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return kq.qmul(np.ascontiguousarray(a[None]), np.ascontiguousarray(b[None]))[0]


def _qconj(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


def _kdl_sign(q: np.ndarray) -> np.ndarray:
    """``q`` or ``-q``: the sign PyKDL's ``Rotation.GetQuaternion`` gives.

    GetQuaternion reads a quaternion from a rotation matrix: if the trace is
    above 1e-12 it makes w positive; otherwise the component that belongs to
    the largest diagonal element (x for m00, y for m11, else z).
    """
    w, x, y, z = q
    m00 = w * w + x * x - y * y - z * z
    m11 = w * w - x * x + y * y - z * z
    m22 = w * w - x * x - y * y + z * z
    if m00 + m11 + m22 > 1e-12:
        positive = w
    elif m00 > m11 and m00 > m22:
        positive = x
    elif m11 > m22:
        positive = y
    else:
        positive = z
    return -q if positive < 0 else q
