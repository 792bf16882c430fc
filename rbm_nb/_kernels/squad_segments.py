"""The squad segments of a block of output rows, set up in scratch space.

:mod:`.squad_walk` walks its output times in blocks of :data:`_BLOCK` rows;
for each block, the squad segments it falls in are set up here
(:func:`_prepare` for every segment from the block's first to its last at
once, in short vector loops; the ``_exact`` functions one segment at a time,
for sparse blocks and for whatever the vector loops do not cover): the
samples' unit parts and scales, the logs of the steps between them, the
control points and each segment's record of the two great-circle arcs
(:data:`_N_REC` quantities), in the flat scratch array described below.
Both routes compute the same expressions in the same order and give the
same bits.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from numba import types
from numba.extending import intrinsic

from .._infra.config import KERNEL, VECTOR_KERNEL
from ._jit import helper
from .quaternion import _qmul1
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    atan_over_x_small,
    cos_small,
    sinc_small,
)

# Scales |q| whose log is beyond this take the exact route (the bounds used
# to decide a slerp's direction assume scales near 1).
_LOG_SCALE_LIMIT = 0.05
# Margin around a slerp's direction decision within which the exact route
# decides instead (the scaled decision is right to ~1e-15).
_DECISION_MARGIN = 1e-9
# Below this, exp and log1p are evaluated by their Taylor series.
_SMALL = 1e-3

# a segment's record (see _prepare)
_N_REC = 29
# output rows per block, and the most segments a block sets up at once
_BLOCK = 96
_SPAN = 2 * _BLOCK

# fused multiply-add in the series (fastmath "contract" only: results move by
# an ulp at most, far inside the 1e-12 the tests hold them to): the walk and
# its scalar parts
_SERIAL = dataclasses.replace(KERNEL, fastmath=frozenset({"contract"}))
# The vector loops: fused multiply-add in the series (fastmath "contract"
# only: results move by an ulp at most, far inside the 1e-12 the tests hold
# them to), and no ZeroDivisionError branch (it would keep LLVM from
# vectorising them; nothing else changes).
_VECTOR = VECTOR_KERNEL

# fast-math flags of the arithmetic of _qmul_plain: numba adds a function's
# flags ("contract") only to operations that carry none, and "arcp"
# concerns divisions, of which there are none
_PLAIN = ("arcp",)


def _qmul_plain_ir(typingctx, aw, ax, ay, az, bw, bx, by, bz):
    """:func:`_qmul1` emitted in place, with its rounding (``_qmul_plain``).

    A call of the helper _qmul1 keeps a loop from vectorising; inlined by
    numba it would take the caller's "contract" flag and round differently
    (fused multiply-adds), whereas _qmul1 is compiled without it.
    """
    f8 = types.float64
    signature = types.UniTuple(f8, 4)(f8, f8, f8, f8, f8, f8, f8, f8)

    def codegen(context, builder, sig, args):
        pw, px, py, pz, qw, qx, qy, qz = args

        def mul(a, b):
            return builder.fmul(a, b, flags=_PLAIN)

        def add(a, b):
            return builder.fadd(a, b, flags=_PLAIN)

        def sub(a, b):
            return builder.fsub(a, b, flags=_PLAIN)

        w = sub(sub(sub(mul(pw, qw), mul(px, qx)), mul(py, qy)), mul(pz, qz))
        x = sub(add(add(mul(pw, qx), mul(px, qw)), mul(py, qz)), mul(pz, qy))
        y = add(add(sub(mul(pw, qy), mul(px, qz)), mul(py, qw)), mul(pz, qx))
        z = add(sub(add(mul(pw, qz), mul(px, qy)), mul(py, qx)), mul(pz, qw))
        return context.make_tuple(builder, sig.return_type, (w, x, y, z))

    return signature, codegen


# called from kernels with the eight components (typing context aside)
_qmul_plain: Any = intrinsic(_qmul_plain_ir)


@helper(inline=True)
def _unit(w, x, y, z):
    """(unit w, x, y, z, ln |q|, NaN?) of a quaternion."""
    n2 = w * w + x * x + y * y + z * z
    nan = math.isnan(n2)
    e = n2 - 1.0
    if abs(e) < _SMALL:
        # ln |q| = log1p(e) / 2
        lam = (
            0.5
            * e
            * (1.0 - e * (0.5 - e * (1.0 / 3.0 - e * (0.25 - e * (0.2 - e / 6.0)))))
        )
    else:
        lam = 0.5 * math.log(n2)
    if n2 == 1.0:
        return w, x, y, z, 0.0, nan
    inv = 1.0 / math.sqrt(n2)
    return w * inv, x * inv, y * inv, z * inv, lam, nan


@helper(inline=True)
def _log_vec(aw, ax, ay, az, bw, bx, by, bz):
    """Vector part of log(a⁻¹ b) for unit a and b (its scalar part is 0)."""
    pw, px, py, pz = _qmul1(aw, -ax, -ay, -az, bw, bx, by, bz)
    b2 = px * px + py * py + pz * pz
    if pw > 0.0 and b2 < (SERIES_RATIO * pw) ** 2:
        f = atan_over_x_small(b2 / (pw * pw)) / pw
        return f * px, f * py, f * pz
    b = math.sqrt(b2)
    if b <= 1e-14 * abs(pw):
        if pw < 0.0:
            return math.pi, 0.0, 0.0  # numpy-quaternion's choice (_qlog1)
        return 0.0, 0.0, 0.0
    f = math.atan2(b, pw) / b
    return f * px, f * py, f * pz


@helper(inline=True)
def _exp_vec(ux, uy, uz):
    """exp of the pure quaternion (0, u): (cos|u|, sin|u| u/|u|)."""
    u2 = ux * ux + uy * uy + uz * uz
    if u2 < SERIES_ANGLE * SERIES_ANGLE:
        c = cos_small(u2)
        s = sinc_small(u2)
    else:
        un = math.sqrt(u2)
        c = math.cos(un)
        s = math.sin(un) / un
    return c, s * ux, s * uy, s * uz


@helper(inline=True)
def _great_circle(aw, ax, ay, az, bw, bx, by, bz):
    """The arc from unit a to unit b as (o, θ², θ, g).

    o = b - (a·b) a and g = θ / |o|, so that
    slerp(a, b, τ) = cos(τθ) a + sin(τθ)/(τθ) τ g o (:func:`_along`).
    """
    d = aw * bw + ax * bx + ay * by + az * bz
    ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
    o2 = ow * ow + ox * ox + oy * oy + oz * oz
    if d > 0.0 and o2 < (SERIES_RATIO * d) ** 2:
        # x = tan θ = |o| / d is small: θ / |o| = atan(x) / x / d
        g = atan_over_x_small(o2 / (d * d)) / d
        theta2 = o2 * g * g
        return ow, ox, oy, oz, theta2, math.sqrt(theta2), g
    so = math.sqrt(o2)
    theta = math.atan2(so, d)
    return ow, ox, oy, oz, theta * theta, theta, theta / so if so > 0.0 else 0.0


@helper(inline=True)
def _flip_bound(la, lb):
    """A bound on |δ|, where |a - b|² > 2 ⇔ â·b̂ < δ for |a| = e^la, |b| = e^lb.

    δ = cosh(la - lb) - exp(-(la + lb)) = (la + lb) + O(la² + lb²), so
    |δ| <= 2 (|la| + |lb|) while |la|, |lb| <= _LOG_SCALE_LIMIT.
    """
    return 2.0 * (abs(la) + abs(lb))


@helper(inline=True)
def _decide(d, bound):
    """+1 no flip, -1 flip, 0 too close to call (|δ| <= bound, see _flip_bound)."""
    if d > bound + _DECISION_MARGIN:
        return 1.0
    if d < -bound - _DECISION_MARGIN:
        return -1.0
    return 0.0


@helper(inline=True)
def _control_point(bw, bx, by, bz, ux, uy, uz):
    """base exp((0, u)): a squad control point from its sample (unit parts)."""
    ew, ex, ey, ez = _exp_vec(ux, uy, uz)
    return _qmul1(bw, bx, by, bz, ew, ex, ey, ez)


# The scratch of a block (one flat array, :data:`_WS` float64): quantity k
# of item a at ``k * _W + a``. Fixed offsets in one array let LLVM see that
# the quantities do not overlap, so that the loops over a block's samples and
# segments vectorise without runtime checks. Samples are stored from the
# sample before the block's first segment: with s0 the first segment, row a
# holds sample s0 - 1 + a, and the log row a the step from sample
# s0 - 1 + a to the next; segment s0 + r has slot r (row r + 1 holds its
# first sample).
_W = _SPAN + 8
# samples: unit parts w, x, y, z (0:4), ln of the scale (4), 1.0 if NaN (5)
_SMP = 0
# log r[k]⁻¹ r[k+1] (vector part, 0:3), t[k+1] - t[k] (3) and its inverse (4)
_LOG = 6 * _W
# per segment: the end sample r[i+1] (0:4), A[i] (4:8), B[i] (8:12), their
# ln scales (12:15), the number of its own samples missing (15)
_CTL = 11 * _W
# per segment: the record of _N_REC quantities (see _prepare)
_REC = 27 * _W
# per segment: 1.0 where a vector stage's branch does not apply
_REDO = (27 + _N_REC) * _W
_WS = _REDO + _W


@helper(options=_VECTOR)
def _samples(qf, sign, ws, k0, k1, a0, scalar):
    """Samples k0..k1 of ``qf`` (n * 4, flat), sign-corrected, as unit parts,
    ln scale and NaN flag into rows a0.. (as :func:`_unit`; a0 is 0 or 1).

    A vector loop takes _unit's series branch for ln |q|; the samples off
    it (all of them if ``scalar``) are then redone by _unit itself.
    """
    base = max(k0, 0)
    row = min(max(a0, 0), 1)
    # views from the first item, and a count LLVM can bound, so that every
    # index is provably within the arrays (no negative-index wraparound)
    src = qf[4 * base :]
    sg = sign[base:]
    dst = ws[row:]
    slow = 0
    for b in range(min(k1 - k0 + 1, _W - 1)):
        s = sg[b]
        w, x, y, z = (
            s * src[4 * b],
            s * src[4 * b + 1],
            s * src[4 * b + 2],
            s * src[4 * b + 3],
        )
        n2 = w * w + x * x + y * y + z * z
        e = n2 - 1.0
        # _unit's series branch for ln |q| (the others are redone below)
        lam = (
            0.5
            * e
            * (1.0 - e * (0.5 - e * (1.0 / 3.0 - e * (0.25 - e * (0.2 - e / 6.0)))))
        )
        one = n2 == 1.0
        inv = 1.0 / math.sqrt(n2)
        dst[_SMP + b] = w if one else w * inv
        dst[_SMP + _W + b] = x if one else x * inv
        dst[_SMP + 2 * _W + b] = y if one else y * inv
        dst[_SMP + 3 * _W + b] = z if one else z * inv
        dst[_SMP + 4 * _W + b] = 0.0 if one else lam
        dst[_SMP + 5 * _W + b] = 1.0 if math.isnan(n2) else 0.0
        # (a missing sample's values are never used: it makes NaN every
        # segment that reads it)
        slow += abs(e) >= _SMALL
    if slow or scalar:
        for b in range(k1 - k0 + 1):
            k = base + b
            s = sign[k]
            w, x, y, z = (
                s * qf[4 * k],
                s * qf[4 * k + 1],
                s * qf[4 * k + 2],
                s * qf[4 * k + 3],
            )
            # (the vector loop's test, on the same values)
            if not scalar and not abs((w * w + x * x + y * y + z * z) - 1.0) >= _SMALL:
                continue
            w, x, y, z, lam, bad = _unit(w, x, y, z)
            a = row + b
            ws[_SMP + a] = w
            ws[_SMP + _W + a] = x
            ws[_SMP + 2 * _W + a] = y
            ws[_SMP + 3 * _W + a] = z
            ws[_SMP + 4 * _W + a] = lam
            ws[_SMP + 5 * _W + a] = 1.0 if bad else 0.0


@helper(options=_VECTOR)
def _logs(t_in, ws, k0, k1, a0, scalar):
    """Log rows a0.. of the steps between samples k0..k1 (rows a0.. of the
    samples), with the sampling intervals and their inverses (as
    :func:`_log_vec`; a0 is 0 or 1).

    A vector loop takes _log_vec's series branch; the steps off it (all of
    them if ``scalar``) are then redone by _log_vec itself.
    """
    base = max(k0, 0)
    row = min(max(a0, 0), 1)
    tt = t_in[base:]
    dst = ws[row:]
    slow = 0
    for b in range(min(k1 - k0, _W - 2)):
        pw, px, py, pz = _qmul_plain(
            dst[_SMP + b], -dst[_SMP + _W + b], -dst[_SMP + 2 * _W + b],
            -dst[_SMP + 3 * _W + b], dst[_SMP + b + 1], dst[_SMP + _W + b + 1],
            dst[_SMP + 2 * _W + b + 1], dst[_SMP + 3 * _W + b + 1],
        )  # fmt: skip
        b2 = px * px + py * py + pz * pz
        # _log_vec's series branch (the others are redone below)
        f = atan_over_x_small(b2 / (pw * pw)) / pw
        dst[_LOG + b] = f * px
        dst[_LOG + _W + b] = f * py
        dst[_LOG + 2 * _W + b] = f * pz
        dt = tt[b + 1] - tt[b]
        dst[_LOG + 3 * _W + b] = dt
        dst[_LOG + 4 * _W + b] = 1.0 / dt
        # (a step from or to a missing sample, pw NaN, is never used)
        slow += (not ((pw > 0.0) & (b2 < (SERIES_RATIO * pw) ** 2))) & (pw == pw)
    if slow or scalar:
        for b in range(k1 - k0):
            a = row + b
            aw, ax = ws[_SMP + a], ws[_SMP + _W + a]
            ay, az = ws[_SMP + 2 * _W + a], ws[_SMP + 3 * _W + a]
            bw, bx = ws[_SMP + a + 1], ws[_SMP + _W + a + 1]
            by, bz = ws[_SMP + 2 * _W + a + 1], ws[_SMP + 3 * _W + a + 1]
            if not scalar:
                # (the vector loop's test, on the same values)
                pw, px, py, pz = _qmul_plain(aw, -ax, -ay, -az, bw, bx, by, bz)
                b2 = px * px + py * py + pz * pz
                if (pw > 0.0) & (b2 < (SERIES_RATIO * pw) ** 2) or pw != pw:
                    continue
            v = _log_vec(aw, ax, ay, az, bw, bx, by, bz)
            ws[_LOG + a] = v[0]
            ws[_LOG + _W + a] = v[1]
            ws[_LOG + 2 * _W + a] = v[2]


@helper(inline=True)
def _exp_vec_series(ux, uy, uz, u2):
    """:func:`_exp_vec`'s branch for u² < SERIES_ANGLE²."""
    c = cos_small(u2)
    s = sinc_small(u2)
    return c, s * ux, s * uy, s * uz


