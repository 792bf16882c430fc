"""Player: time axis, linking by time, frame dropping with an injected clock,
widget state without a kernel, and bad input."""

from __future__ import annotations

import threading
import time
import uuid

import comm
import ipywidgets
import numpy as np
import pytest
import traitlets

import rbm_nb as rbm
from rbm_nb.widgets import Player


class RecordingComm:
    """Stands in for a kernel comm: widgets work and we see what they send."""

    kernel = "Truthy"

    def __init__(self, *args, **kwargs):
        self.comm_id = uuid.uuid4().hex  # unique, like a kernel's comms
        self.messages = []

    def open(self, *args, **kwargs):
        pass

    def on_msg(self, *args, **kwargs):
        pass

    def send(self, data=None, *args, **kwargs):
        self.messages.append(data)

    def close(self, *args, **kwargs):
        pass


@pytest.fixture(autouse=True)
def recording_comm(monkeypatch):
    comms = []

    def create_comm(**kwargs):
        c = RecordingComm()
        comms.append(c)
        return c

    monkeypatch.setattr(comm, "create_comm", create_comm)
    yield comms
    ipywidgets.Widget.close_all()  # no widget (or playback thread) outlives its test


class FakeClock:
    def __init__(self, now=100.0):
        self.now = now

    def __call__(self):
        return self.now


class TimeLinked:
    def __init__(self):
        self.times = []

    def set_time(self, t):
        self.times.append(t)


class IndexLinked:
    def __init__(self, timestamps=None):
        if timestamps is not None:
            self.timestamps = timestamps
        self.published = []

    def publish(self, idx):
        self.published.append(idx)


def player(ts, **kwargs):
    kwargs.setdefault("threaded", False)
    return Player(ts, **kwargs)


# -- time axis ------------------------------------------------------------------
@pytest.mark.parametrize(
    "ts, step, speed, expected",
    [
        (np.arange(11) * 0.1, 1, 1.0, 0.1),
        (np.arange(11) * 0.1, 2, 1.0, 0.2),
        (np.arange(11) * 0.1, 2, 0.5, 0.4),
        (np.arange(11) * 0.1, 1, 4.0, 0.025),
        (np.array([0.0, 0.1, 0.5, 1.0]), 1, 1.0, 1.0 / 3),
    ],
)
def test_interval_is_mean_difference_times_step_over_speed(ts, step, speed, expected):
    p = player(ts, step=step, speed=speed)
    assert p.interval == pytest.approx(expected)


def test_interval_of_datetime_timestamps_is_in_seconds():
    ts = np.datetime64("2020-02-02T00:27:14") + np.arange(100) * np.timedelta64(5, "ms")
    p = player(ts, step=2)
    assert p.interval == pytest.approx(0.010)
    assert p.timestamps_kind == "datetime"
    assert p.readout() == "0 / 99  2020-02-02 00:27:14.000"
    p.seek(50)
    assert p.readout() == "50 / 99  2020-02-02 00:27:14.250"
    assert p.timestamp == ts[50]


def test_max_rate_bounds_the_interval_but_not_the_playback_speed():
    ts = np.arange(1001) * 0.001  # 1 kHz
    clock = FakeClock()
    p = player(ts, clock=clock, max_rate=100)
    assert p.interval == pytest.approx(0.01)
    p.play()
    clock.now += 0.5
    p.tick()
    assert p.index == 500  # half a second of recording after half a second


def test_readout_of_float_timestamps():
    p = player(np.arange(5) * 0.5 + 10)
    p.seek(3)
    assert p.readout() == "3 / 4  11.500 s"
    assert p.time == 11.5


# -- navigation -------------------------------------------------------------------
def test_step_skip_and_clipping():
    p = player(np.arange(100) * 0.01, step=3, skip=20)
    p.step_forward()
    assert p.index == 3
    p.skip_forward()
    assert p.index == 23
    p.step_back()
    assert p.index == 20
    p.skip_back()
    p.skip_back()
    assert p.index == 0
    p.seek(1000)
    assert p.index == 99


def test_default_skip_is_ten_steps():
    assert player(np.arange(10.0), step=2).skip == 20


def test_seek_time_picks_latest_sample_at_or_before():
    p = player(np.array([0.0, 1.0, 2.0, 3.0]))
    p.seek_time(2.5)
    assert p.index == 2
    p.seek_time(2.0)
    assert p.index == 2
    p.seek_time(-5)
    assert p.index == 0


# -- linking ---------------------------------------------------------------------
def test_linked_objects_stay_in_sync_by_time():
    p = player(np.arange(0, 10, 1.0))
    by_time = p.link(TimeLinked())
    fast = p.link(IndexLinked(np.arange(0, 10, 0.25)))  # 4x the player's rate
    late = p.link(IndexLinked(np.arange(3.5, 10, 1.0)))  # starts later
    plain = p.link(IndexLinked())  # no timestamps: gets the player's index
    for idx in (2, 5, 9):
        p.seek(idx)
    assert by_time.times == [0.0, 2.0, 5.0, 9.0]
    assert fast.published == [0, 8, 20, 36]
    # nothing at or before t=0 and t=2; then the latest sample at or before t
    assert late.published == [1, 5]
    assert plain.published == [0, 2, 5, 9]


