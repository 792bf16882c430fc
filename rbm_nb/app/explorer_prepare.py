"""The dashboard's code, loaded while the notebook does something else.

On a fresh kernel about a quarter of :func:`~rbm_nb.explorer.dashboard`'s
first build is code, not data: importing the 3D view's and the plots' modules
(the scene, meshcat, anywidget) and loading the explorer's kernels' machine
code from numba's cache (the first load also sets up numba's own registries).
None of it depends on the recording. So importing the explorer starts one
daemon thread that does it, while the notebook loads the recording or its
user reads; ``dashboard()`` waits for the thread first (by then it has
usually finished) and so never does the work twice.

Only signatures already in numba's cache are loaded, never compiled: on a
fresh install whose warm-up is still compiling, the warm-up keeps that work
(a kernel the dashboard needs meanwhile waits for it, as before).

``RBM_NB_PREPARE=0`` in the environment turns the thread off (the kernels
then load when the dashboard first calls them).
"""

from __future__ import annotations

import importlib
import os
import threading

from .._kernels import _warmup

#: what ``dashboard()`` imports beyond the explorer's own imports
MODULES = (
    "rbm_nb.scene.scene",
    "rbm_nb.scene.widget",
    "rbm_nb.scene.one_mover",
    "rbm_nb.scene.path_source",
    "rbm_nb.widgets.timeseries",
    "rbm_nb.widgets.frame_tree",
)

#: the longest a fork waits for the thread (it needs ~1 s of one core)
FORK_WAIT = 30.0

_lock = threading.Lock()
_thread: threading.Thread | None = None


def start() -> None:
    """Start loading the dashboard's code in the background (once per process)."""
    global _thread
    if os.environ.get("RBM_NB_PREPARE", "1") == "0":
        return
    with _lock:
        if _thread is not None:
            return
        _thread = threading.Thread(
            target=_prepare, name="rbm-explorer-prepare", daemon=True
        )
        _thread.start()


def wait(timeout: float | None = None) -> None:
    """Return once the background loading is over (at once if it never started)."""
    thread = _thread
    if thread is not None and thread is not threading.current_thread():
        thread.join(timeout)


def _prepare() -> None:
    try:
        for name in MODULES:
            importlib.import_module(name)
        load_cached_kernels()
    except Exception:  # noqa: BLE001
        # nothing is lost: whatever did not load here loads when the
        # dashboard calls it, and any error is raised there, with its context
        pass


def load_cached_kernels() -> int:
    """Load the explorer's kernel signatures that numba's cache holds; how many.

    A signature is loaded only if the account says it was compiled or loaded
    since the kernel sources last changed; one whose lock another process
    holds (the warm-up compiling it) is passed over, not waited for.
    """
    kernels = _warmup.explorer_kernels()
    cached = _warmup.ready(kernels)
    loaded = 0
    for kernel in kernels:
        if _warmup.key(kernel) in cached:
            if _warmup.compile_signature(kernel, wait=False):
                loaded += 1
    return loaded


# a process forked while the thread holds numba's compiler lock or an import
# lock would inherit the lock held by nobody: forks wait for the thread
if hasattr(os, "register_at_fork"):
    os.register_at_fork(before=lambda: wait(FORK_WAIT))
