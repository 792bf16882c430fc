"""The one build step pyproject.toml cannot express: notebooks inside the wheel.

``rbm-nb demo`` opens ``notebooks/06_head_eye_explorer.ipynb``. A clone has the
folder; an installed wheel has only the package, so the notebooks are copied
into ``rbm_nb/_notebooks/`` of the build (never into the source tree, so there
is one copy to edit). Editable installs skip this: the demo uses the clone's
folder.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

NOTEBOOKS = Path(__file__).resolve().parent / "notebooks"


class BuildPyWithNotebooks(build_py):
    def run(self):
        super().run()
        if self.editable_mode:
            return
        notebooks = sorted(NOTEBOOKS.glob("*.ipynb"))
        if not notebooks:  # a wheel without them would fail only at `rbm-nb demo`
            raise RuntimeError(f"no notebooks in {NOTEBOOKS}: the sdist must ship them")
        target = Path(self.build_lib) / "rbm_nb" / "_notebooks"
        self.mkpath(str(target))
        for src in notebooks:
            self.copy_file(str(src), str(target / src.name))


setup(cmdclass={"build_py": BuildPyWithNotebooks})
