"""A TimeSeries of a long recording in chromium (JupyterLab): it draws, or says why not.

The left eye of the example recording (the real one when ``RBM_NB_DATA_DIR``
holds it, else the synthetic one) is tiled in time to 1.6 h with every
low-confidence sample kept as a NaN row, and plotted at full resolution (no
``max_points``): well over 125k runs of missing samples, where the bundled
uPlot's own gap collection (``gaps.push(...findGaps(...))``) overflowed the
call stack and left the panel empty with an error in the console only.
Checked: the panel holds every sample, its line is drawn across the plot, no
page error; then, with the canvas made to fail on purpose, the widget shows
a message naming the panel instead of an empty plot.
"""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow]

from browser_support import (  # noqa: E402
    new_context,
    open_notebook,
    png_pixels,
    run_all_cells,
    save,
    write_notebook,
)

HOURS = 1.6
#: uPlot 1.6.32 overflowed past about this many runs of missing samples
UPLOT_SPREAD_LIMIT = 125_000

SETUP = f"""
import numpy as np
from rbm_nb.explorer import load_head_eye, MIN_CONFIDENCE
import ipywidgets as widgets
from rbm_nb.widgets import Player, TimeSeries

_, eye, _, note = load_head_eye()
t = (eye.time.values - eye.time.values[0]).astype("timedelta64[ns]").astype(float) / 1e9
x = eye.position.values[:, 0].copy()
x[~(eye.confidence.values >= MIN_CONFIDENCE)] = np.nan
period = t[-1] + np.median(np.diff(t))
tiles = int(np.ceil({HOURS} * 3600 / period))
t_long = (t[None, :] + period * np.arange(tiles)[:, None]).ravel()
x_long = np.tile(x, tiles)
missing = np.isnan(x_long)
runs = int(np.count_nonzero(missing[1:] & ~missing[:-1]) + missing[0])
plot = TimeSeries({{"left eye x": (t_long, x_long)}}, title="long recording", max_points=None)
sent = np.frombuffer(plot.data[0]["x"], dtype=np.float64).size  # samples + a NaN row per pause
print(f"LONG-READY samples={{t_long.size}} sent={{sent}} runs={{runs}} hours={{t_long[-1] / 3600:.2f}}")
# a player whose clock starts 0.7 ms before the plot's (as the eyes' before the head's)
player = Player(np.r_[-0.0007, t_long[::10000], t_long[-1]])
attach = widgets.Button(description="attach the player")
attach.on_click(lambda _: setattr(plot, "player", player))
# the same recording as its min/max overview at the view's pixel width; a zoom
# fetches the samples in view
overview = TimeSeries({{"left eye x": (t_long, x_long)}}, title="overview", max_points=2000)
sent_overview = sum(len(b) for b in [overview.data[0]["x"], *overview.data[0]["y"]])
print(f"OVERVIEW-SENT bytes={{sent_overview}} width={{overview.overview_width}}")
np.save(EXPECTED, np.c_[t_long, x_long])
widgets.VBox([plot, attach, overview])
"""


@pytest.fixture(scope="module")
def lab(jupyter_servers, tmp_path_factory):
    """The session's JupyterLab with the long-plot notebook; its kernel is shut
    down after the module."""
    server = jupyter_servers("lab")
    tmp = tmp_path_factory.mktemp("long_plot")
    server.expected = tmp / "expected.npy"
    cells = [SETUP.replace("EXPECTED", repr(str(server.expected)))]
    server.long_plot = server.add_notebook(write_notebook(tmp / "long.ipynb", cells))
    try:
        yield server
    finally:
        server.end_sessions()


# Path2D.lineTo fails once the test asks it to: a canvas that cannot draw
BREAK_PATHS = """
const lineTo = Path2D.prototype.lineTo;
Path2D.prototype.lineTo = function (...args) {
  if (window.rbmBreakPaths) throw new RangeError("broken on purpose by the test");
  return lineTo.apply(this, args);
};
"""


@pytest.fixture(scope="module")
def long_plot(browser, lab):
    context, _ = new_context(browser, viewport={"width": 1200, "height": 900})
    context.add_init_script(BREAK_PATHS)
    page = context.new_page()
    page.console_errors = []
    # bytes the kernel sends to the page over its websockets
    page.received = [0]

    def count(ws):
        ws.on(
            "framereceived",
            lambda frame: page.received.__setitem__(
                0,
                page.received[0]
                + len(frame if isinstance(frame, bytes) else frame.encode()),
            ),
        )

    page.on("websocket", count)
    page.on(
        "console",
        lambda msg: msg.type == "error" and page.console_errors.append(msg.text),
    )
    try:
        open_notebook(page, lab, lab.long_plot)
        run_all_cells(page)
        ready = page.locator(".jp-OutputArea-output", has_text="LONG-READY")
        ready.wait_for(timeout=300000)
        page.ready_text = ready.inner_text()
        page.expected = lab.expected
        page.wait_for_function(
            "document.querySelector('.rbm-ts') && document.querySelector('.rbm-ts').rbmCharts"
            " && document.querySelector('.rbm-ts').rbmCharts.length === 1"
            " && document.querySelectorAll('.rbm-ts').length === 2",
            timeout=180000,
        )
        page.wait_for_timeout(1500)
        yield page
    except Exception:
        save("long_plot_failure.png", page.screenshot(full_page=True))
        print(lab.log_text())
        raise
    finally:
        context.close()


