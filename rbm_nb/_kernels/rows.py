"""Validation of sample rows in one pass (frames' data at registration).

The numpy versions in :mod:`rbm_nb._validation` make several temporaries
per check (``isnan``, ``isinf``, ``any``/``all`` along rows, norms); for
recordings of 1e5-1e7 samples those passes dominate registering a frame.
These kernels answer "is every row fine?" in one pass without
temporaries; only when the answer is no does the caller run the numpy
version, which names the offending row in its error.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._config import KERNEL
from ._jit import F1, F2, B, F, helper, kernel

# Branch-free passes that LLVM vectorises (division without a
# ZeroDivisionError branch; no fused multiply-add, so that results stay those
# of the plain arithmetic bit for bit).
_COUNTING = dataclasses.replace(KERNEL, error_model="numpy")


@kernel(F1, options=_COUNTING)
def infinities(f):
    """How many values of ``f`` are infinite (one vectorised pass)."""
    count = 0
    for i in range(f.shape[0]):
        count += np.int64(abs(f[i]) == np.inf)
    return count


@helper(inline=True)
def _first_bad_row_scalar(a):
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


@kernel(F2, options=_COUNTING)
def first_bad_row(a):
    """The first row of (n, k) ``a`` that is partly NaN or holds an infinity.

    Rows entirely NaN (missing samples) and finite rows are fine. For k of 3
    or 4 a vectorised pass counts the bad rows first (flat, constant-stride
    indexing), and only when there is one does a second pass find it.

    Returns
    -------
    int
        Its index, or -1 if every row is fine.
    """
    n, k = a.shape
    if k != 3 and k != 4:
        return _first_bad_row_scalar(a)
    f = a.reshape(-1)
    bad = 0
    if k == 3:
        for i in range(n):
            x, y, z = f[3 * i], f[3 * i + 1], f[3 * i + 2]
            nan = (x != x) + (y != y) + (z != z)
            inf = (abs(x) == np.inf) + (abs(y) == np.inf) + (abs(z) == np.inf)
            bad += ((nan != 0) & (nan != 3)) | (inf != 0)
    else:
        for i in range(n):
            w, x, y, z = f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]
            nan = (w != w) + (x != x) + (y != y) + (z != z)
            inf = (abs(w) == np.inf) + (abs(x) == np.inf) + (abs(y) == np.inf)
            inf += abs(z) == np.inf
            bad += ((nan != 0) & (nan != 4)) | (inf != 0)
    return -1 if bad == 0 else _first_bad_row_scalar(a)


@helper(inline=True)
def _first_unacceptable(q, tol, allow_nan):
    for i in range(q.shape[0]):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        if math.isinf(w) or math.isinf(x) or math.isinf(y) or math.isinf(z):
            return i
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if math.isnan(norm):
            if not allow_nan:
                return i
        elif abs(norm - 1.0) > tol:
            return i
    return -1


@kernel(F2, F, B, options=_COUNTING)
def unit_rows(q, tol, allow_nan):
    """Quaternions (n, 4) divided by their norms, if every row is acceptable.

    A row is acceptable if its norm is within ``tol`` of 1, or (with
    ``allow_nan``) if it contains NaN and no infinity. One vectorised pass
    normalises every row and counts the unacceptable ones; only when there
    is one does a second pass find the first.

    Returns
    -------
    out : ndarray, shape (n, 4)
        Rows divided by their norms (rows of norm exactly 1 and NaN rows
        copied as they are); not meaningful when ``bad`` >= 0.
    bad : int
        The first row that is not acceptable, or -1.
    """
    n = q.shape[0]
    out = np.empty((n, 4))
    f = q.reshape(-1)
    o = out.reshape(-1)
    count = 0
    for i in range(n):
        w, x, y, z = f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        inf = (abs(w) == np.inf) | (abs(x) == np.inf) | (abs(y) == np.inf)
        inf |= abs(z) == np.inf
        nan = norm != norm
        count += inf | (nan & (not allow_nan)) | (abs(norm - 1.0) > tol)
        # rows of norm 1 and NaN rows as they are (x / 1.0 is x)
        d = 1.0 if (norm == 1.0) | nan else norm
        o[4 * i] = w / d
        o[4 * i + 1] = x / d
        o[4 * i + 2] = y / d
        o[4 * i + 3] = z / d
    return out, -1 if count == 0 else _first_unacceptable(q, tol, allow_nan)
