"""Helpers for the browser tests: Debian's chromium, screenshots, Jupyter servers.

Every process started here is stopped by whoever started it (see
:meth:`JupyterLab.stop`), also when a test fails.

The browser tests share one JupyterLab and one Notebook 7 server per session
(the ``jupyter_servers`` / ``jupyter_server`` fixtures of tests/conftest.py):
a test adds its notebook (:meth:`JupyterLab.add_notebook`, with its own
kernel environment through :meth:`JupyterLab.kernel_with_env`), opens it in
a context of its own (:func:`new_context`, :func:`open_notebook`) and its
kernels are shut down when it ends (:meth:`JupyterLab.end_sessions`).
JupyterLab opens each notebook in a workspace of its own, so that no test
reopens another's notebooks.

anywidget gives a widget 2 s from its model's creation to load its module
and initialise (``AbortSignal.timeout(2000)`` in anywidget's Runtime, in its
lab extension's bundle), else the model fails with "[anywidget] Failed to
initialize model." and never renders. A 2-core machine running the suite,
chromium and a kernel can take longer than that to compile our multi-MB
bundles; every page of the browser tests therefore gets
:data:`ANYWIDGET_TIMEOUT_JS`, which lengthens only the timeouts anywidget's
own scripts ask for, to :data:`ANYWIDGET_TIMEOUT_MS`. A widget that never
initialises still fails (later, with anywidget's own message).
"""

from __future__ import annotations

import io
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
ARTIFACTS = REPO / "test-artifacts"
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
    "--disable-gpu",
]


#: what anywidget's model initialisation may take in the tests' pages (ms)
ANYWIDGET_TIMEOUT_MS = 60_000
#: an init script: AbortSignal.timeout(ms) called from a script of anywidget's
#: bundle (its URL has /anywidget/static/) waits ANYWIDGET_TIMEOUT_MS instead;
#: window.rbmAnywidgetTimeouts counts those calls (one per model)
ANYWIDGET_TIMEOUT_JS = """(() => {
  const timeout = AbortSignal.timeout.bind(AbortSignal);
  window.rbmAnywidgetTimeouts = 0;
  AbortSignal.timeout = (ms) => {
    const caller = (new Error().stack || '').split('\\n').slice(2).join('\\n');
    if (!/\\/anywidget\\/static\\//.test(caller)) return timeout(ms);
    window.rbmAnywidgetTimeouts += 1;
    return timeout(Math.max(ms, STRETCHED));
  };
})();""".replace("STRETCHED", str(ANYWIDGET_TIMEOUT_MS))


