"""The prefetch hints reach the compiled code and change nothing else."""

from __future__ import annotations

import numpy as np
from numba import njit

from rbm_nb._kernels._prefetch import prefetch, prefetch_for_write


@njit
def _copy_with_hints(src, dst, ahead):
    flat = dst.reshape(-1)
    for k in range(flat.shape[0]):
        prefetch(src, k + ahead)  # past the end too: a hint never faults
        prefetch_for_write(dst, k + ahead)
        flat[k] = src.reshape(-1)[k] * 2.0


def test_hints_leave_the_data_alone_even_past_the_end():
    src = np.arange(40.0).reshape(10, 4)
    dst = np.zeros_like(src)
    _copy_with_hints(src, dst, 10_000)
    assert np.array_equal(dst, 2.0 * src)
    assert np.array_equal(src, np.arange(40.0).reshape(10, 4))


def test_hints_are_llvm_prefetches_for_read_and_for_write():
    src = np.arange(8.0)
    _copy_with_hints(src, np.zeros(8), 4)
    ir = _copy_with_hints.inspect_llvm(_copy_with_hints.signatures[0])
    calls = [line for line in ir.splitlines() if "call void @llvm.prefetch" in line]
    # rw flag 0 (read) and 1 (write), locality 3, data cache
    assert any(", i32 0, i32 3, i32 1)" in line for line in calls), calls
    assert any(", i32 1, i32 3, i32 1)" in line for line in calls), calls
