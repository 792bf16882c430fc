"""Zooming into a long recording in chromium (JupyterLab and Notebook 7).

The real head recording (the synthetic one without ``RBM_NB_DATA_DIR``) is
tiled in time to 30 min: a TimeSeries of the head's position goes as its
min/max overview, and a Scene draws the head's path simplified for its whole
extent. Every port but Jupyter's is blocked. Checked:

- hovering over the overview, the readout first marks the overview's kept
  sample as approximate ("≈"), then shows the recording's own sample nearest
  the cursor's time (its time and values, bit for bit), fetched from the
  kernel; zoomed in to full resolution, nothing is asked;
- zooming the camera into part of the path, the page asks the kernel for the
  line there at half a pixel and draws more vertices in view than the coarse
  line had; zoomed back out, the coarse line alone is drawn again.

Latencies (hover to exact readout, camera settled to refined path) are
printed, not asserted.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(900)]

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
SHOTS = Path("/work/shots/issue-35z")
MINUTES = 30

SETUP = f"""
import numpy as np
import xarray as xr
import ipywidgets as widgets
import rbm_nb as rbm
from rbm_nb import explorer
from rbm_nb.scene import Scene
from rbm_nb.widgets import TimeSeries

def tiled(ds, minutes):
    time = ds.time.values
    period = (time[-1] - time[0]) + np.timedelta64(5, "ms")
    tiles = int(np.ceil(minutes * 60e9 / period.astype("timedelta64[ns]").astype(np.int64)))
    return xr.concat([ds.assign_coords(time=time + k * period) for k in range(tiles)], dim="time")

head, _, _, note = explorer.load_head_eye()
head = tiled(head, {MINUTES})
rbm.clear_registry()
rbm.register_frame("world")
rbm.register_frame("head", parent="world", timestamps=head.time.values,
                   translation=head.position.values, rotation=head.orientation.values)
