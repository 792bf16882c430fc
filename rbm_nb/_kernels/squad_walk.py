"""Squad interpolation of a stored rotation series in one pass: numba, unchecked.

:func:`squad_walk` gives what ``unflip`` → ``squad`` → ``stored_signs`` give
together (``rbm_nb.quaternions.qinterp`` on one series), without their
temporaries: no sign-corrected copy of the input (only its signs), no
coefficient tables over every sample. The output times are walked in blocks
of :data:`_BLOCK` rows; the squad segments a block falls in are set up once,
from the samples around them, in scratch space of the size of a block
(every segment from the block's first to its last when they are few, else
only the segments used), and then serve every output time inside them. The
stages are short loops over independent segments or rows, so that the
processor overlaps their long dependency chains.

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

import numpy as np
from numba import prange

from .._config import KERNEL, PARALLEL_KERNEL
from ._jit import F1, F2, F, helper, kernel
from .quaternion import (
    _qexp1,
    _qinv1,
    _qlog1,
    _qmul1,
    _qslerp1,
    _qslerp_unit1,
    _sincos,
)
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    TINY_SQUARE,
    atan_over_x_small,
    cos_small,
    sinc_small,
)

__all__ = [
    "squad_walk",
    "squad_walk_parallel",
    "unflip_signs",
    "squad_input_fault",
]

# fused multiply-add in the series (fastmath "contract" only: results move by
# an ulp at most, far inside the 1e-12 the tests hold them to)
_SERIAL = dataclasses.replace(KERNEL, fastmath=frozenset({"contract"}))
_PARALLEL = dataclasses.replace(PARALLEL_KERNEL, fastmath=frozenset({"contract"}))

# Scales |q| whose log is beyond this take the exact route (the bounds used
# to decide a slerp's direction assume scales near 1).
_LOG_SCALE_LIMIT = 0.05
# Margin around a slerp's direction decision within which the exact route
# decides instead (the scaled decision is right to ~1e-15).
_DECISION_MARGIN = 1e-9
# Below this, exp and log1p are evaluated by their Taylor series.
_SMALL = 1e-3

# a segment's record (see _setup)
_N_REC = 29
# output rows per block, and the most segments a block sets up at once
_BLOCK = 128
_SPAN = 2 * _BLOCK
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


@helper(inline=True)
def _exp_small(x):
    """exp(x), by its series near 0 (the scales of near-unit quaternions)."""
    if abs(x) < TINY_SQUARE:
        return 1.0 + x * (1.0 + x * 0.5 * (1.0 + x / 3.0))  # next term < 4.2e-18
    if abs(x) < _SMALL:
        return 1.0 + x * (
            1.0
            + x
            * 0.5
            * (1.0 + x / 3.0 * (1.0 + x * 0.25 * (1.0 + x * 0.2 * (1.0 + x / 6.0))))
        )
    return math.exp(x)


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
def _along(aw, ax, ay, az, ow, ox, oy, oz, theta2, theta, g, tau):
    """The point at τ of the arc (a, o, θ², θ, g) of :func:`_great_circle`."""
    y2 = tau * tau * theta2
    if y2 < SERIES_ANGLE * SERIES_ANGLE:
        c = cos_small(y2)
        k = sinc_small(y2) * tau * g
    else:
        s, c = _sincos(tau * theta)
        k = s * g / theta
    return c * aw + k * ow, c * ax + k * ox, c * ay + k * oy, c * az + k * oz


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


@helper(inline=True)
def _prepare(q, sign, t_in, s0, s1, smp, logs, ctl, rec, r0):
    """Set up segments s0..s1 of the squad spline in rec[r0..r0+s1-s0].

    rec[r, 0:11]: the arc r[i] -> r[i+1] (r[i], then o, θ², θ, g of
    :func:`_great_circle`); rec[r, 11:22]: the arc A[i] -> B[i] (unit
    parts; the last segment continues to the virtual sample
    r[n-1] r[n-2]⁻¹ r[n-1]); rec[r, 22:26]: ln of the scales of r[i],
    r[i+1], A[i], B[i]; rec[r, 26]: the bound of the outer slerp's
    direction decision; rec[r, 28]: 1 if the fast route applies, 0 for the
    exact route, -1 if the segment touches a missing sample (NaN).

    Each stage is a loop over independent items with a short body, so that
    the processor overlaps their long dependency chains; no helper in the
    loops takes an array (each would cost atomic reference counting per
    call). Scratch: ``smp`` (samples: unit parts, ln scale, NaN), ``logs``
    (log r[k]⁻¹ r[k+1], vector part; t[k+1] - t[k] and its inverse), ``ctl`` (end sample and control
    points: r[i+1], A[i], B[i], their ln scales, NaN count).
    """
    n = q.shape[0]
    k0 = max(s0 - 1, 0)
    k1 = min(s1 + 2, n - 1)
    for k in range(k0, k1 + 1):
        s = sign[k]
        w, x, y, z, lam, bad = _unit(s * q[k, 0], s * q[k, 1], s * q[k, 2], s * q[k, 3])
        a = k - k0
        smp[a, 0] = w
        smp[a, 1] = x
        smp[a, 2] = y
        smp[a, 3] = z
        smp[a, 4] = lam
        smp[a, 5] = 1.0 if bad else 0.0
    for a in range(k1 - k0):
        v = _log_vec(
            smp[a, 0], smp[a, 1], smp[a, 2], smp[a, 3],
            smp[a + 1, 0], smp[a + 1, 1], smp[a + 1, 2], smp[a + 1, 3],
        )  # fmt: skip
        logs[a, 0] = v[0]
        logs[a, 1] = v[1]
        logs[a, 2] = v[2]
        # the sampling interval and its inverse, for the ratios below
        dt = t_in[k0 + a + 1] - t_in[k0 + a]
        logs[a, 3] = dt
        logs[a, 4] = 1.0 / dt
    for i in range(s0, s1 + 1):
        r = r0 + i - s0
        c = i - k0  # row of sample i
        # samples i-1..i+2 (those that exist) all present?
        nan = smp[c, 5]
        if i >= 1:
            nan += smp[c - 1, 5]
        if i + 1 <= n - 1:
            nan += smp[c + 1, 5]
        if i + 2 <= n - 1:
            nan += smp[c + 2, 5]
        ctl[r, 15] = nan
        if nan > 0.0:
            continue
        lr = smp[c, 4]
        if i < n - 1:
            nw, nx, ny, nz = smp[c + 1, 0], smp[c + 1, 1], smp[c + 1, 2], smp[c + 1, 3]
            ln_ = smp[c + 1, 4]
        else:
            # r[n-1] r[n-2]⁻¹ r[n-1], of scale |r[n-1]|² / |r[n-2]|
            pw, px, py, pz = _qmul1(
                smp[c, 0], smp[c, 1], smp[c, 2], smp[c, 3],
                smp[c - 1, 0], -smp[c - 1, 1], -smp[c - 1, 2], -smp[c - 1, 3],
            )  # fmt: skip
            nw, nx, ny, nz = _qmul1(
                pw, px, py, pz, smp[c, 0], smp[c, 1], smp[c, 2], smp[c, 3]
            )
            ln_ = 2.0 * lr - smp[c - 1, 4]
        ctl[r, 0] = nw
        ctl[r, 1] = nx
        ctl[r, 2] = ny
        ctl[r, 3] = nz
        ctl[r, 12] = ln_
        # A[i] = r[i] exp((-L[i] + L[i-1] (t[i+1]-t[i]) / (t[i]-t[i-1])) / 4)
        if 1 <= i <= n - 2:
            ratio = logs[c, 3] * logs[c - 1, 4]  # (t[i+1]-t[i]) / (t[i]-t[i-1])
            aw, ax, ay, az = _control_point(
                smp[c, 0], smp[c, 1], smp[c, 2], smp[c, 3],
                (-logs[c, 0] + logs[c - 1, 0] * ratio) * 0.25,
                (-logs[c, 1] + logs[c - 1, 1] * ratio) * 0.25,
                (-logs[c, 2] + logs[c - 1, 2] * ratio) * 0.25,
            )  # fmt: skip
            la = lr + (-(ln_ - lr) + (lr - smp[c - 1, 4]) * ratio) * 0.25
        else:
            aw, ax, ay, az, la = smp[c, 0], smp[c, 1], smp[c, 2], smp[c, 3], lr
        ctl[r, 4] = aw
        ctl[r, 5] = ax
        ctl[r, 6] = ay
        ctl[r, 7] = az
        ctl[r, 13] = la
        # B[i] = r[i+1] exp((L[i+1] (t[i+1]-t[i]) / (t[i+2]-t[i+1]) - L[i]) / -4)
        if i <= n - 3:
            ratio = logs[c, 3] * logs[c + 1, 4]  # (t[i+1]-t[i]) / (t[i+2]-t[i+1])
            bw, bx, by, bz = _control_point(
                nw, nx, ny, nz,
                (logs[c + 1, 0] * ratio - logs[c, 0]) * -0.25,
                (logs[c + 1, 1] * ratio - logs[c, 1]) * -0.25,
                (logs[c + 1, 2] * ratio - logs[c, 2]) * -0.25,
            )  # fmt: skip
            lb = ln_ + ((smp[c + 2, 4] - ln_) * ratio - (ln_ - lr)) * -0.25
        else:
            bw, bx, by, bz, lb = nw, nx, ny, nz, ln_
        ctl[r, 8] = bw
        ctl[r, 9] = bx
        ctl[r, 10] = by
        ctl[r, 11] = bz
        ctl[r, 14] = lb
    for i in range(s0, s1 + 1):
        r = r0 + i - s0
        if ctl[r, 15] > 0.0:
            rec[r, 28] = -1.0
            continue
        c = i - k0
        rw, rx, ry, rz, lr = smp[c, 0], smp[c, 1], smp[c, 2], smp[c, 3], smp[c, 4]
        nw, nx, ny, nz, ln_ = ctl[r, 0], ctl[r, 1], ctl[r, 2], ctl[r, 3], ctl[r, 12]
        # the "shorter way round", decided as for the scaled values
        f = _decide(rw * nw + rx * nx + ry * ny + rz * nz, _flip_bound(lr, ln_))
        rec[r, 0] = rw
        rec[r, 1] = rx
        rec[r, 2] = ry
        rec[r, 3] = rz
        if f == 1.0 and i < n - 1:
            # the arc towards r[i+1] is r[i] exp(τ L[i]): o = r[i] (0, L[i])
            # has length θ, so g = 1 (no great circle to work out)
            lx, ly, lz = logs[c, 0], logs[c, 1], logs[c, 2]
            ow, ox, oy, oz = _qmul1(rw, rx, ry, rz, 0.0, lx, ly, lz)
            theta2 = lx * lx + ly * ly + lz * lz
            arc = (ow, ox, oy, oz, theta2, math.sqrt(theta2), 1.0)
        else:
            arc = _great_circle(rw, rx, ry, rz, f * nw, f * nx, f * ny, f * nz)
        for k in range(7):
            rec[r, 4 + k] = arc[k]
        rec[r, 22] = lr
        rec[r, 23] = ln_
        rec[r, 28] = (
            0.0 if f == 0.0 or max(abs(lr), abs(ln_)) > _LOG_SCALE_LIMIT else 1.0
        )
    for i in range(s0, s1 + 1):
        r = r0 + i - s0
        if rec[r, 28] < 0.0:
            continue
        aw, ax, ay, az, la = ctl[r, 4], ctl[r, 5], ctl[r, 6], ctl[r, 7], ctl[r, 13]
        bw, bx, by, bz, lb = ctl[r, 8], ctl[r, 9], ctl[r, 10], ctl[r, 11], ctl[r, 14]
        f = _decide(aw * bw + ax * bx + ay * by + az * bz, _flip_bound(la, lb))
        arc = _great_circle(aw, ax, ay, az, f * bw, f * bx, f * by, f * bz)
        rec[r, 11] = aw
        rec[r, 12] = ax
        rec[r, 13] = ay
        rec[r, 14] = az
        for k in range(7):
            rec[r, 15 + k] = arc[k]
        rec[r, 24] = la
        rec[r, 25] = lb
        # the outer slerp's scales lie between e^lr and e^ln_, and between
        # e^la and e^lb
        rec[r, 26] = _flip_bound(
            max(abs(rec[r, 22]), abs(rec[r, 23])), max(abs(la), abs(lb))
        )
        if f == 0.0 or max(abs(la), abs(lb)) > _LOG_SCALE_LIMIT:
            rec[r, 28] = 0.0


@helper
def _exact_row(q, sign, t_in, i, tau):
    """Segment i at τ by the arithmetic of ``squad_coefficients`` and the
    general branch of ``squad_evaluate``, on the sign-continuous samples."""
    n = q.shape[0]
    lo = max(i - 1, 0)
    hi = min(i + 2, n - 1)
    r = np.empty((4, 4))
    for k in range(lo, hi + 1):
        for j in range(4):
            r[k - lo, j] = sign[k] * q[k, j]
    logs = np.zeros((3, 4))
    for k in range(lo, hi):
        iw, ix, iy, iz = _qinv1(r[k - lo, 0], r[k - lo, 1], r[k - lo, 2], r[k - lo, 3])
        nw, nx, ny, nz = _qmul1(
            iw,
            ix,
            iy,
            iz,
            r[k + 1 - lo, 0],
            r[k + 1 - lo, 1],
            r[k + 1 - lo, 2],
            r[k + 1 - lo, 3],
        )
        lw, lx, ly, lz = _qlog1(nw, nx, ny, nz)
        logs[k - lo, 0] = lw
        logs[k - lo, 1] = lx
        logs[k - lo, 2] = ly
        logs[k - lo, 3] = lz
    c = i - lo
    rw, rx, ry, rz = r[c, 0], r[c, 1], r[c, 2], r[c, 3]
    if i < n - 1:
        nw, nx, ny, nz = r[c + 1, 0], r[c + 1, 1], r[c + 1, 2], r[c + 1, 3]
    else:
        iw, ix, iy, iz = _qinv1(r[c - 1, 0], r[c - 1, 1], r[c - 1, 2], r[c - 1, 3])
        pw, px, py, pz = _qmul1(rw, rx, ry, rz, iw, ix, iy, iz)
        nw, nx, ny, nz = _qmul1(pw, px, py, pz, rw, rx, ry, rz)
    if 1 <= i <= n - 2:
        ratio = (t_in[i + 1] - t_in[i]) / (t_in[i] - t_in[i - 1])
        ew, ex, ey, ez = _qexp1(
            (-logs[c, 0] + logs[c - 1, 0] * ratio) * 0.25,
            (-logs[c, 1] + logs[c - 1, 1] * ratio) * 0.25,
            (-logs[c, 2] + logs[c - 1, 2] * ratio) * 0.25,
            (-logs[c, 3] + logs[c - 1, 3] * ratio) * 0.25,
        )
        aw, ax, ay, az = _qmul1(rw, rx, ry, rz, ew, ex, ey, ez)
    else:
        aw, ax, ay, az = rw, rx, ry, rz
    if i <= n - 3:
        ratio = (t_in[i + 1] - t_in[i]) / (t_in[i + 2] - t_in[i + 1])
        ew, ex, ey, ez = _qexp1(
            (logs[c + 1, 0] * ratio - logs[c, 0]) * -0.25,
            (logs[c + 1, 1] * ratio - logs[c, 1]) * -0.25,
            (logs[c + 1, 2] * ratio - logs[c, 2]) * -0.25,
            (logs[c + 1, 3] * ratio - logs[c, 3]) * -0.25,
        )
        bw, bx, by, bz = _qmul1(nw, nx, ny, nz, ew, ex, ey, ez)
    else:
        bw, bx, by, bz = nw, nx, ny, nz
    s1 = _qslerp1(rw, rx, ry, rz, nw, nx, ny, nz, tau)
    s2 = _qslerp1(aw, ax, ay, az, bw, bx, by, bz, tau)
    return _qslerp_unit1(
        s1[0], s1[1], s1[2], s1[3], s2[0], s2[1], s2[2], s2[3], 2.0 * tau * (1.0 - tau)
    )


@helper(inline=True)
def _outer(aw, ax, ay, az, bw, bx, by, bz, tau):
    """slerp of unit a towards unit b (no direction flip), as _qslerp_unit1."""
    d = aw * bw + ax * bx + ay * by + az * bz
    ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
    o2 = ow * ow + ox * ox + oy * oy + oz * oz
    if d > 0.0 and o2 < (SERIES_RATIO * d) ** 2:
        inv_d = 1.0 / d
        x2 = o2 * inv_d * inv_d
        p = atan_over_x_small(x2)
        y2 = tau * tau * x2 * p * p
        if y2 < SERIES_ANGLE * SERIES_ANGLE:
            c = cos_small(y2)
            k = sinc_small(y2) * tau * p * inv_d
            return c * aw + k * ow, c * ax + k * ox, c * ay + k * oy, c * az + k * oz
    so = math.sqrt(o2)
    if so == 0.0:
        return aw, ax, ay, az
    s, c = _sincos(tau * math.atan2(so, d))
    k = s / so
    return c * aw + k * ow, c * ax + k * ox, c * ay + k * oy, c * az + k * oz


@helper(inline=True)
def _walk(q, sign, t_in, t_out, out, first, last):
    """Rows first..last-1 of :func:`squad_walk` (n >= 2), block by block."""
    n = q.shape[0]
    # scratch for one block of output rows: each row's sample index and
    # segment record, the segments' samples, logs, control points and
    # records (at most _SPAN segments when set up at once), the rows' two
    # inner slerps
    found = np.empty(_BLOCK, dtype=np.int64)
    slot = np.empty(_BLOCK, dtype=np.int64)
    smp = np.empty((_SPAN + 3, 6))
    logs = np.empty((_SPAN + 3, 5))
    ctl = np.empty((_SPAN, 16))
    rec = np.empty((_SPAN, _N_REC))
    inner = np.empty((_BLOCK, 9))
    dt_last = t_in[n - 1] - t_in[n - 2]
    i = -1
    for start in range(first, last, _BLOCK):
        stop = min(start + _BLOCK, last)
        ordered = True
        for j in range(start, stop):
            t = t_out[j]
            # i: the last sample at or before t (-1 before the first),
            # galloping forward from the previous row's (sorted t_out) or
            # by bisection when t went back
            if i >= 0 and t < t_in[i]:
                i = -1
                ordered = False
            step = 1
            lo = i
            hi = i + 1
            while hi < n and t_in[hi] <= t:
                lo = hi
                hi = i + 1 + step
                step *= 2
            if hi > n:
                hi = n
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if t_in[mid] <= t:
                    lo = mid
                else:
                    hi = mid
            i = lo
            found[j - start] = i
        s0 = found[0]
        s1 = found[stop - start - 1]
        if ordered and s0 >= 0 and s1 - s0 < _SPAN:
            # dense: every segment from the first to the last at once
            _prepare(q, sign, t_in, s0, s1, smp, logs, ctl, rec, 0)
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
                    _prepare(q, sign, t_in, seg, seg, smp, logs, ctl, rec, free)
                    loaded = seg
                    free += 1
                slot[j - start] = free - 1
        # first stage: the two inner slerps of each row
        for j in range(start, stop):
            jj = j - start
            i_j = found[jj]
            seg = i_j if i_j >= 0 else n - 1
            r = slot[jj]
            if seg < n - 1:
                dt = t_in[seg + 1] - t_in[seg]
            else:
                dt = (t_in[n - 1] + dt_last) - t_in[n - 1]
            tau = (t_out[j] - t_in[seg]) / dt
            inner[jj, 8] = tau
            if rec[r, 28] > 0.0 and 0.0 <= tau <= 1.0:
                aw, ax, ay, az = _along(
                    rec[r, 0], rec[r, 1], rec[r, 2], rec[r, 3],
                    rec[r, 4], rec[r, 5], rec[r, 6], rec[r, 7],
                    rec[r, 8], rec[r, 9], rec[r, 10], tau,
                )  # fmt: skip
                bw, bx, by, bz = _along(
                    rec[r, 11], rec[r, 12], rec[r, 13], rec[r, 14],
                    rec[r, 15], rec[r, 16], rec[r, 17], rec[r, 18],
                    rec[r, 19], rec[r, 20], rec[r, 21], tau,
                )  # fmt: skip
                inner[jj, 0] = aw
                inner[jj, 1] = ax
                inner[jj, 2] = ay
                inner[jj, 3] = az
                inner[jj, 4] = bw
                inner[jj, 5] = bx
                inner[jj, 6] = by
                inner[jj, 7] = bz
        # second stage: the outer slerp, the scale and the stored sign
        for j in range(start, stop):
            jj = j - start
            i_j = found[jj]
            seg = i_j if i_j >= 0 else n - 1
            r = slot[jj]
            s = sign[min(max(i_j, 0), n - 2)]
            tau = inner[jj, 8]
            state = rec[r, 28]
            if state < 0.0:
                out[j, 0] = out[j, 1] = out[j, 2] = out[j, 3] = np.nan
                continue
            if state > 0.0 and 0.0 <= tau <= 1.0:
                aw, ax, ay, az = inner[jj, 0], inner[jj, 1], inner[jj, 2], inner[jj, 3]
                bw, bx, by, bz = inner[jj, 4], inner[jj, 5], inner[jj, 6], inner[jj, 7]
                flip = _decide(aw * bw + ax * bx + ay * by + az * bz, rec[r, 26])
                if flip != 0.0:
                    h = 2.0 * tau * (1.0 - tau)
                    w, x, y, z = _outer(
                        aw, ax, ay, az, flip * bw, flip * bx, flip * by, flip * bz, h
                    )
                    u = 1.0 - tau
                    scale = _exp_small(
                        (1.0 - h) * (u * rec[r, 22] + tau * rec[r, 23])
                        + h * (u * rec[r, 24] + tau * rec[r, 25])
                    )
                    k = s * scale
                    out[j, 0] = k * w
                    out[j, 1] = k * x
                    out[j, 2] = k * y
                    out[j, 3] = k * z
                    continue
            w, x, y, z = _exact_row(q, sign, t_in, seg, tau)
            out[j, 0] = s * w
            out[j, 1] = s * x
            out[j, 2] = s * y
            out[j, 3] = s * z


@kernel(F2, F1, F1, options=_SERIAL)
def squad_walk(q, t_in, t_out):
    """Squad of the stored series ``q`` at ``t_out``, with the stored signs.

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
    n = q.shape[0]
    m = t_out.shape[0]
    out = np.empty((m, 4))
    if n < 2 or m == 0:
        for j in range(m):
            for k in range(4):
                out[j, k] = q[0, k]
        return out
    sign = unflip_signs(q)
    _walk(q, sign, t_in, t_out, out, 0, m)
    return out


@kernel(F2, F1, F1, options=_PARALLEL)
def squad_walk_parallel(q, t_in, t_out):
    """:func:`squad_walk` with chunks of output rows on numba's threads."""
    n = q.shape[0]
    m = t_out.shape[0]
    out = np.empty((m, 4))
    if n < 2 or m == 0:
        for j in range(m):
            for k in range(4):
                out[j, k] = q[0, k]
        return out
    sign = unflip_signs(q)
    # whole blocks per chunk, many more chunks than threads (numba's thread
    # count is not read here: that would keep the kernel out of the cache)
    chunks = _CHUNKS
    size = ((m + chunks - 1) // chunks + _BLOCK - 1) // _BLOCK * _BLOCK
    for c in prange(chunks):
        _walk(q, sign, t_in, t_out, out, min(c * size, m), min((c + 1) * size, m))
    return out


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
