"""Derivatives of sampled time series: numba kernels, unchecked.

Conventions shared by every kernel here:

* time runs along axis 0; ``t`` is a float64 array of shape (n,), strictly
  increasing, in seconds; values are C-contiguous float64 arrays (n, k) or,
  where several independent series share the time base, (n, b, k);
* nothing is validated: the public modules (``rbm_nb.estimators``) check
  lengths, ordering and finiteness first.

Two derivative schemes are provided because the reference package uses both:
``gradient`` is numpy's second-order scheme for uneven spacing (used for
positions and rotation vectors), ``spline_derivative`` differentiates the
not-a-knot cubic interpolating spline (what numpy-quaternion's ``derivative``
evaluates through FITPACK, used for quaternions).
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import B2, F1, F2, F3, helper, kernel


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _weights(t0, t1, t2):
    """numpy.gradient's three-point weights at t1, between t0 and t2."""
    h1 = t1 - t0
    h2 = t2 - t1
    a = -h2 / (h1 * (h1 + h2))
    b = (h2 - h1) / (h1 * h2)
    c = h1 / (h2 * (h1 + h2))
    return a, b, c


@kernel(F2, F1, options=EXACT_VECTOR_KERNEL)
def gradient(f, t):
    """First derivative by central differences on uneven spacing (numpy's).

    Interior samples use the second-order three-point formula of
    ``numpy.gradient``; the two end samples use one-sided first differences.

    Parameters
    ----------
    f : ndarray, shape (n, k), n >= 2
    t : ndarray, shape (n,)

    Returns
    -------
    ndarray, shape (n, k)
    """
    n, k = f.shape
    out = np.empty((n, k))
    h0 = t[1] - t[0]
    hn = t[n - 1] - t[n - 2]
    for j in range(k):
        out[0, j] = (f[1, j] - f[0, j]) / h0
        out[n - 1, j] = (f[n - 1, j] - f[n - 2, j]) / hn
    # flat views with constant strides: numba indexes 2-D rows with a
    # runtime stride, which keeps LLVM from vectorising the loop over rows
    ff = f.reshape(-1)
    of = out.reshape(-1)
    # (loop counters from 0: LLVM vectorises only loops whose indices it
    # can bound, and numba's negative-index wraparound hides that otherwise)
    if k == 3:
        for r in range(n - 2):
            a, b, c = _weights(t[r], t[r + 1], t[r + 2])
            x0, y0, z0 = ff[3 * r], ff[3 * r + 1], ff[3 * r + 2]
            x1, y1, z1 = ff[3 * r + 3], ff[3 * r + 4], ff[3 * r + 5]
            x2, y2, z2 = ff[3 * r + 6], ff[3 * r + 7], ff[3 * r + 8]
            of[3 * r + 3] = a * x0 + b * x1 + c * x2
            of[3 * r + 4] = a * y0 + b * y1 + c * y2
            of[3 * r + 5] = a * z0 + b * z1 + c * z2
        return out
    for r in range(n - 2):
        a, b, c = _weights(t[r], t[r + 1], t[r + 2])
        for j in range(k):
            of[(r + 1) * k + j] = (
                a * ff[r * k + j] + b * ff[(r + 1) * k + j] + c * ff[(r + 2) * k + j]
            )
    return out


@kernel(F2, F1)
def spline_derivative(f, t):
    """Slopes at the samples of the not-a-knot cubic interpolating spline.

    With four or more samples this is the cubic spline whose third derivative
    is continuous at the second and the second-to-last sample (FITPACK's
    interpolating spline, scipy's ``CubicSpline`` default). Three samples give
    the interpolating parabola, two the straight line.

    Parameters
    ----------
    f : ndarray, shape (n, k), n >= 2
    t : ndarray, shape (n,)

    Returns
    -------
    ndarray, shape (n, k)
    """
    n, k = f.shape
    out = np.empty((n, k))
    h = np.empty(n - 1)
    for i in range(n - 1):
        h[i] = t[i + 1] - t[i]
    # secant slopes, reused by every row below
    d = np.empty((n - 1, k))
    for i in range(n - 1):
        inv = 1.0 / h[i]
        for j in range(k):
            d[i, j] = (f[i + 1, j] - f[i, j]) * inv
    if n == 2:
        for j in range(k):
            out[0, j] = d[0, j]
            out[1, j] = d[0, j]
        return out
    if n == 3:
        for j in range(k):
            mid = (h[1] * d[0, j] + h[0] * d[1, j]) / (h[0] + h[1])
            curv = 2.0 * (d[1, j] - d[0, j]) / (h[0] + h[1])
            out[0, j] = mid - curv * h[0]
            out[1, j] = mid
            out[2, j] = mid + curv * h[1]
        return out

    # Unknowns are the slopes s[0..n-1]. Continuity of the second derivative
    # at every interior sample gives the tridiagonal rows 1..n-2; the two
    # not-a-knot conditions are substituted into rows 1 and n-2, which leaves
    # a strictly diagonally dominant system in s[1..n-2] (safe for Thomas'
    # algorithm without pivoting); s[0] and s[n-1] follow at the end.
    d_start = h[0] + h[1]
    d_end = h[n - 2] + h[n - 3]
    r_start = np.empty(k)
    r_end = np.empty(k)
    for j in range(k):
        r_start[j] = (
            (h[0] + 2.0 * d_start) * h[1] * d[0, j] + h[0] * h[0] * d[1, j]
        ) / d_start
        r_end[j] = (
            h[n - 2] * h[n - 2] * d[n - 3, j]
            + (2.0 * d_end + h[n - 2]) * h[n - 3] * d[n - 2, j]
        ) / d_end
    # forward sweep; out[i] holds the eliminated right-hand side of row i
    cp = np.empty(n)
    prev_cp = 0.0
    for i in range(1, n - 1):
        sub = h[i]
        diag = 2.0 * (h[i - 1] + h[i])
        if i == 1:
            diag = d_start
            sub = 0.0
        if i == n - 2:
            diag = d_end
        inv = 1.0 / (diag - sub * prev_cp)
        cp[i] = h[i - 1] * inv
        for j in range(k):
            rhs = 3.0 * (h[i] * d[i - 1, j] + h[i - 1] * d[i, j])
            if i == 1:
                rhs -= r_start[j]
            if i == n - 2:
                rhs -= r_end[j]
            if i > 1:
                rhs -= sub * out[i - 1, j]
            out[i, j] = rhs * inv
        prev_cp = cp[i]
    # back substitution
    for i in range(n - 3, 0, -1):
        for j in range(k):
            out[i, j] -= cp[i] * out[i + 1, j]
    for j in range(k):
        out[0, j] = (r_start[j] - d_start * out[1, j]) / h[1]
        out[n - 1, j] = (r_end[j] - d_end * out[n - 2, j]) / h[n - 3]
    return out


