"""The split's deviations are computed a chunk of points at a time (issue 35).

``_kernels.simplify`` reads a long segment :data:`CHUNK` points at a time
(its scratch stays in the cache); what it keeps is still what the former
numpy loop kept, bit for bit, on segments many chunks long, with the
farthest point in any chunk, ties across chunks and NaN-free runs.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_path_simplify_kernel import _same, _walk

from rbm_nb._kernels.simplify import CHUNK


@pytest.mark.parametrize("kind", ["walk", "grid", "mixed"])
def test_segments_many_chunks_long_keep_what_numpy_kept(kind):
    rng = np.random.default_rng(36)
    for n in (CHUNK + 2, CHUNK * 3 + 1, CHUNK * 7 + 5, 40_000):
        samples = _walk(rng, n, kind)
        for max_points in (3, 50, 2000):
            for tolerance in (None, 1e-2):
                _same(samples, tolerance, max_points)


def test_equal_farthest_points_in_two_chunks_split_at_the_first():
    # a flat line with two equally far teeth, chunks apart
    n = CHUNK * 3
    line = np.zeros((n, 3))
    line[:, 0] = np.arange(n)
    line[CHUNK + 10, 1] = 5.0
    line[2 * CHUNK + 20, 1] = 5.0
    assert _same(line, 0.0, 3) == 3
