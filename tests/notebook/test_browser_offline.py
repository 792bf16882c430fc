"""A notebook's saved HTML works without a kernel or a network.

Notebook 01 is executed (its widget state saved, as JupyterLab's "save
widget state" does), exported by nbconvert with the docs' own widget manager
(``docs/_static/widgets``, built by ``js/embed/build.mjs``) in place of the
CDN, and opened from disk in chromium with every other request refused.
Moving the yaw slider must turn the observer's triad in the 3D view and
print the body's coordinates in the observer's axes, computed in the page;
dragging the transform gizmo (three.js's TransformControls on meshcat's
three.js) must move the triad and set the sliders.
"""

from __future__ import annotations

import shutil

import pytest
from conftest import REPO

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(300)]

WIDGETS = REPO / "docs" / "_static" / "widgets"
TRIAD = "/rbm/root/sliders_observer/pose"
NODE_MATRIX_JS = """(path) => {
  const view = document.querySelector('.rbm-scene').rbmView;
  return view.viewer.scene_tree.find(path.split('/').filter((p) => p)).object.matrix.toArray();
}"""


@pytest.fixture(scope="module")
def saved_01(tmp_path_factory, executed_notebook):
    # notebook 01 as test_notebooks.py executed it (once per session), without
    # the kernel listing cell tests/notebook_runs.py appends
    notebook = executed_notebook("01_reference_frames.ipynb")
    notebook.cells.pop()
    return _saved_html(notebook, tmp_path_factory.mktemp("saved01"))


def _saved_html(notebook, tmp_path):
    from nbconvert import HTMLExporter

    assert notebook.metadata["widgets"]["application/vnd.jupyter.widget-state+json"]
    exporter = HTMLExporter(
        template_name="lab",
        widget_renderer_url="widgets/embed.js",
        require_js_url="widgets/embed.js",  # the bundle needs no require.js
    )
    body, _ = exporter.from_notebook_node(notebook)
    shutil.copytree(WIDGETS, tmp_path / "widgets")
    page = tmp_path / "01_reference_frames.html"
    page.write_text(body, encoding="utf-8")
    return page


def test_the_slider_turns_the_frame_in_saved_html(saved_01):
    from browser_support import ARTIFACTS
    from offline_pages import offline_page, wait_for_scene

    page_file = saved_01
    ARTIFACTS.mkdir(exist_ok=True)
    with offline_page(page_file) as (page, refused, errors):
        wait_for_scene(page)
        sliders = page.locator(".rbm-sliders").first
        sliders.scroll_into_view_if_needed()
        before = page.evaluate(NODE_MATRIX_JS, TRIAD)
        page.screenshot(path=str(ARTIFACTS / "saved-01-sliders-before.png"))
        yaw = sliders.locator("input.rbm-slider-yaw")
        yaw.evaluate(
            "(el) => { el.value = '180'; el.dispatchEvent(new Event('input')); }"
        )
        page.wait_for_timeout(500)
        after = page.evaluate(NODE_MATRIX_JS, TRIAD)
        page.screenshot(path=str(ARTIFACTS / "saved-01-sliders-yaw-180.png"))
        printed = sliders.locator(".rbm-local").inner_text()
    # yaw 90 -> 180: the observer's x axis turns from world +y to world -x
    assert before[0:3] == pytest.approx([0, 1, 0], abs=1e-6)
    assert after[0:3] == pytest.approx([-1, 0, 0], abs=1e-6)
    assert after[12:15] == pytest.approx([5, 0, 0])
    # the body (2, 0, 0) is now 3 m straight ahead of the observer
    assert "(3.000, 0.000, 0.000)" in printed, printed
    assert not errors, errors
    assert not [u for u in refused if "widget" in u or "require" in u], refused


ORIGIN_ON_SCREEN_JS = """(path) => {
  const view = document.querySelector('.rbm-scene').rbmView;
  const object = view.viewer.scene_tree.find(path.split('/').filter((p) => p)).object;
  const p = new globalThis.MeshCat.THREE.Vector3();
  object.getWorldPosition(p);
  p.project(view.viewer.camera);
  const r = view.viewer.renderer.domElement.getBoundingClientRect();
  return [r.left + ((p.x + 1) / 2) * r.width, r.top + ((1 - p.y) / 2) * r.height];
}"""


def test_dragging_the_gizmo_moves_the_frame_in_saved_html(saved_01):
    from browser_support import ARTIFACTS
    from offline_pages import offline_page, wait_for_scene

    with offline_page(saved_01) as (page, refused, errors):
        wait_for_scene(page)
        sliders = page.locator(".rbm-sliders").first
        page.locator(".rbm-scene").first.scroll_into_view_if_needed()
        page.wait_for_timeout(500)
        grab = sliders.locator("button.rbm-grab")
        assert grab.inner_text() == "grab in 3D: off"
        grab.click()
        grab.click()
        assert grab.inner_text() == "grab in 3D: move"
        page.wait_for_timeout(300)
        x, y = page.evaluate(ORIGIN_ON_SCREEN_JS, TRIAD)
        # the gizmo's centre handle drags the frame in the plane of the screen
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x - 40, y + 10, steps=8)
        page.mouse.move(x - 80, y + 20, steps=8)
        page.mouse.up()
        page.wait_for_timeout(500)
        moved = [
            float(sliders.locator(f"input.rbm-slider-{n}").input_value()) for n in "xyz"
        ]
        matrix = page.evaluate(NODE_MATRIX_JS, TRIAD)
        printed = sliders.locator(".rbm-local").inner_text()
        page.screenshot(path=str(ARTIFACTS / "saved-01-gizmo-moved.png"))
    assert moved != pytest.approx([5, 0, 0], abs=0.05), (
        "the drag did not move the frame"
    )
    # the sliders show the pose the triad has (sliders round to their steps)
    assert matrix[12:15] == pytest.approx(moved, abs=0.03)
    assert matrix[0:3] == pytest.approx([0, 1, 0], abs=1e-6)  # moved, not turned
    assert "in observer's axes" in printed
    assert not errors, errors
