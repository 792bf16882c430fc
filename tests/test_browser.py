"""The notebook layer in a real browser: Debian's chromium through playwright.

(a) a ``to_html`` export plays offline; the live viewer page follows the
kernel; (b) JupyterLab runs ``tests/notebooks/live_scene.ipynb``: the tree
lists the frames, Play advances the time, the meshcat view renders; (c) the
viewer works through jupyter-server-proxy under a base URL prefix.

Screenshots go to ``test-artifacts/`` at the repository root. Every process
started here (chromium, JupyterLab and its kernels) is stopped by the fixture
that started it, also when a test fails.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rbm_nb as rbm

# JupyterLab and chromium start in the fixtures (about 30 s here)
pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(300)]

from browser_support import (  # noqa: E402
    JupyterLab,
    changed_pixels,
    magenta_pixels,
    png_pixels,
    save,
)

NOTEBOOK = Path(__file__).resolve().parent / "notebooks" / "live_scene.ipynb"
BASE_URL = "/rbm-test/"  # a path prefix like JupyterHub's /user/<name>/


@pytest.fixture(autouse=True)
def fresh_viewer_server():
    yield
    from rbm_nb.scene import shutdown_server

    shutdown_server()


def circling_scene(name: str | None = None):
    """world -> body circling the origin (10 s per turn) -> eye; path in magenta."""
    from rbm_nb.scene import Scene

    rbm.register_frame("world")
    t = np.arange(0, 10.0, 0.02)
    angle = 2 * np.pi * t / 10
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=t,
        translation=np.c_[2 * np.cos(angle), 2 * np.sin(angle), 0.5 + 0 * t],
        rotation=np.c_[np.cos(angle / 2), 0 * t, 0 * t, np.sin(angle / 2)],
    )
    rbm.register_frame("eye", parent="body", translation=(0.1, 0.0, 0.2))
    scene = Scene("world", name=name)
    scene.add_frame("world", scale=1.0)
    scene.add_frame("body", scale=0.6)
    scene.add_path("body", color="#ff00ff")
    scene.add_vectors("eye", (1, 0, 0), length=2.0, color="#ffff00")
    scene.add_mesh("body", "box", size=(0.4, 0.25, 0.15), color="#00e0e0")
    return scene


# -- (a) export and live page without Jupyter ------------------------------------------
def test_export_plays_offline_and_moves(page, tmp_path):
    scene = circling_scene()
    out = scene.to_html(tmp_path / "scene.html")
    scene.close()
    requests = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(out.as_uri())
    page.wait_for_function("window.rbmExport !== undefined", timeout=60000)
    page.evaluate("rbmExport.pause(); rbmExport.seek(0)")
    page.wait_for_timeout(300)
    canvas = page.locator("#meshcat-pane canvas")
    first = canvas.screenshot()
    page.evaluate("rbmExport.seek(2.5)")
    page.wait_for_timeout(300)
    later = canvas.screenshot()
    assert page.inner_text("#rbm-time") == "2.500 s"
    save("export_t0.png", first)
    save("export_t2.5.png", page.screenshot())
    a, b = png_pixels(first), png_pixels(later)
    assert magenta_pixels(a) > 200  # the path is drawn
    assert changed_pixels(a, b) > 100  # the body moved
    page.click("#rbm-play")
    page.wait_for_function("rbmExport.time() > 2.6", timeout=30000)
    assert [
        u for u in requests if not u.startswith("file://")
    ] == []  # offline: nothing fetched
    assert page.errors == []


def test_export_of_static_and_datetime_scenes(page, tmp_path):
    from rbm_nb.scene import Scene

    rbm.register_frame("world")
    rbm.register_frame("observer", parent="world", translation=(1, 1, 0))
    with Scene("world") as scene:
        scene.add_frame("observer", scale=1.0)
        scene.add_mesh("world", "sphere", size=0.3, color="#ff00ff")
        static = scene.to_html(tmp_path / "static.html")
    page.goto(static.as_uri())
    page.wait_for_function("window.rbmExport !== undefined", timeout=60000)
    page.wait_for_timeout(300)
    assert page.evaluate("rbmExport.duration") == 0
    assert (
        magenta_pixels(png_pixels(page.locator("#meshcat-pane canvas").screenshot()))
        > 200
    )

    ts = np.datetime64("2020-02-02T00:27:14") + np.arange(50) * np.timedelta64(
        100, "ms"
    )
    rbm.register_frame(
        "head", parent="world", timestamps=ts, translation=np.zeros((50, 3))
    )
    with Scene("world") as scene:
        scene.add_frame("head")
        dated = scene.to_html(tmp_path / "dated.html")
    page.goto(dated.as_uri())
    page.wait_for_function("window.rbmExport !== undefined", timeout=60000)
    page.evaluate("rbmExport.pause(); rbmExport.seek(1.5)")
    assert page.inner_text("#rbm-time") == "2020-02-02 00:27:15.500"
    assert page.errors == []


def test_live_viewer_page_follows_the_kernel(page):
    scene = circling_scene()
    page.goto(scene.url)
    page.wait_for_function(
        "window.rbmViewerStats && window.rbmViewerStats.messages > 5", timeout=60000
    )
    page.wait_for_timeout(300)
    canvas = page.locator("#meshcat-pane canvas")
    before = png_pixels(canvas.screenshot())
    count = page.evaluate("rbmViewerStats.messages")
    scene.set_time(5.0)
    page.wait_for_function(f"rbmViewerStats.messages > {count}", timeout=30000)
    page.wait_for_timeout(300)
    shot = canvas.screenshot()
    save("live_viewer.png", page.screenshot())
    after = png_pixels(shot)
    assert magenta_pixels(after) > 200
    assert changed_pixels(before, after) > 100
    assert page.inner_text("#rbm-status") == "live"
    scene.close()
    page.wait_for_function(
        "document.getElementById('rbm-status').textContent === 'scene closed'",
        timeout=30000,
    )
    assert page.errors == []


# -- (b), (c) JupyterLab and jupyter-server-proxy ----------------------------------------
@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    server = JupyterLab(tmp_path_factory.mktemp("jupyterlab"), [NOTEBOOK], BASE_URL)
    try:
        yield server
    finally:
        server.stop()
        assert server.process.poll() is not None


@pytest.fixture(scope="module")
def lab_page(browser, lab):
    """The test notebook, opened and run in JupyterLab (shared by (b) and (c))."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    context = browser.new_context(viewport={"width": 1280, "height": 1600})
    page = context.new_page()
    try:
        page.goto(lab.url(f"lab/tree/{NOTEBOOK.name}"), timeout=120000)
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=120000)
        select_kernel = page.locator(".jp-Dialog").get_by_role(
            "button", name="Select", exact=True
        )
        try:  # JupyterLab may ask which kernel to start
            select_kernel.click(timeout=20000)
        except PlaywrightTimeout:
            pass
        page.wait_for_selector(
            ".jp-Notebook-ExecutionIndicator[data-status='idle']", timeout=120000
        )
        page.get_by_role("menuitem", name="Run", exact=True).click()
        page.get_by_text("Run All Cells", exact=True).click()
        page.locator(".jp-OutputArea-output", has_text="RBM_VIEWER_PORT").wait_for(
            timeout=180000
        )
        yield page
    except Exception:
        save("jupyterlab_failure.png", page.screenshot(full_page=True))
        print(lab.log_text())
        raise
    finally:
        context.close()


