"""Angular velocity of a stored rotation series in one kernel: numba, unchecked.

:func:`body_rates` gives what ``unflip`` → ``spline_derivative`` →
``angular_velocity_from_derivative`` (:mod:`rbm_nb._kernels.differences`)
give together for a series without missing samples, with the same
arithmetic in the same order, but without their intermediate (n, 4) arrays:
the sign-continuous samples and their secant slopes are formed when the
tridiagonal sweep reaches them, and the slopes are kept in the result's
own rows (x, y, z) and one (n,) column (w) until each row's rate is
written over them. Besides the result: 17 bytes per sample.

Quaternions are float64 (n, 4) arrays in ``w, x, y, z`` order.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import F1, F2, kernel

__all__ = ["body_rates"]


@kernel(F2, F1)
def body_rates(q, t):
    """Vector part of 2 q⁻¹ dq/dt of the not-a-knot spline through ``q``.

    Parameters
    ----------
    q : ndarray, shape (n, 4), n >= 4
        Stored quaternions; sign flips between samples are undone first.
    t : ndarray, shape (n,)
        Strictly increasing times.

    Returns
    -------
    out : ndarray, shape (n, 3)
        Incomplete if ``bad`` is not 0.
    bad : int
        0, or 1 if a row holds NaN or is zero (the caller then takes the
        step-by-step path, which handles both).
    """
    n = q.shape[0]
    out = np.empty((n, 3))
    sign = np.empty(n, dtype=np.int8)  # ±1 (a byte: less memory than a float64)
    # unflip's signs; missing or zero samples send the caller elsewhere
    pw = px = py = pz = 0.0
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        n2 = w * w + x * x + y * y + z * z
        if math.isnan(n2) or n2 == 0.0:
            return out, 1
        flip = i > 0 and (pw * w + px * x + py * y + pz * z) < 0.0
        s = -1.0 if flip else 1.0
        sign[i] = -1 if flip else 1
        pw, px, py, pz = s * w, s * x, s * y, s * z
    # the slopes: spline_derivative's rows, secants formed as they are needed;
    # their x, y, z in ``out`` until the last pass writes the rates over
    # them, w in a column of its own (no (n, 4) array)
    slope_w = np.empty(n)
    cp = np.empty(n)
    h0 = t[1] - t[0]
    h1 = t[2] - t[1]
    hm = t[n - 1] - t[n - 2]  # h[n-2]
    hm1 = t[n - 2] - t[n - 3]  # h[n-3]
    d_start = h0 + h1
    d_end = hm + hm1
    inv0 = 1.0 / h0
    inv1 = 1.0 / h1
    invm = 1.0 / hm
    invm1 = 1.0 / hm1
    r_start = np.empty(4)
    r_end = np.empty(4)
    for j in range(4):
        da = (sign[1] * q[1, j] - sign[0] * q[0, j]) * inv0
        db = (sign[2] * q[2, j] - sign[1] * q[1, j]) * inv1
        r_start[j] = ((h0 + 2.0 * d_start) * h1 * da + h0 * h0 * db) / d_start
        dc = (sign[n - 2] * q[n - 2, j] - sign[n - 3] * q[n - 3, j]) * invm1
        dd = (sign[n - 1] * q[n - 1, j] - sign[n - 2] * q[n - 2, j]) * invm
        r_end[j] = (hm * hm * dc + (2.0 * d_end + hm) * hm1 * dd) / d_end
    prev_cp = 0.0
    for i in range(1, n - 1):
        h_prev = t[i] - t[i - 1]
        h_i = t[i + 1] - t[i]
        sub = h_i
        diag = 2.0 * (h_prev + h_i)
        if i == 1:
            diag = d_start
            sub = 0.0
        if i == n - 2:
            diag = d_end
        inv = 1.0 / (diag - sub * prev_cp)
        cp[i] = h_prev * inv
        inv_prev = 1.0 / h_prev
        inv_i = 1.0 / h_i
        for j in range(4):
            a = sign[i - 1] * q[i - 1, j]
            b = sign[i] * q[i, j]
            c = sign[i + 1] * q[i + 1, j]
            rhs = 3.0 * (h_i * ((b - a) * inv_prev) + h_prev * ((c - b) * inv_i))
            if i == 1:
                rhs -= r_start[j]
            if i == n - 2:
                rhs -= r_end[j]
            if i > 1:
                rhs -= sub * (slope_w[i - 1] if j == 0 else out[i - 1, j - 1])
            if j == 0:
                slope_w[i] = rhs * inv
            else:
                out[i, j - 1] = rhs * inv
        prev_cp = cp[i]
    # back substitution
    for i in range(n - 3, 0, -1):
        slope_w[i] -= cp[i] * slope_w[i + 1]
        for j in range(3):
            out[i, j] -= cp[i] * out[i + 1, j]
    slope_w[0] = (r_start[0] - d_start * slope_w[1]) / h1
    slope_w[n - 1] = (r_end[0] - d_end * slope_w[n - 2]) / hm1
    for j in range(3):
        out[0, j] = (r_start[j + 1] - d_start * out[1, j]) / h1
        out[n - 1, j] = (r_end[j + 1] - d_end * out[n - 2, j]) / hm1
    # angular_velocity_from_derivative, row by row (each row's slopes are
    # read before its result is written over them)
    for i in range(n):
        s = sign[i]
        w, x, y, z = s * q[i, 0], s * q[i, 1], s * q[i, 2], s * q[i, 3]
        dw, dx, dy, dz = slope_w[i], out[i, 0], out[i, 1], out[i, 2]
        f = 2.0 / (w * w + x * x + y * y + z * z)
        out[i, 0] = f * (w * dx - dw * x - (y * dz - z * dy))
        out[i, 1] = f * (w * dy - dw * y - (z * dx - x * dz))
        out[i, 2] = f * (w * dz - dw * z - (x * dy - y * dx))
    return out, 0
