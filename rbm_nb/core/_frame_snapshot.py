"""Frames as immutable values, cut to a time window, for tasks on other processes.

A lazy computation (:mod:`rbm_nb._door.dask_blocks`) resolves its frames once, on the
client, when its graph is built: names are looked up in the registry then,
and the graph holds values, not names. A frame registered, replaced or
removed afterwards does not change a graph already built -- a graph is a
snapshot of the registry. The values travel to dask workers, which may be
other processes or other machines where the registry is empty.

:class:`FrameTree` holds the frames a computation needs (those between the
frames it names and their lowest common ancestor, which becomes the root)
as :class:`FrameValue` records: the public samples, times and options of
each frame's one immutable value (``ReferenceFrame.data``, the value the
engine computes with), so that a snapshot is one consistent state of every
frame in it. :meth:`FrameTree.window` keeps, of
every moving frame, only the samples a chunk's time window needs plus
:data:`MARGIN` samples on each side, so that what one task carries grows
with its chunk, not with the recording. The margin covers every stencil of
the engine -- SQUAD reads samples i-1 .. i+2, linear interpolation i and
i+1, the missing-sample rules the same neighbours -- with room to spare, and
it does not depend on how those rules treat missing samples: the eager
engine runs on the window's frames (:meth:`FrameTree.build`) exactly as on
the whole ones, and the margin keeps the window's edges out of reach.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._door.dask_blocks import MARGIN
from .._engine.frame_data import FrameData
from .frames import ReferenceFrame

__all__ = ["FrameValue", "FrameTree"]


@dataclass(frozen=True)
class FrameValue:
    """One frame's data as a value: what :class:`~rbm_nb.ReferenceFrame` takes.

    ``parent`` is the index of the parent in the :class:`FrameTree` (-1 for
    its root). Arrays are the frame's public, read-only ones (no copy), or
    for a window the rows it keeps.
    """

    name: str | None
    parent: int
    translation: np.ndarray | None
    rotation: np.ndarray | None
    timestamps: np.ndarray | None
    discrete: bool
    max_gap: float | None

    @classmethod
    def of(cls, data: FrameData, parent: int) -> FrameValue:
        """The record of a frame's value (``ReferenceFrame.data``)."""
        if parent < 0:  # the root of the tree: no transform
            return cls(data.name, parent, None, None, None, data.discrete, data.max_gap)
        track = data.track
        moving = track is not None
        return cls(
            data.name,
            parent,
            _read_only(data.t if moving else data.t[0]),
            _read_only(data.rotation if moving else data.rotation[0]),
            None if track is None else _read_only(track.values),
            data.discrete,
            data.max_gap,
        )

    @property
    def nbytes(self) -> int:
        arrays = (self.translation, self.rotation, self.timestamps)
        return sum(a.nbytes for a in arrays if a is not None)

    def window(self, first: Any, last: Any, margin: int) -> FrameValue:
        """The samples covering ``first .. last``, ``margin`` more on each side.

        The samples bracketing the window are found by time (the sample at
        or before ``first``, the one at or after ``last``); a window outside
        the frame's samples keeps its edge samples (discrete frames hold
        them). Times of another kind than the frame's (datetime64 against
        numbers) are not cut here: the engine names that error on compute.
        """
        ts = self.timestamps
        if ts is None or not _comparable(ts, first):
            return self
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
        # numbers; it is far outside the stencils the margin keeps
        rows = np.r_[0, lo:hi] if lo > 0 else slice(lo, hi)
        assert self.translation is not None and self.rotation is not None
        return replace(
            self,
            translation=self.translation[rows],
            rotation=self.rotation[rows],
            timestamps=ts[rows],
        )


def _read_only(arr: np.ndarray) -> np.ndarray:
    """A view nobody can write through (the arrays are the frame's own)."""
    view = arr.view()
    view.setflags(write=False)
    return view


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

    @contextmanager
    def built(self) -> Iterator[list[ReferenceFrame]]:
        """Fresh ReferenceFrame objects (unregistered), the named ones in order.

        Built with the public constructor, so the frames are validated and
        prepared (sign continuity, missing samples) exactly as the user's
        frames were: the engine cannot tell them from the originals. On
        leaving, the frames are detached from each other: a tree is a
        reference cycle (parents list their children), so without this a
        worker would keep every finished task's window -- its samples and
        the engine's tables, which go with them -- until a full pass of the
        garbage collector.
        """
        frames = self._build()
        try:
            yield [frames[k] for k in self.named]
        finally:
            for frame in reversed(frames[1:]):
                frame.parent = None

    def _build(self) -> list[ReferenceFrame]:
        built: list[ReferenceFrame] = []
        for value in self.frames:
            if value.parent < 0:
                built.append(ReferenceFrame(value.name))
                continue
            built.append(
                ReferenceFrame(
                    value.name,
                    parent=built[value.parent],
                    translation=value.translation,
                    rotation=value.rotation,
                    timestamps=value.timestamps,
                    discrete=value.discrete,
                    max_gap=value.max_gap,
                )
            )
        return built
