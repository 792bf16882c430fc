"""Rotation conversions on arrays: numba kernels, unchecked.

Conventions shared by every kernel here:

* quaternions are float64 arrays of shape (n, 4) in ``w, x, y, z`` order,
  rotation matrices (n, 3, 3), homogeneous matrices (n, 4, 4), vectors and
  angle triples (n, 3), all C-contiguous;
* non-unit quaternions are normalised on the fly. Each kernel also counts,
  in the same pass, the input rows that are not valid (a quaternion farther
  than ``tol`` from unit norm, a matrix farther than ``tol`` from SO(3), a
  value that is not finite) and returns that count; the public module finds
  and reports the worst row only when the count is non-zero;
* Euler sequences are three axis indices (0 = x, 1 = y, 2 = z) plus an
  ``extrinsic`` flag; the intrinsic sequence (i, j, k) with angles (a, b, c)
  is the same rotation as the extrinsic sequence (k, j, i) with angles
  (c, b, a), which is how one case is reduced to the other.

Why the loops look the way they do: they are written so that LLVM can
vectorise them (8 rows per AVX-512 instruction), which is what brings the
conversions close to the memory-bandwidth floor. That rules out, inside the
hot loops, calls to libm's sin/cos/atan2 (LLVM has no vector versions of them
here), data-dependent branches (written as conditional expressions instead)
and argmax-style bookkeeping (replaced by integer counts). Hence:

* ``sincos`` and ``atan2`` (from :mod:`rbm_nb._kernels.scalar`) are
  polynomial implementations accurate to about one unit in the last place; arguments too large for ``_sincos``'s
  argument reduction are recomputed with libm in a second, scalar pass that
  only runs when such rows exist;
* the kernels are compiled with ``error_model="numpy"`` so that a division
  does not carry Python's ZeroDivisionError check (a branch that blocks
  vectorisation); the rows where a division by zero could occur are either
  discarded by a conditional expression or counted as invalid.
"""

from __future__ import annotations

import math

import numpy as np

from .._config import VECTOR_KERNEL
from ._jit import F1, F2, F3, B, F, I, helper, kernel
from .scalar import PI as _PI
from .scalar import PIO2 as _PIO2
from .scalar import SINCOS_LIMIT as _SINCOS_LIMIT
from .scalar import TINY_ANGLE as _SMALL_ANGLE
from .scalar import atan2 as _atan2
from .scalar import atan2_pos as _atan2_pos
from .scalar import sincos as _sincos
from .scalar import wrap_angle as _wrap

# Middle Euler angle this close to a singular value counts as gimbal lock.
# Exactly singular input lands within ~1e-16 of it; below the threshold the
# third angle is zeroed, which moves the rotation by at most the threshold,
# hence a value far smaller than scipy's 1e-7 (whose round trips are off by
# up to that much).
_GIMBAL_EPS = 1e-13
# Below this, x² + y² + z² may have lost digits to underflow; such rows are
# recomputed after scaling by _TINY_SCALE (powers of two, so exactly).
_TINY_SQUARE = 2.0**-1000
_TINY_SCALE = 2.0**600

# ---------------------------------------------------------------------------
# scalar helpers (inlined into the loops)
# ---------------------------------------------------------------------------


@helper(inline=True, options=VECTOR_KERNEL)
def _pick(axis, x, y, z):
    return x if axis == 0 else (y if axis == 1 else z)


@helper(inline=True, options=VECTOR_KERNEL)
def _canonical_sign(w, x, y, z):
    """-1 if -q is the canonical one of q and -q, else +1.

    Canonical: w > 0, or for half turns (w = 0) the first non-zero of x, y, z
    positive - the rule scipy uses, so that results match it exactly.
    """
    flip = w < 0.0 or (
        w == 0.0 and (x < 0.0 or (x == 0.0 and (y < 0.0 or (y == 0.0 and z < 0.0))))
    )
    return -1.0 if flip else 1.0


