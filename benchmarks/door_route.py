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

With ``--facades``, the other facades' routes too (issue 32, item 2): per
call, its stays, modules, climbs, the *door calls* (calls from a facade
module of ``rbm_nb.core`` into a function or a class constructor of
``rbm_nb._door``; a method of a value the door returned, such as
``args.result(out)``, is the facade using that value, as
``tests/core/test_one_door_call.py`` counts), the *own checks* (calls
of the facade module's private helpers whose name says they check or
unpack: ``_check*``, ``_unpack``, ``_as_*``, ``_split``, ``_checked``,
``_poses``, ``_vectors``; the facades' ``_rows`` are layout helpers) and
the depth of the first kernel.

Run: ``PYTHONPATH=. python benchmarks/door_route.py [--tree] [--facades]
[--only-facades] [--compare OTHER_CHECKOUT]`` (``--tree`` also prints each
route's call tree; ``--only-facades`` skips the transform_points routes;
``--compare`` runs the facades' door-call count in the other checkout too, in
a subprocess on its rbm_nb, and prints before -> after per facade). It
traces the rbm_nb on ``sys.path``.
"""

from __future__ import annotations

import json
import os
import subprocess
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


_OWN_CHECKS = ("_check", "_unpack", "_as_", "_split", "_checked", "_poses",
               "_vectors", "_paired_rows", "_resolve_dim_axis", "_dim_axis")  # fmt: skip


def _facade_calls() -> list[tuple[str, object]]:
    """The calls ``tests/core/test_one_door_call.py`` holds to one door call."""
    from test_one_door_call import FACADE_CALLS

    return FACADE_CALLS


def _facade_figures(route) -> tuple[int, int, int | None]:
    """(door calls, own checks, kernel depth) of one facade's route."""
    stack: list[str] = []
    door = own = 0
    kernel = None
    for depth, name in route:
        del stack[depth:]
        module = _module_of(name)
        caller = stack[-1] if stack else None
        qualname = name.split(" ")[0][len(module) + 1 :]
        entry = "." not in qualname or qualname.endswith(".__init__")
        if (
            caller
            and caller.startswith("rbm_nb.core.")
            and module.startswith("rbm_nb._door")
            and entry
        ):
            door += 1
        function = name.split(" ")[0].rsplit(".", 1)[-1]
        if module.startswith("rbm_nb.core.") and function.startswith(_OWN_CHECKS):
            own += 1
        if kernel is None and name.endswith("[numba kernel]"):
            kernel = depth
        stack.append(module)
    return door, own, kernel


def _door_counts(importers) -> dict[str, list]:
    """label -> [stays, modules, climbs, door calls, own checks, kernel depth]."""
    _register(True)
    out = {}
    for label, call in _facade_calls():
        call()  # compile, fill the caches
        route = _route(call)
        stays, modules, n_climbs, _ = _figures(route, importers)
        out[label] = [stays, modules, n_climbs, *_facade_figures(route)]
    return out


def facades(importers, other: str | None = None) -> None:
    counts = _door_counts(importers)
    before = {}
    if other is not None:
        env = dict(os.environ, PYTHONPATH=str(Path(other).resolve()))
        done = subprocess.run(
            [sys.executable, __file__, "--door-json"], env=env, cwd=other,
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        before = json.loads(done.stdout.strip().splitlines()[-1])
        print(f"\nbefore: rbm_nb at {other}")
    print("\nfacades: stays, modules, climbs, door calls, own checks, kernel depth")
    for label, (stays, modules, n_climbs, door, own, kernel) in counts.items():
        b = before.get(label)
        was = [f"{b[k]:3d} -> " if b else "" for k in range(4)]
        print(
            f"  {label:34s} {was[0]}{stays:3d} stays {was[1]}{modules:2d} modules "
            f"{was[2]}{n_climbs:2d} climbs {was[3]}{door:2d} door calls "
            f"{own:2d} own checks  kernel at {kernel}"
        )
    if before:
        many = [k for k, v in counts.items() if v[3] != 1]
        was_many = [k for k, v in before.items() if v[3] != 1]
        print(
            f"facades not at one door call: {len(was_many)} of {len(before)} before, "
            f"{len(many)} of {len(counts)} now ({', '.join(many) or 'none'})"
        )


def main() -> None:
    tree = "--tree" in sys.argv
    importers = _importers()
    if "--door-json" in sys.argv:  # the --compare subprocess
        print(json.dumps(_door_counts(importers)))
        return
    other = None
    if "--compare" in sys.argv:
        other = sys.argv[sys.argv.index("--compare") + 1]
    if "--only-facades" in sys.argv:
        facades(importers, other)
        return
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
    if "--facades" in sys.argv:
        facades(importers, other)


if __name__ == "__main__":
    main()
