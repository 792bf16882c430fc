"""The rows of a block of squad_walk's output, from their segments' records.

:mod:`.squad_walk` finds each output row's segment and sets the segments up
(:mod:`.squad_segments`); here each row's record is gathered into the rows'
scratch (:func:`_gather_records`), the rows are evaluated in vector loops
over the common branches (:func:`_rows`: inner slerps, outer slerp, scale),
and the rows those do not cover one by one with every branch
(:func:`_scalar_rows`, :func:`_exact_row`). Both give a row the same bits.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import helper
from .quaternion import _qexp1, _qinv1, _qlog1, _qmul1, _qslerp1, _qslerp_unit1, _sincos
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    TINY_SQUARE,
    atan_over_x_small,
    cos_small,
    sinc_small,
)
from .squad_segments import (
    _BLOCK,
    _N_REC,
    _REC,
    _SERIAL,
    _SMALL,
    _VECTOR,
    _W,
    _decide,
)


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


# The rows' scratch (a second flat array, :data:`_WR` float64, quantity k of
# row b at ``k * _R + b``): each row's segment record (_N_REC quantities),
# its τ, the sign of its stored sample, its two inner slerps (8), and 1.0
# where it takes the scalar route. Together the two take 124,480 bytes,
# below 128 KiB, glibc's default thresholds for mmap and for trimming the heap:
# allocated for every chunk of the parallel twin, they come from the heap
# and cost no page faults (a 400 KB scratch cost 230 more per call when
# big arrays are fresh mmap pages, MALLOC_MMAP_THRESHOLD_=131072).
_R = _BLOCK + 8
_ROW = 0
_TAU = _ROW + _N_REC * _R
_SGN = _TAU + _R
_INN = _SGN + _R
_EXACT = _INN + 8 * _R
_WR = _EXACT + _R


@helper(inline=True)
def _along_series(aw, ax, ay, az, ow, ox, oy, oz, theta2, g, tau):
    """:func:`_along` where τ²θ² < SERIES_ANGLE² (its first branch), and τ²θ²."""
    y2 = tau * tau * theta2
    c = cos_small(y2)
    k = sinc_small(y2) * tau * g
    return c * aw + k * ow, c * ax + k * ox, c * ay + k * oy, c * az + k * oz, y2


@helper(inline=True)
def _outer_series(aw, ax, ay, az, bw, bx, by, bz, tau):
    """:func:`_outer`'s series branch, and whether it applies."""
    d = aw * bw + ax * bx + ay * by + az * bz
    ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
    o2 = ow * ow + ox * ox + oy * oy + oz * oz
    inv_d = 1.0 / d
    x2 = o2 * inv_d * inv_d
    p = atan_over_x_small(x2)
    y2 = tau * tau * x2 * p * p
    c = cos_small(y2)
    k = sinc_small(y2) * tau * p * inv_d
    ok = (d > 0.0) & (o2 < (SERIES_RATIO * d) ** 2) & (y2 < SERIES_ANGLE * SERIES_ANGLE)
    return (
        c * aw + k * ow,
        c * ax + k * ox,
        c * ay + k * oy,
        c * az + k * oz,
        ok,
    )


@helper(inline=True)
def _exp_series(x):
    """:func:`_exp_small` for |x| < _SMALL (its first two branches)."""
    tiny = 1.0 + x * (1.0 + x * 0.5 * (1.0 + x / 3.0))
    small = 1.0 + x * (
        1.0
        + x
        * 0.5
        * (1.0 + x / 3.0 * (1.0 + x * 0.25 * (1.0 + x * 0.2 * (1.0 + x / 6.0))))
    )
    return tiny if abs(x) < TINY_SQUARE else small


