"""Timestamps as the kernels take them: float64 seconds from an origin."""

from __future__ import annotations

import numpy as np

from ._jit import I1, I, kernel  # noqa: E741

__all__ = ["seconds_since"]


@kernel(I1, I)
def seconds_since(keys, origin):
    """int64 nanosecond keys as float64 seconds since ``origin`` (NaT -> NaN).

    ``(key - origin) / 1e9`` as numpy computes it, in one pass over the
    keys (numpy takes four: subtract, divide, isnat, where).
    """
    n = keys.shape[0]
    out = np.empty(n)
    nat = np.iinfo(np.int64).min
    for i in range(n):
        k = keys[i]
        out[i] = np.nan if k == nat else (k - origin) / 1e9
    return out
