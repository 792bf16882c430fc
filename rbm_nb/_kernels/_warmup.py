"""Fill numba's on-disk cache with every rbm_nb kernel, the explorer's first.

Each kernel module declares the one signature each of its kernels is
compiled for (``@kernel(...)``, see :mod:`rbm_nb._kernels._jit`), and the
door hands kernels exactly those argument types. The warm-up therefore
compiles exactly the declared signatures, with no replay of the public API:
a new kernel is warmed up as soon as it is declared, and
``tests/test_zz_kernel_signatures.py`` fails if any call compiles something
else.

Order. The kernels notebook 06 (the head/eye explorer, also ``rbm-nb demo``
and ``rbm-nb app``) calls come first (:data:`EXPLORER`, recorded from a real
run of the notebook on the real and on the synthetic recording): the most
expensive of them, ``fused.lookup_chain``, at once, the others cheapest first
(the first cells need only cheap ones); then the others, most expensive first
(:data:`COST`, seconds measured on one core), so that a large one does not
start last and hold everything up.

Processes. numba compiles on one core, so the warm-up runs one worker
process per usable core (``--jobs N`` to choose). Each signature compiles at
most once over every process sharing the cache folder: workers, and also a
notebook's kernel or a test process that calls a kernel meanwhile
(:func:`rbm_nb._infra.numba_cache.compile_once`, a lock per signature in numba's
cache folder). A worker passes over a signature whose lock another process
holds and comes back to it at the end, when it only has to load it. Every
compile and every load of a worker is written to the account
(``rbm-nb-compiles.log`` in the cache folder), which is how progress is
counted: per signature, exactly.

Commands::

    python -m rbm_nb._kernels._warmup [-v] [--jobs N] [--status FILE]
        every signature, in the foreground (Binder's postBuild; a wheel's
        tests); the last line says "M of M kernel signatures ready (c
        compiled, l loaded from the cache ...)", c + l = M
    python -m rbm_nb._kernels._warmup --start [--jobs N] [--pids FILE] [--log FILE] [--background]
        starts the workers and returns at once (``.ci/setup.sh``, before the
        install has finished). --background: after the explorer's kernels
        the workers lower their priority (``nice``), as they keep compiling
        while the user works
    python -m rbm_nb._kernels._warmup --wait explorer|all [--pids FILE] [--status FILE]
        waits until the explorer's (or every) signature is ready, printing
        "N of M" with an estimate of the time left every 15 s
    python -m rbm_nb._kernels._warmup --report [--status FILE]
        one line: N of M ready, and the time the rest should take

Why the cache is found again: numba stores it next to the kernel sources
(``rbm_nb/_kernels/__pycache__``, inside site-packages for a normal install,
or under ``NUMBA_CACHE_DIR``) and keys it on each source file's path and
modification time, the function's bytecode and the CPU. Run it with ``-P`` or
from another working directory to compile an installed package rather than
a source tree in the working directory.

With ``--status FILE`` the command keeps ``FILE`` saying ``N M``: N of the M
declared kernel signatures are ready (compiled or loaded).
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._infra import numba_cache as _numba_cache
from .._infra.parallel import usable_cores
from ._jit import Declared, declared_kernels

__all__ = [
    "COST",
    "EXPLORER",
    "KernelStats",
    "kernel_dispatchers",
    "kernel_stats",
    "account_stats",
    "plan",
    "ready",
    "warm_up",
    "main",
]

# What notebook 06 calls, from a real run (nbclient, a fresh kernel, then the
# kernels with an overload listed), roughly in the order of use (the first
# cell loads the recording: times.*): the real recording needs all but
# qmul, the synthetic one also qmul. tests/project/test_warmup_explorer.py
# runs the explorer's cells again and fails if this list is out of date.
EXPLORER: tuple[str, ...] = (
    "times.ns_key_faults",
    "times.float_key_faults",
    "times.seconds_since",
    "quaternion.qmul",
    "quaternion.qconj",
    "quaternion.rotate_vectors",
    "resample.chain_step",
    "fused.lookup_chain",
    "rows.infinities",
    "rows.moving_signs",
    "masked_rows.masked_signs",
    "masked_rows.kept_translations",
    "gaze_rows.sight_components",
    "gaze_rows.windowed_slopes",
    "m4.column_extremes",
    "rotations.rotate_vectors_into",
    "velocity_fused.body_rates",
    "conversions.quaternion_from_matrix",
    # the scene's head path, simplified when the dashboard is built
    "simplify.split_worst_first",
    "simplify.cell_pass",
    # the scene's looked-up tracks: bounds, coarse copy, the path's blocks
    "one_mover.mover_summary",
    "one_mover.mover_poses",
    "one_mover.mover_translations",
)

# Seconds one process takes to compile the kernel from an empty cache on this
# project's 2-core machine (kernels of 3 s and more; the others count 1.5 s):
# a warm-up's account (``rbm_nb-compiles.log``) measured under a load of ~10,
# scaled by 0.35 to the quiet machine's total (the 88 signatures: ~460 s of
# one core). Only the order and the time estimate use it: a stale figure
# costs time, never a wrong result.
COST: dict[str, float] = {
    "squad_walk.squad_walk_parallel": 66.4,
    "squad_walk.squad_walk_scalar": 65.0,
    "squad_walk.squad_walk": 63.2,
    "fused.lookup_chain": 38.5,
    "squad_table.squad_table": 24.6,
    "velocity_chain.chain_body_rates": 23.5,
    "chain_prefill.prefill_chain": 21.4,
    "velocity_chain.chain_body_rates_parallel": 20.2,
    "fused.transform_chain_parallel": 16.9,
    "fused.lookup_chain_parallel": 15.4,
    "sdf.mesh_distances": 12.3,
    "rotations.rotate_vectors_into_parallel": 9.3,
    "rotations.qmul_into_parallel": 7.4,
    "rows.moving_signs": 6.3,
    "fused.transform_chain": 5.8,
    "quaternion.squad_evaluate": 3.8,
    "euler.euler_from_quaternion": 3.0,
}
DEFAULT_COST = 1.5

#: the role of the warm-up's processes in the account
ROLE = "warm-up"
#: seconds between two progress lines of --wait
PROGRESS_EVERY = 15.0


@dataclass(frozen=True)
class KernelStats:
    """Signatures ready, and how: compiled or loaded from the cache.

    Counted per declared signature: ``compiled + loaded == kernels`` once
    every signature is ready.
    """

    kernels: int
    compiled: int
    loaded: int
    cache_dirs: tuple[str, ...]


def short_name(kernel: Declared) -> str:
    """``module.function`` below ``rbm_nb._kernels`` (the names of EXPLORER and COST)."""
    return kernel.name.removeprefix("rbm_nb._kernels.")


def cost(kernel: Declared) -> float:
    return COST.get(short_name(kernel), DEFAULT_COST)


def plan() -> list[Declared]:
    """Every declared kernel in compile order: the explorer's, then the rest."""
    kernels = declared_kernels()
    # ties (most kernels have no measured cost) in the notebook's order of use
    first = sorted(
        (k for k in kernels if short_name(k) in EXPLORER),
        key=lambda k: (cost(k), EXPLORER.index(short_name(k))),
    )
    rest = [k for k in kernels if short_name(k) not in EXPLORER]
    # the explorer's costliest (lookup_chain) on one worker from the start, its
    # cheapest next on the other: the notebook's first cells need only cheap
    # ones (times.*), which a fresh clone then has before the URL
    return [first[-1], *first[:-1], *sorted(rest, key=cost, reverse=True)]


