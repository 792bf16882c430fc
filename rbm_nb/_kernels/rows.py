"""Validation of sample rows in one pass (frames' data at registration).

The numpy versions in :mod:`rbm_nb._validation` make several temporaries
per check (``isnan``, ``isinf``, ``any``/``all`` along rows, norms); for
recordings of 1e5-1e7 samples those passes dominate registering a frame.
These kernels answer "is every row fine?" in one pass without
temporaries; only when the answer is no does the caller run the numpy
version, which names the offending row in its error.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import F2, B, F, kernel


@kernel(F2)
def first_bad_row(a):
    """The first row of (n, k) ``a`` that is partly NaN or holds an infinity.

    Rows entirely NaN (missing samples) and finite rows are fine.

    Returns
    -------
    int
        Its index, or -1 if every row is fine.
    """
    n, k = a.shape
    for i in range(n):
        nan = 0
        for j in range(k):
            v = a[i, j]
            if math.isnan(v):
                nan += 1
            elif math.isinf(v):
                return i
        if nan != 0 and nan != k:
            return i
    return -1


@kernel(F2, F, B)
def unit_rows(q, tol, allow_nan):
    """Quaternions (n, 4) divided by their norms, if every row is acceptable.

    A row is acceptable if its norm is within ``tol`` of 1, or (with
    ``allow_nan``) if it contains NaN and no infinity.

    Returns
    -------
    out : ndarray, shape (n, 4)
        Rows divided by their norms (rows of norm exactly 1 and NaN rows
        copied as they are).
    bad : int
        The first row that is not acceptable (then ``out`` is incomplete),
        or -1.
    """
    n = q.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        if math.isinf(w) or math.isinf(x) or math.isinf(y) or math.isinf(z):
            return out, i
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if math.isnan(norm):
            if not allow_nan:
                return out, i
        elif abs(norm - 1.0) > tol:
            return out, i
        elif norm != 1.0:
            w, x, y, z = w / norm, x / norm, y / norm, z / norm
        out[i, 0] = w
        out[i, 1] = x
        out[i, 2] = y
        out[i, 3] = z
    return out, -1
