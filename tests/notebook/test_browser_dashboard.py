"""The dashboard widgets (TimeSeries, FrameTree, Scene, Player) in chromium.

JupyterLab runs a notebook written by the test: a frame tree and a 3D scene
of a circling body, a Player, and a plot of two panels (one with a run of NaN
values). Checked in the page: the panels render and the NaN run is a break in
the line; dragging and the wheel zoom (the range reaches the kernel); a click
in the plot seeks the Player (the kernel sees the new time) and moves the 3D
view; the cursor follows the Player, also while it plays with the kernel
busy (a button holds it until the test lets go); selecting in the tree
selects in the 3D view and a click on a frame in 3D selects it in the tree.
Then the same plot in a ``to_html`` export, offline. Screenshots go to test-artifacts/.
"""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow]

from browser_support import (  # noqa: E402
    changed_pixels,
    new_context,
    open_notebook,
    png_pixels,
    run_all_cells,
    save,
    write_notebook,
)

NAN_RUN = (8.0, 10.0)  # seconds with NaN values in the "wave" panel

SETUP = f"""
import numpy as np
import ipywidgets as widgets
import pathlib
import time
import rbm_nb as rbm
from rbm_nb.scene import Scene
from rbm_nb.widgets import FrameTree, TimeSeries

t = np.arange(0.0, 20.0, 0.01)
wave = np.sin(t)
wave[(t > {NAN_RUN[0]}) & (t < {NAN_RUN[1]})] = np.nan
circle = np.c_[np.cos(t), np.sin(t)]
# a body circling the origin once in 20 s, drawn in 3D
rbm.register_frame("world")
angle = 2 * np.pi * t / 20
rbm.register_frame(
    "body", parent="world", timestamps=t,
    translation=np.c_[2 * np.cos(angle), 2 * np.sin(angle), 0.5 + 0 * t],
    rotation=np.c_[np.cos(angle / 2), 0 * t, 0 * t, np.sin(angle / 2)],
)
scene = Scene("world")
scene.add_frame("world", scale=1.0)
scene.add_frame("body", scale=0.8)
scene.add_path("body", color="#ff00ff")
scene.add_mesh("body", "box", size=(0.6, 0.4, 0.3), color="#00e0e0")
scene.widget.height = 300
scene.widget.layout.flex = "1 1 60%"
player = scene.player()
tree = FrameTree("world", scene=scene, player=player)
tree.layout.flex = "0 0 38%"
plot = TimeSeries(
    {{"wave": (t, wave), "circle": (t, circle, ["cos", "sin"])}},
    player=player, title="test plot", panel_height=160,
)
kernel_time = widgets.Label("kernel waiting")
kernel_range = widgets.Label("range waiting")
player.observe(lambda c: setattr(kernel_time, "value", f"KERNEL-TIME {{c.new:.3f}}"), "time")
plot.observe(lambda c: setattr(kernel_range, "value", f"KERNEL-RANGE {{c.new}}"), "x_range")
jump = widgets.Button(description="jump to 15 s")
jump.on_click(lambda _: setattr(player, "time", 15.0))
busy = widgets.Button(description="keep the kernel busy")
hold_dir = pathlib.Path(HOLD_DIR)
def hold(_):  # until the test releases it (at most a minute)
    (hold_dir / "holding").touch()
    deadline = time.monotonic() + 60
    while not (hold_dir / "release").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    released = (hold_dir / "release").exists()
    (hold_dir / "done").write_text("released" if released else "gave up")
busy.on_click(hold)
widgets.VBox([widgets.HBox([tree, scene.widget]), player, plot, kernel_time, kernel_range, jump, busy])
"""


@pytest.fixture(scope="module")
def hold_dir(tmp_path_factory):
    """Where the busy button's handler says it holds the kernel ("holding"),
    waits for the test's "release", and says it let go ("done")."""
    return tmp_path_factory.mktemp("busy")