@helper(options=_VECTOR)
def _controls(ws, r0, count):
    """End sample, control points and missing-sample count of the segments
    at slots r0..r0+count-1, all with 1 <= i <= n-3 (as
    :func:`_controls_exact`); returns how many need that function (a
    control point's angle beyond the series) and marks them in _REDO."""
    ws = ws[min(max(r0, 0), 1) :]  # (r0 is 0 or 1; see _samples)
    slow = 0
    for r in range(min(count, _SPAN)):
        c = r + 1  # sample row of i
        # the segment's own samples i and i+1; a missing outer neighbour
        # (i-1 or i+2) sends it to _controls_exact for the end rule
        nan = ws[_SMP + 5 * _W + c] + ws[_SMP + 5 * _W + c + 1]
        edge = ws[_SMP + 5 * _W + c - 1] + ws[_SMP + 5 * _W + c + 2]
        ws[_CTL + 15 * _W + r] = nan
        rw, rx = ws[_SMP + c], ws[_SMP + _W + c]
        ry, rz = ws[_SMP + 2 * _W + c], ws[_SMP + 3 * _W + c]
        lr = ws[_SMP + 4 * _W + c]
        nw, nx = ws[_SMP + c + 1], ws[_SMP + _W + c + 1]
        ny, nz = ws[_SMP + 2 * _W + c + 1], ws[_SMP + 3 * _W + c + 1]
        ln_ = ws[_SMP + 4 * _W + c + 1]
        ws[_CTL + r] = nw
        ws[_CTL + _W + r] = nx
        ws[_CTL + 2 * _W + r] = ny
        ws[_CTL + 3 * _W + r] = nz
        ws[_CTL + 12 * _W + r] = ln_
        ratio = ws[_LOG + 3 * _W + c] * ws[_LOG + 4 * _W + c - 1]
        ux = (-ws[_LOG + c] + ws[_LOG + c - 1] * ratio) * 0.25
        uy = (-ws[_LOG + _W + c] + ws[_LOG + _W + c - 1] * ratio) * 0.25
        uz = (-ws[_LOG + 2 * _W + c] + ws[_LOG + 2 * _W + c - 1] * ratio) * 0.25
        u2a = ux * ux + uy * uy + uz * uz
        ew, ex, ey, ez = _exp_vec_series(ux, uy, uz, u2a)
        aw, ax, ay, az = _qmul_plain(rw, rx, ry, rz, ew, ex, ey, ez)
        la = lr + (-(ln_ - lr) + (lr - ws[_SMP + 4 * _W + c - 1]) * ratio) * 0.25
        ws[_CTL + 4 * _W + r] = aw
        ws[_CTL + 5 * _W + r] = ax
        ws[_CTL + 6 * _W + r] = ay
        ws[_CTL + 7 * _W + r] = az
        ws[_CTL + 13 * _W + r] = la
        ratio = ws[_LOG + 3 * _W + c] * ws[_LOG + 4 * _W + c + 1]
        ux = (ws[_LOG + c + 1] * ratio - ws[_LOG + c]) * -0.25
        uy = (ws[_LOG + _W + c + 1] * ratio - ws[_LOG + _W + c]) * -0.25
        uz = (ws[_LOG + 2 * _W + c + 1] * ratio - ws[_LOG + 2 * _W + c]) * -0.25
        u2b = ux * ux + uy * uy + uz * uz
        ew, ex, ey, ez = _exp_vec_series(ux, uy, uz, u2b)
        bw, bx, by, bz = _qmul_plain(nw, nx, ny, nz, ew, ex, ey, ez)
        lb = ln_ + ((ws[_SMP + 4 * _W + c + 2] - ln_) * ratio - (ln_ - lr)) * -0.25
        ws[_CTL + 8 * _W + r] = bw
        ws[_CTL + 9 * _W + r] = bx
        ws[_CTL + 10 * _W + r] = by
        ws[_CTL + 11 * _W + r] = bz
        ws[_CTL + 14 * _W + r] = lb
        limit = SERIES_ANGLE * SERIES_ANGLE
        redo = (nan == 0.0) & ((edge != 0.0) | (not ((u2a < limit) & (u2b < limit))))
        ws[_REDO + r] = 1.0 if redo else 0.0
        slow += redo
    return slow


