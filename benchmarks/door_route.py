"""Hops of ``transform_points`` through the code, eager and dask-backed, in figures.

For each route: *stays* (calls of rbm_nb functions, as
``transform_points_route.py`` traces them), the modules visited, and the
*climbs*: calls from a module into one that imports it (directly or through
others; the import graph of ``tests/core/test_module_graph.py``), i.e. a
lower layer calling a higher one back. Routes:

* eager, static chain: ``transform_points(p (1, 3), "world", "eye")``;
* eager, moving chain: the same through a moving head;
* dask: a dask-backed DataArray of 200 samples in 2 chunks through the
  moving chain, computed with the synchronous scheduler (graph building
  and the tasks both traced).

Run: ``PYTHONPATH=. python benchmarks/door_route.py [--tree]``
(``--tree`` also prints each route's call tree). Run it from another
checkout to compare (it traces the rbm_nb on ``sys.path``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent / "tests" / "core"))

from test_module_graph import import_edges  # noqa: E402
from transform_points_route import _module_of, _register, _route  # noqa: E402

import rbm_nb as rbm  # noqa: E402


def _importers() -> dict[str, set[str]]:
    """module -> every module that imports it, directly or through others."""
    package = Path(rbm.__file__).resolve().parent
    edges = {m: set(t) for m, t in import_edges(package).items()}
    above: dict[str, set[str]] = {}
    for start in edges:
        seen, todo = set(), [start]
        while todo:
            m = todo.pop()
            for t in edges.get(m, ()):
                if t not in seen:
                    seen.add(t)
                    todo.append(t)
        for t in seen:
            above.setdefault(t, set()).add(start)
    return above


def _figures(route, importers) -> tuple[int, int, int, list[str]]:
    modules = [_module_of(n) for _, n in route]
    stack: list[str] = []
    climbs = []
    for (depth, name), module in zip(route, modules, strict=True):
        del stack[depth:]
        caller = stack[-1] if stack else None
        if caller is not None and caller in importers.get(module, set()):
            pass  # a call down the import graph
        elif caller is not None and module in importers.get(caller, set()):
            climbs.append(f"{caller} -> {name}")
        stack.append(module)
    return len(route), len(set(modules)), len(climbs), climbs


def _dask_call():
    import dask.array as da
    import xarray as xr

    t = np.arange(200) * 0.005
    arr = xr.DataArray(
        da.from_array(np.random.default_rng(0).normal(size=(200, 3)), chunks=(100, 3)),
        {"time": t},
        ("time", "cartesian_axis"),
        attrs={"reference_frame": "eye", "representation_frame": "eye"},
    )
    return lambda: rbm.transform_points(arr, "world").compute(scheduler="sync")


def main() -> None:
    tree = "--tree" in sys.argv
    importers = _importers()
    p = np.array([[0.1, 0.2, 0.3]])
    routes = []
    for label, moving in (("static chain", False), ("moving chain", True)):
        _register(moving)
        rbm.transform_points(p, "world", "eye")  # compile, fill the caches
        routes.append(
            (f"eager, {label}", _route(lambda: rbm.transform_points(p, "world", "eye")))
        )
    _register(True)
    call = _dask_call()
    call()
    routes.append(("dask, moving chain (2 chunks)", _route(call)))
    print(f"rbm_nb at {Path(rbm.__file__).parent}")
    for label, route in routes:
        stays, modules, n_climbs, climbs = _figures(route, importers)
        print(f"{label}: {stays} stays, {modules} modules, {n_climbs} climbs")
        for c in climbs:
            print(f"    climb: {c}")
        if tree:
            for d, n in route:
                print(f"{'  ' * d}{n}")


if __name__ == "__main__":
    main()