@pytest.fixture(scope="module")
def lab(jupyter_servers, tmp_path_factory, hold_dir):
    """The session's JupyterLab with the dashboard notebook, whose busy button
    holds the kernel until ``hold_dir/release`` exists, and says so in
    ``hold_dir``; its kernel is shut down after the module."""
    server = jupyter_servers("lab")
    source = SETUP.replace("HOLD_DIR", repr(str(hold_dir)))
    cells = [source, 'print("DASHBOARD-READY")']
    path = tmp_path_factory.mktemp("dashboard") / "dashboard.ipynb"
    server.dashboard = server.add_notebook(write_notebook(path, cells))
    try:
        yield server
    finally:
        server.end_sessions()


@pytest.fixture(scope="module")
def dashboard(browser, lab):
    context, _ = new_context(browser, viewport={"width": 1200, "height": 1400})
    page = context.new_page()
    try:
        open_notebook(page, lab, lab.dashboard)
        run_all_cells(page)
        page.locator(".jp-OutputArea-output", has_text="DASHBOARD-READY").wait_for(
            timeout=180000
        )
        page.wait_for_function(
            "document.querySelector('.rbm-ts') && document.querySelector('.rbm-ts').rbmCharts"
            " && document.querySelector('.rbm-ts').rbmCharts.length === 2",
            timeout=60000,
        )
        page.wait_for_timeout(500)
        yield page
    except Exception:
        save("dashboard_failure.png", page.screenshot(full_page=True))
        print(lab.log_text())
        raise
    finally:
        context.close()


def chart(page, i, expr):
    return page.evaluate(
        f"(() => {{ const u = document.querySelector('.rbm-ts').rbmCharts[{i}]; return {expr}; }})()"
    )


def over_box(page, i):
    return chart(
        page,
        i,
        "(() => { const r = u.over.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })()",
    )


def test_panels_render_with_a_break_at_the_nan_run(dashboard):
    page = dashboard
    plot = page.locator(".rbm-ts")
    save("dashboard_plot.png", plot.screenshot())
    x, y, w, h = over_box(page, 0)
    shot = png_pixels(page.screenshot(clip={"x": x, "y": y, "width": w, "height": h}))
    r, g, b = shot[..., 0], shot[..., 1], shot[..., 2]
    blue = (
        (b > 120) & (r < 120) & (g > 70) & (g < 160)
    )  # the first line colour, #1f77b4
    per_column = blue.sum(axis=0)

    def column(t):
        return int(round(chart(page, 0, f"u.valToPos({t}, 'x')")))

    inside = per_column[column(NAN_RUN[0]) + 3 : column(NAN_RUN[1]) - 3]
    before = per_column[column(1.0) : column(7.0)]
    after = per_column[column(11.0) : column(19.0)]
    assert (before > 0).mean() > 0.95 and (after > 0).mean() > 0.95
    assert inside.sum() == 0, "the NaN run should be a break in the line"
    legend = page.locator(".rbm-ts .u-legend").first.inner_text()
    assert "wave" in legend and "time" in legend
    # hovering shows the values at the mouse in every panel's legend
    x1, y1, w1, h1 = over_box(page, 1)
    page.mouse.move(x1 + 0.25 * w1, y1 + h1 / 2)
    at = chart(page, 1, f"u.posToVal({0.25 * w1}, 'x')")
    page.wait_for_timeout(200)
    circle = page.locator(".rbm-ts .u-legend").nth(1).inner_text()
    per_px = chart(page, 1, "(u.scales.x.max - u.scales.x.min) / u.over.clientWidth")
    shown = re.search(r"time\s*(-?[\d.]+) s", circle)
    cos_value = re.search(r"cos\s*(-?[\d.]+)", circle)
    assert shown and cos_value, circle
    # the sample nearest the mouse, its time as the readout prints it
    assert abs(float(shown.group(1)) - at) <= 2 * per_px
    assert float(cos_value.group(1)) == pytest.approx(
        np.cos(float(shown.group(1))), abs=1e-3
    )
    assert page.locator(".rbm-ts .u-legend").nth(1).inner_text().count("sin") == 1
    assert not page.errors


