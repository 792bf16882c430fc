"""Build rbm_nb's wheel and sdist, make throw-away virtual environments, seed caches."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from collections.abc import Sequence
from pathlib import Path

from conftest import REPO

# what would make a fresh environment see this one (or this clone)
LEAKY_ENV = ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "CONDA_PREFIX")


def clean_env(**extra: str) -> dict[str, str]:
    """This process's environment without what points into this venv or clone."""
    env = {k: v for k, v in os.environ.items() if k not in LEAKY_ENV}
    env.pop("NUMBA_CACHE_DIR", None)
    env.update(extra)
    return env


def uv() -> str:
    """The uv executable installed beside this interpreter (the dev extra)."""
    found = shutil.which("uv", path=str(Path(sys.executable).parent))
    if found is None:
        raise RuntimeError("uv is not installed in this environment: pip install uv")
    return found


def run(cmd: list[str], *, timeout: float, **kwargs) -> subprocess.CompletedProcess:
    """Run ``cmd``; on failure raise with the tail of its output."""
    result = subprocess.run(
        cmd, capture_output=True, text=True, timeout=timeout, **kwargs
    )
    if result.returncode != 0:
        raise AssertionError(
            f"{' '.join(map(str, cmd))} failed ({result.returncode}):\n"
            f"{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
        )
    return result


def build_dists(out: Path, prefix: Sequence[str] = ()) -> tuple[Path, Path]:
    """``python -m build`` (isolated, uv as installer): the wheel and the sdist.

    ``prefix``: a command to run it under (head_start.low_priority)."""
    build = [sys.executable, "-m", "build", "--installer", "uv", "-o", str(out)]
    run(
        [*prefix, *build, str(REPO)],
        timeout=600,
        env=clean_env(
            PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"
        ),
    )
    (wheel,) = out.glob("rbm_nb-*.whl")
    (sdist,) = out.glob("rbm_nb-*.tar.gz")
    return wheel, sdist


def make_venv(path: Path, *, see_this_env: bool) -> Path:
    """A new venv at ``path`` (made by uv); return its python.

    With ``see_this_env`` the packages of the running environment are on its
    path *after* its own site-packages (a ``.pth`` line), so installing rbm_nb
    with ``--no-deps`` gives an environment that imports the installed rbm_nb
    but needs no download. The running environment's own ``.pth`` files (its
    editable rbm_nb) are not processed there.
    """
    run([uv(), "venv", "-q", "--python", sys.executable, str(path)], timeout=120)
    python = path / "bin" / "python"
    if see_this_env:
        site = run(
            [
                str(python),
                "-c",
                "import sysconfig; print(sysconfig.get_path('purelib'))",
            ],
            timeout=60,
        ).stdout.strip()
        (Path(site) / "_rbm_nb_test_parent_env.pth").write_text(
            sysconfig.get_path("purelib") + "\n"
        )
    return python


def site_packages(python: Path) -> Path:
    """The purelib folder of the environment of ``python``."""
    out = run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
        timeout=60,
    )
    return Path(out.stdout.strip())


def seed_numba_cache(tree: Path) -> int:
    """Copy this checkout's compiled kernels into the rbm_nb source tree ``tree``.

    For a copy of these sources (an unpacked sdist, the Binder simulation's
    copy of the working tree) whose warm-up would otherwise compile every
    kernel again: minutes that test nothing the set-up's own warm-up did not.
    numba keys each cached kernel on its source file's size and modification
    time (``shutil.copy2`` and tar keep both), and rbm_nb's stamp file (the
    fingerprint of all kernel sources, ``rbm_nb._infra.numba_cache``) comes along:
    if any source differed, the first import would drop every copied file
    and the warm-up compile as usual. Returns the number of cache files
    copied (0 when this checkout caches elsewhere, under NUMBA_CACHE_DIR).
    """
    import rbm_nb

    ours = Path(rbm_nb.__file__).parent / "_kernels" / "__pycache__"
    theirs = tree / "rbm_nb" / "_kernels" / "__pycache__"
    files = sorted(ours.glob("*.nb[ci]"))
    if not files or not (ours / "rbm_nb-kernels.sha256").is_file():
        return 0
    theirs.mkdir(exist_ok=True)
    for f in [*files, ours / "rbm_nb-kernels.sha256"]:
        shutil.copy2(f, theirs / f.name)
    return len(files)
