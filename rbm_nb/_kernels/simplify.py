"""The top-down split of a path, worst segment first (Ramer-Douglas-Peucker).

:func:`split_worst_first` is the inner loop of
:func:`rbm_nb.scene.decimate.simplify_path`: each run of points is one
segment at first; the segment whose farthest point lies farthest from it is
split there, until ``max_points`` points are kept or no point lies farther
than the tolerance. It keeps exactly the points the former numpy loop kept:

* the deviation is computed with the same arithmetic: the dot products go
  through BLAS as numpy's ``@`` does (``np.dot``: ``ddot`` for one point or
  the segment's length, ``dgemv`` for two points and more; their rounding,
  fused multiply-adds included, depends on the BLAS kernel),
  and the squared distances add ``x*x + z*z`` first, then ``y*y``, as numpy's
  ``einsum("ij,ij->i")`` does;
* the farthest point is the first of equal ones (``np.argmax``, a NaN
  counting as the largest);
* the heap is :mod:`heapq`'s binary heap, sifted the same way, ordered as
  the tuples ``(-error, at, first, last)`` compare.
"""

from __future__ import annotations

import numpy as np

from ._jit import F1, F2, I1, F, I, helper, kernel

__all__ = ["cell_pass", "split_worst_first"]

# the kept-point flags, written in place
B1 = "boolean[::1]"


#: points whose deviation is computed at a time: the scratch stays in the
#: cache (a long path's first splits read each point once from memory
#: instead of writing and reading a copy of the whole path)
CHUNK = 2048


@helper
def _deviation(points, a, b, offsets, alongs):
    """(distance, index) of the farthest of ``points[a+1:b]`` from segment a-b.

    ``offsets`` (CHUNK, 3) and ``alongs`` (CHUNK,): scratch, so that a split
    allocates nothing. The points are taken :data:`CHUNK` at a time: BLAS
    computes each row's dot product on its own (the same bits in any chunk).
    """
    if b - a < 2:
        return 0.0, -1
    k = b - a - 1
    start = points[a]
    direction = points[b] - start
    length2 = np.dot(direction, direction)
    best = 0.0
    at = 0
    for lo in range(0, k, CHUNK):
        m = min(CHUNK, k - lo)
        offset = offsets[:m]
        for i in range(m):
            for c in range(3):
                offset[i, c] = points[a + 1 + lo + i, c] - start[c]
        if length2 > 0:
            along = alongs[:m]
            if k == 1:  # numpy's matmul takes a (1, 3) @ (3,) as ddot
                along[0] = np.dot(offset[0], direction)
            else:
                np.dot(offset, direction, along)
            for i in range(m):
                t = along[i] / length2
                # np.clip: a NaN stays NaN
                if t < 0.0:
                    t = 0.0
                elif t > 1.0:
                    t = 1.0
                for c in range(3):
                    offset[i, c] = offset[i, c] - t * direction[c]
        for i in range(m):
            x, y, z = offset[i, 0], offset[i, 1], offset[i, 2]
            d2 = (x * x + z * z) + y * y
            if d2 != d2:  # np.argmax: the first NaN wins
                return np.sqrt(d2), a + 1 + lo + i
            if (lo == 0 and i == 0) or d2 > best:
                best = d2
                at = lo + i
    return np.sqrt(best), a + 1 + at


@helper
def _less(errors, ats, firsts, i, j):
    """Entry i < entry j, as the tuples (-error, at, first, last) compare."""
    if errors[i] != errors[j]:
        return errors[i] < errors[j]
    if ats[i] != ats[j]:
        return ats[i] < ats[j]
    # a segment's point at lies strictly inside it: equal at, equal segment
    return firsts[i] < firsts[j]


@helper
def _swap_in(errors, ats, firsts, lasts, to, frm):
    errors[to] = errors[frm]
    ats[to] = ats[frm]
    firsts[to] = firsts[frm]
    lasts[to] = lasts[frm]


@helper
def _sift_down(errors, ats, firsts, lasts, start, pos, spare):
    """heapq._siftdown: the entry at pos moves up towards start (entry ``spare`` is scratch)."""
    _swap_in(errors, ats, firsts, lasts, spare, pos)
    while pos > start:
        parent = (pos - 1) >> 1
        if _less(errors, ats, firsts, spare, parent):
            _swap_in(errors, ats, firsts, lasts, pos, parent)
            pos = parent
            continue
        break
    _swap_in(errors, ats, firsts, lasts, pos, spare)


@helper
def _sift_up(errors, ats, firsts, lasts, pos, end, spare):
    """heapq._siftup over entries [0, end): the smaller child rises to the leaf, then back."""
    start = pos
    _swap_in(errors, ats, firsts, lasts, spare, pos)
    child = 2 * pos + 1
    while child < end:
        right = child + 1
        if right < end and not _less(errors, ats, firsts, child, right):
            child = right
        _swap_in(errors, ats, firsts, lasts, pos, child)
        pos = child
        child = 2 * pos + 1
    _swap_in(errors, ats, firsts, lasts, pos, spare)
    _sift_down(errors, ats, firsts, lasts, start, pos, spare)


