"""rbm_nb as a user gets it: the wheel and the sdist, installed in a fresh venv.

One module-scoped build (``python -m build``) and one fresh venv (uv, the exact
pins of .ci/constraints.txt, dependencies downloaded or taken from uv's cache)
with the wheel installed non-editable; then the user's first commands, the
demo from the wheel, and the sdist's own fast tests.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import tarfile
import time
import urllib.request
import zipfile
from pathlib import Path

import pytest
from conftest import REPO, SHARED
from packaging_support import (
    build_dists,
    clean_env,
    make_venv,
    run,
    seed_numba_cache,
    uv,
)

import rbm_nb

pytestmark = [pytest.mark.slow, pytest.mark.timeout(3600)]

EXPLORER = "06_head_eye_explorer.ipynb"


@pytest.fixture(scope="module")
def dists(tmp_path_factory):
    return build_dists(tmp_path_factory.mktemp("dist"))


@pytest.fixture(scope="module")
def venv(dists, tmp_path_factory):
    """A fresh venv with rbm_nb[all,lab,dev] from the wheel (not editable)."""
    wheel, _ = dists
    root = tmp_path_factory.mktemp("venv")
    python = make_venv(root / "venv", see_this_env=False)
    run(
        [
            uv(),
            "pip",
            "install",
            "--quiet",
            "--python",
            str(python),
            "-c",
            str(REPO / ".ci" / "constraints.txt"),
            f"rbm_nb[all,lab,dev] @ {wheel.as_uri()}",
        ],
        timeout=1800,
        env=clean_env(),
    )
    return python


def _user_env(root: Path, python: Path) -> dict[str, str]:
    """A user's shell: the venv's bin on PATH, HOME of their own, no repo."""
    home = root / "home"
    home.mkdir(exist_ok=True)
    env = clean_env(HOME=str(home), MPLBACKEND="Agg")
    env.pop("XDG_DATA_HOME", None)
    env["PATH"] = f"{python.parent}{os.pathsep}{env['PATH']}"
    return env


def test_wheel_and_sdist_contents(dists):
    wheel, sdist = dists
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in (
        "rbm_nb/py.typed",
        f"rbm_nb/_notebooks/{EXPLORER}",
        f"rbm_nb-{rbm_nb.__version__}.dist-info/licenses/LICENSE",
    ):
        assert name in names, f"{name} missing from {wheel.name}"
    assert not [n for n in names if n.startswith(("tests/", "docs/", "notebooks/"))]
    top = f"rbm_nb-{rbm_nb.__version__}"
    members = set(tarfile.open(sdist).getnames())
    for name in (
        "LICENSE",
        "CHANGELOG.md",
        "conftest.py",
        "tests/conftest.py",
        "tests/browser_support.py",
        "tests/naive.py",
        "tests/packaging_support.py",
        ".ci/run",
        ".ci/constraints.txt",
        "docs/conf.py",
        f"notebooks/{EXPLORER}",
    ):
        assert f"{top}/{name}" in members, f"{name} missing from {sdist.name}"
    assert not [m for m in members if "__pycache__" in m or m.endswith(".pyc")]


def test_version_and_text_demo_from_the_wheel(venv, tmp_path):
    env = _user_env(tmp_path, venv)
    rbm_nb_cmd = str(venv.parent / "rbm-nb")
    version = run([rbm_nb_cmd, "--version"], timeout=60, env=env, cwd=tmp_path)
    assert version.stdout.strip() == f"rbm-nb {rbm_nb.__version__}"
    where = run(
        [str(venv), "-c", "import rbm_nb; print(rbm_nb.__file__)"],
        timeout=60,
        env=env,
        cwd=tmp_path,
    ).stdout
    assert "site-packages" in where and str(REPO) not in where
    text = run([rbm_nb_cmd, "demo", "--text"], timeout=900, env=env, cwd=tmp_path)
    assert "└── body" in text.stdout
    assert "5.00   [5.  0.  0.1]" in text.stdout


def test_demo_from_the_wheel_serves_a_writable_copy_of_the_explorer(venv, tmp_path):
    env = _user_env(tmp_path, venv)
    env["JUPYTER_RUNTIME_DIR"] = str(tmp_path / "runtime")
    process = subprocess.Popen(
        [str(venv.parent / "rbm-nb"), "demo", "--no-browser", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        cwd=tmp_path,
        start_new_session=True,
    )
    try:
        lines = []
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            line = process.stdout.readline()
            lines.append(line)
            if "http://" in line or not line:
                break
        output = "".join(lines)
        copy = tmp_path / "home" / ".local" / "share" / "rbm_nb"
        copy = copy / f"notebooks-{rbm_nb.__version__}"
        shipped = len(list((REPO / "notebooks").glob("*.ipynb")))
        assert f"copied {shipped} notebooks to {copy}" in output, output
        assert (copy / EXPLORER).is_file()
        url = re.search(r"http://\S+", output).group(0)
        base, token = url.split("/lab/")[0], url.split("token=")[1]
        request = urllib.request.Request(
            f"{base}/api/contents/{EXPLORER}?content=0",
            headers={"Authorization": f"token {token}"},
        )
        deadline = time.monotonic() + 120
        while True:
            try:
                with urllib.request.urlopen(request, timeout=5) as response:
                    assert response.status == 200
                    break
            except OSError:
                if time.monotonic() > deadline or process.poll() is not None:
                    raise
                time.sleep(0.5)
    finally:
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=30)


def test_sdist_fast_tests_pass_against_its_own_tree(dists, venv, tmp_path):
    """Unpacked sdist + the venv: warm-up, then pytest -m "not slow and not browser"
    (in two processes at once)."""
    _, sdist = dists
    with tarfile.open(sdist) as tar:
        tar.extractall(tmp_path, filter="data")
    (src,) = tmp_path.glob("rbm_nb-*")
    env = _user_env(tmp_path, venv)
    env["RBM_NB_SHARED"] = str(SHARED)  # the real recordings of this machine
    # as .ci/setup.sh does: fill numba's cache before the tests (from this
    # checkout's, which saves compiling every kernel a second time: 2.5 min)
    seeded = seed_numba_cache(src)
    warm = run(
        [str(venv), "-m", "rbm_nb._kernels._warmup"], timeout=1800, env=env, cwd=src
    )
    print(f"sdist: {seeded} numba cache files seeded;", warm.stdout + warm.stderr)
    # The fast selection in two processes side by side, one per core of CI's
    # two: the frame core's tests, and every other layer with the docstring
    # examples (about half the time each). The checks that run last in a
    # session (tests/test_*.py: what numba compiled) run in both.
    layers = sorted(
        p.name for p in (src / "tests").iterdir() if any(p.glob("test_*.py"))
    )
    assert "core" in layers, layers
    last = [str(p.relative_to(src)) for p in sorted(src.glob("tests/test_*.py"))]
    halves = (
        ["tests/core", *last],
        [*(f"tests/{name}" for name in layers if name != "core"), "rbm_nb", *last],
    )
    command = [str(venv), "-m", "pytest", "-q", "-p", "no:cacheprovider"]
    command += ["-m", "not slow and not browser"]
    logs = [tmp_path / f"half{k}.log" for k in range(len(halves))]
    runs = []
    try:
        for paths, log in zip(halves, logs, strict=True):
            with log.open("w") as sink:  # the child keeps its own copy open
                runs.append(
                    subprocess.Popen(
                        [*command, *paths],
                        stdout=sink,
                        stderr=subprocess.STDOUT,
                        env=env,
                        cwd=src,
                    )
                )
        codes = [process.wait(timeout=1800) for process in runs]
    finally:
        for process in runs:
            process.kill()
            process.wait()
    for paths, log, code in zip(halves, logs, codes, strict=True):
        out = log.read_text()
        summary = out.strip().splitlines()[-1] if out.strip() else ""
        print(f"sdist: pytest {' '.join(paths)}: {summary}")
        assert code == 0, f"pytest {' '.join(paths)}:\n{out[-6000:]}"
        assert " passed" in summary and "error" not in summary, summary
