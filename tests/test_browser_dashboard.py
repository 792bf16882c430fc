"""The TimeSeries widget in JupyterLab, in Debian's chromium (playwright).

The notebook is written by the test: a plot of two panels (one with a run of
NaN values) linked to a Player. Checked in the page: the panels render, the
run of NaN is a break in the line, dragging zooms (the axis range changes and
reaches the kernel), a click seeks the Player (the kernel sees the new time)
and the cursor follows the Player's time. Screenshots go to test-artifacts/.
"""

from __future__ import annotations

import nbformat
import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow]

from browser_support import JupyterLab, png_pixels, save  # noqa: E402

NAN_RUN = (8.0, 10.0)  # seconds with NaN values in the "wave" panel

SETUP = f"""
import numpy as np
import ipywidgets as widgets
import time
from rbm_nb.widgets import Player, TimeSeries

t = np.arange(0.0, 20.0, 0.01)
wave = np.sin(t)
wave[(t > {NAN_RUN[0]}) & (t < {NAN_RUN[1]})] = np.nan
circle = np.c_[np.cos(t), np.sin(t)]
player = Player(t)
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
busy.on_click(lambda _: time.sleep(4))
widgets.VBox([player, plot, kernel_time, kernel_range, jump, busy])
"""


def _notebook(path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell(SETUP),
        nbformat.v4.new_code_cell('print("DASHBOARD-READY")'),
    ]
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nbformat.write(nb, path)
    return path


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dashboard")
    notebook = _notebook(tmp / "dashboard.ipynb")
    (tmp / "lab").mkdir()
    server = JupyterLab(tmp / "lab", [notebook])
    try:
        yield server
    finally:
        server.stop()


@pytest.fixture(scope="module")
def dashboard(browser, lab):
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    context = browser.new_context(viewport={"width": 1200, "height": 1400})
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda err: page.errors.append(str(err)))
    try:
        page.goto(lab.url("lab/tree/dashboard.ipynb"), timeout=120000)
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=120000)
        try:
            page.locator(".jp-Dialog").get_by_role(
                "button", name="Select", exact=True
            ).click(timeout=20000)
        except PlaywrightTimeout:
            pass
        page.wait_for_selector(
            ".jp-Notebook-ExecutionIndicator[data-status='idle']", timeout=120000
        )
        page.get_by_role("menuitem", name="Run", exact=True).click()
        page.get_by_text("Run All Cells", exact=True).click()
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
    save("dashboard_seeked.png", page.locator(".rbm-ts").screenshot())
    assert not page.errors


def cursor_left(page, i=0):
    return float(
        page.locator(".rbm-ts-cursor")
        .nth(i)
        .evaluate("el => parseFloat(el.style.left)")
    )


def test_cursor_follows_play_while_the_kernel_is_busy(dashboard):
    page = dashboard
    page.get_by_role("button", name="jump to 15 s").click()
    page.wait_for_function(
        "document.querySelector('.rbm-ts-time').textContent.startsWith('t = 15.000 s')",
        timeout=30000,
    )
    page.locator(".rbm-player .rbm-big-back").click()  # back to 5 s
    page.wait_for_timeout(300)
    page.get_by_role("button", name="keep the kernel busy").click()
    page.wait_for_timeout(300)  # the kernel now sleeps for 4 s
    start = cursor_left(page)
    page.locator(".rbm-player .rbm-play").click()
    page.wait_for_timeout(1500)
    moved = cursor_left(page)
    per_second = chart(page, 0, "u.valToPos(1, 'x') - u.valToPos(0, 'x')")
    # about 1.5 s of playback, counted in the page while the kernel sleeps
    assert moved - start > 0.8 * per_second
    readout = page.locator(".rbm-ts-time").inner_text()
    player_readout = page.locator(".rbm-player .rbm-readout").inner_text()
    save(
        "dashboard_playing.png",
        page.locator(".jp-OutputArea-output").first.screenshot(),
    )
    page.locator(".rbm-player .rbm-play").click()  # pause
    # the plot and the Player print the time the same way
    assert readout[len("t = ") :].split(" s")[0].replace(".", "").isdigit()
    assert " s" in player_readout
    assert not page.errors