@helper(inline=True, options=VECTOR_KERNEL)
def _indicator(flag):
    return 1.0 if flag else 0.0


@helper(inline=True, options=VECTOR_KERNEL)
def _unit_norm_bounds(tol):
    """Bounds on ‖q‖² equivalent to |‖q‖ - 1| <= tol."""
    low = max(1.0 - tol, 0.0)
    return low * low, (1.0 + tol) * (1.0 + tol)


@helper(inline=True, options=VECTOR_KERNEL)
def _rotation_ok(m00, m01, m02, m10, m11, m12, m20, m21, m22, tol):
    """Entries of |RᵀR - I| all <= tol and det R > 0 (False for NaN)."""
    ok = abs(m00 * m00 + m10 * m10 + m20 * m20 - 1.0) <= tol
    ok &= abs(m01 * m01 + m11 * m11 + m21 * m21 - 1.0) <= tol
    ok &= abs(m02 * m02 + m12 * m12 + m22 * m22 - 1.0) <= tol
    ok &= abs(m00 * m01 + m10 * m11 + m20 * m21) <= tol
    ok &= abs(m00 * m02 + m10 * m12 + m20 * m22) <= tol
    ok &= abs(m01 * m02 + m11 * m12 + m21 * m22) <= tol
    det = (
        m00 * (m11 * m22 - m12 * m21)
        - m01 * (m10 * m22 - m12 * m20)
        + m02 * (m10 * m21 - m11 * m20)
    )
    ok &= det > 0.0
    return ok


@helper(inline=True, options=VECTOR_KERNEL)
def _quaternion_of_matrix(m00, m01, m02, m10, m11, m12, m20, m21, m22):
    """Unit quaternion with w >= 0 from a rotation matrix (Shepperd's choice).

    Of the four equivalent formulas, the one built on the largest of the
    trace and the diagonal is used, so the norm that is divided out stays
    at least 1 for every rotation. Normalising (rather than dividing by a
    square root of one entry) also maps a matrix that is orthonormal only to
    a few digits onto a unit quaternion.
    """
    trace = m00 + m11 + m22
    use_trace = trace >= m00 and trace >= m11 and trace >= m22
    use_x = m00 >= m11 and m00 >= m22
    use_y = m11 >= m22
    if use_trace:
        w, x, y, z = 1.0 + trace, m21 - m12, m02 - m20, m10 - m01
    elif use_x:
        w, x, y, z = m21 - m12, 1.0 + m00 - m11 - m22, m01 + m10, m02 + m20
    elif use_y:
        w, x, y, z = m02 - m20, m01 + m10, 1.0 - m00 + m11 - m22, m12 + m21
    else:
        w, x, y, z = m10 - m01, m02 + m20, m12 + m21, 1.0 - m00 - m11 + m22
    n2 = w * w + x * x + y * y + z * z
    inv = 1.0 / math.sqrt(n2) if n2 > 0.0 else math.nan
    inv *= _canonical_sign(w, x, y, z)
    return w * inv, x * inv, y * inv, z * inv


@helper(inline=True, options=VECTOR_KERNEL)
def _exp_row(theta2, theta, sin_h, cos_h):
    """(w, k) with q = (w, k v) for a rotation vector v of norm theta."""
    small = theta2 < _SMALL_ANGLE * _SMALL_ANGLE
    # Taylor series of cos(t/2) and sin(t/2)/t
    w = 1.0 - theta2 / 8.0 if small else cos_h
    k = 0.5 - theta2 / 48.0 if small else sin_h / theta
    return w, k


