"""The import graph of rbm_nb: no cycles, whatever kind of import makes them.

Every ``import``/``from ... import`` statement of every module of the package
is parsed with :mod:`ast`: module level, inside functions and classes, and
under ``if TYPE_CHECKING:`` (those never run, but a loop a type checker needs
is still a loop a reader has to untangle). An edge goes from a module to
each module of the package it imports; ``from pkg import name`` counts as
importing ``pkg.name`` when that is a module, else ``pkg`` itself (so
importing the top package ``rbm_nb``, whose ``TYPE_CHECKING`` block names
every submodule, from inside the package is a loop).

Imports of package modules inside functions are few (``MAX_IN_FUNCTION``)
and each says why on its line or the line above: ``# lazy (import time):``,
``# lazy (optional dependency):`` or ``# lazy (loop):``.
``benchmarks/module_graph_stats.py`` prints the figures.
"""

from __future__ import annotations

import ast
import functools
import re
from dataclasses import dataclass
from pathlib import Path

import pytest
from conftest import REPO

PACKAGE = REPO / "rbm_nb"

# The frame core: intra-package imports here are all at module level (imports
# inside functions are left for optional third-party dependencies).
CORE = (
    "rbm_nb.core",
    "rbm_nb.errors",
    "rbm_nb._door",
    "rbm_nb._infra.config",
    "rbm_nb._engine",
    "rbm_nb._kernels",
)

# Imports inside functions the core keeps on purpose (the reason is the
# ``# lazy (...)`` comment at the import).
LAZY = {("rbm_nb.core.accessors", "rbm_nb.core.quaternions")}

# At most this many import statements inside functions import a package module.
MAX_IN_FUNCTION = 25

# The layers of the package, bottom up: what ``ls rbm_nb`` shows. A module
# imports from its own layer and the layers below it, never from above.
LAYERS = (
    ("rbm_nb._version", "rbm_nb.errors", "rbm_nb._infra"),
    ("rbm_nb._kernels",),
    ("rbm_nb._engine",),
    ("rbm_nb._door",),
    ("rbm_nb.core",),
    ("rbm_nb.io", "rbm_nb.sdf"),
    ("rbm_nb.widgets", "rbm_nb.scene"),
    # bags are read into frames and played into scenes and players
    ("rbm_nb.ros",),
    # the example data write their synthetic bag; studies read bags
    ("rbm_nb.data", "rbm_nb.study"),
    ("rbm_nb.app",),
    ("rbm_nb",),
)
# the package root holds the layers and nothing else: at most this many entries
MAX_ROOT_ENTRIES = 20

# Loops between sub-packages (each module of ``rbm_nb.<name>`` counted as
# ``rbm_nb.<name>``), known and left for the move of code between layers
# (issue 32, items 5 and 6): no module imports itself back, but the packages do.
# scene -> widgets: (scene takes its time rule from _engine.time, not widgets)
# and scene.{scene,export,widget} widgets.player, while widgets.slider_panel
# builds a scene.widget.SceneWidget. The test fails when a new loop appears
# and when this one goes (then delete it here).
KNOWN_PACKAGE_LOOPS = [["rbm_nb.scene", "rbm_nb.widgets"]]


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


# The comment that keeps an import inside a function, on the import's line or
# the line above: ``# lazy (import time): ...``, ``# lazy (optional
# dependency): ...`` or ``# lazy (loop): ...``, followed by the why.
REASON = re.compile(r"#\s*lazy \((import time|optional dependency|loop)\):\s*\S.*")


@dataclass(frozen=True)
class Import:
    """One module of the package imported by one statement."""

    source: str  # the importing module
    target: str  # the imported module of the package
    line: int
    in_function: bool
    type_checking: bool
    reason: str  # the ``# lazy (...)`` comment, or ""


@functools.cache
def graph(package: Path = PACKAGE) -> dict[str, tuple[Import, ...]]:
    """module -> every import of a package module it makes (all of them:
    module level, inside functions and classes, under ``TYPE_CHECKING``)."""
    modules = _modules(package)
    result: dict[str, tuple[Import, ...]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        found: list[Import] = []

        def reason_of(lineno: int, lines=lines) -> str:
            for candidate in (
                lines[lineno - 1],
                lines[lineno - 2] if lineno > 1 else "",
            ):
                match = REASON.search(candidate)
                if match:
                    return match.group(0)
            return ""

        def add(target, node, inside, typing_only, name=name, found=found):
            if target in modules and target != name:
                found.append(
                    Import(
                        name,
                        target,
                        node.lineno,
                        inside,
                        typing_only,
                        reason_of(node.lineno) if inside else "",
                    )
                )

        def visit(node, inside, typing_only, name=name, is_package=is_package):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.If) and _is_type_checking(child):
                    for other in child.body:
                        visit_one(other, inside, True)
                    for other in child.orelse:
                        visit_one(other, inside, typing_only)
                else:
                    visit_one(child, inside, typing_only)

        def visit_one(child, inside, typing_only, name=name, is_package=is_package):
            if isinstance(child, ast.Import):
                for alias in child.names:
                    add(alias.name, child, inside, typing_only)
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
                    add(full if full in modules else source, child, inside, typing_only)
            function = isinstance(
                child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
            )
            visit(child, inside or function, typing_only)

        visit(ast.parse(text), False, False)
        result[name] = tuple(found)
    return result


