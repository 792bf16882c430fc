"""Large arrays start on a huge page boundary (rbm_nb._infra.memory)."""

from __future__ import annotations

import numpy as np
import pytest

from rbm_nb._infra import memory as _memory


@pytest.mark.parametrize(
    "shape", [(10, 15), (40_000, 15), (300_001, 15), (1_000_000, 3)]
)
def test_arrays_are_numpys_and_large_ones_start_on_a_huge_page(shape):
    a = _memory.zeros(shape)
    assert a.shape == shape and a.dtype == np.float64
    assert a.flags.c_contiguous and a.flags.writeable and a.flags.aligned
    assert not a.any()
    if a.nbytes >= _memory.ADVISED:
        assert a.ctypes.data % _memory.HUGE_PAGE == 0
    a[...] = 1.0  # every element is inside the allocation
    assert a.sum() == a.size


def test_squad_tables_are_aligned():
    from rbm_nb._engine import fused as _fused

    assert _fused._Table(300_000).rows.ctypes.data % _memory.HUGE_PAGE == 0
