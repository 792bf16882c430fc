"""A local dask.distributed cluster set up for studies of long recordings.

Two things make a stock ``LocalCluster`` slower than it needs to be for
rbm_nb's analyses, and one makes it less private than it should be:

* distributed's nanny starts every worker with ``MALLOC_TRIM_THRESHOLD_``
  set, which also pins glibc's mmap threshold at 128 kB: every array above
  it is a fresh mapping that the next task page-faults in again. An hour of
  eye data is arrays of tens of MB, and on 2 cores the faults cost the
  workers a third more CPU than the same analysis in a plain loop
  (``benchmarks/bench_study.py``: 620k faults against 233k).
  :data:`WORKER_SETTINGS` keeps arrays up to 32 MB on the heap and 256 MB
  of freed heap.
* the statistical profiler samples every worker's stack every 10 ms;
  it is switched off.
* each worker would run rbm_nb's parallel kernels on every core while the
  other workers do the same; :func:`local_cluster` gives each worker its
  share of the cores (``RBM_NB_NUM_THREADS``, see :mod:`rbm_nb._infra.parallel`).
* the scheduler and workers listen on local ports; :func:`local_cluster`
  secures them with a throw-away TLS certificate (distributed's
  ``Security.temporary()``), so only this process's clients can connect:
  the certificate is the token.
* distributed serves plain HTTP beside its protocol -- the dashboard, and
  on every scheduler and worker routes such as ``/metrics``,
  ``/json/identity.json``, ``/health`` and the workers' logs and call
  stacks -- without credentials, on 8787 or a free port. Unless the
  dashboard is asked for, :func:`local_cluster` gives those servers no
  route at all (every request is answered 404) and binds them to
  127.0.0.1; asked for, the dashboard and the routes are served on a free
  port of 127.0.0.1 only (``cluster.dashboard_link``), never on another
  interface.

For an existing cluster, give its workers the same environment variables
(e.g. in the worker's job script, or ``distributed.nanny.pre-spawn-environ``
in its dask configuration).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from typing import Any, Final

from .._infra.parallel import ENV_THREADS

__all__ = ["WORKER_SETTINGS", "local_cluster"]

#: dask configuration for worker processes analysing long recordings.
WORKER_SETTINGS: Final[dict[str, Any]] = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": str(256 << 20),
    "distributed.nanny.pre-spawn-environ.MALLOC_MMAP_THRESHOLD_": str(32 << 20),
    "distributed.nanny.pre-spawn-environ.MALLOC_TOP_PAD_": str(64 << 20),
    "distributed.worker.profile.enabled": False,
}


# a free port on the loopback interface
_LOOPBACK_ANY_PORT: Final = "127.0.0.1:0"
# no plain-HTTP route on the scheduler or the workers (the nanny passes its
# configuration on to the worker processes it starts)
_NO_HTTP_ROUTES: Final[dict[str, Any]] = {
    "distributed.scheduler.http.routes": [],
    "distributed.worker.http.routes": [],
}


def local_cluster(
    n_workers: int | None = None,
    *,
    threads_per_worker: int = 1,
    dashboard: bool = False,
    secure: bool = True,
    **kwargs: Any,
):
    """Start a ``distributed.LocalCluster`` of worker processes for a study.

    Parameters
    ----------
    n_workers : int, optional
        Worker processes (default: one per core).
    threads_per_worker : int
        Threads per worker. 1 by default: rbm_nb's kernels already use the
        core they run on, and netCDF reads in one process take one lock.
    dashboard : bool
        Serve distributed's dashboard and its HTTP routes (on a free port of
        127.0.0.1, without credentials: anyone with an account on this
        machine can read them) if True. False serves no HTTP route at all.
    secure : bool
        Connect scheduler, workers and clients over TLS with a temporary
        certificate (needs the ``cryptography`` package, part of the
        ``dask`` extra). False gives plain TCP on 127.0.0.1.
    **kwargs
        Passed on to ``LocalCluster``.

    Returns
    -------
    distributed.LocalCluster
        Close it (or use it as a context manager) when done. A ``Client``
        connected with ``cluster.get_client()`` makes :meth:`Study.map` run on
        it.

    Raises
    ------
    ImportError
        If distributed (or, with ``secure``, cryptography) is not installed.
    ValueError
        If ``n_workers`` or ``threads_per_worker`` is not a positive integer.
    """
    checked: dict[str, Any] = {"threads_per_worker": threads_per_worker}
    if n_workers is not None:
        checked["n_workers"] = n_workers
    for name, value in checked.items():
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
    try:
        import dask
        from distributed import LocalCluster
    except ImportError as err:
        raise ImportError(
            "local_cluster needs dask.distributed: pip install 'rbm_nb[dask]'"
        ) from err
    options: dict[str, Any] = {
        "threads_per_worker": threads_per_worker,
        "processes": True,
        "host": "127.0.0.1",
        # LocalCluster turns the dashboard on for any address; without one
        # the scheduler still serves its routes, on 8787 (see the module doc)
        "dashboard_address": _LOOPBACK_ANY_PORT if dashboard else None,
    }
    if not dashboard:
        options["scheduler_kwargs"] = {"dashboard_address": _LOOPBACK_ANY_PORT}
    if n_workers is not None:
        options["n_workers"] = n_workers
    cores = os.cpu_count() or 1
    workers = (
        n_workers if n_workers is not None else max(1, cores // threads_per_worker)
    )
    # the cores left to each of a worker's threads for rbm_nb's parallel kernels
    share = max(1, cores // (workers * threads_per_worker))
    settings = dict(WORKER_SETTINGS)
    if not dashboard:
        settings.update(_NO_HTTP_ROUTES)
    settings["distributed.nanny.environ." + ENV_THREADS] = str(share)
    if secure:
        try:
            from distributed.security import Security

            options["security"] = Security.temporary()
        except ImportError as err:
            raise ImportError(
                "local_cluster(secure=True) needs the cryptography package: "
                "pip install 'rbm_nb[dask]' (or pass secure=False)"
            ) from err
        options["protocol"] = "tls://"
    scheduler_kwargs = {
        **options.get("scheduler_kwargs", {}),
        **(kwargs.pop("scheduler_kwargs", None) or {}),
    }
    options.update(kwargs)
    if scheduler_kwargs:
        options["scheduler_kwargs"] = scheduler_kwargs
    # the nanny reads pre-spawn-environ when it starts each worker
    with dask.config.set(settings), _client_environ(settings):
        return LocalCluster(**options)


_PRE_SPAWN = "distributed.nanny.pre-spawn-environ."


@contextlib.contextmanager
def _client_environ(settings: dict[str, Any]) -> Iterator[None]:
    """The workers' pre-spawn variables in this process's environment while
    the cluster starts, and the environment as it was afterwards.

    A nanny lets the client's environment override pre-spawn-environ, and
    writes its own values there when it spawns a worker: after any stock
    LocalCluster of processes this process holds MALLOC_TRIM_THRESHOLD_=65536,
    which the next cluster's workers would get instead of ours.
    """
    ours = {
        k[len(_PRE_SPAWN) :]: v for k, v in settings.items() if k.startswith(_PRE_SPAWN)
    }
    before = {k: os.environ.get(k) for k in ours}
    os.environ.update(ours)
    try:
        yield
    finally:
        for key, value in before.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
