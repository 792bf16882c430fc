"""The documentation site builds with warnings as errors.

The notebooks are executed by myst-nb; jupyter-cache (``docs/_build/.jupyter_cache``)
keeps their outputs until a notebook changes, so a rebuild re-executes only
what changed (first build here: about 2 minutes, a rebuild: about 15 s).
"""

from __future__ import annotations

import pytest
from conftest import REPO

pytestmark = [pytest.mark.slow, pytest.mark.timeout(1200)]


def test_sphinx_builds_with_warnings_as_errors(docs_build):
    # (the build started with the first project test: tests/docs_build.py)
    returncode, output = docs_build.wait(timeout=1100)
    assert returncode == 0, output[-5000:]
    out = docs_build.out
    # the API reference is generated from the docstrings
    api = (out / "generated" / "rbm_nb.html").read_text()
    assert "transform_points" in api and "Parameters" in api
    assert (out / "generated" / "rbm_nb.ros.html").is_file()
    # every notebook is rendered with the outputs of its execution
    for notebook in sorted((REPO / "notebooks").glob("*.ipynb")):
        page = (out / "notebooks" / notebook.with_suffix(".html").name).read_text()
        assert "cell_output" in page, f"{notebook.name} rendered without outputs"
