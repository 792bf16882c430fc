"""rbm_nb._infra.parallel: which twin a call runs, and with how many threads."""

from __future__ import annotations

import math
import os
import threading
import time

import numba
import pytest

from rbm_nb._infra import parallel as _parallel


def _twins():
    ran: list[tuple[str, int]] = []

    def serial(x):
        ran.append(("serial", 1))
        return x

    def parallel(x):
        ran.append(("parallel", numba.get_num_threads()))
        return x

    return ran, serial, parallel


@pytest.fixture(autouse=True)
def _two_threads_allowed(monkeypatch, ignore_load):
    monkeypatch.delenv(_parallel.ENV_THREADS, raising=False)
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", max(2, os.cpu_count() or 2))
    monkeypatch.setattr(_parallel, "_launched_in", None)


def test_short_calls_run_serially():
    ran, serial, parallel = _twins()
    assert _parallel.launch(serial, parallel, _parallel.MIN_ROWS - 1, 7) == 7
    assert ran == [("serial", 1)]


def test_long_calls_run_in_parallel_and_restore_the_thread_count(monkeypatch):
    monkeypatch.setenv(_parallel.ENV_THREADS, "2")
    before = numba.get_num_threads()
    ran, serial, parallel = _twins()
    assert _parallel.launch(serial, parallel, _parallel.MIN_ROWS, 7) == 7
    assert ran == [("parallel", 2)]
    assert numba.get_num_threads() == before


def test_one_thread_means_serial(monkeypatch):
    monkeypatch.setenv(_parallel.ENV_THREADS, "1")
    ran, serial, parallel = _twins()
    _parallel.launch(serial, parallel, 10 * _parallel.MIN_ROWS, 0)
    assert ran == [("serial", 1)]


def test_the_environment_cannot_ask_for_more_than_numba_has(monkeypatch):
    monkeypatch.setenv(_parallel.ENV_THREADS, "10000")
    assert _parallel.threads() == numba.config.NUMBA_NUM_THREADS


@pytest.mark.parametrize("raw", ["0", "-2", "two", "1.5"])
def test_a_bad_thread_count_names_the_variable(monkeypatch, raw):
    monkeypatch.setenv(_parallel.ENV_THREADS, raw)
    with pytest.raises(ValueError, match=_parallel.ENV_THREADS):
        _parallel.threads()


def test_a_second_thread_runs_serially_while_a_parallel_kernel_runs():
    inside = threading.Event()
    release = threading.Event()
    ran: list[str] = []

    def slow_parallel(x):
        inside.set()
        release.wait(10)
        ran.append("parallel")
        return x

    def serial(x):
        ran.append("serial")
        return x

    first = threading.Thread(
        target=_parallel.launch, args=(serial, slow_parallel, _parallel.MIN_ROWS, 1)
    )
    first.start()
    assert inside.wait(10)
    # the lock is taken: this thread must not launch a second parallel kernel
    _parallel.launch(serial, slow_parallel, _parallel.MIN_ROWS, 2)
    release.set()
    first.join(10)
    assert ran == ["serial", "parallel"]


def test_a_forked_child_of_a_launching_process_runs_serially(monkeypatch):
    monkeypatch.setattr(_parallel, "_launched_in", os.getpid() + 1)
    ran, serial, parallel = _twins()
    _parallel.launch(serial, parallel, _parallel.MIN_ROWS, 0)
    assert ran == [("serial", 1)]


# ---------------------------------------------------------------------------
# the load: cores that other runnable threads want
# ---------------------------------------------------------------------------


@pytest.fixture
def load(monkeypatch, tmp_path):
    """``load(running, cores)``: /proc/loadavg as Linux writes it, with
    ``running`` runnable threads, on ``cores`` cores; free_cores reads it."""
    monkeypatch.undo()  # ignore_load's stand-in goes: the real free_cores reads
    monkeypatch.setattr(_parallel, "_launched_in", None)
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", 2)
    monkeypatch.setenv(_parallel.ENV_THREADS, "2")

    def set_load(running, cores, own=1):
        # launch reads the new load at once (not RECHECK_AFTER later)
        monkeypatch.setattr(_parallel, "_reading", (-math.inf, None))
        path = tmp_path / "loadavg"
        path.write_text(f"0.52 0.58 0.59 {running}/345 12345\n")
        monkeypatch.setattr(_parallel, "_LOADAVG", str(path))
        monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(cores)))
        if own is not None:  # this process's runnable threads (None: the real count)
            monkeypatch.setattr(_parallel, "_own_runnable", lambda: own)

    return set_load