def _chart(page, expr):
    return page.evaluate(
        f"(() => {{ const u = document.querySelector('.rbm-ts').rbmCharts[0]; return {expr}; }})()"
    )


def _blue_columns(page) -> np.ndarray:
    """Per pixel column of the plot area, how many pixels of the line's colour."""
    x, y, w, h = _chart(
        page,
        "(() => { const r = u.over.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })()",
    )
    shot = png_pixels(page.screenshot(clip={"x": x, "y": y, "width": w, "height": h}))
    r, b = shot[..., 0], shot[..., 2]
    return ((b - r > 40) & (b > 150)).sum(axis=0)  # #1f77b4 and its antialiased edge


def test_a_long_recording_with_many_gaps_draws_every_sample(long_plot):
    page = long_plot
    ready = page.ready_text.split("LONG-READY")[1].split("\n")[0]
    fields = dict(part.split("=") for part in ready.split())
    samples, sent, runs = (int(fields[k]) for k in ("samples", "sent", "runs"))
    assert samples <= sent < samples + 1000
    assert float(fields["hours"]) >= 1.5
    assert runs > UPLOT_SPREAD_LIMIT  # what used to leave the panel empty
    save("long_plot.png", page.locator(".rbm-ts").first.screenshot())
    # every sample is in the chart, and the line was built (not thrown away)
    assert _chart(page, "u.data[0].length") == sent
    assert _chart(
        page, "u.series[1]._paths !== null && u.series[1]._paths.stroke !== null"
    )
    # at 1.6 h on ~1000 px a run of missing samples is narrower than a pixel:
    # clipping each would erase the samples around it, so none is (and there
    # are never more clipped spans than pixel columns)
    width = _chart(page, "u.bbox.width")
    assert _chart(page, "u.series[1]._paths.gaps.length") <= width + 1
    columns = _blue_columns(page)
    assert (columns > 0).mean() > 0.9, "the line should cover the plot's width"
    # zoomed in, the runs of missing samples are breaks in the line again
    _chart(page, "u.setScale('x', {min: 100, max: 130})")
    page.wait_for_timeout(300)
    save("long_plot_zoom.png", page.locator(".rbm-ts").first.screenshot())
    spans = _chart(page, "u.series[1]._paths.gaps.length")
    assert 0 < spans <= width + 1
    missing_in_view = _chart(
        page,
        "(() => { let n = 0; const y = u.data[1]; const x = u.data[0];"
        " for (let i = 0; i < x.length; i++) if (x[i] >= 100 && x[i] <= 130 && y[i] === undefined) n++;"
        " return n; })()",
    )
    assert missing_in_view > 0
    assert (_blue_columns(page) > 0).mean() > 0.5
    _chart(
        page,
        "u.setScale('x', {min: u.data[0][0], max: u.data[0][u.data[0].length - 1]})",
    )
    assert page.locator(".rbm-ts-error").count() == 0
    assert not page.errors
    assert not [e for e in page.console_errors if "Maximum call stack" in e]


def test_a_panel_that_cannot_draw_says_so_in_the_widget(long_plot):
    page = long_plot
    page.evaluate("window.rbmBreakPaths = true")
    # zoom in: uPlot rebuilds the line, and the canvas now refuses it
    _chart(page, "u.setScale('x', {min: 100, max: 200})")
    page.wait_for_selector(".rbm-ts-error", timeout=10000)
    text = page.locator(".rbm-ts-error").first.inner_text()
    save("long_plot_error.png", page.locator(".rbm-ts").first.screenshot())
    assert "left eye x" in text and "could not be drawn" in text
    assert "broken on purpose by the test" in text
    page.evaluate("window.rbmBreakPaths = false")