def test_jupyterlab_tree_player_and_live_view(lab_page):
    page = lab_page
    nodes = page.locator(".rbm-frame-node")
    nodes.first.wait_for(timeout=60000)
    assert nodes.all_inner_texts() == ["world", "body", "eye"]
    page.locator(".rbm-frame-node", has_text="body").click()
    page.wait_for_selector(".rbm-frame-details >> text=parent: world", timeout=30000)

    readout = page.locator(".rbm-player-readout")
    start = readout.inner_text()
    assert start.startswith("0 / 1499")
    view = page.frame_locator("iframe[title^='rbm_nb scene']").first
    canvas = view.locator("#meshcat-pane canvas")
    canvas.wait_for(timeout=60000)
    frame = page.frame(
        url=lambda u: (
            u.startswith("http://127.0.0.1:") and "/proxy/" not in u and "/nbtest/" in u
        )
    )
    frame.wait_for_function(
        "window.rbmViewerStats && window.rbmViewerStats.messages > 5", timeout=60000
    )
    page.wait_for_timeout(500)
    before = png_pixels(canvas.screenshot())

    page.locator("button[title='Play / pause']").click()
    page.wait_for_function(
        "document.querySelector('.rbm-player-readout').textContent.split(' ')[0] > 10",
        timeout=60000,
    )
    page.wait_for_timeout(1000)
    page.locator("button[title='Play / pause']").click()
    assert readout.inner_text() != start
    page.wait_for_timeout(500)
    shot = canvas.screenshot()
    save("jupyterlab_live_view.png", shot)
    save("jupyterlab_notebook.png", page.screenshot(full_page=True))
    after = png_pixels(shot)
    assert magenta_pixels(after) > 200  # the path in the live view
    assert changed_pixels(before, after) > 100  # playing moved the body
    # the tree's pose follows the player's time
    assert "at 0.000 s" not in page.locator(".rbm-frame-details").inner_text()


