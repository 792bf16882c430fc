"""The ``rbm-nb`` command.

``rbm-nb demo`` opens JupyterLab on the head/eye explorer notebook (offline it
uses the synthetic recording); ``rbm-nb demo --html out.html`` writes the
explorer's dashboard (3D view, time series, player) as one self-contained page
that plays offline, with no Jupyter involved; ``rbm-nb demo --text`` prints a
lookup across a small moving frame tree; ``rbm-nb app`` serves the explorer as
a standalone Voilà app (no code cells); ``rbm-nb --version`` prints the
installed version.

The notebooks come from the clone rbm_nb runs from, or, for an installed
wheel, from the copies shipped in ``rbm_nb/_notebooks``: those are copied once
into a writable folder (the explorer writes its exports beside itself, and
JupyterLab its checkpoints), which keeps the user's edits on later runs.
"""

from __future__ import annotations

import argparse
import os
import secrets
import shutil
import socket
import sys
import tempfile
from pathlib import Path

from .._version import __version__
from ..core import frames, lookups, quaternions, transforms
from ..data.fetch import ExampleDataStore
from ..data.registry import DATA_DIR_ENV

EXPLORER = "06_head_eye_explorer.ipynb"
# this file is rbm_nb/app/cli.py: the clone is two folders up, the package one
CLONE_NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
PACKAGED_NOTEBOOKS = Path(__file__).resolve().parents[1] / "_notebooks"
# a Jupyter config folder whose labconfig/ holds the demo's default settings
LAB_DEFAULTS = Path(__file__).resolve().parent


def _text_demo() -> int:
    import numpy as np

    frames.clear_registry()
    frames.register_frame("world")
    # a body walking 5 m along x in 5 s while turning 90 degrees about z
    ts = np.linspace(0.0, 5.0, 6)
    yaw = np.linspace(0.0, np.pi / 2, 6)
    frames.register_frame(
        "body",
        parent="world",
        translation=np.column_stack([ts, np.zeros(6), np.zeros(6)]),
        rotation=quaternions.from_euler_angles(yaw=yaw),
        timestamps=ts,
    )
    # a camera fixed on the body, 10 cm above it
    frames.register_frame("camera", parent="body", translation=(0.0, 0.0, 0.1))

    print("Frame tree:")
    frames.render_tree("world")
    position, orientation, stamps = lookups.lookup_pose(
        "camera", "world", return_timestamps=True
    )
    print("\nPose of 'camera' in 'world':")
    print(" time [s]   position [m]              orientation (w, x, y, z)")
    for t, p, q in zip(stamps, position, orientation, strict=True):
        print(
            f" {t:6.2f}   {np.array2string(p, precision=3):24s}  "
            f"{np.array2string(q, precision=3)}"
        )
    point = transforms.transform_points((1.0, 0.0, 0.0), outof="world", into="camera")
    print("\nThe world point (1, 0, 0) seen from 'camera' over time:")
    print(np.array2string(point, precision=3))
    return 0


def _notebook_dir(given: str | None) -> Path:
    """The notebooks folder: given, the clone's, or a user copy of the packaged ones."""
    if given:
        folder = Path(given)
    elif (CLONE_NOTEBOOKS / EXPLORER).is_file():
        folder = CLONE_NOTEBOOKS
    elif (PACKAGED_NOTEBOOKS / EXPLORER).is_file():
        folder = _user_copy(PACKAGED_NOTEBOOKS)
    else:
        folder = PACKAGED_NOTEBOOKS
    if not (folder / EXPLORER).is_file():
        raise SystemExit(
            f"rbm-nb demo: {EXPLORER} not found in {folder}. Pass --notebook-dir "
            "pointing to the notebooks/ folder of an rbm_nb clone, or reinstall "
            "rbm_nb (its wheel ships the notebooks)."
        )
    return folder


def _user_data_home() -> Path:
    """``$XDG_DATA_HOME`` or ``~/.local/share`` (where per-user data lives)."""
    xdg = os.environ.get("XDG_DATA_HOME")
    return Path(xdg) if xdg else Path.home() / ".local" / "share"


def _user_copy(packaged: Path) -> Path:
    """Copy the packaged notebooks to a writable folder once; return that folder.

    One folder per version, so an upgrade brings the new notebooks while the
    user's edits of an older copy stay where they were. Files already there are
    left alone. With no writable home (containers, HPC) a temporary folder is
    used and the message says so.
    """
    target = _user_data_home() / "rbm_nb" / f"notebooks-{__version__}"
    try:
        target.mkdir(parents=True, exist_ok=True)
        probe = target / ".rbm_nb-write-test"
        probe.touch()
        probe.unlink()
    except OSError as err:
        target = Path(tempfile.mkdtemp(prefix="rbm_nb-notebooks-"))
        print(
            f"rbm-nb demo: cannot write to {_user_data_home()} ({err.strerror}); "
            f"the notebooks are copied to {target} and removed with it."
        )
    copied = 0
    for src in sorted(packaged.glob("*.ipynb")):
        dst = target / src.name
        if not dst.exists():
            shutil.copyfile(src, dst)
            copied += 1
    if copied:
        print(f"rbm-nb demo: copied {copied} notebooks to {target}")
    return target


