"""rbm_nb._kernels._warmup: order, sharing the work between processes, progress (fast checks).

The whole parallel warm-up, in a fresh environment with an empty cache, is
run by ``binder/postBuild`` in ``tests/project/test_binder.py``, which then
checks that a first call and the explorer notebook compile nothing; a fresh
clone's set-up is timed by ``benchmarks/first_run.py``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

import pytest

from rbm_nb._infra import numba_cache as _numba_cache
from rbm_nb._kernels import _warmup
from rbm_nb._kernels._jit import declared_kernels


def test_explorer_and_cost_name_declared_kernels():
    names = {_warmup.short_name(k) for k in declared_kernels()}
    assert set(_warmup.EXPLORER) <= names, set(_warmup.EXPLORER) - names
    assert set(_warmup.COST) <= names, set(_warmup.COST) - names


def test_the_plan_is_every_kernel_once_the_explorer_s_first():
    plan = _warmup.plan()
    assert sorted(k.name for k in plan) == sorted(k.name for k in declared_kernels())
    first = [_warmup.short_name(k) for k in plan[: len(_warmup.EXPLORER)]]
    assert set(first) == set(_warmup.EXPLORER)
    assert first[0] == "fused.lookup_chain"  # the longest: at once
    cheap = [_warmup.COST.get(n, _warmup.DEFAULT_COST) for n in first[1:]]
    assert cheap == sorted(cheap)  # the first cells' cheap kernels next
    assert first[1].startswith("times.")  # the first cell's: at once
    rest = [_warmup.cost(k) for k in plan[len(_warmup.EXPLORER) :]]
    assert rest == sorted(rest, reverse=True)


def test_a_busy_signature_is_put_off_then_waited_for(monkeypatch):
    """A worker goes on past a signature another process compiles, then loads it."""
    kernels = _warmup.plan()[:4]
    calls = []

    def compile_(kernel, wait=True):
        calls.append((kernel.name, wait))
        return wait or kernel is not kernels[1]  # kernels[1]: another process's

    monkeypatch.setattr(_warmup, "compile_signature", compile_)
    monkeypatch.setattr(_warmup, "ready", lambda ks=None: {})
    _warmup.compile_all(kernels)
    names = [k.name for k in kernels]
    assert calls == [(n, False) for n in names] + [(names[1], True)]
    # the other process finished it meanwhile: nothing to wait for or load
    calls.clear()
    done = {_warmup.key(kernels[1]): "compiled"}
    looks = iter([{}] * len(kernels) + [done])
    monkeypatch.setattr(_warmup, "ready", lambda ks=None: next(looks))
    _warmup.compile_all(kernels)
    assert calls == [(n, False) for n in names]


def test_a_signature_the_account_lists_is_skipped(monkeypatch):
    kernels = _warmup.plan()[:3]
    done = {_warmup.key(kernels[0]): "compiled"}
    compiled = []
    monkeypatch.setattr(_warmup, "ready", lambda ks=None: done)
    monkeypatch.setattr(
        _warmup,
        "compile_signature",
        lambda k, wait=True: compiled.append(k.name) or True,
    )
    _warmup.compile_all(kernels)
    assert compiled == [k.name for k in kernels[1:]]


@pytest.mark.parametrize("value", ["0", "-1", "two", None])
def test_jobs_must_be_a_positive_number(capsys, value):
    argv = ["--jobs"] if value is None else ["--jobs", value]
    assert _warmup.main(argv) == 2
    assert "--jobs needs a positive number of processes" in capsys.readouterr().out


def _fake_interpreter(tmp_path, monkeypatch, body):
    """Workers of a parallel warm-up start ``sys.executable``: make it a script."""
    script = tmp_path / "python"
    script.write_text(f"#!/bin/sh\n{body}\n")
    script.chmod(0o755)
    monkeypatch.setattr(_warmup.sys, "executable", str(script))


def test_a_failed_worker_fails_the_warm_up_with_its_output(tmp_path, monkeypatch):
    _fake_interpreter(tmp_path, monkeypatch, "echo 'no numba here'; exit 3")
    monkeypatch.setattr(_warmup, "compile_signature", lambda k, wait=True: True)
    with pytest.raises(RuntimeError, match=r"exit code 3:\nno numba here"):
        _warmup.warm_up(jobs=2)


def test_an_interrupted_warm_up_stops_its_workers(tmp_path, monkeypatch):
    _fake_interpreter(
        tmp_path, monkeypatch, f"echo $$ > {tmp_path}/pid; exec sleep 600"
    )

    def interrupted(kernel, wait=True):
        while not (tmp_path / "pid").exists():
            time.sleep(0.01)
        raise KeyboardInterrupt

    monkeypatch.setattr(_warmup, "compile_signature", interrupted)
    monkeypatch.setattr(_warmup, "ready", lambda ks=None: {})
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        _warmup.warm_up(jobs=2)
    assert time.perf_counter() - start < 60  # not the worker's 600 s
    pid = int((tmp_path / "pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # killed and reaped


def _account_rows(keys, outcome="compiled"):
    now = time.time()
    return [_numba_cache.AccountRow(k, outcome, 2.0, 1, "warm-up", now) for k in keys]


def test_progress_counts_signatures_in_the_account_and_the_last_line_matches(
    tmp_path, monkeypatch, capsys
):
    """ "N of M" while waiting, with the time left; the last line says M of M."""
    plan = _warmup.plan()
    keys = [_warmup.key(k) for k in plan]
    explorer = len(_warmup.EXPLORER)
    # the account grows by one signature per look (the explorer's first)
    looks = iter(range(len(keys) + 1))

    def read_account(folder):
        n = next(looks, len(keys))
        # the first signature was loaded, the others compiled
        return _account_rows(keys[:1][:n], "loaded") + _account_rows(
            keys[1:n], "compiled"
        )

    monkeypatch.setattr(_numba_cache, "read_account", read_account)
    monkeypatch.setattr(_warmup, "PROGRESS_EVERY", 0.0)
    monkeypatch.setattr(_warmup.time, "sleep", lambda s: None)
    status = tmp_path / "status"
    assert _warmup.wait("all", [], str(status), jobs=2) == 0
    out = capsys.readouterr().out.strip().splitlines()
    progress = [line for line in out if "kernel signatures ready," in line]
    assert progress, out
    counts = [int(line.split()[0]) for line in progress]
    assert counts == sorted(counts) and counts[-1] < len(keys)
    assert all(f"of {len(keys)} kernel signatures" in line for line in progress)
    assert all(line.rstrip().endswith("s left") for line in progress)
    assert out[-1].startswith(f"rbm_nb warm-up: {len(keys)} of {len(keys)} kernel")
    assert f"({len(keys) - 1} compiled, 1 loaded from the cache)" in out[-1]
    assert status.read_text().split() == [str(len(keys)), str(len(keys))]
    # waiting for the explorer ends as soon as its signatures are there
    looks = iter(range(explorer, len(keys) + 1))
    assert _warmup.wait("explorer", [], None, jobs=2) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    n = int(last.split()[2])
    assert explorer <= n < len(keys), last
    assert last.startswith(f"rbm_nb warm-up: {n} of {len(keys)} kernel signatures")
    assert f"(all {explorer} of the explorer's); the other {len(keys) - n}" in last


def test_waiting_ends_when_the_workers_are_gone(monkeypatch, capsys):
    monkeypatch.setattr(_numba_cache, "read_account", lambda folder: [])
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    assert _warmup.wait("explorer", [gone.pid], None, jobs=2) == 1
    assert "the workers stopped with 0 of" in capsys.readouterr().out


def test_the_estimate_follows_the_pace_and_the_longest_kernel():
    plan = _warmup.plan()
    lookup = plan[0]
    assert _warmup.short_name(lookup) == "fused.lookup_chain"
    rest = plan[1:5]
    # nothing done: at least the longest kernel's cost
    left = _warmup.estimate(plan[:5], {}, {}, jobs=2)
    assert left == pytest.approx(
        max(_warmup.cost(lookup), sum(map(_warmup.cost, plan[:5])) / 2)
    )
    # the done ones took twice their cost: twice as long left
    done = {_warmup.key(k): "compiled" for k in rest}
    seconds = {_warmup.key(k): 2 * _warmup.cost(k) for k in rest}
    assert _warmup.estimate(plan[:5], done, seconds, jobs=2) == pytest.approx(
        2 * _warmup.cost(lookup)
    )
    assert _warmup.estimate(rest, done, seconds, jobs=2) == 0.0


# -- one compile per signature, over processes -------------------------------

_CALLER = textwrap.dedent(
    """
    import sys
    import numpy as np
    from rbm_nb._kernels import quaternion
    print("imported", flush=True)
    sys.stdin.readline()  # the test says when
    quaternion.qconj(np.zeros((2, 4)))
    """
)


def test_a_signature_is_compiled_once_over_processes_that_need_it_together(tmp_path):
    """Two processes call a kernel their empty cache lacks: one compiles, one loads."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "RBM_NB_COMPILE_ROLE": "t"}
    callers = [
        subprocess.Popen(
            [sys.executable, "-c", _CALLER],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        for _ in range(2)
    ]
    for c in callers:
        assert c.stdout.readline().strip() == "imported"
    for c in callers:  # as close together as the test can make it
        c.stdin.write("go\n")
        c.stdin.flush()
    for c in callers:
        c.stdin.close()
        assert c.wait(timeout=120) == 0
    (account,) = list(tmp_path.rglob(_numba_cache.ACCOUNT))
    rows = _numba_cache.read_account(account.parent)
    assert sorted(r.outcome for r in rows) == ["compiled", "loaded"], rows
    assert {r.key for r in rows} == {
        "rbm_nb._kernels.quaternion.qconj(array(float64,2d,C))"
    }
    assert len({r.pid for r in rows}) == 2


def test_a_process_waits_for_the_lock_holder_and_then_loads(tmp_path):
    """While another process holds a signature's lock, a caller compiles nothing."""
    from rbm_nb._kernels import quaternion

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "RBM_NB_COMPILE_ROLE": "t"}
    # the folder and the lock's name this process would use under tmp_path
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            "from rbm_nb._infra import numba_cache as c; from rbm_nb._kernels import quaternion"
            " as q; from numba import types as t; a = (t.float64[:, ::1],);"
            " k = c.signature_key(q.qconj, a); print(c._lock_path(c.cache_folder(q.qconj), k))",
        ],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    lock = probe.stdout.strip()
    assert lock.startswith(str(tmp_path)) and quaternion.qconj is not None
    with _numba_cache._file_lock(_numba_cache.Path(lock)) as held:
        assert held
        caller = subprocess.Popen(
            [sys.executable, "-c", _CALLER],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert caller.stdout.readline().strip() == "imported"
        caller.stdin.write("go\n")
        caller.stdin.close()
        with pytest.raises(subprocess.TimeoutExpired):
            caller.wait(timeout=3)  # waiting for this process's lock
    assert caller.wait(timeout=120) == 0
    rows = _numba_cache.read_account(_numba_cache.Path(lock).parent)
    assert [r.outcome for r in rows] == ["compiled"]  # after the lock was free


def test_the_report_says_n_of_m_and_the_time_left_without_waiting(
    tmp_path, monkeypatch, capsys
):
    """What the demo's set-up ends with while the compile goes on."""
    plan = _warmup.plan()
    keys = [_warmup.key(k) for k in plan]
    monkeypatch.setattr(
        _numba_cache, "read_account", lambda folder: _account_rows(keys[1:3])
    )
    status = tmp_path / "status"
    assert _warmup.report(str(status), jobs=2) == 0
    (line,) = capsys.readouterr().out.strip().splitlines()
    explorer = len(_warmup.EXPLORER)
    assert line.startswith(f"rbm_nb warm-up: 2 of {len(keys)} kernel signatures ready")
    assert f"(2 of the explorer's {explorer})" in line
    assert status.read_text().split() == ["2", str(len(keys))]
    # lookup_chain (first in the plan) still to come: at least its cost left
    first = float(line.split("the explorer's first (about ")[1].split(" s)")[0])
    assert first >= _warmup.COST["fused.lookup_chain"] * 0.5
