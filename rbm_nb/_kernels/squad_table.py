"""The squad table of a moving frame: its spline's segments, filled lazily.

One row per sample (:data:`TABLE_COLUMNS` float64): the control point a[i]
and the two great circles squad follows in segment i (or b[i] where the
segment is not unit), and a state column (not computed yet, not unit, or
unit with the divisor that makes the sample's unit row from the stored one;
its sign that of the stored sample). The fused chain kernels
(:mod:`.fused`) fill a row on its first use (:func:`_fill_run`, a run of
rows at a time), :func:`squad_table` fills them all; either way each row
holds the same values, to within 4 ulp of
``quaternion.squad_coefficients``/``squad_segments``
(tests/core/test_fused.py), whatever the order rows were filled in.
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F1, F2, S1, helper, kernel  # noqa: E741
from .quaternion import _EPS, _SQRT2, _is_unit, _qexp1, _qinv1, _qlog1, _qmul1
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    atan2,
    atan_over_x_small,
    cos_small,
    sinc_small,
)
from .signed_rows import signed_unit_row, unit_divisor

__all__ = [
    "TABLE_COLUMNS",
    "RUN",
    "DIVISOR_LOW",
    "DIVISOR_HIGH",
    "is_unit",
    "squad_table",
]

# squad table columns: a (0:4); for a segment of unit quaternions the great
# circles r[i] -> r[i+1] (4:9: θ, u) and a[i] -> b[i] (9:14), else b (4:8)
# (squad falls back to slerps, which need b and nothing else); the state
# (14: 0.0 not computed yet, 2.0 not unit; a unit row holds its sample's
# divisor d, ``signed_rows.unit_divisor``, where 0.5 <= d < 1.5, else 4.0),
# negative where the stored sample i is -r[i] (so that the usual row reads
# the sign its result takes here rather than the stored rotations: 32 bytes
# less per row). 15 float64 per sample: b of unit segments is not kept, as
# the great circle a -> b replaces it.
#
# The divisor in the state column spares the usual row a square root: it
# makes r[i] = p[i] / state (p the stored row; the sign of a unit row's
# state is its sign code's, as r[i]·p[i] = ±|p[i]|²/d), bit for bit the row
# ``signed_rows.signed_unit_row`` makes.
TABLE_COLUMNS = 15
_DONE = 14
_NOT_UNIT = 2.0
# a unit row's state holds its divisor d where DIVISOR_LOW <= d < DIVISOR_HIGH
# (every frame registered through the door: norms within 1e-2 of 1), else
# _UNIT_FAR; none of them is _NOT_UNIT or 0.0
DIVISOR_LOW = 0.5
DIVISOR_HIGH = 1.5
_UNIT_FAR = 4.0


@helper(inline=True)
def _unit_state(d, sign):
    """The state of a unit row whose sample has divisor ``d`` and stored sign ``sign``."""
    return sign * (d if (d >= DIVISOR_LOW) & (d < DIVISOR_HIGH) else _UNIT_FAR)


@helper(inline=True)
def is_unit(state):
    """Whether a computed row's state (column 14) is that of a unit row."""
    return abs(state) != _NOT_UNIT


# below this, exp(w) is 1 + w and log(1 + d) is d - d²/2 to within an ulp
_TINY = 2.0**-27


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
def _log_step(sg, rp, i):
    """log(r[i]⁻¹ r[i+1]), as :func:`quaternion.squad_coefficients` forms it."""
    n = sg.shape[0]
    if i < 0 or i > n - 2:
        return 0.0, 0.0, 0.0, 0.0  # not used by any row
    # r[i]⁻¹ with one division, not _qinv1's four (within an ulp of it)
    w, x, y, z = signed_unit_row(rp, sg, i)
    k = 1.0 / (w * w + x * x + y * y + z * z)
    iw, ix, iy, iz = w * k, -x * k, -y * k, -z * k
    bw, bx, by, bz = signed_unit_row(rp, sg, i + 1)
    nw, nx, ny, nz = _qmul1(iw, ix, iy, iz, bw, bx, by, bz)
    return _qlog_table(nw, nx, ny, nz)


@helper(inline=True)
def _inv_interval(t, k):
    """1 / (t[k+1] - t[k]), or 0.0 where sample k or k+1 does not exist."""
    if k < 0 or k > t.shape[0] - 2:
        return 0.0
    return 1.0 / (t[k + 1] - t[k])


@helper
def _stored_sign(rw, rx, ry, rz, rp, i):
    """-1.0 where the stored sample i is -r[i], else 1.0 (the chain's test)."""
    dot = rw * rp[i, 0] + rx * rp[i, 1] + ry * rp[i, 2] + rz * rp[i, 3]
    return -1.0 if dot < 0.0 else 1.0


