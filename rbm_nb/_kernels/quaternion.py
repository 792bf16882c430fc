"""Quaternion algebra on arrays: numba kernels, unchecked.

Conventions shared by every function here:

* quaternions are float64 arrays of shape (n, 4) in ``w, x, y, z`` order,
  vectors are float64 arrays of shape (n, 3), both C-contiguous;
* where two operands are given, their first dimensions are equal or one of
  them is 1, in which case that row is reused for every output row (the
  broadcast happens in the loop, nothing is materialised);
* nothing is validated: the public modules check shapes and values first.

The scalar helpers (names starting with ``_q``) work on unpacked components
so that the array loops allocate nothing but their output.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import F1, F2, helper, kernel
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    SINCOS_LIMIT,
    atan2,
    atan_over_x,
    cos_series,
    sinc_series,
    sincos,
)
from .search import gallop

# Below this relative size the vector part of a quaternion counts as zero in
# exp/log, as in numpy-quaternion (whose results squad must reproduce).
_EPS = 1e-14
_SQRT2 = 1.414213562373096


# ---------------------------------------------------------------------------
# scalar helpers
# ---------------------------------------------------------------------------


@helper
def _qmul1(aw, ax, ay, az, bw, bx, by, bz):
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


@helper
def _qinv1(w, x, y, z):
    n2 = w * w + x * x + y * y + z * z
    return w / n2, -x / n2, -y / n2, -z / n2


@helper
def _qdiv1(aw, ax, ay, az, bw, bx, by, bz):
    """a * b⁻¹, evaluated in one step like numpy-quaternion's division."""
    n2 = bw * bw + bx * bx + by * by + bz * bz
    return (
        (aw * bw + ax * bx + ay * by + az * bz) / n2,
        (-aw * bx + ax * bw - ay * bz + az * by) / n2,
        (-aw * by + ax * bz + ay * bw - az * bx) / n2,
        (-aw * bz - ax * by + ay * bx + az * bw) / n2,
    )


@helper
def _qexp1(w, x, y, z):
    vnorm = math.sqrt(x * x + y * y + z * z)
    e = math.exp(w)
    if vnorm > _EPS:
        s = math.sin(vnorm) / vnorm
        return e * math.cos(vnorm), e * s * x, e * s * y, e * s * z
    return e, 0.0, 0.0, 0.0


@helper
def _qlog1(w, x, y, z):
    b = math.sqrt(x * x + y * y + z * z)
    if b <= _EPS * abs(w):
        if w < 0.0:
            # a negative real number: one of infinitely many logarithms,
            # the one numpy-quaternion picks (rotation by pi about x)
            if abs(w + 1.0) > _EPS:
                return math.log(-w), math.pi, 0.0, 0.0
            return 0.0, math.pi, 0.0, 0.0
        return math.log(w), 0.0, 0.0, 0.0
    f = math.atan2(b, w) / b
    return math.log(w * w + b * b) / 2.0, f * x, f * y, f * z


@helper
def _qpow1(w, x, y, z, s):
    if w == 0.0 and x == 0.0 and y == 0.0 and z == 0.0:
        if s == 0.0:
            return 1.0, 0.0, 0.0, 0.0
        return 0.0, 0.0, 0.0, 0.0
    lw, lx, ly, lz = _qlog1(w, x, y, z)
    return _qexp1(s * lw, s * lx, s * ly, s * lz)


@helper
def _qslerp1(aw, ax, ay, az, bw, bx, by, bz, tau):
    """Geodesic from a (tau=0) to b (tau=1), taking the shorter way round."""
    dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
    if math.sqrt(dw * dw + dx * dx + dy * dy + dz * dz) > _SQRT2:
        bw, bx, by, bz = -bw, -bx, -by, -bz
    rw, rx, ry, rz = _qdiv1(bw, bx, by, bz, aw, ax, ay, az)
    pw, px, py, pz = _qpow1(rw, rx, ry, rz, tau)
    return _qmul1(pw, px, py, pz, aw, ax, ay, az)


@helper
def _sincos(y):
    """(sin y, cos y): the polynomial within its range, libm beyond it."""
    if abs(y) < SINCOS_LIMIT:
        return sincos(y)
    return math.sin(y), math.cos(y)


