"""Angular velocity of a chain of frames without its rotations in memory: numba, unchecked.

:func:`chain_body_rates` gives, bit for bit, what the chain's rotations
(:func:`rbm_nb._kernels.fused.lookup_chain`, rotation only) followed by
:func:`rbm_nb._kernels.velocity_fused.body_rates` (and, for rates in the
reference's axes, a rotation of each rate by its row's rotation) give,
without holding the (n, 4) rotations. The chain is evaluated twice, a run
of :data:`SUPER` rows at a time into a small buffer: once for the forward
sweep of the spline's tridiagonal system, and once, runs in reverse, for
the back substitution and the rates. Both evaluate the same rows with the
same arithmetic (a run's segment search starts afresh, as the parallel
twins' chunks do, and the segment of a time does not depend on where the
search started).

That second evaluation is the price: about 1.4 times the time of the
lookup and estimate on one thread, 1.2 times on two. What it buys is
memory. Besides the result (24 bytes per row) the kernel keeps the ``w``
slopes (8 bytes per row), a bit per row for the sign flips, and the
elimination's factor at each block's first row (a block's factors are
recomputed from it with the sweep's arithmetic): 1.35 times the result,
where the rotations, the estimate's arrays and the rotated copy came to
3.3 times.

The chain's arguments are those of :mod:`rbm_nb._kernels.fused`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import prange

from .._infra.config import PARALLEL_KERNEL
from ._jit import F1, F2, I1, I, compiled_as, helper, kernel  # noqa: E741
from .chain_block import SLOT_TYPES, SLOTS, _chain_block
from .chain_rows import _ACC, BLOCK, WORK
from .quaternion import _rotate1

__all__ = ["BODY", "REFERENCE", "chain_body_rates", "chain_body_rates_parallel"]

# the axes the rates are given in
BODY = 0  # the moving frame's (2 q⁻¹ dq/dt)
REFERENCE = 1  # the reference frame's (each row rotated by its rotation)

_W = _ACC + 3 * BLOCK  # the block's rotations in the chain's scratch: w, x, y, z
_X = _ACC + 4 * BLOCK
_Y = _ACC + 5 * BLOCK
_Z = _ACC + 6 * BLOCK


@helper(inline=True)
def _factor(t, i, n, prev, d_start, d_end):
    """Row i's elimination step: (1 / pivot, factor), as ``body_rates`` forms them."""
    h_prev = t[i] - t[i - 1]
    h_i = t[i + 1] - t[i]
    sub = h_i
    diag = 2.0 * (h_prev + h_i)
    if i == 1:
        diag = d_start
        sub = 0.0
    if i == n - 2:
        diag = d_end
    inv = 1.0 / (diag - sub * prev)
    return inv, h_prev * inv


@helper(inline=True)
def _end_row(h0, h1, d_start, aw, bw, cw):
    """``r_start``'s component from three signed samples (h0, h1 their intervals)."""
    da = (bw - aw) * (1.0 / h0)
    db = (cw - bw) * (1.0 / h1)
    return ((h0 + 2.0 * d_start) * h1 * da + h0 * h0 * db) / d_start


@helper(inline=True)
def _last_row(hm, hm1, d_end, aw, bw, cw):
    """``r_end``'s component from the last three signed samples."""
    dc = (bw - aw) * (1.0 / hm1)
    dd = (cw - bw) * (1.0 / hm)
    return (hm * hm * dc + (2.0 * d_end + hm) * hm1 * dd) / d_end


# rows evaluated at a time (a multiple of BLOCK): their rotations wait in a
# buffer (96 KiB) for the sequential sweep; the parallel kernel evaluates
# them in CHUNKS pieces on all threads
SUPER = 32 * BLOCK
CHUNKS = 8

# the sweep's state between runs of rows, in one array
_A = 0  # 0:4 signed sample i - 2 (w, x, y, z)
_B = 4  # 4:8 signed sample i - 1
_S = 8  # 8:12 r_start
_E = 12  # 12:16 r_end
_PREV = 16  # the last elimination factor
_F = 17  # 17:21 row i + 1's final slopes (the back substitution)
_STATE = 21