def test_link_publishes_each_index_once():
    p = player(np.arange(0, 10, 1.0))
    slow = p.link(IndexLinked(np.arange(0, 10, 2.0)))
    for idx in range(6):
        p.seek(idx)
    assert slow.published == [0, 1, 2]


def test_unlink():
    p = player(np.arange(5.0))
    obj = p.link(TimeLinked())
    p.unlink(obj)
    p.seek(3)
    assert obj.times == [0.0]
    assert p.linked == []


# -- playback with an injected clock ------------------------------------------------
def test_tick_follows_the_wall_clock():
    clock = FakeClock()
    p = player(np.arange(100) * 0.1, step=1, clock=clock)
    rec = p.link(IndexLinked())
    p.play()
    assert p.playing
    for k in range(1, 6):
        clock.now += 0.1
        assert p.tick()
        assert p.index == k
    assert rec.published == [0, 1, 2, 3, 4, 5]


def test_tick_respects_step_and_speed():
    clock = FakeClock()
    p = player(np.arange(100) * 0.1, step=3, speed=2.0, clock=clock)
    p.play()
    clock.now += 0.35  # 0.7 s of recording: 7 samples, rounded down to a step
    p.tick()
    assert p.index == 6
    clock.now += 0.05  # 0.8 s: still 6
    p.tick()
    assert p.index == 6
    clock.now += 0.05  # 0.9 s
    p.tick()
    assert p.index == 9


def test_slow_linked_object_makes_frames_drop_not_queue():
    clock = FakeClock()
    p = player(np.arange(1000) * 0.01, clock=clock)  # interval 10 ms

    class Slow:
        def __init__(self):
            self.published = []
            self.clock_at_publish = []

        def publish(self, idx):
            self.published.append(idx)
            self.clock_at_publish.append(clock.now)
            clock.now += 0.035  # each publish takes 3.5 intervals

    slow = Slow()
    p.link(slow)
    p.play()
    start = clock.now
    for _ in range(20):
        clock.now += p.interval  # the loop waits one interval between ticks
        p.tick()
    shown = np.array(slow.published[1:])  # [0] came from link()
    assert len(shown) == 20
    assert (np.diff(shown) >= 4).all()  # intermediate samples were dropped
    # each published sample is the one due by the wall clock when it was sent
    due = np.floor((np.array(slow.clock_at_publish[1:]) - start) / 0.01 + 1e-3).astype(
        int
    )
    np.testing.assert_array_equal(shown, due)
    p.pause()
    count = len(slow.published)
    for _ in range(5):
        clock.now += 1.0
        assert not p.tick()
    assert len(slow.published) == count  # no backlog after pause


def test_speed_change_while_playing_keeps_the_position():
    clock = FakeClock()
    p = player(np.arange(1000) * 0.01, clock=clock)
    p.play()
    clock.now += 1.0
    p.tick()
    assert p.index == 100
    p.speed = 4.0
    clock.now += 0.5
    p.tick()
    assert p.index == 300


def test_playback_stops_at_the_end_or_loops():
    clock = FakeClock()
    p = player(np.arange(10) * 0.1, step=4, clock=clock)
    p.play()
    clock.now += 5.0
    assert not p.tick()
    assert p.index == 8  # last index reachable in steps of 4
    assert not p.playing
    p.play()  # at the end: starts over
    assert p.index == 0 and p.playing

    looping = player(np.arange(10) * 0.1, clock=clock, loop=True)
    looping.play()
    clock.now += 5.0
    assert looping.tick()
    assert looping.index == 0 and looping.playing


def test_error_in_linked_object_pauses_and_is_shown():
    clock = FakeClock()
    p = player(np.arange(100) * 0.1, clock=clock)

    class Broken:
        def set_time(self, t):
            if t > 0.25:
                raise RuntimeError("boom")

    p.link(Broken())
    p.play()
    for _ in range(5):
        clock.now += 0.1
        p.tick()
    assert not p.playing
    assert isinstance(p.error, RuntimeError)
    assert "boom" in p._error.value and p._error.layout.display is None


def test_single_sample_cannot_play():
    p = player(np.array([1.0]))
    p.play()
    assert not p.playing
    assert p.interval == float("inf")