@helper(options=_VECTOR)
def _rows(wr, ob, count):
    """The first ``count`` rows of the block, from the row scratch (record,
    τ, sign) into ``ob`` (4 per row, flat), where the fast route's series
    apply: the two inner slerps (:func:`_along`), the outer slerp
    (:func:`_outer`), the scale (:func:`_exp_small`) and the stored sign.
    Marks the other rows in _EXACT (they take the scalar route) and returns
    how many it marked."""
    limit = SERIES_ANGLE * SERIES_ANGLE
    for b in range(min(count, _BLOCK)):
        tau = wr[_TAU + b]
        aw, ax, ay, az, ya = _along_series(
            wr[_ROW + b], wr[_ROW + _R + b], wr[_ROW + 2 * _R + b],
            wr[_ROW + 3 * _R + b], wr[_ROW + 4 * _R + b], wr[_ROW + 5 * _R + b],
            wr[_ROW + 6 * _R + b], wr[_ROW + 7 * _R + b], wr[_ROW + 8 * _R + b],
            wr[_ROW + 10 * _R + b], tau,
        )  # fmt: skip
        bw, bx, by, bz, yb = _along_series(
            wr[_ROW + 11 * _R + b], wr[_ROW + 12 * _R + b], wr[_ROW + 13 * _R + b],
            wr[_ROW + 14 * _R + b], wr[_ROW + 15 * _R + b], wr[_ROW + 16 * _R + b],
            wr[_ROW + 17 * _R + b], wr[_ROW + 18 * _R + b], wr[_ROW + 19 * _R + b],
            wr[_ROW + 21 * _R + b], tau,
        )  # fmt: skip
        wr[_INN + b] = aw
        wr[_INN + _R + b] = ax
        wr[_INN + 2 * _R + b] = ay
        wr[_INN + 3 * _R + b] = az
        wr[_INN + 4 * _R + b] = bw
        wr[_INN + 5 * _R + b] = bx
        wr[_INN + 6 * _R + b] = by
        wr[_INN + 7 * _R + b] = bz
        wr[_EXACT + b] = 0.0 if (ya < limit) & (yb < limit) else 1.0
    exact = 0
    for b in range(min(count, _BLOCK)):
        tau = wr[_TAU + b]
        aw, ax, ay, az = (
            wr[_INN + b],
            wr[_INN + _R + b],
            wr[_INN + 2 * _R + b],
            wr[_INN + 3 * _R + b],
        )
        bw, bx, by, bz = (
            wr[_INN + 4 * _R + b],
            wr[_INN + 5 * _R + b],
            wr[_INN + 6 * _R + b],
            wr[_INN + 7 * _R + b],
        )
        flip = _decide(aw * bw + ax * bx + ay * by + az * bz, wr[_ROW + 26 * _R + b])
        h = 2.0 * tau * (1.0 - tau)
        w, x, y, z, ok = _outer_series(
            aw, ax, ay, az, flip * bw, flip * bx, flip * by, flip * bz, h
        )
        u = 1.0 - tau
        e = (1.0 - h) * (
            u * wr[_ROW + 22 * _R + b] + tau * wr[_ROW + 23 * _R + b]
        ) + h * (u * wr[_ROW + 24 * _R + b] + tau * wr[_ROW + 25 * _R + b])
        k = wr[_SGN + b] * _exp_series(e)
        ob[4 * b] = k * w
        ob[4 * b + 1] = k * x
        ob[4 * b + 2] = k * y
        ob[4 * b + 3] = k * z
        fast = (
            (wr[_ROW + 28 * _R + b] > 0.0)
            & (0.0 <= tau)
            & (tau <= 1.0)
            & (flip != 0.0)
            & ok
            & (abs(e) < _SMALL)
            & (wr[_EXACT + b] == 0.0)
        )
        wr[_EXACT + b] = 0.0 if fast else 1.0
        exact += not fast
    return exact


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
    # (a missing outer neighbour: the end rule, as in _controls_exact)
    if 1 <= i <= n - 2 and not math.isnan(logs[c - 1, 0]):
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
    if i <= n - 3 and not math.isnan(logs[c + 1, 0]):
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


@helper(options=_SERIAL)
def _gather_records(t_in, t_out, sign, n, dt_last, start, stop, found, slot, ws, wr):
    """Each row's τ, stored sign and segment record into the row scratch
    ``wr`` (a scalar loop: the records are gathered by slot)."""
    for jj in range(stop - start):
        j = start + jj
        i_j = found[jj]
        seg = i_j if i_j >= 0 else n - 1
        if seg < n - 1:
            dt = t_in[seg + 1] - t_in[seg]
        else:
            dt = (t_in[n - 1] + dt_last) - t_in[n - 1]
        wr[_TAU + jj] = (t_out[j] - t_in[seg]) / dt
        wr[_SGN + jj] = sign[min(max(i_j, 0), n - 2)]
        # (slots are >= 0: max spares the negative-index wraparound)
        r = max(slot[jj], 0)
        wr[_ROW + 0 * _R + jj] = ws[_REC + 0 * _W + r]
        wr[_ROW + 1 * _R + jj] = ws[_REC + 1 * _W + r]
        wr[_ROW + 2 * _R + jj] = ws[_REC + 2 * _W + r]
        wr[_ROW + 3 * _R + jj] = ws[_REC + 3 * _W + r]
        wr[_ROW + 4 * _R + jj] = ws[_REC + 4 * _W + r]
        wr[_ROW + 5 * _R + jj] = ws[_REC + 5 * _W + r]
        wr[_ROW + 6 * _R + jj] = ws[_REC + 6 * _W + r]
        wr[_ROW + 7 * _R + jj] = ws[_REC + 7 * _W + r]
        wr[_ROW + 8 * _R + jj] = ws[_REC + 8 * _W + r]
        wr[_ROW + 10 * _R + jj] = ws[_REC + 10 * _W + r]
        wr[_ROW + 11 * _R + jj] = ws[_REC + 11 * _W + r]
        wr[_ROW + 12 * _R + jj] = ws[_REC + 12 * _W + r]
        wr[_ROW + 13 * _R + jj] = ws[_REC + 13 * _W + r]
        wr[_ROW + 14 * _R + jj] = ws[_REC + 14 * _W + r]
        wr[_ROW + 15 * _R + jj] = ws[_REC + 15 * _W + r]
        wr[_ROW + 16 * _R + jj] = ws[_REC + 16 * _W + r]
        wr[_ROW + 17 * _R + jj] = ws[_REC + 17 * _W + r]
        wr[_ROW + 18 * _R + jj] = ws[_REC + 18 * _W + r]
        wr[_ROW + 19 * _R + jj] = ws[_REC + 19 * _W + r]
        wr[_ROW + 21 * _R + jj] = ws[_REC + 21 * _W + r]
        wr[_ROW + 22 * _R + jj] = ws[_REC + 22 * _W + r]
        wr[_ROW + 23 * _R + jj] = ws[_REC + 23 * _W + r]
        wr[_ROW + 24 * _R + jj] = ws[_REC + 24 * _W + r]
        wr[_ROW + 25 * _R + jj] = ws[_REC + 25 * _W + r]
        wr[_ROW + 26 * _R + jj] = ws[_REC + 26 * _W + r]
        wr[_ROW + 28 * _R + jj] = ws[_REC + 28 * _W + r]