def explorer_kernels() -> list[Declared]:
    return [k for k in declared_kernels() if short_name(k) in EXPLORER]


def kernel_dispatchers() -> list[Any]:
    """Every declared kernel's numba dispatcher (importing the kernel modules)."""
    return [k.dispatcher for k in declared_kernels()]


@functools.cache  # parsing a signature costs ~0.1 ms: --wait asks often
def _args(kernel: Declared) -> tuple:
    # numba keys its cache on the signature as compile() receives it: a call
    # passes a tuple of types, so the declared string is parsed into one (a
    # string would be cached under another key that no call ever finds)
    from numba.core.sigutils import normalize_signature

    args, _ = normalize_signature(kernel.signature)
    return tuple(args)


def key(kernel: Declared) -> str:
    """The kernel's signature as the account names it."""
    return _numba_cache.signature_key(kernel.dispatcher, _args(kernel))


def _folders(kernels: list[Declared]) -> set[Path]:
    return {f for k in kernels if (f := _numba_cache.cache_folder(k.dispatcher))}


def ready(kernels: list[Declared] | None = None) -> dict[str, str]:
    """Signatures in numba's cache now: account key -> "compiled" or "loaded".

    Read from the account (any process's compile, a warm-up's loads), counting
    only lines written since the kernel sources last changed: numba keys its
    cache on the sources' modification times, so older lines describe
    entries it no longer uses.
    """
    kernels = declared_kernels() if kernels is None else kernels
    wanted = {key(k) for k in kernels}
    since = _numba_cache.sources_mtime()
    how: dict[str, str] = {}
    for folder in _folders(kernels):
        for row in _numba_cache.read_account(folder):
            if row.key in wanted and row.time >= since:
                # compiled wins over a later load of the same entry
                if how.get(row.key) != "compiled":
                    how[row.key] = row.outcome
    return how


