"""Fused chain kernels: one pass over the output rows, nothing else allocated.

A chain of frames between two frames is, once its static runs are composed,
``S0 M1 S1 M2 S2 ...``: static transforms ``S`` and up to :data:`SLOTS`
moving frames ``M`` (each possibly inverted). For every output row the
kernels here find each moving frame's segment by walking forward from the
previous row's segment (a merge walk over sorted target times; unsorted
times restart the walk, which then is a galloping binary search), evaluate
the frame there (squad for rotations and linear for translations of
continuous frames, the held event of discrete frames), compose the whole
chain in registers and write only the result: the transform itself
(:func:`lookup_chain`) or the point/vector/quaternion it carries
(:func:`transform_chain`).

The arithmetic is that of the unfused engine (``chain.resample_frame``,
``resample.chain_step``, ``quaternion.squad_evaluate``), so results agree
with it to rounding.

Inputs (unchecked, like every kernel)
-------------------------------------
plan : int64 (3 * steps,)
    Per step ``(kind, index, inverse)``: kind :data:`STATIC` (index into
    ``statics``), :data:`SQUAD` (continuous frame: linear translation,
    squad rotation), :data:`CONSTANT` (a continuous frame of one sample),
    :data:`HELD` (discrete frame); index is the slot (0..SLOTS-1) of a
    moving frame. ``inverse`` is 1 for a step traversed against its
    direction (static steps are composed forward beforehand: 0).
statics : float64 (s, 7)
    Static transforms as ``tx, ty, tz, w, x, y, z``.
offsets : float64 (SLOTS,)
    Added to the target times to put them on each slot's time origin.
own : int64 (SLOTS,)
    1 + i0 where the target times are the run of the slot's own sample
    times from sample i0 (then every row is a sample: its stored value),
    else 0 (a target time that happens to equal a sample time is evaluated
    like any other: the stored translation, squad's unit rotation; the
    stored sample where the segment after it misses its end). With a wrong
    i0 the results are the same, only slower (blocks are checked before
    they are copied).
gaps : float64 (SLOTS,)
    Each slot's ``max_gap`` (inf: none): target times strictly inside a
    longer gap between two samples get NaN.
slot k : ``times_k`` (n,), ``t_k`` (n, 3), ``r_k`` (n, 4), ``p_k`` (n, 4), ``c_k`` (n, 15)
    A moving frame's sample times, translations, rotations free of sign
    flips (``unflip``), rotations as stored (with their signs) and its
    squad table (:func:`squad_table`; any (1, 15) array for a frame that is
    not interpolated by squad). Unused slots get any arrays of these types.

Signs: squad runs on the sign-continuous rotations; an interpolated value
takes the sign of the stored sample its segment starts from, a sample time
or a held event returns the stored sample (as ``chain.stored_signs``).

Missing samples
---------------
NaN rows in a frame's translations or rotations are missing samples. A
result is NaN only where a sample it needs is missing: at a sample's own
time the sample itself (NaN if it is the missing one), between samples i
and i+1 of a continuous frame those two (linear translation; squad
rotation, whose control points take the end rule of a series where
sample i-1 or i+2 is missing: each run between missing samples is
interpolated as a series of its own), and a discrete frame's held event.
Nothing else produces NaN.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numba import prange

from .._config import KERNEL, PARALLEL_KERNEL
from ._jit import F1, F2, F3, I1, B, I, helper, kernel  # noqa: E741
from ._prefetch import prefetch, prefetch_for_write
from .quaternion import (
    _EPS,
    _SQRT2,
    _is_unit,
    _qexp1,
    _qinv1,
    _qlog1,
    _qmul1,
    _qslerp1,
    _qslerp_unit1,
    _rotate1,
    _sincos,
)
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    SINCOS_LIMIT,
    atan2,
    atan_over_x,
    atan_over_x_small,
    cos_series,
    cos_small,
    sinc_series,
    sinc_small,
    sincos,
)

__all__ = [
    "SLOTS",
    "STATIC",
    "SQUAD",
    "CONSTANT",
    "HELD",
    "TABLE_COLUMNS",
    "squad_table",
    "lookup_chain",
    "transform_chain",
    "prefill_chain",
    "lookup_chain_parallel",
    "transform_chain_parallel",
]

SLOTS = 3
STATIC = 0
SQUAD = 1
CONSTANT = 2
HELD = 3

# squad table columns: a (0:4); for a segment of unit quaternions the great
# circles r[i] -> r[i+1] (4:9: θ, u) and a[i] -> b[i] (9:14), else b (4:8)
# (squad falls back to slerps, which need b and nothing else); the state
# (14: 0.0 not computed yet, 1.0 unit, 2.0 not unit), negative where the
# stored sample i is -r[i] (so that the usual row reads the sign its result
# takes here rather than the stored rotations: 32 bytes less per row). 15
# float64 per sample: b of unit segments is not kept, as the great circle
# a -> b replaces it.
TABLE_COLUMNS = 15
_DONE = 14
_UNIT = 1.0
_NOT_UNIT = 2.0

# below this, exp(w) is 1 + w and log(1 + d) is d - d²/2 to within an ulp
_TINY = 2.0**-27

# The vectorised loops (the table fill's blocks, the chain's passes) divide
# without numba's ZeroDivisionError check: it is a branch out of the loop,
# which stops LLVM from vectorising it. Nothing else changes (no fastmath:
# vector lanes round as scalar code does).
_NO_DIVISION_CHECK = dataclasses.replace(KERNEL, error_model="numpy")


# ---------------------------------------------------------------------------
# the squad table, one segment at a time
# ---------------------------------------------------------------------------


@helper(inline=True)
def _qexp_table(w, x, y, z):
    """exp of a quaternion as ``quaternion._qexp1``, with short series for small arcs.

    Below ``SERIES_ANGLE`` the truncated series of cos(v) and sin(v)/v are
    exact to under one rounding error (and need neither libm's sin/cos nor
    a division); elsewhere the libm route. A zero vector part (a control
    point between repeated samples) takes the series too: cos and sin(v)/v
    are then 1. Within 4 ulp of ``_qexp1`` (tests/core/test_fused.py).
    """
    v2 = x * x + y * y + z * z
    if v2 < SERIES_ANGLE * SERIES_ANGLE and (v2 > _EPS * _EPS or v2 == 0.0):
        # w is a sum of log-norms of unit quaternions (~1e-16): then 1 + w
        # is exp(w) to within w²/2, below half an ulp of 1
        e = 1.0 + w if abs(w) < _TINY else math.exp(w)
        c = cos_small(v2)
        k = e * sinc_small(v2)
        return e * c, k * x, k * y, k * z
    return _qexp1(w, x, y, z)


@helper(inline=True)
def _qlog_table(w, x, y, z):
    """log of a quaternion as ``quaternion._qlog1``, with a short series for small arcs.

    For w > 0 and |v| < SERIES_RATIO w, atan2(|v|, w) / |v| is
    atan_over_x((|v|/w)²) / w: no sqrt, no atan2. A zero vector part (the
    step between repeated samples, 30 % of the real eye recording's) takes
    it too: its vector part is then 0 and its real part the same series of
    log |q|. Within 4 ulp of ``_qlog1`` for quaternions within a few ulp of
    unit norm, as the steps between unit samples are (tests/core/test_fused.py).
    """
    b2 = x * x + y * y + z * z
    if w > 0.0 and b2 < (SERIES_RATIO * w) ** 2 and (b2 > (_EPS * w) ** 2 or b2 == 0.0):
        inv_w = 1.0 / w
        f = atan_over_x_small(b2 * inv_w * inv_w) * inv_w
        b = math.sqrt(b2)  # the real part exactly as _qlog1 forms it
        n2 = w * w + b * b
        d = n2 - 1.0  # exact (Sterbenz)
        # a unit quaternion's norm² is 1 to within rounding: then log(1 + d)
        # is d - d²/2 to within d³/3, far below an ulp of the result
        half_log = (d - 0.5 * d * d) / 2.0 if abs(d) < _TINY else math.log(n2) / 2.0
        return half_log, f * x, f * y, f * z
    return _qlog1(w, x, y, z)


@helper(inline=True)
def _geodesic_table(aw, ax, ay, az, bw, bx, by, bz):
    """``quaternion._geodesic1`` with a short series for the angle of small arcs.

    For d = a·b > 0 and |o| < SERIES_RATIO d, θ = atan(|o|/d) is
    x atan_over_x(x²) with x = |o|/d (no atan2). Within 4 ulp of 1.
    """
    dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
    if dw * dw + dx * dx + dy * dy + dz * dz > _SQRT2 * _SQRT2:
        bw, bx, by, bz = -bw, -bx, -by, -bz
    d = aw * bw + ax * bx + ay * by + az * bz
    ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
    so = math.sqrt(ow * ow + ox * ox + oy * oy + oz * oz)
    if so == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    k = 1.0 / so
    if d > 0.0 and so < SERIES_RATIO * d:
        x = so / d
        theta = x * atan_over_x_small(x * x)
    else:
        theta = atan2(so, d)
    return theta, ow * k, ox * k, oy * k, oz * k


# A missing row is computed together with the missing rows after it (up to
# RUN of them), so that each log(r[i]⁻¹ r[i+1]) is computed once rather
# than for each of the three rows that use it; sorted lookups need those
# rows next anyway.
RUN = 256


@helper(inline=True)
def _log_step(r, i):
    """log(r[i]⁻¹ r[i+1]), as :func:`quaternion.squad_coefficients` forms it."""
    n = r.shape[0]
    if i < 0 or i > n - 2:
        return 0.0, 0.0, 0.0, 0.0  # not used by any row
    # r[i]⁻¹ with one division, not _qinv1's four (within an ulp of it)
    w, x, y, z = r[i, 0], r[i, 1], r[i, 2], r[i, 3]
    k = 1.0 / (w * w + x * x + y * y + z * z)
    iw, ix, iy, iz = w * k, -x * k, -y * k, -z * k
    nw, nx, ny, nz = _qmul1(
        iw, ix, iy, iz, r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3]
    )
    return _qlog_table(nw, nx, ny, nz)


@helper(inline=True)
def _inv_interval(t, k):
    """1 / (t[k+1] - t[k]), or 0.0 where sample k or k+1 does not exist."""
    if k < 0 or k > t.shape[0] - 2:
        return 0.0
    return 1.0 / (t[k + 1] - t[k])


@helper(inline=True)
def _first_half(r, i):
    """Whether r[i]·r[i+1] > 0 (the arc between them is under π/2)."""
    return (
        r[i, 0] * r[i + 1, 0]
        + r[i, 1] * r[i + 1, 1]
        + r[i, 2] * r[i + 1, 2]
        + r[i, 3] * r[i + 1, 3]
    ) > 0.0


@helper
def _stored_sign(r, rp, i):
    """-1.0 where the stored sample i is -r[i], else 1.0 (the chain's test)."""
    dot = (
        r[i, 0] * rp[i, 0]
        + r[i, 1] * rp[i, 1]
        + r[i, 2] * rp[i, 2]
        + r[i, 3] * rp[i, 3]
    )
    return -1.0 if dot < 0.0 else 1.0


@helper
def _table_row(r, rp, c, i, pw, px, py, pz, lw, lx, ly, lz, nw, nx, ny, nz, ra, rb):
    """Fill row i of the squad table of (r, t) (n >= 2) into ``c``.

    ``rp``: the rotations as stored, for the sign in the state column.

    Row i of ``squad_coefficients`` (a, b) and ``squad_segments`` to within
    4 ulp, from samples i-1 .. i+2, the logs p = L[i-1], l = L[i],
    n = L[i+1] (``_log_step``) and the ratios of sampling intervals
    ra = (t[i+1]-t[i]) / (t[i]-t[i-1]), rb = (t[i+1]-t[i]) / (t[i+2]-t[i+1])
    (where those samples exist).

    Not inlined: the vectorised blocks call it only for the rows their
    route does not cover, and inlining its exact routes (exp, log and
    great circles) into every caller multiplied compile time.
    """
    n = r.shape[0]
    # a[i]; a missing sample i-1 (a NaN log p) starts a run: the end rule,
    # as at the first sample (``quaternion.squad_coefficients``)
    if i == 0 or i == n - 1 or math.isnan(pw):
        aw, ax, ay, az = r[i, 0], r[i, 1], r[i, 2], r[i, 3]
    else:
        ew, ex, ey, ez = _qexp_table(
            (-lw + pw * ra) * 0.25,
            (-lx + px * ra) * 0.25,
            (-ly + py * ra) * 0.25,
            (-lz + pz * ra) * 0.25,
        )
        aw, ax, ay, az = _qmul1(r[i, 0], r[i, 1], r[i, 2], r[i, 3], ew, ex, ey, ez)
    # b[i], and the sample the segment ends at; a missing sample i+2 (a
    # NaN log n) ends the run at i+1
    if i < n - 2 and not math.isnan(nw):
        ew, ex, ey, ez = _qexp_table(
            (nw * rb - lw) * -0.25,
            (nx * rb - lx) * -0.25,
            (ny * rb - ly) * -0.25,
            (nz * rb - lz) * -0.25,
        )
        bw, bx, by, bz = _qmul1(
            r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3], ew, ex, ey, ez
        )
    elif i <= n - 2:
        bw, bx, by, bz = r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3]
    else:
        # the virtual sample past the end: r[n-1] r[n-2]⁻¹ r[n-1]
        iw, ix, iy, iz = _qinv1(r[n - 2, 0], r[n - 2, 1], r[n - 2, 2], r[n - 2, 3])
        w, x, y, z = _qmul1(
            r[n - 1, 0], r[n - 1, 1], r[n - 1, 2], r[n - 1, 3], iw, ix, iy, iz
        )
        bw, bx, by, bz = _qmul1(
            w, x, y, z, r[n - 1, 0], r[n - 1, 1], r[n - 1, 2], r[n - 1, 3]
        )
    if i < n - 1:
        ew, ex, ey, ez = r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3]
    else:
        ew, ex, ey, ez = bw, bx, by, bz
    c[i, 0] = aw
    c[i, 1] = ax
    c[i, 2] = ay
    c[i, 3] = az
    unit = (
        _is_unit(r[i, 0], r[i, 1], r[i, 2], r[i, 3])
        and _is_unit(ew, ex, ey, ez)
        and _is_unit(aw, ax, ay, az)
        and _is_unit(bw, bx, by, bz)
    )
    if unit:
        theta2 = lx * lx + ly * ly + lz * lz
        if i < n - 1 and theta2 > 0.0 and abs(lw) < _TINY and _first_half(r, i):
            # r[i+1] = r[i] exp(l) with |l| < π/2 (r[i]·r[i+1] > 0, no flip):
            # the arc is θ = |l| along u = r[i] (0, l / θ), which the log has
            # all but worked out (within 4 ulp of _geodesic_table's atan)
            theta = math.sqrt(theta2)
            k = 1.0 / theta
            ow, ox, oy, oz = _qmul1(
                r[i, 0], r[i, 1], r[i, 2], r[i, 3], 0.0, lx * k, ly * k, lz * k
            )
            c[i, 4] = theta
            c[i, 5] = ow
            c[i, 6] = ox
            c[i, 7] = oy
            c[i, 8] = oz
        else:
            g = _geodesic_table(r[i, 0], r[i, 1], r[i, 2], r[i, 3], ew, ex, ey, ez)
            c[i, 4] = g[0]
            c[i, 5] = g[1]
            c[i, 6] = g[2]
            c[i, 7] = g[3]
            c[i, 8] = g[4]
        g = _geodesic_table(aw, ax, ay, az, bw, bx, by, bz)
        c[i, 9] = g[0]
        c[i, 10] = g[1]
        c[i, 11] = g[2]
        c[i, 12] = g[3]
        c[i, 13] = g[4]
        c[i, _DONE] = _UNIT * _stored_sign(r, rp, i)
    else:
        c[i, 4] = bw
        c[i, 5] = bx
        c[i, 6] = by
        c[i, 7] = bz
        for k in range(8, 14):
            c[i, k] = 0.0
        c[i, _DONE] = _NOT_UNIT * _stored_sign(r, rp, i)


