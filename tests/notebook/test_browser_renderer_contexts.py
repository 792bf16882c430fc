"""The 3D view holds one WebGL context, and lets it go when closed (JupyterLab and Notebook 7).

A WebGL context keeps its drawing buffers (with antialiasing, one per
sample) in the renderer or GPU process until it is lost or garbage
collected. The page's ``getContext`` is wrapped to remember every WebGL
context made; while the explorer's 3D view of the real recording (the
synthetic one without ``RBM_NB_DATA_DIR``) is shown, exactly one is live
(not lost), and closing the widget from the kernel releases it. Under
software WebGL (this chromium) that context is not antialiased. The memory
figures are in ``benchmarks/bench_renderer_memory.py``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(600)]

from browser_support import (  # noqa: E402
    REPO,
    new_context,
    open_notebook,
    run_until,
    save,
    write_notebook,
)

REAL_DATA = (
    Path(os.environ.get("RBM_NB_SHARED", REPO.parent / "shared")) / "data" / "rbm-data"
)

SHOW = """
from rbm_nb import explorer
head, left, right, note = explorer.load_head_eye()
explorer.register_head_eye_frames(head, left, right)
scene = explorer.explorer_scene()
print("SCENE-READY")
scene.widget
"""
CLOSE = """
scene.widget.close()
print("SCENE-CLOSED")
"""

# every WebGL context the page makes, and how many are not lost
COUNT_CONTEXTS = """(() => {
  const made = [];
  const original = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
    const context = original.call(this, kind, ...rest);
    if (context && /webgl/.test(String(kind)) && !made.includes(context)) made.push(context);
    return context;
  };
  window.rbmWebGL = () => ({made: made.length,
                            live: made.filter((gl) => !gl.isContextLost()).length});
})();"""


@pytest.mark.parametrize("app", ["lab", "notebook"])
def test_the_3d_view_holds_one_webgl_context_and_releases_it(
    app, browser, jupyter_server, tmp_path
):
    server = jupyter_server(app)
    env = {"RBM_NB_DATA_DIR": str(REAL_DATA)} if REAL_DATA.is_dir() else {}
    name = server.add_notebook(
        write_notebook(
            tmp_path / "contexts.ipynb", [SHOW, CLOSE], server.kernel_with_env(env)
        )
    )
    context, blocked = new_context(
        browser, server, viewport={"width": 1200, "height": 900}
    )
    context.add_init_script(COUNT_CONTEXTS)
    page = context.new_page()
    try:
        open_notebook(page, server, name)
        assert page.evaluate("window.rbmWebGL()")["made"] == 0
        run_until(page, 0, "SCENE-READY")
        page.wait_for_function(
            """() => { const el = document.querySelector('.rbm-scene');
                       return el && el.rbmView && el.rbmView.frames > 0
                              && el.querySelectorAll('.rbm-label').length > 0; }""",
            timeout=120000,
        )
        shown = page.evaluate("window.rbmWebGL()")
        view = page.evaluate(
            """(() => { const v = document.querySelector('.rbm-scene').rbmView;
                 const gl = v.viewer.renderer.getContext();
                 const info = gl.getExtension('WEBGL_debug_renderer_info');
                 return {antialias: gl.getContextAttributes().antialias,
                         software: /swiftshader|llvmpipe|software/i.test(
                           info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : ''),
                         canvases: v.pane.querySelectorAll('canvas').length}; })()"""
        )
        save(f"renderer_contexts_{app}.png", page.locator(".rbm-scene").screenshot())
        # one live context for the one 3D view, drawn into the view's one canvas
        assert shown["live"] == 1, shown
        assert view["canvases"] == 1, view
        if view["software"]:
            assert view["antialias"] is False, view
        run_until(page, 1, "SCENE-CLOSED")
        page.wait_for_function(
            "() => document.querySelector('.rbm-scene') === null", timeout=60000
        )
        closed = page.evaluate("window.rbmWebGL()")
        assert closed["live"] == 0, closed
        assert blocked == [], blocked
    except Exception:
        save(f"renderer_contexts_{app}_failure.png", page.screenshot(full_page=True))
        print(server.log_text())
        raise
    finally:
        context.close()
