"""The import graph of rbm_nb in figures: loops and imports inside functions.

Every ``import`` statement of every module is parsed with :mod:`ast`
(module level, inside functions, inside ``if TYPE_CHECKING:``). Prints the
strongly connected components of more than one module (the loops), and every
import of a package module made inside a function with the reason comment
it carries (``# lazy: ...`` on the line of the import or on the line above).

Run: ``PYTHONPATH=. python benchmarks/module_graph_stats.py [path/to/rbm_nb]``.
The parser is the one of ``tests/core/test_module_graph.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "tests" / "core"))

from test_module_graph import (  # noqa: E402
    cycles,
    graph,
    import_edges,
    in_function_imports,
    package_edges,
)


def main(package: Path) -> None:
    imports = graph(package)
    edges = {m: {i.target for i in found} for m, found in imports.items()}
    loops = cycles(edges)
    inside = sorted(
        {
            (i.source, i.line, i.target, i.reason): i
            for found in imports.values()
            for i in found
            if i.in_function
        }.values(),
        key=lambda i: (i.source, i.line),
    )
    type_checking = [i for found in imports.values() for i in found if i.type_checking]
    print(f"package: {package}")
    print(f"modules: {len(imports)}")
    print(f"loops (TYPE_CHECKING and in-function imports counted): {len(loops)}")
    for loop in loops:
        print("  " + " <-> ".join(loop))
    between_packages = cycles(package_edges(import_edges(package)))
    print(f"loops between sub-packages: {len(between_packages)}")
    for loop in between_packages:
        print("  " + " <-> ".join(loop))
    print(f"TYPE_CHECKING imports of package modules: {len(type_checking)}")
    statements = in_function_imports(package)
    print(f"in-function import statements of package modules: {len(statements)}")
    without = [i for i in inside if not i.reason]
    print(f"  without a reason comment: {len(without)}")
    for i in inside:
        print(f"  {i.source}:{i.line} -> {i.target}  [{i.reason or 'no reason'}]")


if __name__ == "__main__":
    main(Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else REPO / "rbm_nb")
