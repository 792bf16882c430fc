"""Root of the test run: what the doctests in ``rbm_nb/`` need as well as ``tests/``.

pytest collects ``tests/`` and, with ``--doctest-modules``, the docstring
examples of every module in ``rbm_nb/`` (see ``[tool.pytest.ini_options]``).
A fixture in ``tests/conftest.py`` would not reach the doctests, so the one
that keeps examples from seeing each other's frames lives here.
"""

from __future__ import annotations

import sys

import pytest


@pytest.fixture(autouse=True)
def _empty_registry():
    """Clear the frame registry around each test and doctest (if frames are loaded)."""
    frames = sys.modules.get("rbm_nb.core.frames")
    if frames is not None:
        frames.clear_registry()
    yield
    frames = sys.modules.get("rbm_nb.core.frames")
    if frames is not None:
        frames.clear_registry()
