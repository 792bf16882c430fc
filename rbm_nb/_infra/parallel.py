"""When a kernel may run on several cores, and how many.

Kernels that loop over many independent rows have a ``prange`` twin compiled
with :data:`rbm_nb._infra.config.PARALLEL_KERNEL`. :func:`launch` chooses between
the serial kernel and its twin for each call. The twin is used only when all
of these hold:

* the call has at least :data:`MIN_ROWS` rows: below that, waking numba's
  thread pool costs more than the second core saves (the threshold is
  measured by ``benchmarks/bench_parallel.py``);
* more than one thread is allowed (:func:`threads`) and more than one core
  is free (:func:`free_cores`, read at most every :data:`RECHECK_AFTER`
  seconds): a parallel kernel splits its rows
  evenly between its threads, so a thread that has to share its core with
  another busy process holds up the whole call. Measured on the 2-core
  machine with another process keeping one core busy: 1M rotations took
  3.4-7.7 ms on 2 threads against 1.8 ms on 1 (see :data:`MIN_ROWS` for the
  lookups). As with OpenMP's ``OMP_DYNAMIC``, the thread count follows the
  load; results do not depend on it (twins are bit for bit equal);
* no other thread of this process is running a parallel kernel. numba's
  ``workqueue`` threading layer -- the only one a plain ``pip install`` is
  sure to have, as OpenMP needs the system's libgomp and TBB the ``tbb``
  wheel -- aborts the process when two threads launch parallel kernels at
  once. So parallel launches take one lock without waiting, and a thread
  that finds it taken runs the serial kernel instead. That is also what
  dask's threaded scheduler wants: its threads already keep the cores busy,
  and the serial kernels release the GIL (``nogil=True``);
* the process is not a fork of one that has launched parallel kernels:
  GNU OpenMP's thread pool does not survive ``fork`` and the child would
  hang.

The number of threads is ``RBM_NB_NUM_THREADS`` when set, else numba's own
setting (``NUMBA_NUM_THREADS``, by default the number of cores). Choosing
numba's threading layer is left to the user (``NUMBA_THREADING_LAYER``):
every layer is safe under the rules above.
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable
from typing import Any, Final, TypeVar

__all__ = ["MIN_ROWS", "ENV_THREADS", "threads", "usable_cores", "free_cores", "launch"]

#: Rows from which a parallel twin is used. benchmarks/bench_parallel.py on
#: the 2-core machine (fused lookup_transform and transform_points of the
#: head/eye chain, 2 threads against 1, best of 7 in turns):
#:
#: * other processes mostly idle: 1.25-1.35x at 1e3-5e3 rows, 1.7-1.8x at
#:   1e4, 1.8-1.85x from 2e4 to 1e6 (and 1.86x at 1e7);
#: * another process keeping one core busy: every parallel call waits ~5-7 ms
#:   for the second core (its worker thread must be scheduled), so 2 threads
#:   lose up to 5x below 2e4 rows and win 1.5-1.6x from 5e4. That is numba's
#:   ``omp`` layer (GNU libgomp, chosen here by default); ``workqueue`` waited
#:   ~0.1 ms under the same load.
#:
#: 50,000 rows (a ~6 ms serial call; the head/eye recording's lookups have
#: 76k-113k) keeps most of the gain on a quiet machine and loses little on
#: a busy one.
MIN_ROWS: Final = 50_000

#: Environment variable capping the threads of rbm_nb's parallel kernels.
ENV_THREADS: Final = "RBM_NB_NUM_THREADS"

#: Seconds for which a reading of the load (:func:`free_cores`) also stands
#: for the launches that follow. In a loop of parallel calls numba's workers
#: are still spinning from one call when the next starts, so each reading
#: has to look up every thread of this process in /proc: 180 µs with 6
#: threads, measured after a lookup of 76k rows on 2 threads (1.1 ms). A
#: process that starts keeping a core busy meanwhile makes the calls of at
#: most this long wait for the second core.
RECHECK_AFTER: Final = 0.02

# Linux's count of runnable threads, in its 4th field ("running/total"), and
# this process's threads (each with its state in its stat file)
_LOADAVG = "/proc/loadavg"
_TASKS = "/proc/self/task"

_LOCK = threading.Lock()
# pid of the process that first launched a parallel kernel (None: none yet)
_launched_in: int | None = None
# (_now(), free_cores()) of the last reading that launch took
_reading: tuple[float, int | None] = (-math.inf, None)
_now = time.monotonic

_Result = TypeVar("_Result")


def threads() -> int:
    """How many threads a parallel kernel may use (1: run serially).

    ``RBM_NB_NUM_THREADS`` when set (at most numba's ``NUMBA_NUM_THREADS``),
    else numba's setting.

    Raises
    ------
    ValueError
        If ``RBM_NB_NUM_THREADS`` is not a positive integer.
    """
    import numba

    available = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    raw = os.environ.get(ENV_THREADS, "").strip()
    if not raw:
        return available
    try:
        wanted = int(raw)
    except ValueError:
        wanted = 0
    if wanted < 1:
        raise ValueError(
            f"{ENV_THREADS} must be a positive integer (the number of threads "
            f"for rbm_nb's parallel kernels), got {raw!r}"
        )
    return min(wanted, available)


def _runnable() -> int:
    """Runnable threads right now, by Linux's count in ``/proc/loadavg``."""
    with open(_LOADAVG, "rb") as f:
        return int(f.read().split()[3].split(b"/")[0])


def _own_runnable() -> int:
    """Runnable threads of this process right now (``/proc/self/task``)."""
    count = 0
    for task in os.listdir(_TASKS):
        try:
            with open(f"{_TASKS}/{task}/stat", "rb") as f:
                stat = f.read()
        except OSError:  # the thread ended meanwhile
            continue
        # the state follows the command name, which is in parentheses
        state = stat.rindex(b")") + 2
        count += stat[state : state + 1] == b"R"
    return count


def usable_cores() -> int:
    """Cores in this process's affinity mask (all the machine's off Linux)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def free_cores() -> int | None:
    """Cores this process may use that no other process's thread wants now.

    The cores of the process's affinity mask less the threads of other
    processes that the kernel counts as runnable at this instant
    (``/proc/loadavg``'s count less this process's own runnable threads).
    This process's threads are left out: numba's workers keep spinning for
    a moment after a parallel call, and counting them made every other
    call of a loop serial; rbm_nb runs one parallel kernel per process at
    a time anyway. The count is read twice and the smaller kept: a busy
    process is runnable both times, while kernel workers and short-lived
    processes, which would otherwise cost a long call its second core now
    and then, rarely are. None where the counts are not available (not
    Linux): then the load is not taken into account.
    """
    cores = usable_cores()
    try:
        first = _runnable()
        if first <= 1:
            # only the calling thread: every core is free, and the 40 µs of
            # reading this process's threads are not needed
            return cores
        others = min(first - _own_runnable(), _runnable() - _own_runnable())
    except (OSError, ValueError, IndexError):
        return None
    return max(cores - max(others, 0), 1)


def _free_cores_lately() -> int | None:
    """:func:`free_cores`, read again only :data:`RECHECK_AFTER` after the last time."""
    global _reading
    now = _now()
    when, free = _reading
    if now - when < RECHECK_AFTER:
        return free
    free = free_cores()
    _reading = (now, free)
    return free


def launch(
    serial: Callable[..., _Result],
    parallel: Callable[..., _Result],
    rows: int,
    *args: Any,
) -> _Result:
    """``parallel(*args)`` when it is worth it and safe, else ``serial(*args)``.

    Parameters
    ----------
    serial, parallel : callable
        A kernel and its ``prange`` twin, taking the same arguments and
        returning the same results.
    rows : int
        Rows the call processes (compared with :data:`MIN_ROWS`).
    *args
        The kernel's arguments.
    """
    global _launched_in
    if rows < MIN_ROWS:
        return serial(*args)
    n = threads()
    if n > 1:
        free = _free_cores_lately()
        if free is not None:
            n = min(n, free)
    pid = os.getpid()
    if n < 2 or (_launched_in is not None and _launched_in != pid):
        return serial(*args)
    if not _LOCK.acquire(blocking=False):
        return serial(*args)
    try:
        import numba

        _launched_in = pid
        # numba's thread count is per calling thread: set it for this call only
        previous = numba.get_num_threads()
        numba.set_num_threads(n)
        try:
            return parallel(*args)
        finally:
            numba.set_num_threads(previous)
    finally:
        _LOCK.release()