@helper(inline=True, options=VECTOR_KERNEL)
def _euler_row(s1, c1, s2, c2, s3, c3, i, j, proper, eps):
    """Intrinsic product q_i(a) q_j(b) q_k(c) from half-angle sines/cosines.

    Returns (w, v_i, v_j, v_k): the vector part on the three distinct axes
    i, j and the remaining one, for proper (third axis = i) and Tait-Bryan
    sequences; ``eps`` is +1 if (i, j, other) is a cyclic permutation of
    (x, y, z) and -1 otherwise.
    """
    tw = c1 * c2
    ti = s1 * c2
    tj = c1 * s2
    tk = eps * s1 * s2
    if proper:
        w = tw * c3 - ti * s3
        vi = ti * c3 + tw * s3
        vj = tj * c3 + eps * tk * s3
        vk = tk * c3 - eps * tj * s3
    else:
        w = tw * c3 - tk * s3
        vi = ti * c3 + eps * tj * s3
        vj = tj * c3 - eps * ti * s3
        vk = tk * c3 + tw * s3
    return w, vi, vj, vk


# ---------------------------------------------------------------------------
# quaternion <-> rotation matrix
# ---------------------------------------------------------------------------


@kernel(F2, F, options=VECTOR_KERNEL)
def matrix_from_quaternion(q, tol):
    """Rotation matrices of (normalised) quaternions.

    Parameters
    ----------
    q : ndarray, shape (n, 4)
    tol : float
        Rows with |‖q‖ - 1| > tol (or not finite) are counted as invalid.

    Returns
    -------
    out : ndarray, shape (n, 3, 3)
    n_invalid : int
    """
    n = q.shape[0]
    src = q.reshape(-1)
    out = np.empty(9 * n)
    low, high = _unit_norm_bounds(tol)
    n_invalid = 0
    for i in range(n):
        w, x, y, z = src[4 * i], src[4 * i + 1], src[4 * i + 2], src[4 * i + 3]
        n2 = w * w + x * x + y * y + z * z
        n_invalid += not (low <= n2 and n2 <= high)
        # 2 / ‖q‖² both doubles the products and normalises q
        s = 2.0 / n2 if n2 > 0.0 else math.nan
        xx, yy, zz = s * x * x, s * y * y, s * z * z
        xy, xz, yz = s * x * y, s * x * z, s * y * z
        wx, wy, wz = s * w * x, s * w * y, s * w * z
        out[9 * i] = 1.0 - yy - zz
        out[9 * i + 1] = xy - wz
        out[9 * i + 2] = xz + wy
        out[9 * i + 3] = xy + wz
        out[9 * i + 4] = 1.0 - xx - zz
        out[9 * i + 5] = yz - wx
        out[9 * i + 6] = xz - wy
        out[9 * i + 7] = yz + wx
        out[9 * i + 8] = 1.0 - xx - yy
    return out.reshape((n, 3, 3)), n_invalid


@kernel(F3, F, options=VECTOR_KERNEL)
def quaternion_from_matrix(m, tol):
    """Unit quaternions (w >= 0) of rotation matrices.

    Parameters
    ----------
    m : ndarray, shape (n, 3, 3)
    tol : float
        Rows with an entry of |RᵀR - I| above tol, det R <= 0 or non-finite
        values are counted as invalid.

    Returns
    -------
    out : ndarray, shape (n, 4)
    n_invalid : int
    """
    n = m.shape[0]
    src = m.reshape(-1)
    out = np.empty(4 * n)
    n_invalid = 0
    for i in range(n):
        b = 9 * i
        m00, m01, m02 = src[b], src[b + 1], src[b + 2]
        m10, m11, m12 = src[b + 3], src[b + 4], src[b + 5]
        m20, m21, m22 = src[b + 6], src[b + 7], src[b + 8]
        n_invalid += not _rotation_ok(m00, m01, m02, m10, m11, m12, m20, m21, m22, tol)
        w, x, y, z = _quaternion_of_matrix(m00, m01, m02, m10, m11, m12, m20, m21, m22)
        out[4 * i] = w
        out[4 * i + 1] = x
        out[4 * i + 2] = y
        out[4 * i + 3] = z
    return out.reshape((n, 4)), n_invalid


# ---------------------------------------------------------------------------
# quaternion <-> rotation vector (exponential / logarithm maps)
# ---------------------------------------------------------------------------


