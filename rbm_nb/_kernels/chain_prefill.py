"""The squad table rows a parallel chain call will read, filled beforehand.

The lazily filled squad tables (:mod:`.squad_table`) must never be written
by two threads, nor read half-written. So before a prange twin of
:mod:`.fused` runs, :func:`prefill_chain` computes every table row the call
will read: per chunk of target rows (the twin's chunks), the range of
segments its squad evaluations use (a merge walk with the serial kernel's
rules: the frame's own sample times and rows inside a gap read no table
row); the ranges merged into disjoint intervals; and their missing rows
filled in pieces shared out to the threads. The twins then only read the
tables. The engine calls both under its table lock, as one launch
(rbm_nb._engine.fused).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from .._infra.config import PARALLEL_KERNEL
from ._jit import F1, F2, I1, helper, kernel
from .chain_block import SLOT_TYPES, SLOTS, SQUAD
from .chain_rows import BLOCK
from .search import gallop
from .squad_table import RUN, _fill_range

__all__ = ["CHUNKS", "prefill_chain"]

# Chunks per call: enough for many threads (numba hands each thread an equal
# run of consecutive chunks). A fixed number rather than one per thread:
# ``numba.get_num_threads()`` inside a kernel makes it uncacheable (numba
# reaches the threading layer through a ctypes pointer), and a chunk costs
# only one binary search per moving frame.
CHUNKS = 128


@helper
def _chunk_bounds(m, chunks):
    """Row bounds (k+1,) of at most ``chunks`` chunks of whole blocks over m rows."""
    blocks = (m + BLOCK - 1) // BLOCK
    k = max(min(chunks, blocks), 1)
    per = max((blocks + k - 1) // k, 1)
    k = max((blocks + per - 1) // per, 1)
    bounds = np.empty(k + 1, dtype=np.int64)
    for c in range(k + 1):
        bounds[c] = min(c * per * BLOCK, m)
    return bounds


@helper
def _segments_read(times, own, gap, off, target, j0, j1, increasing):
    """The squad table rows read by rows j0:j1, as (lo, hi, last), or more.

    Rows lo..hi (lo > hi: none), and whether row n-1 is read by a target
    before the first sample. The rules of ``_chain_block``: a sample time
    of the frame's own times and a time inside a gap read no row. With
    ``increasing`` target times (never decreasing from j0 to j1), for a
    frame not evaluated at its own times, the range also takes in the rows
    no time reads between the first and the last.
    """
    n = times.shape[0]
    if j1 <= j0:
        return n, -1, False
    if own != 0:
        # the target times said to be the frame's own, from sample own - 1:
        # if they are (one vectorised comparison), no row is read
        i0 = own - 1 + j0
        if off == 0.0 and i0 >= 0 and i0 + (j1 - j0) <= n:
            odd = 0
            for j in range(j1 - j0):
                odd += np.int64(target[j0 + j] != times[i0 + j])
            if odd == 0:
                return n, -1, False
    elif increasing:
        # (the engine's targets always are) every row from the first time's
        # segment to the last one's, found by two searches instead of a walk
        # over the rows; rows no time reads (inside a gap, between two
        # times) are filled too: rows hold the same values whoever fills them
        a = gallop(times, target[j0] + off, -1)
        b = gallop(times, target[j1 - 1] + off, a)
        if b < 0:
            return n, -1, True  # every time before the first sample
        return max(a, 0), b, a < 0
    lo = n
    hi = -1
    last = False
    i = -1
    for j in range(j0, j1):
        t = target[j] + off
        i = gallop(times, t, i)
        if own != 0 and i >= 0 and t == times[i]:
            continue
        if 0 <= i < n - 1 and t != times[i] and times[i + 1] - times[i] > gap:
            continue
        if i < 0:
            last = True
        else:
            lo = min(lo, i)
            hi = max(hi, i)
    return lo, hi, last


@helper
def _fill_pieces(plan, sizes, lo, hi, last, pieces_wanted):
    """The table rows to fill: disjoint intervals, and pieces of them.

    ``lo``, ``hi``, ``last`` (SLOTS, chunks) as from :func:`_segments_read`;
    ``sizes`` (SLOTS,) the tables' lengths. Per slot the chunks' ranges are
    merged into disjoint intervals (q, 3): (slot, start, stop), ranges less
    than RUN rows apart into one, then cut
    into about ``pieces_wanted`` pieces (p, 3) of at least RUN rows overall.
    """
    nch = lo.shape[1]
    starts = np.empty(nch + 1, dtype=np.int64)
    stops = np.empty(nch + 1, dtype=np.int64)
    # merged intervals of every slot, (slot, start, stop)
    merged = np.empty((SLOTS * (nch + 1), 3), dtype=np.int64)
    count = 0
    total = 0
    for s in range(plan.shape[0] // 3):
        if plan[3 * s] != SQUAD:
            continue
        slot = plan[3 * s + 1]
        k = 0
        need_last = False
        for ch in range(nch):
            if lo[slot, ch] <= hi[slot, ch]:
                starts[k] = lo[slot, ch]
                stops[k] = hi[slot, ch] + 1
                k += 1
            need_last = need_last or last[slot, ch]
        if need_last:
            starts[k] = sizes[slot] - 1
            stops[k] = sizes[slot]
            k += 1
        if k == 0:
            continue
        order = np.argsort(starts[:k])
        a = starts[order[0]]
        b = stops[order[0]]
        for q in range(1, k):
            sa = starts[order[q]]
            sb = stops[order[q]]
            if sa <= b + RUN:
                # a short hole (segments no target falls in, such as a
                # dropout of the target clock) is filled too, as the serial
                # kernels' runs would: the interval stays whole, and later
                # calls inside it find every row they read computed
                b = max(b, sb)
            else:
                merged[count, 0] = slot
                merged[count, 1] = a
                merged[count, 2] = b
                count += 1
                total += b - a
                a, b = sa, sb
        merged[count, 0] = slot
        merged[count, 1] = a
        merged[count, 2] = b
        count += 1
        total += b - a
    size = max(RUN, (total + pieces_wanted - 1) // max(pieces_wanted, 1))
    n_pieces = 0
    for q in range(count):
        n_pieces += (merged[q, 2] - merged[q, 1] + size - 1) // size
    pieces = np.empty((n_pieces, 3), dtype=np.int64)
    p = 0
    for q in range(count):
        for a in range(merged[q, 1], merged[q, 2], size):
            pieces[p, 0] = merged[q, 0]
            pieces[p, 1] = a
            pieces[p, 2] = min(a + size, merged[q, 2])
            p += 1
    return merged[:count], pieces


@kernel(I1, F2, F1, F1, I1, *SLOT_TYPES, F1, options=PARALLEL_KERNEL)
def prefill_chain(
    plan, statics, offsets, gaps, own, slot_times, slot_t, slot_s, slot_p, slot_c,
    target,
):  # fmt: skip
    """Compute every squad table row a call at these target times will read.

    The rows on all threads (``prange``); afterwards :func:`lookup_chain_parallel`
    and :func:`transform_chain_parallel` at the same targets only read the
    tables. Arguments as for :func:`lookup_chain`.

    Returns
    -------
    computed : int
        Rows of the squad tables computed.
    filled : ndarray, shape (q, 3)
        Disjoint intervals (slot, start, stop) of table rows that are all
        computed now: every row the call reads is in one of them.
    """
    m = target.shape[0]
    bounds = _chunk_bounds(m, CHUNKS)
    nch = bounds.shape[0] - 1
    lo = np.zeros((SLOTS, nch), dtype=np.int64)
    hi = np.full((SLOTS, nch), -1, dtype=np.int64)
    last = np.zeros((SLOTS, nch), dtype=np.bool_)
    sizes = np.empty(SLOTS, dtype=np.int64)
    for k in range(SLOTS):
        sizes[k] = slot_times[k].shape[0]
    # the walk is a few ns per row: serial, as every parallel region costs a
    # wait for the other threads (milliseconds when another process keeps
    # their core busy), and a first call already has two (fill, evaluate)
    for ch in range(nch):
        # whether the chunk's times never decrease: one vectorised pass,
        # shared by the chunk's frames
        decreasing = 0
        for j in range(bounds[ch], bounds[ch + 1] - 1):
            decreasing += np.int64(target[j + 1] < target[j])
        for s in range(plan.shape[0] // 3):
            if plan[3 * s] != SQUAD:
                continue
            slot = plan[3 * s + 1]
            a, b, before = _segments_read(
                slot_times[slot], own[slot], gaps[slot], offsets[slot],
                target, bounds[ch], bounds[ch + 1], decreasing == 0,
            )  # fmt: skip
            lo[slot, ch] = a
            hi[slot, ch] = b
            last[slot, ch] = before
    filled, pieces = _fill_pieces(plan, sizes, lo, hi, last, CHUNKS)
    computed = 0
    for p in prange(pieces.shape[0]):
        slot = pieces[p, 0]
        computed += _fill_range(
            slot_s[slot], slot_p[slot], slot_times[slot], slot_c[slot],
            pieces[p, 1], pieces[p, 2],
        )  # fmt: skip
    return computed, filled
