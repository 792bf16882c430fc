"""Binder, simulated: what repo2docker would build, and the explorer running in it.

Binder itself is out of reach here, so the slow tests do its steps by hand:
a fresh Python 3.11 venv gets ``binder/requirements.txt`` and nothing else, a
copy of the working tree (tracked and untracked files, not ignored ones) runs
``binder/postBuild`` (with numba's cache seeded from this checkout's, see
the ``binder`` fixture), a JupyterLab server with jupyter-server-proxy starts
from that venv on loopback with a token, and the explorer notebook runs cell
by cell in a kernel of that server (through its REST and websocket API, as
JupyterLab drives it). The 3D view is a widget over the kernel's comm, so
the kernel must have made one and no proxy route is involved.

Timings (install, postBuild, first frame-core call, notebook) are printed and
written to ``test-artifacts/binder_timing.json``; nothing asserts on time.
What is asserted is that the warm-up works: a fresh process of the venv, and
the notebook's kernel, load every kernel they call from numba's cache and
compile none.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
import urllib.error
import urllib.request
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
import psutil
import pytest
import tomllib
import websocket
from conftest import REPO
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging_support import seed_numba_cache

BINDER = REPO / "binder"
NOTEBOOK = "notebooks/06_head_eye_explorer.ipynb"
ARTIFACT = REPO / "test-artifacts" / "binder_timing.json"
EXTRAS = ("notebook", "data", "ros", "sdf", "lab")
TEST_ONLY = {
    "rigid-body-motion",
    "pytest",
    "pytest-timeout",
    "hypothesis",
    "playwright",
    "anytree",
    "ruff",
}
# packages a fresh venv has before anything is installed
VENV_SEED = {"pip", "setuptools", "wheel"}
# environment that would make the simulated Binder see this machine's setup
LEAKY_ENV = (
    "VIRTUAL_ENV",
    "PYTHONPATH",
    "PYTHONHOME",
    "PYTHONSTARTUP",
    "NUMBA_CACHE_DIR",
    "NUMBA_DISABLE_JIT",
    "RBM_NB_DATA_DIR",
    "RBM_NB_VIEWER_PORT",
    "XDG_CACHE_HOME",
    "XDG_CONFIG_HOME",
    "XDG_DATA_HOME",
    "XDG_RUNTIME_DIR",
    "MPLCONFIGDIR",
    "IPYTHONDIR",
    "PYTHONDONTWRITEBYTECODE",
    "JUPYTER_CONFIG_DIR",
    "JUPYTER_DATA_DIR",
    "JUPYTER_PATH",
    "JUPYTER_RUNTIME_DIR",
    "JUPYTER_CONFIG_PATH",
)

TIMINGS: dict = {}

# The first frame-core call as a user makes it, in a fresh process: a moving
# head frame (1000 samples) with a static camera on it, looked up in world.
FIRST_CALL = """
import json, time
t0 = time.perf_counter()
import numpy as np
import rbm_nb as rbm
t1 = time.perf_counter()
n = 1000
angle = np.linspace(0.0, 1.0, n)
rotation = np.column_stack([np.cos(angle / 2), np.zeros(n), np.zeros(n), np.sin(angle / 2)])
translation = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(n)])
rbm.register_frame("world")
rbm.register_frame("head", parent="world", translation=translation, rotation=rotation,
                   timestamps=np.arange(n) * 0.005)
rbm.register_frame("camera", parent="head", translation=(0.02, -0.03, 0.0),
                   rotation=(0.5, -0.5, 0.5, -0.5))
t, r = rbm.lookup_transform(outof="camera", into="world")
t2 = time.perf_counter()
assert t.shape == (n, 3) and r.shape == (n, 4)
from rbm_nb._kernels._warmup import kernel_stats
stats = kernel_stats()
print(json.dumps({"import_s": t1 - t0, "call_s": t2 - t1, "import_and_call_s": t2 - t0,
                  "compiled": stats.compiled, "loaded": stats.loaded,
                  "rbm_nb": rbm.__file__}))
