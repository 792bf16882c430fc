"""Slow subprocess checks that start with the session and are awaited by their tests.

pytest runs one test at a time in one process, so for most of a session one
of CI's two cores is idle: the frame core's tests use one, and the browser
tests mostly wait on chromium and on kernels. The checks here spend minutes
in subprocesses that need nothing from the tests before them: the kernel
tests compiled under ``NUMBA_BOUNDSCHECK`` (``checked_runs``, awaited by
``tests/project/test_boundscheck.py``) and the wheel, the sdist, a fresh
venv and the sdist's own fast tests (``packaging_runs``, awaited by
``tests/project/test_packaging.py``) and the explorer's kernels compiled
in three orders (``explorer_compiles`` of compile_order.py, awaited by
``tests/project/test_warmup_explorer.py``). ``conftest.py`` requests each
of these session fixtures before the first test when a selected test uses
it (:data:`HEAD_STARTS`), so they run on the idle core during the session.

They run in Linux's idle scheduling class: when the foreground tests want
both cores (two notebooks executing, a browser test's kernel and chromium),
the background gives way rather than slowing tests that wait on a page with
a timeout. A test that waits for background work moves it back to the
normal class (:func:`promote`): it is then what the session
waits for. What each check asserts is unchanged; only the wall-clock
guards inside the background runs are longer (a run that waited behind the
foreground must not fail for it), and their tests still bound the wait.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
import tarfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[1]
TESTS = REPO / "tests"

# Linux's idle scheduling class (SCHED_IDLE, util-linux's chrt): a background
# run gets a core only when no foreground process wants it, so the foreground
# loses nothing to it; nice 19 where chrt is missing (about 1.5 % of a core
# against a foreground process)
CHRT = shutil.which("chrt")
NICE = 19

# the session fixtures of the slow checks: conftest.py requests each one that
# a selected test uses before the first test runs
HEAD_STARTS = ("checked_runs", "packaging_runs", "explorer_compiles")


def low_priority(command: list[str]) -> list[str]:
    if CHRT is not None and hasattr(os, "SCHED_IDLE"):
        return [CHRT, "--idle", "0", *command]
    return ["nice", "-n", str(NICE), *command]


def promote(roots: Callable[[], list]) -> int:
    """Move the idle-class threads of ``roots()`` (psutil processes) and of
    their descendants to the normal class.

    Called while a test waits for background work: that work is then what
    the session waits for, and in the idle class any other process on the
    machine (another session, a build) would hold it back indefinitely. Only
    the awaited work: the other background runs keep to the idle core.
    Processes it starts later begin idle-class again, so a waiting test calls
    this every few seconds. Returns how many threads moved.
    """
    if not hasattr(os, "SCHED_IDLE"):
        return 0  # the nice fallback: nothing to undo
    import psutil

    moved = 0
    for root in roots():
        try:
            tree = [root, *root.children(recursive=True)]
        except psutil.Error:
            continue  # gone meanwhile
        for process in tree:
            try:
                threads = [t.id for t in process.threads()]
            except psutil.Error:
                continue
            for tid in threads:
                try:
                    if os.sched_getscheduler(tid) == os.SCHED_IDLE:
                        os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
                        moved += 1
                except OSError:
                    pass  # gone meanwhile, or not ours to change
    return moved


def running(pids: list[int]) -> list:
    """The psutil processes of ``pids`` that still run."""
    import psutil

    found = []
    for pid in pids:
        try:
            found.append(psutil.Process(pid))
        except psutil.Error:
            pass
    return found


def processes_naming(marker: str) -> list:
    """This process's descendants with ``marker`` in their command line."""
    import psutil

    found = []
    for process in psutil.Process().children(recursive=True):
        try:
            if any(marker in arg for arg in process.cmdline()):
                found.append(process)
        except psutil.Error:
            pass  # gone meanwhile
    return found


def wait_promoting(
    done: Callable[[float], bool], timeout: float, roots: Callable[[], list]
) -> bool:
    """``done(seconds)`` (wait up to that long; finished?) in slices of a few
    seconds until it says True or ``timeout`` passes, promoting ``roots()``
    before each slice. Returns the last answer."""
    deadline = time.monotonic() + timeout
    while True:
        promote(roots)
        left = deadline - time.monotonic()
        if done(max(0.0, min(5.0, left))) or left <= 0:
            return done(0.0)


class Job:
    """``work()`` in a thread from now on; ``result()`` waits for it and
    returns its value or raises what it raised (in the test that asks)."""

    def __init__(self, name: str, work: Callable[[], Any], marker: str):
        self.name = name
        self.marker = marker  # in the command line of every process it starts
        self._value: Any = None
        self._error: BaseException | None = None
        self._thread = threading.Thread(
            target=self._run, args=(work,), name=name, daemon=True
        )
        self._thread.start()

    def _run(self, work: Callable[[], Any]) -> None:
        try:
            self._value = work()
        except BaseException as error:  # noqa: BLE001 -- re-raised by result()
            self._error = error

    def _joined(self, seconds: float) -> bool:
        self._thread.join(seconds)
        return not self._thread.is_alive()

    def result(self, timeout: float) -> Any:
        mine = functools.partial(processes_naming, self.marker)
        if not wait_promoting(self._joined, timeout, mine):
            pytest.fail(f"{self.name} did not finish within {timeout} s")
        if self._error is not None:
            raise self._error
        return self._value