@helper(inline=True)
def _controls_exact(ws, n, i, r, c):
    """End sample r[i+1] (the virtual one past the last), control points
    A[i] and B[i], their ln scales and the number of missing samples among
    those the segment cannot do without, of segment i (slot r, sample i in
    row c).

    A segment needs its two samples (the last one, which extrapolates, the
    sample before it instead of the next). A control point whose outer
    neighbour (i-1 for A, i+2 for B) is missing takes the end rule, as at
    the ends of the series: each run between missing samples is a series
    of its own (``quaternion.squad_coefficients``)."""
    nan = ws[_SMP + 5 * _W + c]
    if i + 1 <= n - 1:
        nan += ws[_SMP + 5 * _W + c + 1]
    else:
        nan += ws[_SMP + 5 * _W + c - 1]  # the virtual sample reads i-1
    ws[_CTL + 15 * _W + r] = nan
    if nan > 0.0:
        return
    before = i >= 1 and ws[_SMP + 5 * _W + c - 1] == 0.0
    after = i + 2 <= n - 1 and ws[_SMP + 5 * _W + c + 2] == 0.0
    rw, rx = ws[_SMP + c], ws[_SMP + _W + c]
    ry, rz = ws[_SMP + 2 * _W + c], ws[_SMP + 3 * _W + c]
    lr = ws[_SMP + 4 * _W + c]
    if i < n - 1:
        nw, nx = ws[_SMP + c + 1], ws[_SMP + _W + c + 1]
        ny, nz = ws[_SMP + 2 * _W + c + 1], ws[_SMP + 3 * _W + c + 1]
        ln_ = ws[_SMP + 4 * _W + c + 1]
    else:
        # r[n-1] r[n-2]⁻¹ r[n-1], of scale |r[n-1]|² / |r[n-2]|
        pw, px, py, pz = _qmul1(
            rw, rx, ry, rz, ws[_SMP + c - 1], -ws[_SMP + _W + c - 1],
            -ws[_SMP + 2 * _W + c - 1], -ws[_SMP + 3 * _W + c - 1],
        )  # fmt: skip
        nw, nx, ny, nz = _qmul1(pw, px, py, pz, rw, rx, ry, rz)
        ln_ = 2.0 * lr - ws[_SMP + 4 * _W + c - 1]
    ws[_CTL + r] = nw
    ws[_CTL + _W + r] = nx
    ws[_CTL + 2 * _W + r] = ny
    ws[_CTL + 3 * _W + r] = nz
    ws[_CTL + 12 * _W + r] = ln_
    # A[i] = r[i] exp((-L[i] + L[i-1] (t[i+1]-t[i]) / (t[i]-t[i-1])) / 4)
    if before and i <= n - 2:
        ratio = ws[_LOG + 3 * _W + c] * ws[_LOG + 4 * _W + c - 1]
        aw, ax, ay, az = _control_point(
            rw, rx, ry, rz,
            (-ws[_LOG + c] + ws[_LOG + c - 1] * ratio) * 0.25,
            (-ws[_LOG + _W + c] + ws[_LOG + _W + c - 1] * ratio) * 0.25,
            (-ws[_LOG + 2 * _W + c] + ws[_LOG + 2 * _W + c - 1] * ratio) * 0.25,
        )  # fmt: skip
        la = lr + (-(ln_ - lr) + (lr - ws[_SMP + 4 * _W + c - 1]) * ratio) * 0.25
    else:
        aw, ax, ay, az, la = rw, rx, ry, rz, lr
    ws[_CTL + 4 * _W + r] = aw
    ws[_CTL + 5 * _W + r] = ax
    ws[_CTL + 6 * _W + r] = ay
    ws[_CTL + 7 * _W + r] = az
    ws[_CTL + 13 * _W + r] = la
    # B[i] = r[i+1] exp((L[i+1] (t[i+1]-t[i]) / (t[i+2]-t[i+1]) - L[i]) / -4)
    if after:
        ratio = ws[_LOG + 3 * _W + c] * ws[_LOG + 4 * _W + c + 1]
        bw, bx, by, bz = _control_point(
            nw, nx, ny, nz,
            (ws[_LOG + c + 1] * ratio - ws[_LOG + c]) * -0.25,
            (ws[_LOG + _W + c + 1] * ratio - ws[_LOG + _W + c]) * -0.25,
            (ws[_LOG + 2 * _W + c + 1] * ratio - ws[_LOG + 2 * _W + c]) * -0.25,
        )  # fmt: skip
        lb = ln_ + ((ws[_SMP + 4 * _W + c + 2] - ln_) * ratio - (ln_ - lr)) * -0.25
    else:
        bw, bx, by, bz, lb = nw, nx, ny, nz, ln_
    ws[_CTL + 8 * _W + r] = bw
    ws[_CTL + 9 * _W + r] = bx
    ws[_CTL + 10 * _W + r] = by
    ws[_CTL + 11 * _W + r] = bz
    ws[_CTL + 14 * _W + r] = lb


