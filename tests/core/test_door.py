"""The door of the transforms (issue 32, item 2): checks once, before the engine.

The facades and the dask path hand the engine what :mod:`rbm_nb._door.inputs`
returns; the engine's transform modules check nothing; the dask path calls
no facade back and reads no private name of the engine.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._door import inputs as _inputs

PACKAGE = Path(rbm.__file__).resolve().parent


def _imports(module: Path) -> list[tuple[str, list[str]]]:
    """(module imported from, names) of every ``from`` import of a module file."""
    found = []
    for node in ast.walk(ast.parse(module.read_text())):
        if isinstance(node, ast.ImportFrom):
            found.append(
                ("." * node.level + (node.module or ""), [a.name for a in node.names])
            )
    return found


@pytest.mark.parametrize("name", ["transform.py", "twist.py"])
def test_the_engine_transforms_check_nothing(name):
    sources = [m for m, _ in _imports(PACKAGE / "_engine" / name)]
    assert ".._validation" not in sources, sources


DASK_MODULES = sorted((PACKAGE / "_door").glob("dask_*.py"))


def test_the_dask_path_is_the_modules_checked_here():
    names = {p.stem for p in DASK_MODULES}
    assert {"dask_blocks", "dask_chunks", "dask_transforms"} <= names, names


@pytest.mark.parametrize("path", DASK_MODULES, ids=lambda p: p.stem)
def test_the_dask_path_reads_no_private_name_of_the_engine(path):
    tree = ast.parse(path.read_text())
    engine_aliases = set()
    private = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
            "_engine"
        ):
            private += [a.name for a in node.names if a.name.startswith("_")]
            if node.module == "_engine":
                engine_aliases |= {a.asname or a.name for a in node.names}
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id in engine_aliases
            and node.attr.startswith("_")
        ):
            private.append(f"{node.value.id}.{node.attr}")
    assert private == []


def _register_moving() -> None:
    rbm.clear_registry()
    rbm.register_frame("world")
    t = np.arange(100) * 0.01
    half = 0.5 * t
    rbm.register_frame(
        "head", translation=np.c_[t, 0 * t, 0 * t + 1], timestamps=t, parent="world",
        rotation=np.c_[np.cos(half), 0 * t, 0 * t, np.sin(half)],
    )  # fmt: skip
    rbm.register_frame("eye", translation=(0.03, 0.1, 0.0), parent="head")


def test_the_dask_path_calls_no_facade_back():
    da = pytest.importorskip("dask.array")
    xr = pytest.importorskip("xarray")
    _register_moving()
    t = np.arange(100) * 0.01
    arr = xr.DataArray(
        da.from_array(np.ones((100, 3)), chunks=(50, 3)), {"time": t},
        ("time", "cartesian_axis"), attrs={"reference_frame": "eye"},
    )  # fmt: skip
    facades = {
        "rbm_nb.core.transforms",
        "rbm_nb.core.lookups",
        "rbm_nb.core.estimators",
    }
    calls = []

    def profile(frame, event, arg):
        if event == "call" and frame.f_back is not None:
            caller = frame.f_back.f_globals.get("__name__", "")
            callee = frame.f_globals.get("__name__", "")
            if caller.startswith("rbm_nb._door.dask_") and callee in facades:
                calls.append(f"{callee}.{frame.f_code.co_name}")

    sys.setprofile(profile)
    try:
        out = rbm.transform_points(arr, "world").compute(scheduler="sync")
    finally:
        sys.setprofile(None)
    assert calls == []
    eager = rbm.transform_points(arr.compute(), "world")
    np.testing.assert_array_equal(out.values, eager.values)


def test_the_short_way_gives_the_long_ways_bits():
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "head", parent="world", translation=(0.1, 0.2, 1.7),
        rotation=(np.cos(0.2), 0.0, 0.0, np.sin(0.2)),
    )  # fmt: skip
    p = np.random.default_rng(3).normal(size=(5, 3))
    args = _inputs.arguments(
        "points", p, "world", "head", None, None, None, None, "reference_frame",
        rbm.frames.resolve_frame,
    )  # fmt: skip
    assert args.rows is not None  # the short way was taken
    short = rbm.transform_points(p, "world", "head")
    long = rbm.transform_points(p.T.copy(), "world", "head", axis=0).T  # laid out
    np.testing.assert_array_equal(short, long)


@pytest.mark.parametrize(
    "point, message",
    [
        (np.array([np.nan, 0.0, 0.0]), "arr is not finite"),
        (np.array([np.inf, 0.0, 0.0]), "arr is not finite"),
        (np.array([1e200, 0.0, 0.0]), "beyond"),
    ],
)
def test_the_short_way_leaves_bad_rows_to_the_checks(point, message):
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame("head", parent="world", translation=(0.0, 0.0, 1.0))
    with pytest.raises(ValueError, match=message):
        rbm.transform_points(point, "world", "head")