def test_drag_zooms_every_panel_and_tells_the_kernel(dashboard):
    page = dashboard
    x, y, w, h = over_box(page, 0)
    start = chart(page, 0, "[u.scales.x.min, u.scales.x.max]")
    page.mouse.move(x + 0.25 * w, y + h / 2)
    page.mouse.down()
    page.mouse.move(x + 0.5 * w, y + h / 2, steps=8)
    page.mouse.up()
    page.wait_for_timeout(300)
    zoomed = chart(page, 0, "[u.scales.x.min, u.scales.x.max]")
    assert zoomed[1] - zoomed[0] < 0.3 * (start[1] - start[0])
    assert chart(page, 1, "[u.scales.x.min, u.scales.x.max]") == zoomed
    page.locator(".widget-label", has_text="KERNEL-RANGE [").wait_for(timeout=30000)
    save("dashboard_zoomed.png", page.locator(".rbm-ts").screenshot())
    # the wheel zooms out around the mouse, a double click shows everything again
    page.mouse.move(x + 0.5 * w, y + h / 2)
    page.mouse.wheel(0, 300)
    page.wait_for_timeout(300)
    wider = chart(page, 0, "[u.scales.x.min, u.scales.x.max]")
    assert wider[1] - wider[0] > zoomed[1] - zoomed[0]
    page.mouse.dblclick(x + 0.5 * w, y + h / 2)
    page.wait_for_timeout(300)
    assert chart(page, 0, "[u.scales.x.min, u.scales.x.max]") == pytest.approx(start)


def test_click_seeks_the_player_and_the_cursor_follows_it(dashboard):
    page = dashboard
    x, y, w, h = over_box(page, 1)
    per_px = chart(page, 1, "(u.scales.x.max - u.scales.x.min) / u.over.clientWidth")
    target = chart(page, 1, f"u.posToVal({0.3 * w}, 'x')")
    before_click = png_pixels(page.locator(".rbm-scene canvas").first.screenshot())
    page.mouse.click(x + 0.3 * w, y + 0.9 * h)
    # the double click of the zoom test seeked too: wait for this click's time
    page.wait_for_function(
        """([target, tol]) => [...document.querySelectorAll('.widget-label')].some((el) => {
            const m = el.textContent.match(/KERNEL-TIME (\\S+)/);
            return m && Math.abs(parseFloat(m[1]) - target) <= tol;
        })""",
        arg=[target, per_px + 1e-3],
        timeout=30000,
    )
    label = page.locator(".widget-label", has_text="KERNEL-TIME")
    seen = float(label.inner_text().split()[-1])
    # the 3D view follows the same Player: the click moved the body
    page.wait_for_timeout(500)
    after_click = png_pixels(page.locator(".rbm-scene canvas").first.screenshot())
    assert changed_pixels(before_click, after_click) > 200
    cursor = page.locator(".rbm-ts-cursor").nth(1)
    left = float(cursor.evaluate("el => parseFloat(el.style.left)"))
    assert abs(left + 1 - 0.3 * w) < 1.5
    assert page.locator(".rbm-ts-time").inner_text().startswith(f"t = {seen:.3f} s")
    # the kernel moves the player: the cursor of every panel follows
    page.get_by_role("button", name="jump to 15 s").click()
    page.wait_for_function(
        "document.querySelector('.rbm-ts-time').textContent.startsWith('t = 15.000 s')",
        timeout=30000,
    )
    expected = chart(page, 0, "u.valToPos(15, 'x')")
    for i in range(2):
        left = float(
            page.locator(".rbm-ts-cursor")
            .nth(i)
            .evaluate("el => parseFloat(el.style.left)")
        )
        assert abs(left + 1 - expected) < 1.5
    save(
        "dashboard_seeked.png", page.locator(".jp-OutputArea-output").first.screenshot()
    )
    assert not page.errors


