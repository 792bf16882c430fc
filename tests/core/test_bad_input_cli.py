"""The servers the CLI starts, as real processes (issue 31, items 2 and 15).

* The token of ``rbm-nb demo``'s JupyterLab and of ``rbm-nb app``'s Voilà is
  never on a command line (``/proc/<pid>/cmdline`` is readable by every user
  of the machine), yet the server still asks for it.
* ``rbm-nb app`` ended by SIGTERM, SIGHUP (a closed terminal) or SIGKILL
  leaves no Voilà server or kernel behind and nothing listening.

The one-line refusals of bad CLI options are rows of the bad-input table.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import psutil
import pytest

pytestmark = pytest.mark.slow

RBM_NB = Path(sys.executable).with_name("rbm-nb")


def _start(args: list[str], tmp_path: Path) -> subprocess.Popen:
    env = dict(os.environ)
    for var, sub in (
        ("JUPYTER_CONFIG_DIR", "config"),
        ("JUPYTER_RUNTIME_DIR", "runtime"),
        ("JUPYTER_DATA_DIR", "data"),
        ("IPYTHONDIR", "ipython"),
    ):
        (tmp_path / sub).mkdir(exist_ok=True)
        env[var] = str(tmp_path / sub)
    env["JUPYTER_PLATFORM_DIRS"] = "1"
    env.pop("JUPYTER_TOKEN", None)
    return subprocess.Popen(
        [str(RBM_NB), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        start_new_session=True,  # our signals go to rbm-nb alone
    )


def _url(process: subprocess.Popen) -> str:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        match = re.search(r"http://\S+token=\w+", line)
        if match:
            # drain the rest so the server never blocks on a full pipe
            threading.Thread(target=process.stdout.read, daemon=True).start()
            return match.group(0)
        if not line and process.poll() is not None:
            break
    raise AssertionError("no address printed")


def _tree(pid: int) -> list[psutil.Process]:
    root = psutil.Process(pid)
    return [root, *root.children(recursive=True)]


def _cmdlines(pid: int) -> list[str]:
    lines = []
    for proc in _tree(pid):
        # what any user of the machine can read
        raw = Path(f"/proc/{proc.pid}/cmdline").read_bytes()
        lines.append(raw.replace(b"\0", b" ").decode(errors="replace"))
    return lines


def _status(url: str) -> int:
    class NoRedirect(urllib.request.HTTPRedirectHandler):
        def redirect_request(self, *args, **kwargs):
            return None

    opener = urllib.request.build_opener(NoRedirect)
    try:
        with opener.open(url, timeout=60) as response:
            return response.status
    except urllib.error.HTTPError as err:
        return err.code


def _open_quietly(url: str) -> None:
    try:
        _status(url)
    except OSError:
        pass  # the server may be stopped before it answers


def _wait_listening(base: str, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        assert process.poll() is None, "the server ended"
        try:
            _status(f"{base}/favicon.ico")
            return
        except OSError:
            time.sleep(0.5)
    raise AssertionError(f"{base} never answered")


def _port_open(port: int) -> bool:
    return any(
        c.laddr and c.laddr.port == port and c.status == psutil.CONN_LISTEN
        for c in psutil.net_connections("tcp")
    )


def _stop_group(process: subprocess.Popen) -> None:
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait(timeout=30)


def test_demo_token_is_not_on_the_command_line(tmp_path):
    process = _start(["demo", "--no-browser", "--port", "0"], tmp_path)
    try:
        url = _url(process)
        base, token = url.split("/lab/")[0], url.split("token=")[1]
        _wait_listening(base, process)
        lines = _cmdlines(process.pid)
        assert "jupyter-lab" in lines[0]  # the server took over rbm-nb's pid
        assert not [line for line in lines if token in line]
        # still needed, and the printed one works
        contents = f"{base}/api/contents/06_head_eye_explorer.ipynb?content=0"
        assert _status(contents) == 403
        assert _status(f"{contents}&token={token}") == 200
    finally:
        _stop_group(process)


def test_demo_first_screen_has_no_warning_and_no_news_question(tmp_path):
    # what a newcomer saw first: jupyter-server's "ServerApp.token config is
    # deprecated" (about a setting the demo does not make) and JupyterLab's
    # "Would you like to get notified about official Jupyter news?"
    process = _start(["demo", "--no-browser", "--port", "0"], tmp_path)
    lines = []
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            line = process.stdout.readline()
            lines.append(line)
            # the server says so once every extension is loaded
            if "is running at" in line or (not line and process.poll() is not None):
                break
        text = "".join(lines)
        assert "is running at" in text, text
        url = re.search(r"http://\S+token=\w+", text).group(0)
        base, token = url.split("/lab/")[0], url.split("token=")[1]
        _wait_listening(base, process)
        # JupyterLab asks about news while this setting is "none"
        plugin = "@jupyterlab/apputils-extension:notification"
        request = urllib.request.Request(
            f"{base}/lab/api/settings/{plugin}",
            headers={"Authorization": f"token {token}"},
        )
        with urllib.request.urlopen(request, timeout=60) as response:
            # (the server folds default overrides into the schema's defaults)
            defaults = json.load(response)["schema"]["properties"]
    finally:
        _stop_group(process)
    assert "Warning" not in text, text
    assert defaults["fetchNews"]["default"] == "false"
    assert defaults["checkForUpdates"]["default"] is False


@pytest.mark.timeout(300)
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL])
def test_app_token_hidden_and_voila_ends_with_rbm_nb(tmp_path, signum):
    process = _start(
        ["app", "--no-browser", "--source", "synthetic", "--port", "0"], tmp_path
    )
    try:
        url = _url(process)
        base, token = url.split("/?")[0], url.split("token=")[1]
        port = int(base.rsplit(":", 1)[1])
        _wait_listening(base, process)
        assert _status(f"{base}/?token=wrong") in (302, 401, 403)
        # opening the page starts a kernel under Voilà
        threading.Thread(target=_open_quietly, args=(url,), daemon=True).start()
        deadline = time.monotonic() + 120
        while not any("ipykernel" in line for line in _cmdlines(process.pid)):
            assert time.monotonic() < deadline, "no kernel started"
            time.sleep(0.5)
        lines = _cmdlines(process.pid)
        assert not [line for line in lines if token in line]
        started = _tree(process.pid)
        assert len(started) >= 3  # rbm-nb, Voilà, the kernel

        os.kill(process.pid, signum)
        process.wait(timeout=60)
        gone, alive = psutil.wait_procs(started, timeout=60)
        assert not alive, f"left running: {[p.cmdline() for p in alive]}"
        assert not _port_open(port)
    finally:
        _stop_group(process)
        for proc in psutil.process_iter():
            try:
                if token in " ".join(proc.environ().values()):
                    proc.kill()
            except (psutil.Error, NameError):
                pass
