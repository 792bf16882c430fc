"""Shared fixtures: every test starts and ends with an empty frame registry."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


def _import_oracle_first() -> None:
    """Import the test-only oracle up front, then make ``DataArray.rbm`` ours again.

    rigid-body-motion registers an xarray accessor under the same name as ours
    when it is imported, and whichever registers last wins. Importing it once
    here, before any test, and re-registering ours afterwards means the oracle
    can be imported anywhere in the tests without hijacking ``da.rbm``.
    """
    try:
        import rigid_body_motion  # noqa: F401
    except ImportError:  # the oracle is a dev extra; tests that need it say so
        return
    import warnings

    import xarray as xr

    with warnings.catch_warnings():
        # importing rbm_nb registers ours over the oracle's: expected here
        warnings.simplefilter("ignore")
        from rbm_nb.accessors import DataArrayAccessor

        xr.register_dataarray_accessor("rbm")(DataArrayAccessor)


_import_oracle_first()


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
        pytest.fail(
            f"{SHARED_DATA} is missing: CI must have ../shared beside the clone"
        )
    return SHARED_DATA


@pytest.fixture(scope="module")
def browser():
    """Debian's chromium driven by playwright (never a downloaded browser)."""
    from browser_support import CHROMIUM, CHROMIUM_ARGS

    if not Path(CHROMIUM).exists():
        pytest.fail(
            f"{CHROMIUM} is missing: install Debian's chromium (bash .ci/setup.sh test)"
        )
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        chromium = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield chromium
        finally:
            chromium.close()


@pytest.fixture
def page(browser):
    """A fresh page; its JavaScript errors are collected in ``page.errors``."""
    context = browser.new_context(viewport={"width": 1100, "height": 900})
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda err: page.errors.append(str(err)))
    try:
        yield page
    finally:
        context.close()
