"""rbm_nb as a user gets it: the wheel and the sdist, installed in a fresh venv.

One build (``python -m build``) and one fresh venv (uv, the exact pins of
.ci/constraints.txt, dependencies downloaded or taken from uv's cache) with
the wheel installed non-editable; then the user's first commands, the demo
from the wheel, and the sdist's own fast tests. The build, the venv and the
sdist's tests are the session fixture ``packaging_runs`` of head_start.py:
they start with the session when these tests are selected, at low priority
on the core the other tests leave idle, and are awaited here.
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

import pytest
from conftest import REPO
from head_start import SDIST_SELECTION, SDIST_TEST, user_env
from packaging_support import run

import rbm_nb

pytestmark = [pytest.mark.slow, pytest.mark.timeout(3600)]

EXPLORER = "06_head_eye_explorer.ipynb"


@pytest.fixture(scope="module")
def dists(packaging_runs):
    return packaging_runs.dists.result(timeout=3600)


@pytest.fixture(scope="module")
def venv(packaging_runs):
    """A fresh venv with rbm_nb[all,lab,dev] from the wheel (not editable)."""
    assert packaging_runs.venv is not None  # made when this module's tests run
    return packaging_runs.venv.result(timeout=3600)


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
    env = user_env(tmp_path, venv)
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
    env = user_env(tmp_path, venv)
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


def test_sdist_fast_tests_pass_against_its_own_tree(packaging_runs):
    """Unpacked sdist + the venv: warm-up, then pytest -m "not slow and not browser"
    (in two processes at once; head_start._start_sdist_tests)."""
    # started when a test named SDIST_TEST is selected: this one
    assert packaging_runs.sdist_tests is not None, f"{SDIST_TEST} is not this test"
    runs, account = packaging_runs.sdist_tests.result(timeout=3600)
    print(account)
    assert runs, "the sdist's tests did not start"
    for paths, sdist_run in runs:
        code, out, _ = sdist_run.finish(timeout=1800)  # stderr goes to out
        summary = out.strip().splitlines()[-1] if out.strip() else ""
        print(f"sdist: pytest -m {SDIST_SELECTION!r} {' '.join(paths)}: {summary}")
        assert code == 0, f"pytest {' '.join(paths)}:\n{out[-6000:]}"
        assert " passed" in summary and "error" not in summary, summary
