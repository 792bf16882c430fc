"""The head/eye explorer as a standalone app, served by Voilà.

Voilà runs a notebook and shows only its widgets, so the explorer opens as a
page with no code: the frame tree, the 3D view, the Player and the
time-series plot (the same widgets as notebook 06). ``rbm-nb app`` writes the
app's one-cell notebook to a temporary folder and serves it on loopback with
a random token; ``notebooks/explorer_app.ipynb`` is the same notebook for
Binder (``?urlpath=voila/render/notebooks/explorer_app.ipynb``).
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
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


def voila_command(
    notebook, *, port: int, token: str, open_browser: bool = False
) -> list[str]:
    """The Voilà command line serving ``notebook`` on 127.0.0.1 with ``token``.

    Raises
    ------
    ValueError
        If ``token`` is empty (the app never listens without one).
    """
    if not token:
        raise ValueError("voila_command: token must be a non-empty string")
    return [
        sys.executable,
        "-m",
        "voila",
        str(notebook),
        "--Voila.ip=127.0.0.1",
        f"--Voila.port={int(port)}",
        "--Voila.port_retries=0",
        f"--Voila.token={token}",
        f"--Voila.open_browser={bool(open_browser)}",
    ]


def serve(*, port: int, source: str = "auto", open_browser: bool = True) -> int:
    """Serve the app with Voilà until Ctrl-C; returns Voilà's exit code."""
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
        command = voila_command(
            notebook, port=port, token=token, open_browser=open_browser
        )
        process = subprocess.Popen(command, cwd=folder, env=dict(os.environ))
        try:
            return process.wait()
        except KeyboardInterrupt:  # Ctrl-C reaches Voilà too; let it stop
            return process.wait()
    finally:
        shutil.rmtree(folder, ignore_errors=True)
