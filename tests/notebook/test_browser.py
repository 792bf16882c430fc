"""The notebook layer in a real browser: Debian's chromium through playwright.

(a) ``to_html`` exports play offline: the player's buttons, keyboard and
slider, the 3D view moving, clicking a frame selects it; (b) JupyterLab 4 and
Notebook 7, each without jupyter-server-proxy and with every request to
another port than Jupyter's blocked, run the head/eye explorer: the 3D view
renders, Play moves it, and it keeps moving while another cell sleeps; play,
pause, scrub and speed pressed while the kernel is busy act at once; the
kernel learns the time afterwards and opens no listening socket.

Screenshots go to ``test-artifacts/`` at the repository root. Every process
started here (chromium, the Jupyter server and its kernels) is stopped by the
test that started it, also when it fails.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import rbm_nb as rbm

# JupyterLab and chromium start in the fixtures (about 30 s here)
pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(300)]

from browser_support import (  # noqa: E402
    ARTIFACTS,
    MEASURE_JS,
    REPO,
    changed_pixels,
    listening_sockets,
    magenta_pixels,
    new_context,
    open_notebook,
    our_errors,
    output_text,
    png_pixels,
    prompt,
    run_cell,
    save,
    wait_done,
    write_notebook,
)

REAL_DATA = (
    Path(os.environ.get("RBM_NB_SHARED", REPO.parent / "shared")) / "data" / "rbm-data"
)


def circling_scene():
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
    scene = Scene("world")
    scene.add_frame("world", scale=1.0)
    scene.add_frame("body", scale=0.6)
    scene.add_path("body", color="#ff00ff")
    scene.add_vectors("eye", (1, 0, 0), length=2.0, color="#ffff00")
    scene.add_mesh("body", "box", size=(0.4, 0.25, 0.15), color="#00e0e0")
    return scene


def player_time(page) -> float:
    return page.evaluate(
        "document.querySelector('.rbm-scene').rbmView.player.get('time')"
    )


# -- (a) exports ------------------------------------------------------------------------
def test_export_plays_offline_and_moves(page, tmp_path):
    scene = circling_scene()
    out = scene.to_html(tmp_path / "scene.html")
    scene.close()
    requests = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(out.as_uri())
    page.wait_for_function("window.rbmExport && window.rbmExport.ready", timeout=60000)
    page.wait_for_timeout(500)
    canvas = page.locator(".rbm-scene canvas")
    first = canvas.screenshot()
    assert page.inner_text(".rbm-readout") == "0.000 s"
    page.click(".rbm-play")
    page.wait_for_function(
        "document.querySelector('.rbm-scene').rbmView.currentTime() > 2.5",
        timeout=30000,
    )
    page.click(".rbm-play")  # pause
    paused = player_time(page)
    page.wait_for_timeout(300)
    assert player_time(page) == paused
    later = canvas.screenshot()
    save("export_t0.png", first)
    save("export_playing.png", page.screenshot())
    a, b = png_pixels(first), png_pixels(later)
    assert magenta_pixels(a) > 200  # the path is drawn
    assert changed_pixels(a, b) > 100  # the body moved
    # keyboard: space plays/pauses, arrows skip 1 s, shift+arrows 10 s (here: to the end)
    player = page.locator(".rbm-player")
    player.focus()
    page.keyboard.press("ArrowRight")
    assert player_time(page) == pytest.approx(paused + 1.0)
    page.keyboard.press("Shift+ArrowLeft")
    assert player_time(page) == 0.0
    page.keyboard.press("Space")
    page.wait_for_function(
        "document.querySelector('.rbm-scene').rbmView.player.get('playing')",
        timeout=5000,
    )
    page.keyboard.press("Space")
    assert not page.evaluate(
        "document.querySelector('.rbm-scene').rbmView.player.get('playing')"
    )
    assert [
        u for u in requests if not u.startswith(("file://", "blob:", "data:"))
    ] == []
    assert page.errors == []


def test_clicking_a_frame_in_3d_selects_it(page, tmp_path):
    scene = circling_scene()
    out = scene.to_html(tmp_path / "scene.html")
    scene.close()
    page.goto(out.as_uri())
    page.wait_for_function("window.rbmExport && window.rbmExport.ready", timeout=60000)
    page.wait_for_timeout(500)
    where = page.evaluate(
        """() => { const v = document.querySelector('.rbm-scene').rbmView;
                   const box = v.pane.getBoundingClientRect();
                   const xy = v.screenPosition(v.model.get('_frames').body);
                   return [box.left + xy[0], box.top + xy[1]]; }"""
    )
    page.mouse.click(where[0] + 3, where[1] + 2)
    view = "document.querySelector('.rbm-scene').rbmView"
    assert page.evaluate(f"{view}.model.get('selected')") == "body"
    label = page.locator(".rbm-label.rbm-selected")
    assert label.inner_text() == "body"
    page.click(".rbm-follow")  # the camera follows the selected frame
    assert page.evaluate(f"{view}.model.get('follow')") == "body"
    page.click(".rbm-play")
    page.wait_for_timeout(1500)
    target = page.evaluate(
        f"""() => {{ const v = {view}; const p = v.viewer.camera.parent;
                   const w = v.worldPosition(v.model.get('_frames').body);
                   const local = p.worldToLocal(w.clone());
                   return local.distanceTo(v.viewer.controls.target); }}"""
    )
    assert target < 1e-3  # the orbit target is on the moving frame
    save("export_selected_follow.png", page.screenshot())
    assert page.errors == []


def test_export_of_static_and_datetime_scenes(page, tmp_path):
    from rbm_nb.scene import Scene

    rbm.register_frame("world")
    ts = np.datetime64("2020-02-02T00:27:14") + np.arange(50) * np.timedelta64(
        100, "ms"
    )
    rbm.register_frame(
        "head", parent="world", timestamps=ts, translation=np.zeros((50, 3))
    )
    with Scene("world") as scene:
        scene.add_frame("head")
        scene.add_mesh("world", "sphere", size=0.3, color="#ff00ff")
        dated = scene.to_html(tmp_path / "dated.html")
    page.goto(dated.as_uri())
    page.wait_for_function("window.rbmExport && window.rbmExport.ready", timeout=60000)
    page.locator(".rbm-player").focus()
    page.keyboard.press("ArrowRight")
    assert page.inner_text(".rbm-readout") == "1.000 s \u00b7 2020-02-02 00:27:15.000"
    assert (
        magenta_pixels(png_pixels(page.locator(".rbm-scene canvas").screenshot())) > 200
    )
    assert page.errors == []


# -- (b) the explorer in JupyterLab 4 and Notebook 7 -----------------------------------
CELLS = [
    # 0: the kernel's own listening sockets (ZeroMQ) before rbm_nb runs
    """import os, psutil
