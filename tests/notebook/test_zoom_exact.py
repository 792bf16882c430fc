"""The kernel's answers to a zoomed view: exact values at the cursor, finer paths.

A long TimeSeries goes to the browser as a min/max overview; the cursor's
readout asks the kernel for the recording's own sample nearest its time
(``TimeSeries.nearest_samples``, the ``exact`` comm request). A long 3D path
goes simplified for its whole extent; a zoomed camera asks for the line
through the box it sees at half a pixel (``rbm_nb.scene.path_refine``).
Checked against brute force, and with hostile requests that must be refused
or clamped without an exception reaching the comm.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.scene import Scene
from rbm_nb.scene.decimate import refine_region
from rbm_nb.scene.path_refine import MAX_POINTS, PathRefiner
from rbm_nb.widgets import TimeSeries

pytestmark = pytest.mark.usefixtures("recording_comm")


# -- exact values at the cursor ---------------------------------------------------
def long_series(n=200_000, seed=0):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.002, 0.008, n))
    t[n // 2 :] += 30.0  # a pause
    y = np.c_[np.cumsum(rng.normal(size=n)), rng.normal(size=n)]
    y[rng.random(n) < 0.05, 0] = np.nan  # missing samples
    return t, y


def nearest_row(t: np.ndarray, at: float) -> int:
    """Naive twin: the row of ``t`` nearest ``at`` (the earlier one on a tie)."""
    d = np.abs(t - at)
    return int(np.flatnonzero(d == d.min())[0])


def custom(comm, kind: str) -> list[tuple[dict, list[bytes]]]:
    """The custom messages of type ``kind`` the kernel sent, with their buffers."""
    out = []
    for data, buffers in comm.sent:
        content = (
            (data or {}).get("content")
            if (data or {}).get("method") == "custom"
            else None
        )
        if isinstance(content, dict) and content.get("type") == kind:
            out.append((content, buffers))
    return out


def exact_replies(plot):
    plot._last_exact.result(timeout=30)
    return custom(plot.comm, "exact")


def test_the_exact_value_at_a_cursor_time_is_the_recordings_sample():
    t, y = long_series()
    plot = TimeSeries({"a": (t, y, ["p", "q"])}, max_points=2000)
    assert plot.panels[0]["reduced"]  # the browser holds an overview only
    rng = np.random.default_rng(1)
    span = t[-1] - t[0]
    for at in [*rng.uniform(-5, span + 5, 200), span / 2 + 0.5, 0.0, span]:
        (x, values) = plot.nearest_samples(at)["a"]
        row = nearest_row(t - t[0], at)
        assert x == t[row] - t[0]
        np.testing.assert_array_equal(values, y[row])
    # the comm request carries a time; the reply the sample, bit for bit
    for k, at in enumerate([12.3456, span / 2 + 10.0, 1e300, -1e300]):
        plot.comm.receive({"type": "exact", "t": at, "id": k, "view": "v"})
        head, [buffer] = exact_replies(plot)[-1]
        assert head["id"] == k and head["t"] == at
        row = nearest_row(t - t[0], min(max(at, -1.0), span + 1.0))
        np.testing.assert_array_equal(
            np.frombuffer(buffer, np.float64), [t[row] - t[0], *y[row]]
        )
    plot.close()


def test_the_exact_value_of_datetime_samples_follows_a_linked_shift():
    t, y = long_series(20_000)
    stamps = np.datetime64("2020-02-02T00:00:00", "ns") + (t * 1e9).astype(
        "timedelta64[ns]"
    )
    plot = TimeSeries({"a": (stamps, y)}, max_points=100)
    at = 40.0
    (x, values) = plot.nearest_samples(at)["a"]
    seconds = (stamps - stamps[0]).astype(np.int64) / 1e9
    row = nearest_row(seconds, at)
    assert x == seconds[row]
    np.testing.assert_array_equal(values, y[row])
    plot.close()


@pytest.mark.parametrize(
    "bad",
    [
        {"type": "exact"},
        {"type": "exact", "t": float("nan")},
        {"type": "exact", "t": float("inf")},
        {"type": "exact", "t": "12"},
        {"type": "exact", "t": None},
        {"type": "exact", "t": [1.0]},
        {"type": "exact", "t": {"x": 1}},
    ],
)
def test_a_malformed_exact_request_gets_no_reply_and_breaks_nothing(bad):
    t, y = long_series(5000)
    plot = TimeSeries({"a": (t, y)}, max_points=100)
    plot.comm.receive(bad)
    assert not hasattr(plot, "_last_exact")
    plot.comm.receive({"type": "exact", "t": 3.0, "id": 7, "view": "v"})
    head, [buffer] = exact_replies(plot)[-1]
    assert head["id"] == 7
    plot.close()


# -- a path refined where the camera has zoomed in ----------------------------------
def segment_distance(points: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Naive twin: each point's distance to the nearest of the segments ``ends`` (m, 2, 3)."""
    best = np.full(len(points), np.inf)
    for a, b in ends:
        d = b - a
        length2 = d @ d
        s = (
            np.zeros(len(points))
            if length2 == 0
            else np.clip((points - a) @ d / length2, 0, 1)
        )
        best = np.minimum(best, np.linalg.norm(points - (a + s[:, None] * d), axis=1))
    return best