def kernel_stats() -> KernelStats:
    """What this process compiled and loaded, per declared signature (numba's counts)."""
    kernels = declared_kernels()
    compiled = loaded = 0
    for k in kernels:
        stats = k.dispatcher.stats
        if any(stats.cache_misses.values()):
            compiled += 1
        elif any(stats.cache_hits.values()):
            loaded += 1
    dirs = tuple(sorted(str(f) for f in _folders(kernels)))
    return KernelStats(len(kernels), compiled, loaded, dirs)


def account_stats(since: float = 0.0) -> KernelStats:
    """Of every declared signature in the cache: compiled, or already there (the account).

    ``since`` (seconds since the epoch): a signature counts as compiled only
    if it was compiled after that moment (a warm-up's own work), else as
    loaded from the cache.
    """
    kernels = declared_kernels()
    how = ready(kernels)
    compiled = 0
    for folder in _folders(kernels):
        compiled += len(
            {
                row.key
                for row in _numba_cache.read_account(folder)
                if row.key in how and row.outcome == "compiled" and row.time >= since
            }
        )
    dirs = tuple(sorted(str(f) for f in _folders(kernels)))
    return KernelStats(len(kernels), compiled, len(how) - compiled, dirs)


def compile_signature(kernel: Declared, wait: bool = True) -> bool:
    """Compile the kernel's signature (or load it); False if another process has it.

    With ``wait=False`` a signature whose lock another process holds is left
    to it; with ``wait=True`` this waits for that process and then loads.
    """
    return kernel.dispatcher.compile(_args(kernel), wait=wait) is not None


def compile_all(
    kernels: list[Declared], verbose: bool = False, lower_after: int = -1
) -> None:
    """Make every kernel's signature ready, in order, sharing the work.

    A signature the account already lists is skipped; one another process is
    compiling is put off, then waited for (and loaded) at the end. With
    ``lower_after >= 0`` the process lowers its priority (``nice``) once that
    many kernels are behind it.
    """
    put_off = []
    for index, k in enumerate(kernels):
        if index == lower_after:
            _lower_priority()
        if key(k) in ready([k]):
            continue
        start = time.perf_counter()
        if not compile_signature(k, wait=False):
            put_off.append(k)
            continue
        if verbose:
            print(f"  {k.name}: {time.perf_counter() - start:.1f} s", flush=True)
    for k in put_off:
        if key(k) not in ready([k]):  # still compiling elsewhere: wait, load
            compile_signature(k, wait=True)


def _lower_priority() -> None:
    try:
        os.nice(10)
    except (AttributeError, OSError):
        pass


def warm_up(
    verbose: bool = False, jobs: int = 1, status: str | None = None
) -> KernelStats:
    """Compile (or load from the cache) every declared kernel signature.

    Parameters
    ----------
    verbose : bool, default False
        Print one line per compiled kernel (name, seconds).
    jobs : int, default 1
        Processes that compile at the same time: this one and ``jobs - 1``
        workers (``python -m rbm_nb._kernels._warmup --worker``, with this
        interpreter, environment and working directory, so that they import
        the same rbm_nb).
    status : str, optional
        A file kept saying ``"N M"``: N of the M declared signatures ready.

    Returns
    -------
    KernelStats
        Per declared signature: compiled or loaded from the cache
        (``compiled == 0`` after a previous warm-up: the cache is effective).

    Raises
    ------
    RuntimeError
        If a worker process fails (its output is in the message).
    """
    os.environ.setdefault(_numba_cache.ROLE_VARIABLE, ROLE)
    began = time.time()
    kernels = plan()
    _write_status(status, len(ready(kernels)), len(kernels))
    workers = [_spawn(verbose, background=False, log=None) for _ in range(jobs - 1)]
    try:
        compile_all(kernels, verbose)
    except BaseException:  # interrupted or failed: so are the workers
        for w in workers:
            w.kill()
            w.wait()
        raise
    for w in workers:
        output = w.communicate()[0] or ""
        if w.returncode != 0:
            raise RuntimeError(
                f"a warm-up worker (pid {w.pid}) failed with exit code "
                f"{w.returncode}:\n{output[-5000:]}"
            )
        if verbose and output.strip():
            print(output.rstrip("\n"), flush=True)
    stats = account_stats(since=began)
    _write_status(status, stats.compiled + stats.loaded, stats.kernels)
    return stats


