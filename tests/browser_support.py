"""Helpers for the browser tests: Debian's chromium, screenshots, a JupyterLab server.

Every process started here is stopped by whoever started it (see
:meth:`JupyterLab.stop`), also when a test fails.
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
    hub or in VS Code where it is not installed.
    """

    def __init__(
        self,
        tmp: Path,
        notebooks: list[Path],
        base_url: str = "/",
        *,
        app: str = "lab",
        proxy: bool = True,
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
        env = dict(os.environ)
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
        """Address of a notebook in this server's user interface."""
        if self.app == "lab":
            return self.url(f"lab/tree/{name}")
        return self.url(f"notebooks/{name}")

    def kernel_pids(self) -> list[int]:
        """Process ids of the kernels this server started."""
        import psutil

        return [
            child.pid
            for child in psutil.Process(self.process.pid).children(recursive=True)
            if "ipykernel" in " ".join(child.cmdline())
        ]

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
