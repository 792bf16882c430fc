"""Shared fixtures of the tests (the registry is cleared by ../conftest.py).

Layout: the tests live in one folder per layer of rbm_nb --
``core/`` (frames, lookups, transforms, kernels, estimators, quaternions,
parity with the reference, bad input, module graph), ``data/`` (example and
synthetic recordings, rosbag, OptiTrack, transformer, atomic writes,
studies), ``notebook/`` (scene, widgets, exports, browser and Voila tests,
the teaching notebooks) and ``project/`` (packaging, Binder, docs, tools,
numba cache, boundscheck). The helper modules (``naive*.py``,
``recordings.py``, ``widget_support.py``, ``browser_support.py``, ...) stay
here and are imported by module name: this folder is put on ``sys.path``
below, and ``REPO`` (``from conftest import REPO``) is the repository root
whatever the depth of the test file. There is no ``conftest.py`` in the
layer folders (a second one would shadow this module for ``from conftest
import ...``). ``test_zz_kernel_signatures.py`` stays here: pytest collects
a folder's entries in name order, so it comes after the layer folders and
checks what the whole session compiled.

Fast local selection (no browser, nothing over a few seconds):
``python -m pytest -m "not slow and not browser"``.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import math
import os
import sys
import warnings
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
# the helper modules are imported by name from every layer folder (pytest's
# default import mode adds this folder too; other modes do not)
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))
# The real recordings live beside the clone; RBM_NB_SHARED points elsewhere
# (an unpacked sdist, a worktree).
SHARED = Path(os.environ.get("RBM_NB_SHARED", REPO.parent / "shared"))
SHARED_DATA = SHARED / "data"
ORACLE = "rigid_body_motion"

# No background loading of the explorer's code in the test processes (nor in
# the kernels and subprocesses they start): tests importing the explorer
# would otherwise share the process with a thread that allocates and loads
# kernels at its own pace (tracemalloc counts every thread). Its own tests
# (notebook/test_explorer_prepare.py) turn it on where they need it.
os.environ.setdefault("RBM_NB_PREPARE", "0")

# the session fixtures of the slow subprocess checks (see head_start.py)
from compile_order import explorer_compiles  # noqa: E402, F401
from head_start import HEAD_STARTS, checked_runs, packaging_runs  # noqa: E402, F401


class _ReclaimAccessorAfterOracle(importlib.abc.MetaPathFinder):
    """Make ``DataArray.rbm`` ours again right after the oracle is imported.

    rigid-body-motion registers an xarray accessor under the same name as ours
    when it is imported, and whichever registers last wins. Instead of
    importing the oracle up front for every test (seconds before the first
    one), this finder waits for a test module to import it and re-registers
    ours the moment that import has finished.
    """

    def find_spec(self, fullname, path=None, target=None):
        if fullname != ORACLE:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return None  # not installed: the importing test module says so
        exec_module = spec.loader.exec_module

        def exec_then_reclaim(module):
            exec_module(module)
            _register_our_accessor()

        spec.loader.exec_module = exec_then_reclaim  # type: ignore[method-assign]
        return spec


def _register_our_accessor() -> None:
    import xarray as xr

    from rbm_nb.core.accessors import DataArrayAccessor

    with warnings.catch_warnings():
        # "overriding a preexisting attribute": the oracle's, on purpose
        warnings.simplefilter("ignore")
        xr.register_dataarray_accessor("rbm")(DataArrayAccessor)


if ORACLE in sys.modules:
    _register_our_accessor()
else:
    sys.meta_path.insert(0, _ReclaimAccessorAfterOracle())


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The real recordings beside the repo (``../shared/data``, or
    ``$RBM_NB_SHARED/data``)."""
    if not SHARED_DATA.is_dir():
        pytest.fail(
            f"{SHARED_DATA} is missing: CI must have ../shared beside the clone "
            "(or RBM_NB_SHARED naming a folder with data/)"
        )
    return SHARED_DATA


@pytest.fixture(autouse=True, scope="session")
def _head_starts(request):
    """Start the slow subprocess checks of the selected tests before the first
    test, so that they run on the core the session leaves idle (head_start.py)."""
    items = request.session.items
    used = {name for item in items for name in getattr(item, "fixturenames", ())}
    for fixture in HEAD_STARTS:
        if fixture in used:
            request.getfixturevalue(fixture)


@pytest.fixture
def ignore_load(monkeypatch):
    """rbm_nb's parallel twins run whatever other processes do at the time.

    ``_parallel.launch`` runs serially when other runnable threads keep the
    cores busy; tests that check the twins themselves, or measure a call's
    memory after a warm-up call (which must have taken the same twin), must
    not depend on what else runs on the machine.
    """
    from rbm_nb._infra import parallel as _parallel

    monkeypatch.setattr(_parallel, "free_cores", lambda: None)
    monkeypatch.setattr(_parallel, "_reading", (-math.inf, None))  # read it now