@helper(options=_VECTOR)
def _records(ws, n, s0, count):
    """Records of the segments at slots 0..count-1 (segment s0 + r) from
    their samples, logs and control points, as :func:`_records_exact` where
    both arcs are short (the arc r[i] -> r[i+1] then is r[i] exp(τ L[i]));
    marks the others in _REDO (those whose state would be 1) and returns
    how many it marked, with the earlier marks of :func:`_controls`."""
    slow = 0
    for r in range(min(count, _SPAN)):
        c = r + 1
        nan = ws[_CTL + 15 * _W + r]
        rw, rx = ws[_SMP + c], ws[_SMP + _W + c]
        ry, rz = ws[_SMP + 2 * _W + c], ws[_SMP + 3 * _W + c]
        lr = ws[_SMP + 4 * _W + c]
        nw, nx = ws[_CTL + r], ws[_CTL + _W + r]
        ny, nz = ws[_CTL + 2 * _W + r], ws[_CTL + 3 * _W + r]
        ln_ = ws[_CTL + 12 * _W + r]
        f1 = _decide(rw * nw + rx * nx + ry * ny + rz * nz, _flip_bound(lr, ln_))
        ws[_REC + r] = rw
        ws[_REC + _W + r] = rx
        ws[_REC + 2 * _W + r] = ry
        ws[_REC + 3 * _W + r] = rz
        lx, ly, lz = ws[_LOG + c], ws[_LOG + _W + c], ws[_LOG + 2 * _W + c]
        ow, ox, oy, oz = _qmul_plain(rw, rx, ry, rz, 0.0, lx, ly, lz)
        theta2 = lx * lx + ly * ly + lz * lz
        ws[_REC + 4 * _W + r] = ow
        ws[_REC + 5 * _W + r] = ox
        ws[_REC + 6 * _W + r] = oy
        ws[_REC + 7 * _W + r] = oz
        ws[_REC + 8 * _W + r] = theta2
        ws[_REC + 9 * _W + r] = math.sqrt(theta2)
        ws[_REC + 10 * _W + r] = 1.0
        ws[_REC + 22 * _W + r] = lr
        ws[_REC + 23 * _W + r] = ln_
        aw, ax = ws[_CTL + 4 * _W + r], ws[_CTL + 5 * _W + r]
        ay, az = ws[_CTL + 6 * _W + r], ws[_CTL + 7 * _W + r]
        la = ws[_CTL + 13 * _W + r]
        bw, bx = ws[_CTL + 8 * _W + r], ws[_CTL + 9 * _W + r]
        by, bz = ws[_CTL + 10 * _W + r], ws[_CTL + 11 * _W + r]
        lb = ws[_CTL + 14 * _W + r]
        f2 = _decide(aw * bw + ax * bx + ay * by + az * bz, _flip_bound(la, lb))
        bw, bx, by, bz = f2 * bw, f2 * bx, f2 * by, f2 * bz
        # _great_circle's series branch
        d = aw * bw + ax * bx + ay * by + az * bz
        ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
        o2 = ow * ow + ox * ox + oy * oy + oz * oz
        g = atan_over_x_small(o2 / (d * d)) / d
        theta2 = o2 * g * g
        ws[_REC + 11 * _W + r] = aw
        ws[_REC + 12 * _W + r] = ax
        ws[_REC + 13 * _W + r] = ay
        ws[_REC + 14 * _W + r] = az
        ws[_REC + 15 * _W + r] = ow
        ws[_REC + 16 * _W + r] = ox
        ws[_REC + 17 * _W + r] = oy
        ws[_REC + 18 * _W + r] = oz
        ws[_REC + 19 * _W + r] = theta2
        # (θ² >= 0: abs lets LLVM use the sqrt instruction, not libm's call)
        ws[_REC + 20 * _W + r] = math.sqrt(abs(theta2))
        ws[_REC + 21 * _W + r] = g
        ws[_REC + 24 * _W + r] = la
        ws[_REC + 25 * _W + r] = lb
        ws[_REC + 26 * _W + r] = _flip_bound(
            max(abs(lr), abs(ln_)), max(abs(la), abs(lb))
        )
        wide1 = max(abs(lr), abs(ln_)) > _LOG_SCALE_LIMIT
        wide2 = max(abs(la), abs(lb)) > _LOG_SCALE_LIMIT
        fast = (f1 != 0.0) & (not wide1) & (f2 != 0.0) & (not wide2)
        state = -1.0 if nan > 0.0 else (1.0 if fast else 0.0)
        ws[_REC + 28 * _W + r] = state
        short = (d > 0.0) & (o2 < (SERIES_RATIO * d) ** 2)
        redo = (state > 0.0) & ((f1 != 1.0) | (s0 + r >= n - 1) | (not short))
        redo |= ws[_REDO + r] != 0.0
        ws[_REDO + r] = 1.0 if redo else 0.0
        slow += redo
    return slow