def _free_port(preferred: int) -> int:
    """``preferred`` if it is free on loopback, else any free port (0: any)."""
    with socket.socket() as sock:
        try:
            sock.bind(("127.0.0.1", preferred))
        except OSError:
            sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _lab_demo(args) -> int:
    folder = _notebook_dir(args.notebook_dir)
    if shutil.which("jupyter-lab", path=os.path.dirname(sys.executable)) is None:
        raise SystemExit(
            "rbm-nb demo: JupyterLab is not installed in this environment; "
            "pip install 'rbm_nb[lab]' (or use --html / --text)"
        )
    port = _free_port(args.port)
    token = secrets.token_hex(16)
    url = f"http://127.0.0.1:{port}/lab/tree/{EXPLORER}?token={token}"
    print(f"rbm-nb demo: JupyterLab on the head/eye explorer at\n\n    {url}\n")
    print("Open that address in a browser; stop the server with Ctrl-C.", flush=True)
    command = [
        os.path.join(os.path.dirname(sys.executable), "jupyter-lab"),
        f"--ServerApp.root_dir={folder}",
        "--ServerApp.ip=127.0.0.1",
        f"--ServerApp.port={port}",
        "--ServerApp.port_retries=0",
        f"--ServerApp.open_browser={not args.no_browser}",
        f"--LabApp.default_url=/lab/tree/{EXPLORER}",
        # notebook_shim's server extension only carries old NotebookApp
        # settings over, and on the way reads the deprecated ServerApp.token
        # trait: jupyter-server then warns a newcomer about a setting nobody
        # made (the token comes as IdentityProvider reads it, JUPYTER_TOKEN;
        # Voila's import turns traitlets' DeprecationWarnings back on, so a
        # PYTHONWARNINGS filter cannot hide it)
        "--ServerApp.jpserver_extensions={'notebook_shim': False}",
        # no request out for news or a newer release
        "--LabApp.news_url=None",
        "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
    ]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        command.append("--allow-root")  # containers and CI machines run as root
    # the token goes through the environment: a command line is world-readable
    # (/proc/<pid>/cmdline), an environment only by its owner
    env = {k: v for k, v in os.environ.items() if k != "JUPYTER_TOKEN_FILE"}
    env["JUPYTER_TOKEN"] = token
    # and no "official Jupyter news?" question on the first screen: JupyterLab
    # asks until a setting says no, and layers defaults from a labconfig
    # folder on the config path (the user's own settings still win)
    env["JUPYTER_CONFIG_PATH"] = os.pathsep.join(
        p for p in (str(LAB_DEFAULTS), os.environ.get("JUPYTER_CONFIG_PATH")) if p
    )
    # the server takes over this process (and its signals: Ctrl-C, SIGTERM, SIGHUP)
    os.execve(command[0], command, env)
    return 0  # pragma: no cover


def _html_demo(args) -> int:
    # lazy (import time): the explorer loads numba and xarray (~0.6 s)
    from .explorer import write_explorer_html

    print(_data_note(args.source), flush=True)
    path = write_explorer_html(
        args.html, source=args.source, max_frames=args.max_frames, progress=True
    )
    print(
        f"rbm-nb demo: wrote {path} ({path.stat().st_size / 1e6:.1f} MB); "
        "open it in a browser, it plays offline."
    )
    return 0


def _data_note(source: str) -> str:
    """Which recording the demo shows, and how to get the real one if it is not here."""
    if source == "synthetic":
        return (
            "rbm-nb demo: data: the synthetic head/eye recording (--source synthetic)"
        )

    store = ExampleDataStore()
    names = ("head", "left_eye", "right_eye")
    missing = [store.path(n).name for n in names if not store.is_available(n)]
    wrong = [store.path(n).name for n in names if store.path(n).is_file()]
    wrong = [name for name in wrong if name in missing]
    if wrong:
        return (
            f"rbm-nb demo: data: {', '.join(wrong)} in {store.data_dir}: not the "
            "registered file(s) of the real head/eye recording (the sha256 differs), "
            "so not used: the demo shows the synthetic recording. Replace them, or "
            f"point {DATA_DIR_ENV} at a folder with the right head.nc, left_eye.nc "
            "and right_eye.nc."
        )
    if not missing:
        return (
            "rbm-nb demo: data: the real head/eye recording (rbm-data) from "
            f"{store.data_dir}"
        )
    fallback = "" if source == "remote" else ", or the synthetic one if that fails"
    return (
        f"rbm-nb demo: data: {', '.join(missing)} of the real head/eye recording "
        f"(rbm-data) are not in {store.data_dir}; the demo downloads the real "
        f"recording{fallback}. "
        f"To use a copy you have, set {DATA_DIR_ENV} to the folder holding "
        "head.nc, left_eye.nc and right_eye.nc."
    )


