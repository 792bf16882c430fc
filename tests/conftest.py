"""Shared fixtures: every test starts and ends with an empty frame registry."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(autouse=True)
def _empty_registry():
    """Clear the frame registry around each test (only if frames are loaded)."""
    frames = sys.modules.get("rbm_nb.frames")
    if frames is not None:
        frames.clear_registry()
    yield
    frames = sys.modules.get("rbm_nb.frames")
    if frames is not None:
        frames.clear_registry()


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The real recordings beside the repo (``../shared/data``)."""
    if not SHARED_DATA.is_dir():
        pytest.fail(f"{SHARED_DATA} is missing: CI must have ../shared beside the clone")
    return SHARED_DATA