def test_dragging_the_red_line_scrubs_without_zooming(dashboard):
    page = dashboard
    x, y, w, h = over_box(page, 0)
    before = chart(page, 0, "[u.scales.x.min, u.scales.x.max]")
    line = (
        float(
            page.locator(".rbm-ts-cursor").first.evaluate(
                "el => parseFloat(el.style.left)"
            )
        )
        + 1
    )
    target = chart(page, 0, f"u.posToVal({0.2 * w}, 'x')")
    page.mouse.move(x + line, y + h / 2)
    page.mouse.down()
    page.mouse.move(x + 0.5 * (line + 0.2 * w), y + h / 2, steps=5)
    page.mouse.move(x + 0.2 * w, y + h / 2, steps=5)
    page.mouse.up()
    per_px = chart(page, 0, "(u.scales.x.max - u.scales.x.min) / u.over.clientWidth")
    page.wait_for_function(
        """([target, tol]) => [...document.querySelectorAll('.widget-label')].some((el) => {
            const m = el.textContent.match(/KERNEL-TIME (\\S+)/);
            return m && Math.abs(parseFloat(m[1]) - target) <= tol;
        })""",
        arg=[target, 2 * per_px + 1e-3],
        timeout=30000,
    )
    assert chart(page, 0, "[u.scales.x.min, u.scales.x.max]") == before
    assert abs(cursor_left(page) + 1 - 0.2 * w) < 2.5


def cursor_left(page, i=0):
    return float(
        page.locator(".rbm-ts-cursor")
        .nth(i)
        .evaluate("el => parseFloat(el.style.left)")
    )


def _wait_for_file(path, timeout):
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path.name} did not appear"
        time.sleep(0.05)


def test_cursor_follows_play_while_the_kernel_is_busy(dashboard, hold_dir):
    page = dashboard
    page.get_by_role("button", name="jump to 15 s").click()
    page.wait_for_function(
        "document.querySelector('.rbm-ts-time').textContent.startsWith('t = 15.000 s')",
        timeout=30000,
    )
    page.locator(".rbm-player .rbm-big-back").click()  # back to 5 s
    page.wait_for_timeout(300)
    page.get_by_role("button", name="keep the kernel busy").click()
    # The handler's own files say whether the kernel is held: JupyterLab's
    # busy/idle indicator is not evidence, as a control-channel request (a
    # kernel_info nudge, the debugger's probe) publishes "idle" while the shell
    # is still busy (jupyter/jupyter_client#838, jupyterlab/jupyterlab#10701).
    try:
        _wait_for_file(hold_dir / "holding", timeout=30)
        start = cursor_left(page)
        page.locator(".rbm-player .rbm-play").click()
        page.wait_for_timeout(1500)
        moved = cursor_left(page)
        per_second = chart(page, 0, "u.valToPos(1, 'x') - u.valToPos(0, 'x')")
        readout = page.locator(".rbm-ts-time").inner_text()
        player_readout = page.locator(".rbm-player .rbm-readout").inner_text()
        save(
            "dashboard_playing.png",
            page.locator(".jp-OutputArea-output").first.screenshot(),
        )
        page.locator(".rbm-player .rbm-play").click()  # pause
        held_throughout = not (hold_dir / "done").exists()
    finally:
        # let go even when a check failed, so the module's later tests get
        # a kernel that answers
        (hold_dir / "release").touch()
    _wait_for_file(hold_dir / "done", timeout=60)
    assert held_throughout, "the kernel was not busy through the checks"
    assert (hold_dir / "done").read_text() == "released"
    # about 1.5 s of playback, counted in the page while the kernel was held
    assert moved - start > 0.8 * per_second
    # the plot and the Player print the time the same way
    assert readout[len("t = ") :].split(" s")[0].replace(".", "").isdigit()
    assert " s" in player_readout
    assert not page.errors