# Rows are filled in blocks: the samples, logs and intervals a block reads
# are gathered into structure-of-arrays scratch (one contiguous row of
# FILL_BLOCK + 3 per quantity), and the common case -- interior rows of
# unit quaternions whose arcs are small enough for the short series -- is
# computed in loops over the block without calls or exceptions, which LLVM
# vectorises. Each row records whether it took that route; the others (the
# first and last two rows, non-unit samples, large arcs, a control-point
# arc that goes the other way round) are filled by _table_row afterwards,
# one by one. Every operation of the block loops is the one _table_row
# performs (no fused multiply-add: vector lanes round as scalar code), so a
# row's value depends only on the data, not on the block it fell in.
FILL_BLOCK = 64
# scratch rows: samples (0:4), intervals and their inverses (4, 5), logs
# (6:10), whether a log needs the exact route (10), the table row (11:26),
# whether the row needs the exact route (26), the control point b (27:31),
# whether the row's own arc has a zero log and takes the geodesic instead (31)
_S_Q = 0
_S_DT = 4
_S_IDT = 5
_S_L = 6
_S_LBAD = 10
_S_OUT = 11
_S_BAD = 26
_S_B = 27
_S_ZERO = 31
_S_ROWS = 32


@helper(inline=True)
def _control_point_series(rw, rx, ry, rz, ew, ex, ey, ez):
    """r exp(e) by _qexp_table's series route, and whether that route holds
    (a small arc, a scale of 1 to within rounding, a unit result)."""
    v2 = ex * ex + ey * ey + ez * ez
    e = 1.0 + ew
    k = e * sinc_small(v2)
    w, x, y, z = _qmul1(rw, rx, ry, rz, e * cos_small(v2), k * ex, k * ey, k * ez)
    fast = (
        (v2 < SERIES_ANGLE * SERIES_ANGLE)
        & ((v2 > _EPS * _EPS) | (v2 == 0.0))
        & (abs(ew) < _TINY)
        & (abs(w * w + x * x + y * y + z * z - 1.0) <= 1e-12)
    )
    return w, x, y, z, fast