def test_attaching_a_player_shifts_the_axis_without_resending(long_plot):
    page = long_plot
    first_x = _chart(page, "u.data[0][0]")
    last_x = _chart(page, "u.data[0][u.data[0].length - 1]")
    before = page.received[0]
    assert before > 8 * 2_000_000  # the samples came over this websocket
    page.get_by_role("button", name="attach the player").click()
    page.wait_for_function(
        f"document.querySelector('.rbm-ts').rbmCharts[0].data[0][0] > {first_x}",
        timeout=30000,
    )
    page.wait_for_timeout(1000)
    # the view shifted what it holds by the 0.7 ms ...
    assert _chart(page, "u.data[0][0]") == pytest.approx(first_x + 0.0007, abs=1e-9)
    assert _chart(page, "u.data[0][u.data[0].length - 1]") == pytest.approx(
        last_x + 0.0007, abs=1e-9
    )
    # ... and the kernel sent a few kB of state, not the 30 MB of samples again
    assert page.received[0] - before < 20_000
    assert not page.errors


def _overview(page, expr):
    return page.evaluate(
        "(() => { const root = document.querySelectorAll('.rbm-ts')[1];"
        f" const u = root.rbmCharts[0]; return {expr}; }})()"
    )


def test_zooming_into_10_s_fetches_the_samples_there_at_full_resolution(long_plot):
    page = long_plot
    # what the kernel put in the widget for the 2 million samples: an overview
    # of overview_width columns, x and y as float64
    sent = page.ready_text.split("OVERVIEW-SENT")[1].split("\n")[0]
    fields = dict(part.split("=") for part in sent.split())
    assert int(fields["bytes"]) <= 16 * 5 * int(fields["width"])
    rows = _overview(page, "u.data[0].length")
    width = _overview(page, "u.bbox.width")
    # the whole 1.6 h as its M4 at this view's own pixel width (asked for
    # once the view knew it): per column at most first, last, min, max and
    # first missing sample, and a NaN row per pause
    resolution = page.evaluate("document.querySelectorAll('.rbm-ts')[1].rbmResolution")
    assert f"per pixel column ({int(width)} columns)" in resolution, resolution
    assert rows <= 5 * width + 100
    # only recorded samples, each with its own value
    t, x = np.load(page.expected).T
    xs, ys = _overview(
        page,
        "[Array.from(u.data[0]), u.data[1].map((v) => v === undefined ? null : v)]",
    )
    xs, ys = np.asarray(xs), np.array([np.nan if v is None else v for v in ys])
    recorded = np.isin(xs, t)
    assert recorded.sum() > 0.9 * rows and np.isnan(ys[~recorded]).all()
    np.testing.assert_array_equal(ys[recorded], x[np.searchsorted(t, xs[recorded])])
    # every pixel column's extremes of the full recording are in it
    column = np.minimum(
        ((t - t[0]) * width / (t[-1] - t[0])).astype(int), int(width) - 1
    )
    full_max = np.full(int(width), -np.inf)
    np.fmax.at(full_max, column, x)
    kept_max = np.full(int(width), -np.inf)
    np.fmax.at(kept_max, column[np.searchsorted(t, xs[recorded])], ys[recorded])
    np.testing.assert_array_equal(kept_max, full_max)
    start, end = 1000.0, 1010.0
    _overview(page, f"u.setScale('x', {{min: {start}, max: {end}}})")
    page.wait_for_function(
        "(() => { const w = document.querySelectorAll('.rbm-ts')[1].rbmWindow;"
        f" return w && w.start === {start} && w.end === {end}; }})()",
        timeout=30000,
    )
    page.wait_for_timeout(300)
    save("long_plot_overview_zoom.png", page.locator(".rbm-ts").nth(1).screenshot())
    shown_x, shown_y = _overview(
        page,
        f"(() => {{ const xs = [], ys = []; for (let i = 0; i < u.data[0].length; i++)"
        f" if (u.data[0][i] >= {start} && u.data[0][i] <= {end})"
        " { xs.push(u.data[0][i]); ys.push(u.data[1][i] === undefined ? null : u.data[1][i]); }"
        " return [xs, ys]; })()",
    )
    shown_x = np.asarray(shown_x)
    shown_y = np.array([np.nan if v is None else v for v in shown_y])
    inside = (t >= start) & (t <= end)
    assert inside.sum() > 2500  # ~340 samples a second, a few pauses
    real = np.isin(shown_x, t[inside])
    # every sample of the recording there, with its own value (NaN where missing) ...
    np.testing.assert_array_equal(shown_x[real], t[inside])
    np.testing.assert_array_equal(shown_y[real], x[inside])
    # ... and nothing else but the NaN rows that mark a pause in the timestamps
    assert np.isnan(shown_y[~real]).all()
    # the line is drawn there, and a double-click goes back to the envelope
    assert _overview(page, "u.series[1]._paths !== null")
    _overview(
        page,
        "u.setScale('x', {min: u.data[0][0], max: u.data[0][u.data[0].length - 1]})",
    )
    page.wait_for_function(
        "document.querySelectorAll('.rbm-ts')[1].rbmWindow === null", timeout=30000
    )
    assert _overview(page, "u.data[0].length") == rows
    assert not page.errors