def _command(verbose: bool, background: bool) -> list[str]:
    # -P again if this process has it: the workers must import this rbm_nb
    flags = ["-P"] if getattr(sys.flags, "safe_path", False) else []
    cmd = [sys.executable, *flags, "-m", "rbm_nb._kernels._warmup", "--worker"]
    return cmd + (["-v"] if verbose else []) + (["--background"] if background else [])


def _spawn(verbose: bool, background: bool, log: str | None) -> subprocess.Popen:
    env = dict(os.environ)
    env[_numba_cache.ROLE_VARIABLE] = ROLE
    if log is None:
        return subprocess.Popen(
            _command(verbose, background),
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=env,
        )
    with open(log, "a") as out:
        # its own session: the workers outlive the set-up script (and its
        # terminal's Ctrl-C) and are stopped by their pids
        return subprocess.Popen(
            _command(verbose, background),
            stdout=out,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env=env,
            start_new_session=True,
        )


def start(
    jobs: int, pids: str | None, log: str | None, background: bool, verbose: bool
) -> list[int]:
    """Start ``jobs`` workers that outlive this process; returns their pids."""
    _numba_cache.configure()  # stale caches dropped once, before the workers start
    log = log or os.devnull
    started = [_spawn(verbose, background, log).pid for _ in range(jobs)]
    if pids:
        _write_atomic(pids, " ".join(map(str, started)) + "\n")
    return started


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a zombie has finished
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(") ", 1)[1][:1] != "Z"
    except OSError:
        return True


def estimate(
    kernels: list[Declared], how: dict[str, str], seconds: dict[str, float], jobs: int
) -> float:
    """Seconds left for the signatures not yet ready (COST, scaled by this run's pace)."""
    left = [cost(k) for k in kernels if key(k) not in how]
    if not left:
        return 0.0
    done = [k for k in kernels if key(k) in seconds]
    expected = sum(cost(k) for k in done)
    pace = sum(seconds[key(k)] for k in done) / expected if expected else 1.0
    return max(max(left), sum(left) / max(jobs, 1)) * max(pace, 0.5)


def _compile_seconds(kernels: list[Declared]) -> dict[str, float]:
    since = _numba_cache.sources_mtime()
    out = {}
    for folder in _folders(kernels):
        for row in _numba_cache.read_account(folder):
            if row.outcome == "compiled" and row.time >= since:
                out[row.key] = row.seconds
    return out


def report(status: str | None, jobs: int) -> int:
    """Say how many signatures are ready and how long the explorer's and the rest take."""
    everything = plan()
    explorer = explorer_kernels()
    how = ready(everything)
    _write_status(status, len(how), len(everything))
    seconds = _compile_seconds(everything)
    mine = sum(key(k) in how for k in explorer)
    if mine == len(explorer):
        return wait("explorer", [], status, jobs)
    print(
        f"rbm_nb warm-up: {len(how)} of {len(everything)} kernel signatures ready "
        f"({mine} of the explorer's {len(explorer)}); compiling on in the "
        f"background, the explorer's first (about "
        f"{estimate(explorer, how, seconds, jobs):.0f} s), all in about "
        f"{estimate(everything, how, seconds, jobs):.0f} s; a notebook that needs "
        "one waits for it",
        flush=True,
    )
    return 0


