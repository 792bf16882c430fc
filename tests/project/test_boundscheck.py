"""The kernels under numba's bounds checking (issue 12, item 1).

Kernels are compiled without bounds checks for speed, so a read past the end
of an array returns whatever is in memory. ``NUMBA_BOUNDSCHECK=1`` compiles
every kernel with checks (a fresh ``NUMBA_CACHE_DIR``, so no unchecked build
is reused): the kernel test suite must pass that way, and public calls at the
smallest sizes must never read out of bounds.
"""

from __future__ import annotations

import pytest

# The two checked runs (the kernel tests, the probe of public calls) are the
# session fixture ``checked_runs`` of head_start.py: they start with the
# session when these tests are selected, at low priority on the core the
# other tests leave idle, and are awaited here.


# Both compile every kernel they reach under bounds checking into an empty cache.
# Here (2 cores, 2.4 GHz) that took 130-255 s per test run alone; CI's 2 GHz
# cores are slower.
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_kernel_tests_pass_with_boundscheck(checked_runs):
    returncode, stdout, stderr = checked_runs["kernel tests"].finish(timeout=1800)
    assert returncode == 0, stdout[-4000:] + stderr[-2000:]
    assert " passed" in stdout


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_public_calls_at_small_sizes_stay_in_bounds(checked_runs):
    returncode, stdout, stderr = checked_runs["probe"].finish(timeout=1800)
    assert "checked" in stdout, stderr[-3000:]
    assert returncode == 0, stdout
