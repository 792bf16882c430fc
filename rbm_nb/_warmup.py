"""Fill numba's on-disk cache with every rbm_nb kernel, so first calls are fast.

Each kernel module declares the one signature each of its kernels is
compiled for (``@kernel(...)``, see :mod:`rbm_nb._kernels._jit`), and the
door hands kernels exactly those argument types. The warm-up therefore
compiles exactly the declared signatures, module by module, with no replay
of the public API: a new kernel is warmed up as soon as it is declared, and
``tests/test_zz_kernel_signatures.py`` fails if any call compiles something
else.

Binder's ``postBuild`` and ``.ci/setup.sh`` run ``python -m rbm_nb._warmup``
once. numba compiles on one core, so the command starts a helper process for
each further usable core (``--jobs N`` to choose); every process claims
kernels one at a time (a file created exclusively in a shared folder) until
none is left, so that a slow kernel does not hold up the others.

Why the cache is found again: numba stores it next to the kernel sources
(``rbm_nb/_kernels/__pycache__``, inside site-packages for a normal install,
or under ``NUMBA_CACHE_DIR``) and keys it on each source file's path and
modification time, the function's bytecode and the CPU. Run it with ``-P`` or
from another working directory to compile an installed package rather than
a source tree in the working directory.

With ``--status FILE`` the processes keep ``FILE`` saying ``N M``: N of the
M declared kernel signatures are ready (compiled or loaded), for a caller
that shows progress (``.ci/setup.sh`` prints "N of M").

Usage::

    python -m rbm_nb._warmup [-v] [--jobs N] [--status FILE]
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from typing import Any

from ._kernels._jit import Declared, declared_kernels
from ._parallel import usable_cores

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


def warm_up(
    verbose: bool = False, jobs: int = 1, status: str | None = None
) -> KernelStats:
    """Compile (or load from the cache) every declared kernel signature.

    Parameters
    ----------
    verbose : bool, default False
        Print one line per kernel module (name, seconds, kernels); with
        several jobs, one line per kernel.
    jobs : int, default 1
        Processes that compile at the same time: this one and ``jobs - 1``
        helpers (``python -m rbm_nb._warmup --claims DIR``, with this
        interpreter, environment and working directory, so that they import
        the same rbm_nb).
    status : str, optional
        A file kept saying ``"N M"``: N of the M declared signatures ready.

    Returns
    -------
    KernelStats
        What the processes compiled and loaded from the cache in total
        (``compiled == 0`` after a previous warm-up: the cache is effective).

    Raises
    ------
    RuntimeError
        If a helper process fails (its output is in the message).
    """
    if jobs > 1:
        return _warm_up_in_parallel(verbose, jobs, status)
    by_module: dict[str, list[Declared]] = {}
    total = len(declared_kernels())
    done = 0
    _write_status(status, done, total)
    for k in declared_kernels():
        by_module.setdefault(k.dispatcher.py_func.__module__, []).append(k)
    for module, kernels in by_module.items():
        start = time.perf_counter()
        for k in kernels:
            _compile(k)
            done += 1
            _write_status(status, done, total)
        if verbose:
            print(
                f"  {module}: {len(kernels)} kernels, "
                f"{time.perf_counter() - start:.1f} s",
                flush=True,
            )
    return kernel_stats()


def _write_status(status: str | None, done: int, total: int) -> None:
    """``status`` says "done total", replaced whole (a reader never sees half)."""
    if not status:
        return
    partial = f"{status}.{os.getpid()}"
    with open(partial, "w") as f:
        f.write(f"{done} {total}\n")
    os.replace(partial, status)


def _compile_claimed(claims: str, verbose: bool, status: str | None = None) -> None:
    """Compile every kernel no other process has claimed yet, claiming each.

    A claimed kernel's file gets a ``.done`` twin once it is ready, so the
    processes can count what all of them have done.
    """
    kernels = declared_kernels()
    for index, k in enumerate(kernels):
        try:
            os.close(os.open(os.path.join(claims, str(index)), os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            continue  # another process has it
        start = time.perf_counter()
        _compile(k)
        os.close(os.open(os.path.join(claims, f"{index}.done"), os.O_CREAT))
        done = sum(name.endswith(".done") for name in os.listdir(claims))
        _write_status(status, done, len(kernels))
        if verbose:
            print(f"  {k.name}: {time.perf_counter() - start:.1f} s", flush=True)


def _warm_up_in_parallel(
    verbose: bool, jobs: int, status: str | None = None
) -> KernelStats:
    claims = tempfile.mkdtemp(prefix="rbm_nb-warm-up-")
    try:
        _write_status(status, 0, len(declared_kernels()))
        # -P again if this process has it: the helpers must import this rbm_nb
        flags = ["-P"] if getattr(sys.flags, "safe_path", False) else []
        cmd = [sys.executable, *flags, "-m", "rbm_nb._warmup", "--claims", claims]
        cmd += ["-v"] if verbose else []
        cmd += ["--status", status] if status else []
        helpers = [
            subprocess.Popen(
                cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
            )
            for _ in range(jobs - 1)
        ]
        try:
            _compile_claimed(claims, verbose, status)
        except BaseException:  # interrupted or failed: so are the helpers
            for h in helpers:
                h.kill()
            raise
        finally:
            outputs = [h.communicate()[0] for h in helpers]
        totals = kernel_stats()
        compiled, loaded, dirs = totals.compiled, totals.loaded, set(totals.cache_dirs)
        for helper, output in zip(helpers, outputs, strict=True):
            *lines, last = output.rstrip("\n").split("\n")
            if helper.returncode != 0 or not last.startswith("{"):
                raise RuntimeError(
                    f"a warm-up helper (pid {helper.pid}) failed with exit code "
                    f"{helper.returncode}:\n{output[-5000:]}"
                )
            if lines:
                print("\n".join(lines), flush=True)
            stats = json.loads(last)
            compiled += stats["compiled"]
            loaded += stats["loaded"]
            dirs.update(stats["cache_dirs"])
        return KernelStats(totals.kernels, compiled, loaded, tuple(sorted(dirs)))
    finally:
        shutil.rmtree(claims, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    verbose = "-v" in argv or "--verbose" in argv
    status = None
    if "--status" in argv:
        status = argv[argv.index("--status") + 1] if argv[-1] != "--status" else ""
        if not status:
            print("--status needs a file name")
            return 2
    if "--claims" in argv:  # a helper of a parallel warm-up
        _compile_claimed(argv[argv.index("--claims") + 1], verbose, status)
        print(json.dumps(kernel_stats().__dict__))
        return 0
    jobs = usable_cores()
    if "--jobs" in argv:
        value = argv[argv.index("--jobs") + 1] if argv[-1] != "--jobs" else ""
        if not value.isdigit() or int(value) < 1:
            print(f"--jobs needs a positive number of processes, got {value!r}")
            return 2
        jobs = int(value)
    start = time.perf_counter()
    stats = warm_up(verbose=verbose, jobs=jobs, status=status)
    where = ", ".join(stats.cache_dirs) or "no cache directory"
    # "M of M": the same total as the progress, whatever numba recompiled
    print(
        f"rbm_nb warm-up: {stats.kernels} of {stats.kernels} kernel signatures "
        f"ready ({stats.compiled} compiled, {stats.loaded} loaded from the cache; "
        f"{jobs} process{'es' if jobs > 1 else ''}), "
        f"{time.perf_counter() - start:.1f} s; cache: {where}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