def wait(target: str, pids: list[int], status: str | None, jobs: int) -> int:
    """Wait until the target's signatures are ready, printing "N of M" and the time left."""
    everything = plan()
    wanted = explorer_kernels() if target == "explorer" else everything
    start = time.perf_counter()
    last = start
    # the estimate is made when a signature gets ready and counts down from
    # there: the kernels being compiled meanwhile are getting closer too
    counted, base, since = -1, 0.0, start
    while True:
        how = ready(everything)
        _write_status(status, len(how), len(everything))
        have = sum(key(k) in how for k in wanted)
        if have == len(wanted):
            break
        if pids and not any(_alive(p) for p in pids):
            # the workers ended without finishing (killed, or failed: their
            # log says why); what is missing compiles on first use instead
            print(
                f"rbm_nb warm-up: the workers stopped with {have} of {len(wanted)} "
                "signatures ready; the others compile on first use",
                flush=True,
            )
            return 1
        now = time.perf_counter()
        if have != counted:
            counted, since = have, now
            base = estimate(wanted, how, _compile_seconds(everything), jobs)
        if now - last >= PROGRESS_EVERY:
            last = now
            left = max(base - (now - since), 1.0)
            whose = " (the explorer's)" if target == "explorer" else ""
            print(
                f"  {have} of {len(wanted)} kernel signatures ready{whose}, "
                f"about {left:.0f} s left",
                flush=True,
            )
        time.sleep(0.25)
    how = ready(everything)
    total = len(everything)
    if target == "explorer" and len(how) < total:
        print(
            f"rbm_nb warm-up: {len(how)} of {total} kernel signatures ready (all "
            f"{len(wanted)} of the explorer's); the other {total - len(how)} compile "
            f"in the background, about {estimate(everything, how, _compile_seconds(everything), jobs):.0f} s more",
            flush=True,
        )
    else:
        compiled = sum(v == "compiled" for v in how.values())
        print(
            f"rbm_nb warm-up: {len(how)} of {total} kernel signatures ready "
            f"({compiled} compiled, {len(how) - compiled} loaded from the cache), "
            f"{time.perf_counter() - start:.1f} s waited",
            flush=True,
        )
    return 0


def _write_atomic(path: str, text: str) -> None:
    partial = f"{path}.{os.getpid()}"
    with open(partial, "w") as f:
        f.write(text)
    os.replace(partial, path)


def _write_status(status: str | None, done: int, total: int) -> None:
    """``status`` says "done total", replaced whole (a reader never sees half)."""
    if status:
        _write_atomic(status, f"{done} {total}\n")


def _option(argv: list[str], name: str) -> str | None:
    if name not in argv:
        return None
    index = argv.index(name)
    return argv[index + 1] if index + 1 < len(argv) else ""


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    verbose = "-v" in argv or "--verbose" in argv
    status = _option(argv, "--status")
    if status == "":
        print("--status needs a file name")
        return 2
    if "--worker" in argv:  # one of the processes of a warm-up
        os.environ.setdefault(_numba_cache.ROLE_VARIABLE, ROLE)
        explorer = len(explorer_kernels()) if "--background" in argv else -1
        compile_all(plan(), verbose, lower_after=explorer)
        return 0
    jobs = usable_cores()
    value = _option(argv, "--jobs")
    if value is not None:
        if not value.isdigit() or int(value) < 1:
            print(f"--jobs needs a positive number of processes, got {value!r}")
            return 2
        jobs = int(value)
    pids_file = _option(argv, "--pids")
    if "--start" in argv:
        start(jobs, pids_file, _option(argv, "--log"), "--background" in argv, verbose)
        return 0
    if "--report" in argv:
        return report(status, jobs)
    target = _option(argv, "--wait")
    if target is not None:
        if target not in ("explorer", "all"):
            print(f"--wait needs explorer or all, got {target!r}")
            return 2
        pids: list[int] = []
        if pids_file:
            try:
                pids = [int(p) for p in Path(pids_file).read_text().split()]
            except (OSError, ValueError):
                pids = []
        return wait(target, pids, status, jobs)
    begin = time.perf_counter()
    stats = warm_up(verbose=verbose, jobs=jobs, status=status)
    where = ", ".join(stats.cache_dirs) or "no cache directory"
    print(
        f"rbm_nb warm-up: {stats.compiled + stats.loaded} of {stats.kernels} kernel "
        f"signatures ready ({stats.compiled} compiled, {stats.loaded} loaded from "
        f"the cache; {jobs} process{'es' if jobs > 1 else ''}), "
        f"{time.perf_counter() - begin:.1f} s; cache: {where}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
