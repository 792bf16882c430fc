"""Row helpers of the conversion kernels, inlined into their loops.

Shared by :mod:`.conversions` and :mod:`.euler`: branch-free scalar code
(conditional expressions, no libm calls) so that the loops they are
inlined into still vectorise.
"""

from __future__ import annotations

import math

from .._infra.config import VECTOR_KERNEL
from ._jit import helper
from .scalar import TINY_ANGLE as _SMALL_ANGLE


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