@helper(inline=True)
def _records_exact(ws, n, i, r, c):
    """The record of segment i (slot r, sample i in row c), see _prepare."""
    if ws[_CTL + 15 * _W + r] > 0.0:
        ws[_REC + 28 * _W + r] = -1.0
        return
    rw, rx = ws[_SMP + c], ws[_SMP + _W + c]
    ry, rz = ws[_SMP + 2 * _W + c], ws[_SMP + 3 * _W + c]
    lr = ws[_SMP + 4 * _W + c]
    nw, nx = ws[_CTL + r], ws[_CTL + _W + r]
    ny, nz = ws[_CTL + 2 * _W + r], ws[_CTL + 3 * _W + r]
    ln_ = ws[_CTL + 12 * _W + r]
    # the "shorter way round", decided as for the scaled values
    f = _decide(rw * nw + rx * nx + ry * ny + rz * nz, _flip_bound(lr, ln_))
    ws[_REC + r] = rw
    ws[_REC + _W + r] = rx
    ws[_REC + 2 * _W + r] = ry
    ws[_REC + 3 * _W + r] = rz
    if f == 1.0 and i < n - 1:
        # the arc towards r[i+1] is r[i] exp(τ L[i]): o = r[i] (0, L[i])
        # has length θ, so g = 1 (no great circle to work out)
        lx, ly, lz = ws[_LOG + c], ws[_LOG + _W + c], ws[_LOG + 2 * _W + c]
        ow, ox, oy, oz = _qmul1(rw, rx, ry, rz, 0.0, lx, ly, lz)
        theta2 = lx * lx + ly * ly + lz * lz
        arc = (ow, ox, oy, oz, theta2, math.sqrt(theta2), 1.0)
    else:
        arc = _great_circle(rw, rx, ry, rz, f * nw, f * nx, f * ny, f * nz)
    for k in range(7):
        ws[_REC + (4 + k) * _W + r] = arc[k]
    ws[_REC + 22 * _W + r] = lr
    ws[_REC + 23 * _W + r] = ln_
    fast = f != 0.0 and not max(abs(lr), abs(ln_)) > _LOG_SCALE_LIMIT
    aw, ax = ws[_CTL + 4 * _W + r], ws[_CTL + 5 * _W + r]
    ay, az = ws[_CTL + 6 * _W + r], ws[_CTL + 7 * _W + r]
    la = ws[_CTL + 13 * _W + r]
    bw, bx = ws[_CTL + 8 * _W + r], ws[_CTL + 9 * _W + r]
    by, bz = ws[_CTL + 10 * _W + r], ws[_CTL + 11 * _W + r]
    lb = ws[_CTL + 14 * _W + r]
    f = _decide(aw * bw + ax * bx + ay * by + az * bz, _flip_bound(la, lb))
    arc = _great_circle(aw, ax, ay, az, f * bw, f * bx, f * by, f * bz)
    ws[_REC + 11 * _W + r] = aw
    ws[_REC + 12 * _W + r] = ax
    ws[_REC + 13 * _W + r] = ay
    ws[_REC + 14 * _W + r] = az
    for k in range(7):
        ws[_REC + (15 + k) * _W + r] = arc[k]
    ws[_REC + 24 * _W + r] = la
    ws[_REC + 25 * _W + r] = lb
    # the outer slerp's scales lie between e^lr and e^ln_, and between
    # e^la and e^lb
    ws[_REC + 26 * _W + r] = _flip_bound(max(abs(lr), abs(ln_)), max(abs(la), abs(lb)))
    fast = fast and f != 0.0 and not max(abs(la), abs(lb)) > _LOG_SCALE_LIMIT
    ws[_REC + 28 * _W + r] = 1.0 if fast else 0.0


