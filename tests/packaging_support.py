"""Build rbm_nb's wheel and sdist and make throw-away virtual environments."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
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


def build_dists(out: Path) -> tuple[Path, Path]:
    """``python -m build`` (isolated, uv as installer): the wheel and the sdist."""
    run(
        [sys.executable, "-m", "build", "--installer", "uv", "-o", str(out), str(REPO)],
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