# pids of the background runs: a test that looks at this process's children
# (what they listen on) leaves the runs' process trees out (``in_background``)
BACKGROUND: set[int] = set()


def in_background(process) -> bool:
    """Whether the ``psutil.Process`` is a background run or one of its children."""
    try:
        return any(p.pid in BACKGROUND for p in [process, *process.parents()])
    except Exception:  # noqa: BLE001 -- gone meanwhile: not one of the test's own
        return True


class Run:
    """A subprocess writing to files (a pipe nobody reads while another run is
    awaited could fill and stall its writer); ``merge``: stderr into stdout's."""

    def __init__(
        self, command: list[str], folder: Path, name: str, merge=False, **kwargs
    ):
        self.command = command
        self.out = folder / f"{name}.out"
        self.err = folder / f"{name}.err"
        with self.out.open("w") as out, self.err.open("w") as err:
            self.process = subprocess.Popen(
                command,
                stdout=out,
                stderr=subprocess.STDOUT if merge else err,
                text=True,
                **kwargs,
            )
        BACKGROUND.add(self.process.pid)

    def _exited(self, seconds: float) -> bool:
        try:
            self.process.wait(timeout=seconds)
        except subprocess.TimeoutExpired:
            return False
        return True

    def finish(self, timeout: float) -> tuple[int, str, str]:
        mine = functools.partial(running, [self.process.pid])
        if not wait_promoting(self._exited, timeout, mine):
            self.process.kill()
            self.process.wait()
        return self.process.returncode, self.out.read_text(), self.err.read_text()

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()


# -- the kernels under bounds checking (test_boundscheck.py) ----------------------------

# The chain kernel of angular velocity works in blocks and runs of rows, each
# with its own last row: its edge tests are where a bounds slip would show.
CHAIN_EDGE_TESTS = [
    "tests/core/test_velocity_chain.py::test_kernels_at_the_edges_of_blocks_and_runs",
    "tests/core/test_velocity_chain.py::test_a_missing_row_anywhere_is_reported",
]


def checked_env(cache: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("NUMBA_DISABLE_JIT", None)
    env["NUMBA_BOUNDSCHECK"] = "1"
    env["NUMBA_CACHE_DIR"] = cache
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), str(TESTS)])
    return env


def kernel_tests_command() -> list[str]:
    kernel_tests = sorted(str(p) for p in (TESTS / "core").glob("test_kernels_*.py"))
    assert kernel_tests, "no kernel tests found"
    return [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
            # the first test to reach the SQUAD walk compiles it (~120 s here
            # while the walk was inlined into each kernel; without bounds checks
            # each walk kernel compiled in 116-201 s then, 58-67 s since); 1800:
            # at low priority a compile can also wait behind the foreground
            "-o", "addopts=", "-o", "timeout=1800", *kernel_tests, *CHAIN_EDGE_TESTS]  # fmt: skip


@pytest.fixture(scope="session")
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
    env = checked_env(str(folder / "cache"))
    commands = {
        "kernel tests": kernel_tests_command(),
        "probe": [sys.executable, str(TESTS / "boundscheck_probe.py")],
    }
    runs = {
        name: Run(low_priority(command), folder, name, cwd=REPO, env=env)
        for name, command in commands.items()
    }
    try:
        yield runs
    finally:
        for run in runs.values():
            run.stop()


# -- the wheel, the sdist, a user's venv, the sdist's tests (test_packaging.py) ---------

# The fast selection in two processes side by side, one per core of CI's two.
SDIST_SELECTION = "not slow and not browser"


def _install_from_the_wheel(wheel: Path, root: Path) -> Path:
    """A fresh venv with rbm_nb[all,lab,dev] from the wheel (not editable)."""
    from packaging_support import clean_env, make_venv, run, uv

    python = make_venv(root / "venv", see_this_env=False)
    command = [uv(), "pip", "install", "--quiet", "--python", str(python),
               "-c", str(REPO / ".ci" / "constraints.txt"),
               f"rbm_nb[all,lab,dev] @ {wheel.as_uri()}"]  # fmt: skip
    run(low_priority(command), timeout=1800, env=clean_env())
    return python


def user_env(root: Path, python: Path) -> dict[str, str]:
    """A user's shell: the venv's bin on PATH, HOME of their own, no repo."""
    from packaging_support import clean_env

    home = root / "home"
    home.mkdir(exist_ok=True)
    env = clean_env(HOME=str(home), MPLBACKEND="Agg")
    env.pop("XDG_DATA_HOME", None)
    env["PATH"] = f"{python.parent}{os.pathsep}{env['PATH']}"
    return env


