"""Every import path users were given still works after the modules moved.

The spec's facades live in ``rbm_nb.core``, the explorer and the command line
in ``rbm_nb.app``; ``rbm_nb.frames`` & co. are the same module objects under
their old names, and every ``import``/``from ... import`` of rbm_nb written in
the README, the docs and the notebooks resolves.
"""

from __future__ import annotations

import importlib
import json
import pickle
import re

import pytest
from conftest import REPO

import rbm_nb

MOVED = {
    **{
        name: f"rbm_nb.core.{name}"
        for name in (
            "accessors",
            "conversions",
            "coordinates",
            "estimators",
            "evaluation",
            "frames",
            "gaze",
            "lookups",
            "plot",
            "quaternions",
            "rigid_transform",
            "se3",
            "transforms",
        )
    },
    "explorer": "rbm_nb.app.explorer",
    "cli": "rbm_nb.app.cli",
}

_STATEMENT = re.compile(
    r"^\s*(?:from\s+(rbm_nb[\w.]*)\s+import\s+([\w, ()]+)|import\s+(rbm_nb[\w.]*))",
    re.MULTILINE,
)


def _documents():
    for path in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        yield path, path.read_text()
    for path in sorted((REPO / "notebooks").glob("*.ipynb")):
        cells = json.loads(path.read_text())["cells"]
        yield path, "\n".join("".join(c["source"]) for c in cells)


def _written_imports():
    found = set()
    for path, text in _documents():
        for module, names, plain in _STATEMENT.findall(text):
            if plain:
                found.add((path.name, plain, ""))
            else:
                for name in names.strip("()").split(","):
                    name = name.split(" as ")[0].strip()
                    if name:
                        found.add((path.name, module, name))
    return sorted(found)


@pytest.mark.parametrize(("old", "new"), sorted(MOVED.items()))
def test_an_old_path_is_the_moved_module(old, new):
    module = importlib.import_module(f"rbm_nb.{old}")
    assert module is importlib.import_module(new)
    assert module.__name__ == new
    if old in rbm_nb._SUBMODULES:
        assert getattr(rbm_nb, old) is module


def test_objects_keep_one_identity_whichever_path_named_them():
    from rbm_nb.rigid_transform import Transform as Old

    from rbm_nb.core.rigid_transform import Transform as New

    assert Old is New is rbm_nb.Transform
    value = New(translation=(1.0, 2.0, 3.0))
    assert type(pickle.loads(pickle.dumps(value))) is New


def test_the_server_names_are_still_in_rbm_nb_app():
    from rbm_nb.app import serve
    from rbm_nb.app.server import serve as moved

    assert serve is moved


def test_the_documents_write_imports():
    assert len(_written_imports()) > 20


@pytest.mark.parametrize(("document", "module", "name"), _written_imports())
def test_every_import_the_documents_write_resolves(document, module, name):
    imported = importlib.import_module(module)
    if name and name != "*":
        assert hasattr(imported, name) or importlib.util.find_spec(
            f"{module}.{name}"
        ), f"{document}: from {module} import {name}"
