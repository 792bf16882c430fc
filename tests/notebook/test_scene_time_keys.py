"""The scene keeps the core's time rule: exact keys, seconds only for the browser.

A float epoch second is ~0.24 µs coarse today (and ~1 µs in 2262): a scene
that counted its axis in them merged samples closer than that, showed the
wrong one, and sent the browser times off by up to a quarter microsecond
for a track starting after another. These tests fail on the float axis.
"""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.scene import Scene
from rbm_nb.scene.state import SceneState
from rbm_nb.scene.tracks import PoseTrack

ROOT = "/rbm"

#: a stamp whose epoch float is not exact (nanoseconds in every digit)
TODAY = np.datetime64("2020-02-02T00:27:14.123456789", "ns")
#: 8 ns before the last datetime64[ns] there is (2262-04-11T23:47:16.854775807)
LAST = np.datetime64(np.iinfo(np.int64).max - 8, "ns")


def ns(stamps) -> np.ndarray:
    return np.asarray(stamps).astype("datetime64[ns]").astype(np.int64)


def marching(timestamps) -> PoseTrack:
    """A body at x = its sample's index (identity rotation)."""
    n = len(timestamps)
    translation = np.c_[np.arange(n, dtype=float), np.zeros(n), np.zeros(n)]
    rotation = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    return PoseTrack(translation, rotation, timestamps, name="body")


def times_of(state: SceneState, path: str) -> np.ndarray:
    """The float64 seconds the browser gets for the track at ``path``."""
    meta, buffers = state.track_payload()
    entry = next(m for m in meta if m["path"] == path)
    return np.frombuffer(buffers[entry["times"]], dtype="<f8")


@pytest.mark.parametrize("first", [TODAY, LAST], ids=["2020", "2262"])
def test_samples_one_nanosecond_apart_stay_apart(first):
    stamps = first + np.arange(8) * np.timedelta64(1, "ns")
    state = SceneState()
    state.add_track(f"{ROOT}/body", marching(stamps))
    for k, stamp in enumerate(stamps):
        key = int(ns(stamp))
        assert state.pose_at(f"{ROOT}/body", key)[0, 3] == k
    # the browser's times: 1 ns steps from the first sample, not one float
    np.testing.assert_array_equal(times_of(state, f"{ROOT}/body"), np.arange(8) / 1e9)
    keys, original = state.timeline()
    np.testing.assert_array_equal(original, stamps)
    assert len(np.unique(keys)) == 8


@pytest.mark.usefixtures("recording_comm")
@pytest.mark.parametrize("first", [TODAY, LAST], ids=["2020", "2262"])
def test_set_time_to_a_nanosecond_shows_that_sample(first):
    stamps = first + np.arange(8) * np.timedelta64(1, "ns")
    rbm.register_frame("world")
    with Scene("world", grid=False) as scene:
        points = np.c_[np.arange(8.0), np.zeros(8), np.zeros(8)]
        scene.add_points(points, timestamps=stamps, label="dot")
        widget = scene.widget  # the browser's time: seconds from the first sample
        for k in (0, 3, 7):
            scene.set_time(stamps[k])
            assert widget.time == k / 1e9
            assert scene.timestamps[k] == stamps[k]
        scene.publish(5)  # sample 5 of the axis, not the last of one float
        assert widget.time == 5 / 1e9
        scene.set_time(1e300)  # a float epoch second far away: kept to the end
        assert widget.time == 7 / 1e9
        scene.set_time(-1e300)  # one span before the start (all hidden)
        assert widget.time < 0


