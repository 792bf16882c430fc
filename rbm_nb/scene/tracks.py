"""Poses over time, sampled per player step.

A scene object is placed by the transform of its frame into the scene's base.
When that transform moves it is a :class:`~rbm_nb.scene.looked_up.LookedUpTrack`:
the frames' values, its samples looked up per window when asked for (never
kept whole). Poses the user hands in (moving points and vectors) and static
ones are a :class:`PoseTrack` holding its arrays. Both answer the same
questions: how many rows, the rows before a time (:meth:`PoseTrack.search`),
the rows of a window or of chosen indices (:meth:`PoseTrack.take`), bounds.

Times are the core's exact keys (:mod:`rbm_nb._engine.time`): int64
nanoseconds for datetime64/timedelta64 timestamps, float seconds for
numbers. A time given as a float epoch second becomes a key once, where it
enters (:func:`~rbm_nb._engine.time.time_key`); seconds for the browser are
counted from the scene's second 0 where a message is packed
(:mod:`rbm_nb.scene.state`).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from typing import Any, Literal

import numpy as np

from .._engine import chain as _chain
from .._engine.time import TimeBase, as_track, check_compatible
from ..core import lookups
from .commands import pose_matrix
from .looked_up import LookedUpTrack
from .timekeys import KEYS_PER_SECOND, at_or_before

__all__ = ["PoseTrack", "LookedUpTrack", "SceneTrack", "moving_span", "duration"]


class _Times:
    """A track's timestamps as given and their exact keys."""

    __slots__ = ("values", "key")

    def __init__(self, values: np.ndarray, key: np.ndarray) -> None:
        self.values = values
        self.key = key

    def __len__(self) -> int:
        return int(self.key.shape[0])


