"""The slow subprocess checks that start with the session (head_start.py)."""

from __future__ import annotations

import ast
import os
import subprocess
import sys

import pytest
from conftest import TESTS
from head_start import CHRT, HEAD_STARTS, NICE, Job, Run, low_priority


def test_each_head_start_is_a_fixture_some_test_takes():
    """A renamed fixture would silently stop the head start (its tests would
    then start the work themselves, minutes later)."""
    taken = set()
    for path in TESTS.glob("*/test_*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef):
                taken.update(arg.arg for arg in node.args.args)
    for fixture in HEAD_STARTS:
        assert fixture in taken, f"no test or fixture takes {fixture}"


def test_background_commands_run_at_low_priority():
    code = "import os; print(os.sched_getscheduler(0), os.nice(0))"
    ours = int(subprocess.check_output([sys.executable, "-c", code]).split()[1])
    # (not Run.finish: a test's wait promotes what it waits for, see below)
    out = subprocess.check_output(low_priority([sys.executable, "-c", code]))
    policy, nice = map(int, out.split())
    if CHRT is not None:
        assert policy == os.SCHED_IDLE, out
    else:
        assert nice == min(ours + NICE, 19), out


def test_a_job_hands_its_value_or_its_error_to_the_test_that_waits():
    assert Job("value", lambda: 42, "no process").result(timeout=30) == 42

    def fail():
        raise AssertionError("the build failed: the reason")

    with pytest.raises(AssertionError, match="the build failed: the reason"):
        Job("failing", fail, "no process").result(timeout=30)


def test_a_run_that_a_test_waits_for_leaves_the_idle_class(tmp_path):
    """Awaited, background work is what the session waits for: another
    process on the machine must not hold it back (head_start.promote)."""
    if CHRT is None or not hasattr(os, "SCHED_IDLE"):
        pytest.skip("no idle scheduling class here (the nice fallback stays)")
    # the policy after the first promotions (one every 5 s while waiting)
    code = "import os, time; time.sleep(6.5); print(os.sched_getscheduler(0))"
    run = Run(low_priority([sys.executable, "-c", code]), tmp_path, "promoted")
    # background work nobody waits for keeps to the idle class
    other = Run(low_priority([sys.executable, "-c", code]), tmp_path, "other")
    try:
        returncode, out, err = run.finish(timeout=60)
        assert returncode == 0, err
        assert int(out) == os.SCHED_OTHER, out
        assert os.sched_getscheduler(other.process.pid) == os.SCHED_IDLE
    finally:
        other.stop()
