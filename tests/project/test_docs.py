"""The documentation site builds with warnings as errors.

The notebooks are executed by myst-nb; jupyter-cache (``docs/_build/.jupyter_cache``)
keeps their outputs until a notebook changes, so a rebuild re-executes only
what changed (first build here: about 2 minutes, a rebuild: about 15 s).
"""

from __future__ import annotations

import os

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
    # the pages built from the example recording say which one they used: the
    # real one whenever the build could have it
    from docs_build import real_data_env

    real = bool(real_data_env()) or bool(os.environ.get("RBM_NB_DATA_DIR"))
    for name, said in (
        ("04_xarray", "data source: real recording"),
        ("06_head_eye_explorer", "data: real head/eye recording"),
        ("09_velocity_tools_and_evaluation", "data: real recording"),
    ):
        page = (out / "notebooks" / f"{name}.html").read_text()
        if real:
            assert said in page, f"{name} was not built with the real recording"
        else:
            assert "synthetic" in page, (
                f"{name} does not say it used the synthetic data"
            )
    # the widget manager is the site's own, from no CDN
    page = (out / "notebooks" / "05_rosbag_and_3d.html").read_text()
    assert "_static/widgets/embed.js" in page
    assert "cdn.jsdelivr.net" not in page and "cdnjs.cloudflare.com" not in page


@pytest.mark.browser
def test_notebook_pages_play_offline(docs_build):
    """Pages 05 and 06 from disk, all network refused: the 3D view has its
    content (from the saved widget state) and moves when Play is pressed."""
    from browser_support import ARTIFACTS
    from offline_pages import SCENE_STATE_JS, offline_page, wait_for_scene

    returncode, output = docs_build.wait(timeout=1100)
    assert returncode == 0, output[-5000:]
    ARTIFACTS.mkdir(exist_ok=True)
    for name in ("05_rosbag_and_3d", "06_head_eye_explorer"):
        page_file = docs_build.out / "notebooks" / f"{name}.html"
        with offline_page(page_file) as (page, refused, errors):
            wait_for_scene(page)
            before = page.evaluate(SCENE_STATE_JS)
            scene = next(s for s in before if s and s["commands"])
            assert scene["tracks"] > 0, f"{name}: the 3D view has no moving objects"
            view = page.locator(".rbm-scene").first
            view.scroll_into_view_if_needed()
            page.screenshot(path=str(ARTIFACTS / f"docs-{name}-before-play.png"))
            play = page.locator(".rbm-player .rbm-play").first
            play.click()
            page.wait_for_timeout(2500)
            after = page.evaluate(SCENE_STATE_JS)
            page.screenshot(path=str(ARTIFACTS / f"docs-{name}-playing.png"))
            moved = [
                a["positions"] != b["positions"]
                for a, b in zip(before, after, strict=True)
                if a and a["tracks"]
            ]
            assert any(moved), f"{name}: Play did not move the 3D view's content"
            assert not errors, f"{name}: {errors}"
            assert not refused, f"{name} asked the network for {refused}"