class PoseTrack:
    """Translation and rotation of something, static or sampled over time.

    Parameters
    ----------
    translation : array_like, shape (3,) or (n, 3)
    rotation : array_like, shape (4,) or (n, 4)
        Quaternions ``(w, x, y, z)``.
    timestamps : array_like, shape (n,), optional
        None for a static pose.
    scale : array_like, shape (n,), optional
        Uniform scale per sample (vector lengths).
    name : str
        Used in error messages.
    owned : bool, default False
        The caller hands ``translation`` and ``rotation`` over (a lookup's
        fresh results, held by nobody else): missing rows are marked in them
        instead of in copies. At 3 h of the explorer's recording the copies
        were ~40 % of the scene's memory (two gaze rays of 3.7 M samples).
    """

    def __init__(
        self,
        translation,
        rotation,
        timestamps=None,
        scale=None,
        name: str = "track",
        *,
        owned: bool = False,
    ):
        self.name = name
        # the timestamps as given and their exact keys (a view of them for
        # datetime64[ns]); None for a static pose. The Track's float seconds
        # are not kept: nothing here interpolates
        self._times: _Times | None
        self.kind: str | None
        # rows with data, when some are missing (None: all of them)
        self._present: np.ndarray | None = None
        t = np.asarray(translation, dtype=np.float64)
        r = np.asarray(rotation, dtype=np.float64)
        if timestamps is None:
            if t.shape != (3,) or r.shape != (4,):
                raise ValueError(
                    f"{name}: a static pose needs translation (3,) and rotation (4,), "
                    f"got {t.shape} and {r.shape}"
                )
            self._times = None
            self.kind = None
        else:
            track = as_track(timestamps, f"{name} timestamps", copy=False, repeats=True)
            self._times = _Times(track.values, track.key)
            self.kind = track.kind
            n = len(self._times)
            if t.shape != (n, 3) or r.shape != (n, 4):
                raise ValueError(
                    f"{name}: {n} timestamps need translation ({n}, 3) and rotation ({n}, 4), "
                    f"got {t.shape} and {r.shape}"
                )
        if np.isinf(t).any() or np.isinf(r).any():
            raise ValueError(f"{name}: translation and rotation must not be infinite")
        if self._times is None:
            if np.isnan(t).any() or np.isnan(r).any():
                raise ValueError(f"{name}: a static pose must not be NaN")
        else:
            # a missing sample (NaN anywhere in its row) hides the object there
            missing = np.isnan(t).any(axis=1) | np.isnan(r).any(axis=1)
            # kept (1 byte a sample): positions() is asked for often while a
            # scene is built (extent, reach, grid) and need not search again
            if missing.any():
                self._present = np.logical_not(missing)
                if not (owned and _fresh(t) and _fresh(r)):
                    t, r = t.copy(), r.copy()
                t[missing] = np.nan
                r[missing] = np.nan
        self.translation = np.ascontiguousarray(t)
        self.rotation = np.ascontiguousarray(r)
        if scale is not None:
            scale = np.ascontiguousarray(scale, dtype=np.float64)
            if self._times is None or scale.shape != (len(self._times),):
                raise ValueError(f"{name}: scale must have one value per timestamp")
        self.scale: np.ndarray | None = scale

    @classmethod
    def lookup(cls, frame, base, name: str | None = None) -> PoseTrack | LookedUpTrack:
        """The transform of ``frame`` into ``base`` (points in frame -> base).

        Static: a :class:`PoseTrack`. Moving: a :class:`LookedUpTrack`, which
        looks its samples up per window (the scene keeps no copy of them).
        """
        label = name or f"pose of {frame.name!r} in {base.name!r}"
        if frame is base:
            return cls(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), name=label)
        if _chain.static_transform(frame.data, base.data) is not None:
            t, r = lookups.lookup_transform(outof=frame, into=base)
            return cls(np.asarray(t).reshape(3), np.asarray(r).reshape(4), name=label)
        return LookedUpTrack(frame, base, _max_gap(frame, base), label)

    @classmethod
    def looked_up_whole(cls, frame, base, name: str | None = None) -> PoseTrack:
        """The transform of a moving ``frame`` into ``base``, every sample
        held (what :meth:`lookup` kept before it looked up per window: the
        tests' reference)."""
        label = name or f"pose of {frame.name!r} in {base.name!r}"
        t, r, ts = lookups.lookup_transform(
            outof=frame, into=base, return_timestamps=True
        )
        t, r = np.asarray(t), np.asarray(r)
        if ts is None:
            raise ValueError(f"{label}: does not move")
        gap = _max_gap(frame, base)
        if gap is not None:
            t, r, ts = _hidden_across_gaps(t, r, np.asarray(ts), gap)
        # a lookup's results are the caller's (the engine copies what it keeps)
        return cls(t, r, ts, name=label, owned=True)

    @property
    def static(self) -> bool:
        return self._times is None

    @property
    def original_timestamps(self) -> np.ndarray | None:
        """The timestamps as given (None for a static pose)."""
        return None if self._times is None else self._times.values

    def sample_keys(self) -> np.ndarray:
        """Exact keys of the samples, shape (n,), of a track that moves."""
        if self._times is None:
            raise ValueError(f"{self.name}: a static pose has no sample times")
        return self._times.key

    def __len__(self) -> int:
        return 1 if self._times is None else len(self._times)

    @property
    def start(self) -> int | float | None:
        """Key of the first sample (None for a static pose)."""
        return None if self._times is None else self._times.key[0].item()

    @property
    def end(self) -> int | float | None:
        """Key of the last sample (None for a static pose)."""
        return None if self._times is None else self._times.key[-1].item()

    def index_at(self, key: int | float) -> int:
        """Index of the latest sample at or before time ``key``; -1 before the start.

        The core's rule (:func:`~rbm_nb.scene.timekeys.at_or_before`): ns
        keys exact, a float time within half a nanosecond of a sample is it.
        """
        if self._times is None:
            return 0
        return self.search(at_or_before(key, self.kind), side="right") - 1

    def search(self, key: int | float, side: Literal["left", "right"] = "left") -> int:
        """Rows before time ``key`` (``np.searchsorted`` on the rows' keys)."""
        return int(np.searchsorted(self.sample_keys(), key, side=side))

    def keys_of(self, rows) -> np.ndarray:
        """Exact keys of ``rows`` (indices), shape (k,)."""
        return self.sample_keys()[np.atleast_1d(np.asarray(rows, dtype=np.int64))]

    def take(self, index):
        """Keys, translation, rotation and scale (or None) of rows
        ``index``: None (all), a slice or indices (views where they can be)."""
        keys = self.sample_keys()

        def pick(a):
            return a if index is None else a[index]

        scale = None if self.scale is None else pick(self.scale)
        return pick(keys), pick(self.translation), pick(self.rotation), scale

    def matrix(self, index: int = 0) -> np.ndarray:
        """Homogeneous (4, 4) matrix of sample ``index``."""
        if self._times is None:
            return pose_matrix(self.translation, self.rotation)
        m = pose_matrix(self.translation[index], self.rotation[index])
        if self.scale is not None:
            m[:3, :3] *= self.scale[index]
        return m

    def blocks(self) -> Iterator[np.ndarray]:
        """The translations, as one block (they are held)."""
        yield self.translation.reshape(-1, 3)

    def positions_with_gaps(self) -> np.ndarray:
        """Every sample's translation, shape (n, 3), NaN where missing (held)."""
        return self.translation.reshape(-1, 3)

    def positions(self) -> np.ndarray:
        """The translations of the samples that are not missing, as (n, 3)."""
        points = self.translation.reshape(-1, 3)
        if self._times is None:
            return points[~np.isnan(points).any(axis=1)]
        if self._present is None:
            return points.copy()
        return points[self._present]

    @functools.cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int] | None:
        """Lowest, highest and mean position of the samples that are not
        missing, and their count; None when all are missing.

        Computed once, without copying the samples (a missing sample is NaN
        across its row): the scene's grid and camera ask at every change.
        """
        points = self.translation.reshape(-1, 3)
        present = ~np.isnan(points[:, 0])
        count = int(present.sum())
        if count == 0:
            return None
        mean = np.add.reduce(points, axis=0, where=present[:, np.newaxis]) / count
        return (
            np.fmin.reduce(points, axis=0),
            np.fmax.reduce(points, axis=0),
            mean,
            count,
        )

    def missing(self, index: int) -> bool:
        """Whether sample ``index`` has no data (the object is hidden then)."""
        return bool(np.isnan(self.translation.reshape(-1, 3)[index]).any())

    def check_kind(self, kind: str | None, what: str) -> None:
        check_compatible([kind, self.kind], what)