@kernel(F2, options=VECTOR_KERNEL)
def quaternion_from_rotation_vector(v):
    """exp of rotation vectors: angle ‖v‖ about v / ‖v‖.

    Parameters
    ----------
    v : ndarray, shape (n, 3)

    Returns
    -------
    out : ndarray, shape (n, 4)
        w = cos(‖v‖ / 2), which is negative for angles beyond pi.
    n_invalid : int
        Rows that are not finite.
    """
    n = v.shape[0]
    src = v.reshape(-1)
    out = np.empty(4 * n)
    limit2 = _SINCOS_LIMIT * _SINCOS_LIMIT
    n_slow = 0
    for i in range(n):
        x, y, z = src[3 * i], src[3 * i + 1], src[3 * i + 2]
        theta2 = x * x + y * y + z * z
        n_slow += not theta2 < limit2
        theta = math.sqrt(theta2)
        sin_h, cos_h = _sincos(0.5 * theta)
        w, k = _exp_row(theta2, theta, sin_h, cos_h)
        out[4 * i] = w
        out[4 * i + 1] = k * x
        out[4 * i + 2] = k * y
        out[4 * i + 3] = k * z
    n_invalid = 0
    if n_slow > 0:
        for i in range(n):
            x, y, z = src[3 * i], src[3 * i + 1], src[3 * i + 2]
            theta2 = x * x + y * y + z * z
            if theta2 < limit2:
                continue
            if not theta2 < math.inf:
                n_invalid += 1
                continue
            theta = math.sqrt(theta2)
            w, k = _exp_row(theta2, theta, math.sin(0.5 * theta), math.cos(0.5 * theta))
            out[4 * i] = w
            out[4 * i + 1] = k * x
            out[4 * i + 2] = k * y
            out[4 * i + 3] = k * z
    return out.reshape((n, 4)), n_invalid


@kernel(F2, F, options=VECTOR_KERNEL)
def rotation_vector_from_quaternion(q, tol):
    """log of (normalised) quaternions as rotation vectors of norm <= pi.

    Parameters
    ----------
    q : ndarray, shape (n, 4)
    tol : float
        As in ``matrix_from_quaternion``.

    Returns
    -------
    out : ndarray, shape (n, 3)
    n_invalid : int
    """
    n = q.shape[0]
    src = q.reshape(-1)
    out = np.empty(3 * n)
    low, high = _unit_norm_bounds(tol)
    n_invalid = 0
    for i in range(n):
        w, x, y, z = src[4 * i], src[4 * i + 1], src[4 * i + 2], src[4 * i + 3]
        n2 = w * w + x * x + y * y + z * z
        n_invalid += not (low <= n2 and n2 <= high)
        # -q is the same rotation; the one with w >= 0 has angle <= pi
        sign = _canonical_sign(w, x, y, z)
        w = sign * w
        s = math.sqrt(x * x + y * y + z * z)
        # atan2 needs no normalisation: only the ratio s / w matters
        small = s < _SMALL_ANGLE * w
        r = s / w if small else 0.0
        k = 2.0 / w * (1.0 - r * r / 3.0) if small else 2.0 * _atan2_pos(s, w) / s
        k *= sign
        out[3 * i] = k * x
        out[3 * i + 1] = k * y
        out[3 * i + 2] = k * z
    return out.reshape((n, 3)), n_invalid


# ---------------------------------------------------------------------------
# quaternion <-> axis-angle
# ---------------------------------------------------------------------------


