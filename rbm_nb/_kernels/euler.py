"""Euler angles <-> quaternions on arrays: numba kernels, unchecked.

The conventions and the reasons the loops look the way they do are those of
:mod:`.conversions` (which imports these kernels, its callers' address for
them): (n, 4) quaternions ``w, x, y, z``, (n, 3) angles, a count of invalid
rows returned with the result, vectorisable loops. A sequence is three axis
indices (0 = x, 1 = y, 2 = z) plus an ``extrinsic`` flag; the intrinsic
sequence (i, j, k) with angles (a, b, c) is the same rotation as the
extrinsic sequence (k, j, i) with angles (c, b, a), which is how one case
is reduced to the other.
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import VECTOR_KERNEL
from ._jit import F2, B, F, I, helper, kernel
from .conversion_rows import _indicator, _pick, _unit_norm_bounds
from .scalar import PI as _PI
from .scalar import PIO2 as _PIO2
from .scalar import SINCOS_LIMIT as _SINCOS_LIMIT
from .scalar import atan2 as _atan2
from .scalar import atan2_pos as _atan2_pos
from .scalar import sincos as _sincos
from .scalar import wrap_angle as _wrap

__all__ = ["quaternion_from_euler", "euler_from_quaternion"]

# Middle Euler angle this close to a singular value counts as gimbal lock.
# Exactly singular input lands within ~1e-16 of it; below the threshold the
# third angle is zeroed, which moves the rotation by at most the threshold,
# hence a value far smaller than scipy's 1e-7 (whose round trips are off by
# up to that much).
_GIMBAL_EPS = 1e-13


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