def long_path_scene(minutes=60):
    rbm.clear_registry()
    rbm.register_frame("world")
    n = int(minutes * 60 * 200)
    ts = np.arange(n) / 200
    rng = np.random.default_rng(0)
    xyz = np.c_[
        np.cos(ts / 60) * 10 + 0.01 * np.sin(ts * 7),
        np.sin(ts / 45) * 10 + np.cumsum(rng.normal(size=n)) * 1e-4,
        0.02 * np.sin(ts * 3),
    ]
    for start in range(60_000, n, 120_000):  # 10 s lost every 10 min
        xyz[start : start + 2000] = np.nan
    rbm.register_frame("body", parent="world", timestamps=ts, translation=xyz)
    scene = Scene("world", grid=False)
    handle = scene.add_path("body", max_points=2000)
    assert scene.widget is not None  # the view: its refiner answers the page
    refiner = scene._view.path_refiner
    assert isinstance(refiner, PathRefiner)
    return scene, handle, refiner, xyz


def decoded(head, buffers):
    return np.frombuffer(buffers[0], np.float32).reshape(-1, 2, 3).astype(np.float64)


def test_a_refined_region_keeps_every_sample_there_within_the_tolerance():
    scene, handle, refiner, xyz = long_path_scene()
    _, coarse_error = handle.stretches()
    # a box around a stretch of the path crossed by a gap (rows 60,000-62,000)
    centre = xyz[59_900]
    low, high = centre - 0.6, centre + 0.6
    tolerance = coarse_error / 64
    head, buffers = refiner.answer(
        {
            "type": "path_refine",
            "path": handle.name,
            "lo": low.tolist(),
            "hi": high.tolist(),
            "tolerance": tolerance,
            "id": 1,
            "view": "v",
        }
    )
    assert "refused" not in head, head
    assert head["tolerance"] <= tolerance and head["error"] <= head["tolerance"]
    ends = decoded(head, buffers)
    assert head["points"] - head["stretches"] == len(ends)
    assert head["points"] <= MAX_POINTS
    box_low, box_high = np.asarray(head["lo"]), np.asarray(head["hi"])
    inside = ((xyz >= box_low) & (xyz <= box_high)).all(axis=1)
    # snapped outward and clipped to the path: every sample asked for is in it
    asked = ((xyz >= low) & (xyz <= high)).all(axis=1)
    assert asked.any() and not (asked & ~inside).any()
    assert inside.sum() > 2000
    # every recorded sample in the box lies within the tolerance of the line
    # (float32 ends: a micrometre more at 10 m)
    far = segment_distance(xyz[inside], ends)
    assert far.max() <= head["tolerance"] + 2e-6
    # and the coarse line there did not: it is a refinement
    coarse = np.vstack(
        [np.repeat(p, 2, axis=0)[1:-1] for p in handle.stretches()[0] if len(p) > 1]
    ).reshape(-1, 2, 3)
    assert segment_distance(xyz[inside], coarse).max() > 4 * head["tolerance"]
    # the gap is kept: no segment joins the samples on its two sides
    before, after = xyz[59_999], xyz[62_000]
    assert inside[59_999] or inside[62_000]
    jump = np.linalg.norm(after - before)
    assert jump > head["tolerance"]
    lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    crossing = (np.linalg.norm(ends[:, 0] - before, axis=1) < 1e-5) & (
        np.linalg.norm(ends[:, 1] - after, axis=1) < 1e-5
    )
    assert not crossing.any() and lengths.max() < jump
    scene.close()


