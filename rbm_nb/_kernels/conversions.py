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
* Euler sequences (the kernels in :mod:`.euler`, imported here) are three axis indices (0 = x, 1 = y, 2 = z) plus an
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

from .._infra.config import VECTOR_KERNEL
from ._jit import F1, F2, F3, F, helper, kernel
from .conversion_rows import (
    _canonical_sign,
    _exp_row,
    _quaternion_of_matrix,
    _rotation_ok,
    _unit_norm_bounds,
)

# the Euler kernels live in their own module; this stays their callers' address
from .euler import euler_from_quaternion, quaternion_from_euler  # noqa: F401 (their address)
from .scalar import SINCOS_LIMIT as _SINCOS_LIMIT
from .scalar import TINY_ANGLE as _SMALL_ANGLE
from .scalar import atan2_pos as _atan2_pos
from .scalar import sincos as _sincos

# Below this, x² + y² + z² may have lost digits to underflow; such rows are
# recomputed after scaling by _TINY_SCALE (powers of two, so exactly).
_TINY_SQUARE = 2.0**-1000
_TINY_SCALE = 2.0**600

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
