"""Large result arrays start on a huge page boundary (rbm_nb._memory)."""

from __future__ import annotations

import numpy as np
import pytest

from rbm_nb import _memory


@pytest.mark.parametrize("make", [_memory.empty, _memory.zeros])
@pytest.mark.parametrize(
    "shape", [(10, 15), (40_000, 15), (300_001, 15), (1_000_000, 3)]
)
def test_arrays_are_numpys_and_large_ones_start_on_a_huge_page(make, shape):
    a = make(shape)
    assert a.shape == shape and a.dtype == np.float64
    assert a.flags.c_contiguous and a.flags.writeable and a.flags.aligned
    if make is _memory.zeros:
        assert not a.any()
    if a.nbytes >= _memory.ADVISED:
        assert a.ctypes.data % _memory.HUGE_PAGE == 0
    a[...] = 1.0  # every element is inside the allocation
    assert a.sum() == a.size


def test_squad_tables_and_rotated_vectors_are_aligned():
    import rbm_nb as rbm
    from rbm_nb._engine import fused as _fused

    assert _fused._Table(300_000).rows.ctypes.data % _memory.HUGE_PAGE == 0
    q = np.tile([1.0, 0.0, 0.0, 0.0], (300_000, 1))
    out = rbm.rotate_vectors(q, np.ones((300_000, 3)))
    assert out.ctypes.data % _memory.HUGE_PAGE == 0
    np.testing.assert_array_equal(out, 1.0)
