"""The kernels under numba's bounds checking (issue 12, item 1).

Kernels are compiled without bounds checks for speed, so a read past the end
of an array returns whatever is in memory. ``NUMBA_BOUNDSCHECK=1`` compiles
every kernel with checks (a fresh ``NUMBA_CACHE_DIR``, so no unchecked build
is reused): the kernel test suite must pass that way, and public calls at the
smallest sizes must never read out of bounds.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from conftest import REPO

TESTS = REPO / "tests"  # the helpers (boundscheck_probe.py) by module name


@pytest.fixture(scope="module")
def checked_env(tmp_path_factory):
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    env["NUMBA_BOUNDSCHECK"] = "1"
    env["NUMBA_CACHE_DIR"] = str(tmp_path_factory.mktemp("numba-boundscheck"))
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), str(TESTS)])
    return env


# The chain kernel of angular velocity works in blocks and runs of rows, each
# with its own last row: its edge tests are where a bounds slip would show.
CHAIN_EDGE_TESTS = [
    "tests/core/test_velocity_chain.py::test_kernels_at_the_edges_of_blocks_and_runs",
    "tests/core/test_velocity_chain.py::test_a_missing_row_anywhere_is_reported",
]


# Both compile every kernel they reach under bounds checking into an empty cache
# (shared between them: the second compiles only what the first did not reach).
# Here (2 cores, 2.4 GHz) that took 130-255 s per test; CI's 2 GHz cores are slower.
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_kernel_tests_pass_with_boundscheck(checked_env):
    kernel_tests = sorted(str(p) for p in (TESTS / "core").glob("test_kernels_*.py"))
    assert kernel_tests, "no kernel tests found"
    kernel_tests += CHAIN_EDGE_TESTS
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
         # the first test to reach the SQUAD walk compiles it (~120 s here
         # while the walk was inlined into each kernel; without bounds checks
         # each walk kernel compiled in 116-201 s then, 58-67 s since)
         "-o", "addopts=", "-o", "timeout=600", *kernel_tests],
        cwd=REPO, env=checked_env, capture_output=True, text=True, timeout=1800,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert " passed" in done.stdout


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_public_calls_at_small_sizes_stay_in_bounds(checked_env):
    done = subprocess.run(
        [sys.executable, str(TESTS / "boundscheck_probe.py")],
        cwd=REPO, env=checked_env, capture_output=True, text=True, timeout=1800,
    )  # fmt: skip
    assert "checked" in done.stdout, done.stderr[-3000:]
    assert done.returncode == 0, done.stdout
