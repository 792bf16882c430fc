"""A scene's path is simplified to what shows on screen, its gaps kept.

``simplify_path`` against a plain brute-force check: every sample lies within
the tolerance of the line drawn, the points drawn are samples of the
recording, runs of missing samples break the line, and the bytes of a path do
not grow with the recording's length.
"""

from __future__ import annotations

import numpy as np
import pytest
import umsgpack

import rbm_nb as rbm
from rbm_nb.scene import Scene
from rbm_nb.scene.decimate import PATH_TOLERANCE, simplify_path

pytestmark = pytest.mark.usefixtures("recording_comm")


def distance_to_polyline(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Naive twin: each point's distance to the nearest segment of ``line``."""
    best = np.full(len(points), np.inf)
    for a, b in zip(line[:-1], line[1:], strict=True):
        d = b - a
        length2 = d @ d
        t = (
            np.zeros(len(points))
            if length2 == 0
            else np.clip((points - a) @ d / length2, 0, 1)
        )
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * d), axis=1))
    if len(line) == 1:
        best = np.linalg.norm(points - line[0], axis=1)
    return best


def walk(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.normal(size=(n, 3)) * [0.01, 0.01, 0.002], axis=0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_sample_is_within_the_tolerance_of_the_line(seed):
    points = walk(5000, seed)
    tolerance = 0.05
    [line], error = simplify_path(points, tolerance, max_points=5000)
    assert error <= tolerance
    assert len(line) < len(points) / 3  # it did reduce
    assert distance_to_polyline(points, line).max() <= tolerance + 1e-12
    # the points drawn are samples, in order, with both ends
    index = [int(np.flatnonzero((points == p).all(axis=1))[0]) for p in line]
    assert index == sorted(index) and index[0] == 0 and index[-1] == len(points) - 1


def test_the_budget_bounds_the_points_and_reports_the_error_left():
    points = walk(20000)
    [line], error = simplify_path(points, 1e-6, max_points=300)
    assert len(line) == 300
    # the error reported bounds every sample's distance to the line (its own segment's)
    assert 0 < distance_to_polyline(points, line).max() <= error + 1e-12


def test_missing_samples_break_the_line_unless_the_jump_cannot_be_seen():
    points = walk(3000)
    points[1000:1010] = np.nan  # lost tracking while walking on
    points[2000:2002] = np.nan
    points[2002:] += 5.0  # a visible jump across the second run ...
    points[1010:] -= points[1010] - points[999]  # ... and none across the first
    stretches, _ = simplify_path(points, 0.01, max_points=2000)
    assert len(stretches) == 2  # broken at the visible jump only
    assert np.isin(stretches[0], points[:2000]).all()
    np.testing.assert_array_equal(stretches[1][0], points[2002])
    # with a tolerance below the hidden jump, both runs break the line
    jump = np.linalg.norm(points[1010] - points[999])
    assert len(simplify_path(points, jump / 2 if jump else 1e-9, 2000)[0]) in (2, 3)


def test_more_runs_than_the_budget_join_the_smallest_jumps():
    points = walk(10000)
    points[10::20] = np.nan  # 500 runs of missing samples
    stretches, _ = simplify_path(points, 1e-9, max_points=100)
    assert sum(len(s) for s in stretches) <= 100
    assert len(stretches) <= 50


def path_bytes(minutes: float) -> tuple[int, int, float]:
    rbm.clear_registry()
    rbm.register_frame("world")
    n = int(minutes * 60 * 200)
    ts = np.arange(n) / 200
    xyz = np.c_[np.cos(ts / 60) * 10, np.sin(ts / 45) * 10, np.zeros(n)]
    for start in range(60_000, n, 120_000):  # 10 s lost every 10 min, 1.7 m walked
        xyz[start : start + 2000] = np.nan
    rbm.register_frame("body", parent="world", timestamps=ts, translation=xyz)
    scene = Scene("world", grid=False)
    handle = scene.add_path("body", max_points=2000)
    [command] = [
        m
        for m in scene.state.snapshot()
        if m.path == handle.geom_path and m.op == "set_object"
    ]
    stretches, error = handle.stretches()
    scene.close()
    return len(command.data), len(stretches), error


def test_a_path_of_hours_sends_what_one_of_minutes_does():
    short, short_runs, short_error = path_bytes(10)
    long, long_runs, _ = path_bytes(180)
    # within the budget, the default tolerance: 1/2000 of the extent
    assert short_error <= PATH_TOLERANCE * np.linalg.norm([20, 20, 0])
    assert short_runs == 2 and long_runs == 19  # the gaps are kept ...
    assert long < 2000 * 2 * 12 + 10_000  # ... within the budget of points
    assert long < 180 * 60 * 200 * 12 / 500  # every sample as float32: 26 MB


def test_the_drawn_segments_stop_at_a_gap():
    rbm.register_frame("world")
    ts = np.arange(100) * 0.1
    xyz = np.c_[ts, np.zeros(100), np.zeros(100)]
    xyz[50:60] = np.nan
    xyz[60:, 1] = 1.0  # moved sideways while not tracked
    rbm.register_frame("body", parent="world", timestamps=ts, translation=xyz)
    scene = Scene("world", grid=False)
    handle = scene.add_path("body")
    [command] = [
        m
        for m in scene.state.snapshot()
        if m.path == handle.geom_path and m.op == "set_object"
    ]
    obj = umsgpack.unpackb(command.data)["object"]
    position = obj["geometries"][0]["data"]["attributes"]["position"]
    xyz = np.frombuffer(position["array"].data, "<f4").reshape(-1, 3)
    segments = xyz.reshape(-1, 2, 3)
    # no segment crosses the gap (x 4.9 .. 6.0)
    assert not ((segments[:, 0, 0] < 5.0) & (segments[:, 1, 0] > 5.5)).any()
    assert len(segments) == 2  # a straight line on each side
    scene.close()


def test_a_path_of_a_frame_with_objects_drawn_in_it_reuses_their_poses():
    rbm.register_frame("world")
    ts = np.arange(100) * 0.1
    rbm.register_frame(
        "body", parent="world", timestamps=ts, translation=np.c_[ts, ts, ts]
    )
    scene = Scene("world", grid=False)
    scene.add_frame("body", base="body")  # an object that moves with the body
    path = scene.add_path("body")
    # no second lookup: the path's samples are the anchor's poses, looked up
    # by the anchor's track when the line is drawn
    anchor = scene.state.tracks["/rbm/anchor_body"]
    assert path._samples is anchor
    np.testing.assert_array_equal(path.samples, np.c_[ts, ts, ts])
    scene.close()
