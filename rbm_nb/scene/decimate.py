"""A long 3D path reduced to the points that show on screen, gaps kept.

The path is simplified top-down (Ramer-Douglas-Peucker, the worst segment
first): a point is kept while some sample lies farther than ``tolerance``
from the line drawn, up to ``max_points`` points in all. Runs of missing
samples (NaN rows, and the rows a frame's ``max_gap`` inserts) break the
line, except where the jump across them is within ``tolerance`` (it could
not be seen) or where more runs than ``max_points`` allows would need their
own ends (the shortest jumps are joined first).

:data:`PATH_TOLERANCE` is the default tolerance as a fraction of the path's
bounding-box diagonal: 1/2000, half a pixel when the whole path spans a view
1000 pixels wide.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from .._kernels._arrays import kernel_array
from .._kernels.simplify import cell_pass, split_worst_first

#: default tolerance, as a fraction of the path's bounding-box diagonal
PATH_TOLERANCE = 1 / 2000
#: width of the grid cells of the first pass, as a share of the tolerance
CELL_SHARE = 0.25


def _runs(points: np.ndarray, gap_after: np.ndarray, tolerance: float, max_points: int):
    """(first, last) index pairs into ``points`` of the unbroken stretches.

    ``gap_after[j]``: samples are missing between ``points[j]`` and the next.
    """
    n = len(points)
    if n == 0:
        return []
    jumps = np.flatnonzero(gap_after[:-1])
    if len(jumps):
        size = np.linalg.norm(points[jumps + 1] - points[jumps], axis=1)
        breaks = jumps[size > tolerance]
        # every stretch needs its two ends: join the shortest jumps past the budget
        allowed = max(max_points // 2 - 1, 0)
        if len(breaks) > allowed:
            order = np.argsort(size[size > tolerance])[::-1][:allowed]
            breaks = np.sort(breaks[order])
    else:
        breaks = jumps
    firsts = np.r_[0, breaks + 1]
    lasts = np.r_[breaks, n - 1]
    return list(zip(firsts.tolist(), lasts.tolist(), strict=True))


def simplify_path(
    samples, tolerance: float | None = None, max_points: int = 1000
) -> tuple[list[np.ndarray], float]:
    """The stretches of the line to draw, and the largest error left.

    Parameters
    ----------
    samples : array_like, shape (n, 3)
        Positions in time order; NaN rows are missing samples.
    tolerance : float, optional
        Metres a sample may lie from the line drawn; by default
        :data:`PATH_TOLERANCE` of the bounding-box diagonal.
    max_points : int, default 1000
        Points kept in all (at least 2).

    Returns
    -------
    stretches : list of ndarray, shape (k, 3)
        Unbroken pieces of the line (k >= 1; a lone sample is one point).
    error : float
        Largest distance (m) of a sample from its own segment of the line
        drawn, a bound on its distance from the line (0 if every sample is
        kept).
    """
    samples = np.asarray(samples, dtype=np.float64).reshape(-1, 3)
    rows = np.flatnonzero(~np.isnan(samples).any(axis=1))
    points = samples[rows]
    if len(points) == 0:
        return [], 0.0
    if tolerance is None:
        diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
        tolerance = PATH_TOLERANCE * diagonal
    # first, samples in the grid cell of the one before them go: on a
    # recording at 200 Hz most do. A dropped sample is within the cell's
    # diagonal (slack) of a kept one, so the line is then drawn within the
    # tolerance less the slack of the samples kept
    gap_after = np.zeros(len(points), dtype=bool)
    gap_after[:-1] = np.diff(rows) > 1
    cell = CELL_SHARE * tolerance
    slack = 0.0
    if cell > 0 and len(points) > 2:
        cells = np.floor(points / cell)
        fresh = np.ones(len(points), dtype=bool)
        # the samples on both sides of a gap stay
        fresh[1:] = (cells[1:] != cells[:-1]).any(axis=1) | gap_after[:-1]
        fresh |= gap_after
        fresh[-1] = True
        if not fresh.all():
            points, gap_after = points[fresh], gap_after[fresh]
            slack = float(np.sqrt(3.0) * cell)
    return _simplified(points, gap_after, tolerance, slack, max_points)


def simplify_path_blocks(
    blocks: Iterable[np.ndarray],
    low: np.ndarray,
    high: np.ndarray,
    tolerance: float | None = None,
    max_points: int = 1000,
) -> tuple[list[np.ndarray], float]:
    """:func:`simplify_path` of a path handed over in blocks, same result.

    The grid-cell pass runs block by block (it compares each sample with
    the one before), so only the samples it keeps are ever held at once.

    Parameters
    ----------
    blocks : iterable of ndarray, shape (k, 3)
        The samples in time order, in consecutive blocks (NaN rows missing).
    low, high : ndarray, shape (3,)
        Lowest and highest coordinates of the samples that are not missing
        (the default tolerance is :data:`PATH_TOLERANCE` of their diagonal).
    tolerance, max_points
        As :func:`simplify_path`.
    """
    if tolerance is None:
        tolerance = PATH_TOLERANCE * float(np.linalg.norm(high - low))
    cell = CELL_SHARE * tolerance
    kept: list[np.ndarray] = []
    kept_gaps: list[np.ndarray] = []
    # the last sample seen, held back until it is known whether a gap
    # follows: [has_last, x, y, z, last_fresh, gap_pending, dropped]
    state = np.zeros(7)
    for block in blocks:
        # one kernel pass a block (numpy's dozen passes a block were ~0.1 s
        # of the 3 h head path); the same samples and flags
        points, gaps = cell_pass(kernel_array(block), float(cell), state)
        kept.append(points)
        kept_gaps.append(gaps)
    if state[0] == 0.0:
        return [], 0.0
    points = np.vstack([*kept, state[1:4][np.newaxis]])
    gap_after = np.r_[np.concatenate(kept_gaps), False].astype(bool)
    # (a pass over two samples or fewer drops none, as simplify_path skips it)
    slack = float(np.sqrt(3.0) * cell) if state[6] != 0.0 else 0.0
    return _simplified(points, gap_after, tolerance, slack, max_points)


def _simplified(points, gap_after, tolerance: float, slack: float, max_points: int):
    """The worst-first simplification of ``points`` after the cell pass."""
    runs = _runs(points, gap_after, tolerance, max_points)
    tolerance -= slack
    keep = np.zeros(len(points), dtype=bool)
    firsts = np.array([first for first, _ in runs], dtype=np.int64)
    lasts = np.array([last for _, last in runs], dtype=np.int64)
    # the worst segment first, in the kernel: points (m, 3) C-contiguous float64
    error = split_worst_first(
        np.ascontiguousarray(points),
        firsts,
        lasts,
        float(tolerance),
        int(max_points),
        keep,
    )
    stretches = [
        points[first : last + 1][keep[first : last + 1]] for first, last in runs
    ]
    return stretches, max(error, 0.0) + slack


def refine_region(
    samples: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    tolerance: float,
    max_points: int,
) -> tuple[list[np.ndarray], float]:
    """The stretches of the line through the box ``[low, high]``, finer.

    Every sample inside the box and the one on each side of every run of
    them (so the line reaches the box's edges) is simplified as
    :func:`simplify_path` does, at ``tolerance``, up to ``max_points``;
    samples outside break the line, as missing ones do.

    Parameters
    ----------
    samples : ndarray, shape (n, 3)
        The whole path, NaN rows where samples are missing (not copied).
    low, high : ndarray, shape (3,)
        Corners of the box, in the path's coordinates.
    tolerance : float
        Metres a sample may lie from the line drawn (> 0).
    max_points : int

    Returns
    -------
    stretches, error
        As :func:`simplify_path`; error is the largest distance left.
    """
    # NaN rows compare False: a missing sample is never inside
    inside = np.asarray(((samples >= low) & (samples <= high)).all(axis=1))
    near = inside.copy()
    near[1:] |= inside[:-1]
    near[:-1] |= inside[1:]
    rows = np.flatnonzero(near)
    return _refined(samples[rows], rows, tolerance, max_points)


def refine_region_blocks(
    blocks: Iterable[np.ndarray],
    low: np.ndarray,
    high: np.ndarray,
    tolerance: float,
    max_points: int,
) -> tuple[list[np.ndarray], float]:
    """:func:`refine_region` of a path handed over in consecutive blocks
    (same result): only the samples near the box are ever held."""
    picked: list[np.ndarray] = []
    picked_rows: list[np.ndarray] = []
    offset = 0
    # the previous block's last row, whether it was inside, and picked
    previous: np.ndarray | None = None
    previous_inside = previous_picked = False
    for block in blocks:
        if len(block) == 0:
            continue
        inside = np.asarray(((block >= low) & (block <= high)).all(axis=1))
        near = inside.copy()
        near[1:] |= inside[:-1]
        near[:-1] |= inside[1:]
        near[0] |= previous_inside
        if previous is not None and inside[0] and not previous_picked:
            picked.append(previous[np.newaxis])
            picked_rows.append(np.array([offset - 1]))
        rows = np.flatnonzero(near)
        picked.append(block[rows])
        picked_rows.append(rows + offset)
        previous = block[-1]
        previous_inside, previous_picked = bool(inside[-1]), bool(near[-1])
        offset += len(block)
    if not picked:
        return [], 0.0
    return _refined(
        np.vstack(picked), np.concatenate(picked_rows), tolerance, max_points
    )


def _refined(picked: np.ndarray, rows: np.ndarray, tolerance: float, max_points: int):
    """The line through the samples ``picked`` (rows ``rows`` of the path)."""
    if rows.size == 0:
        return [], 0.0
    # rows left out between two picked ones: a break, as a missing sample is
    breaks = np.flatnonzero(np.diff(rows) > 1) + 1
    if breaks.size:
        picked = np.insert(picked, breaks, np.nan, axis=0)
    return simplify_path(picked, tolerance, max_points)
