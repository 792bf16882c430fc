"""Compile time of the chain and squad kernels, from an empty numba cache.

Compiles each kernel's declared signature in one fresh process with
``NUMBA_CACHE_DIR`` set to a new empty folder (nothing is loaded from a
cache), in a fixed order, and prints the seconds each took (helpers shared
by several kernels are compiled with the first that calls them) and the
total. Run it from the tree to measure:

    PYTHONPATH=TREE .venv/bin/python benchmarks/kernel_compile_times.py

Optional arguments: kernel names (``module.function``) to compile instead
of the default list.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time

DEFAULT = [
    "quaternion.squad",
    "resample.interp_linear",
    "resample.hold_last",
    "resample.hold_index",
    "squad_walk.squad_walk",
    "squad_walk.squad_walk_parallel",
    "squad_walk.squad_walk_scalar",
    "fused.squad_table",
    "fused.lookup_chain",
    "fused.transform_chain",
    "fused.prefill_chain",
    "fused.lookup_chain_parallel",
    "fused.transform_chain_parallel",
    "velocity_chain.chain_body_rates",
    "velocity_chain.chain_body_rates_parallel",
]


def main(names: list[str]) -> None:
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="rbm_nb_compile_")
    from rbm_nb._kernels import _jit

    declared = {
        k.name.replace("rbm_nb._kernels.", ""): k for k in _jit.declared_kernels()
    }
    # a kernel may have moved to another module: match by function name too
    by_func = {name.rpartition(".")[2]: k for name, k in declared.items()}
    total = 0.0
    for name in names:
        k = declared.get(name) or by_func.get(name.rpartition(".")[2])
        if k is None:
            print(f"{name:45s} not declared")
            continue
        t0 = time.perf_counter()
        k.dispatcher.compile(k.signature)
        dt = time.perf_counter() - t0
        total += dt
        print(f"{name:45s} {dt:7.2f} s")
    print(f"{'total':45s} {total:7.2f} s")


if __name__ == "__main__":
    main(sys.argv[1:] or DEFAULT)