def png_pixels(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def magenta_pixels(img: np.ndarray) -> int:
    """Pixels of the test scenes' path colour (#ff00ff, blended by antialiasing)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return int(((r > 150) & (b > 150) & (g < 110)).sum())


def changed_pixels(a: np.ndarray, b: np.ndarray) -> int:
    return int((np.abs(a - b).sum(axis=-1) > 60).sum())


def save(name: str, png: bytes) -> Path:
    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / name
    path.write_bytes(png)
    return path


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class JupyterLab:
    """A Jupyter server on loopback in a temporary home, and its cleanup.

    ``app`` is ``"lab"`` (JupyterLab) or ``"notebook"`` (Notebook 7). With
    ``proxy=False`` the jupyter-server-proxy extension is disabled, as on a
    hub or in VS Code where it is not installed. The server and its kernels
    get ``environ`` (default: this process's environment now).
    """

    def __init__(
        self,
        tmp: Path,
        notebooks: list[Path],
        base_url: str = "/",
        *,
        app: str = "lab",
        proxy: bool = True,
        environ: dict[str, str] | None = None,
    ):
        if app not in ("lab", "notebook"):
            raise ValueError(f"app must be 'lab' or 'notebook', got {app!r}")
        self.app = app
        self.tmp = tmp
        self.root = tmp / "root"
        self.root.mkdir()
        for notebook in notebooks:
            shutil.copy(notebook, self.root / notebook.name)
        self.port = free_port()
        self.token = secrets.token_hex(16)
        self.base = f"http://127.0.0.1:{self.port}{base_url}"
        env = dict(os.environ if environ is None else environ)
        for var, sub in (
            ("JUPYTER_CONFIG_DIR", "config"),
            ("JUPYTER_RUNTIME_DIR", "runtime"),
            ("JUPYTER_DATA_DIR", "data"),
            ("IPYTHONDIR", "ipython"),
            ("MPLCONFIGDIR", "mpl"),
        ):
            (tmp / sub).mkdir()
            env[var] = str(tmp / sub)
        env["JUPYTER_PLATFORM_DIRS"] = "1"
        # the token through the environment: a command line is world-readable
        # (/proc/<pid>/cmdline)
        env["JUPYTER_TOKEN"] = self.token
        # no "official Jupyter news?" toast over the screenshots, no requests out
        settings = tmp / "config" / "lab" / "user-settings" / "@jupyterlab"
        (settings / "apputils-extension").mkdir(parents=True)
        (
            settings / "apputils-extension" / "notification.jupyterlab-settings"
        ).write_text(json.dumps({"fetchNews": "false", "checkForUpdates": False}))
        if not proxy:
            (tmp / "config" / "jupyter_server_config.json").write_text(
                json.dumps(
                    {
                        "ServerApp": {
                            "jpserver_extensions": {"jupyter_server_proxy": False}
                        }
                    }
                )
            )
        self.log = open(tmp / "jupyter.log", "wb")
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "jupyter",
                app,
                "--no-browser",
                "--ServerApp.open_browser=False",
                "--ServerApp.ip=127.0.0.1",
                f"--ServerApp.port={self.port}",
                "--ServerApp.port_retries=0",
                f"--ServerApp.base_url={base_url}",
                f"--ServerApp.root_dir={self.root}",
            ]
            + (
                [
                    "--LabApp.news_url=",
                    "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
                ]
                if app == "lab"
                else []
            )
            + (
                ["--allow-root"] if os.geteuid() == 0 else []
            ),  # CI containers run as root
            env=env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # its own process group, stopped as a whole
        )
        self.wait_ready()
        cmdline = Path(f"/proc/{self.process.pid}/cmdline").read_bytes()
        assert self.token.encode() not in cmdline, "the token is on the command line"

    def api(self, path: str, method: str = "GET"):
        request = urllib.request.Request(
            f"{self.base}api/{path}",
            method=method,
            headers={"Authorization": f"token {self.token}"},
        )
        with urllib.request.urlopen(request, timeout=10) as response:
            body = response.read()
        return json.loads(body) if body else None

    def wait_ready(self, timeout: float = 120.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"JupyterLab exited early:\n{self.log_text()}")
            try:
                self.api("status")
                return
            except OSError:
                time.sleep(0.5)
        raise RuntimeError(
            f"JupyterLab did not start in {timeout} s:\n{self.log_text()}"
        )

    def log_text(self) -> str:
        self.log.flush()
        return (self.tmp / "jupyter.log").read_text(errors="replace")[-4000:]

    def url(self, path: str) -> str:
        return f"{self.base}{path}?token={self.token}"

    def notebook_url(self, name: str) -> str:
        """Address of a notebook in this server's user interface.

        JupyterLab opens it in a workspace named after it: a workspace
        restores the notebooks open in it, and on a server the tests share
        that would start the kernels of earlier tests' notebooks again.
        """
        if self.app == "lab":
            workspace = Path(name).stem.replace(" ", "-")
            return self.url(f"lab/workspaces/{workspace}/tree/{name}")
        return self.url(f"notebooks/{name}")

    def add_notebook(self, notebook: Path) -> str:
        """Copy ``notebook`` into the server's root; its name there.

        A name already taken (a parametrised test, a rerun) gets a suffix, so
        that no test opens another's notebook.
        """
        name, n = notebook.name, 1
        while (self.root / name).exists():
            n += 1
            name = f"{notebook.stem}-{n}{notebook.suffix}"
        shutil.copy(notebook, self.root / name)
        return name

    def kernel_with_env(self, env: dict[str, str]) -> str:
        """A kernel spec like ``python3`` whose kernels get ``env`` on top of
        the server's environment; its name (for :func:`write_notebook`).

        The kernels of a shared server inherit its environment, not the
        test's: what a test would set with ``monkeypatch.setenv`` for its
        kernel goes here.
        """
        name = f"python3-{secrets.token_hex(4)}"
        folder = self.tmp / "data" / "kernels" / name
        folder.mkdir(parents=True)
        spec = {
            "argv": [
                sys.executable,
                "-m",
                "ipykernel_launcher",
                "-f",
                "{connection_file}",
            ],
            "display_name": "Python 3 (ipykernel)",
            "language": "python",
            "env": env,
            "metadata": {"debugger": True},
        }
        (folder / "kernel.json").write_text(json.dumps(spec))
        return name

    def kernel_pids(self) -> list[int]:
        """Process ids of the kernels this server started."""
        import psutil

        return [
            child.pid
            for child in psutil.Process(self.process.pid).children(recursive=True)
            if "ipykernel" in " ".join(child.cmdline())
        ]

    def kernel_pid(self, notebook: str) -> int | None:
        """Process id of the kernel of ``notebook``'s session, once it runs."""
        import psutil

        ids = [
            s["kernel"]["id"]
            for s in self.api("sessions")
            if s.get("path") == notebook and s.get("kernel")
        ]
        for child in psutil.Process(self.process.pid).children(recursive=True):
            try:
                cmdline = " ".join(child.cmdline())
            except psutil.NoSuchProcess:
                continue
            if any(f"kernel-{i}.json" in cmdline for i in ids):
                return child.pid
        return None

    def end_sessions(self) -> None:
        """Shut down every session and kernel: what a test leaves on a shared server."""
        if self.process.poll() is not None:
            return
        try:
            for session in self.api("sessions"):
                self.api(f"sessions/{session['id']}", method="DELETE")
            for kernel in self.api("kernels"):
                self.api(f"kernels/{kernel['id']}", method="DELETE")
        except OSError:
            pass

    def stop(self) -> None:
        import psutil

        try:
            children = psutil.Process(self.process.pid).children(recursive=True)
        except psutil.NoSuchProcess:
            children = []
        if self.process.poll() is None:
            try:
                for kernel in self.api("kernels"):
                    self.api(f"kernels/{kernel['id']}", method="DELETE")
            except OSError:
                pass
            os.killpg(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(timeout=10)
        # kernels run in their own sessions: stop any that survived, by pid
        for child in children:
            try:
                child.terminate()
                child.wait(timeout=10)
            except psutil.NoSuchProcess:
                pass
            except psutil.TimeoutExpired:
                child.kill()
        self.log.close()


def write_notebook(path: Path, cells: list[str], kernel: str = "python3") -> Path:
    """A notebook of code cells for the kernel spec ``kernel``."""
    import nbformat

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(source) for source in cells]
    nb.metadata["kernelspec"] = {
        "name": kernel,
        "display_name": "Python 3",
        "language": "python",
    }
    nbformat.write(nb, path)
    return path


def new_context(browser, server: JupyterLab | None = None, **options):
    """A browser context (``options`` as playwright's ``new_context``) whose
    requests to another port than ``server``'s are refused; the list they are
    appended to. Its pages collect their errors in ``page.errors`` as
    ``(message, stack)``.
    """
    context = browser.new_context(**options)
    blocked = block_other_ports(context, server.port) if server else []

    def collect(page):
        page.errors = []
        page.on(
            "pageerror", lambda err: page.errors.append((str(err), err.stack or ""))
        )

    context.on("page", collect)
    return context, blocked


def open_notebook(page, server: JupyterLab, name: str) -> None:
    """Open ``name`` in the server's user interface and wait for its cells
    (accepting the kernel the UI may offer)."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    page.goto(server.notebook_url(name), timeout=120000)
    page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=120000)
    try:  # the UI may ask which kernel to start
        page.locator(".jp-Dialog").get_by_role(
            "button", name="Select", exact=True
        ).click(timeout=10000)
    except PlaywrightTimeout:
        pass


def run_all_cells(page) -> None:
    """Run every cell from the Run menu once the kernel is idle."""
    page.wait_for_selector(
        ".jp-Notebook-ExecutionIndicator[data-status='idle']", timeout=120000
    )
    page.get_by_role("menuitem", name="Run", exact=True).click()
    page.get_by_text("Run All Cells", exact=True).click()


def run_cell(page, index: int) -> None:
    """Run code cell ``index`` (shift+enter), retrying while the UI is not ready."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    cell = page.locator(".jp-Notebook .jp-CodeCell").nth(index)
    for _ in range(10):
        cell.locator(".jp-InputArea-editor").click()
        page.keyboard.press("Shift+Enter")
        try:
            page.wait_for_function(
                """(i) => { const c = document.querySelectorAll('.jp-Notebook .jp-CodeCell')[i];
                            return /\\[(\\*|\\d+)\\]/.test(c.querySelector('.jp-InputPrompt').innerText); }""",
                arg=index,
                timeout=5000,
            )
            return
        except PlaywrightTimeout:
            continue
    raise AssertionError(f"cell {index} did not start running")


def run_until(page, index: int, marker: str, timeout: float = 400000) -> str:
    """Run code cell ``index`` and wait for an output holding ``marker``; its text."""
    run_cell(page, index)
    done = page.locator(".jp-OutputArea-output", has_text=marker)
    done.wait_for(timeout=timeout)
    return done.inner_text()


def prompt(page, index: int) -> str:
    return (
        page.locator(".jp-Notebook .jp-CodeCell")
        .nth(index)
        .locator(".jp-InputPrompt")
        .inner_text()
    )


def wait_done(page, index: int, timeout: float = 300000) -> None:
    page.wait_for_function(
        """(i) => { const c = document.querySelectorAll('.jp-Notebook .jp-CodeCell')[i];
                    const t = c.querySelector('.jp-InputPrompt').innerText;
                    return /\\[\\d+\\]/.test(t); }""",
        arg=index,
        timeout=timeout,
    )


def output_text(page, index: int) -> str:
    return (
        page.locator(".jp-Notebook .jp-CodeCell")
        .nth(index)
        .locator(".jp-OutputArea")
        .inner_text()
    )


def our_errors(errors: list[tuple[str, str]], server: JupyterLab) -> list:
    """The page errors that are not Jupyter's own.

    Notebook 7 itself throws on start-up (a settings schema it lacks): errors
    whose every frame is in Jupyter's own bundles are not ours.
    """
    own = f"{server.base}static/"
    return [
        (message, stack)
        for message, stack in errors
        if not all(
            own in line
            for line in stack.splitlines()[1:]
            if "http" in line or "blob:" in line
        )
    ]


def block_other_ports(context, port: int) -> list[str]:
    """Abort every request of ``context`` to a port other than ``port``.

    Returns the list the blocked URLs are appended to (the widgets must not
    need any: the scene comes over the kernel's own connection).
    """
    from urllib.parse import urlsplit

    blocked: list[str] = []

    def handle(route):
        url = route.request.url
        parts = urlsplit(url)
        if parts.scheme in ("http", "https", "ws", "wss"):
            other = parts.port or (443 if parts.scheme in ("https", "wss") else 80)
            if parts.hostname not in ("127.0.0.1", "localhost") or other != port:
                blocked.append(url)
                route.abort()
                return
        route.continue_()

    context.route("**/*", handle)
    return blocked


def listening_sockets(pid: int) -> set:
    """(address, port) pairs the process listens on (TCP)."""
    import psutil

    return {
        (c.laddr.ip, c.laddr.port)
        for c in psutil.Process(pid).net_connections(kind="inet")
        if c.status == psutil.CONN_LISTEN
    }


# frames per second of requestAnimationFrame and of the 3D view's renders,
# and how far the scene's time moved, over ``ms`` milliseconds
MEASURE_JS = """async (ms) => {
  const view = document.querySelector('.rbm-scene').rbmView;
  const f0 = view.frames, s0 = view.currentTime(), t0 = performance.now();
  let n = 0;
  await new Promise((resolve) => {
    function tick() {
      n += 1;
      if (performance.now() - t0 < ms) { requestAnimationFrame(tick); } else { resolve(); }
    }
    requestAnimationFrame(tick);
  });
  const seconds = (performance.now() - t0) / 1000;
  return {raf: n / seconds, rendered: (view.frames - f0) / seconds,
          advanced: view.currentTime() - s0, seconds: seconds};
}"""