"""

# Run in the notebook's kernel after the notebook: what it compiled, where it
# runs, and the 3D views it made (widgets over the kernel's comm, no port).
KERNEL_PROBE = """
import json, os, sys
import rbm_nb
from ipywidgets.widgets.widget import _instances
from rbm_nb._kernels._warmup import kernel_dispatchers, kernel_stats
from rbm_nb.scene.widget import SceneWidget
_stats = kernel_stats()
print(json.dumps({
    "pid": os.getpid(), "executable": sys.executable, "rbm_nb": rbm_nb.__file__,
    "compiled": _stats.compiled, "loaded": _stats.loaded,
    "compiled_kernels": sorted({d.py_func.__name__ for d in kernel_dispatchers()
                                if d.stats.cache_misses}),
    "scene_widgets": sum(isinstance(w, SceneWidget) for w in _instances.values()),
}))
"""


# ---------------------------------------------------------------------------
# processes: every one started here is stopped here
# ---------------------------------------------------------------------------


class Processes:
    """Processes started in their own session, stopped with their whole group."""

    def __init__(self, marker: str):
        self.marker = marker  # a path every process of ours has in its command line
        self.started: list[subprocess.Popen] = []

    def start(self, cmd, **kwargs) -> subprocess.Popen:
        proc = subprocess.Popen(cmd, start_new_session=True, **kwargs)
        self.started.append(proc)
        return proc

    def run(self, cmd, *, timeout: float, **kwargs) -> tuple[int, str]:
        """Run to completion; returns (exit code, stdout and stderr together)."""
        proc = self.start(
            cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kwargs
        )
        try:
            out, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.stop(proc)
            out, _ = proc.communicate()
            pytest.fail(f"{cmd} did not finish within {timeout} s:\n{out[-3000:]}")
        finally:
            self.stop(proc)
        return proc.returncode, out

    @staticmethod
    def stop(proc: subprocess.Popen, grace: float = 15.0) -> None:
        """SIGTERM to the process group, SIGKILL if it is still there after ``grace``."""
        for sig in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(proc.pid, sig)
            except ProcessLookupError:
                break
            try:
                proc.wait(timeout=grace)
                break
            except subprocess.TimeoutExpired:
                continue
        proc.wait()

    def stragglers(self) -> list[psutil.Process]:
        """Processes still running from our venv or tree (e.g. kernels)."""
        found = []
        for p in psutil.process_iter(["cmdline", "exe"]):
            text = " ".join(p.info["cmdline"] or []) + " " + (p.info["exe"] or "")
            if self.marker in text and p.pid != os.getpid():
                found.append(p)
        return found

    def stop_all(self) -> list[str]:
        for proc in self.started:
            self.stop(proc)
        leaked = self.stragglers()
        for p in leaked:  # ours by construction: their command line names our tmp dir
            try:
                p.kill()
            except psutil.NoSuchProcess:
                pass
        psutil.wait_procs(leaked, timeout=10)
        return [" ".join(p.info["cmdline"] or []) for p in leaked]


# ---------------------------------------------------------------------------
# the simulated Binder build
# ---------------------------------------------------------------------------


@dataclass
class BinderBuild:
    root: Path
    repo: Path
    venv: Path
    env: dict
    procs: Processes
    installed: dict = field(default_factory=dict)  # name -> version before postBuild
    postbuild_output: str = ""
    site_packages: Path = field(default=Path())
    seeded: int = 0  # numba cache files copied from this checkout before postBuild

    @property
    def python(self) -> str:
        return str(self.venv / "bin" / "python")

    def run_python(self, code: str, cwd=None, **env) -> tuple[int, str, float]:
        """Run ``code`` in a fresh process (in ``cwd``, default outside the repo)."""
        start = time.perf_counter()
        rc, out = self.procs.run(
            [self.python, "-c", code],
            timeout=300,
            cwd=cwd or self.root,
            env={**self.env, **env},
        )
        return rc, out, time.perf_counter() - start


def _pins() -> dict[str, str]:
    pins = {}
    for line in (BINDER / "requirements.txt").read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            req = Requirement(line)
            (spec,) = req.specifier  # exactly one specifier per line
            assert spec.operator == "==", (
                f"binder/requirements.txt: {line!r} is not an exact pin"
            )
            pins[canonicalize_name(req.name)] = spec.version
    return pins


def _binder_python() -> str:
    """The interpreter binder/runtime.txt asks for (``python-3.11``)."""
    runtime = (BINDER / "runtime.txt").read_text().strip()
    match = re.fullmatch(r"python-(\d+\.\d+)", runtime)
    assert match, f"binder/runtime.txt must read like 'python-3.11', got {runtime!r}"
    version = match.group(1)
    found = shutil.which(f"python{version}")
    if found is None and f"{sys.version_info[0]}.{sys.version_info[1]}" == version:
        found = getattr(sys, "_base_executable", None) or sys.executable
    if found is None:
        pytest.fail(f"binder/runtime.txt asks for Python {version}: not installed")
    # the interpreter itself, not a shim (pyenv's depend on HOME, which moves)
    code = "import sys; print(sys.executable)"
    real = subprocess.run([found, "-c", code], capture_output=True, text=True)
    return real.stdout.strip() or found


def _copy_working_tree(dst: Path) -> None:
    """Tracked and untracked files that are not ignored, as Binder would get them."""
    listed = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard", "-z"],
        cwd=REPO,
        capture_output=True,
        check=True,
    ).stdout.decode()
    for rel in filter(None, listed.split("\0")):
        src = REPO / rel
        if src.is_file():  # deleted but still tracked files are left out
            (dst / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst / rel)


def _environment(root: Path, venv: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in LEAKY_ENV}
    # pip's cache by absolute path, before HOME moves: the wheels were just
    # installed on this machine, so the fresh venv installs mostly offline
    cache = subprocess.run(
        [sys.executable, "-m", "pip", "cache", "dir"], capture_output=True, text=True
    ).stdout.strip()
    if cache:
        env["PIP_CACHE_DIR"] = cache
    home = root / "home"
    home.mkdir()
    env.update(
        HOME=str(home),  # Binder's user: data cache, Jupyter and matplotlib dirs
        PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}",
        PIP_DISABLE_PIP_VERSION_CHECK="1",
        PIP_NO_INPUT="1",
    )
    return env


@pytest.fixture(scope="module")
def timings():
    yield TIMINGS
    if TIMINGS:
        ARTIFACT.parent.mkdir(exist_ok=True)
        tmp = ARTIFACT.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(TIMINGS, indent=2) + "\n")
        os.replace(tmp, ARTIFACT)
        print("\nBinder simulation timings (s):")
        for key, value in TIMINGS.items():
            if isinstance(value, float):
                print(f"  {key:<44} {value:8.2f}")


@pytest.fixture(scope="module")
def binder(tmp_path_factory, timings):
    root = tmp_path_factory.mktemp("binder")
    venv, repo = root / "venv", root / "repo"
    procs = Processes(str(root))
    try:
        env = _environment(root, venv)
        build = BinderBuild(root, repo, venv, env, procs)
        start = time.perf_counter()
        rc, out = procs.run(
            [_binder_python(), "-m", "venv", str(venv)], timeout=120, env=env
        )
        assert rc == 0, out
        # --no-compile halves the install time. pip byte-compiles on Binder; here
        # each module gets its .pyc when first imported (PYTHONDONTWRITEBYTECODE
        # is dropped above), and postBuild imports all that a first call needs
        pip = [build.python, "-m", "pip"]
        requirements = str(BINDER / "requirements.txt")
        cmd = [*pip, "install", "--no-compile", "-q", "-r", requirements]
        rc, out = procs.run(cmd, timeout=900, env=env)
        assert rc == 0, f"pip install -r binder/requirements.txt failed:\n{out[-5000:]}"
        timings["venv + pip install -r requirements.txt"] = time.perf_counter() - start
        rc, out = procs.run([*pip, "check"], timeout=120, env=env)
        assert rc == 0, f"pip check after installing binder/requirements.txt:\n{out}"
        rc, out = procs.run([*pip, "list", "--format=json"], timeout=120, env=env)
        assert rc == 0, out
        build.installed = {
            canonicalize_name(d["name"]): d["version"] for d in json.loads(out)
        }

        _copy_working_tree(repo)
        if not os.environ.get("RBM_NB_BINDER_COLD"):
            # this checkout's compiled kernels, for the same sources: postBuild's
            # warm-up then loads them instead of compiling for 4-5 minutes what
            # .ci/setup.sh's warm-up (the same command) has just compiled. Set
            # RBM_NB_BINDER_COLD=1 to time a Binder build from an empty cache.
            build.seeded = seed_numba_cache(repo)
        TIMINGS["numba cache files seeded"] = build.seeded
        start = time.perf_counter()
        rc, out = procs.run(
            [str(repo / "binder" / "postBuild")], timeout=900, cwd=repo, env=env
        )
        timings["postBuild"] = time.perf_counter() - start
        build.postbuild_output = out
        assert rc == 0, f"binder/postBuild failed:\n{out[-5000:]}"
        code = "import sysconfig; print(sysconfig.get_paths()['purelib'])"
        rc, out = procs.run([build.python, "-c", code], timeout=60, env=env)
        assert rc == 0, out
        build.site_packages = Path(out.strip())
        yield build
    finally:
        leaked = procs.stop_all()
        assert not leaked, f"processes were left running: {leaked}"


# ---------------------------------------------------------------------------
# the pinned requirements (fast)
# ---------------------------------------------------------------------------


def test_requirements_pin_everything_rbm_nb_needs_and_nothing_for_tests():
    pins = _pins()
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    needed = list(pyproject["dependencies"])
    for extra in EXTRAS:
        needed += pyproject["optional-dependencies"][extra]
    needed.append("ipykernel")
    for line in needed:
        req = Requirement(line)
        if canonicalize_name(req.name) == "rbm-nb":
            continue  # rbm_nb[...] self references: their contents are listed
        name = canonicalize_name(req.name)
        assert name in pins, f"binder/requirements.txt does not pin {req.name} ({line})"
        assert req.specifier.contains(pins[name], prereleases=True), (
            f"binder/requirements.txt pins {req.name}=={pins[name]}, pyproject wants {line}"
        )
    assert not TEST_ONLY & set(pins), (
        f"test-only packages pinned: {TEST_ONLY & set(pins)}"
    )
    assert "rbm-nb" not in pins, "rbm_nb itself is installed by postBuild"
    # the same versions as the environment CI tests (a subset of its freeze)
    ci = {}
    for line in (REPO / ".ci" / "constraints.txt").read_text().splitlines():
        if "==" in line and not line.lstrip().startswith("#"):
            name, version = line.split("==")
            ci[canonicalize_name(name.strip())] = version.strip()
    drift = {n: (v, ci.get(n)) for n, v in pins.items() if ci.get(n) != v}
    assert not drift, f"binder pins differ from .ci/constraints.txt: {drift}"


def test_binder_files_are_what_repo2docker_runs():
    assert os.access(BINDER / "postBuild", os.X_OK), (
        "binder/postBuild must be executable"
    )
    script = (BINDER / "postBuild").read_text()
    assert script.startswith("#!/usr/bin/env bash\n") and "set -euo pipefail" in script
    assert (BINDER / "runtime.txt").read_text().strip() == "python-3.11"


# ---------------------------------------------------------------------------
# the simulated build (slow)
# ---------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.timeout(900)  # builds a venv with pip (about 70 s here)
def test_requirements_install_alone_and_pin_every_package(binder):
    pins, installed = _pins(), binder.installed  # installed: before postBuild
    unpinned = {n: v for n, v in installed.items() if n not in {*pins, *VENV_SEED}}
    assert not unpinned, f"installed, not pinned in binder/requirements.txt: {unpinned}"
    other = {n: (v, pins[n]) for n, v in installed.items() if pins.get(n, v) != v}
    assert not other, f"installed versions differ from the pins: {other}"
    assert not set(pins) - set(installed), "pinned but not installed"


@pytest.mark.slow
@pytest.mark.timeout(900)  # builds a venv with pip (about 70 s here)
def test_postbuild_installs_fetches_and_warms_the_cache(binder, timings):
    out = binder.postbuild_output
    assert "Successfully installed rbm_nb-" in out
    # editable: the install and the repository's ./rbm_nb are the same files
    (finder,) = binder.site_packages.glob("__editable__*rbm_nb*finder.py")
    assert str(binder.repo / "rbm_nb") in finder.read_text()
    assert not (binder.site_packages / "rbm_nb").exists()
    # example data: fetched, or one clear line that the synthetic recording is used
    offline = re.search(
        r"^postBuild: example data unavailable \(([a-z_, ]+): .+\); the notebooks "
        r"will use the synthetic recording instead$",
        out,
        re.M,
    )
    unavailable = set(offline.group(1).split(", ")) if offline else set()
    for name in ("head", "left_eye", "right_eye", "rosbag"):
        ready = f"postBuild: example data {name!r} ready at" in out
        assert ready != (name in unavailable), f"postBuild on {name!r}:\n{out}"
    timings["postBuild: example data"] = float(
        re.search(r"example data step took (\d+) s", out).group(1)
    )
    # one warm-up, of the repository's rbm_nb, on every core of the machine
    summaries = re.findall(
        r"^rbm_nb warm-up: (\d+) of (\d+) kernel signatures ready \((\d+) compiled, "
        r"(\d+) loaded from the cache; (\d+) process(?:es)?\), ([\d.]+) s; cache: (.+)$",
        out,
        re.M,
    )
    assert len(summaries) == 1, f"expected one warm-up summary:\n{out[-3000:]}"
    ((ready, declared, compiled, loaded, jobs, seconds, cache),) = summaries
    kernels = binder.repo / "rbm_nb" / "_kernels"
    assert Path(cache) == kernels / "__pycache__", summaries
    # every declared kernel is in the cache afterwards: compiled there, or (with
    # the cache seeded from this checkout's, same sources) loaded, none compiled
    assert int(ready) == int(declared), summaries
    if binder.seeded:
        assert (int(compiled), int(loaded)) == (0, int(declared)), summaries
    else:
        assert int(compiled) > 0, summaries
    assert int(jobs) == len(os.sched_getaffinity(0))
    for module in sorted(kernels.glob("[a-z]*.py")):
        if "@njit" in module.read_text():
            indexes = list((kernels / "__pycache__").glob(f"{module.stem}.*.nbi"))
            assert indexes, f"no numba cache index for {module}"
    timings["postBuild: warm-up"] = float(seconds)
    TIMINGS["warm-up signatures compiled"] = int(compiled)


@pytest.mark.slow
@pytest.mark.timeout(900)  # builds a venv with pip (about 70 s here)
def test_first_frame_core_call_loads_its_kernels_from_the_cache(binder, timings):
    rc, out, wall = binder.run_python(FIRST_CALL)
    assert rc == 0, out
    first = json.loads(out.strip().splitlines()[-1])
    assert Path(first["rbm_nb"]).is_relative_to(binder.repo)
    assert first["compiled"] == 0 and first["loaded"] > 0, first
    timings["first call after postBuild: calls only"] = first["call_s"]
    timings["first call after postBuild: import + calls"] = first["import_and_call_s"]
    timings["first call after postBuild: process wall"] = wall

    # the same call without the warmed cache compiles: the check above can fail
    rc, out, wall = binder.run_python(
        FIRST_CALL, NUMBA_CACHE_DIR=str(binder.root / "cold")
    )
    assert rc == 0, out
    cold = json.loads(out.strip().splitlines()[-1])
    assert cold["compiled"] > 0, cold
    timings["same call, empty cache: calls only"] = cold["call_s"]

    # a kernel at the repository root imports ./rbm_nb: the same files, warm
    rc, out, _ = binder.run_python(FIRST_CALL, cwd=binder.repo)
    assert rc == 0, out
    at_root = json.loads(out.strip().splitlines()[-1])
    assert Path(at_root["rbm_nb"]).is_relative_to(binder.repo)
    assert at_root["compiled"] == 0 and at_root["loaded"] > 0, at_root

    # and a second warm-up has nothing left to compile
    rc, out, _ = binder.run_python("from rbm_nb._kernels._warmup import main; main([])")
    assert rc == 0, out
    assert re.search(
        r"warm-up: (\d+) of \1 kernel signatures ready \(0 compiled, [1-9]\d* loaded",
        out,
    ), out


# ---------------------------------------------------------------------------
# the explorer in a Jupyter server of the Binder venv (slow)
# ---------------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Server:
    url: str
    token: str
    log: Path

    def request(self, method: str, path: str, body=None, timeout: float = 30.0):
        """(status, body bytes) of a request with the token."""
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(
            self.url + path,
            data=data,
            method=method,
            headers={
                "Authorization": f"token {self.token}",
                "Content-Type": "application/json",
            },
        )
        try:
            with urllib.request.urlopen(req, timeout=timeout) as resp:
                return resp.status, resp.read()
        except urllib.error.HTTPError as err:
            return err.code, err.read()

    def log_tail(self) -> str:
        return self.log.read_text(errors="replace")[-4000:]


@pytest.fixture(scope="module")
def jupyter(binder, timings):
    port, token = _free_port(), uuid.uuid4().hex
    log = binder.root / "jupyter.log"
    cmd = [
        str(binder.venv / "bin" / "jupyter-lab"),
        "--no-browser",
        "--ip=127.0.0.1",
        f"--port={port}",
        "--ServerApp.port_retries=0",
        f"--ServerApp.root_dir={binder.repo}",
    ]
    if os.geteuid() == 0:  # CI containers run as root; Binder's user is not
        cmd.append("--allow-root")
    with open(log, "w") as log_file:
        proc = binder.procs.start(
            cmd,
            cwd=binder.repo,
            # the token through the environment, never on a command line
            env={**binder.env, "JUPYTER_TOKEN": token},
            stdout=log_file,
            stderr=subprocess.STDOUT,
        )
    server = Server(f"http://127.0.0.1:{port}", token, log)
    try:
        start = time.perf_counter()
        while True:
            assert proc.poll() is None, f"jupyter-lab exited:\n{server.log_tail()}"
            try:
                if server.request("GET", "/api/status", timeout=5)[0] == 200:
                    break
            except OSError:
                pass
            assert time.perf_counter() - start < 180, f"no answer:\n{server.log_tail()}"
            time.sleep(0.5)
        timings["jupyter-lab start"] = time.perf_counter() - start
        yield server
    finally:
        binder.procs.stop(proc)  # SIGTERM: the server shuts its kernels down


class KernelChannel:
    """The kernel's websocket as JupyterLab uses it: execute, collect, wait for idle."""

    def __init__(self, server: Server, kernel_id: str):
        session = uuid.uuid4().hex
        self.session = session
        self.ws = websocket.create_connection(
            f"ws{server.url[4:]}/api/kernels/{kernel_id}/channels?session_id={session}",
            header=[f"Authorization: token {server.token}"],
            timeout=30,
        )

    def close(self) -> None:
        self.ws.close()

    def _receive(self, timeout: float) -> dict:
        self.ws.settimeout(timeout)
        opcode, data = self.ws.recv_data()
        if opcode == websocket.ABNF.OPCODE_BINARY:
            # jupyter_server's binary framing: count, offsets, then the JSON part
            (count,) = struct.unpack("!I", data[:4])
            offsets = struct.unpack(f"!{count}I", data[4 : 4 * (count + 1)])
            end = offsets[1] if count > 1 else len(data)
            data = data[offsets[0] : end]
        return json.loads(data)

    def execute(self, code: str, timeout: float = 600.0) -> tuple[str, list]:
        """Run ``code``; returns (stdout text, errors as 'ename: evalue' + traceback)."""
        msg_id = uuid.uuid4().hex
        self.ws.send(
            json.dumps(
                {
                    "header": {
                        "msg_id": msg_id,
                        "msg_type": "execute_request",
                        "username": "binder-test",
                        "session": self.session,
                        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                        "version": "5.3",
                    },
                    "parent_header": {},
                    "metadata": {},
                    "channel": "shell",
                    "buffers": [],
                    "content": {
                        "code": code,
                        "silent": False,
                        "store_history": True,
                        "user_expressions": {},
                        "allow_stdin": False,
                        "stop_on_error": True,
                    },
                }
            )
        )
        deadline = time.monotonic() + timeout
        text, errors, replied, idle = [], [], False, False
        while not (replied and idle):
            left = deadline - time.monotonic()
            assert left > 0, (
                f"no reply within {timeout} s; output so far:\n{''.join(text)}"
            )
            msg = self._receive(left)
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            kind, content = msg["msg_type"], msg["content"]
            if kind == "stream" and content.get("name") == "stdout":
                text.append(content["text"])
            elif kind == "error":
                errors.append(
                    f"{content['ename']}: {content['evalue']}\n"
                    + "\n".join(content.get("traceback", []))
                )
            elif kind == "execute_reply":
                replied = True
                if content["status"] != "ok" and not errors:
                    errors.append(f"execute_reply status {content['status']}")
            elif kind == "status" and content["execution_state"] == "idle":
                idle = True
        return "".join(text), errors