@kernel(F2)
def nan_rows(x):
    """Whether each row of ``x`` (n, k) contains a NaN, shape (n,)."""
    n, k = x.shape
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        for j in range(k):
            if math.isnan(x[i, j]):
                out[i] = True
                break
    return out


@kernel(F3)
def second_difference_score(x):
    """Outlier score of each sample from second-order differences.

    ``d[i]`` is the norm of ``x[i+2] - 2 x[i+1] + x[i]`` over the last axis;
    sample i scores ``d[i] + d[i-1]`` (missing terms count as zero), the
    window the reference package uses, so the first sample is judged by the
    difference centred on its successor and the last sample always scores 0.

    Parameters
    ----------
    x : ndarray, shape (n, b, k)

    Returns
    -------
    ndarray, shape (n, b)
        NaN where a difference involves a NaN sample.
    """
    n, nb, k = x.shape
    out = np.zeros((n, nb))
    for i in range(n - 2):
        for b in range(nb):
            acc = 0.0
            for j in range(k):
                d = x[i + 2, b, j] - 2.0 * x[i + 1, b, j] + x[i, b, j]
                acc += d * d
            d = math.sqrt(acc)
            out[i, b] += d
            out[i + 1, b] += d
    return out


@kernel(F1, F3, B2)
def interpolate_rejected(t, values, keep):
    """Replace rejected samples by linear interpolation between kept ones.

    Parameters
    ----------
    t : ndarray, shape (n,)
    values : ndarray, shape (n, b, k)
    keep : ndarray of bool, shape (n, b)

    Returns
    -------
    ndarray, shape (n, b, k)
        Kept samples unchanged; rejected samples interpolated from the nearest
        kept samples before and after them, NaN where there is none on one side.
    """
    n, nb, k = values.shape
    out = np.empty((n, nb, k))
    for b in range(nb):
        prev = -1
        i = 0
        while i < n:
            if keep[i, b]:
                for j in range(k):
                    out[i, b, j] = values[i, b, j]
                prev = i
                i += 1
                continue
            # run of rejected samples i..nxt-1
            nxt = i
            while nxt < n and not keep[nxt, b]:
                nxt += 1
            for r in range(i, nxt):
                if prev < 0 or nxt >= n:
                    for j in range(k):
                        out[r, b, j] = np.nan
                else:
                    w = (t[r] - t[prev]) / (t[nxt] - t[prev])
                    for j in range(k):
                        out[r, b, j] = values[prev, b, j] + w * (
                            values[nxt, b, j] - values[prev, b, j]
                        )
            i = nxt
    return out


@kernel(F2, F2)
def angular_velocity_from_derivative(q, dq):
    """Angular velocity as the vector part of 2 q⁻¹ dq/dt.

    Dividing by |q|² instead of assuming unit norm makes the result
    independent of the quaternions' scale: for q = s u with unit u,
    q⁻¹ dq = ds/s + u* du, and the scalar ds/s is discarded.

    Parameters
    ----------
    q, dq : ndarray, shape (n, 4)
        Quaternions (w, x, y, z) and their time derivatives.

    Returns
    -------
    ndarray, shape (n, 3)
    """
    n = q.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        dw, dx, dy, dz = dq[i, 0], dq[i, 1], dq[i, 2], dq[i, 3]
        f = 2.0 / (w * w + x * x + y * y + z * z)
        # vector part of conj(q) * dq = w dv - dw v - v x dv
        out[i, 0] = f * (w * dx - dw * x - (y * dz - z * dy))
        out[i, 1] = f * (w * dy - dw * y - (z * dx - x * dz))
        out[i, 2] = f * (w * dz - dw * z - (x * dy - y * dx))
    return out
