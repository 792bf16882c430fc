"""FrameSliders with a kernel, in JupyterLab and Notebook 7.

Moving the yaw slider in the browser turns the observer's triad in the 3D
view at once (browser side), and the kernel re-registers the observer and
answers with its lookup (the printout and a later cell agree).
"""

from __future__ import annotations

import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(300)]

from browser_support import (  # noqa: E402
    ARTIFACTS,
    new_context,
    open_notebook,
    our_errors,
    output_text,
    run_cell,
    save,
    wait_done,
    write_notebook,
)

CELLS = [
    """import numpy as np
import rbm_nb as rbm
from rbm_nb.widgets import FrameSliders
rbm.clear_registry()
rbm.register_frame("world")
scene = rbm.scene.Scene("world")
scene.add_frame("world", scale=1.5)
scene.add_points([2.0, 0.0, 0.0], color="#ffff00", size=0.15)
def body():
    p = rbm.transform_points((2.0, 0.0, 0.0), outof="world", into="observer")
    return f"kernel: {(np.round(p, 3) + 0.0).tolist()}"
sliders = FrameSliders("observer", "world", translation=(5, 0, 0), angles=(90, 0, 0),
                       scene=scene, report=body, point=(2.0, 0.0, 0.0), reach=6.0)
sliders""",
    """print("LOOKUP", (np.round(rbm.transform_points((2.0, 0, 0), outof="world",
      into="observer"), 3) + 0.0).tolist(), sliders.values["yaw"])""",
]
TRIAD_X_JS = """() => {
  const view = document.querySelector('.rbm-scene').rbmView;
  const m = view.viewer.scene_tree.find(['rbm', 'root', 'sliders_observer', 'pose']).object.matrix;
  return m.toArray().slice(0, 3);
}"""


@pytest.mark.parametrize("app", ["lab", "notebook"])
def test_sliders_turn_the_frame_and_the_kernel_follows(
    app, browser, jupyter_server, tmp_path
):
    server = jupyter_server(app)
    name = server.add_notebook(write_notebook(tmp_path / "sliders.ipynb", CELLS))
    context, blocked = new_context(
        browser, server, viewport={"width": 1200, "height": 1300}
    )
    page = context.new_page()
    try:
        open_notebook(page, server, name)
        run_cell(page, 0)
        wait_done(page, 0)
        page.wait_for_selector(".rbm-sliders .rbm-report", timeout=60000)
        page.wait_for_function(
            "() => { const e = document.querySelector('.rbm-report'); "
            "return e && e.innerText.includes('kernel: [0.0, 3.0, 0.0]'); }",
            timeout=60000,
        )
        page.wait_for_function(
            "() => { const s = document.querySelector('.rbm-scene'); "
            "return s && s.rbmView && s.rbmView.store.commands.length > 0; }",
            timeout=60000,
        )
        assert page.evaluate(TRIAD_X_JS) == pytest.approx([0, 1, 0], abs=1e-6)
        # the pages' longer wait for anywidget's models applied (conftest.py's
        # browser fixture): one per model of the scene and the sliders
        assert page.evaluate("window.rbmAnywidgetTimeouts") >= 2
        ARTIFACTS.mkdir(exist_ok=True)
        save(f"sliders-{app}-yaw-90.png", page.screenshot())
        page.locator("input.rbm-slider-yaw").evaluate(
            "(el) => { el.value = '180'; el.dispatchEvent(new Event('input')); }"
        )
        # the browser turns the triad itself (its matrix follows at the next
        # frame the view draws) ...
        page.wait_for_function(
            f"() => Math.abs(({TRIAD_X_JS})()[0] + 1) < 1e-6", timeout=10000
        )
        # ... and the kernel answers for the new pose
        page.wait_for_function(
            "() => document.querySelector('.rbm-report').innerText.includes('kernel: [3.0, 0.0, 0.0]')",
            timeout=60000,
        )
        assert page.evaluate(TRIAD_X_JS) == pytest.approx([-1, 0, 0], abs=1e-6)
        save(f"sliders-{app}-yaw-180.png", page.screenshot())
        run_cell(page, 1)
        wait_done(page, 1)
        assert "LOOKUP [3.0, 0.0, 0.0] 180.0" in output_text(page, 1)
        ours = our_errors(page.errors, server)
        assert not ours, ours
        assert not blocked, blocked
    finally:
        context.close()
