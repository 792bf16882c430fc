"""The one search of sorted sample times every kernel uses.

:func:`gallop` answers "which segment holds time t" for the interpolating
and holding kernels (``quaternion.search_right``, the fused chain, the squad
walk). Output times usually come sorted, so each search starts from the
previous answer and gallops forward: a row costs O(log(gap)) instead of a
full binary search, and a time that goes back restarts from the beginning
(then it is a plain binary search). The answer never depends on where the
search started, so rows may be evaluated in any order or in chunks.
"""

from __future__ import annotations

from ._jit import helper

__all__ = ["gallop"]


@helper(inline=True)
def gallop(times, t, i):
    """The segment of time t: i with times[i] <= t < times[i+1], -1 before, n-1 after.

    ``times`` strictly increasing; ``i`` the previous answer (-1 for none).
    Like ``np.searchsorted(times, t, "right") - 1``.
    """
    n = times.shape[0]
    if i >= 0 and t < times[i]:
        i = -1  # went back in time: restart from the beginning
    # gallop: find hi with t < times[hi] (or hi == n)
    lo = i
    step = 1
    hi = i + 1
    while hi < n and times[hi] <= t:
        lo = hi
        hi = i + 1 + step
        step *= 2
    if hi > n:
        hi = n
    # invariant: times[lo] <= t (or lo == -1) and t < times[hi] (or hi == n)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if times[mid] <= t:
            lo = mid
        else:
            hi = mid
    return lo