@helper(options=_NO_DIVISION_CHECK)
def _fill_block(r, rp, t, c, i0, i1, s):
    """Rows i0..i1-1 of the table (1 <= i0, i1 <= n - 2, i1 - i0 <= FILL_BLOCK).

    ``s``: scratch of shape (_S_ROWS, FILL_BLOCK + 3).
    """
    m = i1 - i0
    # gather samples i0-1 .. i1+1 (index k: sample i0 - 1 + k)
    for j in range(4):
        for k in range(m + 3):
            s[_S_Q + j, k] = r[i0 - 1 + k, j]
    for k in range(m + 2):
        s[_S_DT, k] = t[i0 + k] - t[i0 - 1 + k]
    for k in range(m + 2):
        s[_S_IDT, k] = 1.0 / s[_S_DT, k]
    # logs L[i0-1+k] = log(q[k]⁻¹ q[k+1]), k = 0 .. m+1 (_log_step, _qlog_table)
    for k in range(m + 2):
        aw, ax, ay, az = s[0, k], s[1, k], s[2, k], s[3, k]
        bw, bx, by, bz = s[0, k + 1], s[1, k + 1], s[2, k + 1], s[3, k + 1]
        inv = 1.0 / (aw * aw + ax * ax + ay * ay + az * az)
        iw, ix, iy, iz = aw * inv, -ax * inv, -ay * inv, -az * inv
        pw, px, py, pz = _qmul1(iw, ix, iy, iz, bw, bx, by, bz)
        b2 = px * px + py * py + pz * pz
        inv_w = 1.0 / pw
        f = atan_over_x_small(b2 * inv_w * inv_w) * inv_w
        b = math.sqrt(b2)
        d = (pw * pw + b * b) - 1.0
        s[_S_L, k] = (d - 0.5 * d * d) / 2.0
        s[_S_L + 1, k] = f * px
        s[_S_L + 2, k] = f * py
        s[_S_L + 3, k] = f * pz
        fast = (
            (pw > 0.0)
            & (b2 < (SERIES_RATIO * pw) ** 2)
            & ((b2 > (_EPS * pw) ** 2) | (b2 == 0.0))
            & (abs(d) < _TINY)
        )
        s[_S_LBAD, k] = 0.0 if fast else 1.0
    for k in range(m + 2):
        if s[_S_LBAD, k] != 0.0:
            lw, lx, ly, lz = _log_step(r, i0 - 1 + k)
            s[_S_L, k] = lw
            s[_S_L + 1, k] = lx
            s[_S_L + 2, k] = ly
            s[_S_L + 3, k] = lz
    # rows: row b is sample i = i0 + b, at scratch index b + 1. Three short
    # loops rather than one long one: LLVM vectorises each of them.
    # the control points a = r[i] exp((-l + p ra) / 4) and
    # b = r[i+1] exp((n rb - l) / -4), each in a loop of its own (together,
    # LLVM did not vectorise them)
    for b in range(m):
        ra = s[_S_DT, b + 1] * s[_S_IDT, b]
        aw, ax, ay, az, fast = _control_point_series(
            s[0, b + 1], s[1, b + 1], s[2, b + 1], s[3, b + 1],
            (-s[_S_L, b + 1] + s[_S_L, b] * ra) * 0.25,
            (-s[_S_L + 1, b + 1] + s[_S_L + 1, b] * ra) * 0.25,
            (-s[_S_L + 2, b + 1] + s[_S_L + 2, b] * ra) * 0.25,
            (-s[_S_L + 3, b + 1] + s[_S_L + 3, b] * ra) * 0.25,
        )  # fmt: skip
        s[_S_OUT, b] = aw
        s[_S_OUT + 1, b] = ax
        s[_S_OUT + 2, b] = ay
        s[_S_OUT + 3, b] = az
        s[_S_BAD, b] = 0.0 if fast else 1.0
    for b in range(m):
        rb = s[_S_DT, b + 1] * s[_S_IDT, b + 2]
        bw, bx, by, bz, fast = _control_point_series(
            s[0, b + 2], s[1, b + 2], s[2, b + 2], s[3, b + 2],
            (s[_S_L, b + 2] * rb - s[_S_L, b + 1]) * -0.25,
            (s[_S_L + 1, b + 2] * rb - s[_S_L + 1, b + 1]) * -0.25,
            (s[_S_L + 2, b + 2] * rb - s[_S_L + 2, b + 1]) * -0.25,
            (s[_S_L + 3, b + 2] * rb - s[_S_L + 3, b + 1]) * -0.25,
        )  # fmt: skip
        s[_S_B, b] = bw
        s[_S_B + 1, b] = bx
        s[_S_B + 2, b] = by
        s[_S_B + 3, b] = bz
        if not fast:
            s[_S_BAD, b] = 1.0
    for b in range(m):
        # the arc r[i] -> r[i+1] from the log (see _table_row)
        rw, rx, ry, rz = s[0, b + 1], s[1, b + 1], s[2, b + 1], s[3, b + 1]
        qw, qx, qy, qz = s[0, b + 2], s[1, b + 2], s[2, b + 2], s[3, b + 2]
        lw, lx, ly, lz = (
            s[_S_L, b + 1], s[_S_L + 1, b + 1], s[_S_L + 2, b + 1], s[_S_L + 3, b + 1]
        )  # fmt: skip
        theta2 = lx * lx + ly * ly + lz * lz
        theta = math.sqrt(theta2)
        inv_theta = 1.0 / theta
        ow, ox, oy, oz = _qmul1(
            rw, rx, ry, rz, 0.0, lx * inv_theta, ly * inv_theta, lz * inv_theta
        )
        units = (abs(rw * rw + rx * rx + ry * ry + rz * rz - 1.0) <= 1e-12) & (
            abs(qw * qw + qx * qx + qy * qy + qz * qz - 1.0) <= 1e-12
        )
        fast = (
            units
            & (theta2 > 0.0)
            & (abs(lw) < _TINY)
            & (rw * qw + rx * qx + ry * qy + rz * qz > 0.0)
        )
        zero = units & (theta2 == 0.0)
        s[_S_OUT + 4, b] = theta
        s[_S_OUT + 5, b] = ow
        s[_S_OUT + 6, b] = ox
        s[_S_OUT + 7, b] = oy
        s[_S_OUT + 8, b] = oz
        s[_S_ZERO, b] = 1.0 if zero else 0.0
        if not (fast or zero):
            s[_S_BAD, b] = 1.0
    for b in range(m):
        # a zero log (a repeated sample, 30 % of the real eye recording's
        # steps): the arc is _geodesic_table's, as the scalar code takes it
        # (one branch per row here, rather than that route for every row in
        # the vector loop above, which took 6 % more time on a recording without
        # repeats)
        if s[_S_ZERO, b] != 0.0:
            g = _geodesic_table(
                s[0, b + 1], s[1, b + 1], s[2, b + 1], s[3, b + 1],
                s[0, b + 2], s[1, b + 2], s[2, b + 2], s[3, b + 2],
            )  # fmt: skip
            s[_S_OUT + 4, b] = g[0]
            s[_S_OUT + 5, b] = g[1]
            s[_S_OUT + 6, b] = g[2]
            s[_S_OUT + 7, b] = g[3]
            s[_S_OUT + 8, b] = g[4]
    for b in range(m):
        # the arc a -> b (_geodesic_table's series route, no flip)
        aw, ax, ay, az = (
            s[_S_OUT, b],
            s[_S_OUT + 1, b],
            s[_S_OUT + 2, b],
            s[_S_OUT + 3, b],
        )
        bw, bx, by, bz = s[_S_B, b], s[_S_B + 1, b], s[_S_B + 2, b], s[_S_B + 3, b]
        dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
        d = aw * bw + ax * bx + ay * by + az * bz
        gw, gx, gy, gz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
        so = math.sqrt(gw * gw + gx * gx + gy * gy + gz * gz)
        kg = 1.0 / so
        x = so / d
        fast = (
            (dw * dw + dx * dx + dy * dy + dz * dz <= _SQRT2 * _SQRT2)
            & (so != 0.0)
            & (d > 0.0)
            & (so < SERIES_RATIO * d)
        )
        s[_S_OUT + 9, b] = x * atan_over_x_small(x * x)
        s[_S_OUT + 10, b] = gw * kg
        s[_S_OUT + 11, b] = gx * kg
        s[_S_OUT + 12, b] = gy * kg
        s[_S_OUT + 13, b] = gz * kg
        if not fast:
            s[_S_BAD, b] = 1.0
    for b in range(m):
        i = i0 + b
        if s[_S_BAD, b] != 0.0:
            _table_row(
                r, rp, c, i,
                s[_S_L, b], s[_S_L + 1, b], s[_S_L + 2, b], s[_S_L + 3, b],
                s[_S_L, b + 1], s[_S_L + 1, b + 1], s[_S_L + 2, b + 1],
                s[_S_L + 3, b + 1],
                s[_S_L, b + 2], s[_S_L + 1, b + 2], s[_S_L + 2, b + 2],
                s[_S_L + 3, b + 2],
                s[_S_DT, b + 1] * s[_S_IDT, b], s[_S_DT, b + 1] * s[_S_IDT, b + 2],
            )  # fmt: skip
        else:
            for j in range(_DONE):
                c[i, j] = s[_S_OUT + j, b]
            # (_stored_sign written out: a helper taking the arrays would
            # count references once per row)
            dot = (
                r[i, 0] * rp[i, 0]
                + r[i, 1] * rp[i, 1]
                + r[i, 2] * rp[i, 2]
                + r[i, 3] * rp[i, 3]
            )
            c[i, _DONE] = -_UNIT if dot < 0.0 else _UNIT