@pytest.fixture
def recording_comm(monkeypatch):
    """Widgets open a ``RecordingComm`` (widget_support.py) instead of a kernel's.

    Yields the comms in the order they were opened; closes every widget after.
    A test module whose tests all build widgets says
    ``pytestmark = pytest.mark.usefixtures("recording_comm")``.
    """
    comm = pytest.importorskip("comm")
    import ipywidgets
    from widget_support import RecordingComm

    comms = []

    def create_comm(**kwargs):
        comms.append(RecordingComm(**kwargs))
        return comms[-1]

    monkeypatch.setattr(comm, "create_comm", create_comm)
    yield comms
    # closing also removes the listeners widgets keep on the frame registry
    ipywidgets.Widget.close_all()


@pytest.fixture(scope="session")
def executed_notebook(tmp_path_factory):
    """``executed_notebook(name, data=None)``: notebooks/<name> executed in a
    fresh kernel, once per session for every test that checks it (a copy each
    time); ``data``: "real", "synthetic" or None. Executions run two at a
    time in the background once asked for (``.prefetch``; see
    notebook_runs.py)."""
    pytest.importorskip("nbclient")
    from notebook_runs import NotebookRuns

    runs = NotebookRuns(tmp_path_factory.mktemp("notebooks"), dict(os.environ))
    try:
        yield runs
    finally:
        runs.close()


def selected_params(request, test_name: str) -> list[dict]:
    """The parameters of the selected runs of ``test_name`` in the requesting
    module, in the order they run (for fixtures that start work ahead)."""
    return [
        item.callspec.params
        for item in request.session.items
        # doctest items (rbm_nb's docstrings) have no module attribute
        if getattr(item, "module", None) is request.module
        and getattr(item, "originalname", None) == test_name
        and hasattr(item, "callspec")
    ]


@pytest.fixture(scope="session")
def docs_build(tmp_path_factory):
    """The documentation build, running in the background from first use."""
    pytest.importorskip("sphinx", reason="the docs extra is not installed")
    from docs_build import DocsBuild

    build = DocsBuild(tmp_path_factory.mktemp("docs"))
    yield build
    build.stop()


@pytest.fixture(autouse=True, scope="module")
def _docs_build_starts_with_the_project_tests(request):
    """Start the docs build with the first project test when the docs test runs.

    It then overlaps the Binder simulation (mostly pip, one core) instead of
    adding its one and a half minutes after it.
    """
    if request.path.parent.name != "project" or request.path.name == "test_docs.py":
        return
    if importlib.util.find_spec("sphinx") is None:
        return  # test_docs.py skips
    if any(item.path.name == "test_docs.py" for item in request.session.items):
        request.getfixturevalue("docs_build")


@pytest.fixture(scope="module")
def browser():
    """Debian's chromium driven by playwright (never a downloaded browser).

    Every context it makes with ``new_context`` runs
    ``browser_support.ANYWIDGET_TIMEOUT_JS`` first: anywidget's 2 s for a
    model to initialise, lengthened (see browser_support.py). Pages from
    ``browser.new_page`` do not (exports opened from disk: no Jupyter).
    """
    from browser_support import ANYWIDGET_TIMEOUT_JS, CHROMIUM, CHROMIUM_ARGS

    if not Path(CHROMIUM).exists():
        pytest.fail(
            f"{CHROMIUM} is missing: install Debian's chromium (bash .ci/setup.sh test)"
        )
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        chromium = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        new_context = chromium.new_context

        def new_context_with_init_script(*args, **kwargs):
            context = new_context(*args, **kwargs)
            context.add_init_script(ANYWIDGET_TIMEOUT_JS)
            return context

        chromium.new_context = new_context_with_init_script
        try:
            yield chromium
        finally:
            chromium.close()


@pytest.fixture(scope="session")
def jupyter_servers(tmp_path_factory):
    """``jupyter_servers(app)``: the session's JupyterLab (``"lab"``) or
    Notebook 7 (``"notebook"``) server, without jupyter-server-proxy (as on a
    hub or in VS Code), started on first use and stopped at the end.

    A module-scoped fixture that uses one calls ``end_sessions()`` on it when
    done; a test takes ``jupyter_server`` instead, which does that for it.
    """
    from browser_support import JupyterLab

    servers: dict[str, JupyterLab] = {}
    # the environment as the session has it, not as the test that happens to
    # start a server has patched it (a kernel's own variables: kernel_with_env)
    environ = dict(os.environ)

    def get(app: str = "lab") -> JupyterLab:
        if app not in servers:
            home = tmp_path_factory.mktemp(f"jupyter-{app}")
            servers[app] = JupyterLab(home, [], app=app, proxy=False, environ=environ)
        return servers[app]

    try:
        yield get
    finally:
        for server in servers.values():
            server.stop()


@pytest.fixture
def jupyter_server(jupyter_servers):
    """``jupyter_server(app)``: the shared server (see ``jupyter_servers``);
    the kernels the test started there are shut down after it."""
    used = []

    def get(app: str = "lab"):
        server = jupyter_servers(app)
        used.append(server)
        return server

    try:
        yield get
    finally:
        for server in used:
            server.end_sessions()


@pytest.fixture
def page(browser):
    """A fresh page; its JavaScript errors are collected in ``page.errors``."""
    context = browser.new_context(viewport={"width": 1100, "height": 900})
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda err: page.errors.append(str(err)))
    try:
        yield page
    finally:
        context.close()