@helper
def _geodesic1(aw, ax, ay, az, bw, bx, by, bz):
    """Arc from unit a towards unit b: (θ, u) with b = cos θ a + sin θ u.

    b is negated first if it is farther than √2 from a (the shorter way
    round, as numpy-quaternion's slerp). u is the unit quaternion orthogonal
    to a in the plane of a and b (zero when b == a).
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
    return atan2(so, d), ow * k, ox * k, oy * k, oz * k


@helper
def _is_unit(w, x, y, z):
    return abs(w * w + x * x + y * y + z * z - 1.0) <= 1e-12


@helper
def _qslerp_unit1(aw, ax, ay, az, bw, bx, by, bz, tau):
    """:func:`_qslerp1` for unit quaternions, along the great circle.

    For unit a and b, (b a⁻¹)^τ a is cos(τθ) a + sin(τθ) u with (θ, u) from
    :func:`_geodesic1`: no quaternion products and no exp/log. Other
    quaternions take the general route, so results stay numpy-quaternion's
    to rounding.
    """
    if not (_is_unit(aw, ax, ay, az) and _is_unit(bw, bx, by, bz)):
        return _qslerp1(aw, ax, ay, az, bw, bx, by, bz, tau)
    dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
    if dw * dw + dx * dx + dy * dy + dz * dz > _SQRT2 * _SQRT2:
        bw, bx, by, bz = -bw, -bx, -by, -bz
    d = aw * bw + ax * bx + ay * by + az * bz
    ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
    o2 = ow * ow + ox * ox + oy * oy + oz * oz
    if d > 0.0 and o2 < (SERIES_RATIO * d) ** 2:
        # small arcs (the rule in squad's outer slerp): with x = tan θ and
        # y = τθ, the result is cos(y) a + τ (θ/x) (sin y / y) / d o, and
        # every factor is a short series in x² or y², so neither sqrt nor
        # atan2 is needed
        inv_d = 1.0 / d
        x2 = o2 * inv_d * inv_d
        p = atan_over_x(x2)
        y2 = tau * tau * x2 * p * p
        if y2 < SERIES_ANGLE * SERIES_ANGLE:
            c = cos_series(y2)
            k = sinc_series(y2) * tau * p * inv_d
            return c * aw + k * ow, c * ax + k * ox, c * ay + k * oy, c * az + k * oz
    theta, uw, ux, uy, uz = _geodesic1(aw, ax, ay, az, bw, bx, by, bz)
    s, c = _sincos(tau * theta)
    return c * aw + s * uw, c * ax + s * ux, c * ay + s * uy, c * az + s * uz


def _rotate_one(w, x, y, z, vx, vy, vz):
    """q v q⁻¹ for any non-zero q (dividing by |q|², so the norm of v is kept)."""
    n2 = w * w + x * x + y * y + z * z
    d = x * vx + y * vy + z * vz
    cx = y * vz - z * vy
    cy = z * vx - x * vz
    cz = x * vy - y * vx
    s = w * w - (x * x + y * y + z * z)
    k = 1.0 / n2  # one division instead of three
    d2 = 2.0 * d
    w2 = 2.0 * w
    return (
        (s * vx + d2 * x + w2 * cx) * k,
        (s * vy + d2 * y + w2 * cy) * k,
        (s * vz + d2 * z + w2 * cz) * k,
    )


_rotate1 = helper(_rotate_one)
# The same operations inlined into the caller (numba inlines the IR, so the
# caller's options hold: under error_model="numpy" a zero q gives NaN, and a
# vector kernel may contract): a loop over rows runs ~5x faster than with a
# call per row.
_rotate1_inline = helper(inline=True)(_rotate_one)


@helper
def search_right(t_in, t_out):
    """For each t_out[j], the index i with t_in[i] <= t_out[j] < t_in[i+1].

    -1 before the first sample, n-1 at or after the last (like
    ``np.searchsorted(t_in, t_out, "right") - 1``). Each search gallops from
    the previous result, so sorted ``t_out`` costs O(m log(gap)) instead of
    m full binary searches; unsorted input is still answered correctly.
    """
    m = t_out.shape[0]
    out = np.empty(m, dtype=np.int64)
    i = -1
    for j in range(m):
        i = gallop(t_in, t_out[j], i)
        out[j] = i
    return out


# ---------------------------------------------------------------------------
# array kernels
# ---------------------------------------------------------------------------


@kernel(F2, F2)
def qmul(p, q):
    """Hamilton product p * q, shapes (n, 4) x (n, 4) -> (n, 4) (n or 1)."""
    n = max(p.shape[0], q.shape[0])
    sp = 1 if p.shape[0] > 1 else 0
    sq = 1 if q.shape[0] > 1 else 0
    out = np.empty((n, 4))
    for i in range(n):
        a = i * sp
        b = i * sq
        w, x, y, z = _qmul1(
            p[a, 0], p[a, 1], p[a, 2], p[a, 3], q[b, 0], q[b, 1], q[b, 2], q[b, 3]
        )
        out[i, 0] = w
        out[i, 1] = x
        out[i, 2] = y
        out[i, 3] = z
    return out


@kernel(F2)
def qconj(q):
    """Conjugate (w, -x, -y, -z), shape (n, 4) -> (n, 4)."""
    out = np.empty_like(q)
    for i in range(q.shape[0]):
        out[i, 0] = q[i, 0]
        out[i, 1] = -q[i, 1]
        out[i, 2] = -q[i, 2]
        out[i, 3] = -q[i, 3]
    return out


@kernel(F2, F2)
def rotate_vectors(q, v):
    """Rotate v by q as q v q⁻¹, shapes (n, 4) x (n, 3) -> (n, 3) (n or 1).

    Correct for quaternions of any non-zero norm: the result is divided by
    |q|², so a non-unit q rotates without scaling.
    """
    n = max(q.shape[0], v.shape[0])
    sq = 1 if q.shape[0] > 1 else 0
    sv = 1 if v.shape[0] > 1 else 0
    out = np.empty((n, 3))
    for i in range(n):
        a = i * sq
        b = i * sv
        x, y, z = _rotate1(
            q[a, 0], q[a, 1], q[a, 2], q[a, 3], v[b, 0], v[b, 1], v[b, 2]
        )
        out[i, 0] = x
        out[i, 1] = y
        out[i, 2] = z
    return out


@kernel(F2, F2)
def rotate_vectors_outer(q, v):
    """Every q applied to every v, shapes (nq, 4) x (nv, 3) -> (nq, nv, 3)."""
    nq = q.shape[0]
    nv = v.shape[0]
    out = np.empty((nq, nv, 3))
    for i in range(nq):
        for j in range(nv):
            x, y, z = _rotate1(
                q[i, 0], q[i, 1], q[i, 2], q[i, 3], v[j, 0], v[j, 1], v[j, 2]
            )
            out[i, j, 0] = x
            out[i, j, 1] = y
            out[i, j, 2] = z
    return out


@kernel(F2, F2, F1)
def slerp(q0, q1, tau):
    """Spherical linear interpolation along the shorter arc.

    Parameters
    ----------
    q0, q1 : ndarray, shape (n, 4) or (1, 4)
        Values at tau = 0 and tau = 1.
    tau : ndarray, shape (n,) or (1,)
        Interpolation parameters (values outside [0, 1] extrapolate).

    Returns
    -------
    ndarray, shape (n, 4)
    """
    n = max(q0.shape[0], q1.shape[0], tau.shape[0])
    s0 = 1 if q0.shape[0] > 1 else 0
    s1 = 1 if q1.shape[0] > 1 else 0
    st = 1 if tau.shape[0] > 1 else 0
    out = np.empty((n, 4))
    for i in range(n):
        a = i * s0
        b = i * s1
        w, x, y, z = _qslerp1(
            q0[a, 0], q0[a, 1], q0[a, 2], q0[a, 3],
            q1[b, 0], q1[b, 1], q1[b, 2], q1[b, 3],
            tau[i * st],
        )  # fmt: skip
        out[i, 0] = w
        out[i, 1] = x
        out[i, 2] = y
        out[i, 3] = z
    return out


@helper(inline=True)
def _missing1(r, i):
    """Whether row i of ``r`` (n, 4) is a missing sample (any NaN)."""
    return math.isnan(r[i, 0] + r[i, 1] + r[i, 2] + r[i, 3])


@kernel(F2, F1)
def squad_coefficients(r, t):
    """Control points of the squad spline, as numpy-quaternion builds them.

    Parameters
    ----------
    r : ndarray, shape (n, 4), n >= 2
        Samples, assumed free of sign flips.
    t : ndarray, shape (n,)
        Strictly increasing sample times (only their ratios matter, so any
        time origin gives the same coefficients).

    Returns
    -------
    a, b : ndarray, shape (n, 4)
        ``a[i]`` belongs to sample i, ``b[i]`` to the end of segment i; the
        last row of ``b`` is the virtual sample r[n-1] r[n-2]⁻¹ r[n-1].

    Missing samples (NaN rows) split the series into runs, and each run
    gets the control points it would get as a series of its own: a control
    point whose outer neighbour is missing takes the end rule (``a[i] =
    r[i]`` where sample i-1 is missing, ``b[i] = r[i+1]`` where sample i+2
    is). So a segment between two present samples is finite, and the curve
    is unchanged (and C¹) wherever samples i-1 .. i+2 are all present.
    """
    n = r.shape[0]
    a_coef = np.empty((n, 4))
    b_coef = np.empty((n, 4))
    # logs[i] = log(r[i]⁻¹ r[i+1]): each enters two A's and two B's, so it
    # is computed once (the same operations numpy-quaternion performs)
    logs = np.empty((max(n - 1, 0), 4))
    for i in range(n - 1):
        iw, ix, iy, iz = _qinv1(r[i, 0], r[i, 1], r[i, 2], r[i, 3])
        nw, nx, ny, nz = _qmul1(
            iw, ix, iy, iz, r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3]
        )
        lw, lx, ly, lz = _qlog1(nw, nx, ny, nz)
        logs[i, 0] = lw
        logs[i, 1] = lx
        logs[i, 2] = ly
        logs[i, 3] = lz
    for k in range(4):
        a_coef[0, k] = r[0, k]
        a_coef[n - 1, k] = r[n - 1, k]
    for i in range(1, n - 1):
        if _missing1(r, i - 1):
            # a run of samples starts at i: its end rule (see the docstring)
            for k in range(4):
                a_coef[i, k] = r[i, k]
            continue
        # A[i] = r[i] exp((-L[i] + L[i-1] (t[i+1]-t[i]) / (t[i]-t[i-1])) / 4)
        ratio = (t[i + 1] - t[i]) / (t[i] - t[i - 1])
        ew, ex, ey, ez = _qexp1(
            (-logs[i, 0] + logs[i - 1, 0] * ratio) * 0.25,
            (-logs[i, 1] + logs[i - 1, 1] * ratio) * 0.25,
            (-logs[i, 2] + logs[i - 1, 2] * ratio) * 0.25,
            (-logs[i, 3] + logs[i - 1, 3] * ratio) * 0.25,
        )
        w, x, y, z = _qmul1(r[i, 0], r[i, 1], r[i, 2], r[i, 3], ew, ex, ey, ez)
        a_coef[i, 0] = w
        a_coef[i, 1] = x
        a_coef[i, 2] = y
        a_coef[i, 3] = z
    for i in range(n - 2):
        if _missing1(r, i + 2):
            # a run of samples ends at i + 1
            for k in range(4):
                b_coef[i, k] = r[i + 1, k]
            continue
        # B[i] = r[i+1] exp((L[i+1] (t[i+1]-t[i]) / (t[i+2]-t[i+1]) - L[i]) / -4)
        ratio = (t[i + 1] - t[i]) / (t[i + 2] - t[i + 1])
        ew, ex, ey, ez = _qexp1(
            (logs[i + 1, 0] * ratio - logs[i, 0]) * -0.25,
            (logs[i + 1, 1] * ratio - logs[i, 1]) * -0.25,
            (logs[i + 1, 2] * ratio - logs[i, 2]) * -0.25,
            (logs[i + 1, 3] * ratio - logs[i, 3]) * -0.25,
        )
        w, x, y, z = _qmul1(
            r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3], ew, ex, ey, ez
        )
        b_coef[i, 0] = w
        b_coef[i, 1] = x
        b_coef[i, 2] = y
        b_coef[i, 3] = z
    # past the last sample the curve continues as if r[n] = r[n-1] r[n-2]⁻¹ r[n-1]
    iw, ix, iy, iz = _qinv1(r[n - 2, 0], r[n - 2, 1], r[n - 2, 2], r[n - 2, 3])
    w, x, y, z = _qmul1(
        r[n - 1, 0], r[n - 1, 1], r[n - 1, 2], r[n - 1, 3], iw, ix, iy, iz
    )
    ew, ex, ey, ez = _qmul1(
        w, x, y, z, r[n - 1, 0], r[n - 1, 1], r[n - 1, 2], r[n - 1, 3]
    )
    for k in range(4):
        b_coef[n - 2, k] = r[n - 1, k]
    b_coef[n - 1, 0] = ew
    b_coef[n - 1, 1] = ex
    b_coef[n - 1, 2] = ey
    b_coef[n - 1, 3] = ez
    return a_coef, b_coef


@kernel(F2, F2, F2)
def squad_segments(r, a_coef, b_coef):
    """Per-segment great circles for :func:`squad_evaluate`, shape (n, 11).

    Row i holds the :func:`_geodesic1` (θ, u) of r[i] -> r[i+1] and of
    a[i] -> b[i] (the last row continues to the virtual sample
    ``b_coef[n-1]``), and a flag: 1 if any of these is not a unit
    quaternion, in which case evaluation takes numpy-quaternion's general
    exp/log route for that segment.
    """
    n = r.shape[0]
    seg = np.zeros((n, 11))
    for i in range(n):
        if i < n - 1:
            nw, nx, ny, nz = r[i + 1, 0], r[i + 1, 1], r[i + 1, 2], r[i + 1, 3]
        else:
            nw, nx, ny, nz = (
                b_coef[n - 1, 0],
                b_coef[n - 1, 1],
                b_coef[n - 1, 2],
                b_coef[n - 1, 3],
            )
        unit = (
            _is_unit(r[i, 0], r[i, 1], r[i, 2], r[i, 3])
            and _is_unit(nw, nx, ny, nz)
            and _is_unit(a_coef[i, 0], a_coef[i, 1], a_coef[i, 2], a_coef[i, 3])
            and _is_unit(b_coef[i, 0], b_coef[i, 1], b_coef[i, 2], b_coef[i, 3])
        )
        if not unit:
            seg[i, 10] = 1.0
            continue
        v = _geodesic1(r[i, 0], r[i, 1], r[i, 2], r[i, 3], nw, nx, ny, nz)
        for k in range(5):
            seg[i, k] = v[k]
        v = _geodesic1(
            a_coef[i, 0], a_coef[i, 1], a_coef[i, 2], a_coef[i, 3],
            b_coef[i, 0], b_coef[i, 1], b_coef[i, 2], b_coef[i, 3],
        )  # fmt: skip
        for k in range(5):
            seg[i, 5 + k] = v[k]
    return seg


@helper
def _along1(seg, i, o, tau, qw, qx, qy, qz):
    """cos(τθ) q + sin(τθ) u for the great circle stored at seg[i, o:o+5]."""
    s, c = _sincos(tau * seg[i, o])
    return (
        c * qw + s * seg[i, o + 1],
        c * qx + s * seg[i, o + 2],
        c * qy + s * seg[i, o + 3],
        c * qz + s * seg[i, o + 4],
    )


@kernel(F2, F1, F2, F2, F2, F1)
def squad_evaluate(q_in, t_in, a_coef, b_coef, seg, t_out):
    """Evaluate a squad spline whose coefficients are already known.

    Parameters
    ----------
    q_in : ndarray, shape (n, 4), n >= 2
    t_in : ndarray, shape (n,)
    a_coef, b_coef : ndarray, shape (n, 4)
        From :func:`squad_coefficients` (with the same ``q_in``, ``t_in``).
    seg : ndarray, shape (n, 11)
        From :func:`squad_segments`.
    t_out : ndarray, shape (m,)
        Must be on the same time origin as ``t_in``.

    Returns
    -------
    ndarray, shape (m, 4)
    """
    n = q_in.shape[0]
    m = t_out.shape[0]
    out = np.empty((m, 4))
    dt_last = t_in[n - 1] - t_in[n - 2]
    idx = search_right(t_in, t_out)
    for j in range(m):
        i = idx[j]
        if i < 0:
            i = n - 1  # numpy-quaternion indexes with -1 before the start
        if i < n - 1:
            dt = t_in[i + 1] - t_in[i]
        else:
            dt = (t_in[n - 1] + dt_last) - t_in[n - 1]
        tau = (t_out[j] - t_in[i]) / dt
        if seg[i, 10] == 0.0:
            s1 = _along1(seg, i, 0, tau, q_in[i, 0], q_in[i, 1], q_in[i, 2], q_in[i, 3])
            s2 = _along1(
                seg, i, 5, tau, a_coef[i, 0], a_coef[i, 1], a_coef[i, 2], a_coef[i, 3]
            )
        else:
            if i < n - 1:
                nw, nx, ny, nz = (
                    q_in[i + 1, 0],
                    q_in[i + 1, 1],
                    q_in[i + 1, 2],
                    q_in[i + 1, 3],
                )
            else:
                nw, nx, ny, nz = (
                    b_coef[n - 1, 0],
                    b_coef[n - 1, 1],
                    b_coef[n - 1, 2],
                    b_coef[n - 1, 3],
                )
            s1 = _qslerp1(
                q_in[i, 0], q_in[i, 1], q_in[i, 2], q_in[i, 3], nw, nx, ny, nz, tau
            )
            s2 = _qslerp1(
                a_coef[i, 0], a_coef[i, 1], a_coef[i, 2], a_coef[i, 3],
                b_coef[i, 0], b_coef[i, 1], b_coef[i, 2], b_coef[i, 3],
                tau,
            )  # fmt: skip
        w, x, y, z = _qslerp_unit1(
            s1[0], s1[1], s1[2], s1[3], s2[0], s2[1], s2[2], s2[3],
            2.0 * tau * (1.0 - tau),
        )  # fmt: skip
        if tau == 0.0 and math.isnan(w):
            # at a sample whose next one is missing: the sample itself
            w, x, y, z = q_in[i, 0], q_in[i, 1], q_in[i, 2], q_in[i, 3]
        out[j, 0] = w
        out[j, 1] = x
        out[j, 2] = y
        out[j, 3] = z
    return out


@kernel(F2, F1, F1)
def squad(q_in, t_in, t_out):
    """Cubic spline ("squad") interpolation of a rotation time series.

    Reproduces numpy-quaternion's ``quaternion.squad`` including its edge
    behaviour: times at or after the last sample extrapolate the last
    segment, and times before the first sample use the last segment's
    coefficients (numpy-quaternion indexes with -1 there).

    Parameters
    ----------
    q_in : ndarray, shape (n, 4)
        Samples, assumed free of sign flips.
    t_in : ndarray, shape (n,)
        Strictly increasing sample times.
    t_out : ndarray, shape (m,)
        Times to interpolate to.

    Returns
    -------
    ndarray, shape (m, 4)
        A single sample (n == 1) is held constant.
    """
    n = q_in.shape[0]
    m = t_out.shape[0]
    if n < 2 or m == 0:
        out = np.empty((m, 4))
        for j in range(m):
            for k in range(4):
                out[j, k] = q_in[0, k]
        return out
    a_coef, b_coef = squad_coefficients(q_in, t_in)
    seg = squad_segments(q_in, a_coef, b_coef)
    return squad_evaluate(q_in, t_in, a_coef, b_coef, seg, t_out)


@kernel(F2)
def unflip(q):
    """Flip signs along axis 0 so that successive quaternions are closest.

    ``q`` and ``-q`` are the same rotation; series converted from matrices or
    recorded by trackers may switch between them, which ruins derivatives and
    interpolation (squad between q[i] and a flipped q[i+1] turns the long way
    round). Each row is negated when its dot product with the previous
    valid (non-NaN) row, after that row's own correction, is negative: gaps
    of missing samples are bridged. The first valid row keeps its sign.

    Parameters
    ----------
    q : ndarray, shape (n, 4)

    Returns
    -------
    ndarray, shape (n, 4)
    """
    n = q.shape[0]
    out = np.empty((n, 4))
    # flat views (constant strides) and the last valid row kept in registers
    f = q.reshape(-1)
    o = out.reshape(-1)
    have = False
    pw = px = py = pz = 0.0
    for i in range(n):
        w, x, y, z = f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]
        d = 0.0
        if have:
            d = pw * w + px * x + py * y + pz * z
        sign = -1.0 if d < 0.0 else 1.0
        o[4 * i] = sign * w
        o[4 * i + 1] = sign * x
        o[4 * i + 2] = sign * y
        o[4 * i + 3] = sign * z
        if not math.isnan(w + x + y + z):
            pw, px, py, pz = sign * w, sign * x, sign * y, sign * z
            have = True
    return out
