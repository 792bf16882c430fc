"""rbm_nb._warmup: how the work is shared between processes (fast checks).

The whole parallel warm-up, in a fresh environment with an empty cache, is
run by ``binder/postBuild`` in ``tests/project/test_binder.py``, which then
checks that a first call and the explorer notebook compile nothing.
"""

from __future__ import annotations

import os
import time

import pytest

from rbm_nb import _warmup
from rbm_nb._kernels._jit import declared_kernels


def test_a_claimed_kernel_is_left_to_the_process_that_claimed_it(tmp_path, monkeypatch):
    compiled = []
    monkeypatch.setattr(_warmup, "_compile", lambda k: compiled.append(k.name))
    kernels = declared_kernels()
    taken = {0, 3, len(kernels) - 1}  # claimed by other processes
    for index in taken:
        (tmp_path / str(index)).touch()
    _warmup._compile_claimed(str(tmp_path), verbose=False)
    assert compiled == [k.name for i, k in enumerate(kernels) if i not in taken]
    claimed = [n for n in os.listdir(tmp_path) if not n.endswith(".done")]
    assert sorted(claimed, key=int) == [str(i) for i in range(len(kernels))]
    # a second process finds everything claimed
    compiled.clear()
    _warmup._compile_claimed(str(tmp_path), verbose=False)
    assert compiled == []


@pytest.mark.parametrize("value", ["0", "-1", "two", None])
def test_jobs_must_be_a_positive_number(capsys, value):
    argv = ["--jobs"] if value is None else ["--jobs", value]
    assert _warmup.main(argv) == 2
    assert "--jobs needs a positive number of processes" in capsys.readouterr().out


def _fake_interpreter(tmp_path, monkeypatch, body):
    """Helpers of a parallel warm-up start ``sys.executable``: make it a script."""
    script = tmp_path / "python"
    script.write_text(f"#!/bin/sh\n{body}\n")
    script.chmod(0o755)
    monkeypatch.setattr(_warmup.sys, "executable", str(script))


def test_a_failed_helper_fails_the_warm_up_with_its_output(tmp_path, monkeypatch):
    _fake_interpreter(tmp_path, monkeypatch, "echo 'no numba here'; exit 3")
    monkeypatch.setattr(_warmup, "_compile", lambda k: None)
    with pytest.raises(RuntimeError, match=r"exit code 3:\nno numba here"):
        _warmup.warm_up(jobs=2)


def test_an_interrupted_warm_up_stops_its_helpers(tmp_path, monkeypatch):
    _fake_interpreter(
        tmp_path, monkeypatch, f"echo $$ > {tmp_path}/pid; exec sleep 600"
    )

    def interrupted(kernel):
        while not (tmp_path / "pid").exists():
            time.sleep(0.01)
        raise KeyboardInterrupt

    monkeypatch.setattr(_warmup, "_compile", interrupted)
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        _warmup.warm_up(jobs=2)
    assert time.perf_counter() - start < 60  # not the helper's 600 s
    pid = int((tmp_path / "pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # killed and reaped


def test_the_status_file_counts_n_of_m_and_ends_at_m(tmp_path, monkeypatch):
    """What .ci/setup.sh prints: "N of M", the same M to the end (issue 29)."""
    seen = []
    status = tmp_path / "status"

    def compile_and_look(kernel):
        seen.append(status.read_text().split() if status.exists() else None)

    monkeypatch.setattr(_warmup, "_compile", compile_and_look)
    total = len(declared_kernels())
    _warmup.warm_up(jobs=1, status=str(status))
    assert seen[0] == ["0", str(total)]
    assert [int(s[0]) for s in seen] == list(range(total))
    assert status.read_text().split() == [str(total), str(total)]
    # the claims of a parallel warm-up count what every process has done
    claims = tmp_path / "claims"
    claims.mkdir()
    (claims / "0").touch()
    (claims / "0.done").touch()  # another process's
    _warmup._compile_claimed(str(claims), False, str(status))
    assert status.read_text().split() == [str(total), str(total)]


def test_the_last_line_says_m_of_m(capsys, monkeypatch):
    monkeypatch.setattr(_warmup, "_compile", lambda k: None)
    assert _warmup.main(["--jobs", "1"]) == 0
    total = len(declared_kernels())
    assert f"{total} of {total} kernel signatures ready" in capsys.readouterr().out
