"""A panel's rows at a pixel width: min/max (M4) decimation, gaps as NaN rows.

The plot never needs more than a few rows per pixel column to look exactly
like the full series: the first and last row of the column (so the line
enters and leaves it where it should), each component's minimum and maximum
(so peaks such as saccades survive), and the first missing sample (so a run of
missing samples still breaks the line). That is M4 (Jugel et al., VLDB 2014)
plus the gap row; only recorded samples are kept, never an average.

Nothing here copies a whole series: the kept rows are chosen with temporaries
of one component at a time and only the kept rows are gathered. Pauses in the
timestamps are not written into the series either (that was a copy of every
array): ``pause_rows`` finds them once, ``pause_sides`` keeps both rows of
each column's first pause (as M4 keeps its first missing sample), and a NaN
row is put between the two kept rows on each side of a pause only in what is
sent.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._infra.frozen import kernel_alias
from .._kernels import m4 as _m4
from .._kernels._arrays import kernel_array

#: Median sample intervals a pause must exceed to be drawn as a gap.
GAP_FACTOR = 10.0


class Cancelled(Exception):
    """A newer request made this one pointless (raised between steps)."""


def pause_rows(x: np.ndarray, gap: float | None) -> tuple[np.ndarray, float | None]:
    """Rows ``i`` after which the timestamps pause longer than ``gap``.

    ``x`` are the raw timestamps as numbers (seconds, or int64 ns with ``gap``
    in the same unit). Default ``gap``: ``GAP_FACTOR`` median intervals.
    Returns the rows and the threshold used (None: nothing to measure).
    """
    if x.size < 2:
        return np.empty(0, dtype=np.int64), gap
    dt = np.diff(x)
    if gap is None:
        positive = dt[dt > 0]
        if positive.size == 0:
            return np.empty(0, dtype=np.int64), None
        # (positive is a fresh array: partitioned in place, not copied again)
        gap = GAP_FACTOR * float(np.median(positive, overwrite_input=True))
    return np.flatnonzero(dt > gap), gap


#: Rows per step of :func:`m4_rows`: bounds its temporaries (a few times 8 MB)
#: whatever the series' length, and is where a cancelled request stops.
CHUNK_ROWS = 1 << 20


def m4_rows(
    x: np.ndarray,
    y: np.ndarray,
    lo: float,
    hi: float,
    width: int,
    cancelled: Callable[[], bool] = lambda: False,
) -> np.ndarray:
    """Rows of ``y`` that draw ``[lo, hi]`` exactly at ``width`` pixel columns.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Sorted timestamps of the rows as numbers (any unit, same as lo, hi).
    y : ndarray, shape (n, k)
        Values, NaN where missing.
    lo, hi : float
        The range drawn (lo < hi); rows outside fall in the edge columns.
    width : int
        Pixel columns.
    cancelled : callable
        Asked before each step of ``CHUNK_ROWS`` rows; when it returns True,
        :class:`Cancelled` is raised.

    Returns
    -------
    ndarray of int, sorted
        Per column: its first and last row, each component's minimum and
        maximum row and its first missing row.
    """
    n = y.shape[0]
    if n == 0:
        return np.empty(0, dtype=np.int64)
    # where each column starts, found by bisection: no per-row column array
    edges = lo + (hi - lo) * (np.arange(1, width) / width)
    starts = np.unique(np.r_[0, np.searchsorted(x, edges, side="left")])
    starts = starts[starts < n]
    ends = np.r_[starts[1:], n]
    keep = [starts, ends - 1]
    # steps of whole columns, about CHUNK_ROWS rows each
    step_at = np.unique(
        np.searchsorted(starts, np.arange(0, n, CHUNK_ROWS), side="right") - 1
    )
    step_at = np.r_[step_at, starts.size]
    for a, b in zip(step_at[:-1], step_at[1:], strict=True):
        if cancelled():
            raise Cancelled
        r0, r1 = starts[a], ends[b - 1]
        local = starts[a:b] - r0
        keep.extend(rows + r0 for rows in _extremes(y[r0:r1], local))
    rows = np.unique(np.concatenate(keep))
    return rows[rows < n]


def _extremes(y: np.ndarray, starts: np.ndarray) -> list[np.ndarray]:
    """Per column (rows from each of ``starts``): each component's min, max and first missing row."""
    values = y if y.dtype == np.float64 and y.flags.c_contiguous else kernel_array(y)
    rows = _m4.column_extremes(
        kernel_alias(values), np.ascontiguousarray(starts, dtype=np.int64)
    )
    return [rows[rows >= 0]]


def _extremes_by_numpy(y: np.ndarray, starts: np.ndarray) -> list[np.ndarray]:
    """:func:`_extremes` by numpy (the kernel's twin, for its tests)."""
    n, k = y.shape
    counts = np.diff(np.r_[starts, n])
    index = np.arange(n)
    out = []
    for c in range(k):
        values = y[:, c]
        missing = np.isnan(values)
        for fill, reduce in ((np.inf, np.minimum), (-np.inf, np.maximum)):
            filled = np.where(missing, fill, values)
            extreme = np.repeat(reduce.reduceat(filled, starts), counts)
            # the first row holding the column's extreme (an all-missing
            # column: its first row, kept anyway)
            out.append(
                np.minimum.reduceat(np.where(filled == extreme, index, n), starts)
            )
        first_missing = np.minimum.reduceat(np.where(missing, index, n), starts)
        out.append(first_missing[first_missing < n])
    return out


def pause_sides(
    x: np.ndarray, pauses: np.ndarray, lo: float, hi: float, width: int
) -> np.ndarray:
    """The rows on both sides of the first pause in each of ``width`` columns.

    ``pauses`` are rows ``i`` after which the timestamps ``x`` pause (see
    :func:`pause_rows`); kept with ``i + 1``, such a pause draws as a gap in
    the decimated rows as in the full series (at most two rows per column,
    whatever the number of pauses). Rows past the end of ``x`` are left out.
    """
    if pauses.size == 0:
        return np.empty(0, dtype=np.int64)
    column = np.floor((x[pauses] - lo) / (hi - lo) * width)
    first = pauses[np.unique(column, return_index=True)[1]]
    rows = np.r_[first, first + 1]
    return rows[rows < x.shape[0]]


def gathered(
    xs: np.ndarray, y: np.ndarray, rows: np.ndarray, pauses: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``xs`` (the kept rows' x) and ``y[rows]`` with a NaN row in every kept pause.

    A pause after row ``i`` shows when both ``i`` and ``i + 1`` are kept: a
    row at their midpoint with every value NaN goes between them. (A pause
    whose sides are not both kept is narrower than a pixel column.)
    """
    ys = y[rows]
    if pauses.size == 0 or rows.size < 2:
        return xs, ys
    after = np.flatnonzero((np.diff(rows) == 1) & np.isin(rows[:-1], pauses))
    if after.size == 0:
        return xs, ys
    mid = xs[after] + (xs[after + 1] - xs[after]) / 2
    return (
        np.insert(xs, after + 1, mid),
        np.insert(ys, after + 1, np.nan, axis=0),
    )