@helper
def _fill_row(r, rp, t, c, i):
    """Row i of the table alone (its three logs computed here)."""
    n = r.shape[0]
    pw, px, py, pz = _log_step(r, i - 1)
    lw, lx, ly, lz = _log_step(r, i)
    nw, nx, ny, nz = _log_step(r, i + 1)
    dt = t[i + 1] - t[i] if i < n - 1 else 0.0
    _table_row(
        r, rp, c, i, pw, px, py, pz, lw, lx, ly, lz, nw, nx, ny, nz,
        dt * _inv_interval(t, i - 1), dt * _inv_interval(t, i + 1),
    )  # fmt: skip


@helper
def _fill_run(r, rp, t, c, g, count):
    """Compute row g of the table and the missing rows after it (``count`` at most).

    Stops before the first row already computed. Returns the number of
    rows computed.
    """
    n = r.shape[0]
    end = min(g + count, n)
    stop = g + 1
    while stop < end and c[stop, _DONE] == 0.0:
        stop += 1
    s = np.empty((_S_ROWS, FILL_BLOCK + 3))
    i = g
    while i < stop:
        if i == 0 or i >= n - 2:
            _fill_row(r, rp, t, c, i)
            i += 1
        else:
            j = min(i + FILL_BLOCK, stop, n - 2)
            _fill_block(r, rp, t, c, i, j, s)
            i = j
    return stop - g


@kernel(F2, F2, F1)
def squad_table(r, p, t):
    """The whole squad table of rotations r (n >= 2) at strictly increasing t.

    ``r``: the rotations free of sign flips (``unflip``) of ``p``, the
    rotations as stored.

    Returns
    -------
    ndarray, shape (n, 15)
        See the module docstring; every row computed.
    """
    n = r.shape[0]
    c = np.zeros((n, TABLE_COLUMNS))
    _fill_run(r, p, t, c, 0, n)
    return c


# ---------------------------------------------------------------------------
# the chain over a block of rows
# ---------------------------------------------------------------------------

# Rows are evaluated in blocks: for each block, each step of the chain is
# applied to all its rows before the next step. The block's accumulated
# transforms stay in a small scratch array (in L1 cache), and a step's
# arrays are picked once per block, not once per row: numba counts
# references whenever an array is assigned or handed to a function, and
# per-row reference counting costs more than the arithmetic.
#
# The scratch ``work`` holds each quantity for the block's rows side by
# side (structure of arrays), so that the arithmetic of a step is a loop
# over contiguous rows without branches or calls, which LLVM vectorises (8
# rows per instruction with AVX-512). A moving step runs in passes: whole
# blocks at the frame's own sample times are copied (:func:`_own_rows`);
# otherwise a scalar pass finds each row's segment and either gathers its
# squad segment into the scratch (the usual row: inside the samples, no
# gap, a unit segment, in a short route of its own) or evaluates the row
# (held and constant frames, own sample times, gaps, segments that are not
# unit, arguments beyond the polynomial sine's range, times outside the
# samples); the vector pass :func:`_squad_rows` evaluates
# the gathered rows (both inner great circles and the outer slerp's
# small-arc series) and marks the rows whose outer slerp needs the general
# branch, which :func:`_wide_rows` (another vector pass, for blocks with
# many) and then a scalar pass (``_qslerp_unit1``) take;
# :func:`_compose_rows` composes the step into the block's transforms.
# Every row gets exactly the operations of the scalar code, in the same
# order (no fastmath): results are bit for bit those of a row-by-row loop
# (tests/core/test_fused_rows.py).
#
# 96 rows: the scratch (27 kB) and the rows streamed through stay in L1
# (256 rows were 1.4x slower, 64 rows 1.05x, 128 rows 1-2 % faster but
# their scratch, one per thread in the prange twins, took a 20k-row
# transform over 1.5x its output's memory).
BLOCK = 96

# Rows ahead whose samples the short route asks for (``_prefetch``). A
# lookup left_eye -> world on one thread, after 64 MB were streamed through
# the caches, took 3.1-3.3 ms with no hints; with hints 16 rows ahead
# 2.8 ms, 48 rows 2.7 ms (no better at 96).
AHEAD = 48

# ``work`` (WORK * BLOCK,): quantity q of row b at q * BLOCK + b. One flat
# array with fixed offsets (and loops over whole blocks), so that LLVM sees
# that the quantities do not overlap and vectorises without runtime checks.
# Every row a pass uses is written first; the vector passes also compute on
# the rows a block does not use (results kept, never read). So the scratch
# starts as zeros, not uninitialised: whatever the allocator hands back
# (denormal numbers, say) would be computed on at a hundred times the cost.
# A lookup of one time through the head/eye chain took 80 µs in the kernel
# with np.empty, 13 µs once a full block had left sane values there.
_ACC = 0  # 0:7 the block's accumulated transforms (tx, ty, tz, w, x, y, z)
_STEP = 7 * BLOCK  # 7:14 the step's transform at each row
_TAU = 14 * BLOCK  # squad's fraction τ of the row's segment g
_TH1 = 15 * BLOCK  # θ of the great circle r[g] -> r[g+1] (table column 4)
_TH2 = 16 * BLOCK  # θ of the great circle a[g] -> b[g] (table column 9)
_P = 17 * BLOCK  # 17:21 r[g]; after the squad pass the inner slerp r[g] -> r[g+1]
_U1 = 21 * BLOCK  # 21:25 u of the first great circle (table columns 5:9)
_Q = 25 * BLOCK  # 25:29 a[g]; after the squad pass the inner slerp a[g] -> b[g]
_U2 = 29 * BLOCK  # 29:33 u of the second great circle (table columns 10:14)
_NEG = 33 * BLOCK  # 1.0 where the result takes the opposite sign (the stored sample's)
# 1.0 rows gathered for the squad pass, 0.0 rows already evaluated; the
# squad pass turns 1.0 into 2.0 where the outer slerp needs the general route
_PATH = 34 * BLOCK
WORK = 35
_GATHERED = 1.0
_GENERAL = 2.0

# The chain's vector passes use the table fill's options (_NO_DIVISION_CHECK);
# their quaternion helpers are the ones of :mod:`.quaternion`, inlined with
# those options.
_rotate_rows = helper(inline=True, options=_NO_DIVISION_CHECK)(_rotate1.py_func)
_qmul_rows = helper(inline=True, options=_NO_DIVISION_CHECK)(_qmul1.py_func)
_is_unit_rows = helper(inline=True, options=_NO_DIVISION_CHECK)(_is_unit.py_func)


@helper(inline=True)
def _seek(times, t, i):
    """The segment of time t: i with times[i] <= t < times[i+1], -1 before, n-1 after.

    A merge walk: gallops forward from ``i``, the previous row's segment (an
    earlier time restarts from -1, which makes it a binary search). The
    answer does not depend on ``i`` (times are strictly increasing), so
    rows can be evaluated in any order and in chunks.
    """
    n = times.shape[0]
    if i >= 0 and t < times[i]:
        i = -1
    lo = i
    step = 1
    hi = i + 1
    while hi < n and times[hi] <= t:
        lo = hi
        hi = i + 1 + step
        step *= 2
    if hi > n:
        hi = n
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if times[mid] <= t:
            lo = mid
        else:
            hi = mid
    return lo


@helper(inline=True, options=_NO_DIVISION_CHECK)
def _compose(ax, ay, az, aw, bx, by, bz, tx, ty, tz, qw, qx, qy, qz, inverse):
    """Accumulated transform followed by (t, q), as ``resample.chain_step``.

    Arguments: the accumulated translation (ax, ay, az) and rotation
    (aw, bx, by, bz), then the step's translation and rotation.
    """
    if inverse:
        x, y, z = _rotate_rows(qw, -qx, -qy, -qz, ax - tx, ay - ty, az - tz)
        k = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
        qw, qx, qy, qz = qw * k, -qx * k, -qy * k, -qz * k
    else:
        x, y, z = _rotate_rows(qw, qx, qy, qz, ax, ay, az)
        x += tx
        y += ty
        z += tz
    w, rx, ry, rz = _qmul_rows(qw, qx, qy, qz, aw, bx, by, bz)
    return x, y, z, w, rx, ry, rz


@helper(options=_NO_DIVISION_CHECK)
def _compose_rows(work, inverse, first):
    """The step's transforms (rows _STEP) composed into the block's (rows _ACC).

    Over the whole block (rows past the block's end hold stale values,
    never read). ``first``: the chain's first step, not inverted, is taken
    as it is (``chain.compose`` does the same).
    """
    a, s = _ACC, _STEP
    if first:
        for b in range(7 * BLOCK):
            work[a + b] = work[s + b]
        return
    for b in range(BLOCK):
        x, y, z, w, rx, ry, rz = _compose(
            work[a + b], work[a + BLOCK + b], work[a + 2 * BLOCK + b],
            work[a + 3 * BLOCK + b], work[a + 4 * BLOCK + b],
            work[a + 5 * BLOCK + b], work[a + 6 * BLOCK + b],
            work[s + b], work[s + BLOCK + b], work[s + 2 * BLOCK + b],
            work[s + 3 * BLOCK + b], work[s + 4 * BLOCK + b],
            work[s + 5 * BLOCK + b], work[s + 6 * BLOCK + b],
            inverse,
        )  # fmt: skip
        work[a + b] = x
        work[a + BLOCK + b] = y
        work[a + 2 * BLOCK + b] = z
        work[a + 3 * BLOCK + b] = w
        work[a + 4 * BLOCK + b] = rx
        work[a + 5 * BLOCK + b] = ry
        work[a + 6 * BLOCK + b] = rz


