"""No module of rbm_nb over 700 lines (issue 32, items 4 and 7).

A module that long does several jobs; split it by role into modules with one
job each (as ``rbm_nb/scene/`` and ``rbm_nb/_door/dask_*`` were). Lines are
counted as ``wc -l`` counts them. No module is exempt: the last one over
(``core/frames.py``, 1051 lines) was split into ``core/frame_*.py`` bases.
"""

from __future__ import annotations

from pathlib import Path

from conftest import REPO

PACKAGE = REPO / "rbm_nb"

MAX_LINES = 700


def line_count(path: Path) -> int:
    """Lines as ``wc -l`` counts them: newline characters."""
    return path.read_bytes().count(b"\n")


def module_sizes(package: Path = PACKAGE) -> dict[str, int]:
    """Path relative to ``package`` (posix) -> lines, for every ``.py`` file."""
    return {
        path.relative_to(package).as_posix(): line_count(path)
        for path in sorted(package.rglob("*.py"))
    }


def too_long(sizes: dict[str, int]) -> dict[str, int]:
    return {name: n for name, n in sizes.items() if n > MAX_LINES}


def test_the_check_sees_a_long_module(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "short.py").write_text("x = 1\n" * MAX_LINES)
    (pkg / "sub" / "long.py").write_text("x = 1\n" * (MAX_LINES + 1))
    sizes = module_sizes(pkg)
    assert sizes["short.py"] == MAX_LINES
    assert too_long(sizes) == {"sub/long.py": MAX_LINES + 1}


def test_no_module_is_over_700_lines():
    assert too_long(module_sizes()) == {}, (
        f"modules over {MAX_LINES} lines: split each by role"
    )