@helper
def _table_row(sg, rp, c, i, pw, px, py, pz, lw, lx, ly, lz, nw, nx, ny, nz, ra, rb):
    """Fill row i of the squad table of (r, t) (n >= 2) into ``c``.

    ``rp``: the rotations as stored, ``sg`` their sign codes: the samples
    r (:func:`.signed_rows.signed_unit_row`), and the sign in the state
    column.

    Row i of ``squad_coefficients`` (a, b) and ``squad_segments`` to within
    4 ulp, from samples i-1 .. i+2, the logs p = L[i-1], l = L[i],
    n = L[i+1] (``_log_step``) and the ratios of sampling intervals
    ra = (t[i+1]-t[i]) / (t[i]-t[i-1]), rb = (t[i+1]-t[i]) / (t[i+2]-t[i+1])
    (where those samples exist).

    Not inlined: the vectorised blocks call it only for the rows their
    route does not cover, and inlining its exact routes (exp, log and
    great circles) into every caller multiplied compile time.
    """
    n = sg.shape[0]
    # samples i and i+1 (r1 is not read for the last row)
    rw, rx, ry, rz = signed_unit_row(rp, sg, i)
    r1w = r1x = r1y = r1z = 0.0
    if i < n - 1:
        r1w, r1x, r1y, r1z = signed_unit_row(rp, sg, i + 1)
    # a[i]; a missing sample i-1 (a NaN log p) starts a run: the end rule,
    # as at the first sample (``quaternion.squad_coefficients``)
    if i == 0 or i == n - 1 or math.isnan(pw):
        aw, ax, ay, az = rw, rx, ry, rz
    else:
        ew, ex, ey, ez = _qexp_table(
            (-lw + pw * ra) * 0.25,
            (-lx + px * ra) * 0.25,
            (-ly + py * ra) * 0.25,
            (-lz + pz * ra) * 0.25,
        )
        aw, ax, ay, az = _qmul1(rw, rx, ry, rz, ew, ex, ey, ez)
    # b[i], and the sample the segment ends at; a missing sample i+2 (a
    # NaN log n) ends the run at i+1
    if i < n - 2 and not math.isnan(nw):
        ew, ex, ey, ez = _qexp_table(
            (nw * rb - lw) * -0.25,
            (nx * rb - lx) * -0.25,
            (ny * rb - ly) * -0.25,
            (nz * rb - lz) * -0.25,
        )
        bw, bx, by, bz = _qmul1(r1w, r1x, r1y, r1z, ew, ex, ey, ez)
    elif i <= n - 2:
        bw, bx, by, bz = r1w, r1x, r1y, r1z
    else:
        # the virtual sample past the end: r[n-1] r[n-2]⁻¹ r[n-1] (i is n-1)
        iw, ix, iy, iz = signed_unit_row(rp, sg, n - 2)
        iw, ix, iy, iz = _qinv1(iw, ix, iy, iz)
        w, x, y, z = _qmul1(rw, rx, ry, rz, iw, ix, iy, iz)
        bw, bx, by, bz = _qmul1(w, x, y, z, rw, rx, ry, rz)
    if i < n - 1:
        ew, ex, ey, ez = r1w, r1x, r1y, r1z
    else:
        ew, ex, ey, ez = bw, bx, by, bz
    c[i, 0] = aw
    c[i, 1] = ax
    c[i, 2] = ay
    c[i, 3] = az
    unit = (
        _is_unit(rw, rx, ry, rz)
        and _is_unit(ew, ex, ey, ez)
        and _is_unit(aw, ax, ay, az)
        and _is_unit(bw, bx, by, bz)
    )
    if unit:
        theta2 = lx * lx + ly * ly + lz * lz
        # (r[i]·r[i+1] > 0: the arc between them is under π/2)
        first_half = (rw * r1w + rx * r1x + ry * r1y + rz * r1z) > 0.0
        if i < n - 1 and theta2 > 0.0 and abs(lw) < _TINY and first_half:
            # r[i+1] = r[i] exp(l) with |l| < π/2 (r[i]·r[i+1] > 0, no flip):
            # the arc is θ = |l| along u = r[i] (0, l / θ), which the log has
            # all but worked out (within 4 ulp of _geodesic_table's atan)
            theta = math.sqrt(theta2)
            k = 1.0 / theta
            ow, ox, oy, oz = _qmul1(rw, rx, ry, rz, 0.0, lx * k, ly * k, lz * k)
            c[i, 4] = theta
            c[i, 5] = ow
            c[i, 6] = ox
            c[i, 7] = oy
            c[i, 8] = oz
        else:
            g = _geodesic_table(rw, rx, ry, rz, ew, ex, ey, ez)
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
        sign = _stored_sign(rw, rx, ry, rz, rp, i)
        c[i, _DONE] = _unit_state(unit_divisor(rp, sg, i), sign)
    else:
        c[i, 4] = bw
        c[i, 5] = bx
        c[i, 6] = by
        c[i, 7] = bz
        for k in range(8, 14):
            c[i, k] = 0.0
        c[i, _DONE] = _NOT_UNIT * _stored_sign(rw, rx, ry, rz, rp, i)


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


