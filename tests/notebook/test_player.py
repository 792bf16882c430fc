"""Player: the pure playback model (seek, skips in seconds, loop, clock arithmetic),
the widget's traits and kernel-side links without a browser, and bad input.

The browser clock itself runs in test_browser.py; js/src/lib/clock.js mirrors
:class:`rbm_nb.widgets.playback.Playback`, whose arithmetic is tested here.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest
import traitlets

import rbm_nb as rbm
from rbm_nb.widgets import Player
from rbm_nb.widgets.playback import Playback

pytestmark = pytest.mark.usefixtures("recording_comm")


class SetTimeLinked:
    def __init__(self):
        self.times = []

    def set_time(self, t):
        self.times.append(t)


class IndexLinked:
    def __init__(self, timestamps):
        self.timestamps = timestamps
        self.published = []

    def publish(self, idx):
        self.published.append(idx)


# -- the playback model ---------------------------------------------------------------
def test_clock_follows_wall_time_and_speed():
    pb = Playback(np.arange(11) * 0.5)  # 0 .. 5 s
    assert pb.duration == 5.0 and pb.mean_interval == 0.5
    pb.play(now=100.0)
    assert pb.advance(101.2) == pytest.approx(1.2)
    assert pb.index == 2
    pb.set_speed(2.0, now=102.0)  # no jump at the change
    assert pb.time == pytest.approx(2.0)
    assert pb.advance(102.5) == pytest.approx(3.0)
    pb.pause(now=102.75)
    assert pb.time == pytest.approx(3.5) and not pb.playing
    assert pb.advance(200.0) == pytest.approx(3.5)  # paused: the clock is ignored


def test_end_stops_or_loops():
    pb = Playback([10.0, 11.0, 12.0, 13.0])
    pb.play(now=0.0)
    assert pb.advance(10.0) == 3.0 and not pb.playing  # stops at the end
    pb.play(now=20.0)  # at the end, play starts over
    assert pb.time == 0.0 and pb.playing
    pb.loop = True
    assert pb.advance(24.5) == pytest.approx(1.5) and pb.playing  # wrapped
    assert pb.advance(25.0) == pytest.approx(2.0)


def test_seek_and_skips_in_seconds():
    pb = Playback(np.arange(101) * 0.1)  # 0 .. 10 s
    assert pb.seek(4.25, now=0.0) == 4.25 and pb.index == 42
    assert pb.skip(1.0, now=0.0) == pytest.approx(5.25)
    assert pb.skip(-10.0, now=0.0) == 0.0  # clamped
    assert pb.skip(30.0, now=0.0) == 10.0
    pb.loop = True
    assert pb.skip(1.5, now=0.0) == pytest.approx(1.5)  # wraps around the end
    assert pb.skip(-2.0, now=0.0) == pytest.approx(9.5)
    assert pb.step(3, now=0.0) == pytest.approx(9.8)
    assert pb.step(-200, now=0.0) == 0.0


def test_seek_while_playing_continues_from_there():
    pb = Playback(np.arange(101) * 0.1)
    pb.play(now=0.0)
    pb.seek(7.0, now=1.0)
    assert pb.advance(2.0) == pytest.approx(8.0)


def test_index_counts_floating_point_neighbours_as_equal():
    pb = Playback(np.array([0.0, 0.1, 0.2, 0.30000000000000004]))
    assert pb.index_at(0.3) == 3
    assert pb.index_at(-1.0) == 0 and pb.index_at(99.0) == 3


@pytest.mark.parametrize(
    "seconds, message",
    [
        ([], "non-empty"),
        ([[0.0]], "1-D"),
        ([0.0, np.nan], "finite"),
        ([1.0, 0.0], "sorted"),
    ],
)
def test_playback_bad_axis(seconds, message):
    with pytest.raises(ValueError, match=message):
        Playback(seconds)


# -- the widget --------------------------------------------------------------------------
def test_traits_of_the_timeline_contract():
    ts = np.datetime64("2020-02-02T00:27:14.300365210") + np.arange(5) * np.timedelta64(
        250, "ms"
    )
    p = Player(ts, speed=2.0, loop=True)
    assert p.duration == pytest.approx(1.0) and p.time == 0.0
    assert p.t0_ns == ts[0].astype("datetime64[ns]").astype(np.int64)
    assert p.origin == pytest.approx(ts[0].astype(np.int64) / 1e9)
    assert p.speed == 2.0 and p.loop and not p.playing
    assert p.trait_metadata("time", "echo_update") is False
    state = p.get_state()
    assert {"time", "playing", "speed", "loop", "duration", "t0_ns", "origin"} <= set(
        state
    )
    assert "export default" in p._esm or "initialize" in p._esm
    floats = Player(np.array([3.0, 4.0, 5.5]))
    assert floats.t0_ns is None and floats.origin == 3.0 and floats.duration == 2.5


def test_navigation_from_python():
    p = Player(np.arange(101) * 0.1, step=4, skip=2.0)
    p.step_forward()
    assert p.index == 4 and p.time == pytest.approx(0.4)
    p.skip_forward()
    assert p.time == pytest.approx(2.4)
    p.skip_back(5.0)
    assert p.time == 0.0
    p.seek_time(7.25)
    assert p.index == 72 and p.data_time == pytest.approx(7.25)
    p.time = 50.0  # clamped to the axis
    assert p.time == 10.0
    assert p.readout() == "10.000 s"
    assert p.big_skip == 20.0


def test_play_pause_only_set_traits_and_start_no_thread():
    """The clock is in the browser: the kernel runs no playback thread."""
    before = {t.ident for t in threading.enumerate()}
    p = Player(np.arange(50) * 0.1)
    p.seek(49)
    p.play()
    assert p.playing and p.time == 0.0  # at the end, play starts over
    p.pause()
    p.toggle()
    p.toggle()
    assert not p.playing
    assert {t.ident for t in threading.enumerate()} == before


def test_pause_and_play_while_a_link_is_slow_leave_one_state():
    """Issue 12 item 14: pause no longer waits for a linked call, no second thread."""
    release = threading.Event()

    class Slow:
        def set_time(self, t):
            release.wait(0.05)

    p = Player(np.arange(100) * 0.1)
    p.link(Slow())
    p.play()
    p.pause()
    p.play()
    assert p.playing
    assert not [t for t in threading.enumerate() if "player" in t.name.lower()]


def test_browser_time_reaches_python_links_and_callbacks(recording_comm):
    p = Player(np.arange(11) * 0.5)
    follower = SetTimeLinked()
    indexed = IndexLinked(np.arange(0, 5.01, 0.25))
    p.link(follower)
    p.link(indexed)
    seen = []
    p.on_time(seen.append)
    player_comm = p.comm
    sent = len(player_comm.messages)
    player_comm.receive_state({"time": 2.3, "playing": True})  # the throttled push
    assert p.time == 2.3 and p.playing
    assert follower.times[-1] == pytest.approx(2.3) and seen == [pytest.approx(2.3)]
    assert indexed.published[-1] == 9  # latest of its own samples at or before 2.3
    # the time is not sent back to the browser (no echo, no update)
    back = [
        m for m in player_comm.messages[sent:] if m and "time" in m.get("state", {})
    ]
    assert back == []


def test_error_in_a_link_is_shown_and_playback_goes_on(recording_comm):
    class Broken:
        def set_time(self, t):
            if t > 1:
                raise RuntimeError("boom")

    p = Player(np.arange(11) * 0.5)
    p.link(Broken())
    p.playing = True
    p.time = 2.0
    assert p.error == "RuntimeError: boom" and p.playing


def test_one_player_drives_several_views():
    rbm.register_frame("world")
    ts = np.arange(5) * 0.5
    rbm.register_frame(
        "body", parent="world", translation=np.zeros((5, 3)), timestamps=ts
    )
    from rbm_nb.scene import Scene

    with Scene("world") as a, Scene("world") as b:
        a.add_frame("body")
        b.add_frame("body")
        p = a.player()
        p.link(b)
        assert a.widget.player is p and b.widget.player is p
        p.unlink(b)
        assert b.widget.player is None


def test_unlink():
    p = Player(np.arange(5.0))
    follower = SetTimeLinked()
    p.link(follower)
    p.unlink(follower)
    p.time = 3.0
    assert p.linked == [] and follower.times == [0.0]


def test_player_of_a_moving_frame_and_by_name():
    rbm.register_frame("world")
    ts = np.arange(4) * 0.5
    rbm.register_frame(
        "body", parent="world", translation=np.zeros((4, 3)), timestamps=ts
    )
    assert Player("body").n == 4
    assert Player(rbm.registry["body"]).duration == pytest.approx(1.5)


def test_static_frame_has_no_timestamps_to_play():
    rbm.register_frame("world")
    rbm.register_frame("observer", parent="world", translation=(1, 0, 0))
    with pytest.raises(ValueError, match="'observer' is static"):
        Player("observer")


def test_unknown_frame_name():
    with pytest.raises(ValueError, match="no frame named 'nope'"):
        Player("nope")


@pytest.mark.parametrize(
    "ts, message",
    [
        (np.array([]), "timestamps must not be empty"),
        (
            np.array([0.0, 2.0, 1.0]),
            r"timestamps must be sorted \(repeats allowed\): timestamps\[2\]",
        ),
        (np.array([0.0, np.nan]), "finite"),
        (np.zeros((2, 2)), "one-dimensional"),
        (np.array(["a", "b"]), "numeric or datetime64"),
        (None, "None"),
    ],
)
def test_bad_timestamps(ts, message):
    with pytest.raises(ValueError, match=message):
        Player(ts)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"step": 0}, "step"),
        ({"step": 1.5}, "step"),
        ({"skip": 0}, "skip"),
        ({"skip": "x"}, "skip"),
        ({"speed": 0}, "speed"),
        ({"speed": float("nan")}, "speed"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Player(np.arange(5.0), **kwargs)


def test_traits_are_validated():
    p = Player(np.arange(5.0))
    with pytest.raises(traitlets.TraitError, match="speed"):
        p.speed = -1.0
    with pytest.raises(traitlets.TraitError, match="finite"):
        p.time = float("nan")


def test_link_needs_publish_or_set_time():
    with pytest.raises(TypeError, match="set_time"):
        Player(np.arange(5.0)).link(object())


def test_datetime_player_refuses_float_timestamps():
    ts = np.datetime64("2020-01-01") + np.arange(5) * np.timedelta64(1, "s")
    with pytest.raises(
        ValueError,
        match="link.IndexLinked.: cannot match datetime64 timestamps with numeric",
    ):
        Player(ts).link(IndexLinked(np.arange(5.0)))