# -- the real thread -----------------------------------------------------------------
def test_threaded_pause_stops_at_once_without_backlog():
    p = Player(np.arange(100000) * 0.001, max_rate=1000)  # 1 ms interval

    class Slow:
        def __init__(self):
            self.published = []

        def set_time(self, t):
            self.published.append(t)
            time.sleep(0.02)  # 20x slower than the interval

    slow = Slow()
    p.link(slow)
    p.play()
    deadline = time.monotonic() + 30
    while len(slow.published) < 6 and time.monotonic() < deadline:
        time.sleep(0.01)
    p.pause()
    assert not p.playing
    count = len(slow.published)
    time.sleep(0.2)
    assert len(slow.published) == count
    assert not any(
        t.name == "rbm_nb-player" and t.is_alive() for t in threading.enumerate()
    )
    steps = np.diff(slow.published[1:])
    assert steps.min() > 0.001  # samples were skipped, not queued
    p.close()


def test_threaded_playback_reaches_the_end_and_stops():
    p = Player(np.arange(20) * 0.01)
    rec = p.link(TimeLinked())
    p.play()
    deadline = time.monotonic() + 30
    while p.playing and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not p.playing
    assert p.index == 19
    assert rec.times[-1] == pytest.approx(0.19)


# -- widgets without a kernel ------------------------------------------------------
def test_widget_controls_drive_the_player(recording_comm):
    clock = FakeClock()
    p = player(np.arange(50) * 0.1, step=2, skip=10, clock=clock)
    assert p._slider.max == 49 and p._slider.value == 0
    p._step_forward_button.click()
    assert p.index == 2 and p._slider.value == 2
    p._skip_forward_button.click()
    assert p.index == 12
    p._skip_back_button.click()
    p._step_back_button.click()
    assert p.index == 0
    p._slider.value = 30  # as if dragged in the browser
    assert p.index == 30 and p.readout().startswith("30 / 49")
    assert p._readout.value == p.readout()
    p._speed_box.value = 4.0
    assert p.speed == 4.0
    p._play_button.value = True
    assert p.playing and p._play_button.icon == "pause"
    p._play_button.value = False
    assert not p.playing and p._play_button.icon == "play"
    # the slider's new value went out through its comm
    slider_comm = p._slider.comm
    assert any(m.get("state", {}).get("value") == 30 for m in slider_comm.messages if m)


def test_unlisted_speed_is_added_to_the_choices():
    p = player(np.arange(5.0), speed=3.0)
    assert (("3\u00d7", 3.0)) in p._speed_box.options
    assert p._speed_box.value == 3.0
    assert [v for _, v in p._speed_box.options] == [0.25, 0.5, 1.0, 2.0, 3.0, 4.0]


def test_traits_are_validated():
    p = player(np.arange(5.0))
    with pytest.raises(traitlets.TraitError, match="step"):
        p.step = 0
    with pytest.raises(traitlets.TraitError, match="speed"):
        p.speed = -1.0
    with pytest.raises(traitlets.TraitError, match="index"):
        p.index = 5


# -- frames and bad input ----------------------------------------------------------
def test_player_of_a_moving_frame_and_by_name():
    rbm.register_frame("world")
    ts = np.arange(4) * 0.5
    rbm.register_frame(
        "body", parent="world", translation=np.zeros((4, 3)), timestamps=ts
    )
    assert player("body").n == 4
    assert player(rbm.registry["body"]).interval == pytest.approx(0.5)


def test_static_frame_has_no_timestamps_to_play():
    rbm.register_frame("world")
    rbm.register_frame("observer", parent="world", translation=(1, 0, 0))
    with pytest.raises(ValueError, match="'observer' is static"):
        player("observer")
    with pytest.raises(ValueError, match="static"):
        player(rbm.registry["observer"])


def test_unknown_frame_name():
    with pytest.raises(ValueError, match="no frame named 'nope'"):
        player("nope")


@pytest.mark.parametrize(
    "ts, message",
    [
        (np.array([]), "at least one"),
        (np.array([0.0, 2.0, 1.0]), "sorted, but index 2"),
        (np.array([0.0, np.nan]), "finite"),
        (np.zeros((2, 2)), "one-dimensional"),
        (np.array(["a", "b"]), "numbers or datetime64"),
        (None, "None"),
    ],
)
def test_bad_timestamps(ts, message):
    with pytest.raises(ValueError, match=message):
        player(ts)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"step": 0}, "step"),
        ({"step": 1.5}, "step"),
        ({"skip": 0}, "skip"),
        ({"speed": 0}, "speed"),
        ({"speed": float("nan")}, "speed"),
        ({"max_rate": 0}, "max_rate"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        player(np.arange(5.0), **kwargs)


def test_link_needs_publish_or_set_time():
    with pytest.raises(TypeError, match="set_time"):
        player(np.arange(5.0)).link(object())


def test_datetime_player_refuses_float_timestamps():
    ts = np.datetime64("2020-01-01") + np.arange(5) * np.timedelta64(1, "s")
    with pytest.raises(ValueError, match="datetime timestamps with float"):
        player(ts).link(IndexLinked(np.arange(5.0)))