def test_notebook_view_through_jupyter_server_proxy(lab_page, lab):
    """``scene.show(proxy=True)``: the iframe loads <base_url>proxy/<port>/<scene>/."""
    page = lab_page
    frame = page.frame(url=lambda u: f"{BASE_URL}proxy/" in u and "/nbtest/" in u)
    assert frame is not None, [f.url for f in page.frames]
    assert frame.url.startswith(f"http://127.0.0.1:{lab.port}{BASE_URL}proxy/")
    frame.wait_for_function(
        "window.rbmViewerStats && window.rbmViewerStats.messages > 5", timeout=60000
    )
    canvas = (
        page.frame_locator("iframe[title^='rbm_nb scene']")
        .nth(1)
        .locator("#meshcat-pane canvas")
    )
    page.wait_for_timeout(500)
    shot = canvas.screenshot()
    save("jupyterlab_proxied_view.png", shot)
    assert magenta_pixels(png_pixels(shot)) > 100


def test_viewer_through_jupyter_server_proxy(lab_page, lab, browser):
    text = lab_page.locator(
        ".jp-OutputArea-output", has_text="RBM_VIEWER_PORT"
    ).inner_text()
    port = int(text.split()[-1])
    context = browser.new_context(viewport={"width": 900, "height": 700})
    try:
        page = context.new_page()
        page.goto(lab.url(f"proxy/{port}/nbtest/"), timeout=60000)
        page.wait_for_function(
            "window.rbmViewerStats && window.rbmViewerStats.messages > 5", timeout=60000
        )
        url = page.evaluate("rbmViewerStats.url")
        assert url == f"ws://127.0.0.1:{lab.port}{BASE_URL}proxy/{port}/nbtest/ws"
        page.wait_for_timeout(500)
        shot = page.locator("#meshcat-pane canvas").screenshot()
        save("proxied_viewer.png", page.screenshot())
        assert magenta_pixels(png_pixels(shot)) > 200
        # updates from the kernel arrive through the proxy too
        count = page.evaluate("rbmViewerStats.messages")
        lab_page.locator("button[title='Play / pause']").click()
        page.wait_for_function(f"rbmViewerStats.messages > {count}", timeout=60000)
        lab_page.locator("button[title='Play / pause']").click()
    finally:
        context.close()