def test_a_clock_starting_0_7_ms_later_gets_exact_seconds():
    head = TODAY + np.arange(50) * np.timedelta64(5, "ms")
    # the eye's clock starts 0.7 ms (and 1 ns) after the head's
    eye = (
        TODAY + np.timedelta64(700_001, "ns") + np.arange(50) * np.timedelta64(5, "ms")
    )
    state = SceneState()
    state.add_track(f"{ROOT}/head", marching(head))
    state.add_track(f"{ROOT}/eye", marching(eye))
    exact = (ns(eye) - ns(TODAY)) / 1e9  # int64 difference, then one division
    np.testing.assert_array_equal(times_of(state, f"{ROOT}/eye"), exact)
    # every chunk holds the sample shown at its start, whatever the epoch
    chunk = 0.0123
    for k in range(state.chunk_count(chunk)):
        meta, buffers = state.track_chunk(k, chunk)
        entry = next(m for m in meta if m["path"] == f"{ROOT}/eye")
        times = np.frombuffer(buffers[entry["times"]], dtype="<f8")
        start = k * chunk
        if exact[0] <= start:
            assert times[0] <= start < times[1] if len(times) > 1 else True
        assert set(times) <= set(exact)


def test_tracks_one_nanosecond_apart_do_not_share_an_axis():
    a = TODAY + np.arange(4) * np.timedelta64(10, "ms")
    b = a + np.timedelta64(1, "ns")
    state = SceneState()
    state.add_track(f"{ROOT}/a", marching(a))
    state.add_track(f"{ROOT}/b", marching(b))
    _, original = state.timeline()
    assert original is None  # not a's stamps: b's differ
    meta, buffers = state.track_payload()
    assert meta[0]["times"] != meta[1]["times"]  # two time buffers
    np.testing.assert_array_equal(
        np.frombuffer(buffers[meta[1]["times"]], dtype="<f8"), (ns(b) - ns(a[0])) / 1e9
    )


@pytest.mark.usefixtures("recording_comm")
def test_a_player_on_another_clock_is_shifted_exactly():
    from rbm_nb.widgets import Player

    head = TODAY + np.arange(50) * np.timedelta64(5, "ms")
    eye = head + np.timedelta64(700_001, "ns")  # its clock starts 0.7 ms + 1 ns later
    rbm.register_frame("world")
    with Scene("world", grid=False) as scene:
        points = np.c_[np.arange(50.0), np.zeros(50), np.zeros(50)]
        scene.add_points(points, timestamps=head, label="head")
        widget = scene.widget
        player = Player(eye)
        player.link(scene)
        # what the browser adds the player's time to: int64 ns subtracted first
        assert widget._player_shift == 700_001 / 1e9
        # the float epoch seconds the browser had differ from it
        assert player.origin - widget._origin != 700_001 / 1e9
        player.unlink(scene)
        assert widget._player_shift is None
        # an HTML export with that player counts from its second 0 too
        from rbm_nb.scene.export import build_document

        document = build_document(scene, player=player)
        state = document["models"][0]["state"]
        assert state["_player_shift"] == 700_001 / 1e9
        player.close()


@pytest.mark.usefixtures("recording_comm")
@pytest.mark.parametrize(
    "first", [TODAY, LAST - np.timedelta64(1, "s")], ids=["2020", "2262"]
)
def test_a_samples_own_epoch_float_finds_that_sample(first):
    # Scene.time and JavaScript hand out float epoch seconds: ~0.24 us (2020)
    # to ~1 us (2262) coarse; set back, each still shows its own sample
    stamps = first + np.arange(200) * np.timedelta64(5_000_001, "ns")
    rbm.register_frame("world")
    with Scene("world", grid=False) as scene:
        points = np.c_[np.arange(200.0), np.zeros(200), np.zeros(200)]
        scene.add_points(points, timestamps=stamps, label="dot")
        widget = scene.widget
        exact = (ns(stamps) - ns(stamps[0])) / 1e9
        for k in range(200):
            scene.set_time(float(ns(stamps[k])) / 1e9)
            shown = int(np.searchsorted(exact, widget.time + 1e-6, side="right")) - 1
            assert shown == k
            assert abs(widget.time - exact[k]) < 5e-6  # within an ulp of the float