listening = lambda: {c.laddr for c in psutil.Process().net_connections("inet") if c.status == "LISTEN"}
before = listening()
import ipywidgets as widgets
import rbm_nb as rbm
from rbm_nb import explorer
head, left_eye, right_eye, note = explorer.load_head_eye()
print("data:", note)
rbm.clear_registry()
explorer.register_head_eye_frames(head, left_eye, right_eye)
series = explorer.explorer_series(head, left_eye, right_eye)""",
    # 1: the dashboard
    """scene = explorer.explorer_scene()
player = scene.player()
plot = explorer.explorer_plot(series, player)
scene.widget.height = 420
widgets.VBox([scene.widget, player] + ([plot] if plot is not None else []))""",
    # 2: the kernel is busy until the test releases it (a fixed sleep ended too
    # early on a slow machine, before the controls had been pressed); it gives up
    # after two minutes so that a failed test does not leave it running
    """import time, pathlib
release = pathlib.Path({release!r})
deadline = time.monotonic() + 120
while not release.exists() and time.monotonic() < deadline:
    time.sleep(0.05)
print("released" if release.exists() else "gave up")""",
    # 3: what the kernel learned, and its sockets
    """print("KERNEL", round(player.time, 3), player.playing, player.speed)
print("NEW SOCKETS", sorted(listening() - before))""",
]


def explorer_notebook(path: Path, release: Path, kernel: str) -> Path:
    """Write the explorer notebook; its busy cell waits for ``release`` to exist."""
    return write_notebook(
        path,
        [source.replace("{release!r}", repr(str(release))) for source in CELLS],
        kernel,
    )


@pytest.mark.parametrize("app", ["lab", "notebook"])
def test_explorer_plays_in_the_browser_while_the_kernel_is_busy(
    app, browser, jupyter_server, tmp_path
):
    server = jupyter_server(app)
    env = {"RBM_NB_DATA_DIR": str(REAL_DATA)} if REAL_DATA.is_dir() else {}
    release = tmp_path / "release_busy_cell"
    name = server.add_notebook(
        explorer_notebook(
            tmp_path / "explorer_busy.ipynb", release, server.kernel_with_env(env)
        )
    )
    context, blocked = new_context(
        browser, server, viewport={"width": 1300, "height": 1400}
    )
    page = context.new_page()
    measurements = {}
    try:
        # jupyter-server-proxy is really off: its route does not exist
        import urllib.error
        import urllib.request

        with pytest.raises(urllib.error.HTTPError):
            urllib.request.urlopen(server.url(f"proxy/{server.port}/api"), timeout=10)

        open_notebook(page, server, name)
        kernel = None
        for _ in range(120):
            kernel = server.kernel_pid(name)
            if kernel:
                break
            page.wait_for_timeout(500)
        assert kernel, "the notebook's kernel did not start"
        sockets_before = listening_sockets(kernel)

        run_cell(page, 0)
        wait_done(page, 0)
        assert "data:" in output_text(page, 0)
        run_cell(page, 1)
        wait_done(page, 1)
        page.wait_for_function(
            """() => { const el = document.querySelector('.rbm-scene');
                       return el && el.rbmView && el.rbmView.store.tracks.size >= 3
                              && el.rbmView.player !== null && el.rbmView.frames > 0; }""",
            timeout=120000,
        )
        page.wait_for_timeout(1000)
        canvas = page.locator(".rbm-scene canvas")
        before = png_pixels(canvas.screenshot())
        assert (before.std(axis=(0, 1)) > 5).any()  # the 3D view renders something

        # Play moves the view
        page.click(".rbm-play")
        page.wait_for_function(
            "document.querySelector('.rbm-scene').rbmView.currentTime() > 1.0",
            timeout=30000,
        )
        idle_kernel = page.evaluate(MEASURE_JS, 1500)
        measurements["kernel idle"] = idle_kernel

        # another cell keeps the kernel busy until released; the view keeps moving
        run_cell(page, 2)
        page.wait_for_function(
            """() => document.querySelectorAll('.jp-Notebook .jp-CodeCell')[2]
                     .querySelector('.jp-InputPrompt').innerText.includes('*')""",
            timeout=10000,
        )
        page.wait_for_timeout(300)  # past the UI work of starting the cell
        busy = page.evaluate(MEASURE_JS, 1500)
        measurements["busy"] = busy
        # the busy kernel does not slow the view: the page keeps drawing at about
        # the rate it had with the kernel idle (the absolute frame rate, 50 and
        # more here, is benchmarks/bench_notebook.py's to report, not a test's)
        print("frames/s", measurements)
        assert busy["raf"] >= 0.5 * idle_kernel["raf"], measurements
        assert busy["rendered"] >= 0.5 * busy["raf"], (
            busy
        )  # the 3D view redrew each frame
        assert busy["advanced"] == pytest.approx(busy["seconds"], rel=0.2), busy

        # pause, scrub, speed and play while the kernel is still busy: at once
        page.click(".rbm-play")
        paused = player_time(page)
        page.wait_for_timeout(300)
        assert player_time(page) == paused
        page.evaluate(
            """() => { const s = document.querySelector('.rbm-slider');
                       s.value = '100'; s.dispatchEvent(new Event('input', {bubbles: true})); }"""
        )
        assert player_time(page) == pytest.approx(100.0)
        page.wait_for_timeout(100)
        assert page.evaluate(
            "document.querySelector('.rbm-scene').rbmView.currentTime()"
        ) == pytest.approx(100.0)
        page.select_option(".rbm-speed", "4")
        page.click(".rbm-play")
        fast = page.evaluate(MEASURE_JS, 1000)
        measurements["speed 4"] = fast
        assert fast["advanced"] == pytest.approx(4 * fast["seconds"], rel=0.2), fast
        page.click(".rbm-play")
        final = player_time(page)
        still_busy = "*" in prompt(page, 2)
        save(f"explorer_{app}_busy.png", page.screenshot(full_page=True))
        save(f"explorer_{app}_view.png", canvas.screenshot())
        after = png_pixels(canvas.screenshot())
        assert changed_pixels(before, after) > 50  # the head moved in the view
        assert still_busy, "the kernel finished before the controls were tested"

        release.touch()
        wait_done(page, 2, timeout=60000)
        assert "released" in output_text(page, 2)
        # the kernel learned the paused time, speed and state
        run_cell(page, 3)
        wait_done(page, 3)
        text = output_text(page, 3)
        assert f"KERNEL {round(final, 3)} False 4.0" in text, text
        assert "NEW SOCKETS []" in text, text
        assert listening_sockets(kernel) == sockets_before
        assert blocked == [], blocked  # nothing needed another port
        ours = our_errors(page.errors, server)
        assert ours == [], ours
        print(app, measurements)
    except Exception:
        save(f"explorer_{app}_failure.png", page.screenshot(full_page=True))
        print(server.log_text())
        raise
    finally:
        context.close()


def test_plot_click_seeks_and_moves_the_3d_view(page, tmp_path):
    """One Player drives the plot and the 3D view: a click in the plot moves both."""
    from rbm_nb.widgets import TimeSeries

    if not hasattr(TimeSeries, "_esm"):
        pytest.skip("TimeSeries is not the browser widget on this branch")
    scene = circling_scene()
    player = scene.player()
    t = np.arange(0, 10.0, 0.02)
    plot = TimeSeries({"angle": (t, np.degrees(2 * np.pi * t / 10))}, player=player)
    out = scene.to_html(tmp_path / "dash.html", series=plot, player=player)
    scene.close()
    page.goto(out.as_uri())
    page.wait_for_function("window.rbmExport && window.rbmExport.ready", timeout=60000)
    page.wait_for_function(
        "document.querySelector('.rbm-ts') && document.querySelector('.rbm-ts').rbmCharts",
        timeout=30000,
    )
    page.wait_for_timeout(500)
    canvas = page.locator(".rbm-scene canvas")
    before = png_pixels(canvas.screenshot())
    box = page.evaluate(
        """() => { const u = document.querySelector('.rbm-ts').rbmCharts[0];
                   const r = u.over.getBoundingClientRect();
                   return [r.x, r.y, r.width, r.height, u.posToVal(0.6 * r.width, 'x')]; }"""
    )
    x, y, w, h, target = box
    page.mouse.click(x + 0.6 * w, y + 0.5 * h)
    view = "document.querySelector('.rbm-scene').rbmView"
    page.wait_for_function(
        f"Math.abs({view}.currentTime() - {target}) < 0.1", timeout=5000
    )
    page.wait_for_timeout(300)
    after = png_pixels(canvas.screenshot())
    assert changed_pixels(before, after) > 100  # the body moved to the clicked time
    shown = float(page.inner_text(".rbm-readout").split()[0])  # the Player follows too
    assert shown == pytest.approx(target, abs=0.05)
    save("export_plot_seek.png", page.screenshot(full_page=True))
    assert page.errors == []


def _seek_export(page, seconds: float) -> None:
    page.evaluate(
        """(t) => { const s = document.querySelector('.rbm-slider');
                    s.value = String(t); s.dispatchEvent(new Event('input', {bubbles: true})); }""",
        seconds,
    )
    page.wait_for_timeout(300)


def test_export_hides_the_gaze_ray_where_the_real_eye_was_not_seen(
    browser, tmp_path, monkeypatch
):
    """The explorer export on the real recording: no left-eye ray inside the eye
    tracker's longest gap (1.06 s), a ray where the pupil was seen confidently."""
    import xarray as xr
    from conftest import SHARED

    from rbm_nb.app.explorer import write_explorer_html

    folder = SHARED / "data" / "rbm-data"
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(folder))
    path = write_explorer_html(
        tmp_path / "explorer.html", source="remote", progress=False
    )
    eye = xr.load_dataset(folder / "left_eye.nc")
    start = xr.load_dataset(folder / "head.nc").time.values[0]
    seconds = (eye.time.values - start) / np.timedelta64(1, "s")
    gap = int(np.argmax(np.diff(seconds)))
    assert seconds[gap + 1] - seconds[gap] > 1.0
    seen = ~np.isnan(eye.orientation.values).any(axis=1) & (
        eye.confidence.values >= 0.6
    )
    run = np.convolve(seen.astype(int), np.ones(200, int), "valid")
    well_seen = float(seconds[int(np.argmax(run == 200)) + 100])

    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    try:
        page.goto(path.as_uri())
        page.wait_for_function(
            """() => { const el = document.querySelector('.rbm-scene');
                       return el && el.rbmView && el.rbmView.store.tracks.size > 0; }""",
            timeout=120000,
        )
        paths = page.evaluate(
            "() => [...document.querySelector('.rbm-scene').rbmView.store.tracks.keys()]"
        )
        [left] = [p for p in paths if "left_eye" in p]
        visible = "(p) => document.querySelector('.rbm-scene').rbmView.node(p).visible"
        _seek_export(page, (seconds[gap] + seconds[gap + 1]) / 2)
        assert page.evaluate(visible, left) is False
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "export_real_gap_no_ray.png"))
        _seek_export(page, well_seen)
        assert page.evaluate(visible, left) is True
        page.screenshot(path=str(ARTIFACTS / "export_real_ray_seen.png"))
    finally:
        page.close()