def _start_sdist_tests(sdist: Path, python: Path, root: Path, shared: Path):
    """Unpacked sdist + the venv: warm-up, then the fast selection in two
    processes at once. Returns (paths, Run) per process and the warm-up's account."""
    from packaging_support import run, seed_numba_cache

    with tarfile.open(sdist) as tar:
        tar.extractall(root, filter="data")
    (src,) = root.glob("rbm_nb-*")
    env = user_env(root, python)
    env["RBM_NB_SHARED"] = str(shared)  # the real recordings of this machine
    # as .ci/setup.sh does: fill numba's cache before the tests (from this
    # checkout's, which saves compiling every kernel a second time: 2.5 min)
    seeded = seed_numba_cache(src)
    warm = run(
        low_priority([str(python), "-m", "rbm_nb._kernels._warmup"]),
        timeout=1800,
        env=env,
        cwd=src,
    )
    account = f"sdist: {seeded} numba cache files seeded; {warm.stdout + warm.stderr}"
    # the frame core's tests, and every other layer with the docstring
    # examples (about half the time each). The checks that run last in a
    # session (tests/test_*.py: what numba compiled) run in both.
    layers = sorted(
        p.name for p in (src / "tests").iterdir() if any(p.glob("test_*.py"))
    )
    assert "core" in layers, layers
    last = [str(p.relative_to(src)) for p in sorted(src.glob("tests/test_*.py"))]
    halves = (
        ["tests/core", *last],
        [*(f"tests/{name}" for name in layers if name != "core"), "rbm_nb", *last],
    )
    # 900 s per test instead of the configured 120: at low priority a test
    # can wait behind the foreground session
    command = [str(python), "-m", "pytest", "-q", "-p", "no:cacheprovider",
               "-o", "timeout=900", "-m", SDIST_SELECTION]  # fmt: skip
    runs = []
    for k, paths in enumerate(halves):
        command_k = low_priority([*command, *paths])
        runs.append(
            (paths, Run(command_k, root, f"half{k}", merge=True, env=env, cwd=src))
        )
    return runs, account


class PackagingRuns:
    """build -> (wheel, sdist) -> venv -> the sdist's fast tests, in threads.

    The wheel alone is also what tests/project/test_numba_cache.py installs;
    the venv is made when a test of test_packaging.py is selected, the sdist's
    tests (minutes of both cores) when the test that checks them is."""

    def __init__(self, root: Path, shared: Path, venv: bool, sdist_tests: bool):
        self._root = root
        self._runs: list[tuple[list[str], Run]] = []
        self._stopped = threading.Event()
        # every command of theirs names a path under root
        marker = str(root)
        self.dists = Job("python -m build", lambda: self._build(root / "dist"), marker)
        self.venv: Job | None = None
        self.sdist_tests: Job | None = None
        if venv or sdist_tests:
            self.venv = Job("the venv", lambda: self._venv(root), marker)
        if sdist_tests:
            self.sdist_tests = Job(
                "the sdist's fast tests", lambda: self._sdist(root, shared), marker
            )

    @staticmethod
    def _build(out: Path) -> tuple[Path, Path]:
        from packaging_support import build_dists

        out.mkdir()
        return build_dists(out, prefix=low_priority([]))

    def _venv(self, root: Path) -> Path:
        wheel, _ = self.dists.result(timeout=3600)
        return _install_from_the_wheel(wheel, root / "venv")

    def _sdist(self, root: Path, shared: Path):
        assert self.venv is not None
        _, sdist = self.dists.result(timeout=3600)
        python = self.venv.result(timeout=3600)
        if self._stopped.is_set():
            return [], ""
        runs, account = _start_sdist_tests(sdist, python, root / "sdist", shared)
        self._runs = runs
        if self._stopped.is_set():  # the session ended while they started
            self.stop()
        return runs, account

    def stop(self) -> None:
        """Stop what still runs (a session stopped early: -x, Ctrl-C): the
        sdist's tests, and the build or install a thread is waiting on (every
        command of theirs names a path under the root)."""
        import psutil

        self._stopped.set()
        for _, run in self._runs:
            run.stop()
        ours = []
        for process in processes_naming(str(self._root)):
            try:
                ours += [process, *process.children(recursive=True)]
            except psutil.Error:
                pass  # gone meanwhile
        for process in ours:
            try:
                process.kill()
            except psutil.Error:
                pass
        psutil.wait_procs(ours, timeout=30)


SDIST_TEST = "test_sdist_fast_tests_pass_against_its_own_tree"


@pytest.fixture(scope="session")
def packaging_runs(request, tmp_path_factory):
    from conftest import SHARED

    items = request.session.items
    venv = any(item.path.name == "test_packaging.py" for item in items)
    sdist_tests = any(getattr(i, "originalname", None) == SDIST_TEST for i in items)
    root = tmp_path_factory.mktemp("packaging")
    runs = PackagingRuns(root, SHARED, venv, sdist_tests)
    try:
        yield runs
    finally:
        runs.stop()
