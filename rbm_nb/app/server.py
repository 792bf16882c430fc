"""The head/eye explorer as a standalone app, served by Voilà.

Voilà runs a notebook and shows only its widgets, so the explorer opens as a
page with no code: the frame tree, the 3D view, the Player and the
time-series plot (the same widgets as notebook 06). ``rbm-nb app`` writes the
app's one-cell notebook to a temporary folder and serves it on loopback with
a random token; ``notebooks/explorer_app.ipynb`` is the same notebook for
Binder (``?urlpath=voila/render/notebooks/explorer_app.ipynb``).

The token reaches Voilà through its environment (``JUPYTER_TOKEN``), never its
command line: ``/proc/<pid>/cmdline`` is readable by every user of the
machine, a process's environment only by its owner. Voilà ends with
``rbm-nb app`` whatever ends it: Ctrl-C reaches both, SIGTERM and SIGHUP (a
closed terminal) are passed on, and Linux ends Voilà if its parent dies
without a word (SIGKILL).
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

APP_NOTEBOOK = "explorer_app.ipynb"
SOURCES = ("auto", "remote", "synthetic")

_INTRO = """\
# rbm_nb · head/eye explorer

Click a frame in the tree or in the 3D view for its pose at the current time (two frames in
the tree: the transform between them). Press ▶ or the space bar on the player; drag in the
plot to zoom, click it to seek. Every view shows the same time: seconds from the start of the
recording, then the clock time.
"""


def explorer_dashboard(source: str = "auto", *, height: int = 460):
    """The explorer's dashboard: frame tree and 3D view, Player, time series.

    Registers the head/eye frame tree (replacing frames of the same names).

    Parameters
    ----------
    source : {"auto", "remote", "synthetic"}
        Example data, as for :func:`rbm_nb.explorer.load_head_eye`.
    height : int, default 460
        Height of the 3D view in pixels.

    Returns
    -------
    ipywidgets.VBox
        The dashboard; its ``scene``, ``player``, ``tree`` and ``plot``
        attributes are the parts.
    """
    if source not in SOURCES:
        raise ValueError(
            f"explorer_dashboard: source must be one of {SOURCES}, got {source!r}"
        )
    # lazy (import time): the explorer (~0.6 s) loads with the first dashboard
    from . import explorer

    # the same dashboard as notebook 06 (explorer.dashboard), with the app's class
    dashboard = explorer.dashboard(source=source, height=height)
    dashboard.add_class("rbm-explorer-app")
    return dashboard


def app_notebook(source: str = "auto") -> dict:
    """The app as a notebook (nbformat 4 JSON): a title and one code cell."""
    if source not in SOURCES:
        raise ValueError(
            f"app_notebook: source must be one of {SOURCES}, got {source!r}"
        )
    call = (
        "explorer_dashboard()"
        if source == "auto"
        else f"explorer_dashboard({source!r})"
    )
    cells = [
        {"cell_type": "markdown", "id": "intro", "metadata": {}, "source": _INTRO},
        {
            "cell_type": "code",
            "id": "dashboard",
            "execution_count": None,
            "metadata": {},
            "outputs": [],
            "source": f"from rbm_nb.app import explorer_dashboard\n\n{call}",
        },
    ]
    return {
        "cells": cells,
        "metadata": {
            "kernelspec": {
                "display_name": "Python 3",
                "language": "python",
                "name": "python3",
            },
            "language_info": {"name": "python"},
        },
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def write_app_notebook(folder, source: str = "auto") -> Path:
    """Write :func:`app_notebook` as ``folder/explorer_app.ipynb``; returns its path."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(
            2, f"write_app_notebook: folder {str(folder)!r} does not exist"
        )
    path = folder / APP_NOTEBOOK
    path.write_text(json.dumps(app_notebook(source), indent=1) + "\n", encoding="utf-8")
    return path


