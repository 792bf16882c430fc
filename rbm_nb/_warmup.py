"""Fill numba's on-disk cache with every rbm_nb kernel, so first calls are fast.

Each kernel module declares the one signature each of its kernels is
compiled for (``@kernel(...)``, see :mod:`rbm_nb._kernels._jit`), and the
door hands kernels exactly those argument types. The warm-up therefore
compiles exactly the declared signatures, module by module, with no replay
of the public API: a new kernel is warmed up as soon as it is declared, and
``tests/test_zz_kernel_signatures.py`` fails if any call compiles something
else.

Binder's ``postBuild`` and ``.ci/setup.sh`` run ``python -P -m rbm_nb._warmup``
once. Why the cache is found again: numba stores it next to the kernel
sources (``rbm_nb/_kernels/__pycache__``, inside site-packages for a normal
install, or under ``NUMBA_CACHE_DIR``) and keys it on each source file's path
and modification time, the function's bytecode and the CPU. Run it from
outside the repository (``-P`` or another working directory) so that it
compiles the installed package rather than the source tree.

Usage::

    python -m rbm_nb._warmup [-v]
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from typing import Any

from ._kernels._jit import Declared, declared_kernels

__all__ = ["KernelStats", "kernel_dispatchers", "kernel_stats", "warm_up", "main"]


@dataclass(frozen=True)
class KernelStats:
    """Signatures compiled and loaded from the cache, over all rbm_nb kernels."""

    kernels: int
    compiled: int
    loaded: int
    cache_dirs: tuple[str, ...]


def kernel_dispatchers() -> list[Any]:
    """Every declared kernel's numba dispatcher (importing the kernel modules)."""
    return [k.dispatcher for k in declared_kernels()]


def kernel_stats() -> KernelStats:
    """Totals of this process so far: what numba compiled, what it loaded."""
    dispatchers = kernel_dispatchers()
    compiled = loaded = 0
    dirs = set()
    for d in dispatchers:
        stats = d.stats
        compiled += sum(stats.cache_misses.values())
        loaded += sum(stats.cache_hits.values())
        if stats.cache_path:
            dirs.add(str(stats.cache_path))
    return KernelStats(len(dispatchers), compiled, loaded, tuple(sorted(dirs)))


def _compile(kernel: Declared) -> None:
    # Loads the signature from the cache when it is there, else compiles it.
    # numba keys its cache on the signature as compile() receives it: a call
    # passes a tuple of types, so the declared string is parsed into one (a
    # string would be cached under another key that no call ever finds).
    from numba.core.sigutils import normalize_signature

    args, _ = normalize_signature(kernel.signature)
    kernel.dispatcher.compile(tuple(args))


def warm_up(verbose: bool = False) -> KernelStats:
    """Compile (or load from the cache) every declared kernel signature.

    Parameters
    ----------
    verbose : bool, default False
        Print one line per kernel module (name, seconds, kernels).

    Returns
    -------
    KernelStats
        What this process compiled and loaded from the cache in total
        (``compiled == 0`` after a previous warm-up: the cache is effective).
    """
    by_module: dict[str, list[Declared]] = {}
    for k in declared_kernels():
        by_module.setdefault(k.dispatcher.py_func.__module__, []).append(k)
    for module, kernels in by_module.items():
        start = time.perf_counter()
        for k in kernels:
            _compile(k)
        if verbose:
            print(
                f"  {module}: {len(kernels)} kernels, "
                f"{time.perf_counter() - start:.1f} s",
                flush=True,
            )
    return kernel_stats()


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    verbose = "-v" in argv or "--verbose" in argv
    start = time.perf_counter()
    stats = warm_up(verbose=verbose)
    where = ", ".join(stats.cache_dirs) or "no cache directory"
    print(
        f"rbm_nb warm-up: {stats.compiled} kernel signatures compiled, "
        f"{stats.loaded} loaded from the cache ({stats.kernels} kernels), "
        f"{time.perf_counter() - start:.1f} s; cache: {where}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
