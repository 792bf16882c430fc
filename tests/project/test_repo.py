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


def test_license_changelog_and_typing_marker_ship_with_the_package():
    import tomllib

    import rbm_nb

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["license"] == "MIT"
    assert (REPO / "LICENSE").read_text().startswith("MIT License")
    assert (REPO / "rbm_nb" / "py.typed").is_file()
    changelog = (REPO / "CHANGELOG.md").read_text()
    assert "## [Unreleased]" in changelog
    assert f"## [{rbm_nb.__version__}]" in changelog, "CHANGELOG misses this version"


def test_pytest_collects_the_tests_and_every_modules_doctests():
    import tomllib

    options = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["pytest"]
    options = options["ini_options"]
    assert options["testpaths"] == ["tests", "rbm_nb"]
    assert "--doctest-modules" in options["addopts"].split()
    assert options["timeout"] <= 120
