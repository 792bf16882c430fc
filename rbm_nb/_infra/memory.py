"""Large arrays that start on a transparent huge page boundary.

numpy advises the kernel to back arrays of 4 MB or more with 2 MB huge pages
(``MADV_HUGEPAGE``), so that writing a fresh array takes a few huge page
faults instead of one fault per 4 kB page. The advice covers only the whole
2 MB pages inside the allocation, and ``malloc`` hands back addresses 16
bytes past a 4 kB page: the array's unaligned ends are still faulted in 4 kB
pages, up to 1,022 of them. Starting the array on a 2 MB boundary (the
allocation is 2 MB longer; its untouched head costs no memory) leaves none.
Measured on the 2-core VM, where a fault costs 1-2 µs: the first lookup of
the head/eye chain took 1,434 page faults in all, 608 once its squad table
(8 MB) was aligned (8.4 -> 6.9 ms).

The price is up to 2 MB of address space per array, never touched (so
never memory), but counted by allocation tracers: used for the squad
tables, which live as long as their frames, and not for results, whose
callers measure their allocations (tests/core/test_array_door_memory.py).
"""

from __future__ import annotations

import numpy as np

__all__ = ["HUGE_PAGE", "ADVISED", "zeros"]

HUGE_PAGE = 2 << 20
#: numpy's threshold for the huge page advice
ADVISED = 4 << 20


def zeros(shape: tuple[int, ...]) -> np.ndarray:
    """``np.zeros(shape)`` (float64, C order), huge page aligned when large.

    Large ones come zeroed from the allocator (fresh pages of an mmap: none
    of them touched until used).
    """
    nbytes = 8 * int(np.prod(shape))
    if nbytes < ADVISED:
        return np.zeros(shape)
    raw = np.zeros(nbytes + HUGE_PAGE, dtype=np.uint8)
    start = -raw.ctypes.data % HUGE_PAGE
    return raw[start : start + nbytes].view(np.float64).reshape(shape)
