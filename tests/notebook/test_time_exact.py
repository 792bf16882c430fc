"""The notebook layer keeps times exact: one time module, one rule (issue 32, item 5).

Datetimes 1 ns apart at a 2020 epoch are two samples for the Player, its
links and the TimeSeries (float seconds since the epoch would make them one:
their spacing is ~0.24 µs there); bad timestamps get the time module's
messages, naming the argument.
"""

from __future__ import annotations

import numpy as np
import pytest
import traitlets

from rbm_nb.widgets import Player, TimeSeries

T0 = np.datetime64("2020-02-02T00:27:14.000000000", "ns")
# three stamps 1 ns apart, then one a second later
STAMPS = T0 + np.array([0, 1, 2, 1_000_000_000]).astype("timedelta64[ns]")


class IndexLinked:
    def __init__(self, timestamps):
        self.timestamps = timestamps
        self.published = []

    def publish(self, idx):
        self.published.append(idx)


class TimeLinked:
    def __init__(self):
        self.times = []

    def set_time(self, t):
        self.times.append(t)


def test_epoch_floats_would_merge_these_stamps():
    """The premise: as float seconds since the epoch the first three are one time."""
    seconds = STAMPS.astype(np.int64) / 1e9
    assert seconds[0] == seconds[1] == seconds[2]


def test_player_keeps_stamps_one_ns_apart_distinct_and_ordered():
    player = Player(STAMPS)
    assert player.duration == pytest.approx(1.0, abs=0)
    times = [player.playback.time_of(i) for i in range(len(STAMPS))]
    assert times == sorted(set(times)) and times[1] == 1e-9
    for i in range(len(STAMPS)):
        player.seek(i)
        assert player.index == i
        assert player.timestamp == STAMPS[i]
        assert player.time_value == STAMPS[i]  # exact, in the data's kind
        assert player.index_at(STAMPS[i]) == i


def test_player_links_see_each_ns_sample():
    player = Player(STAMPS)
    follower = IndexLinked(STAMPS)
    timed = TimeLinked()
    player.link(follower)
    player.link(timed)
    for i in (1, 2, 3, 0):
        player.seek(i)
    assert follower.published == [0, 1, 2, 3, 0]
    assert timed.times[1:] == [STAMPS[1], STAMPS[2], STAMPS[3], STAMPS[0]]


def test_player_seek_time_with_a_datetime_is_exact():
    player = Player(STAMPS)
    player.seek_time(STAMPS[2])
    assert player.index == 2 and player.time == 2e-9


def test_timeseries_refuses_stamps_one_ns_out_of_order():
    backwards = STAMPS[[1, 0]]
    with pytest.raises(
        ValueError,
        match=r"timestamps of series 'x' must be sorted \(repeats allowed\): "
        r"timestamps of series 'x'\[1\] = .* is earlier than",
    ):
        TimeSeries({"x": (backwards, np.arange(2.0))})


def test_timeseries_and_player_agree_on_ns_samples():
    plot = TimeSeries({"x": (STAMPS, np.arange(4.0))})
    player = Player(STAMPS)
    plot.player = player
    for i in range(4):
        player.seek(i)
        assert plot.values_at(player.time)["x"][0] == i


def test_repeated_stamps_are_allowed_in_the_notebook_layer():
    stamps = STAMPS[[0, 1, 1, 3]]
    player = Player(stamps)
    player.seek(3)
    assert player.index == 3
    TimeSeries({"x": (stamps, np.arange(4.0))})


@pytest.mark.parametrize(
    "stamps, message",
    [
        (np.array([T0, np.datetime64("NaT", "ns")]), r"timestamps\[1\] is NaT"),
        (np.array([0.0, np.nan]), r"timestamps\[1\] is nan; timestamps must be finite"),
        (
            STAMPS[[2, 1]],
            r"timestamps must be sorted \(repeats allowed\): timestamps\[1\]",
        ),
        (np.array([], dtype="datetime64[ns]"), "timestamps must not be empty"),
    ],
)
def test_bad_player_timestamps_get_the_time_modules_messages(stamps, message):
    with pytest.raises(ValueError, match=message):
        Player(stamps)


def test_timeseries_names_its_series_in_the_messages():
    stamps = np.array([T0, np.datetime64("NaT", "ns")])
    with pytest.raises(ValueError, match=r"timestamps of series 'eye'\[1\] is NaT"):
        TimeSeries({"eye": (stamps, np.arange(2.0))})


def test_mixed_kinds_between_player_and_view_are_refused():
    floats = Player(np.arange(4.0))
    plot = TimeSeries({"x": (STAMPS, np.arange(4.0))})
    with pytest.raises(
        traitlets.TraitError,
        match="TimeSeries.player: cannot match datetime64 timestamps with numeric",
    ):
        plot.player = floats
    with pytest.raises(
        ValueError, match=r"link\(IndexLinked\): cannot match datetime64 timestamps"
    ):
        floats.link(IndexLinked(STAMPS))


def test_frame_tree_shows_each_ns_sample():
    import rbm_nb as rbm
    from rbm_nb.widgets import FrameTree

    rbm.register_frame("world")
    rbm.register_frame(
        "head",
        parent="world",
        translation=np.c_[np.arange(4.0), np.zeros(4), np.zeros(4)],
        timestamps=STAMPS,
    )
    player = Player(STAMPS)
    tree = FrameTree("world", player=player)
    tree.select("head")
    for i in (1, 2, 0, 3):
        player.seek(i)
        assert tree.details.pose.translation == (float(i), 0.0, 0.0)
    alone = FrameTree("world")
    alone.select("head")
    alone.set_time(STAMPS[2])
    assert alone.details.pose.translation == (2.0, 0.0, 0.0)
