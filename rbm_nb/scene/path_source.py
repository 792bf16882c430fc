"""Where a drawn path's positions come from: an array, or a track that looks them up.

A path given as an array (tests, paths of held tracks) is simplified and
refined whole (:mod:`rbm_nb.scene.decimate`). A path of a frame the scene
looks up (:class:`~rbm_nb.scene.looked_up.LookedUpTrack`) is never held
whole: its line is simplified and refined from its blocks, its extent is
its track's bounds. Both give the same lines.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Protocol

import numpy as np

from .decimate import (
    refine_region,
    refine_region_blocks,
    simplify_path,
    simplify_path_blocks,
)


class PathSource(Protocol):
    """Positions in blocks, their bounds, and all of them on request."""

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int] | None: ...

    def blocks(self) -> Iterator[np.ndarray]: ...

    def positions_with_gaps(self) -> np.ndarray: ...


Samples = np.ndarray | PathSource


def every_sample(source: Samples) -> np.ndarray:
    """Every position, shape (n, 3), NaN rows where missing (a whole array)."""
    return source if isinstance(source, np.ndarray) else source.positions_with_gaps()


def simplified(source: Samples, tolerance: float | None, max_points: int):
    """:func:`~rbm_nb.scene.decimate.simplify_path` of the positions."""
    if isinstance(source, np.ndarray):
        return simplify_path(source, tolerance, max_points)
    bounds = source.bounds
    if bounds is None:  # every sample missing
        return [], 0.0
    return simplify_path_blocks(
        source.blocks(), bounds[0], bounds[1], tolerance, max_points
    )


def refined(source: Samples, low, high, tolerance: float, max_points: int):
    """:func:`~rbm_nb.scene.decimate.refine_region` of the positions."""
    if isinstance(source, np.ndarray):
        return refine_region(source, low, high, tolerance, max_points)
    return refine_region_blocks(source.blocks(), low, high, tolerance, max_points)


def extent(source: Samples) -> tuple[np.ndarray, np.ndarray] | None:
    """Lowest and highest position (None when every sample is missing)."""
    if not isinstance(source, np.ndarray):
        bounds = source.bounds
        return None if bounds is None else (bounds[0], bounds[1])
    points = source[~np.isnan(source).any(axis=1)]
    return (points.min(axis=0), points.max(axis=0)) if len(points) else None