@helper(options=_NO_DIVISION_CHECK)
def _compose_static_rows(work, statics, k, inverse, first, rotation_only):
    """Static transform ``statics[k]`` composed into the block's (rows _ACC).

    :func:`_compose_rows` with the same step at every row, taken as scalars
    (no step rows written and read again).
    """
    tx, ty, tz = statics[k, 0], statics[k, 1], statics[k, 2]
    if rotation_only:
        tx = ty = tz = 0.0
    qw, qx, qy, qz = statics[k, 3], statics[k, 4], statics[k, 5], statics[k, 6]
    a = _ACC
    if first:
        for e, v in enumerate((tx, ty, tz, qw, qx, qy, qz)):
            for b in range(BLOCK):
                work[a + e * BLOCK + b] = v
        return
    for b in range(BLOCK):
        x, y, z, w, rx, ry, rz = _compose(
            work[a + b], work[a + BLOCK + b], work[a + 2 * BLOCK + b],
            work[a + 3 * BLOCK + b], work[a + 4 * BLOCK + b],
            work[a + 5 * BLOCK + b], work[a + 6 * BLOCK + b],
            tx, ty, tz, qw, qx, qy, qz, inverse,
        )  # fmt: skip
        work[a + b] = x
        work[a + BLOCK + b] = y
        work[a + 2 * BLOCK + b] = z
        work[a + 3 * BLOCK + b] = w
        work[a + 4 * BLOCK + b] = rx
        work[a + 5 * BLOCK + b] = ry
        work[a + 6 * BLOCK + b] = rz


@helper(inline=True, options=_NO_DIVISION_CHECK)
def _arc_rows(work, theta, start, u):
    """Rows ``start`` (4 quantities) moved along their great circles towards ``u``.

    cos(τθ) start + sin(τθ) u, over the block, into the rows of ``start``.
    """
    for b in range(BLOCK):
        y = work[_TAU + b] * work[theta + b]
        # (in range for the gathered rows; the others, whatever the scratch
        # holds, are kept in it too: out of range sincos's rounding to an
        # integer would be undefined)
        sn, cs = sincos(y if abs(y) < SINCOS_LIMIT else 0.0)
        for e in range(4):
            work[start + e * BLOCK + b] = (
                cs * work[start + e * BLOCK + b] + sn * work[u + e * BLOCK + b]
            )


@helper(options=_NO_DIVISION_CHECK)
def _squad_rows(work):
    """Squad at the gathered rows of the block, into their step rotations.

    Rows with ``work[_PATH + b] == _GATHERED``: the inner slerps along the
    segment's unit great circles (``sincos``, whose range the gathering
    checked), then ``_qslerp_unit1``'s small-arc branch, without branches;
    where that branch does not apply (an argument not unit, a wide arc),
    the row is marked ``_GENERAL``, its inner slerps kept in rows _P and _Q
    for the scalar route. Returns the number of rows marked.

    In several loops, each short: an iteration of one long loop would fill
    the processor's reorder window, and its long chains of dependent
    operations (the polynomials) would then run one after another.
    """
    # the inner slerps, into rows _P and _Q
    _arc_rows(work, _TH1, _P, _U1)
    _arc_rows(work, _TH2, _Q, _U2)
    # _qslerp_unit1(p, q, h): q taken the shorter way round; the arc's
    # d = p.q and the part o of q orthogonal to p (into rows _U1), the
    # conditions of its small-arc branch so far (into _TH1) and x² = tan²
    # of the arc (into _TH2), 1/d (into _U2)
    for b in range(BLOCK):
        aw, ax = work[_P + b], work[_P + BLOCK + b]
        ay, az = work[_P + 2 * BLOCK + b], work[_P + 3 * BLOCK + b]
        bw, bx = work[_Q + b], work[_Q + BLOCK + b]
        by, bz = work[_Q + 2 * BLOCK + b], work[_Q + 3 * BLOCK + b]
        unit = _is_unit_rows(aw, ax, ay, az) & _is_unit_rows(bw, bx, by, bz)
        dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
        far = dw * dw + dx * dx + dy * dy + dz * dz > _SQRT2 * _SQRT2
        cw = -bw if far else bw
        cx = -bx if far else bx
        cy = -by if far else by
        cz = -bz if far else bz
        d = aw * cw + ax * cx + ay * cy + az * cz
        ow, ox, oy, oz = cw - d * aw, cx - d * ax, cy - d * ay, cz - d * az
        o2 = ow * ow + ox * ox + oy * oy + oz * oz
        inv_d = 1.0 / d
        work[_U1 + b] = ow
        work[_U1 + BLOCK + b] = ox
        work[_U1 + 2 * BLOCK + b] = oy
        work[_U1 + 3 * BLOCK + b] = oz
        small = unit & (d > 0.0) & (o2 < (SERIES_RATIO * d) ** 2)
        work[_TH1 + b] = 1.0 if small else 0.0
        work[_TH2 + b] = o2 * inv_d * inv_d
        work[_U2 + b] = inv_d
    # the series, and the result where they apply
    general = 0
    for b in range(BLOCK):
        tau = work[_TAU + b]
        h = 2.0 * tau * (1.0 - tau)
        x2 = work[_TH2 + b]
        p = atan_over_x(x2)
        y2 = h * h * x2 * p * p
        c = cos_series(y2)
        k = sinc_series(y2) * h * p * work[_U2 + b]
        sign = -1.0 if work[_NEG + b] != 0.0 else 1.0
        series = (work[_TH1 + b] != 0.0) & (y2 < SERIES_ANGLE * SERIES_ANGLE)
        gathered = work[_PATH + b] == _GATHERED
        done = gathered & series
        redo = gathered & ~series
        general += redo
        # only the gathered rows change (the others were evaluated already)
        for e in range(4):
            q = c * work[_P + e * BLOCK + b] + k * work[_U1 + e * BLOCK + b]
            q = -q if sign < 0.0 else q
            at = _STEP + (3 + e) * BLOCK + b
            work[at] = q if done else work[at]
        work[_PATH + b] = _GENERAL if redo else work[_PATH + b]
    return general


# A block with at least this many outer slerps off the small-arc series
# takes them in a vector pass (:func:`_wide_rows`), fewer one by one.
_WIDE_ROWS = 8


@helper(options=_NO_DIVISION_CHECK)
def _wide_rows(work):
    """The outer slerps marked ``_GENERAL``, along their great circles.

    ``_qslerp_unit1``'s general branch (with ``_geodesic1``), without
    branches, for the rows whose arguments (rows _P and _Q) are unit, not
    equal and whose angle is in ``sincos``'s range; their rotations go into
    the step's rows and their mark is lifted. Returns the number of rows
    left marked (for the scalar route).
    """
    left = 0
    for b in range(BLOCK):
        aw, ax = work[_P + b], work[_P + BLOCK + b]
        ay, az = work[_P + 2 * BLOCK + b], work[_P + 3 * BLOCK + b]
        bw, bx = work[_Q + b], work[_Q + BLOCK + b]
        by, bz = work[_Q + 2 * BLOCK + b], work[_Q + 3 * BLOCK + b]
        unit = _is_unit_rows(aw, ax, ay, az) & _is_unit_rows(bw, bx, by, bz)
        # the shorter way round, tested by _qslerp_unit1 and again by
        # _geodesic1
        for _ in range(2):
            dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
            far = dw * dw + dx * dx + dy * dy + dz * dz > _SQRT2 * _SQRT2
            bw = -bw if far else bw
            bx = -bx if far else bx
            by = -by if far else by
            bz = -bz if far else bz
        d = aw * bw + ax * bx + ay * by + az * bz
        ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
        so = math.sqrt(ow * ow + ox * ox + oy * oy + oz * oz)
        k = 1.0 / so
        theta = atan2(so, d)
        tau = work[_TAU + b]
        h = 2.0 * tau * (1.0 - tau)
        y = h * theta
        sn, cs = sincos(y if abs(y) < SINCOS_LIMIT else 0.0)  # (as in _arc_rows)
        sign = -1.0 if work[_NEG + b] != 0.0 else 1.0
        wide = work[_PATH + b] == _GENERAL
        done = wide & unit & (so != 0.0) & (abs(y) < SINCOS_LIMIT)
        left += wide & ~done
        for e, (a_e, o_e) in enumerate(((aw, ow), (ax, ox), (ay, oy), (az, oz))):
            q = cs * a_e + sn * (o_e * k)
            q = -q if sign < 0.0 else q
            at = _STEP + (3 + e) * BLOCK + b
            work[at] = q if done else work[at]
        work[_PATH + b] = _GATHERED if done else work[_PATH + b]
    return left