@pytest.mark.slow
@pytest.mark.timeout(900)  # builds a venv with pip (about 70 s here)
def test_explorer_notebook_runs_in_the_binder_jupyter_server(binder, jupyter, timings):
    # JupyterLab itself and jupyter-server-proxy are served
    status, _ = jupyter.request("GET", "/lab")
    assert status == 200, jupyter.log_tail()
    status, body = jupyter.request("GET", "/server-proxy/servers-info")
    assert status == 200, f"jupyter-server-proxy is not enabled:\n{jupyter.log_tail()}"
    assert "server_processes" in json.loads(body)

    # a notebook session, as JupyterLab opens one: the kernel's cwd is notebooks/
    start = time.perf_counter()
    status, body = jupyter.request(
        "POST",
        "/api/sessions",
        {
            "path": NOTEBOOK,
            "type": "notebook",
            "name": Path(NOTEBOOK).name,
            "kernel": {"name": "python3"},
        },
    )
    assert status == 201, f"{status} {body!r}\n{jupyter.log_tail()}"
    session = json.loads(body)
    channel = kernel_pid = None
    try:
        channel = KernelChannel(jupyter, session["kernel"]["id"])
        channel.execute("1 + 1", timeout=120)  # the kernel is up
        timings["kernel start"] = time.perf_counter() - start

        notebook = nbformat.read(binder.repo / NOTEBOOK, as_version=4)
        cells = [c for c in notebook.cells if c.cell_type == "code"]
        assert cells
        start = time.perf_counter()
        for i, cell in enumerate(cells):
            cell_start = time.perf_counter()
            _, errors = channel.execute(cell.source)
            assert not errors, (
                f"{NOTEBOOK} cell {i} failed:\n{cell.source}\n\n{errors[0]}"
            )
            timings[f"notebook cell {i}"] = time.perf_counter() - cell_start
        timings["notebook execution (all cells)"] = time.perf_counter() - start

        text, errors = channel.execute(KERNEL_PROBE)
        assert not errors, errors[0]
        probe = json.loads(text.strip().splitlines()[-1])
        kernel_pid = probe["pid"]
        # the notebook ran in the Binder venv, on the installed rbm_nb ...
        assert Path(probe["executable"]).parent == binder.venv / "bin"
        assert Path(probe["rbm_nb"]).is_relative_to(binder.repo)
        # ... and postBuild's warm-up had compiled every kernel it called
        assert probe["loaded"] > 0
        assert probe["compiled"] == 0, (
            f"the warm-up missed kernels the explorer compiled: {probe['compiled_kernels']}"
        )

        # the 3D view is a widget over the kernel's comm: no viewer server to reach
        assert probe["scene_widgets"] >= 1
    finally:
        if channel is not None:
            channel.close()
        status, _ = jupyter.request("DELETE", f"/api/sessions/{session['id']}")
    assert status == 204
    try:  # the session's kernel ends with it (TimeoutExpired if it does not)
        psutil.Process(kernel_pid).wait(timeout=30)
    except psutil.NoSuchProcess:
        pass


# ---------------------------------------------------------------------------
# the warm-up in this process
# ---------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.timeout(900)  # builds a venv with pip (about 70 s here)
def test_warm_up_leaves_the_registry_as_it_was():
    import rbm_nb as rbm
    from rbm_nb._kernels._warmup import (
        declared_kernels,
        kernel_dispatchers,
        key,
        ready,
        warm_up,
    )

    rbm.register_frame("world")
    rbm.register_frame("head", parent="world", translation=(0.0, 0.0, 1.7))
    before = dict(rbm.registry)
    stats = warm_up()
    assert dict(rbm.registry) == before
    assert all(rbm.registry[name] is frame for name, frame in before.items())
    dispatchers = kernel_dispatchers()
    assert stats.kernels == len(dispatchers) > 0
    # every declared signature of every kernel module is in the cache after
    # it: compiled here or by an earlier process (the account says which; a
    # signature already there is not loaded into this process, so what this
    # process holds depends on the tests that ran before)
    assert stats.compiled + stats.loaded == stats.kernels
    missing = {k.name for k in declared_kernels() if key(k) not in ready()}
    assert not missing, f"the warm-up left these signatures out: {sorted(missing)}"
