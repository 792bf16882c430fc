"""Squad interpolation of a stored rotation series in one pass: numba, unchecked.

:func:`squad_walk` gives what ``unflip`` → ``squad`` → ``stored_signs`` give
together (``rbm_nb.quaternions.qinterp`` on one series), without their
temporaries: no sign-corrected copy of the input (only its signs), no
coefficient tables over every sample. The output times are walked in blocks
of :data:`_BLOCK` rows; the squad segments a block falls in are set up once,
from the samples around them, in scratch space of the size of a block
(every segment from the block's first to its last when they are few, else
only the segments used), and then serve every output time inside them.

When a block's segments are set up at once, short vector loops do the work:
over its samples (unit parts, scales), the steps between them (logs), its
segments (control points, then the two great-circle arcs) and its rows
(inner slerps, outer slerp, scale). They compute the common branch of each
formula (scales near 1, arcs within the series) in one flat scratch array
with fixed offsets, so that LLVM vectorises them without runtime checks;
whatever they do not cover (the ends of the series, wide arcs, scales off
the series, extrapolation, missing samples) is then done by the scalar code
with all its branches. Both compute the same expressions in the same order
and give the same bits (:func:`squad_walk_scalar` runs the scalar code
alone, for the tests).

Non-unit samples (recordings store quaternions with 4-7 digits) follow
numpy-quaternion's arithmetic, which treats them as a unit rotation times a
positive scale. Both parts separate exactly: the log of ``r[i]⁻¹ r[i+1]``
is ``ln(|r[i+1]| / |r[i]|)`` plus the log of the unit rotation, squad's
control points are unit control points times ``exp`` of a scalar, and
``slerp(a, b, τ) = |a|^(1-τ) |b|^τ slerp(â, b̂, τ)``. So the walk
interpolates unit quaternions along great circles (short series for the
small arcs of densely sampled data, no exp/log of quaternions) and
multiplies by one scalar per output row. Where a slerp would decide its
"shorter way round" differently for the scaled values within rounding, or
an output time lies outside its segment (extrapolation), or the scales are
far from 1, that row takes the exact route of
:func:`rbm_nb._kernels.quaternion.squad_evaluate` instead.

Quaternions are float64 (n, 4) arrays in ``w, x, y, z`` order.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import prange

from .._infra.config import PARALLEL_KERNEL
from ._jit import F1, F2, F, compiled_as, helper, kernel
from .search import gallop
from .squad_rows import _WR, _gather_records, _rows, _scalar_rows
from .squad_segments import (
    _BLOCK,
    _SERIAL,
    _SPAN,
    _WS,
    _controls_exact,
    _logs,
    _prepare,
    _records_exact,
    _samples,
)

__all__ = [
    "squad_walk",
    "squad_walk_parallel",
    "squad_walk_scalar",
    "unflip_signs",
    "squad_input_fault",
]

# the walk's options (squad_segments._SERIAL), and the same in parallel
_PARALLEL = dataclasses.replace(PARALLEL_KERNEL, fastmath=frozenset({"contract"}))

# chunks of output rows the parallel twin hands to numba's threads
_CHUNKS = 64


@kernel(F2)
def unflip_signs(q):
    """The signs ``unflip`` gives each row of ``q`` (n, 4): +1.0 or -1.0.

    ``unflip(q)[i] == unflip_signs(q)[i] * q[i]``; rows with NaN keep +1
    and are bridged (the next row is compared with the last valid one).
    """
    n = q.shape[0]
    out = np.empty(n)
    pw = px = py = pz = 0.0
    have = False
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        sign = 1.0
        if have and (pw * w + px * x + py * y + pz * z) < 0.0:
            sign = -1.0
        out[i] = sign
        if not math.isnan(w + x + y + z):
            pw, px, py, pz = sign * w, sign * x, sign * y, sign * z
            have = True
    return out


@helper(options=_SERIAL)
def _find_segments(t_in, t_out, start, stop, i, found):
    """Each row's sample index into ``found`` (the last sample at or before
    its time, -1 before the first), galloping forward from the previous
    row's ``i`` (sorted t_out) or by bisection when a time went back.

    Returns the last row's index and whether the block's times never went
    back.
    """
    ordered = True
    for j in range(start, stop):
        t = t_out[j]
        if i >= 0 and t < t_in[i]:
            i = -1
            ordered = False
        i = gallop(t_in, t, i)
        found[j - start] = i
    return i, ordered


@helper(options=_SERIAL)
def _set_up_segments(qf, sign, t_in, n, start, stop, found, ordered, scalar, ws, slot):
    """The block's segments in the scratch ``ws``, and each row's record slot.

    Dense (sorted times, few segments): every segment from the first to the
    last at once, in vector loops; else each new segment in the next free
    record, by the scalar code.
    """
    s0 = found[0]
    s1 = found[stop - start - 1]
    if ordered and s0 >= 0 and s1 - s0 < _SPAN and not scalar:
        # dense: every segment from the first to the last at once
        _prepare(qf, sign, t_in, n, s0, s1, ws)
        for j in range(start, stop):
            slot[j - start] = found[j - start] - s0
    else:
        # sparse or unordered: each new segment in the next free record
        loaded = -2
        free = 0
        for j in range(start, stop):
            i_j = found[j - start]
            seg = i_j if i_j >= 0 else n - 1  # numpy-quaternion indexes with -1
            if seg != loaded:
                # its samples in rows 0.. (sample seg in row 1), its
                # control points and record in the next free slot
                k0 = max(seg - 1, 0)
                k1 = min(seg + 2, n - 1)
                _samples(qf, sign, ws, k0, k1, k0 - seg + 1, scalar)
                _logs(t_in, ws, k0, k1, k0 - seg + 1, scalar)
                _controls_exact(ws, n, seg, free, 1)
                _records_exact(ws, n, seg, free, 1)
                loaded = seg
                free += 1
            slot[j - start] = free - 1


# The walk's parts are helpers of their own, not inlined into it: inlined
# (numba's inline="always"), _walk took 918 s to compile on the loaded
# 2-core VM where main's one-piece walk took 805 s and this one 763 s (the
# three compiled side by side). Each is called once per block, with the
# walk's options (fused multiply-add: the same rounding as inlined).
#
# Not inlined either: the three kernels below share one compiled walk (inlined into
# each, it made them the slowest kernels to compile by far: 116, 201 and 98 s
# of the warm-up's 746 s on the 2-core VM, the prange twin the worst, as
# numba's parfor passes went over the whole walk). One call per kernel call
# or prange chunk costs nothing measurable.
@helper(options=_SERIAL)
def _walk(q, sign, t_in, t_out, out, first, last, scalar):
    """Rows first..last-1 of :func:`squad_walk` (n >= 2), block by block;
    ``scalar``: every segment and row by the scalar code (see
    :func:`squad_walk_scalar`)."""
    n = q.shape[0]
    qf = q.reshape(-1)
    # scratch for one block of output rows: each row's sample index and
    # segment slot, the segments' samples, logs, control points and records
    # (at most _SPAN segments when set up at once; see _prepare), the rows'
    # records, τ, signs and inner slerps
    found = np.empty(_BLOCK, dtype=np.int64)
    slot = np.empty(_BLOCK, dtype=np.int64)
    ws = np.empty(_WS)
    wr = np.empty(_WR)
    of = out.reshape(-1)
    dt_last = t_in[n - 1] - t_in[n - 2]
    i = -1
    for start in range(first, last, _BLOCK):
        stop = min(start + _BLOCK, last)
        i, ordered = _find_segments(t_in, t_out, start, stop, i, found)
        _set_up_segments(
            qf, sign, t_in, n, start, stop, found, ordered, scalar, ws, slot
        )
        _gather_records(t_in, t_out, sign, n, dt_last, start, stop, found, slot, ws, wr)
        # the rows in vector loops, then the rows these do not cover
        if not (scalar or _rows(wr, of[4 * start :], stop - start)):
            continue
        _scalar_rows(q, sign, t_in, out, n, start, stop, found, slot, ws, wr, scalar)


def _walk_body(chunks: int, scalar: bool) -> Callable[..., Any]:
    """squad_walk's body for ``chunks`` chunks of output rows (1: serial).

    Each chunk is walked on its own (a prange loop: numba's threads in the
    parallel twin, a plain loop otherwise); a segment's value does not
    depend on the walk that reached it, so every twin gives the same bits.
    """

    def body(q, t_in, t_out):
        n = q.shape[0]
        m = t_out.shape[0]
        out = np.empty((m, 4))
        if n < 2 or m == 0:
            for j in range(m):
                for k in range(4):
                    out[j, k] = q[0, k]
            return out
        sign = unflip_signs(q)
        # whole blocks per chunk, many more chunks than threads (numba's
        # thread count is not read here: that would keep the kernel out of
        # the cache)
        size = ((m + chunks - 1) // chunks + _BLOCK - 1) // _BLOCK * _BLOCK
        for c in prange(chunks):
            _walk(
                q, sign, t_in, t_out, out,
                min(c * size, m), min((c + 1) * size, m), scalar,
            )  # fmt: skip
        return out

    return body


_SQUAD_WALK_DOC = """Squad of the stored series ``q`` at ``t_out``, with the stored signs.

    Equal (to rounding) to ``unflip``, ``squad`` on the result and the sign
    of the stored sample each output time starts from
    (:func:`rbm_nb._engine.chain.stored_signs`), including the edge
    behaviour of ``squad``; fastest for sorted ``t_out`` (each segment is
    set up once), correct for any order.

    Parameters
    ----------
    q : ndarray, shape (n, 4)
        Stored samples, non-zero (NaN rows are missing samples).
    t_in : ndarray, shape (n,)
        Strictly increasing sample times.
    t_out : ndarray, shape (m,)
        Times on the same origin as ``t_in``.

    Returns
    -------
    ndarray, shape (m, 4)
        NaN where the spline touches a missing sample.
    """

squad_walk = kernel(F2, F1, F1, options=_SERIAL)(
    compiled_as("squad_walk", _SQUAD_WALK_DOC, _walk_body(1, False))
)
squad_walk_parallel = kernel(F2, F1, F1, options=_PARALLEL)(
    compiled_as(
        "squad_walk_parallel",
        ":func:`squad_walk` with chunks of output rows on numba's threads.",
        _walk_body(_CHUNKS, False),
    )
)
squad_walk_scalar = kernel(F2, F1, F1, options=_SERIAL)(
    compiled_as(
        "squad_walk_scalar",
        """:func:`squad_walk` by its scalar code alone: every segment set up on
    its own (:func:`_unit`, :func:`_log_vec`, :func:`_controls_exact`,
    :func:`_records_exact`) and every row evaluated by the scalar route of
    :func:`_walk`.

    The vector loops compute the common branches of the same expressions,
    so the two agree bit for bit; the tests hold them to that.
    """,
        _walk_body(1, True),
    )
)


@kernel(F2, F1, F1, F)
def squad_input_fault(q, t_in, t_out, tol):
    """0 if :func:`squad_walk` may run on these inputs as qinterp takes them.

    Otherwise what is wrong first: 1 ``q`` (an infinity, or a norm farther
    than ``tol`` from 1; NaN rows pass), 2 ``t_in`` (empty, not finite or
    not strictly increasing; its length must be checked by the caller), 3
    ``t_out`` (not finite, or outside [t_in[0], t_in[-1]]). One pass over
    each array; the caller's own checks then name the culprit.
    """
    n = q.shape[0]
    # squared norms well inside the tolerance need no square root; only
    # rows near its edges (or beyond) are checked as the caller checks them
    inner_lo = (1.0 - tol) ** 2 * (1.0 + 1e-9)
    inner_hi = (1.0 + tol) ** 2 * (1.0 - 1e-9)
    suspect = 0
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        n2 = w * w + x * x + y * y + z * z
        inf = (abs(w) == np.inf) | (abs(x) == np.inf) | (abs(y) == np.inf)
        suspect += inf | (abs(z) == np.inf) | (n2 < inner_lo) | (n2 > inner_hi)
    if suspect:
        for i in range(n):
            w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
            if math.isinf(w) or math.isinf(x) or math.isinf(y) or math.isinf(z):
                return 1
            if abs(math.sqrt(w * w + x * x + y * y + z * z) - 1.0) > tol:
                return 1
    if n == 0:
        return 2
    bad = 0
    for i in range(n):
        bad += not math.isfinite(t_in[i])
    for i in range(1, n):
        bad += not t_in[i] > t_in[i - 1]
    if bad:
        return 2
    lo = t_in[0]
    hi = t_in[n - 1]
    for j in range(t_out.shape[0]):
        bad += not (lo <= t_out[j] <= hi)
    return 3 if bad else 0