plot = TimeSeries({{"head position": head.position}}, title="head, {MINUTES} min", panel_height=160)
scene = Scene("world", grid=False)
path = scene.add_path("head", max_points=2000)
seconds = (head.time.values.astype("datetime64[ns]").astype(np.int64) - plot.t0_ns) / 1e9
np.save(EXPECTED, np.c_[seconds, head.position.values])
print("ZOOM-READY", plot.panels[0]["reduced"], plot.panels[0]["samples"], path.geom_path)
widgets.VBox([plot, scene.widget])
"""

# a slow kernel: the worker that answers the cursor's requests is held for 6 s
# (comm messages are heard while a cell runs, so a busy cell would not do)
BUSY = (
    "import time\n"
    "plot._exact.submit('busy', lambda cancelled: time.sleep(6), lambda result: None)\n"
    "print('BUSY-STARTED')"
)


@pytest.fixture(params=["lab", "notebook"])
def zoomed(request, browser, jupyter_server, tmp_path):

    app = request.param
    server = jupyter_server(app)
    env = {"RBM_NB_DATA_DIR": str(REAL_DATA)} if REAL_DATA.is_dir() else {}
    expected = tmp_path / "expected.npy"
    name = server.add_notebook(
        write_notebook(
            tmp_path / "zoom.ipynb",
            [SETUP.replace("EXPECTED", repr(str(expected))), BUSY],
            server.kernel_with_env(env),
        )
    )
    context, blocked = new_context(
        browser, server, viewport={"width": 1200, "height": 1000}
    )
    page = context.new_page()
    page.app, page.expected, page.blocked = app, expected, blocked
    page.jupyter_static = f"{server.base}static/"
    try:
        open_notebook(page, server, name)
        page.ready_text = run_until(page, 0, "ZOOM-READY")
        page.wait_for_function(
            """() => { const ts = document.querySelector('.rbm-ts');
                       const sc = document.querySelector('.rbm-scene');
                       return ts && ts.rbmCharts && ts.rbmCharts.length === 1 && ts.rbmExact
                              && sc && sc.rbmView && sc.rbmView.frames > 0; }""",
            timeout=120000,
        )
        yield page
    except Exception:
        save(f"zoom_exact_{app}_failure.png", page.screenshot(full_page=True))
        print(server.log_text())
        raise
    finally:
        context.close()


def shot(page, name: str, locator) -> None:
    path = save(f"zoom_exact_{page.app}_{name}.png", locator.screenshot())
    if SHOTS.is_dir():
        shutil.copy(path, SHOTS / path.name)


def chart(page, expr: str):
    return page.evaluate(
        "(() => { const root = document.querySelector('.rbm-ts');"
        f" const u = root.rbmCharts[0]; return {expr}; }})()"
    )


def hover(page, share: float, nudge: float = 0.0) -> float:
    """Move the mouse over the plot at ``share`` of its width; the time there.

    The mouse lands on whole pixels, where an overview's pixel columns meet
    and the samples it keeps (each column's first and last) are the
    recording's nearest. ``nudge`` pixels more (as a zoomed page's
    fractional mouse positions) move the cursor into a column, where the
    nearest sample is seldom one the overview kept.
    """
    page.locator(".rbm-ts").scroll_into_view_if_needed()
    box = page.locator(".rbm-ts .u-over").first.bounding_box()
    x = round(box["x"] + share * box["width"])
    page.mouse.move(x, box["y"] + box["height"] / 2)
    if nudge:
        chart(
            page,
            f"u.setCursor({{left: u.cursor.left + {nudge}, top: u.cursor.top}})",
        )
    return chart(page, "u.posToVal(u.cursor.left, 'x')")


def legend(page) -> list[str]:
    return chart(
        page,
        "Array.from(u.root.querySelectorAll('.u-legend .u-value')).map((e) => e.textContent)",
    )


def hover_dots(page, x: float | None = None, values=None) -> list:
    """Each line's hover dot: [its centre as drawn, where the sample is] (CSS px).

    The sample is ``(x, values)``, default the one uPlot's cursor picked in
    the data here (for an overview, its kept sample).
    """
    return page.evaluate(
        """([x, values]) => {
          const u = document.querySelector('.rbm-ts').rbmCharts[0];
          const over = u.over.getBoundingClientRect();
          const pts = Array.from(u.root.querySelectorAll('.u-cursor-pt'));
          return pts.map((pt, k) => {
            const si = k + 1;
            const r = pt.getBoundingClientRect();
            const sx = x === null ? u.data[0][u.cursor.idx] : x;
            const sy = x === null ? u.data[si][u.cursor.idx] : values[k];
            return [[r.left + r.width / 2 - over.left, r.top + r.height / 2 - over.top],
                    [u.valToPos(sx, 'x'), u.valToPos(sy, u.series[si].scale)]];
          });
        }""",
        [x, None if values is None else [float(v) for v in values]],
    )


def dots_at(dots) -> bool:
    """Whether every dot is drawn on its sample (to the pixel uPlot rounds to)."""
    return bool(dots) and all(
        abs(a[0] - b[0]) <= 1.5 and abs(a[1] - b[1]) <= 1.5 for a, b in dots
    )


def exact_shown(page, t: float) -> bool:
    return page.evaluate(
        "(t) => { const s = document.querySelector('.rbm-ts').rbmExact.shown;"
        " return !!(s && s.t === t && s.panels && s.panels.every((p) => p.exact)); }",
        t,
    )


def nearest(table: np.ndarray, t: float) -> np.ndarray:
    d = np.abs(table[:, 0] - t)
    return table[int(np.flatnonzero(d == d.min())[0])]


def test_hovering_over_a_long_overview_shows_the_exact_recording_value(zoomed):
    page = zoomed
    table = np.load(page.expected)
    assert " True " in page.ready_text  # the panel went as its overview
    # the kernel slow to answer: the readout shows the overview's kept
    # sample, marked approximate
    busy = page.locator(".jp-Notebook .jp-CodeCell").nth(1)
    busy.locator(".jp-InputArea-editor").click()
    page.keyboard.press("Shift+Enter")
    page.locator(".jp-OutputArea-output", has_text="BUSY-STARTED").wait_for(
        timeout=60000
    )
    t = hover(page, 0.4137, nudge=0.5)
    page.wait_for_timeout(300)
    waiting = legend(page)
    shot(page, "readout_waiting", page.locator(".rbm-ts"))
    assert waiting and all(v.startswith("\u2248") for v in waiting), waiting
    assert not exact_shown(page, t)
    # the hover dots sit on the sample the readout shows: the kept one, yet
    assert dots_at(hover_dots(page)), hover_dots(page)
    # once the kernel's worker is free, the recording's own sample arrives
    page.wait_for_function(
        "(t) => { const s = document.querySelector('.rbm-ts').rbmExact.shown;"
        " return s && s.t === t && s.panels && s.panels.every((p) => p.exact); }",
        arg=t,
        timeout=30000,
    )
    shot(page, "readout_exact", page.locator(".rbm-ts"))
    shown = page.evaluate("document.querySelector('.rbm-ts').rbmExact.shown")
    [panel] = shown["panels"]
    want = nearest(table, t)
    assert panel["x"] == want[0]
    np.testing.assert_array_equal(panel["values"], want[1:])
    assert not any(v.startswith("\u2248") for v in legend(page))
    # ... and now on the recording's own sample, as the readout
    dots = hover_dots(page, want[0], want[1:])
    assert dots_at(dots), dots
    kept_dots = hover_dots(page)  # where the kept sample is
    moved = [
        not dots_at([[a, k[1]]]) for (a, _), k in zip(dots, kept_dots, strict=True)
    ]
    # the overview's kept sample there was not the recording's at that time
    kept = chart(page, "[u.data[0][u.cursor.idx], u.data[1][u.cursor.idx]]")
    print(
        f"{page.app}: cursor t={t:.6f} s, recording's sample at {want[0]:.6f} s "
        f"x={want[1]!r}; overview's kept sample at {kept[0]:.6f} s x={kept[1]!r}"
    )
    # more positions, with the kernel idle: the latency of the exact readout
    differed = []
    for share, nudge in [(s, 0.0) for s in (0.1, 0.25, 0.55, 0.7, 0.95)] + [
        (s, 0.5) for s in (0.17, 0.34, 0.62, 0.85)
    ]:
        t = hover(page, share, nudge)
        page.wait_for_function(
            "(t) => { const s = document.querySelector('.rbm-ts').rbmExact.shown;"
            " return s && s.t === t && s.panels && s.panels.every((p) => p.exact); }",
            arg=t,
            timeout=30000,
        )
        got = page.evaluate("document.querySelector('.rbm-ts').rbmExact.shown")
        want = nearest(table, t)
        assert got["panels"][0]["x"] == want[0]
        np.testing.assert_array_equal(got["panels"][0]["values"], want[1:])
        dots = hover_dots(page, want[0], want[1:])
        assert dots_at(dots), (t, dots)
        moved += [
            not dots_at([[a, k[1]]])
            for (a, _), k in zip(dots, hover_dots(page), strict=True)
        ]
        kept = chart(page, "[u.data[0][u.cursor.idx], u.data[1][u.cursor.idx]]")
        if kept[0] != want[0]:
            differed.append(
                (
                    nudge,
                    round(t, 3),
                    round(kept[0] - want[0], 3),
                    round(kept[1] - want[1], 4),
                )
            )
    # how often the dots left the overview's kept sample for the exact one by
    # more than a pixel and a half (this recording: 1-2 px at most, so not
    # asserted; the bundle before drew them on the kept sample, 1.9 px off
    # at t = 1701 s in JupyterLab, and failed the check above)
    print(
        f"{page.app}: hover dots moved off the kept sample: {sum(moved)} of {len(moved)}"
    )
    print(
        f"{page.app}: the overview's kept sample was not the recording's nearest at "
        f"{len(differed)} of 9 cursor times (nudge px, t, dt s, dx m): {differed}"
    )
    stats = page.evaluate("document.querySelector('.rbm-ts').rbmExact")
    idle = stats["latencyMs"][1:]  # the first waited for the busy cell
    print(
        f"{page.app}: exact readout latency (request to answer, kernel idle) "
        f"median {np.median(idle):.1f} ms, max {max(idle):.1f} ms over {len(idle)}; "
        f"asked {stats['asked']}, answered {stats['answered']}"
    )
    # zoomed to full resolution: the data here is exact, nothing is asked
    chart(page, "u.setScale('x', {min: 600, max: 605})")
    page.wait_for_function(
        "(() => { const w = document.querySelector('.rbm-ts').rbmWindow;"
        " return w && w.start === 600 && w.full.every(Boolean); })()",
        timeout=30000,
    )
    # (the mouse rested there while the window was on its way: that asked)
    page.wait_for_timeout(300)
    asked = page.evaluate("document.querySelector('.rbm-ts').rbmExact.asked")
    t = hover(page, 0.5)
    page.wait_for_timeout(500)
    assert page.evaluate("document.querySelector('.rbm-ts').rbmExact.asked") == asked
    values = legend(page)
    assert values and not any(v.startswith("\u2248") for v in values), values
    idx = chart(page, "u.cursor.idx")
    x_here = chart(page, f"u.data[0][{idx}]")
    assert x_here == nearest(table, t)[0]
    shot(page, "readout_zoomed", page.locator(".rbm-ts"))
    assert page.blocked == [], page.blocked


def scene(page, expr: str):
    return page.evaluate(
        f"(() => {{ const v = document.querySelector('.rbm-scene').rbmView; return {expr}; }})()"
    )


ZOOM = """([node, share, factor]) => {
  const v = document.querySelector('.rbm-scene').rbmView;
  const THREE = v.THREE;
  const line = v.refiner.source(v.refiner.paths.find((p) => p.node === node));
  const p = line.geometry.attributes.position.array;
  const i = 6 * Math.floor(share * (p.length / 6));
  line.updateMatrixWorld(true);
  const world = new THREE.Vector3(p[i], p[i + 1], p[i + 2]).applyMatrix4(line.matrixWorld);
  const camera = v.viewer.camera;
  const parent = camera.parent;
  const target = parent ? parent.worldToLocal(world.clone()) : world.clone();
  const offset = camera.position.clone().sub(v.viewer.controls.target).multiplyScalar(factor);
  v.viewer.controls.target.copy(target);
  camera.position.copy(target).add(offset);
  v.viewer.controls.update();
  v.viewer.set_dirty();
  return performance.now();
}"""


def test_zooming_the_camera_into_a_long_path_draws_it_finer_there(zoomed):
    page = zoomed
    page.locator(".rbm-scene").scroll_into_view_if_needed()
    # the camera settles: the page learns which paths it may refine
    page.wait_for_function(
        "() => { const r = document.querySelector('.rbm-scene').rbmView.refiner;"
        " return r.paths && r.paths.length === 1; }",
        timeout=60000,
    )
    node = scene(page, "v.refiner.paths[0].node")
    assert node in page.ready_text
    whole = scene(page, f"v.refiner.visibleVertices('{node}')")
    assert scene(page, "v.refiner.shown.size") == 0  # all in view: coarse is fine
    shot(page, "path_whole", page.locator(".rbm-scene"))
    # zoom onto a point in the middle of the path
    started = page.evaluate(ZOOM, [node, 0.5, 1 / 40])
    coarse = scene(page, f"v.refiner.visibleVertices('{node}')")
    page.wait_for_timeout(100)
    shot(page, "path_zoomed_coarse", page.locator(".rbm-scene"))
    page.wait_for_function(
        f"() => document.querySelector('.rbm-scene').rbmView.refiner.shown.has('{node}')",
        timeout=60000,
    )
    drawn_at = page.evaluate("performance.now()")
    page.wait_for_timeout(200)
    refined = scene(page, f"v.refiner.visibleVertices('{node}')")
    stats = scene(page, "v.refiner.stats")
    answer = scene(
        page,
        f"(() => {{ const a = v.refiner.shown.get('{node}').answer;"
        " return {points: a.points, tolerance: a.tolerance, error: a.error, lo: a.lo, hi: a.hi}; })()",
    )
    shot(page, "path_zoomed_refined", page.locator(".rbm-scene"))
    print(
        f"{page.app}: path vertices in view: whole {whole}, zoomed coarse {coarse}, "
        f"zoomed refined {refined} (answer {answer['points']} points within "
        f"{answer['error'] * 1000:.2f} mm, tolerance {answer['tolerance'] * 1000:.2f} mm); "
        f"request to answer {stats['latencyMs'][-1]:.0f} ms, zoom to drawn "
        f"{drawn_at - started:.0f} ms (of which {250} ms settling)"
    )
    assert refined > coarse
    assert answer["error"] <= answer["tolerance"]
    assert stats["refused"] == 0
    # zoomed back out, the coarse line alone
    scene(page, "v.applyCamera()")
    page.wait_for_function(
        f"() => !document.querySelector('.rbm-scene').rbmView.refiner.shown.has('{node}')",
        timeout=30000,
    )
    assert scene(page, "v.refiner.source(v.refiner.paths[0]).visible")
    assert scene(page, f"v.refiner.visibleVertices('{node}')") == whole
    # back in: the page's cache answers, no new request
    asked = stats["asked"]
    page.evaluate(ZOOM, [node, 0.5, 1 / 40])
    page.wait_for_function(
        f"() => document.querySelector('.rbm-scene').rbmView.refiner.shown.has('{node}')",
        timeout=30000,
    )
    assert scene(page, "v.refiner.stats.asked") == asked
    assert page.blocked == [], page.blocked
    ours = [
        (message, stack)
        for message, stack in page.errors
        if not all(
            page.jupyter_static in line
            for line in stack.splitlines()[1:]
            if "http" in line or "blob:" in line
        )
    ]
    assert ours == [], ours