@pytest.mark.parametrize(
    ("running", "cores", "own", "free"),
    [
        (1, 2, 1, 2),
        (2, 2, 1, 1),
        (5, 2, 1, 1),
        (1, 8, 1, 8),
        (3, 8, 1, 6),
        (3, 2, 3, 2),
    ],
)
def test_free_cores_leaves_out_the_other_processes_runnable_threads(
    load, running, cores, own, free
):
    load(running, cores, own)  # the calling thread is one of the running
    assert _parallel.free_cores() == free


def test_this_processs_own_busy_threads_do_not_count(load):
    """numba's workers spin for a moment after a parallel call: a thread of
    this process that is running must not make the next call serial."""
    from numba import njit

    @njit(nogil=True)
    def spin(seconds):  # releases the GIL: the thread really runs
        x = 0.0
        for i in range(int(seconds * 2e8)):
            x += i * 1e-9
        return x

    spin(0.0)
    thread = threading.Thread(target=spin, args=(1.0,))
    thread.start()
    try:
        time.sleep(0.05)
        own = _parallel._own_runnable()
        assert own >= 2  # this thread and the spinning one
        load(own, 2, own=None)  # every runnable thread is ours
        assert _parallel.free_cores() == 2
    finally:
        thread.join()


def test_a_busy_core_means_serial(load):
    load(2, 2)
    ran, serial, parallel = _twins()
    _parallel.launch(serial, parallel, 10 * _parallel.MIN_ROWS, 0)
    assert ran == [("serial", 1)]
    load(1, 2)
    _parallel.launch(serial, parallel, 10 * _parallel.MIN_ROWS, 0)
    assert ran[-1] == ("parallel", 2)


def test_launches_read_the_load_again_only_after_a_while(load, monkeypatch):
    """In a loop of calls the reading stands for RECHECK_AFTER seconds."""
    load(1, 2)
    readings = []
    real = _parallel.free_cores
    monkeypatch.setattr(_parallel, "free_cores", lambda: readings.append(1) or real())
    now = [1000.0]
    monkeypatch.setattr(_parallel, "_now", lambda: now[0])
    ran, serial, parallel = _twins()
    rows = 10 * _parallel.MIN_ROWS
    _parallel.launch(serial, parallel, rows, 0)
    now[0] += 0.5 * _parallel.RECHECK_AFTER
    path = _parallel._LOADAVG
    with open(path, "w") as f:  # another process starts: 2 runnable threads
        f.write("0.52 0.58 0.59 2/345 12345\n")
    _parallel.launch(serial, parallel, rows, 0)
    assert len(readings) == 1 and ran == [("parallel", 2)] * 2
    now[0] += _parallel.RECHECK_AFTER
    _parallel.launch(serial, parallel, rows, 0)
    assert len(readings) == 2 and ran[-1] == ("serial", 1)


def test_without_a_load_count_the_load_is_not_considered(load, monkeypatch):
    load(1, 2)
    monkeypatch.setattr(_parallel, "_LOADAVG", "/nonexistent/loadavg")
    assert _parallel.free_cores() is None
    ran, serial, parallel = _twins()
    _parallel.launch(serial, parallel, 10 * _parallel.MIN_ROWS, 0)
    assert ran == [("parallel", 2)]


def test_processes_that_keep_every_core_busy_make_calls_serial(monkeypatch):
    """Real load: one busy process per core, seen through the real /proc/loadavg."""
    monkeypatch.undo()  # the real free_cores
    monkeypatch.setattr(_parallel, "_reading", (-math.inf, None))
    if not os.path.exists(_parallel._LOADAVG):
        pytest.skip("no /proc/loadavg here")
    import subprocess
    import sys
    import time

    cores = len(os.sched_getaffinity(0))
    busy = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"])
        for _ in range(cores)
    ]
    try:
        deadline = time.monotonic() + 10
        while _parallel.free_cores() != 1 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _parallel.free_cores() == 1
        monkeypatch.setenv(_parallel.ENV_THREADS, "2")
        monkeypatch.setattr(_parallel, "_launched_in", None)
        ran, serial, parallel = _twins()
        _parallel.launch(serial, parallel, 10 * _parallel.MIN_ROWS, 0)
        assert ran == [("serial", 1)]
    finally:
        for process in busy:
            process.kill()
            process.wait()
