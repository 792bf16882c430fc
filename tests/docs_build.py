"""The documentation build as a background process (tests/project/test_docs.py).

Sphinx and the notebooks myst-nb executes keep one core busy for one and a
half to two minutes; the Binder simulation that comes first among the project
tests mostly waits on pip. Started with the first project test, the build
runs beside it, and the docs test only collects its result.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from conftest import REPO

REAL_DATA = REPO.parent / "shared" / "data" / "rbm-data"


def real_data_env() -> dict[str, str]:
    """RBM_NB_DATA_DIR for the build: as set, else the real recording beside the clone.

    The site is built with the real recording wherever it can be had (CI has
    ../shared); each notebook page prints which one it used.
    """
    if os.environ.get("RBM_NB_DATA_DIR"):
        return {}
    if (REAL_DATA / "head.nc").is_file():
        return {"RBM_NB_DATA_DIR": str(REAL_DATA)}
    return {}


class DocsBuild:
    """``sphinx -W -b html docs`` into ``folder / "html"``, started at once."""

    def __init__(self, folder: Path) -> None:
        self.out = folder / "html"
        self._log = folder / "sphinx.log"
        with open(self._log, "w") as log:
            self._process = subprocess.Popen(
                [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q",
                 "-b", "html", "-d", str(folder / "doctrees"),
                 str(REPO / "docs"), str(self.out)],
                stdout=log, stderr=subprocess.STDOUT, text=True,
                env={**os.environ, "MPLBACKEND": "Agg", **real_data_env()},
            )  # fmt: skip

    def wait(self, timeout: float) -> tuple[int, str]:
        """The build's exit code and its output (killed after ``timeout`` s)."""
        try:
            self._process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        return self._process.returncode, self._log.read_text()

    def stop(self) -> None:
        if self._process.poll() is None:
            self._process.kill()
        self._process.wait()