def import_edges(
    package: Path = PACKAGE, type_checking: bool = True
) -> dict[str, dict[str, bool]]:
    """module -> {imported module of the package: only ever inside functions}."""
    edges: dict[str, dict[str, bool]] = {}
    for name, found in graph(package).items():
        out = edges.setdefault(name, {})
        for i in found:
            if type_checking or not i.type_checking:
                out[i.target] = out.get(i.target, True) and i.in_function
    return edges


def in_function_imports(package: Path = PACKAGE) -> list[tuple[str, int]]:
    """(module, line) of every import statement inside a function that
    imports a module of the package."""
    return sorted(
        {
            (i.source, i.line)
            for found in graph(package).values()
            for i in found
            if i.in_function
        }
    )


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


def package_edges(edges: dict[str, dict[str, bool]]) -> dict[str, dict[str, bool]]:
    """The graph between ``rbm_nb`` and its sub-packages/root modules."""

    def top(module: str) -> str:
        return ".".join(module.split(".")[:2])

    collapsed: dict[str, dict[str, bool]] = {}
    for module, targets in edges.items():
        out = collapsed.setdefault(top(module), {})
        for target in targets:
            if top(target) != top(module):
                out[top(target)] = True
    return collapsed


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
    assert edges["pkg.c"] == {"pkg.a": False}
    assert import_edges(pkg, type_checking=False)["pkg.c"] == {}
    assert cycles(edges) == [["pkg.a", "pkg.b"]]
    assert in_function_imports(pkg) == [("pkg.b", 2)]
    assert graph(pkg)["pkg.b"][0].reason == ""


def test_the_parser_sees_a_type_checking_loop_and_reasons(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text(
        "import typing\nif typing.TYPE_CHECKING:\n    from . import sub\n"
    )
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "m.py").write_text(
        "def f():\n"
        "    # lazy (import time): pkg pulls in numba\n"
        "    import pkg\n"
        "def g():\n"
        "    from .. import sub  # lazy (optional dependency): needs foo\n"
        "def h():\n"
        "    # lazy: no kind given\n"
        "    from pkg import sub\n"
    )
    found = {i.line: i.reason for i in graph(pkg)["pkg.sub.m"]}
    assert found[3].startswith("# lazy (import time): pkg")
    assert found[5].startswith("# lazy (optional dependency)")
    assert found[8] == ""
    assert cycles(import_edges(pkg)) == []
    (pkg / "__init__.py").write_text(
        "import typing\nif typing.TYPE_CHECKING:\n    from .sub import m\n"
    )
    graph.cache_clear()
    assert cycles(import_edges(pkg)) == [["pkg", "pkg.sub.m"]]
    assert cycles(import_edges(pkg, type_checking=False)) == []
    assert cycles(package_edges(import_edges(pkg))) == [["pkg", "pkg.sub"]]


def test_no_import_cycle_touches_the_core():
    touching = [c for c in cycles(import_edges()) if any(_in_core(m) for m in c)]
    assert touching == []


def test_the_package_has_no_import_cycle():
    """TYPE_CHECKING and in-function imports included."""
    assert cycles(import_edges()) == []


def test_the_sub_packages_have_no_other_loop_than_the_known_ones():
    assert sorted(cycles(package_edges(import_edges()))) == KNOWN_PACKAGE_LOOPS


def test_few_imports_of_the_package_inside_functions_each_with_a_reason():
    inside = [i for found in graph().values() for i in found if i.in_function]
    without = sorted(
        f"{i.source}:{i.line} -> {i.target}" for i in inside if not i.reason
    )
    assert without == [], "imports inside functions need a '# lazy (...): why' comment"
    statements = in_function_imports()
    assert len(statements) <= MAX_IN_FUNCTION, statements


@pytest.mark.parametrize("module", sorted(m for m in _modules(PACKAGE) if _in_core(m)))
def test_core_imports_its_own_modules_at_module_level(module):
    inside = sorted(
        t for t, fn in import_edges()[module].items() if fn and (module, t) not in LAZY
    )
    assert inside == [], f"{module} imports {inside} inside functions"


def test_the_engine_never_imports_the_facades():
    facades = {
        "rbm_nb.core.frames",
        "rbm_nb.core.transforms",
        "rbm_nb.core.lookups",
        "rbm_nb",
    }
    edges = import_edges()
    for module, targets in edges.items():
        if module.startswith("rbm_nb._engine") or module.startswith("rbm_nb._kernels"):
            assert not facades & set(targets), (module, sorted(targets))


def _layer_of(module: str) -> int:
    top = ".".join(module.split(".")[:2])
    for level, names in enumerate(LAYERS):
        if top in names:
            return level
    raise AssertionError(f"{top} is in no layer of LAYERS")


def test_the_root_shows_the_layers():
    """``ls rbm_nb``: the layers' folders and modules, nothing else."""
    entries = {
        p.stem if p.suffix == ".py" else p.name
        for p in PACKAGE.iterdir()
        if (p.suffix == ".py" and p.name != "__init__.py")
        or (p.is_dir() and (p / "__init__.py").exists())
    }
    declared = {name.split(".")[1] for names in LAYERS[:-1] for name in names}
    assert entries == declared
    assert len(entries) + 1 <= MAX_ROOT_ENTRIES  # + __init__.py


def test_layers_import_only_downwards():
    upward = {
        (source, target)
        for source, targets in import_edges().items()
        for target in targets
        if _layer_of(target) > _layer_of(source)
    }
    assert upward == set()
