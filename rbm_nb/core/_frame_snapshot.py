"""Frames as immutable values, cut to a time window, for tasks on other processes.

A lazy computation (:mod:`rbm_nb._door.dask_blocks`) resolves its frames once, on the
client, when its graph is built: names are looked up in the registry then,
and the graph holds values, not names. A frame registered, replaced or
removed afterwards does not change a graph already built -- a graph is a
snapshot of the registry. The values travel to dask workers, which may be
other processes or other machines where the registry is empty.

:class:`FrameTree` holds the frames a computation needs (those between the
frames it names and their lowest common ancestor, which becomes the root)
as :class:`FrameValue` records: the prepared samples, times and options of
each frame's one immutable value (``ReferenceFrame.data``, the value the
engine computes with), so that a snapshot is one consistent state of every
frame in it. A worker makes the values again from the records
(:meth:`FrameTree.values`); it builds no ReferenceFrame and checks nothing
again. :meth:`FrameTree.window` keeps, of
every moving frame, only the samples a chunk's time window needs plus
:data:`MARGIN` samples on each side, so that what one task carries grows
with its chunk, not with the recording. The margin covers every stencil of
the engine -- SQUAD reads samples i-1 .. i+2, linear interpolation i and
i+1, the missing-sample rules the same neighbours -- with room to spare, and
it does not depend on how those rules treat missing samples: the eager
engine runs on the window's values (:meth:`FrameTree.values`) exactly as on
the whole ones, and the margin keeps the window's edges out of reach.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._door.dask_blocks import MARGIN
from .._engine import time as _time
from .._engine.frame_data import FrameData, Samples
from .frames import ReferenceFrame

__all__ = ["FrameValue", "FrameTree"]


@dataclass(frozen=True)
class FrameValue:
    """One frame's immutable value, as a record of its tree.

    ``samples`` is the frame's prepared :class:`~rbm_nb._engine.frame_data.Samples`
    (``ReferenceFrame.data.samples``: checked, unit and sign-continuous
    rotations, the Track of its times), or for a window the rows it keeps;
    ``parent`` is the index of the parent in the :class:`FrameTree` (-1 for
    its root, whose transform is the identity). A worker turns the records
    back into :class:`~rbm_nb._engine.frame_data.FrameData` values
    (:meth:`FrameTree.values`) without checking or preparing anything
    again: that was done once, when the user's frame was built.
    """

    name: str | None
    parent: int
    samples: Samples
    discrete: bool
    max_gap: float | None

    @classmethod
    def of(cls, data: FrameData, parent: int) -> FrameValue:
        """The record of a frame's value (``ReferenceFrame.data``)."""
        samples = _IDENTITY if parent < 0 else data.samples
        return cls(data.name, parent, samples, data.discrete, data.max_gap)

    @property
    def nbytes(self) -> int:
        s = self.samples
        arrays = [s.stored_t, s.stored_rotation]
        # a moving frame's sign codes, a static frame's unit rotation
        arrays += [a for a in (s.signs, s.unit) if a is not None]
        if s.missing_rows is not None:
            arrays.append(s.missing_rows)
        if s.track is not None:
            arrays += [s.track.values, s.track.key, s.track.base]
        return sum(a.nbytes for a in arrays)

    def window(self, first: Any, last: Any, margin: int) -> FrameValue:
        """The samples covering ``first .. last``, ``margin`` more on each side.

        The samples bracketing the window are found by time (the sample at
        or before ``first``, the one at or after ``last``); a window outside
        the frame's samples keeps its edge samples (discrete frames hold
        them). Times of another kind than the frame's (datetime64 against
        numbers) are not cut here: the engine names that error on compute.
        """
        track = self.samples.track
        if track is None or not _comparable(track.values, first):
            return self
        ts = track.values
        n = len(ts)
        lo = int(np.searchsorted(ts, first, side="right")) - 1 - margin
        hi = int(np.searchsorted(ts, last, side="left")) + 1 + margin
        lo, hi = max(0, min(lo, n - 1)), min(n, max(hi, 1))
        if hi - lo < 2 <= n:  # at least a segment, as the whole frame has
            lo, hi = max(0, min(lo, n - 2)), max(hi, min(n, lo + 2))
        if (lo, hi) == (0, n):
            return self
        # the first sample stays: times count from it (float seconds since the
        # first sample), so the window interpolates with the whole frame's
        # numbers; it is far outside the stencils the margin keeps. The rows
        # are the prepared ones (sign-continuous over the whole recording),
        # so the window's rows are the eager call's to the bit.
        rows = np.r_[0, lo:hi] if lo > 0 else slice(lo, hi)
        s = self.samples
        cut = _time.Track(
            track.values[rows], track.key[rows], track.base[rows], track.origin,
            track.kind,
        )  # fmt: skip
        mask = s.missing_rows
        assert s.signs is not None  # (every moving frame's)
        samples = Samples(
            cut, s.stored_t[rows], None, s.stored_rotation[rows],
            s.missing_rotations, None if mask is None else mask[rows],
            s.signs[rows],
        )  # fmt: skip
        return replace(self, samples=samples)


