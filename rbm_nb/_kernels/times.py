"""Timestamps as the kernels take them: float64 seconds from an origin."""

from __future__ import annotations

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import RF1, RI1, I, kernel  # noqa: E741

__all__ = ["seconds_since", "ns_key_faults", "float_key_faults"]

_NAT = np.iinfo(np.int64).min


@kernel(RI1, options=EXACT_VECTOR_KERNEL)
def ns_key_faults(keys):
    """(NaT keys, keys not greater than their predecessor) of int64 keys."""
    n = keys.shape[0]
    nat = 0
    for i in range(n):
        nat += np.int64(keys[i] == _NAT)
    unordered = 0
    for i in range(n - 1):
        unordered += np.int64(keys[i + 1] <= keys[i])
    return nat, unordered


@kernel(RF1, options=EXACT_VECTOR_KERNEL)
def float_key_faults(keys):
    """(NaN or infinite keys, keys not greater than their predecessor)."""
    n = keys.shape[0]
    bad = 0
    for i in range(n):
        bad += np.int64(~(abs(keys[i]) < np.inf))
    unordered = 0
    for i in range(n - 1):
        unordered += np.int64(~(keys[i + 1] > keys[i]))
    return bad, unordered


@kernel(RI1, I)
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