@helper(options=_SERIAL)
def _scalar_rows(q, sign, t_in, out, n, start, stop, found, slot, ws, wr, scalar):
    """The rows the vector loops did not cover (all of them if ``scalar``),
    one by one: _along, _outer and _exp_small with all their branches, or
    _exact_row (written out here: a helper receiving the arrays would cost
    reference counting per row)."""
    for jj in range(stop - start):
        if not scalar and wr[_EXACT + jj] == 0.0:
            continue
        j = start + jj
        r = slot[jj]
        s = wr[_SGN + jj]
        tau = wr[_TAU + jj]
        state = ws[_REC + 28 * _W + r]
        if state < 0.0:
            # a segment missing one of its samples: nothing, except at
            # its first sample's own time (when that one is present)
            i_j = found[jj]
            if tau == 0.0 and i_j >= 0:
                out[j, 0], out[j, 1] = q[i_j, 0], q[i_j, 1]
                out[j, 2], out[j, 3] = q[i_j, 2], q[i_j, 3]
            else:
                out[j, 0] = out[j, 1] = out[j, 2] = out[j, 3] = np.nan
            continue
        if state > 0.0 and 0.0 <= tau <= 1.0:
            aw, ax, ay, az = _along(
                ws[_REC + r], ws[_REC + _W + r], ws[_REC + 2 * _W + r],
                ws[_REC + 3 * _W + r], ws[_REC + 4 * _W + r],
                ws[_REC + 5 * _W + r], ws[_REC + 6 * _W + r],
                ws[_REC + 7 * _W + r], ws[_REC + 8 * _W + r],
                ws[_REC + 9 * _W + r], ws[_REC + 10 * _W + r], tau,
            )  # fmt: skip
            bw, bx, by, bz = _along(
                ws[_REC + 11 * _W + r], ws[_REC + 12 * _W + r],
                ws[_REC + 13 * _W + r], ws[_REC + 14 * _W + r],
                ws[_REC + 15 * _W + r], ws[_REC + 16 * _W + r],
                ws[_REC + 17 * _W + r], ws[_REC + 18 * _W + r],
                ws[_REC + 19 * _W + r], ws[_REC + 20 * _W + r],
                ws[_REC + 21 * _W + r], tau,
            )  # fmt: skip
            flip = _decide(
                aw * bw + ax * bx + ay * by + az * bz, ws[_REC + 26 * _W + r]
            )
            if flip != 0.0:
                h = 2.0 * tau * (1.0 - tau)
                w, x, y, z = _outer(
                    aw, ax, ay, az, flip * bw, flip * bx, flip * by, flip * bz, h
                )
                u = 1.0 - tau
                scale = _exp_small(
                    (1.0 - h)
                    * (u * ws[_REC + 22 * _W + r] + tau * ws[_REC + 23 * _W + r])
                    + h * (u * ws[_REC + 24 * _W + r] + tau * ws[_REC + 25 * _W + r])
                )
                k = s * scale
                out[j, 0] = k * w
                out[j, 1] = k * x
                out[j, 2] = k * y
                out[j, 3] = k * z
                continue
        i_j = found[jj]
        w, x, y, z = _exact_row(q, sign, t_in, i_j if i_j >= 0 else n - 1, tau)
        out[j, 0] = s * w
        out[j, 1] = s * x
        out[j, 2] = s * y
        out[j, 3] = s * z