# the root of a tree: its own transform is not on any path below it
_IDENTITY_ROW = np.array([[1.0, 0.0, 0.0, 0.0]])
_IDENTITY = Samples(None, np.zeros((1, 3)), _IDENTITY_ROW, _IDENTITY_ROW)


def _comparable(timestamps: np.ndarray, time: Any) -> bool:
    return (np.asarray(timestamps).dtype.kind == "M") == (
        np.asarray(time).dtype.kind == "M"
    )


@dataclass(frozen=True)
class FrameTree:
    """The frames a computation names, and those between them, as values.

    ``frames[0]`` is the root (the lowest common ancestor of the named
    frames); every frame comes after its parent. ``named[k]`` is the index
    of the k-th frame the computation named.
    """

    frames: tuple[FrameValue, ...]
    named: tuple[int, ...]

    @classmethod
    def of(cls, named: Sequence[ReferenceFrame]) -> FrameTree:
        """The values of ``named`` frames (resolved, of one tree) and of the
        frames between them and their lowest common ancestor.

        Raises
        ------
        ValueError
            If the frames are not all in one tree (the engine's message).
        """
        # one value per frame, read once: root first
        paths = [list(reversed(f.data.path_to_root())) for f in named]
        for other in paths[1:]:
            if other[0] is not paths[0][0]:
                first = paths[0]
                raise ValueError(
                    f"frames {first[-1].name!r} and {other[-1].name!r} are in "
                    f"different trees (roots {first[0].name!r} and "
                    f"{other[0].name!r}); no transform connects them"
                )
        depth = 0  # the lowest common ancestor is paths[*][depth]
        while all(len(p) > depth + 1 for p in paths) and all(
            p[depth + 1] is paths[0][depth + 1] for p in paths
        ):
            depth += 1
        index: dict[FrameData, int] = {}
        values: list[FrameValue] = []
        for path in paths:
            for data in path[depth:]:
                if data not in index:
                    parent = -1 if not values else index[data.parent]  # type: ignore[index]
                    index[data] = len(values)
                    values.append(FrameValue.of(data, parent))
        return cls(tuple(values), tuple(index[path[-1]] for path in paths))

    @property
    def nbytes(self) -> int:
        """Bytes of sample data held (what a task carries, apart from pickling)."""
        return sum(f.nbytes for f in self.frames)

    def window(self, first: Any, last: Any, margin: int = MARGIN) -> FrameTree:
        """The same tree with each moving frame cut to the window ``first .. last``."""
        return replace(
            self, frames=tuple(f.window(first, last, margin) for f in self.frames)
        )

    def values(self) -> list[FrameData]:
        """The named frames' values (FrameData), in order, made from the records.

        No ReferenceFrame is built: the samples were checked and prepared
        when the user's frames were, and a value is all the engine reads
        (:mod:`rbm_nb._engine.frame_data`). Values link only to their parents,
        so a finished task's values go with its last reference.
        """
        made: list[FrameData] = []
        for value in self.frames:
            parent = None if value.parent < 0 else made[value.parent]
            made.append(
                FrameData(
                    value.name, parent, value.samples, value.discrete, value.max_gap
                )
            )
        return [made[k] for k in self.named]
