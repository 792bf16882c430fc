"""The README's two commands are the ones CI and newcomers run."""

from __future__ import annotations

import re

from conftest import REPO


def _command_after(marker: str) -> str:
    text = (REPO / "README.md").read_text()
    match = re.search(rf"<!-- {marker} -->\s*```bash\n(.+?)\n```", text, re.S)
    assert match, f"README.md has no ```bash block after <!-- {marker} -->"
    return match.group(1).strip()


def test_ci_runs_exactly_the_readme_test_command():
    ci_lines = [
        line.strip()
        for line in (REPO / ".ci" / "run").read_text().splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    assert ci_lines[-1] == _command_after("test-command")


def test_demo_command_uses_the_same_setup_script():
    demo = _command_after("demo-command")
    assert demo.startswith("bash .ci/setup.sh demo && ")