def test_refine_region_breaks_where_the_path_leaves_the_box():
    ts = np.linspace(0, 4 * np.pi, 4000)
    xyz = np.c_[np.cos(ts), np.sin(ts), np.zeros_like(ts)]
    low, high = np.array([0.5, -1.1, -1.0]), np.array([1.1, 1.1, 1.0])
    stretches, error = refine_region(xyz, low, high, 1e-4, 10_000)
    assert error <= 1e-4
    assert len(stretches) == 3  # two passes through the box and the start/end
    inside = ((xyz >= low) & (xyz <= high)).all(axis=1)
    ends = np.vstack([np.repeat(p, 2, axis=0)[1:-1] for p in stretches]).reshape(
        -1, 2, 3
    )
    assert segment_distance(xyz[inside], ends).max() <= 1e-4 + 1e-12


def test_an_answer_is_bounded_and_cached():
    scene, handle, refiner, xyz = long_path_scene()
    request = {
        "type": "path_refine",
        "path": handle.name,
        "lo": [-1e9] * 3,
        "hi": [1e9] * 3,
        "tolerance": 1e-12,
        "id": 2,
        "view": "v",
    }
    head, buffers = refiner.answer(request)
    # a huge box at a tiny tolerance: clipped to the path, clamped, bounded
    assert head["points"] <= MAX_POINTS
    assert len(buffers[0]) <= 2 * MAX_POINTS * 12
    assert head["tolerance"] > 1e-12
    assert max(abs(v) for v in head["lo"] + head["hi"]) < 100
    again, _ = refiner.answer(request)
    assert again["error"] == head["error"] and len(refiner._cache) == 1
    scene.close()


@pytest.mark.parametrize(
    "bad, why",
    [
        ({"path": "nope"}, "no path"),
        ({"path": None}, "no path"),
        ({"lo": [math.nan, 0, 0]}, "lo and hi"),
        ({"hi": [0, 0]}, "lo and hi"),
        ({"hi": "everything"}, "lo and hi"),
        ({"lo": [True, 0, 0]}, "lo and hi"),
        ({"lo": [5, 5, 5], "hi": [0, 0, 0]}, "lo must not exceed hi"),
        ({"tolerance": -1.0}, "tolerance"),
        ({"tolerance": 0}, "tolerance"),
        ({"tolerance": math.nan}, "tolerance"),
        ({"tolerance": math.inf}, "tolerance"),
        ({"tolerance": "1"}, "tolerance"),
    ],
)
def test_a_hostile_refine_request_is_refused_through_the_comm(bad, why):
    scene, handle, refiner, _ = long_path_scene(minutes=5)
    request = {
        "type": "path_refine",
        "path": handle.name,
        "lo": [0, 0, -1],
        "hi": [1, 1, 1],
        "tolerance": 1e-3,
        "id": 3,
        "view": "v",
        **bad,
    }
    comm = scene.widget.comm
    comm.receive(request)
    refiner._last_request.result(timeout=30)
    [(head, _)] = custom(comm, "path_refine")
    assert why in head["refused"] and refiner.refused == 1
    # the comm still answers
    comm.receive(
        {
            **request,
            **{
                "path": handle.name,
                "lo": [0, 0, -1],
                "hi": [1, 1, 1],
                "tolerance": 1e-3,
                "id": 4,
            },
        }
    )
    refiner._last_request.result(timeout=30)
    replies = [m for m, _ in custom(comm, "path_refine")]
    assert replies[-1]["id"] == 4 and "refused" not in replies[-1]
    scene.close()


def test_the_page_learns_which_paths_it_may_refine():
    scene, handle, refiner, _ = long_path_scene(minutes=5)
    scene.widget.comm.receive({"type": "paths", "view": "v"})
    [(head, _)] = custom(scene.widget.comm, "paths")
    [path] = head["paths"]
    assert path["id"] == handle.name and path["node"] == handle.geom_path
    assert path["error"] > 0
    scene.close()