def test_selecting_in_the_tree_selects_in_the_3d_view(dashboard):
    page = dashboard
    page.locator(".rbm-frame-node", has_text="body").first.click()
    # the scene's view knows the selection: its follow button names the frame
    page.locator(".rbm-scene .rbm-follow", has_text="body").wait_for(timeout=30000)
    details = page.locator(".rbm-frame-details")
    details.locator("text=pose wrt world").wait_for(timeout=30000)
    text = details.inner_text()
    assert "rotation yaw" in text and "quaternion (w, x, y, z)" in text
    save(
        "dashboard_selected.png",
        page.locator(".jp-OutputArea-output").first.screenshot(),
    )
    assert not page.errors


def test_exported_dashboard_plot_works_offline(page, tmp_path):
    """The plot in a to_html export: drawn, zooms, seeks the Player, follows play."""
    import numpy as np

    import rbm_nb as rbm
    from rbm_nb.scene import Scene
    from rbm_nb.widgets import TimeSeries

    t = np.arange(0.0, 20.0, 0.01)
    rbm.register_frame("world")
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=t,
        translation=np.c_[np.cos(t / 3), np.sin(t / 3), 0 * t],
    )
    wave = np.sin(t)
    wave[(t > NAN_RUN[0]) & (t < NAN_RUN[1])] = np.nan
    scene = Scene("world")
    scene.add_frame("body", scale=0.5)
    player = scene.player()
    plot = TimeSeries({"wave": (t, wave)}, player=player)
    out = scene.to_html(tmp_path / "dashboard.html", series=plot, player=player)
    plot.close()
    player.close()
    scene.close()
    requests = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(out.as_uri())
    page.wait_for_function(
        "document.querySelector('.rbm-ts') && document.querySelector('.rbm-ts').rbmCharts",
        timeout=60000,
    )
    page.wait_for_timeout(300)
    x, y, w, h = over_box(page, 0)
    page.mouse.click(x + 0.5 * w, y + h / 2)  # seek to the middle
    page.wait_for_function(
        "Math.abs(parseFloat(document.querySelector('.rbm-readout').textContent) - 10) < 0.2",
        timeout=30000,
    )
    start = cursor_left(page)
    page.click(".rbm-play")
    page.wait_for_timeout(1000)
    page.click(".rbm-play")
    assert cursor_left(page) > start
    save("export_dashboard.png", page.screenshot(full_page=True))
    assert all(url.startswith(("file:", "data:", "blob:")) for url in requests), (
        requests
    )
    assert not page.errors


def test_clicking_a_frame_in_3d_selects_it_in_the_tree(dashboard):
    page = dashboard
    # start from "world" alone selected (a click toggles a row)
    for name in ("body", "world"):
        row = page.locator(".rbm-frame-node", has_text=name).first
        if "mod-active" in (row.get_attribute("class") or ""):
            row.click()
            page.wait_for_timeout(300)
    page.locator(".rbm-frame-node", has_text="world").first.click()
    page.locator(".rbm-frame-details", has_text="parent: none (root)").wait_for(
        timeout=30000
    )
    where = page.evaluate(
        """() => { const v = document.querySelector('.rbm-scene').rbmView;
                   const box = v.pane.getBoundingClientRect();
                   const xy = v.screenPosition(v.model.get('_frames').body);
                   return [box.left + xy[0], box.top + xy[1]]; }"""
    )
    page.mouse.click(where[0] + 3, where[1] + 2)
    # the scene's `selected` goes through the kernel to the FrameTree
    page.locator(".rbm-frame-details", has_text="parent: world").wait_for(timeout=30000)
    assert page.locator(".rbm-frame-details b").first.inner_text().startswith("body")
    assert page.evaluate(
        "[...document.querySelectorAll('.rbm-frame-node')]"
        ".filter((b) => b.classList.contains('mod-active')).map((b) => b.textContent)"
    ) == ["body"]
    save(
        "dashboard_3d_click.png",
        page.locator(".jp-OutputArea-output").first.screenshot(),
    )
    assert not page.errors
