"""numba's cache when the installed package and HOME are read-only.

The wheel is installed into a fresh venv; then, in a private mount namespace,
its site-packages and a fake HOME are bind-mounted read-only (chmod does not
stop root, a read-only mount does) and a kernel is called in a new process.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import pytest
from packaging_support import clean_env, make_venv, run, site_packages, uv

pytestmark = pytest.mark.slow  # builds a wheel and a venv, compiles a kernel

# a kernel call, the warnings it raised, and where numba put the cache
PROBE = """
import json, os, warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import rbm_nb as rbm
    result = rbm.qmul([1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]).tolist()
print(json.dumps({
    "file": rbm.__file__,
    "result": result,
    "warnings": [f"{w.category.__name__}: {w.message}" for w in caught
                 if "numba" in str(w.message).lower()],
    "cache_dir": os.environ.get("NUMBA_CACHE_DIR"),
}))
"""


def _can_mount_read_only(tmp: Path) -> str | None:
    """None if ``unshare -m`` + a read-only bind mount work here, else why not."""
    if shutil.which("unshare") is None or shutil.which("mount") is None:
        return "unshare/mount are not installed"
    probe = tmp / "ro-probe"
    probe.mkdir()
    script = f"mount --bind -o ro {probe} {probe} && ! touch {probe}/x 2>/dev/null"
    result = subprocess.run(
        ["unshare", "-m", "--propagation", "private", "sh", "-c", script],
        capture_output=True,
        text=True,
    )
    if result.returncode != 0:
        return f"no read-only bind mounts here (unshare -m: {result.stderr.strip()})"
    return None


@pytest.fixture(scope="module")
def installed(tmp_path_factory, packaging_runs):
    """A venv with the wheel installed (dependencies from this environment).

    The wheel is test_packaging.py's (head_start.packaging_runs: built once,
    from the start of the session)."""
    root = tmp_path_factory.mktemp("numba-cache")
    why = _can_mount_read_only(root)
    if why:
        pytest.skip(f"cannot make site-packages read-only: {why}")
    wheel, _ = packaging_runs.dists.result(timeout=3600)
    python = make_venv(root / "venv", see_this_env=True)
    run(
        [
            uv(),
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--python",
            str(python),
            str(wheel),
        ],
        timeout=300,
    )
    return root, python


def _run_read_only(root: Path, python: Path, tmpdir: Path, *, tmp_ro: bool) -> dict:
    """Run PROBE with site-packages and HOME (and maybe TMPDIR) read-only."""
    import json

    home = root / "home"
    home.mkdir(exist_ok=True)
    read_only = [site_packages(python), home]
    if tmp_ro:  # every folder tempfile.gettempdir() would fall back to
        read_only += [tmpdir, Path(tempfile.gettempdir()), Path("/tmp")]
        read_only += [p for p in (Path("/var/tmp"), Path("/usr/tmp")) if p.is_dir()]
    mounts = " && ".join(f"mount --bind -o ro {p} {p}" for p in read_only)
    env = clean_env(HOME=str(home), TMPDIR=str(tmpdir))
    env.pop("XDG_CACHE_HOME", None)  # numba's user folder must be the one in HOME
    result = subprocess.run(
        [
            "unshare",
            "-m",
            "--propagation",
            "private",
            "sh",
            "-c",
            f'{mounts} && exec "$0" -c "$1"',
            str(python),
            PROBE,
        ],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
        cwd=root,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_read_only_install_and_home_cache_in_a_private_temp_folder(installed):
    root, python = installed
    tmpdir = root / "tmp-writable"
    tmpdir.mkdir()
    first = _run_read_only(root, python, tmpdir, tmp_ro=False)
    assert first["file"].startswith(str(site_packages(python)))  # the wheel's copy
    assert first["result"] == [0.0, 1.0, 0.0, 0.0]
    assert len(first["warnings"]) == 1, first["warnings"]
    (message,) = first["warnings"]
    assert message.startswith("NumbaCacheWarning")
    assert "NUMBA_CACHE_DIR" in message and str(site_packages(python)) in message
    cache = tmpdir / f"rbm_nb-numba-cache-{os.getuid()}"
    assert first["cache_dir"] == str(cache)
    assert list(cache.rglob("*.nbi")), "numba wrote no index into the fallback folder"
    assert not (cache.stat().st_mode & 0o077), "the cache folder must be private"
    # a second process finds the same folder (loads instead of compiling)
    second = _run_read_only(root, python, tmpdir, tmp_ro=False)
    assert second["cache_dir"] == str(cache) and len(second["warnings"]) == 1


def test_nothing_writable_means_no_caching_and_one_warning(installed):
    root, python = installed
    tmpdir = root / "tmp-read-only"
    tmpdir.mkdir()
    result = _run_read_only(root, python, tmpdir, tmp_ro=True)
    assert result["result"] == [0.0, 1.0, 0.0, 0.0]
    assert len(result["warnings"]) == 1, result["warnings"]
    assert "caching is off" in result["warnings"][0]
    assert result["cache_dir"] is None


def test_writable_install_keeps_numba_default(tmp_path):
    """In-process: nothing to do when the kernels' own __pycache__ is writable."""
    from rbm_nb._infra import numba_cache as _numba_cache

    if not _numba_cache._writable(_numba_cache.KERNELS / "__pycache__"):
        pytest.skip("this checkout's rbm_nb/_kernels is not writable")
    code = (
        "import os, warnings; warnings.simplefilter('error');"
        "import rbm_nb._kernels; print(os.environ.get('NUMBA_CACHE_DIR'))"
    )
    env = clean_env(PYTHONPATH=str(Path(_numba_cache.__file__).parents[1]))
    out = run([sys.executable, "-c", code], timeout=120, env=env).stdout.strip()
    assert out == "None"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _numba_cache.configure()  # idempotent, silent
