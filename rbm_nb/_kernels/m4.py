"""The rows a plot's min/max (M4) decimation keeps, in one pass per column.

:func:`rbm_nb.widgets._decimate.m4_rows` keeps, per pixel column, each
component's first minimum and first maximum row and its first missing row.
Found with numpy that took, per component, a filled copy, two ``reduceat``,
a ``repeat`` and a comparison of every row (a fifth of the explorer's plot
build at 3 h); :func:`column_extremes` reads each row once.
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F2, I1, kernel


@kernel(F2, I1, options=EXACT_VECTOR_KERNEL)
def column_extremes(y, starts):
    """Per column (rows from each of ``starts`` to the next), per component
    of ``y`` (n, k): the first row of its minimum, of its maximum (missing
    values count as +inf for the minimum and -inf for the maximum, so an
    all-missing column gives its first row) and its first missing row.

    Returns
    -------
    ndarray of int64, shape (columns, 3 k)
        The rows, -1 where a column has no missing row.
    """
    n, k = y.shape
    columns = starts.shape[0]
    out = np.empty((columns, 3 * k), dtype=np.int64)
    for j in range(columns):
        a = starts[j]
        b = starts[j + 1] if j + 1 < columns else n
        for c in range(k):
            low, high = math.inf, -math.inf
            low_at = high_at = a
            missing_at = -1
            for i in range(a, b):
                v = y[i, c]
                if v != v:
                    if missing_at < 0:
                        missing_at = i
                    continue
                if v < low:
                    low, low_at = v, i
                if v > high:
                    high, high_at = v, i
            out[j, 3 * c] = low_at
            out[j, 3 * c + 1] = high_at
            out[j, 3 * c + 2] = missing_at
    return out