@helper(inline=True)
def _prepare(qf, sign, t_in, n, s0, s1, ws):
    """Set up segments s0..s1 of the squad spline, into slots 0..s1-s0.

    The record of a segment (quantity k of slot r at ``_REC + k * _W + r``):
    0:11 the arc r[i] -> r[i+1] (r[i], then o, θ², θ, g of
    :func:`_great_circle`); 11:22 the arc A[i] -> B[i] (unit parts; the
    last segment continues to the virtual sample r[n-1] r[n-2]⁻¹ r[n-1]);
    22:26 ln of the scales of r[i], r[i+1], A[i], B[i]; 26 the bound of
    the outer slerp's direction decision; 28: 1 if the fast route applies,
    0 for the exact route, -1 if the segment touches a missing sample (NaN).

    Vector loops over the samples, the steps between them and the segments
    compute the common case (scales near 1, short arcs) and mark what they
    do not cover; the marked segments, and those at the ends of the series
    (no sample before, or fewer than two after), are then set up one by one
    (:func:`_controls_exact`, :func:`_records_exact`).
    """
    k0 = max(s0 - 1, 0)
    k1 = min(s1 + 2, n - 1)
    a0 = k0 - s0 + 1
    _samples(qf, sign, ws, k0, k1, a0, False)
    _logs(t_in, ws, k0, k1, a0, False)
    # the control points: the segments with two samples on either side in
    # a vector loop, the others (at the ends of the series) one by one
    for r in range(s1 - s0 + 1):
        ws[_REDO + r] = 0.0
    ia = max(s0, 1)
    ib = min(s1, n - 3)
    slow = 0
    if ib >= ia:
        slow = _controls(ws, ia - s0, ib - ia + 1)
    for i in range(s0, s1 + 1):
        if i < ia or i > ib:
            _controls_exact(ws, n, i, i - s0, i - s0 + 1)
    if slow:
        for r in range(s1 - s0 + 1):
            if ws[_REDO + r] != 0.0:
                _controls_exact(ws, n, s0 + r, r, r + 1)
    if _records(ws, n, s0, s1 - s0 + 1):
        for r in range(s1 - s0 + 1):
            if ws[_REDO + r] != 0.0:
                _records_exact(ws, n, s0 + r, r, r + 1)
