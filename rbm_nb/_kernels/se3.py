"""SE(3)/SO(3) matrix algebra on stacks: numba kernels, unchecked.

Conventions shared by every kernel here:

* homogeneous matrices are float64 arrays of shape (n, 4, 4), rotation
  matrices (n, 3, 3), angle triples and vectors (n, 3), differential motions
  (n, 6) ordered ``(dx, dy, dz, rx, ry, rz)``, quaternions (n, 4) ``w, x, y, z``;
* where two operands are given, their first dimension is equal or 1 (that
  row is then reused for every output row, nothing is materialised);
* quaternion exp/log reuse the scalar helpers of
  :mod:`rbm_nb._kernels.quaternion` (numpy-quaternion's conventions);
* nothing is validated: :mod:`rbm_nb.se3` checks shapes and values first.
  Kernels that can meet a singularity return, besides their result, the
  index of the first offending row (-1 when there is none) so that the public
  function can name it in its error.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import F1, F2, F3, B, F, I, helper, kernel
from .quaternion import _qexp1, _qlog1

# Representation codes for ``rotvelxform`` (see rbm_nb.se3.REPRESENTATIONS).
RPY_XYZ = 0
RPY_ZYX = 1
RPY_YXZ = 2
EUL = 3
EXP = 4

# Below this angle the exponential-coordinate Jacobians use their Taylor
# series: the closed forms divide 0 by 0 at the origin and lose all digits
# close to it (1 - cos(t) cancels for t < 1e-4).
_SMALL_ANGLE = 1e-4


@kernel(F2)
def skew(v):
    """Skew-symmetric matrices of vectors, (n, 3) -> (n, 3, 3)."""
    n = v.shape[0]
    out = np.zeros((n, 3, 3))
    for i in range(n):
        x, y, z = v[i, 0], v[i, 1], v[i, 2]
        out[i, 0, 1] = -z
        out[i, 0, 2] = y
        out[i, 1, 0] = z
        out[i, 1, 2] = -x
        out[i, 2, 0] = -y
        out[i, 2, 1] = x
    return out


@kernel(F3)
def vex(s):
    """Vectors of (nearly) skew-symmetric matrices, (n, 3, 3) -> (n, 3).

    The antisymmetric part is used, so a matrix that is not exactly skew
    gives the vector of its nearest skew-symmetric matrix.
    """
    n = s.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        out[i, 0] = 0.5 * (s[i, 2, 1] - s[i, 1, 2])
        out[i, 1] = 0.5 * (s[i, 0, 2] - s[i, 2, 0])
        out[i, 2] = 0.5 * (s[i, 1, 0] - s[i, 0, 1])
    return out


@kernel(F3, F3)
def tr2delta(t0, t1):
    """Differential motion from ``t0`` to ``t1`` in the ``t0`` frame.

    ``inv(t0) @ t1 = [[R, p], [0, 1]]`` gives ``(p, vex(R - I))``;
    (n0 | 1, 4, 4), (n1 | 1, 4, 4) -> (n, 6).
    """
    n = max(t0.shape[0], t1.shape[0])
    a_step = 1 if t0.shape[0] > 1 else 0
    b_step = 1 if t1.shape[0] > 1 else 0
    out = np.empty((n, 6))
    for i in range(n):
        a = t0[i * a_step]
        b = t1[i * b_step]
        d0 = b[0, 3] - a[0, 3]
        d1 = b[1, 3] - a[1, 3]
        d2 = b[2, 3] - a[2, 3]
        # translation of inv(a) @ b: a_R^T (b_t - a_t)
        for r in range(3):
            out[i, r] = a[0, r] * d0 + a[1, r] * d1 + a[2, r] * d2

        # only the off-diagonal entries of a_R^T b_R enter vex(R - I);
        # entry (r, c) is column r of a_R dotted with column c of b_R
        r21 = a[0, 2] * b[0, 1] + a[1, 2] * b[1, 1] + a[2, 2] * b[2, 1]
        r12 = a[0, 1] * b[0, 2] + a[1, 1] * b[1, 2] + a[2, 1] * b[2, 2]
        r02 = a[0, 0] * b[0, 2] + a[1, 0] * b[1, 2] + a[2, 0] * b[2, 2]
        r20 = a[0, 2] * b[0, 0] + a[1, 2] * b[1, 0] + a[2, 2] * b[2, 0]
        r10 = a[0, 1] * b[0, 0] + a[1, 1] * b[1, 0] + a[2, 1] * b[2, 0]
        r01 = a[0, 0] * b[0, 1] + a[1, 0] * b[1, 1] + a[2, 0] * b[2, 1]
        out[i, 3] = 0.5 * (r21 - r12)
        out[i, 4] = 0.5 * (r02 - r20)
        out[i, 5] = 0.5 * (r10 - r01)
    return out


@kernel(F2)
def delta2tr(d):
    """``I + skewa(d)`` for differential motions, (n, 6) -> (n, 4, 4)."""
    n = d.shape[0]
    out = np.zeros((n, 4, 4))
    for i in range(n):
        x, y, z = d[i, 3], d[i, 4], d[i, 5]
        out[i, 0, 0] = 1.0
        out[i, 1, 1] = 1.0
        out[i, 2, 2] = 1.0
        out[i, 3, 3] = 1.0
        out[i, 0, 1] = -z
        out[i, 0, 2] = y
        out[i, 1, 0] = z
        out[i, 1, 2] = -x
        out[i, 2, 0] = -y
        out[i, 2, 1] = x
        out[i, 0, 3] = d[i, 0]
        out[i, 1, 3] = d[i, 1]
        out[i, 2, 3] = d[i, 2]
    return out


@kernel(F3)
def tr2adjoint(t):
    """Adjoints ``[[R, skew(p) R], [0, R]]``, (n, 4, 4) -> (n, 6, 6)."""
    n = t.shape[0]
    out = np.zeros((n, 6, 6))
    for i in range(n):
        px, py, pz = t[i, 0, 3], t[i, 1, 3], t[i, 2, 3]
        for c in range(3):
            r0, r1, r2 = t[i, 0, c], t[i, 1, c], t[i, 2, c]
            out[i, 0, c] = r0
            out[i, 1, c] = r1
            out[i, 2, c] = r2
            out[i, 3, c + 3] = r0
            out[i, 4, c + 3] = r1
            out[i, 5, c + 3] = r2
            # skew(p) @ R[:, c] = p x R[:, c]
            out[i, 0, c + 3] = py * r2 - pz * r1
            out[i, 1, c + 3] = pz * r0 - px * r2
            out[i, 2, c + 3] = px * r1 - py * r0
    return out


@helper(inline=True)
def _set3(out, i, a00, a01, a02, a10, a11, a12, a20, a21, a22):
    out[i, 0, 0] = a00
    out[i, 0, 1] = a01
    out[i, 0, 2] = a02
    out[i, 1, 0] = a10
    out[i, 1, 1] = a11
    out[i, 1, 2] = a12
    out[i, 2, 0] = a20
    out[i, 2, 1] = a21
    out[i, 2, 2] = a22


@helper
def _exp_jacobian(out, i, x, y, z, inverse):
    """``I + a K + b K @ K`` with ``K = skew(v)``: the exp-coordinate rates map.

    Forward: a = (1 - cos t) / t^2, b = (t - sin t) / t^3.
    Inverse: a = -1/2, b = (1 - (t/2) sin t / (1 - cos t)) / t^2.
    Returns False where the inverse is singular (t a non-zero multiple of 2 pi).
    """
    t2 = x * x + y * y + z * z
    t = math.sqrt(t2)
    if inverse:
        a = -0.5
        if t < _SMALL_ANGLE:
            b = 1.0 / 12.0 + t2 / 720.0
        else:
            one_minus_cos = 2.0 * math.sin(0.5 * t) ** 2
            if one_minus_cos == 0.0:
                return False
            b = (1.0 - 0.5 * t * math.sin(t) / one_minus_cos) / t2
    else:
        if t < _SMALL_ANGLE:
            a = 0.5 - t2 / 24.0
            b = 1.0 / 6.0 - t2 / 120.0
        else:
            a = 2.0 * math.sin(0.5 * t) ** 2 / t2
            b = (t - math.sin(t)) / (t2 * t)
    # K @ K = v v^T - t^2 I
    _set3(
        out, i,
        1.0 + b * (x * x - t2), b * x * y - a * z, b * x * z + a * y,
        b * x * y + a * z, 1.0 + b * (y * y - t2), b * y * z - a * x,
        b * x * z - a * y, b * y * z + a * x, 1.0 + b * (z * z - t2),
    )  # fmt: skip
    return True


@kernel(F2, I, B, F)
def rotvelxform(angles, representation, inverse, tol):
    """Rates-to-angular-velocity matrices (or their inverses), (n, 3) -> (n, 3, 3).

    Returns ``(out, bad)``: ``bad`` is the first row whose inverse is singular
    (|cos(pitch)| <= tol for RPY, |sin(theta)| <= tol for ZYZ Euler, a
    rotation angle that is a non-zero multiple of 2 pi within tol for
    exponential coordinates), or -1.
    """
    n = angles.shape[0]
    out = np.empty((n, 3, 3))
    bad = -1
    for i in range(n):
        a0, a1, a2 = angles[i, 0], angles[i, 1], angles[i, 2]
        if representation == EXP:
            if inverse:
                t = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
                k = round(t / (2.0 * math.pi))
                if k > 0 and abs(t - 2.0 * math.pi * k) <= tol:
                    if bad < 0:
                        bad = i
                    continue
            if not _exp_jacobian(out, i, a0, a1, a2, inverse) and bad < 0:
                bad = i
            continue
        if representation == EUL:
            sphi, cphi = math.sin(a0), math.cos(a0)
            sth, cth = math.sin(a1), math.cos(a1)
            if not inverse:
                _set3(
                    out, i, 0.0, -sphi, cphi * sth, 0.0, cphi, sphi * sth, 1.0, 0.0, cth
                )
            elif abs(sth) <= tol:
                if bad < 0:
                    bad = i
            else:
                _set3(
                    out, i,
                    -cphi * cth / sth, -sphi * cth / sth, 1.0,
                    -sphi, cphi, 0.0,
                    cphi / sth, sphi / sth, 0.0,
                )  # fmt: skip
            continue
        sb, cb = math.sin(a1), math.cos(a1)
        sg, cg = math.sin(a2), math.cos(a2)
        if not inverse:
            if representation == RPY_XYZ:
                _set3(out, i, sb, 0.0, 1.0, -sg * cb, cg, 0.0, cb * cg, sg, 0.0)
            elif representation == RPY_ZYX:
                _set3(out, i, cb * cg, -sg, 0.0, sg * cb, cg, 0.0, -sb, 0.0, 1.0)
            else:
                _set3(out, i, sg * cb, cg, 0.0, -sb, 0.0, 1.0, cb * cg, -sg, 0.0)
            continue
        if abs(cb) <= tol:
            if bad < 0:
                bad = i
            continue
        tb = sb / cb
        if representation == RPY_XYZ:
            _set3(out, i, 0.0, -sg / cb, cg / cb, 0.0, cg, sg, 1.0, sg * tb, -cg * tb)
        elif representation == RPY_ZYX:
            _set3(out, i, cg / cb, sg / cb, 0.0, -sg, cg, 0.0, cg * tb, sg * tb, 1.0)
        else:
            _set3(out, i, sg / cb, 0.0, cg / cb, cg, 0.0, -sg, sg * tb, 1.0, cg * tb)
    return out, bad


@kernel(F3)
def trnorm(t):
    """Re-orthonormalise the rotation block of (n, k, k) matrices, k = 3 or 4.

    Keeps the direction of the z column ``a``: ``n = o x a``, ``o = a x n``,
    each normalised. Returns ``(out, bad)`` with ``bad`` the first row whose
    ``o`` and ``a`` are parallel or zero (no frame to build), or -1.
    """
    out = t.copy()
    bad = -1
    for i in range(t.shape[0]):
        ox, oy, oz = t[i, 0, 1], t[i, 1, 1], t[i, 2, 1]
        ax, ay, az = t[i, 0, 2], t[i, 1, 2], t[i, 2, 2]
        nx = oy * az - oz * ay
        ny = oz * ax - ox * az
        nz = ox * ay - oy * ax
        ox = ay * nz - az * ny
        oy = az * nx - ax * nz
        oz = ax * ny - ay * nx
        ln = math.sqrt(nx * nx + ny * ny + nz * nz)
        lo = math.sqrt(ox * ox + oy * oy + oz * oz)
        la = math.sqrt(ax * ax + ay * ay + az * az)
        if ln == 0.0 or lo == 0.0 or la == 0.0:
            if bad < 0:
                bad = i
            continue
        out[i, 0, 0] = nx / ln
        out[i, 1, 0] = ny / ln
        out[i, 2, 0] = nz / ln
        out[i, 0, 1] = ox / lo
        out[i, 1, 1] = oy / lo
        out[i, 2, 1] = oz / lo
        out[i, 0, 2] = ax / la
        out[i, 1, 2] = ay / la
        out[i, 2, 2] = az / la
    return out, bad


@helper(inline=True)
def _quaternion_of_block(m):
    """Unit quaternion of the rotation block of a 4 x 4 matrix (Shepperd).

    The component of largest magnitude is computed from a square root and
    is therefore positive: the sign spatialmath's ``r2q`` returns.
    """
    m00, m11, m22 = m[0, 0], m[1, 1], m[2, 2]
    trace = m00 + m11 + m22
    if trace >= m00 and trace >= m11 and trace >= m22:
        w = 0.5 * math.sqrt(max(1.0 + trace, 0.0))
        f = 0.25 / w
        return (
            w,
            (m[2, 1] - m[1, 2]) * f,
            (m[0, 2] - m[2, 0]) * f,
            (m[1, 0] - m[0, 1]) * f,
        )
    if m00 >= m11 and m00 >= m22:
        x = 0.5 * math.sqrt(max(1.0 + m00 - m11 - m22, 0.0))
        f = 0.25 / x
        return (
            (m[2, 1] - m[1, 2]) * f,
            x,
            (m[0, 1] + m[1, 0]) * f,
            (m[0, 2] + m[2, 0]) * f,
        )
    if m11 >= m22:
        y = 0.5 * math.sqrt(max(1.0 - m00 + m11 - m22, 0.0))
        f = 0.25 / y
        return (
            (m[0, 2] - m[2, 0]) * f,
            (m[0, 1] + m[1, 0]) * f,
            y,
            (m[1, 2] + m[2, 1]) * f,
        )
    z = 0.5 * math.sqrt(max(1.0 - m00 - m11 + m22, 0.0))
    f = 0.25 / z
    return (m[1, 0] - m[0, 1]) * f, (m[0, 2] + m[2, 0]) * f, (m[1, 2] + m[2, 1]) * f, z


@kernel(F3, F3, F1, B)
def trinterp(t0, t1, s, shortest):
    """Slerp the rotations and lerp the translations of pose pairs.

    ``t0``, ``t1`` (n0 | 1, 4, 4) and ``s`` (ns | 1,) fractions; rows of
    length 1 are reused. With ``shortest`` the rotation takes the shorter of
    the two arcs (``q1`` is flipped into ``q0``'s hemisphere); otherwise the
    arc between the quaternions of :func:`_quaternion_of_block`.
    """
    n = max(t0.shape[0], t1.shape[0], s.shape[0])
    a_step = 1 if t0.shape[0] > 1 else 0
    b_step = 1 if t1.shape[0] > 1 else 0
    s_step = 1 if s.shape[0] > 1 else 0
    out = np.zeros((n, 4, 4))
    for i in range(n):
        a = t0[i * a_step]
        b = t1[i * b_step]
        si = s[i * s_step]
        aw, ax, ay, az = _quaternion_of_block(a)
        bw, bx, by, bz = _quaternion_of_block(b)
        if shortest and aw * bw + ax * bx + ay * by + az * bz < 0.0:
            bw, bx, by, bz = -bw, -bx, -by, -bz
        # the angle between the two unit 4-vectors, accurate at 0 and pi
        dw, dx, dy, dz = bw - aw, bx - ax, by - ay, bz - az
        sw, sx, sy, sz = bw + aw, bx + ax, by + ay, bz + az
        theta = 2.0 * math.atan2(
            math.sqrt(dw * dw + dx * dx + dy * dy + dz * dz),
            math.sqrt(sw * sw + sx * sx + sy * sy + sz * sz),
        )
        sin_theta = math.sin(theta)
        if si == 0.0 or sin_theta <= 1e-15:
            # equal (or antipodal) endpoints: every interpolate is q0
            w, x, y, z = aw, ax, ay, az
            if si == 1.0:
                w, x, y, z = bw, bx, by, bz
        else:
            c0 = math.sin((1.0 - si) * theta) / sin_theta
            c1 = math.sin(si * theta) / sin_theta
            w = c0 * aw + c1 * bw
            x = c0 * ax + c1 * bx
            y = c0 * ay + c1 * by
            z = c0 * az + c1 * bz
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        out[i, 0, 0] = 1.0 - 2.0 * (y * y + z * z)
        out[i, 0, 1] = 2.0 * (x * y - w * z)
        out[i, 0, 2] = 2.0 * (x * z + w * y)
        out[i, 1, 0] = 2.0 * (x * y + w * z)
        out[i, 1, 1] = 1.0 - 2.0 * (x * x + z * z)
        out[i, 1, 2] = 2.0 * (y * z - w * x)
        out[i, 2, 0] = 2.0 * (x * z - w * y)
        out[i, 2, 1] = 2.0 * (y * z + w * x)
        out[i, 2, 2] = 1.0 - 2.0 * (x * x + y * y)
        for r in range(3):
            out[i, r, 3] = (1.0 - si) * a[r, 3] + si * b[r, 3]
        out[i, 3, 3] = 1.0
    return out


@helper(inline=True)
def _is_rotation(m, i, tol):
    """Whether the top-left 3 x 3 block of ``m[i]`` is a rotation within ``tol``.

    Every entry of ``RᵀR - I`` within ``tol`` and ``det(R) > 0``; NaN fails.
    """
    worst = 0.0
    for a in range(3):
        for b in range(a, 3):
            dot = (
                m[i, 0, a] * m[i, 0, b]
                + m[i, 1, a] * m[i, 1, b]
                + m[i, 2, a] * m[i, 2, b]
            )
            dev = abs(dot - (1.0 if a == b else 0.0))
            # a NaN deviation must count as bad: compare negated
            if not dev <= worst:
                worst = dev
    det = (
        m[i, 0, 0] * (m[i, 1, 1] * m[i, 2, 2] - m[i, 1, 2] * m[i, 2, 1])
        - m[i, 0, 1] * (m[i, 1, 0] * m[i, 2, 2] - m[i, 1, 2] * m[i, 2, 0])
        + m[i, 0, 2] * (m[i, 1, 0] * m[i, 2, 1] - m[i, 1, 1] * m[i, 2, 0])
    )
    return worst <= tol and det > 0.0


@kernel(F3, F)
def first_non_rotation(m, tol):
    """First row of (n, k, k) matrices (k >= 3) whose top-left 3 x 3 block is
    not a proper rotation: an entry of ``RᵀR - I`` beyond ``tol`` or
    ``det(R) <= 0``. Returns -1 when every row is one.
    """
    for i in range(m.shape[0]):
        if not _is_rotation(m, i, tol):
            return i
    return -1


@kernel(F3, F, B)
def first_bad_pose(m, tol, rotation):
    """First row of (n, 4, 4) matrices that is not a pose, and why.

    Returns ``(i, code)``: code 1 a value is not finite, 2 the last row is
    not (0, 0, 0, 1) within 1e-12, 3 (with ``rotation``) the rotation block
    is not a rotation within ``tol``; ``(-1, 0)`` when every row is a pose.
    One pass, so that validating costs about as much as computing.
    """
    for i in range(m.shape[0]):
        for r in range(4):
            for c in range(4):
                if not math.isfinite(m[i, r, c]):
                    return i, 1
        if (
            abs(m[i, 3, 0]) > 1e-12
            or abs(m[i, 3, 1]) > 1e-12
            or abs(m[i, 3, 2]) > 1e-12
            or abs(m[i, 3, 3] - 1.0) > 1e-12
        ):
            return i, 2
        if rotation and not _is_rotation(m, i, tol):
            return i, 3
    return -1, 0


@kernel(F2)
def qexp(q):
    """Quaternion exponentials, (n, 4) -> (n, 4) ``w, x, y, z`` (any norm)."""
    out = np.empty_like(q)
    for i in range(q.shape[0]):
        w, x, y, z = _qexp1(q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        out[i, 0] = w
        out[i, 1] = x
        out[i, 2] = y
        out[i, 3] = z
    return out


@kernel(F2)
def qlog(q):
    """Principal quaternion logarithms, (n, 4) -> (n, 4), of non-zero quaternions.

    A negative real quaternion gets the vector part (pi, 0, 0), as in
    numpy-quaternion.
    """
    out = np.empty_like(q)
    for i in range(q.shape[0]):
        w, x, y, z = _qlog1(q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        out[i, 0] = w
        out[i, 1] = x
        out[i, 2] = y
        out[i, 3] = z
    return out
