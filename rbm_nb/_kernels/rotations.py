"""Quaternion kernels for the public utilities: numba, unchecked.

The algebra itself lives in :mod:`rbm_nb._kernels.quaternion`; the kernels here
add what the validated public functions need in the same pass over the data
(the index of the first zero quaternion, so that rejecting bad input costs no
second sweep), plus sign continuity and the rotation-vector convention of
numpy-quaternion that the velocity estimators reproduce.

Quaternions are float64 (n, 4) arrays in ``w, x, y, z`` order, vectors (n, 3),
both C-contiguous; where two operands are given their first dimensions are
equal or one of them is 1.
"""

from __future__ import annotations

import numpy as np

from ._jit import F2, kernel
from .quaternion import _qinv1, _qlog1, _rotate1


@kernel(F2, F2)
def rotate_vectors_checked(q, v):
    """q v q⁻¹ row by row, and the first row whose quaternion is zero.

    Parameters
    ----------
    q : ndarray, shape (n, 4) or (1, 4)
    v : ndarray, shape (n, 3) or (1, 3)

    Returns
    -------
    out : ndarray, shape (n, 3)
        NaN in rows rotated by a zero quaternion.
    zero_idx : int
        Index (into ``q``) of the first zero quaternion, or -1.
    """
    n = 0 if q.shape[0] == 0 or v.shape[0] == 0 else max(q.shape[0], v.shape[0])
    sq = 1 if q.shape[0] > 1 else 0
    sv = 1 if v.shape[0] > 1 else 0
    out = np.empty((n, 3))
    zero_idx = -1
    for i in range(n):
        a = i * sq
        b = i * sv
        w, x, y, z = q[a, 0], q[a, 1], q[a, 2], q[a, 3]
        if w == 0.0 and x == 0.0 and y == 0.0 and z == 0.0:
            # numba raises on division by zero; the caller reports the row
            if zero_idx < 0:
                zero_idx = a
            out[i, 0] = out[i, 1] = out[i, 2] = np.nan
            continue
        rx, ry, rz = _rotate1(w, x, y, z, v[b, 0], v[b, 1], v[b, 2])
        out[i, 0] = rx
        out[i, 1] = ry
        out[i, 2] = rz
    return out, zero_idx


@kernel(F2)
def qinv_checked(q):
    """conj(q) / |q|² row by row, and the first row that is zero (or -1).

    Parameters
    ----------
    q : ndarray, shape (n, 4)

    Returns
    -------
    out : ndarray, shape (n, 4)
        NaN in zero rows.
    zero_idx : int
    """
    n = q.shape[0]
    out = np.empty((n, 4))
    zero_idx = -1
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        if w == 0.0 and x == 0.0 and y == 0.0 and z == 0.0:
            if zero_idx < 0:
                zero_idx = i
            out[i, 0] = out[i, 1] = out[i, 2] = out[i, 3] = np.nan
            continue
        iw, ix, iy, iz = _qinv1(w, x, y, z)
        out[i, 0] = iw
        out[i, 1] = ix
        out[i, 2] = iy
        out[i, 3] = iz
    return out, zero_idx


@kernel(F2)
def first_zero_row(q):
    """Index of the first all-zero row of ``q`` (n, k), or -1."""
    for i in range(q.shape[0]):
        zero = True
        for j in range(q.shape[1]):
            if q[i, j] != 0.0:
                zero = False
                break
        if zero:
            return i
    return -1


@kernel(F2)
def rotation_vectors(q):
    """2 log(q), vector part: numpy-quaternion's ``as_rotation_vector``.

    Unlike a shortest-angle conversion this keeps the sign of ``q``: a
    quaternion with w < 0 maps to an angle beyond pi. For a sign-continuous
    series the result is then continuous too, which is what differentiating
    it requires.

    Parameters
    ----------
    q : ndarray, shape (n, 4)

    Returns
    -------
    ndarray, shape (n, 3)
    """
    n = q.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        _, x, y, z = _qlog1(q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        out[i, 0] = 2.0 * x
        out[i, 1] = 2.0 * y
        out[i, 2] = 2.0 * z
    return out