# -- argument types: checked while parsing, before any work ----------------------


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(
            f"{port} is not a port (0 to 65535; 0 picks a free one)"
        )
    return port


def _max_frames(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be at least 2, got {value}")
    return value


def _html_path(text: str) -> Path:
    if not text.strip():
        raise argparse.ArgumentTypeError("give a file name, e.g. explorer.html")
    path = Path(text).expanduser()
    if path.is_dir():
        raise argparse.ArgumentTypeError(
            f"{text} is a folder; give a file name, e.g. {path / 'explorer.html'}"
        )
    if not path.parent.is_dir():
        raise argparse.ArgumentTypeError(
            f"the folder {str(path.parent)!r} does not exist; create it first"
        )
    return path


def _folder(text: str) -> str:
    if not text.strip() or not Path(text).expanduser().is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a folder")
    return text


def _refuse_inapplicable(parser, args, given: set[str]) -> None:
    """One-line error for options the chosen mode does not use (exit 2)."""
    if args.command == "demo":
        mode = "--text" if args.text else "--html" if args.html else "JupyterLab"
        unused = {
            "--text": {
                "--source",
                "--max-frames",
                "--port",
                "--no-browser",
                "--notebook-dir",
            },
            "--html": {"--port", "--no-browser", "--notebook-dir"},
            # the notebook picks its data itself (RBM_NB_DATA_DIR)
            "JupyterLab": {"--source", "--max-frames"},
        }[mode]
        wrong = sorted(unused & given)
        if wrong:
            where = (
                "the JupyterLab demo (add --html OUT.html to export)"
                if mode == "JupyterLab"
                else f"demo {mode}"
            )
            parser.error(f"{', '.join(wrong)} does not apply to {where}")


class _Parser(argparse.ArgumentParser):
    """Errors in one line (no usage block), exit status 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def main(argv: list[str] | None = None) -> int:
    parser = _Parser(prog="rbm-nb", description="rbm_nb: rigid body motion in Jupyter.")
    parser.add_argument(
        "--version", action="version", version=f"%(prog)s {__version__}"
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser(
        "demo", help="open JupyterLab on the head/eye explorer (or export it)"
    )
    mode = demo.add_mutually_exclusive_group()
    mode.add_argument(
        "--html",
        metavar="OUT.html",
        type=_html_path,
        help="write the explorer's dashboard as one self-contained HTML file and exit",
    )
    mode.add_argument(
        "--text",
        action="store_true",
        help="print a lookup across a small moving frame tree and exit",
    )
    demo.add_argument(
        "--source",
        choices=("auto", "remote", "synthetic"),
        default="auto",
        help="example data for --html: the real recording, else synthetic (auto)",
    )
    demo.add_argument(
        "--max-frames",
        type=_max_frames,
        default=10000,
        help="samples per moving object and plotted series in --html (evenly "
        "spaced, at least 2)",
    )
    demo.add_argument("--port", type=_port, default=8888, help="JupyterLab port")
    demo.add_argument(
        "--no-browser", action="store_true", help="do not open a browser window"
    )
    demo.add_argument(
        "--notebook-dir",
        type=_folder,
        help="folder with the notebooks (default: the clone's, else a copy of "
        "the installed ones)",
    )
    app = sub.add_parser(
        "app", help="serve the head/eye explorer as a standalone Voila app"
    )
    app.add_argument(
        "--source",
        choices=("auto", "remote", "synthetic"),
        default="auto",
        help="example data: the real recording, else synthetic (auto)",
    )
    app.add_argument("--port", type=_port, default=8866, help="Voila port")
    app.add_argument(
        "--no-browser", action="store_true", help="do not open a browser window"
    )
    args = parser.parse_args(argv)
    _refuse_inapplicable(demo, args, _given_options(argv))
    if args.command == "app":
        # lazy (import time): the app loads the explorer (~0.6 s)
        from .server import serve

        return serve(
            port=_free_port(args.port),
            source=args.source,
            open_browser=not args.no_browser,
        )
    if args.command == "demo":
        if args.text:
            return _text_demo()
        if args.html:
            return _html_demo(args)
        print(_data_note("auto"), flush=True)
        return _lab_demo(args)
    parser.error(f"unknown command {args.command!r}")
    return 2


def _given_options(argv: list[str] | None) -> set[str]:
    """The long options on the command line (``--port=1`` counts as ``--port``)."""
    words = sys.argv[1:] if argv is None else argv
    return {w.split("=", 1)[0] for w in words if w.startswith("--")}


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
