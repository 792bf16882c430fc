"""The explorer's 3D view of a long recording streams its poses (JupyterLab and Notebook 7).

The real head/eye recording (the synthetic one without ``RBM_NB_DATA_DIR``)
is tiled in time to 20 min and shown by ``explorer_scene()`` with a Player,
in chromium with every port but Jupyter's blocked. Checked: the page got a
coarse copy of the poses and the chunking, not the poses; playing at 4x across
a chunk boundary, every frame shows the head's recorded pose at the time
shown (full resolution, no coarse frame: the next chunk was there before the
playhead); at 10x the clock keeps up and the page holds a bounded window of
chunks. Frames per second at 1x and 10x are printed (no thresholds here;
``benchmarks/bench_scene_scale.py`` has the bytes).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

pytestmark = [pytest.mark.browser, pytest.mark.slow, pytest.mark.timeout(600)]

from browser_support import (  # noqa: E402
    REPO,
    new_context,
    open_notebook,
    our_errors,
    run_until,
    save,
    write_notebook,
)

REAL_DATA = (
    Path(os.environ.get("RBM_NB_SHARED", REPO.parent / "shared")) / "data" / "rbm-data"
)
SHOTS = Path("/work/shots/issue-35s")
MINUTES = 20
ANCHOR = "/rbm/anchor_head"

SETUP = f"""
import numpy as np
import ipywidgets as widgets
from rbm_nb import explorer

def tiled(ds, minutes):
    time = ds.time.values
    period = (time[-1] - time[0]) + np.timedelta64(5, "ms")
    tiles = int(np.ceil(minutes * 60e9 / period.astype("timedelta64[ns]").astype(np.int64)))
    import xarray as xr
    return xr.concat([ds.assign_coords(time=time + k * period) for k in range(tiles)], dim="time")