@helper(options=_NO_DIVISION_CHECK)
def _own_rows(work, times, tr, rp, target, i0, j0, nb, rotation_only, into):
    """Rows j0 .. j0+nb at the frame's own samples i0 .., copied into the step.

    The scalar pass's own-times rule for a whole block at once, in loops
    LLVM vectorises: taken when the block's target times are exactly
    times[i0:i0+nb], so that every row is its stored sample (a missing
    sample's NaN included). ``into``: the scratch's rows to write (_STEP,
    or _ACC for the chain's first step). Returns False otherwise, and the
    scalar pass takes the block (the rows written here are then all written
    again).
    """
    n = times.shape[0]
    if i0 < 0 or j0 < 0 or i0 + nb > n:
        return False
    rf = rp.reshape(-1)
    tf = tr.reshape(-1)
    # the next block's samples, on their way while this block is copied
    ahead = min(n - (i0 + nb), BLOCK)
    for q in range(0, 4 * ahead, 8):
        prefetch(rf, 4 * (i0 + nb) + q)
    if not rotation_only:
        for q in range(0, 3 * ahead, 8):
            prefetch(tf, 3 * (i0 + nb) + q)
    for q in range(0, ahead, 8):
        prefetch(times, i0 + nb + q)
    # (loop counters from 0 and bases known non-negative: LLVM vectorises
    # only loops whose indices it can bound)
    odd = 0
    for b in range(nb):
        odd += np.int64(target[j0 + b] != times[i0 + b])
    if odd != 0:
        return False
    for b in range(nb):
        k = 4 * (i0 + b)
        work[into + 3 * BLOCK + b] = rf[k]
        work[into + 4 * BLOCK + b] = rf[k + 1]
        work[into + 5 * BLOCK + b] = rf[k + 2]
        work[into + 6 * BLOCK + b] = rf[k + 3]
    if rotation_only:
        for b in range(3 * BLOCK):
            work[into + b] = 0.0
    else:
        for b in range(nb):
            k = 3 * (i0 + b)
            work[into + b] = tf[k]
            work[into + BLOCK + b] = tf[k + 1]
            work[into + 2 * BLOCK + b] = tf[k + 2]
    for b in range(BLOCK):
        work[_PATH + b] = 0.0
    return True