@kernel(F2, F1, options=VECTOR_KERNEL)
def quaternion_from_axis_angle(axis, angle):
    """Rotations by ``angle`` about ``axis`` (normalised here).

    Parameters
    ----------
    axis : ndarray, shape (n, 3)
    angle : ndarray, shape (n,)

    Returns
    -------
    out : ndarray, shape (n, 4)
    n_invalid : int
        Rows whose axis has zero length for a non-zero angle, or whose
        values are not finite. A zero axis with a zero angle is the identity.
    """
    n = axis.shape[0]
    src = axis.reshape(-1)
    out = np.empty(4 * n)
    n_slow = 0
    for i in range(n):
        x, y, z = src[3 * i], src[3 * i + 1], src[3 * i + 2]
        length2 = x * x + y * y + z * z
        h = 0.5 * angle[i]
        # exactly zero axis and angle: the identity, right here; rows whose
        # squared axis length under- or overflows, large angles, and zero
        # axes with non-zero angles are (re)done in the slow loop below
        n_slow += not (
            _TINY_SQUARE < length2
            and length2 < math.inf
            and abs(h) < _SINCOS_LIMIT
            or length2 == 0.0
            and h == 0.0
            and x == 0.0
            and y == 0.0
            and z == 0.0
        )
        sin_h, cos_h = _sincos(h)
        k = sin_h / math.sqrt(length2) if length2 > 0.0 else 0.0
        out[4 * i] = cos_h
        out[4 * i + 1] = k * x
        out[4 * i + 2] = k * y
        out[4 * i + 3] = k * z
    n_invalid = 0
    if n_slow > 0:
        for i in range(n):
            x, y, z = src[3 * i], src[3 * i + 1], src[3 * i + 2]
            length2 = x * x + y * y + z * z
            h = 0.5 * angle[i]
            if _TINY_SQUARE < length2 and length2 < math.inf and abs(h) < _SINCOS_LIMIT:
                continue
            if h == 0.0 and x == 0.0 and y == 0.0 and z == 0.0:
                continue
            # the largest component scales the axis safely, whatever its size
            big = max(abs(x), abs(y), abs(z))
            if big > 0.0 and big < math.inf and abs(h) < math.inf:
                x, y, z = x / big, y / big, z / big
                w, k = math.cos(h), math.sin(h) / math.sqrt(x * x + y * y + z * z)
            else:
                n_invalid += 1
                w, k = math.nan, math.nan
            out[4 * i] = w
            out[4 * i + 1] = k * x
            out[4 * i + 2] = k * y
            out[4 * i + 3] = k * z
    return out.reshape((n, 4)), n_invalid


@helper(inline=True, options=VECTOR_KERNEL)
def _axis_angle_row(w, x, y, z, s2, axis, angle, i):
    sign = _canonical_sign(w, x, y, z)
    s = math.sqrt(s2)
    identity = s == 0.0
    k = 1.0 if identity else sign / s
    angle[i] = 2.0 * _atan2_pos(s, sign * w)
    axis[3 * i] = 1.0 if identity else k * x
    axis[3 * i + 1] = k * y
    axis[3 * i + 2] = k * z


@kernel(F2, F, options=VECTOR_KERNEL)
def axis_angle_from_quaternion(q, tol):
    """Unit axes and angles in [0, pi] of (normalised) quaternions.

    Parameters
    ----------
    q : ndarray, shape (n, 4)
    tol : float
        As in ``matrix_from_quaternion``.

    Returns
    -------
    axis : ndarray, shape (n, 3)
        (1, 0, 0) for the identity, whose axis is arbitrary.
    angle : ndarray, shape (n,)
    n_invalid : int
    """
    n = q.shape[0]
    src = q.reshape(-1)
    axis = np.empty(3 * n)
    angle = np.empty(n)
    low, high = _unit_norm_bounds(tol)
    n_invalid = 0
    n_tiny = 0
    for i in range(n):
        w, x, y, z = src[4 * i], src[4 * i + 1], src[4 * i + 2], src[4 * i + 3]
        n2 = w * w + x * x + y * y + z * z
        n_invalid += not (low <= n2 and n2 <= high)
        s2 = x * x + y * y + z * z
        # squares that underflow would lose the axis: redone below
        n_tiny += s2 < _TINY_SQUARE and (x != 0.0 or y != 0.0 or z != 0.0)
        _axis_angle_row(w, x, y, z, s2, axis, angle, i)
    if n_tiny > 0:
        for i in range(n):
            w, x, y, z = src[4 * i], src[4 * i + 1], src[4 * i + 2], src[4 * i + 3]
            s2 = x * x + y * y + z * z
            if s2 < _TINY_SQUARE and (x != 0.0 or y != 0.0 or z != 0.0):
                # scaling by a power of two is exact; the angle scales back
                w, x, y, z = (
                    w * _TINY_SCALE,
                    x * _TINY_SCALE,
                    y * _TINY_SCALE,
                    z * _TINY_SCALE,
                )
                _axis_angle_row(w, x, y, z, x * x + y * y + z * z, axis, angle, i)
    return axis.reshape((n, 3)), angle, n_invalid