def voila_command(notebook, *, port: int, open_browser: bool = False) -> list[str]:
    """The Voilà command line serving ``notebook`` on 127.0.0.1.

    It holds no token: Voilà reads it from ``JUPYTER_TOKEN`` in its
    environment (see :func:`voila_environment`), and with none there makes up
    a random one; it never serves without a token.
    """
    return [
        sys.executable,
        "-m",
        "voila",
        str(notebook),
        "--Voila.ip=127.0.0.1",
        f"--Voila.port={int(port)}",
        "--Voila.port_retries=0",
        # a token from the environment (or a random one), never none
        "--Voila.auto_token=True",
        f"--Voila.open_browser={bool(open_browser)}",
    ]


def voila_environment(token: str, base: dict | None = None) -> dict[str, str]:
    """The environment Voilà runs in: ``base`` (default: this process's) and the token.

    Raises
    ------
    ValueError
        If ``token`` is empty (the app never listens without one).
    """
    if not token:
        raise ValueError("voila_environment: token must be a non-empty string")
    env = dict(os.environ if base is None else base)
    env.pop("JUPYTER_TOKEN_FILE", None)  # would be read instead of ours
    env["JUPYTER_TOKEN"] = token
    return env


def serve(*, port: int, source: str = "auto", open_browser: bool = True) -> int:
    """Serve the app with Voilà until Ctrl-C, SIGTERM or SIGHUP; returns Voilà's exit code."""
    try:
        import voila  # noqa: F401
    except ImportError:
        raise SystemExit(
            "rbm-nb app: Voilà is not installed; pip install 'rbm_nb[app]'"
        ) from None
    token = secrets.token_hex(16)
    folder = Path(tempfile.mkdtemp(prefix="rbm-nb-app-"))
    try:
        notebook = write_app_notebook(folder, source)
        print(
            f"rbm-nb app: the head/eye explorer at\n\n"
            f"    http://127.0.0.1:{port}/?token={token}\n\n"
            "Stop it with Ctrl-C.",
            flush=True,
        )
        command = voila_command(notebook, port=port, open_browser=open_browser)
        return run_child(command, cwd=folder, env=voila_environment(token))
    finally:
        shutil.rmtree(folder, ignore_errors=True)


#: signals that end ``rbm-nb app`` and are passed on to Voilà
STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP)
#: seconds Voilà has to stop its kernels after SIGTERM before it is killed
STOP_GRACE = 20


def run_child(command: list[str], *, cwd, env: dict[str, str]) -> int:
    """Run ``command`` until it ends, and end it with this process.

    Ctrl-C reaches the child directly (same process group). SIGTERM and
    SIGHUP are passed on as SIGTERM (Voilà then stops its kernels), with a
    SIGKILL after :data:`STOP_GRACE` seconds; if this process dies without
    running a handler (SIGKILL), Linux sends the child SIGTERM
    (``PR_SET_PDEATHSIG``). Returns the child's exit code, or 128 + the
    signal that ended this process.
    """
    process = subprocess.Popen(command, cwd=cwd, env=env, preexec_fn=_end_with_parent)
    received: list[int] = []

    def pass_on(signum, frame):
        received.append(signum)
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
            signal.alarm(STOP_GRACE)

    def kill(signum, frame):
        if process.poll() is None:
            process.kill()

    previous = {sig: signal.signal(sig, pass_on) for sig in STOP_SIGNALS}
    previous[signal.SIGALRM] = signal.signal(signal.SIGALRM, kill)
    try:
        while True:
            try:
                code = process.wait()
                break
            except KeyboardInterrupt:  # Ctrl-C reached Voilà too; let it stop
                continue
    finally:
        signal.alarm(0)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if process.poll() is None:  # an error of ours: do not leave it behind
            process.kill()
            process.wait()
    return 128 + received[0] if received else code


_PR_SET_PDEATHSIG = 1


def _end_with_parent() -> None:  # pragma: no cover (runs in the child)
    """In the child before exec: get SIGTERM when the parent dies (Linux)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):
        return  # not Linux: SIGTERM and SIGHUP are still passed on
    if os.getppid() == 1:  # the parent died before prctl: end now
        os.kill(os.getpid(), signal.SIGTERM)