@helper
def _evaluate(
    plan, statics, offsets, gaps, own,
    slot_times, slot_t, slot_s, slot_p, slot_c,
    target, j0, j1, base, rows, work, cur,
):  # fmt: skip
    """The chain's rotations at target[j0:j1] into ``rows[j - base]`` (w, x, y, z)."""
    computed = 0
    for k0 in range(j0, j1, BLOCK):
        k1 = min(k0 + BLOCK, j1)
        computed += _chain_block(
            plan, statics, offsets, gaps, own,
            slot_times, slot_t, slot_s, slot_p, slot_c,
            target, k0, k1, work, cur, True,
        )  # fmt: skip
        for b in range(k1 - k0):
            j = k0 + b - base
            rows[j, 0] = work[_W + b]
            rows[j, 1] = work[_X + b]
            rows[j, 2] = work[_Y + b]
            rows[j, 3] = work[_Z + b]
    return computed


@helper
def _forward(rows, s0, s1, t, out, slope_w, flips, checkpoint, st):
    """The forward sweep as rows s0:s1 arrive (``rows[i - s0]``); 1 if one is missing.

    The sweep runs one row behind the arriving rows: row i - 1's step needs
    the signed samples i - 2, i - 1 and i.
    """
    n = t.shape[0]
    h0 = t[1] - t[0]
    h1 = t[2] - t[1]
    hm = t[n - 1] - t[n - 2]
    hm1 = t[n - 2] - t[n - 3]
    d_start = h0 + h1
    d_end = hm + hm1
    aw, ax, ay, az = st[_A], st[_A + 1], st[_A + 2], st[_A + 3]
    bw, bx, by, bz = st[_B], st[_B + 1], st[_B + 2], st[_B + 3]
    sw, s0_, s1_, s2_ = st[_S], st[_S + 1], st[_S + 2], st[_S + 3]
    ew, e0, e1, e2 = st[_E], st[_E + 1], st[_E + 2], st[_E + 3]
    prev = st[_PREV]
    for i in range(s0, s1):
        w, x, y, z = rows[i - s0, 0], rows[i - s0, 1], rows[i - s0, 2], rows[i - s0, 3]
        n2 = w * w + x * x + y * y + z * z
        if math.isnan(n2) or n2 == 0.0:
            return 1
        flip = i > 0 and (bw * w + bx * x + by * y + bz * z) < 0.0
        s = 1.0
        if flip:
            s = -1.0
            flips[i >> 3] |= 1 << (i & 7)
        cw, cx, cy, cz = s * w, s * x, s * y, s * z
        if i == 2:
            sw = _end_row(h0, h1, d_start, aw, bw, cw)
            s0_ = _end_row(h0, h1, d_start, ax, bx, cx)
            s1_ = _end_row(h0, h1, d_start, ay, by, cy)
            s2_ = _end_row(h0, h1, d_start, az, bz, cz)
        if i == n - 1:
            ew = _last_row(hm, hm1, d_end, aw, bw, cw)
            e0 = _last_row(hm, hm1, d_end, ax, bx, cx)
            e1 = _last_row(hm, hm1, d_end, ay, by, cy)
            e2 = _last_row(hm, hm1, d_end, az, bz, cz)
        if i >= 2:
            k = i - 1  # the row whose step is taken now
            if k % BLOCK == 0:
                checkpoint[k // BLOCK] = prev
            inv, cp = _factor(t, k, n, prev, d_start, d_end)
            h_prev = t[k] - t[k - 1]
            h_k = t[k + 1] - t[k]
            inv_prev = 1.0 / h_prev
            inv_k = 1.0 / h_k
            rw = 3.0 * (h_k * ((bw - aw) * inv_prev) + h_prev * ((cw - bw) * inv_k))
            rx = 3.0 * (h_k * ((bx - ax) * inv_prev) + h_prev * ((cx - bx) * inv_k))
            ry = 3.0 * (h_k * ((by - ay) * inv_prev) + h_prev * ((cy - by) * inv_k))
            rz = 3.0 * (h_k * ((bz - az) * inv_prev) + h_prev * ((cz - bz) * inv_k))
            if k == 1:
                rw -= sw
                rx -= s0_
                ry -= s1_
                rz -= s2_
            if k == n - 2:
                rw -= ew
                rx -= e0
                ry -= e1
                rz -= e2
            if k > 1:
                rw -= h_k * slope_w[k - 1]
                rx -= h_k * out[k - 1, 0]
                ry -= h_k * out[k - 1, 1]
                rz -= h_k * out[k - 1, 2]
            slope_w[k] = rw * inv
            out[k, 0] = rx * inv
            out[k, 1] = ry * inv
            out[k, 2] = rz * inv
            prev = cp
        aw, ax, ay, az = bw, bx, by, bz
        bw, bx, by, bz = cw, cx, cy, cz
    st[_A], st[_A + 1], st[_A + 2], st[_A + 3] = aw, ax, ay, az
    st[_B], st[_B + 1], st[_B + 2], st[_B + 3] = bw, bx, by, bz
    st[_S], st[_S + 1], st[_S + 2], st[_S + 3] = sw, s0_, s1_, s2_
    st[_E], st[_E + 1], st[_E + 2], st[_E + 3] = ew, e0, e1, e2
    st[_PREV] = prev
    return 0


@helper
def _backward(rows, s0, s1, t, out, slope_w, flips, checkpoint, factors, st, axes):
    """Back substitution and rates for rows s1 - 1 down to s0 (``rows[i - s0]``).

    Row i's slopes are final once row i + 1's are (kept in ``st``, as the
    rates are written over the stored slopes). Each block's elimination
    factors are recomputed from its checkpoint with the sweep's arithmetic.
    """
    n = t.shape[0]
    h0 = t[1] - t[0]
    h1 = t[2] - t[1]
    hm = t[n - 1] - t[n - 2]
    hm1 = t[n - 2] - t[n - 3]
    d_start = h0 + h1
    d_end = hm + hm1
    sw, s0_, s1_, s2_ = st[_S], st[_S + 1], st[_S + 2], st[_S + 3]
    ew, e0, e1, e2 = st[_E], st[_E + 1], st[_E + 2], st[_E + 3]
    fw, fx, fy, fz = st[_F], st[_F + 1], st[_F + 2], st[_F + 3]
    for j0 in range(s1 - 1 - (s1 - 1 - s0) % BLOCK, s0 - 1, -BLOCK):
        j1 = min(j0 + BLOCK, s1)
        p = checkpoint[j0 // BLOCK]
        for i in range(max(j0, 1), min(j1, n - 1)):
            _, cp = _factor(t, i, n, p, d_start, d_end)
            factors[i - j0] = cp
            p = cp
        for i in range(j1 - 1, j0 - 1, -1):
            if i == n - 1:
                dw = (ew - d_end * slope_w[n - 2]) / hm1
                dx = (e0 - d_end * out[n - 2, 0]) / hm1
                dy = (e1 - d_end * out[n - 2, 1]) / hm1
                dz = (e2 - d_end * out[n - 2, 2]) / hm1
            elif i == n - 2:
                dw, dx, dy, dz = slope_w[i], out[i, 0], out[i, 1], out[i, 2]
            elif i > 0:
                cp = factors[i - j0]
                dw = slope_w[i] - cp * fw
                dx = out[i, 0] - cp * fx
                dy = out[i, 1] - cp * fy
                dz = out[i, 2] - cp * fz
            else:
                dw = (sw - d_start * fw) / h1
                dx = (s0_ - d_start * fx) / h1
                dy = (s1_ - d_start * fy) / h1
                dz = (s2_ - d_start * fz) / h1
            if i != n - 1:
                fw, fx, fy, fz = dw, dx, dy, dz
            qw, qx, qy, qz = (
                rows[i - s0, 0],
                rows[i - s0, 1],
                rows[i - s0, 2],
                rows[i - s0, 3],
            )
            s = -1.0 if (flips[i >> 3] >> (i & 7)) & 1 else 1.0
            w, x, y, z = s * qw, s * qx, s * qy, s * qz
            f = 2.0 / (w * w + x * x + y * y + z * z)
            vx = f * (w * dx - dw * x - (y * dz - z * dy))
            vy = f * (w * dy - dw * y - (z * dx - x * dz))
            vz = f * (w * dz - dw * z - (x * dy - y * dx))
            if axes == REFERENCE:
                vx, vy, vz = _rotate1(qw, qx, qy, qz, vx, vy, vz)
            out[i, 0] = vx
            out[i, 1] = vy
            out[i, 2] = vz
    st[_F], st[_F + 1], st[_F + 2], st[_F + 3] = fw, fx, fy, fz


@helper
def _buffers(n):
    """The result and the sweep's arrays for n rows (see the module docstring)."""
    out = np.empty((n, 3))
    slope_w = np.empty(n)
    flips = np.zeros((n + 7) // 8, dtype=np.uint8)  # a bit per row: sign flipped
    # the factor before each block's first row (the first block's is 0.0)
    checkpoint = np.zeros((n + BLOCK - 1) // BLOCK)
    factors = np.empty(BLOCK)
    st = np.zeros(_STATE)
    return out, slope_w, flips, checkpoint, factors, st


# ---------------------------------------------------------------------------
# the serial kernel and its prange twin, from one body
# ---------------------------------------------------------------------------

# The runs of rows go forwards, then backwards, through a pipeline: step r
# evaluates run r (in ``chunks`` pieces, into one of two buffers) and sweeps
# run r - 1 (from the other). The sweep is the last of the loop's items, so
# that numba's static schedule gives it to the thread with the fewest
# pieces. Compiled without ``parallel`` and with one piece, prange is range
# and the items run in order: evaluate run r, then sweep run r - 1, which is
# the serial kernel. Each piece's segment search starts afresh (a binary
# search); the segment of a time does not depend on where the search
# started, so both compilations give every row the same arithmetic.


def _rates_body(chunks: int) -> Callable[..., Any]:
    def body(
        plan, statics, offsets, gaps, own,
        slot_times, slot_t, slot_s, slot_p, slot_c,
        target, axes,
    ):  # fmt: skip
        n = target.shape[0]
        out, slope_w, flips, checkpoint, factors, st = _buffers(n)
        both = np.empty((2, min(SUPER, n), 4))
        runs = (n + SUPER - 1) // SUPER
        bad = np.zeros(1, dtype=np.int64)
        computed = 0
        for r in range(2 * runs + 1):
            # step r evaluates run r and sweeps run r - 1; runs 0 .. runs - 1
            # go forwards (the elimination), runs .. 2 runs - 1 backwards
            for item in prange(chunks + 1):
                if item < chunks and r < 2 * runs:
                    s0 = (2 * runs - 1 - r if r >= runs else r) * SUPER
                    s1 = min(s0 + SUPER, n)
                    piece = (s1 - s0 + chunks - 1) // chunks
                    piece = (piece + BLOCK - 1) // BLOCK * BLOCK
                    a = s0 + item * piece
                    b = min(a + piece, s1)
                    if a < b:
                        work_c = np.zeros(WORK * BLOCK)  # zeros: see chain_rows._ACC
                        cur_c = np.full(SLOTS, -1, dtype=np.int64)
                        computed += _evaluate(
                            plan, statics, offsets, gaps, own,
                            slot_times, slot_t, slot_s, slot_p, slot_c,
                            target, a, b, s0, both[r % 2], work_c, cur_c,
                        )  # fmt: skip
                elif item == chunks and r >= 1:
                    k = r - 1
                    s0 = (2 * runs - 1 - k if k >= runs else k) * SUPER
                    s1 = min(s0 + SUPER, n)
                    buf = both[k % 2]
                    if k < runs:
                        bad[0] = _forward(
                            buf, s0, s1, target, out, slope_w, flips, checkpoint, st
                        )
                    else:
                        _backward(
                            buf, s0, s1, target, out, slope_w, flips,
                            checkpoint, factors, st, axes,
                        )  # fmt: skip
            if bad[0]:
                return out, 1, computed
        return out, 0, computed

    return body


_RATES_DOC = """Angular velocity of the chain's rotation at the target times.

    Parameters
    ----------
    plan, statics, offsets, gaps, own, slot_times .. slot_c
        The chain, as for :func:`rbm_nb._kernels.fused.lookup_chain`.
    target : ndarray, shape (n,), n >= 4
        Strictly increasing target times, in seconds (also the spline's).
    axes : int
        :data:`BODY` or :data:`REFERENCE`.

    Returns
    -------
    out : ndarray, shape (n, 3)
        Incomplete if ``bad`` is not 0.
    bad : int
        0, or 1 if a row's rotation holds NaN or is zero (the caller then
        takes the lookup and the step-by-step estimate, which handle both).
    computed : int
        Rows of the squad tables computed by this call.
    """

_TWIN_DOC = """:func:`chain_body_rates` on all threads, bit for bit.

    Call :func:`rbm_nb._kernels.fused.prefill_chain` first (unless the
    tables are complete): the evaluations only read the tables. Each run
    of rows is evaluated in :data:`CHUNKS` pieces on the other threads
    while one thread sweeps the run before it.
    """

chain_body_rates = kernel(I1, F2, F1, F1, I1, *SLOT_TYPES, F1, I)(
    compiled_as("chain_body_rates", _RATES_DOC, _rates_body(1))
)
chain_body_rates_parallel = kernel(
    I1, F2, F1, F1, I1, *SLOT_TYPES, F1, I, options=PARALLEL_KERNEL
)(compiled_as("chain_body_rates_parallel", _TWIN_DOC, _rates_body(CHUNKS)))
