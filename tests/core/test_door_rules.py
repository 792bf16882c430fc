"""Each argument rule is written once, in the door (issue 32, item 2).

The facades (``rbm_nb/core``) used to unpack and check their arguments for
themselves (``estimators._unpack``, ``conversions._as_rows``,
``coordinates._checked``, ``se3._check_rotations``, ...), and axis
normalisation was written five times. These tests read the sources: an
axis is made non-negative only by ``_door.unpack.resolve_axis``, and no
facade module defines an unpacker or shape checker of its own again.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import rbm_nb

PACKAGE = Path(rbm_nb.__file__).resolve().parent

# ``axis % arr.ndim``, ``axis %= ndim``, ``-arr.ndim <= axis``: normalising an
# axis by hand (resolve_axis also checks it and names the argument)
AXIS_BY_HAND = re.compile(r"%=?\s*[\w.]*\bndim\b|-\s*[\w.]*\bndim\s*<=")

# the helpers the facades had; the door's shapes/series/unpack replace them
OLD_UNPACKERS = {
    "_unpack", "_as_array", "_as_rows", "_paired_rows", "_as_float", "_checked",
    "_check_rotations", "_check_directions", "_check_tol", "_where", "_dim_axis",
    "_float_array", "_is_dataarray", "_rows_of",
}  # fmt: skip


def _sources(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(PACKAGE)): p.read_text() for p in sorted(folder.rglob("*.py"))
    }


def test_axes_are_normalised_only_by_resolve_axis():
    found = []
    for name, text in _sources(PACKAGE).items():
        if name == "_door/unpack.py":
            continue  # resolve_axis itself
        for number, line in enumerate(text.splitlines(), 1):
            code = line.split("#", 1)[0]
            if AXIS_BY_HAND.search(code):
                found.append(f"{name}:{number}: {line.strip()}")
    assert found == []


def test_facades_define_no_unpackers_of_their_own():
    found = []
    for name, text in _sources(PACKAGE / "core").items():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef) and node.name in OLD_UNPACKERS:
                found.append(f"{name}:{node.lineno}: def {node.name}")
    assert found == []
