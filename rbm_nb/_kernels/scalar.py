"""Scalar math for the kernels: one implementation of each function.

Inlined into the kernels that call them (``@helper(inline=True)``), so they
cost no call and vectorise with the caller's loop.

* :func:`sincos` and :func:`atan2`: polynomial versions, accurate to about
  one unit in the last place, branch-free so that LLVM vectorises the loops
  around them (it has no vector versions of libm's sin/cos/atan2 here), and
  measured faster than libm in the scalar loops too. ``sincos`` reduces its
  argument by multiples of pi/2 exactly only for ``|x| < SINCOS_LIMIT``;
  callers handle larger arguments with libm.
* :func:`sinc_series`, :func:`cos_series`, :func:`atan_over_x`: truncated
  Taylor series for the small angles that dominate the interpolation of
  densely sampled rotations (below ``SERIES_ANGLE``/``SERIES_RATIO`` they
  are exact to well under one rounding error and need no division).

Two thresholds, two meanings:

* ``SERIES_ANGLE`` (0.1): below it the truncated series above are exact;
  a speed threshold.
* ``TINY_ANGLE`` (1e-6): below it the exponential and logarithm maps use the
  two-term expansions of sin(x)/x and atan(x)/x, because the direct
  formulas are 0/0 at zero; an accuracy threshold.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import helper

__all__ = [
    "sincos",
    "atan2",
    "atan2_pos",
    "atan_ratio",
    "wrap_angle",
    "sinc_series",
    "cos_series",
    "atan_over_x",
    "SINCOS_LIMIT",
    "SERIES_ANGLE",
    "SERIES_RATIO",
    "TINY_SQUARE",
    "atan_over_x_small",
    "cos_small",
    "sinc_small",
    "TINY_ANGLE",
]

# Rotation angles below this are treated with series expansions in the
# exponential and logarithm maps (where sin(x)/x and atan2(s, w)/s are 0/0).
TINY_ANGLE = 1e-6

# |x| below which sincos's reduction by multiples of pi/2 is exact enough:
# k * PIO2_HI is exact for |k| < 2**20, i.e. |x| < 1.6e6.
SINCOS_LIMIT = 1e5

PI = math.pi
PIO2 = 0.5 * math.pi
PIO4 = 0.25 * math.pi
TWO_OVER_PI = 2.0 / math.pi
# pi/2 split into 33 + 33 + 53 significant bits (Cody-Waite reduction)
PIO2_HI = 1.5707963267341256
PIO2_MID = 6.077100506303966e-11
PIO2_LO = 2.0222662487959506e-21
TAN_PI_8 = math.sqrt(2.0) - 1.0

# atan(u) = u * P(u²) for |u| <= tan(pi/8): the Taylor series of
# atan(√s)/√s, economised with Chebyshev polynomials to degree 11 on
# s in [0, 0.1716]; truncation error below 1.3e-18 (the derivation is
# re-run in tests/core/test_conversions.py).
ATAN_P = (
    1.0,
    -0.33333333333333126,
    0.19999999999942258,
    -0.1428571427937341,
    0.11111110750611304,
    -0.09090896962572438,
    0.07692047912901954,
    -0.06662979711761823,
    0.05847071977809275,
    -0.050359375323660804,
    0.037985607685565206,
    -0.01782681529846552,
)
A0, A1, A2, A3, A4, A5, A6, A7, A8, A9, A10, A11 = ATAN_P


# Taylor coefficients for the small angles that dominate interpolation of
# densely sampled rotations: within the thresholds below, the truncated
# series are exact to well under one rounding error, and about 3x cheaper
# than the libm calls (atan2 costs as much as sin and cos together).
SERIES_ANGLE = 0.1
SERIES_RATIO = 0.05


@helper(inline=True)
def sinc_series(y2):
    """sin(y) / y from y², for |y| < SERIES_ANGLE."""
    return 1.0 + y2 * (
        -1.0 / 6.0
        + y2
        * (1.0 / 120.0 + y2 * (-1.0 / 5040.0 + y2 * (1.0 / 362880.0 - y2 / 39916800.0)))
    )


@helper(inline=True)
def cos_series(y2):
    """cos(y) from y², for |y| < SERIES_ANGLE."""
    return 1.0 + y2 * (
        -0.5
        + y2
        * (
            1.0 / 24.0
            + y2
            * (
                -1.0 / 720.0
                + y2 * (1.0 / 40320.0 + y2 * (-1.0 / 3628800.0 + y2 / 479001600.0))
            )
        )
    )


@helper(inline=True)
def atan_over_x(x2):
    """atan(x) / x from x², for 0 <= x < SERIES_RATIO."""
    return 1.0 + x2 * (
        -1.0 / 3.0
        + x2
        * (
            1.0 / 5.0
            + x2
            * (
                -1.0 / 7.0
                + x2 * (1.0 / 9.0 + x2 * (-1.0 / 11.0 + x2 * (1.0 / 13.0 - x2 / 15.0)))
            )
        )
    )


# Below this square of an angle (or of tan), the series above need four
# terms only: the first omitted term is under 1.2e-17 relative. Densely
# sampled recordings have arcs of ~1e-3 between samples, so this is the
# common case of the table fill and of squad's evaluation.
TINY_SQUARE = 1e-4


@helper(inline=True)
def cos_small(y2):
    """cos(y) from y² < SERIES_ANGLE² (four terms when y² < TINY_SQUARE)."""
    if y2 < TINY_SQUARE:
        return 1.0 + y2 * (-0.5 + y2 * (1.0 / 24.0 - y2 / 720.0))
    return cos_series(y2)


@helper(inline=True)
def sinc_small(y2):
    """sin(y)/y from y² < SERIES_ANGLE² (four terms when y² < TINY_SQUARE)."""
    if y2 < TINY_SQUARE:
        return 1.0 + y2 * (-1.0 / 6.0 + y2 * (1.0 / 120.0 - y2 / 5040.0))
    return sinc_series(y2)


@helper(inline=True)
def atan_over_x_small(x2):
    """atan(x)/x from x² < SERIES_RATIO² (four terms when x² < TINY_SQUARE)."""
    if x2 < TINY_SQUARE:
        return 1.0 + x2 * (-1.0 / 3.0 + x2 * (0.2 - x2 / 7.0))
    return atan_over_x(x2)


@helper(inline=True)
def sincos(x):
    """(sin x, cos x) for |x| < SINCOS_LIMIT, branch-free.

    x = k pi/2 + r with |r| <= pi/4; Taylor polynomials of degree 15 (sin)
    and 16 (cos) are exact to below half an ulp on that range, and the
    quadrant k picks signs and swaps.
    """
    k = math.floor(x * TWO_OVER_PI + 0.5)
    r = ((x - k * PIO2_HI) - k * PIO2_MID) - k * PIO2_LO
    z = r * r
    s = r + r * z * (
        -1.0 / 6.0
        + z
        * (
            1.0 / 120.0
            + z
            * (
                -1.0 / 5040.0
                + z
                * (
                    1.0 / 362880.0
                    + z
                    * (
                        -1.0 / 39916800.0
                        + z * (1.0 / 6227020800.0 + z * (-1.0 / 1307674368000.0))
                    )
                )
            )
        )
    )
    c = 1.0 + z * (
        -0.5
        + z
        * (
            1.0 / 24.0
            + z
            * (
                -1.0 / 720.0
                + z
                * (
                    1.0 / 40320.0
                    + z
                    * (
                        -1.0 / 3628800.0
                        + z
                        * (
                            1.0 / 479001600.0
                            + z * (-1.0 / 87178291200.0 + z * (1.0 / 20922789888000.0))
                        )
                    )
                )
            )
        )
    )
    q = np.int64(k)
    swap = (q & 1) != 0
    sin_x = c if swap else s
    cos_x = s if swap else c
    sin_x = -sin_x if (q & 2) != 0 else sin_x
    cos_x = -cos_x if ((q + 1) & 2) != 0 else cos_x
    return sin_x, cos_x


@helper(inline=True)
def atan_ratio(num, den):
    """atan(num / den) for 0 <= num <= den, den > 0, with one division."""
    high = num > TAN_PI_8 * den
    # atan(t) = pi/4 + atan((t - 1) / (t + 1)) brings t into |u| <= tan(pi/8)
    u = (num - den if high else num) / (num + den if high else den)
    s = u * u
    p = A11
    p = p * s + A10
    p = p * s + A9
    p = p * s + A8
    p = p * s + A7
    p = p * s + A6
    p = p * s + A5
    p = p * s + A4
    p = p * s + A3
    p = p * s + A2
    p = p * s + A1
    p = p * s + A0
    a = u * p
    return a + PIO4 if high else a


@helper(inline=True)
def atan2_pos(y, x):
    """atan2(y, x) for y >= 0 and x >= 0 (0 when both are 0)."""
    swap = y > x
    num = x if swap else y
    den = y if swap else x
    den = den if den > 0.0 else 1.0
    a = atan_ratio(num, den)
    return PIO2 - a if swap else a


@helper(inline=True)
def atan2(y, x):
    """atan2(y, x) with libm's signs, also for signed zeros."""
    a = atan2_pos(abs(y), abs(x))
    a = PI - a if math.copysign(1.0, x) < 0.0 else a
    return math.copysign(a, y)


@helper(inline=True)
def wrap_angle(angle):
    """Map an angle in [-2 pi, 2 pi] into [-pi, pi]."""
    if angle > PI:
        return angle - 2.0 * PI
    if angle < -PI:
        return angle + 2.0 * PI
    return angle