@kernel(F2, I1, I1, F, I, B1)
def split_worst_first(points, run_firsts, run_lasts, tolerance, max_points, keep):
    """Mark in ``keep`` the points kept; return the largest deviation left (-0.0/0.0 if none).

    ``points`` (m, 3) finite-or-not, no NaN rows; runs (first, last) index
    pairs in order; ``keep`` all False on entry.
    """
    m = points.shape[0]
    # at most one segment per point in the heap, plus one scratch entry
    size = m + 1
    errors = np.empty(size)  # -error, as the tuples held it
    ats = np.empty(size, dtype=np.int64)
    firsts = np.empty(size, dtype=np.int64)
    lasts = np.empty(size, dtype=np.int64)
    spare = m
    offsets = np.empty((min(m, CHUNK), 3))
    alongs = np.empty(min(m, CHUNK))
    n = 0
    for r in range(run_firsts.shape[0]):
        first, last = run_firsts[r], run_lasts[r]
        keep[first] = True
        keep[last] = True
        error, at = _deviation(points, first, last, offsets, alongs)
        if at >= 0:
            errors[n] = -error
            ats[n] = at
            firsts[n] = first
            lasts[n] = last
            n += 1
    for i in range(n // 2 - 1, -1, -1):  # heapq.heapify
        _sift_up(errors, ats, firsts, lasts, i, n, spare)
    count = 0
    for i in range(m):
        if keep[i]:
            count += 1
    while n > 0 and count < max_points and -errors[0] > tolerance:
        at, first, last = ats[0], firsts[0], lasts[0]
        # heapq.heappop: the last entry to the top, sifted
        n -= 1
        if n > 0:
            _swap_in(errors, ats, firsts, lasts, 0, n)
            _sift_up(errors, ats, firsts, lasts, 0, n, spare)
        keep[at] = True
        count += 1
        for half in range(2):
            a = first if half == 0 else at
            b = at if half == 0 else last
            error, where = _deviation(points, a, b, offsets, alongs)
            if where >= 0:  # heapq.heappush
                errors[n] = -error
                ats[n] = where
                firsts[n] = a
                lasts[n] = b
                _sift_down(errors, ats, firsts, lasts, 0, n, spare)
                n += 1
    return -errors[0] if n > 0 else 0.0


@kernel(F2, F, F1)
def cell_pass(block, cell, state):
    """The grid-cell pass of ``scene.decimate.simplify_path_blocks`` over one
    block: (kept samples (k, 3), whether missing rows follow each (k,)).

    A sample in the grid cell of the sample before it goes, unless missing
    rows come before or after it (``cell`` <= 0: none goes). The last
    sample seen is held back until the next one says whether a gap follows
    it; ``state`` carries it from block to block, updated in place:
    ``[has_last, x, y, z, last_fresh, gap_pending, dropped]`` (flags 0/1).
    The cells are ``floor(p / cell)`` as numpy computes them.
    """
    n = block.shape[0]
    out = np.empty((n + 1, 3))
    out_gaps = np.empty(n + 1, dtype=np.bool_)
    k = 0
    has_last = state[0] != 0.0
    lx, ly, lz = state[1], state[2], state[3]
    last_fresh = state[4] != 0.0
    gap = state[5] != 0.0
    dropped = state[6] != 0.0
    for i in range(n):
        x, y, z = block[i, 0], block[i, 1], block[i, 2]
        if x != x or y != y or z != z:
            if has_last:
                gap = True
            continue
        if not has_last:
            has_last = True
            lx, ly, lz = x, y, z
            last_fresh = True
            gap = False
            continue
        fresh = True
        if cell > 0:
            fresh = (
                gap
                or np.floor(x / cell) != np.floor(lx / cell)
                or np.floor(y / cell) != np.floor(ly / cell)
                or np.floor(z / cell) != np.floor(lz / cell)
            )
        if last_fresh or gap:  # a sample next to missing rows stays
            out[k, 0] = lx
            out[k, 1] = ly
            out[k, 2] = lz
            out_gaps[k] = gap
            k += 1
        else:
            dropped = True
        lx, ly, lz = x, y, z
        last_fresh = fresh
        gap = False
    state[0] = 1.0 if has_last else 0.0
    state[1] = lx
    state[2] = ly
    state[3] = lz
    state[4] = 1.0 if last_fresh else 0.0
    state[5] = 1.0 if gap else 0.0
    state[6] = 1.0 if dropped else 0.0
    # copies: the block's scratch is not kept with the few samples that stay
    return out[:k].copy(), out_gaps[:k].copy()
