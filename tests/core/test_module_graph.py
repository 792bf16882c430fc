"""The import graph of rbm_nb: no cycles, counting imports inside functions.

Every ``import``/``from ... import`` statement of every module of the package
is parsed with :mod:`ast` (module level, inside functions and inside
classes; ``if TYPE_CHECKING:`` blocks are skipped, they never run). An edge
goes from a module to each module of the package it imports; ``from pkg
import name`` counts as importing ``pkg.name`` when that is a module, else
``pkg`` itself.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest
from conftest import REPO

PACKAGE = REPO / "rbm_nb"

# The frame core: intra-package imports here are all at module level (imports
# inside functions are left for optional third-party dependencies).
CORE = (
    "rbm_nb.frames",
    "rbm_nb.transforms",
    "rbm_nb.lookups",
    "rbm_nb.estimators",
    "rbm_nb.quaternions",
    "rbm_nb.coordinates",
    "rbm_nb.conversions",
    "rbm_nb.rigid_transform",
    "rbm_nb.errors",
    "rbm_nb._frame_paths",
    "rbm_nb._time",
    "rbm_nb._door",
    "rbm_nb._validation",
    "rbm_nb._xarray",
    "rbm_nb._config",
    "rbm_nb._engine",
    "rbm_nb._kernels",
    "rbm_nb.plot",
    "rbm_nb.accessors",
)

# Imports inside functions the core keeps on purpose, with the reason.
LAZY = {
    ("rbm_nb.accessors", "rbm_nb.quaternions"): "the accessor is registered as soon "
    "as xarray is imported; numba and the kernels load on its first use",
}


def _modules(package: Path) -> dict[str, Path]:
    found = {}
    for path in package.rglob("*.py"):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


@functools.cache
def import_edges(package: Path = PACKAGE) -> dict[str, dict[str, bool]]:
    """module -> {imported module of the package: imported inside a function}."""
    modules = _modules(package)
    edges: dict[str, dict[str, bool]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        out = edges.setdefault(name, {})

        def add(target: str, in_function: bool, out=out, name=name) -> None:
            if target in modules and target != name:
                out[target] = out.get(target, True) and in_function

        def visit(node: ast.AST, in_function: bool, name=name, is_package=is_package):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.If) and _is_type_checking(child):
                    for other in child.orelse:
                        visit(other, in_function)
                    continue
                inside = in_function or isinstance(
                    child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
                )
                if isinstance(child, ast.Import):
                    for alias in child.names:
                        add(alias.name, inside)
                elif isinstance(child, ast.ImportFrom):
                    if child.level:
                        base = name.split(".")
                        if not is_package:
                            base = base[:-1]
                        base = base[: len(base) - (child.level - 1)]
                        if child.module:
                            base = base + child.module.split(".")
                        source = ".".join(base)
                    else:
                        source = child.module or ""
                    for alias in child.names:
                        full = f"{source}.{alias.name}"
                        add(full if full in modules else source, inside)
                visit(child, inside)

        visit(ast.parse(path.read_text(encoding="utf-8")), False)
    return edges


def cycles(edges: dict[str, dict[str, bool]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def strong(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, {}):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            strong(v)
    return found


def _in_core(module: str) -> bool:
    return any(module == c or module.startswith(c + ".") for c in CORE)


def test_the_parser_sees_a_cycle_and_function_level_imports(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    (pkg / "b.py").write_text("def f():\n    from .a import x\n")
    (pkg / "c.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from . import a\n"
    )
    edges = import_edges(pkg)
    assert edges["pkg.b"] == {"pkg.a": True}
    assert edges["pkg.c"] == {}
    assert cycles(edges) == [["pkg.a", "pkg.b"]]


def test_no_import_cycle_touches_the_core():
    touching = [c for c in cycles(import_edges()) if any(_in_core(m) for m in c)]
    assert touching == []


def test_the_package_has_no_import_cycle():
    assert cycles(import_edges()) == []


@pytest.mark.parametrize("module", sorted(m for m in _modules(PACKAGE) if _in_core(m)))
def test_core_imports_its_own_modules_at_module_level(module):
    inside = sorted(
        t for t, fn in import_edges()[module].items() if fn and (module, t) not in LAZY
    )
    assert inside == [], f"{module} imports {inside} inside functions"


def test_the_engine_never_imports_the_facades():
    facades = {"rbm_nb.frames", "rbm_nb.transforms", "rbm_nb.lookups", "rbm_nb"}
    edges = import_edges()
    for module, targets in edges.items():
        if module.startswith("rbm_nb._engine") or module.startswith("rbm_nb._kernels"):
            assert not facades & set(targets), (module, sorted(targets))