# ---------------------------------------------------------------------------
# quaternion <-> Euler angles
# ---------------------------------------------------------------------------


@kernel(F2, I, I, I, B, options=VECTOR_KERNEL)
def quaternion_from_euler(angles, i, j, k, extrinsic):
    """Compose three elementary rotations about axes i, j, k.

    Parameters
    ----------
    angles : ndarray, shape (n, 3)
        Angles in radians, first column about axis ``i``.
    i, j, k : int
        Axis indices (0, 1, 2 for x, y, z) with i != j and j != k.
    extrinsic : bool
        Rotations about the fixed axes (q_k q_j q_i) instead of the moving
        ones (q_i q_j q_k).

    Returns
    -------
    out : ndarray, shape (n, 4)
    n_invalid : int
        Rows that are not finite.
    """
    if extrinsic:
        i, k = k, i
    proper = i == k
    other = 3 - i - j if proper else k
    eps = float((i - j) * (j - other) * (other - i) // 2)
    # 0/1 weights that route (v_i, v_j, v_k) to (x, y, z): a blend with
    # loop-invariant weights vectorises, a store to a computed index would
    # need scatter instructions
    xi, xj = _indicator(i == 0), _indicator(j == 0)
    yi, yj = _indicator(i == 1), _indicator(j == 1)
    zi, zj = _indicator(i == 2), _indicator(j == 2)
    xk, yk, zk = 1.0 - xi - xj, 1.0 - yi - yj, 1.0 - zi - zj
    n = angles.shape[0]
    src = angles.reshape(-1)
    out = np.empty(4 * n)
    n_slow = 0
    for r in range(n):
        a0, a1, a2 = src[3 * r], src[3 * r + 1], src[3 * r + 2]
        n_slow += not max(abs(a0), abs(a1), abs(a2)) < _SINCOS_LIMIT
        first = a2 if extrinsic else a0
        last = a0 if extrinsic else a2
        s1, c1 = _sincos(0.5 * first)
        s2, c2 = _sincos(0.5 * a1)
        s3, c3 = _sincos(0.5 * last)
        w, vi, vj, vk = _euler_row(s1, c1, s2, c2, s3, c3, i, j, proper, eps)
        out[4 * r] = w
        out[4 * r + 1] = xi * vi + xj * vj + xk * vk
        out[4 * r + 2] = yi * vi + yj * vj + yk * vk
        out[4 * r + 3] = zi * vi + zj * vj + zk * vk
    n_invalid = 0
    if n_slow > 0:
        for r in range(n):
            a0, a1, a2 = src[3 * r], src[3 * r + 1], src[3 * r + 2]
            big = max(abs(a0), abs(a1), abs(a2))
            if big < _SINCOS_LIMIT:
                continue
            if not big < math.inf:  # also true for NaN
                n_invalid += 1
            first = a2 if extrinsic else a0
            last = a0 if extrinsic else a2
            w, vi, vj, vk = _euler_row(
                math.sin(0.5 * first), math.cos(0.5 * first),
                math.sin(0.5 * a1), math.cos(0.5 * a1),
                math.sin(0.5 * last), math.cos(0.5 * last),
                i, j, proper, eps,
            )  # fmt: skip
            out[4 * r] = w
            out[4 * r + 1] = vi if i == 0 else (vj if j == 0 else vk)
            out[4 * r + 2] = vi if i == 1 else (vj if j == 1 else vk)
            out[4 * r + 3] = vi if i == 2 else (vj if j == 2 else vk)
    return out.reshape((n, 4)), n_invalid


@kernel(F2, I, I, I, B, F, options=VECTOR_KERNEL)
def euler_from_quaternion(q, i, j, k, extrinsic, tol):
    """Euler angles of (normalised) quaternions for the sequence i, j, k.

    The direct method of Bernardes & Viollet (2022, PLoS ONE 17(11)): one
    atan2 gives the middle angle, two more the half sum and half difference
    of the outer ones, for all twelve sequences alike.

    Parameters
    ----------
    q : ndarray, shape (n, 4)
    i, j, k : int
        Axis indices as in ``quaternion_from_euler``.
    extrinsic : bool
    tol : float
        As in ``matrix_from_quaternion``.

    Returns
    -------
    out : ndarray, shape (n, 3)
        Outer angles in [-pi, pi]; the middle one in [0, pi] for proper
        sequences (i == k) and [-pi/2, pi/2] for Tait-Bryan ones. At gimbal
        lock the third angle is 0 and the first carries the whole rotation
        about the merged axis.
    n_invalid : int
    """
    if not extrinsic:
        i, k = k, i
    proper = i == k
    if proper:
        k = 3 - i - j
    sign = float((i - j) * (j - k) * (k - i) // 2)
    n = q.shape[0]
    src = q.reshape(-1)
    out = np.empty(3 * n)
    low, high = _unit_norm_bounds(tol)
    n_invalid = 0
    for r in range(n):
        w, x, y, z = src[4 * r], src[4 * r + 1], src[4 * r + 2], src[4 * r + 3]
        n2 = w * w + x * x + y * y + z * z
        n_invalid += not (low <= n2 and n2 <= high)
        qi = _pick(i, x, y, z)
        qj = _pick(j, x, y, z)
        qk = _pick(k, x, y, z) * sign
        a = w if proper else w - qj
        b = qi if proper else qi + qk
        c = qj if proper else qj + w
        d = qk if proper else qk - qi
        middle = 2.0 * _atan2_pos(math.sqrt(c * c + d * d), math.sqrt(a * a + b * b))
        half_sum = _atan2(b, a)
        half_diff = _atan2(d, c)
        first = half_sum - half_diff
        last = half_sum + half_diff
        # the outer angles are only determined up to their sum (middle = 0)
        # or difference (middle = pi); the *returned* third angle is then 0,
        # which for intrinsic output is the extrinsic first one
        at_zero = middle < _GIMBAL_EPS
        at_pi = middle > _PI - _GIMBAL_EPS
        locked_angle = 2.0 * half_sum if at_zero else 2.0 * half_diff
        if at_zero or at_pi:
            if extrinsic:
                first = -locked_angle if at_pi else locked_angle
                last = 0.0
            else:
                first = 0.0
                last = locked_angle
        if not proper:
            last *= sign
            middle -= _PIO2
        first = _wrap(first)
        last = _wrap(last)
        out[3 * r] = first if extrinsic else last
        out[3 * r + 1] = middle
        out[3 * r + 2] = last if extrinsic else first
    return out.reshape((n, 3)), n_invalid


# ---------------------------------------------------------------------------
# (translation, rotation) <-> homogeneous matrices
# ---------------------------------------------------------------------------


@kernel(F2, F2, F, options=VECTOR_KERNEL)
def homogeneous_from_transform(t, q, tol):
    """4 x 4 matrices [[R(q), t], [0, 1]].

    Parameters
    ----------
    t : ndarray, shape (n, 3)
    q : ndarray, shape (n, 4)
    tol : float
        As in ``matrix_from_quaternion``.

    Returns
    -------
    out : ndarray, shape (n, 4, 4)
    n_invalid_rotation : int
        Quaternions off unit norm by more than tol, or not finite.
    n_invalid_translation : int
        Translations that are not finite.
    """
    n = q.shape[0]
    qs = q.reshape(-1)
    ts = t.reshape(-1)
    out = np.empty(16 * n)
    low, high = _unit_norm_bounds(tol)
    n_bad_q = 0
    n_bad_t = 0
    for i in range(n):
        w, x, y, z = qs[4 * i], qs[4 * i + 1], qs[4 * i + 2], qs[4 * i + 3]
        tx, ty, tz = ts[3 * i], ts[3 * i + 1], ts[3 * i + 2]
        n2 = w * w + x * x + y * y + z * z
        n_bad_q += not (low <= n2 and n2 <= high)
        n_bad_t += not abs(tx) + abs(ty) + abs(tz) < math.inf
        s = 2.0 / n2 if n2 > 0.0 else math.nan
        xx, yy, zz = s * x * x, s * y * y, s * z * z
        xy, xz, yz = s * x * y, s * x * z, s * y * z
        wx, wy, wz = s * w * x, s * w * y, s * w * z
        b = 16 * i
        out[b] = 1.0 - yy - zz
        out[b + 1] = xy - wz
        out[b + 2] = xz + wy
        out[b + 3] = tx
        out[b + 4] = xy + wz
        out[b + 5] = 1.0 - xx - zz
        out[b + 6] = yz - wx
        out[b + 7] = ty
        out[b + 8] = xz - wy
        out[b + 9] = yz + wx
        out[b + 10] = 1.0 - xx - yy
        out[b + 11] = tz
        out[b + 12] = 0.0
        out[b + 13] = 0.0
        out[b + 14] = 0.0
        out[b + 15] = 1.0
    return out.reshape((n, 4, 4)), n_bad_q, n_bad_t


@kernel(F3, F, options=VECTOR_KERNEL)
def transform_from_homogeneous(h, tol):
    """Translations and unit quaternions (w >= 0) of 4 x 4 matrices.

    Parameters
    ----------
    h : ndarray, shape (n, 4, 4)
    tol : float
        Rotation blocks are checked as in ``quaternion_from_matrix``; the
        bottom row must be within tol of (0, 0, 0, 1) and the translation
        finite.

    Returns
    -------
    t : ndarray, shape (n, 3)
    q : ndarray, shape (n, 4)
    n_invalid : int
    """
    n = h.shape[0]
    src = h.reshape(-1)
    t = np.empty(3 * n)
    q = np.empty(4 * n)
    n_invalid = 0
    for i in range(n):
        b = 16 * i
        m00, m01, m02, tx = src[b], src[b + 1], src[b + 2], src[b + 3]
        m10, m11, m12, ty = src[b + 4], src[b + 5], src[b + 6], src[b + 7]
        m20, m21, m22, tz = src[b + 8], src[b + 9], src[b + 10], src[b + 11]
        ok = _rotation_ok(m00, m01, m02, m10, m11, m12, m20, m21, m22, tol)
        ok &= abs(src[b + 12]) <= tol and abs(src[b + 13]) <= tol
        ok &= abs(src[b + 14]) <= tol and abs(src[b + 15] - 1.0) <= tol
        ok &= abs(tx) + abs(ty) + abs(tz) < math.inf
        n_invalid += not ok
        w, x, y, z = _quaternion_of_matrix(m00, m01, m02, m10, m11, m12, m20, m21, m22)
        q[4 * i] = w
        q[4 * i + 1] = x
        q[4 * i + 2] = y
        q[4 * i + 3] = z
        t[3 * i] = tx
        t[3 * i + 1] = ty
        t[3 * i + 2] = tz
    return t.reshape((n, 3)), q.reshape((n, 4)), n_invalid
