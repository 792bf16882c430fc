"""ruff, ruff format and mypy, run by the test suite.

Why tests and not steps of ``.ci/run``: ``.ci/run`` must stay textually the
README's test command (tests/project/test_repo.py), which is what a newcomer types, so
the tools run wherever the tests run -- in CI, locally, in an unpacked sdist.
They use the configuration in pyproject.toml.

``PENDING`` listed the files that still had findings when these checks were
introduced; the clean-up emptied it, so every file must be clean now. A file
listed there is excused, and must leave the list once it is clean, so the list
only shrinks.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
from conftest import REPO

PENDING: dict[str, set[str]] = {
    "ruff check": set(),
    "ruff format": set(),
    "mypy": set(),
}


def _tool(module: str, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    pytest.importorskip(module, reason=f"{module} is a dev extra")
    return subprocess.run(
        [sys.executable, "-m", module, *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _judge(tool: str, findings: Counter, details: str) -> None:
    """No findings outside PENDING[tool]; no clean file left in it."""
    unexpected = {f: n for f, n in sorted(findings.items()) if f not in PENDING[tool]}
    assert not unexpected, (
        f"{tool} findings in {unexpected} (run it on those files):\n{details[-4000:]}"
    )
    now_clean = sorted(f for f in PENDING[tool] if f not in findings)
    assert not now_clean, (
        f"{now_clean} passed {tool} now: remove them from PENDING in {__file__}"
    )


def test_ruff_check():
    result = _tool("ruff", "check", "--output-format", "json", ".")
    assert result.returncode in (0, 1), result.stderr
    findings = Counter(
        str(Path(f["filename"]).relative_to(REPO)) for f in json.loads(result.stdout)
    )
    _judge("ruff check", findings, result.stdout)


def test_ruff_format():
    result = _tool("ruff", "format", "--check", "--output-format", "concise", ".")
    assert result.returncode in (0, 1), result.stderr
    findings = Counter(
        line.split(":", 1)[0]
        for line in result.stdout.splitlines()
        if "File would be reformatted" in line
    )
    _judge("ruff format", findings, result.stdout)


@pytest.mark.timeout(600)  # a cold mypy cache: about 20 s here
def test_mypy():
    result = _tool("mypy", "--no-error-summary", "--show-error-codes", timeout=540)
    errors = re.findall(r"^(\S+?\.py):\d+: error:", result.stdout, re.M)
    assert result.returncode in (0, 1) and (result.returncode == 0 or errors), (
        result.stdout[-3000:] + result.stderr[-3000:]
    )
    _judge("mypy", Counter(errors), result.stdout)