@helper(options=EXACT_VECTOR_KERNEL)
def _fill_block(sg, rp, t, c, i0, i1, s):
    """Rows i0..i1-1 of the table (1 <= i0, i1 <= n - 2, i1 - i0 <= FILL_BLOCK).

    ``s``: scratch of shape (_S_ROWS, FILL_BLOCK + 3). In stages, each a few
    short loops over the block (inlined: one loop each, as LLVM vectorises
    them): samples and logs, control points, great circles, the rows.
    """
    m = i1 - i0
    _block_logs(sg, rp, t, s, i0, m)
    _block_control_points(s, m)
    _block_arcs(s, m)
    _block_store(sg, rp, c, s, i0, m)


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _block_logs(sg, rp, t, s, i0, m):
    """Samples i0-1 .. i0+m+1, their intervals and the logs between them, into ``s``."""
    # gather samples i0-1 .. i1+1 (index k: sample i0 - 1 + k)
    for k in range(m + 3):
        w, x, y, z = signed_unit_row(rp, sg, i0 - 1 + k)
        s[_S_Q, k] = w
        s[_S_Q + 1, k] = x
        s[_S_Q + 2, k] = y
        s[_S_Q + 3, k] = z
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
            lw, lx, ly, lz = _log_step(sg, rp, i0 - 1 + k)
            s[_S_L, k] = lw
            s[_S_L + 1, k] = lx
            s[_S_L + 2, k] = ly
            s[_S_L + 3, k] = lz


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _block_control_points(s, m):
    """The block's control points a and b, by the series route where it holds."""
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


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _block_arcs(s, m):
    """The block's great circles r[i] -> r[i+1] and a -> b (θ, u)."""
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


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _block_store(sg, rp, c, s, i0, m):
    """The block's rows into the table: by the vector route where it held,
    else by :func:`_table_row`."""
    for b in range(m):
        i = i0 + b
        if s[_S_BAD, b] != 0.0:
            _table_row(
                sg, rp, c, i,
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
            rw, rx, ry, rz = signed_unit_row(rp, sg, i)
            dot = rw * rp[i, 0] + rx * rp[i, 1] + ry * rp[i, 2] + rz * rp[i, 3]
            sign = -1.0 if dot < 0.0 else 1.0
            c[i, _DONE] = _unit_state(unit_divisor(rp, sg, i), sign)


@helper
def _fill_row(sg, rp, t, c, i):
    """Row i of the table alone (its three logs computed here)."""
    n = sg.shape[0]
    pw, px, py, pz = _log_step(sg, rp, i - 1)
    lw, lx, ly, lz = _log_step(sg, rp, i)
    nw, nx, ny, nz = _log_step(sg, rp, i + 1)
    dt = t[i + 1] - t[i] if i < n - 1 else 0.0
    _table_row(
        sg, rp, c, i, pw, px, py, pz, lw, lx, ly, lz, nw, nx, ny, nz,
        dt * _inv_interval(t, i - 1), dt * _inv_interval(t, i + 1),
    )  # fmt: skip


@helper
def _fill_run(sg, rp, t, c, g, count):
    """Compute row g of the table and the missing rows after it (``count`` at most).

    Stops before the first row already computed. Returns the number of
    rows computed.
    """
    n = sg.shape[0]
    end = min(g + count, n)
    stop = g + 1
    while stop < end and c[stop, _DONE] == 0.0:
        stop += 1
    s = np.empty((_S_ROWS, FILL_BLOCK + 3))
    i = g
    while i < stop:
        if i == 0 or i >= n - 2:
            _fill_row(sg, rp, t, c, i)
            i += 1
        else:
            j = min(i + FILL_BLOCK, stop, n - 2)
            _fill_block(sg, rp, t, c, i, j, s)
            i = j
    return stop - g


@kernel(S1, F2, F1)
def squad_table(sg, p, t):
    """The whole squad table of rotations r (n >= 2) at strictly increasing t.

    ``sg``: the sign codes (:mod:`.signed_rows`) that make r, the rotations
    free of sign flips (``unflip``), from ``p``, the rotations as stored.

    Returns
    -------
    ndarray, shape (n, 15)
        See the module docstring; every row computed.
    """
    n = sg.shape[0]
    c = np.zeros((n, TABLE_COLUMNS))
    _fill_run(sg, p, t, c, 0, n)
    return c


@helper
def _fill_range(sg, rp, t, c, a, b):
    """Compute the missing rows of ``c[a:b]`` (nothing outside). Returns their number."""
    done = 0
    i = a
    while i < b:
        if c[i, _DONE] != 0.0:
            i += 1
            continue
        k = _fill_run(sg, rp, t, c, i, b - i)
        done += k
        i += k
    return done
