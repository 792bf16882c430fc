"""The teaching notebooks executed once per session, two at a time.

Executing a notebook in a fresh kernel is one of the suite's most expensive
set-ups (a kernel, rbm_nb's imports and kernels loaded from numba's cache,
the notebook's own work), and the test process only waits meanwhile: one
core of CI's two is idle. So:

* Several tests check the same executed notebook and share one execution:
  ``tests/notebook/test_notebooks.py`` (each runs offline, says its data,
  creates widgets), ``tests/project/test_warmup_explorer.py`` (the kernels
  notebook 06 calls, on the real and the synthetic recording) and
  ``tests/notebook/test_browser_offline.py`` (notebook 01's saved widget
  state in chromium).
* A test module that executes several notebooks asks for all of them first
  (:meth:`NotebookRuns.prefetch`): they run in the background, two kernels
  at a time, while its tests take them in order.

Each execution gets its own kernel, environment (passed to the kernel, not
set in this process, so two can run at once) and folder. The session
fixture ``executed_notebook`` (tests/conftest.py) hands out a copy.

Every run of a notebook as shipped ends with one extra cell that prints the
kernels the kernel's process has an overload of (``KERNELS[...]``, read by
:func:`kernels_called`): it runs after the notebook's own cells and changes
nothing they print.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Hashable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

from conftest import REPO

NOTEBOOKS = REPO / "notebooks"
REAL_DATA = REPO.parent / "shared" / "data" / "rbm-data"
#: kernels executing at once (CI has two cores; the test process waits)
WORKERS = 2

# Lists the kernels this process has an overload of (the notebook's calls).
LIST_KERNELS = (
    "import json\n"
    "from rbm_nb._kernels._jit import declared_kernels\n"
    "print('KERNELS' + json.dumps(sorted(k.name.removeprefix('rbm_nb._kernels.')"
    " for k in declared_kernels() if k.dispatcher.signatures)))\n"
)


def kernel_env(base: dict[str, str], data: str | None, folder: Path) -> dict[str, str]:
    """The kernel's environment: ``base``, matplotlib's config in ``folder``,
    and the example data per ``data``.

    ``"real"``: the example recording from ``REAL_DATA``; ``"synthetic"``: an
    empty data folder (offline, the recording is then the synthetic
    stand-in); None: as in ``base``.
    """
    env = {k: v for k, v in base.items() if k != "RBM_NB_VIEWER_PROXY"}
    env["MPLCONFIGDIR"] = str(folder / "mpl")
    # the explorer's background loading would give the process every cached
    # explorer kernel, called or not: the listing (LIST_KERNELS) is of calls
    # (conftest turns it off for the session; a base without it still counts)
    env["RBM_NB_PREPARE"] = "0"
    if data == "real":
        if not REAL_DATA.is_dir():
            raise FileNotFoundError(
                f"{REAL_DATA} is missing: CI has ../shared beside the clone"
            )
        env["RBM_NB_DATA_DIR"] = str(REAL_DATA)
    elif data == "synthetic":
        (folder / "no-data").mkdir(exist_ok=True)
        env["RBM_NB_DATA_DIR"] = str(folder / "no-data")
    elif data is not None:
        raise ValueError(f"data must be 'real', 'synthetic' or None, got {data!r}")
    return env


def execute(notebook, env: dict[str, str], folder: Path):
    """Execute ``notebook`` (in place) in a fresh kernel with ``env``, in ``folder``."""
    import nbclient

    nbclient.NotebookClient(
        notebook,
        timeout=900,  # per cell
        kernel_name="python3",
        resources={"metadata": {"path": str(folder)}},  # exports land there
    ).execute(env=env)
    return notebook


def shipped(name: str):
    """``notebooks/<name>`` as shipped, with the kernel listing cell at the end."""
    import nbformat

    notebook = nbformat.read(NOTEBOOKS / name, as_version=4)
    notebook.cells.append(nbformat.v4.new_code_cell(LIST_KERNELS))
    return notebook


def kernels_called(notebook) -> set[str]:
    """The kernels the notebook's process called, from the last cell's output."""
    import json

    text = "".join(o.get("text", "") for o in notebook.cells[-1].outputs)
    return set(json.loads(text[text.index("KERNELS") + len("KERNELS") :]))


class NotebookRuns:
    """Notebook executions by key, each at most once, :data:`WORKERS` at a time.

    ``self(name, data)`` is ``notebooks/<name>`` as shipped (see
    :func:`shipped`) executed with ``data`` (see :func:`kernel_env`);
    :meth:`run` takes any notebook under a key of the caller's. Callers get
    a deep copy of the executed notebook; a failed execution raises for
    every caller.
    """

    def __init__(self, folder: Path, environ: dict[str, str]):
        self.folder = folder
        self.environ = dict(environ)  # the session's, not a patched test's
        self._pool = ThreadPoolExecutor(WORKERS, thread_name_prefix="notebook")
        self._runs: dict[Hashable, Future] = {}

    def _submit(self, key: Hashable, make: Callable, data: str | None) -> Future:
        if key not in self._runs:
            folder = self.folder / f"run-{len(self._runs)}"
            folder.mkdir()
            env = kernel_env(self.environ, data, folder)
            self._runs[key] = self._pool.submit(lambda: execute(make(), env, folder))
        return self._runs[key]

    def prefetch(self, name: str, data: str | None = None) -> None:
        """Start executing ``name`` with ``data`` in the background."""
        self._submit((name, data), lambda: shipped(name), data)

    def prefetch_run(self, key: Hashable, make: Callable, data: str | None) -> None:
        """Start executing the notebook ``make()`` returns, under ``key``."""
        self._submit(key, make, data)

    def __call__(self, name: str, data: str | None = None):
        self.prefetch(name, data)
        return copy.deepcopy(self._runs[(name, data)].result())

    def run(self, key: Hashable, make: Callable, data: str | None):
        """The notebook ``make()`` returns, executed with ``data``."""
        return copy.deepcopy(self._submit(key, make, data).result())

    def close(self) -> None:
        """Drop what has not started; wait for what runs (its kernel stops)."""
        self._pool.shutdown(wait=True, cancel_futures=True)