@helper
def _chain_block(
    plan, statics, offsets, gaps, own,
    times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
    target, j0, j1, work, cur, rotation_only,
):  # fmt: skip
    """The chain at target[j0:j1], into the scratch ``work`` (WORK * BLOCK,).

    Row b's transform (tx, ty, tz, w, x, y, z) ends in ``work[_ACC + q *
    BLOCK + b]`` for q = 0..6. ``cur`` (SLOTS,) holds each
    slot's segment of the previous row and is updated. Returns the number
    of squad table rows computed.
    """
    computed = 0
    nb = j1 - j0
    for q in range(j1, min(j1 + BLOCK, target.shape[0]), 8):
        prefetch(target, q)  # the next block's times (8 per cache line)
    if plan[2] != 0:
        # the identity, for a first step taken inverted (a first step taken
        # forward is written over the rows as it is)
        for b in range(BLOCK):
            work[_ACC + b] = 0.0
            work[_ACC + BLOCK + b] = 0.0
            work[_ACC + 2 * BLOCK + b] = 0.0
            work[_ACC + 3 * BLOCK + b] = 1.0
            work[_ACC + 4 * BLOCK + b] = 0.0
            work[_ACC + 5 * BLOCK + b] = 0.0
            work[_ACC + 6 * BLOCK + b] = 0.0
    for s in range(plan.shape[0] // 3):
        kind = plan[3 * s]
        slot = plan[3 * s + 1]
        inverse = plan[3 * s + 2] != 0
        if kind == STATIC:
            _compose_static_rows(
                work, statics, slot, inverse, s == 0 and not inverse, rotation_only
            )
            continue
        # the slot's arrays, picked once per block
        if slot == 0:
            times, tr, r, rp, c = times0, t0, r0, p0, c0
        elif slot == 1:
            times, tr, r, rp, c = times1, t1, r1, p1, c1
        else:
            times, tr, r, rp, c = times2, t2, r2, p2, c2
        off = offsets[slot]
        n = times.shape[0]
        # the chain's first step, forward, is its accumulated transform
        first = s == 0 and not inverse
        into = _ACC if first else _STEP
        i0 = own[slot] - 1 + j0
        if (
            kind == SQUAD
            and own[slot] != 0
            and off == 0.0
            and _own_rows(work, times, tr, rp, target, i0, j0, nb, rotation_only, into)
        ):
            cur[slot] = own[slot] - 1 + j1 - 1
            if not first:
                _compose_rows(work, inverse, False)
            continue
        i = cur[slot]
        gathered = 0
        gap = gaps[slot]
        for b in range(nb):
            t = target[j0 + b] + off
            if kind == SQUAD:
                # the usual row, in few operations and branches: inside the
                # samples, not a sample time of the frame's own times nor
                # inside a gap, its segment's table row unit (the same
                # operations as the general rules below, which take the rest)
                i = _seek(times, t, i)
                if 0 <= i < n - 1:
                    if i + AHEAD < n:
                        # the segment of a row further on: its table row
                        # (15 values, over two cache lines) and samples
                        g = i + AHEAD
                        prefetch(c, TABLE_COLUMNS * g)
                        prefetch(c, TABLE_COLUMNS * g + 8)
                        prefetch(r, 4 * g)
                        prefetch(tr, 3 * g)
                    if c[i, _DONE] == 0.0:  # first use of the segment
                        computed += _fill_run(r, rp, times, c, i, RUN)
                    ti = times[i]
                    dt = times[i + 1] - ti
                    at_sample = t == ti
                    tau = (t - ti) / dt
                    if (
                        (not at_sample or own[slot] == 0)
                        and (at_sample or not dt > gap)
                        and abs(c[i, _DONE]) == _UNIT
                        and abs(tau * c[i, 4]) < SINCOS_LIMIT
                        and abs(tau * c[i, 9]) < SINCOS_LIMIT
                    ):
                        if rotation_only:
                            tx = ty = tz = 0.0
                        elif at_sample:
                            tx, ty, tz = tr[i, 0], tr[i, 1], tr[i, 2]
                        else:
                            tx = tr[i, 0] + tau * (tr[i + 1, 0] - tr[i, 0])
                            ty = tr[i, 1] + tau * (tr[i + 1, 1] - tr[i, 1])
                            tz = tr[i, 2] + tau * (tr[i + 1, 2] - tr[i, 2])
                        neg = c[i, _DONE] < 0.0  # the stored sample's sign
                        gathered += 1
                        work[_TAU + b] = tau
                        work[_TH1 + b] = c[i, 4]
                        work[_TH2 + b] = c[i, 9]
                        for e in range(4):
                            work[_P + e * BLOCK + b] = r[i, e]
                            work[_U1 + e * BLOCK + b] = c[i, 5 + e]
                            work[_Q + e * BLOCK + b] = c[i, e]
                            work[_U2 + e * BLOCK + b] = c[i, 10 + e]
                        work[_NEG + b] = 1.0 if neg else 0.0
                        work[_PATH + b] = _GATHERED
                        work[_STEP + b] = tx
                        work[_STEP + BLOCK + b] = ty
                        work[_STEP + 2 * BLOCK + b] = tz
                        continue
            tx = ty = tz = 0.0
            qw = qx = qy = qz = 0.0
            if kind == CONSTANT:
                if not rotation_only:
                    tx, ty, tz = tr[0, 0], tr[0, 1], tr[0, 2]
                qw, qx, qy, qz = rp[0, 0], rp[0, 1], rp[0, 2], rp[0, 3]
            else:
                i = _seek(times, t, i)
                k = i if i >= 0 else 0
                if kind == HELD:
                    if not rotation_only:
                        tx, ty, tz = tr[k, 0], tr[k, 1], tr[k, 2]
                    qw, qx, qy, qz = rp[k, 0], rp[k, 1], rp[k, 2], rp[k, 3]
                elif own[slot] != 0 and i >= 0 and t == times[i]:
                    # the frame's own times: the stored sample (NaN where it
                    # is missing), whatever its neighbours
                    qw, qx, qy, qz = rp[i, 0], rp[i, 1], rp[i, 2], rp[i, 3]
                    if not rotation_only:
                        tx, ty, tz = tr[i, 0], tr[i, 1], tr[i, 2]
                elif (
                    0 <= i < n - 1
                    and t != times[i]
                    and times[i + 1] - times[i] > gaps[slot]
                ):
                    # inside a gap longer than the frame's max_gap
                    tx = ty = tz = qw = qx = qy = qz = math.nan
                else:
                    if k > n - 2:
                        k = n - 2
                    # squad in segment g (numpy-quaternion uses the last
                    # segment before the start, indexing with -1)
                    g = i if i >= 0 else n - 1
                    if c[g, _DONE] == 0.0:  # first use of the segment
                        computed += _fill_run(r, rp, times, c, g, RUN)
                    if g < n - 1:
                        dt = times[g + 1] - times[g]
                    else:
                        dt = (times[n - 1] + (times[n - 1] - times[n - 2])) - times[
                            n - 1
                        ]
                    tau = (t - times[g]) / dt
                    if not rotation_only and i >= 0 and t == times[i]:
                        tx, ty, tz = tr[i, 0], tr[i, 1], tr[i, 2]
                    elif not rotation_only:
                        # inside the samples k == g: the translation's weight
                        # is tau (the same operations)
                        if 0 <= i < n - 1:
                            w = tau
                        else:
                            w = (t - times[k]) / (times[k + 1] - times[k])
                        tx = tr[k, 0] + w * (tr[k + 1, 0] - tr[k, 0])
                        ty = tr[k, 1] + w * (tr[k + 1, 1] - tr[k, 1])
                        tz = tr[k, 2] + w * (tr[k + 1, 2] - tr[k, 2])
                    # the sign of the stored sample the segment starts from
                    neg = (
                        r[k, 0] * rp[k, 0]
                        + r[k, 1] * rp[k, 1]
                        + r[k, 2] * rp[k, 2]
                        + r[k, 3] * rp[k, 3]
                    ) < 0.0
                    # (rows inside the samples with a unit segment took the
                    # short route above, into the squad pass; here the rest,
                    # by the scalar route, which the squad pass equals bit for
                    # bit: tests/core/test_fused_rows.py)
                    if abs(c[g, _DONE]) == _UNIT:
                        sn, cs = _sincos(tau * c[g, 4])
                        s1w = cs * r[g, 0] + sn * c[g, 5]
                        s1x = cs * r[g, 1] + sn * c[g, 6]
                        s1y = cs * r[g, 2] + sn * c[g, 7]
                        s1z = cs * r[g, 3] + sn * c[g, 8]
                        sn, cs = _sincos(tau * c[g, 9])
                        s2w = cs * c[g, 0] + sn * c[g, 10]
                        s2x = cs * c[g, 1] + sn * c[g, 11]
                        s2y = cs * c[g, 2] + sn * c[g, 12]
                        s2z = cs * c[g, 3] + sn * c[g, 13]
                    else:  # not unit: b in columns 4:8
                        if g < n - 1:
                            nw, nx, ny, nz = (
                                r[g + 1, 0],
                                r[g + 1, 1],
                                r[g + 1, 2],
                                r[g + 1, 3],
                            )
                        else:
                            nw, nx, ny, nz = (
                                c[n - 1, 4],
                                c[n - 1, 5],
                                c[n - 1, 6],
                                c[n - 1, 7],
                            )
                        s1w, s1x, s1y, s1z = _qslerp1(
                            r[g, 0], r[g, 1], r[g, 2], r[g, 3],
                            nw, nx, ny, nz, tau,
                        )  # fmt: skip
                        s2w, s2x, s2y, s2z = _qslerp1(
                            c[g, 0], c[g, 1], c[g, 2], c[g, 3],
                            c[g, 4], c[g, 5], c[g, 6], c[g, 7],
                            tau,
                        )  # fmt: skip
                    qw, qx, qy, qz = _qslerp_unit1(
                        s1w, s1x, s1y, s1z, s2w, s2x, s2y, s2z,
                        2.0 * tau * (1.0 - tau),
                    )  # fmt: skip
                    if neg:
                        qw, qx, qy, qz = -qw, -qx, -qy, -qz
                    if i >= 0 and t == times[i] and math.isnan(qw):
                        # at a sample whose next one is missing (no segment
                        # to evaluate): the sample itself
                        qw, qx, qy, qz = rp[i, 0], rp[i, 1], rp[i, 2], rp[i, 3]
            work[_PATH + b] = 0.0  # (evaluated here)
            work[_STEP + b] = tx
            work[_STEP + BLOCK + b] = ty
            work[_STEP + 2 * BLOCK + b] = tz
            work[_STEP + 3 * BLOCK + b] = qw
            work[_STEP + 4 * BLOCK + b] = qx
            work[_STEP + 5 * BLOCK + b] = qy
            work[_STEP + 6 * BLOCK + b] = qz
        cur[slot] = i
        for b in range(nb, BLOCK):  # past the end of a short last block
            work[_PATH + b] = 0.0
        wide = _squad_rows(work) if gathered > 0 else 0
        if wide >= _WIDE_ROWS:
            wide = _wide_rows(work)
        if wide > 0:
            # the outer slerps left, by the scalar route
            for b in range(nb):
                if work[_PATH + b] != _GENERAL:
                    continue
                tau = work[_TAU + b]
                qw, qx, qy, qz = _qslerp_unit1(
                    work[_P + b], work[_P + BLOCK + b], work[_P + 2 * BLOCK + b], work[_P + 3 * BLOCK + b],
                    work[_Q + b], work[_Q + BLOCK + b], work[_Q + 2 * BLOCK + b], work[_Q + 3 * BLOCK + b],
                    2.0 * tau * (1.0 - tau),
                )  # fmt: skip
                if work[_NEG + b] != 0.0:
                    qw, qx, qy, qz = -qw, -qx, -qy, -qz
                work[_STEP + 3 * BLOCK + b] = qw
                work[_STEP + 4 * BLOCK + b] = qx
                work[_STEP + 5 * BLOCK + b] = qy
                work[_STEP + 6 * BLOCK + b] = qz
        _compose_rows(work, inverse, s == 0 and not inverse)
    return computed


@helper
def _store_lookup(work, t_out, r_out, j0, j1, rotation_only):
    """Rows j0:j1 of a lookup's result from the block's transforms in ``work``."""
    nb = j1 - j0
    # the next block's rows, to be written (their lines fetched meanwhile)
    m = r_out.shape[0]
    for q in range(4 * j1, 4 * min(j1 + BLOCK, m), 8):
        prefetch_for_write(r_out, q)
    if not rotation_only:
        for q in range(3 * j1, 3 * min(j1 + BLOCK, m), 8):
            prefetch_for_write(t_out, q)
    # flat views of the block's rows: constant strides, so that the copy
    # from the scratch's columns vectorises (LLVM's interleaved stores)
    r = r_out.reshape(-1)[4 * j0 : 4 * j1]
    for b in range(nb):
        r[4 * b] = work[_ACC + 3 * BLOCK + b]
        r[4 * b + 1] = work[_ACC + 4 * BLOCK + b]
        r[4 * b + 2] = work[_ACC + 5 * BLOCK + b]
        r[4 * b + 3] = work[_ACC + 6 * BLOCK + b]
    if not rotation_only:
        t = t_out.reshape(-1)[3 * j0 : 3 * j1]
        for b in range(nb):
            t[3 * b] = work[_ACC + b]
            t[3 * b + 1] = work[_ACC + BLOCK + b]
            t[3 * b + 2] = work[_ACC + 2 * BLOCK + b]


@helper(options=_NO_DIVISION_CHECK)
def _apply_rows(work, d, out, nb, mode):
    """:func:`_apply_block` for one item per row: ``d`` and ``out`` (nb * c,) flat."""
    w, x, y, z = _ACC + 3 * BLOCK, _ACC + 4 * BLOCK, _ACC + 5 * BLOCK, _ACC + 6 * BLOCK
    if mode == 2:
        for b in range(nb):
            ow, ox, oy, oz = _qmul_rows(
                work[w + b], work[x + b], work[y + b], work[z + b],
                d[4 * b], d[4 * b + 1], d[4 * b + 2], d[4 * b + 3],
            )  # fmt: skip
            out[4 * b] = ow
            out[4 * b + 1] = ox
            out[4 * b + 2] = oy
            out[4 * b + 3] = oz
        return
    for b in range(nb):
        px, py, pz = _rotate_rows(
            work[w + b], work[x + b], work[y + b], work[z + b],
            d[3 * b], d[3 * b + 1], d[3 * b + 2],
        )  # fmt: skip
        if mode == 0:
            px += work[_ACC + b]
            py += work[_ACC + BLOCK + b]
            pz += work[_ACC + 2 * BLOCK + b]
        out[3 * b] = px
        out[3 * b + 1] = py
        out[3 * b + 2] = pz


@helper
def _apply_block(work, data, out, j0, j1, mode):
    """Rows j0:j1 of ``data`` carried by the block's transforms in ``work``.

    ``data`` (m|1, k, c) as for :func:`transform_chain`.
    """
    k = data.shape[1]
    # the next block's items (unless one is reused for every row) and results
    # (as _store_lookup)
    w = k * data.shape[2]
    m = out.shape[0]
    per_row = data.shape[0] > 1
    for q in range(w * j1, w * min(j1 + BLOCK, m), 8):
        if per_row:
            prefetch(data, q)
        prefetch_for_write(out, q)
    if k == 1 and data.shape[0] > 1:
        # one item per row (the usual case): flat views, vectorised
        c = data.shape[2]
        d = data.reshape(-1)[c * j0 : c * j1]
        _apply_rows(work, d, out.reshape(-1)[c * j0 : c * j1], j1 - j0, mode)
        return
    s_d = 1 if data.shape[0] > 1 else 0
    for b in range(j1 - j0):
        j = j0 + b
        row = j * s_d
        w, qx, qy, qz = (
            work[_ACC + 3 * BLOCK + b],
            work[_ACC + 4 * BLOCK + b],
            work[_ACC + 5 * BLOCK + b],
            work[_ACC + 6 * BLOCK + b],
        )
        if mode == 2:
            for e in range(k):
                ow, ox, oy, oz = _qmul1(
                    w, qx, qy, qz, data[row, e, 0], data[row, e, 1],
                    data[row, e, 2], data[row, e, 3],
                )  # fmt: skip
                out[j, e, 0] = ow
                out[j, e, 1] = ox
                out[j, e, 2] = oy
                out[j, e, 3] = oz
        else:
            for e in range(k):
                px, py, pz = _rotate1(
                    w, qx, qy, qz, data[row, e, 0], data[row, e, 1], data[row, e, 2]
                )
                if mode == 0:
                    px += work[_ACC + b]
                    py += work[_ACC + BLOCK + b]
                    pz += work[_ACC + 2 * BLOCK + b]
                out[j, e, 0] = px
                out[j, e, 1] = py
                out[j, e, 2] = pz


_SLOT_TYPES = (F1, F2, F2, F2, F2) * SLOTS


@kernel(I1, F2, F1, F1, I1, *_SLOT_TYPES, F1, B)
def lookup_chain(
    plan, statics, offsets, gaps, own,
    times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
    target, rotation_only,
):  # fmt: skip
    """The chain's transform at every target time, in one pass.

    Parameters
    ----------
    plan, statics, offsets, gaps, own, times0 .. c2 : see the module docstring
    target : ndarray, shape (m,)
        Target times (slot k reads ``target + offsets[k]``).
    rotation_only : bool
        Skip the translations (then ``t`` is returned with shape (0, 3)).

    Returns
    -------
    t : ndarray, shape (m, 3) or (0, 3)
    r : ndarray, shape (m, 4)
    computed : int
        Rows of the squad tables computed by this call.
    """
    m = target.shape[0]
    t_out = np.empty((0 if rotation_only else m, 3))
    r_out = np.empty((m, 4))
    work = np.zeros(WORK * BLOCK)  # zeros: see _ACC
    cur = np.full(SLOTS, -1, dtype=np.int64)
    computed = 0
    for j0 in range(0, m, BLOCK):
        j1 = min(j0 + BLOCK, m)
        computed += _chain_block(
            plan, statics, offsets, gaps, own,
            times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
            target, j0, j1, work, cur, rotation_only,
        )  # fmt: skip
        _store_lookup(work, t_out, r_out, j0, j1, rotation_only)
    return t_out, r_out, computed


@kernel(I1, F2, F1, F1, I1, *_SLOT_TYPES, F1, F3, I)
def transform_chain(
    plan, statics, offsets, gaps, own,
    times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
    target, data, mode,
):  # fmt: skip
    """Carry data through the chain at every target time, in one pass.

    Parameters
    ----------
    plan, statics, offsets, gaps, own, times0 .. c2 : see the module docstring
    target : ndarray, shape (m,)
    data : ndarray, shape (m, k, c) or (1, k, c)
        Points or vectors (c == 3) or quaternions (c == 4); a first
        dimension of 1 is reused for every row.
    mode : int
        0 points (rotate and translate), 1 vectors (rotate; translations
        are never evaluated), 2 quaternions (left-multiplied by the
        rotation; translations never evaluated).

    Returns
    -------
    out : ndarray, shape (m, k, c)
    computed : int
        Rows of the squad tables computed by this call.
    """
    m = target.shape[0]
    out = np.empty((m, data.shape[1], data.shape[2]))
    rotation_only = mode != 0
    work = np.zeros(WORK * BLOCK)  # zeros: see _ACC
    cur = np.full(SLOTS, -1, dtype=np.int64)
    computed = 0
    for j0 in range(0, m, BLOCK):
        j1 = min(j0 + BLOCK, m)
        computed += _chain_block(
            plan, statics, offsets, gaps, own,
            times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
            target, j0, j1, work, cur, rotation_only,
        )  # fmt: skip
        _apply_block(work, data, out, j0, j1, mode)
    return out, computed


# ---------------------------------------------------------------------------
# both cores: prange twins
# ---------------------------------------------------------------------------

# The twins split the output rows into contiguous chunks (:data:`CHUNKS`,
# each a whole number of blocks), each with its own scratch and its own
# segment cursors: a chunk starts its walk from -1, a binary search, and
# the segment of a time does not depend on where the walk started, so every
# row gets exactly the arithmetic of the serial kernel (bit for bit).
#
# The lazily filled squad tables must never be written by two threads, nor
# read half-written. So before a twin runs, :func:`prefill_chain` computes
# every table row the call will read: per chunk of target rows, the range
# of segments its squad evaluations use (a merge walk with the serial
# kernel's rules: the frame's own sample times and rows inside a gap read
# no table row); the ranges merged into disjoint intervals; and their
# missing rows filled in pieces shared out to the threads. The twins then only
# read the tables. The engine calls both under its table lock, as one
# launch (rbm_nb._engine.fused).

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
        a = _seek(times, target[j0] + off, -1)
        b = _seek(times, target[j1 - 1] + off, a)
        if b < 0:
            return n, -1, True  # every time before the first sample
        return max(a, 0), b, a < 0
    lo = n
    hi = -1
    last = False
    i = -1
    for j in range(j0, j1):
        t = target[j] + off
        i = _seek(times, t, i)
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


@helper
def _fill_range(r, rp, t, c, a, b):
    """Compute the missing rows of ``c[a:b]`` (nothing outside). Returns their number."""
    done = 0
    i = a
    while i < b:
        if c[i, _DONE] != 0.0:
            i += 1
            continue
        k = _fill_run(r, rp, t, c, i, b - i)
        done += k
        i += k
    return done


@kernel(I1, F2, F1, F1, I1, *_SLOT_TYPES, F1, options=PARALLEL_KERNEL)
def prefill_chain(
    plan, statics, offsets, gaps, own,
    times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
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
    sizes = np.array([times0.shape[0], times1.shape[0], times2.shape[0]])
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
            if slot == 0:
                times = times0
            elif slot == 1:
                times = times1
            else:
                times = times2
            a, b, before = _segments_read(
                times, own[slot], gaps[slot], offsets[slot],
                target, bounds[ch], bounds[ch + 1], decreasing == 0,
            )  # fmt: skip
            lo[slot, ch] = a
            hi[slot, ch] = b
            last[slot, ch] = before
    filled, pieces = _fill_pieces(plan, sizes, lo, hi, last, CHUNKS)
    computed = 0
    for p in prange(pieces.shape[0]):
        slot = pieces[p, 0]
        if slot == 0:
            computed += _fill_range(r0, p0, times0, c0, pieces[p, 1], pieces[p, 2])
        elif slot == 1:
            computed += _fill_range(r1, p1, times1, c1, pieces[p, 1], pieces[p, 2])
        else:
            computed += _fill_range(r2, p2, times2, c2, pieces[p, 1], pieces[p, 2])
    return computed, filled


@kernel(I1, F2, F1, F1, I1, *_SLOT_TYPES, F1, B, options=PARALLEL_KERNEL)
def lookup_chain_parallel(
    plan, statics, offsets, gaps, own,
    times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
    target, rotation_only,
):  # fmt: skip
    """:func:`lookup_chain` on all threads, with tables prefilled.

    Call :func:`prefill_chain` first (unless the tables are complete): rows
    are evaluated in parallel chunks that only read the tables. Returns
    what :func:`lookup_chain` returns, bit for bit (``computed`` is 0 when
    the tables were prefilled).
    """
    m = target.shape[0]
    t_out = np.empty((0 if rotation_only else m, 3))
    r_out = np.empty((m, 4))
    bounds = _chunk_bounds(m, CHUNKS)
    nch = bounds.shape[0] - 1
    # each chunk's segment cursors; its scratch is allocated in the loop,
    # which numba hoists to once per thread (a (chunks, BLOCK, 7) array
    # would be half of a transform_points output of the recording)
    cur = np.full((nch, SLOTS), -1, dtype=np.int64)
    computed = 0
    for ch in prange(nch):
        work_c = np.zeros(WORK * BLOCK)  # zeros: see _ACC
        cur_c = cur[ch]
        for j0 in range(bounds[ch], bounds[ch + 1], BLOCK):
            j1 = min(j0 + BLOCK, bounds[ch + 1])
            computed += _chain_block(
                plan, statics, offsets, gaps, own,
                times0, t0, r0, p0, c0, times1, t1, r1, p1, c1,
                times2, t2, r2, p2, c2,
                target, j0, j1, work_c, cur_c, rotation_only,
            )  # fmt: skip
            _store_lookup(work_c, t_out, r_out, j0, j1, rotation_only)
    return t_out, r_out, computed


@kernel(I1, F2, F1, F1, I1, *_SLOT_TYPES, F1, F3, I, options=PARALLEL_KERNEL)
def transform_chain_parallel(
    plan, statics, offsets, gaps, own,
    times0, t0, r0, p0, c0, times1, t1, r1, p1, c1, times2, t2, r2, p2, c2,
    target, data, mode,
):  # fmt: skip
    """:func:`transform_chain` on all threads, with tables prefilled.

    As :func:`lookup_chain_parallel`; returns what :func:`transform_chain`
    returns, bit for bit.
    """
    m = target.shape[0]
    out = np.empty((m, data.shape[1], data.shape[2]))
    rotation_only = mode != 0
    bounds = _chunk_bounds(m, CHUNKS)
    nch = bounds.shape[0] - 1
    cur = np.full((nch, SLOTS), -1, dtype=np.int64)
    computed = 0
    for ch in prange(nch):
        work_c = np.zeros(WORK * BLOCK)  # zeros: see _ACC
        cur_c = cur[ch]
        for j0 in range(bounds[ch], bounds[ch + 1], BLOCK):
            j1 = min(j0 + BLOCK, bounds[ch + 1])
            computed += _chain_block(
                plan, statics, offsets, gaps, own,
                times0, t0, r0, p0, c0, times1, t1, r1, p1, c1,
                times2, t2, r2, p2, c2,
                target, j0, j1, work_c, cur_c, rotation_only,
            )  # fmt: skip
            _apply_block(work_c, data, out, j0, j1, mode)
    return out, computed
