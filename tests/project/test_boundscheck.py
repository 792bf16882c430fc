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


def _checked_env(cache: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    env["NUMBA_BOUNDSCHECK"] = "1"
    env["NUMBA_CACHE_DIR"] = cache
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), str(TESTS)])
    return env


# The chain kernel of angular velocity works in blocks and runs of rows, each
# with its own last row: its edge tests are where a bounds slip would show.
CHAIN_EDGE_TESTS = [
    "tests/core/test_velocity_chain.py::test_kernels_at_the_edges_of_blocks_and_runs",
    "tests/core/test_velocity_chain.py::test_a_missing_row_anywhere_is_reported",
]


def _kernel_tests_command() -> list[str]:
    kernel_tests = sorted(str(p) for p in (TESTS / "core").glob("test_kernels_*.py"))
    assert kernel_tests, "no kernel tests found"
    return [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
            # the first test to reach the SQUAD walk compiles it (~120 s here
            # while the walk was inlined into each kernel; without bounds checks
            # each walk kernel compiled in 116-201 s then, 58-67 s since)
            "-o", "addopts=", "-o", "timeout=600", *kernel_tests, *CHAIN_EDGE_TESTS]  # fmt: skip


@pytest.fixture(scope="module")
def checked_runs(tmp_path_factory):
    """Both checked runs, started at once into one empty cache.

    Each compiles the kernels it reaches under bounds checking, one core each
    (numba compiles in one thread): run one after the other they took
    128 s + 65 s here; side by side the second no longer waits for the
    first, though both compile the kernels they share. numba writes cache
    files whole (a temporary file, then a rename), so two writers of the same
    kernel leave one valid entry.
    """
    folder = tmp_path_factory.mktemp("numba-boundscheck")
    env = _checked_env(str(folder / "cache"))
    commands = {
        "kernel tests": _kernel_tests_command(),
        "probe": [sys.executable, str(TESTS / "boundscheck_probe.py")],
    }
    # output goes to files: a pipe nobody reads while the other run is awaited
    # could fill and stall its writer
    runs = {}
    for name, command in commands.items():
        with (
            open(folder / f"{name}.out", "w") as out,
            open(folder / f"{name}.err", "w") as err,
        ):
            process = subprocess.Popen(
                command, cwd=REPO, env=env, stdout=out, stderr=err, text=True
            )
        runs[name] = (process, folder / f"{name}.out", folder / f"{name}.err")
    try:
        yield runs
    finally:
        for process, _, _ in runs.values():
            if process.poll() is None:
                process.kill()
            process.wait()


def _finish(run) -> tuple[int, str, str]:
    process, out, err = run
    try:
        process.wait(timeout=1800)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
    return process.returncode, out.read_text(), err.read_text()


# Both compile every kernel they reach under bounds checking into an empty cache.
# Here (2 cores, 2.4 GHz) that took 130-255 s per test run alone; CI's 2 GHz
# cores are slower.
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_kernel_tests_pass_with_boundscheck(checked_runs):
    returncode, stdout, stderr = _finish(checked_runs["kernel tests"])
    assert returncode == 0, stdout[-4000:] + stderr[-2000:]
    assert " passed" in stdout


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_public_calls_at_small_sizes_stay_in_bounds(checked_runs):
    returncode, stdout, stderr = _finish(checked_runs["probe"])
    assert "checked" in stdout, stderr[-3000:]
    assert returncode == 0, stdout