#: what a scene's node follows: poses held, or looked up per window
SceneTrack = PoseTrack | LookedUpTrack


def moving_span(track: SceneTrack) -> tuple[int | float, int | float]:
    """Keys of the first and last row of a moving track (int ns or float s)."""
    first, last = track.keys_of([0, -1])
    return first.item(), last.item()


def duration(track: SceneTrack) -> float:
    """Seconds from the first to the last row of a moving track (exact keys
    subtracted before any division)."""
    first, last = moving_span(track)
    return (last - first) / KEYS_PER_SECOND[track.kind or "numeric"]


def _fresh(arr: np.ndarray) -> bool:
    """Whether an array handed over may be marked in place (not a converted copy's
    source: np.asarray above made no copy of a float64 array)."""
    return bool(arr.flags.writeable and arr.dtype == np.float64)


def _max_gap(frame, base) -> float | None:
    """The smallest ``max_gap`` of ``frame`` and its ancestors below ``base``."""
    gaps = []
    node = frame
    while node is not None and node is not base:
        if getattr(node, "max_gap", None) is not None:
            gaps.append(node.max_gap)
        node = node.parent
    return min(gaps) if gaps else None


def _hidden_across_gaps(t, r, ts, gap: float):
    """A missing row ``gap`` seconds after each sample followed by a longer gap.

    A scene holds each pose until the next sample; across a gap the frame
    core does not interpolate (``max_gap``), the object must not stay drawn
    at its last pose either: it is hidden from ``gap`` after that sample on.
    """
    step: Any
    if ts.dtype.kind == "M":
        step = np.timedelta64(int(round(gap * 1e9)), "ns")
        seconds = TimeBase.of(ts).seconds(ts)
    else:
        step = gap
        seconds = ts.astype(np.float64)
    after = np.flatnonzero(np.diff(seconds) > gap)
    if len(after) == 0:
        return t, r, ts
    at = after + 1  # np.insert puts the new rows before these
    ts = np.insert(ts, at, ts[after] + step)
    t = np.insert(t, at, np.nan, axis=0)
    r = np.insert(r, at, np.nan, axis=0)
    return t, r, ts