head, left, right, note = explorer.load_head_eye()
head, left, right = (tiled(ds, {MINUTES}) for ds in (head, left, right))
explorer.register_head_eye_frames(head, left, right)
scene = explorer.explorer_scene()
player = scene.player()
track = scene.state.tracks["{ANCHOR}"]
keys, translation, _, _ = track.take(None)  # every sample, looked up whole
seconds = (keys - scene.state.base.t0_ns) / 1e9  # from the scene's second 0
np.save(EXPECTED, np.c_[seconds, translation])
print("STREAM-READY", note[:40])
widgets.VBox([scene.widget, player])
"""


@pytest.fixture(params=["lab", "notebook"])
def streamed(request, browser, jupyter_server, tmp_path):

    app = request.param
    server = jupyter_server(app)
    env = {"RBM_NB_DATA_DIR": str(REAL_DATA)} if REAL_DATA.is_dir() else {}
    expected = tmp_path / "expected.npy"
    name = server.add_notebook(
        write_notebook(
            tmp_path / "stream.ipynb",
            [SETUP.replace("EXPECTED", repr(str(expected)))],
            server.kernel_with_env(env),
        )
    )
    context, blocked = new_context(
        browser, server, viewport={"width": 1200, "height": 900}
    )
    page = context.new_page()
    page.app, page.expected, page.blocked = app, expected, blocked
    page.server = server
    try:
        open_notebook(page, server, name)
        run_until(page, 0, "STREAM-READY")
        page.wait_for_function(
            """() => { const el = document.querySelector('.rbm-scene');
                       return el && el.rbmView && el.rbmView.store.stream
                              && el.rbmView.player && el.rbmView.frames > 0
                              && el.rbmView.store.loaded.size >= 2; }""",
            timeout=120000,
        )
        yield page
    except Exception:
        save(f"scene_stream_{app}_failure.png", page.screenshot(full_page=True))
        print(server.log_text())
        raise
    finally:
        context.close()


def view(page, expr: str):
    return page.evaluate(
        f"(() => {{ const v = document.querySelector('.rbm-scene').rbmView; return {expr}; }})()"
    )


def seek(page, t: float) -> None:
    """Move the player so the view shows ``t`` (seconds from the scene's origin)."""
    view(
        page,
        f"""(() => {{ const p = v.player;
            const x = {t} - Number(v.model.get('_player_shift'));
            p.set('time', x); p.save_changes(); }})()""",
    )


# Recording starts the player itself, in the same turn as its first reading:
# started from Python, a busy page (chunks arriving) could let seconds of
# scene time pass before the first frame was recorded.
RECORD = """([seconds, path, speed]) => new Promise((done) => {
  const v = document.querySelector('.rbm-scene').rbmView;
  const node = v.node(path);
  const rows = [];
  v.player.set('speed', speed);
  v.player.set('playing', true);
  const start = performance.now();
  const frames = v.frames, coarse = v.coarseFrames, t0 = v.currentTime();
  function step() {
    if (v.shown) rows.push([v.shown.time, v.shown.coarse, node.visible ? 1 : 0,
                            node.position.x, node.position.y, node.position.z]);
    if (performance.now() - start < seconds * 1000) { requestAnimationFrame(step); return; }
    const wall = (performance.now() - start) / 1000;
    done({rows, wall, rendered: v.frames - frames, coarse: v.coarseFrames - coarse,
          advanced: v.currentTime() - t0});
  }
  requestAnimationFrame(step);
})"""


def expected_pose(table: np.ndarray, t: float) -> np.ndarray:
    i = np.searchsorted(table[:, 0], t + 1e-6, side="right") - 1
    if i < 0:  # before the head's first sample: nothing shown
        return np.full(3, np.nan)
    return table[i, 1:]


def test_playing_across_a_chunk_boundary_shows_the_recording(streamed):
    page = streamed
    table = np.load(page.expected)
    plan = view(page, "v.store.stream")
    whole = view(page, f"v.store.tracks.get('{ANCHOR}').whole.times.length")
    # the page got a coarse copy and the chunking, not the 20 min of poses
    assert plan["count"] >= 10 and whole == 2000 < len(table) / 100
    # play at 4x from the start: 5 s of wall time cross the first boundary
    received = view(page, "v.store.chunksReceived")
    seek(page, 0.0)
    page.wait_for_function(
        "() => { const v = document.querySelector('.rbm-scene').rbmView;"
        " return v.shown && v.shown.time < 1; }",
        timeout=30000,
    )
    run = page.evaluate(RECORD, [5.0, ANCHOR, 4])
    view(page, "v.player.set('playing', false)")
    rows = np.array(run["rows"])
    times = rows[:, 0]
    boundary = (np.floor(times[0] / plan["chunk"]) + 1) * plan["chunk"]
    print(
        f"{page.app} 4x: {run['rendered'] / run['wall']:.1f} frames/s, "
        f"clock {run['advanced'] / run['wall']:.2f}x, coarse frames {run['coarse']}, "
        f"shown {times[0]:.2f}..{times[-1]:.2f} s, boundary {boundary:.2f} s"
    )
    # the playhead crossed the boundary, frames on both sides
    assert (times < boundary).sum() >= 5 and (times > boundary).sum() >= 5
    assert view(page, "v.store.chunksReceived") > received  # chunks came ahead of play
    # every frame: the chunk was there, the pose is the recording's
    assert (rows[:, 1] == 0).all(), rows[rows[:, 1] != 0][:5]
    for t, _, visible, *xyz in rows:
        want = expected_pose(table, t)
        if np.isnan(want).any():
            assert visible == 0
        else:
            assert visible == 1, (t, want)
            np.testing.assert_allclose(xyz, want, rtol=1e-6, atol=1e-5)
    # the clock did not wait for poses
    assert run["advanced"] == pytest.approx(4 * run["wall"], rel=0.25)
    # 1x, for the frame rate
    one = page.evaluate(RECORD, [3.0, ANCHOR, 1])
    view(page, "v.player.set('playing', false)")
    print(
        f"{page.app} 1x: {one['rendered'] / one['wall']:.1f} frames/s, "
        f"clock {one['advanced'] / one['wall']:.2f}x, coarse frames {one['coarse']}"
    )
    assert one["coarse"] == 0

    # 10x: the clock keeps up, the page holds a bounded window of chunks
    fast = page.evaluate(RECORD, [4.0, ANCHOR, 10])
    view(page, "v.player.set('playing', false)")
    held = view(page, "v.store.loaded.size")
    dropped = view(page, "v.store.chunksDropped")
    print(
        f"{page.app} 10x: {fast['rendered'] / fast['wall']:.1f} frames/s, "
        f"clock {fast['advanced'] / fast['wall']:.2f}x, coarse frames {fast['coarse']} "
        f"of {len(fast['rows'])}, chunks held {held}, dropped {dropped}"
    )
    heap = page.evaluate("performance.memory ? performance.memory.usedJSHeapSize : 0")
    print(f"{page.app}: page JS heap {heap / 1e6:.0f} MB after playing")
    assert fast["advanced"] == pytest.approx(10 * fast["wall"], rel=0.25)
    assert dropped > 0 and held <= 1 + 1 + 12
    canvas = page.locator(".rbm-scene canvas")
    shot = save(f"scene_stream_{page.app}.png", page.locator(".rbm-scene").screenshot())
    if SHOTS.is_dir():
        shutil.copy(shot, SHOTS / shot.name)
    assert canvas.count() == 1
    assert page.blocked == [], page.blocked
    ours = our_errors(page.errors, page.server)
    assert ours == [], ours
