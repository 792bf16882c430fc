"""SceneState: what a scene contains and its poses over time, as plain data.

No frames, no widget, no comm: tracks are built by hand and the state is
checked directly (issue 13, item 4).
"""

from __future__ import annotations

import numpy as np
import pytest
import umsgpack

from rbm_nb.scene.commands import meshcat_geometry
from rbm_nb.scene.state import ROOT, SceneState
from rbm_nb.scene.tracks import PoseTrack


def moving_track(ts, x0=0.0):
    n = len(ts)
    rotation = np.zeros((n, 4))
    rotation[:, 0] = 1.0
    return PoseTrack(np.c_[x0 + np.asarray(ts), np.zeros(n), np.zeros(n)], rotation, ts)


def test_snapshot_rebuilds_from_nothing_and_delete_forgets_a_subtree():
    state = SceneState()
    g = meshcat_geometry()
    state.set_object(f"{ROOT}/a/geom", g.triad(1.0))
    state.set_object(f"{ROOT}/b/geom", g.triad(1.0))
    state.set_static(f"{ROOT}/a", np.eye(4))
    state.set_property(f"{ROOT}/a", "visible", False)
    state.add_track(f"{ROOT}/b/pose", moving_track([0.0, 1.0]))
    kinds = [umsgpack.unpackb(m.data)["type"] for m in state.snapshot()]
    assert kinds[0] == "delete"  # a fresh view starts from nothing
    assert kinds.count("set_object") == 2 and "set_property" in kinds
    message = state.delete(f"{ROOT}/a")
    assert umsgpack.unpackb(message.data) == {"type": "delete", "path": f"{ROOT}/a"}
    assert list(state.objects) == [f"{ROOT}/b/geom"]
    assert state.statics == {} and state.properties == {}
    state.delete(f"{ROOT}/b")
    assert state.tracks == {} and state.kind is None


def test_poses_over_time_hidden_before_the_start_and_pins():
    state = SceneState()
    state.set_static(f"{ROOT}/anchor", np.eye(4))
    state.add_track(f"{ROOT}/anchor/body", moving_track([1.0, 2.0, 3.0], x0=10.0))
    assert state.pose_at(f"{ROOT}/anchor/body", 0.5) is None  # not started yet
    assert (
        state.pose_at(f"{ROOT}/anchor/body", 2.5)[0, 3] == 12.0
    )  # latest at or before
    assert state.world_pose(f"{ROOT}/anchor/body/geom", 3.0)[0, 3] == 13.0
    state.pins[f"{ROOT}/anchor/body"] = 1.0  # shown at its own time
    assert state.pose_at(f"{ROOT}/anchor/body", 3.0)[0, 3] == 11.0
    assert state.pose_at(f"{ROOT}/nothing", 3.0).tolist() == np.eye(4).tolist()


def test_timeline_is_shared_or_a_grid_and_the_origin_is_its_start():
    state = SceneState()
    assert state.timeline() is None and state.origin == 0.0
    state.add_track("/rbm/a", moving_track([1.0, 1.5, 2.0]))
    state.add_track("/rbm/b", moving_track([1.0, 1.5, 2.0]))
    seconds, _ = state.timeline()
    np.testing.assert_array_equal(seconds, [1.0, 1.5, 2.0])
    state.add_track("/rbm/c", moving_track([0.5, 0.6, 0.7]))
    seconds, original = state.timeline()
    assert original is None and seconds[0] == 0.5 and seconds[-1] == 2.0
    assert np.diff(seconds).max() <= 0.1 + 1e-12
    assert state.origin == 0.5


def test_track_payload_buffers_and_decimation():
    state = SceneState()
    ts = np.arange(100) * 0.01 + 5.0
    state.add_track("/rbm/a", moving_track(ts))
    state.add_track("/rbm/b", moving_track(ts, x0=1.0))
    meta, buffers = state.track_payload()
    assert [m["times"] for m in meta] == [0, 0]  # one shared time buffer
    times = np.frombuffer(buffers[0], "<f8")
    np.testing.assert_allclose(times, ts - 5.0)  # seconds from the origin
    xyz = np.frombuffer(buffers[meta[1]["translation"]], "<f4").reshape(-1, 3)
    np.testing.assert_allclose(xyz[:, 0], ts + 1.0, rtol=1e-6)
    xyzw = np.frombuffer(buffers[meta[0]["rotation"]], "<f4").reshape(-1, 4)
    assert (xyzw[:, 3] == 1.0).all()  # three.js order: w last
    meta, buffers = state.track_payload(max_samples=10)
    times = np.frombuffer(buffers[0], "<f8")
    assert len(times) == 10 and times[0] == 0.0 and times[-1] == pytest.approx(0.99)
    with pytest.raises(ValueError, match="at least 2"):
        state.track_payload(max_samples=1)


def test_mixing_datetime_and_float_tracks_is_refused():
    state = SceneState()
    state.add_track("/rbm/a", moving_track([0.0, 1.0]))
    stamps = np.datetime64("2020-01-01") + np.arange(2) * np.timedelta64(1, "s")
    dated = PoseTrack(np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 1)), stamps)
    with pytest.raises(
        ValueError,
        match="cannot match datetime64 timestamps with numeric",
    ):
        state.add_track("/rbm/b", dated, "scene 'x'")
    with pytest.raises(ValueError, match="does not move"):
        state.add_track("/rbm/c", PoseTrack(np.zeros(3), [1.0, 0, 0, 0]))
