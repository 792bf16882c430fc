"""TimeSeries: what goes over the comm, gaps, the shared time base, the Player link.

The browser side (zoom, hover, click-to-seek, the cursor) is tested in
``test_browser_dashboard.py``; here the widget runs against a recording comm.
"""

from __future__ import annotations

import ipywidgets
import numpy as np
import pytest
import traitlets
import xarray as xr

from rbm_nb.widgets import Player, TimeSeries
from rbm_nb.widgets._timebase import TimeBase

pytestmark = pytest.mark.usefixtures("recording_comm")


START = np.datetime64("2020-02-02T00:27:14.000000001", "ns")


@pytest.fixture
def speed():
    t = np.arange(0.0, 10.0, 0.1)
    return xr.DataArray(
        np.abs(np.sin(t)), dims="time", coords={"time": t}, attrs={"units": "m/s"}
    )


def _decoded(plot, panel):
    d = plot.data[panel]
    x = np.frombuffer(d["x"], dtype=np.float64)
    y = np.column_stack([np.frombuffer(b, dtype=np.float64) for b in d["y"]])
    return x, y


def test_samples_go_once_as_binary_buffers(speed):
    plot = TimeSeries({"head speed": speed})
    opened_state, buffers = plot.comm.opened
    # every array travels as a buffer, none as JSON numbers
    assert len(buffers) == 2
    assert sorted(len(b) for b in buffers) == [100 * 8, 100 * 8]
    x, y = _decoded(plot, 0)
    np.testing.assert_array_equal(x, speed.time.values)
    np.testing.assert_array_equal(y[:, 0], speed.values)
    assert plot.panels == [
        {
            "label": "head speed",
            "units": "m/s",
            "components": ["head speed"],
            "colors": ["#1f77b4"],
            "samples": 100,
            "reduced": False,
        }
    ]
    assert plot.t0_ns is None
    # moving the cursor sends a float, not the samples again
    plot.comm.sent.clear()
    plot.set_time(3.0)
    assert plot.comm.sent == [
        ({"method": "update", "state": {"time": 3.0}, "buffer_paths": []}, [])
    ]


def test_components_of_a_dataarray_are_lines_of_one_panel():
    t = np.arange(0.0, 2.0, 0.5)
    gaze = xr.DataArray(
        np.c_[t, -t],
        dims=("time", "angle"),
        coords={"time": t, "angle": ["azimuth", "elevation"]},
        attrs={"units": "deg"},
    )
    plot = TimeSeries({"gaze": gaze, "raw": (t, np.c_[t, t, t], ["a", "b", "c"])})
    assert [p["components"] for p in plot.panels] == [
        ["azimuth", "elevation"],
        ["a", "b", "c"],
    ]
    assert plot.panels[0]["units"] == "deg"
    x, y = _decoded(plot, 0)
    np.testing.assert_array_equal(y, np.c_[t, -t])


def test_datetime_data_is_rebased_exactly_to_seconds_from_start():
    stamps = START + (np.arange(200) * 5_000_001).astype("timedelta64[ns]")
    da = xr.DataArray(np.arange(200.0), dims="time", coords={"time": stamps})
    plot = TimeSeries({"count": da})
    assert plot.t0_ns == int(START.astype(np.int64))
    x, _ = _decoded(plot, 0)
    # int64 ns subtraction first: no epoch-sized float rounding
    np.testing.assert_array_equal(x, np.arange(200) * 5_000_001 / 1e9)
    plot.set_time(stamps[10])
    assert plot.time == pytest.approx(10 * 5_000_001 / 1e9, abs=1e-12)
    assert plot.readout() == ("t = 0.050 s \u00b7 2020-02-02 00:27:14.050   count: 10")


def test_nan_values_stay_nan_and_time_gaps_get_a_nan_row():
    t = np.r_[np.arange(0.0, 1.0, 0.1), np.arange(5.0, 6.0, 0.1)]  # 4 s pause
    v = np.sin(t)
    v[3] = np.nan
    plot = TimeSeries({"v": (t, v)})
    x, y = _decoded(plot, 0)
    assert x.size == t.size + 1  # one row inserted in the pause
    inserted = int(np.flatnonzero(~np.isin(x, t))[0])
    assert 0.9 < x[inserted] < 5.0 and np.isnan(y[inserted, 0])
    assert np.isnan(y[3, 0])
    assert np.isfinite(np.delete(y[:, 0], [3, inserted])).all()
    assert plot.gaps == [pytest.approx(1.0)]  # 10 x the 0.1 s median interval


@pytest.mark.parametrize("gap, rows_added", [(0.05, 19), (2.0, 1), (np.inf, 0)])
def test_gap_threshold_can_be_chosen(gap, rows_added):
    t = np.r_[np.arange(0.0, 1.0, 0.1), np.arange(5.0, 6.0, 0.1)]
    plot = TimeSeries({"v": (t, t)}, gap=gap)
    x, _ = _decoded(plot, 0)
    assert x.size - t.size == rows_added


def test_a_player_drives_the_cursor_and_clicks_seek_it(speed):
    player = Player(speed.time.values)
    plot = TimeSeries({"speed": speed}, player=player)
    assert plot.player is player
    player.time = 4.55
    assert plot.current_time == 4.55
    expected = float(speed.sel(time=4.5, method="nearest"))
    assert plot.values_at()["speed"] == pytest.approx([expected])
    assert f"speed: {expected:.3g} m/s" in plot.readout()
    plot.set_time(2.0)  # from Python: moves the player
    assert player.time == 2.0
    # Player.link gives a view the player's trait (the browser follows it)
    other = TimeSeries({"speed": speed})
    assert player.link(other) is other and other.player is player


def test_a_float_seconds_player_lines_up_by_its_origin(speed):
    later = speed.sel(time=slice(3.0, None))  # starts 3 s after the player
    player = Player(speed.time.values)
    plot = TimeSeries({"later": later}, player=player)
    x, _ = _decoded(plot, 0)
    assert x[0] == pytest.approx(3.0)
    player.time = 3.05
    assert plot.values_at()["later"] == pytest.approx([later.values[0]])


def test_a_click_in_the_browser_without_a_player_sets_time(speed):
    plot = TimeSeries({"speed": speed})
    # what the comm delivers when the browser sets `time` and `x_range`
    plot.set_state({"time": 7.25, "x_range": [2.0, 4.0]})
    assert plot.current_time == 7.25
    assert plot.x_range == [2.0, 4.0]


def test_linking_a_datetime_player_rebases_to_its_start():
    stamps = START + np.arange(100).astype("timedelta64[s]")
    da = xr.DataArray(np.arange(100.0), dims="time", coords={"time": stamps})
    earlier = int(START.astype(np.int64)) - 2_000_000_000  # 2 s before
    player = Player(np.r_[np.datetime64(earlier, "ns"), stamps])
    plot = TimeSeries({"count": da}, player=player)
    assert plot.t0_ns == earlier
    x, _ = _decoded(plot, 0)
    assert x[0] == 2.0 and x[-1] == 101.0
    player.time = 12.0
    assert plot.values_at()["count"] == [10.0]
    assert plot.timebase == TimeBase(t0_ns=earlier)


def test_zoom_from_python(speed):
    plot = TimeSeries({"speed": speed})
    plot.zoom(1.0, 2.5)
    assert plot.x_range == [1.0, 2.5]
    plot.zoom()
    assert plot.x_range == []
    with pytest.raises(ValueError, match="start < end"):
        plot.zoom(3.0, 1.0)


@pytest.mark.parametrize(
    "series, message",
    [
        ({}, "non-empty mapping"),
        ({"a": xr.DataArray(np.ones(3), dims="x")}, "'time' dimension"),
        ({"a": (np.arange(3.0), np.ones(4))}, "shape (4,)"),
        ({"a": (np.arange(3.0), np.ones((3, 2)), ["x"])}, "2 columns but 1"),
        ({"a": (np.arange(3.0),)}, "tuple of 1"),
        ({"a": (np.array([0.0, 2.0, 1.0]), np.ones(3))}, "sorted"),
    ],
)
def test_bad_series_are_rejected_with_their_label(series, message):
    with pytest.raises(
        ValueError, match=message.replace("(", r"\(").replace(")", r"\)")
    ):
        TimeSeries(series)


def test_mixed_timestamp_kinds_and_bad_options_are_rejected(speed):
    stamps = np.datetime64("2020-01-01", "ns") + np.arange(3).astype("timedelta64[s]")
    with pytest.raises(
        ValueError, match="cannot match datetime64 timestamps with numeric"
    ):
        TimeSeries({"a": (stamps, np.ones(3)), "b": (np.arange(3.0), np.ones(3))})
    with pytest.raises(ValueError, match="gap must be a positive"):
        TimeSeries({"speed": speed}, gap=0)
    with pytest.raises(traitlets.TraitError, match="'time' and 't0_ns'"):
        TimeSeries({"speed": speed}, player=ipywidgets.IntSlider())
    with pytest.raises(
        traitlets.TraitError, match="cannot match datetime64 timestamps with numeric"
    ):
        TimeSeries({"speed": speed}, player=Player(np.array(["2020-01-01"], "M8[ns]")))


def test_datetime_on_float_data_is_an_error(speed):
    plot = TimeSeries({"speed": speed})
    with pytest.raises(ValueError, match="TimeSeries.set_time"):
        plot.set_time(np.datetime64("2020-01-01"))
    with pytest.raises(ValueError, match="finite"):
        plot.set_time(float("nan"))


def test_max_points_keeps_peaks_and_gaps():
    t = np.arange(0.0, 100.0, 0.001)  # 100k samples
    v = np.sin(t)
    v[50_000] = 7.0  # a one-sample spike
    v[70_000:70_010] = np.nan  # a short gap
    full = TimeSeries({"v": (t, v)}, max_points=None)
    small = TimeSeries({"v": (t, v)}, max_points=1000, overview_width=500)
    x, y = _decoded(small, 0)
    # at most first, last, min, max and first missing per pixel column
    assert x.size <= 5 * 500 < _decoded(full, 0)[0].size == t.size
    assert np.all(np.diff(x) > 0)
    assert np.nanmax(y) == 7.0 and np.nanmin(y) == pytest.approx(-1.0, abs=1e-3)
    # the NaN run still breaks the line, and no value is invented
    gap = np.flatnonzero(np.isnan(y[:, 0]))
    assert gap.size >= 1 and 70.0 <= x[gap[0]] < 70.01
    index = np.round(x * 1000).astype(int)
    np.testing.assert_array_equal(x, t[index])  # only real samples are sent
    np.testing.assert_array_equal(y[:, 0], v[index])
    with pytest.raises(ValueError, match="max_points"):
        TimeSeries({"v": (t, v)}, max_points=3)


def _bytes_sent(plot) -> int:
    """Bytes of every message after the comm opened: JSON and buffers."""
    import json

    return sum(
        len(json.dumps(data)) + sum(len(b) for b in buffers)
        for data, buffers in plot.comm.sent
    )


def test_linking_a_player_later_sends_a_shift_not_the_samples_again():
    stamps = START + (np.arange(5000) * 5_000_001).astype("timedelta64[ns]")
    da = xr.DataArray(np.arange(5000.0), dims="time", coords={"time": stamps})
    plot = TimeSeries({"count": da})
    sent_x, _ = _decoded(plot, 0)
    plot.comm.sent.clear()
    earlier = int(START.astype(np.int64)) - 700_000  # the eye clock: 0.7 ms earlier
    player = Player(np.r_[np.datetime64(earlier, "ns"), stamps])
    plot.player = player
    # a few hundred bytes of state, no buffer: the 5000 samples are not resent
    assert all(not buffers for _, buffers in plot.comm.sent)
    assert _bytes_sent(plot) < 500
    assert plot.t0_ns == earlier and plot.x_shift == pytest.approx(0.0007, abs=1e-15)
    # what the browser shows: the sent x plus the shift, in the player's seconds
    np.testing.assert_allclose(
        sent_x + plot.x_shift, np.arange(5000) * 5_000_001 / 1e9 + 0.0007, atol=1e-12
    )
    player.time = 0.0007 + 10 * 0.005000001
    assert plot.values_at()["count"] == [10.0]
    # and back to the series' own start: again only the shift
    plot.player = None
    assert plot.x_shift == 0.0 and plot.t0_ns == int(START.astype(np.int64))
    assert all(not buffers for _, buffers in plot.comm.sent)


def test_a_player_given_at_construction_sends_the_samples_once(speed):
    later = speed.sel(time=slice(3.0, None))  # starts 3 s after the player
    player = Player(speed.time.values)
    plot = TimeSeries({"later": later}, player=player)
    # in the open message, already in the player's seconds; nothing after it
    _, opened_buffers = plot.comm.opened
    assert sum(len(b) for b in opened_buffers) == 2 * later.size * 8
    assert all(not buffers for _, buffers in plot.comm.sent)
    x, _ = _decoded(plot, 0)
    np.testing.assert_allclose(x, later.time.values, atol=1e-12)
    assert plot.x_shift == 0.0


def test_a_zoomed_view_gets_the_samples_in_view_at_full_resolution():
    t = np.arange(0.0, 600.0, 0.003)  # 200k samples
    v = np.sin(t)
    v[1000:1010] = np.nan
    plot = TimeSeries({"v": (t, v)}, max_points=1000)
    assert plot.detail and plot.comm.opened[1] and len(_decoded(plot, 0)[0]) <= 5000
    plot.comm.sent.clear()
    _ask(plot, {"type": "window", "id": 7, "start": 2.0, "end": 12.0})
    ((message, buffers),) = plot.comm.sent
    reply = message["content"]  # a custom message
    assert reply["type"] == "window" and reply["id"] == 7
    x, y = (np.frombuffer(b, dtype=np.float64) for b in buffers)
    inside = np.flatnonzero((t >= 2.0) & (t <= 12.0))
    rows = np.r_[inside[0] - 1, inside, inside[-1] + 1]  # and one on each side
    np.testing.assert_array_equal(x, t[rows])
    np.testing.assert_array_equal(y, v[rows])  # the NaN run too
    assert reply["rows"] == [rows.size] and reply["full"] == [True]
    # a window with more samples than WINDOW_POINTS comes as their M4 at the
    # view's width
    plot.comm.sent.clear()
    _ask(plot, {"type": "window", "id": 8, "start": 0.0, "end": 300.0, "width": 300})
    ((message, buffers),) = plot.comm.sent
    assert message["content"]["rows"][0] <= 5 * 300 and message["content"]["full"] == [
        False
    ]
    # a request the page got wrong is not answered
    plot.comm.sent.clear()
    for bad in (
        {"type": "window", "start": 5.0, "end": 1.0},
        {"type": "window"},
        {"type": "window", "start": 1.0, "end": 2.0, "width": "wide"},
        {"type": "window", "start": 1.0, "end": 2.0, "width": 1e9},
        "x",
    ):
        plot.comm.receive(bad)
    assert plot.comm.sent == [] and plot.window_requests["answered"] == 2


def test_a_window_follows_a_player_linked_later(speed):
    player = Player(np.r_[-1.0, speed.time.values])  # second 0 one second earlier
    plot = TimeSeries({"speed": speed}, max_points=20)
    plot.player = player
    assert plot.x_shift == 1.0
    ((x, _),) = plot.window(3.0, 4.0)  # axis seconds; x as sent (the data's seconds)
    np.testing.assert_allclose(x, speed.time.values[19:32])


def test_a_short_series_goes_whole_and_needs_no_fetch(speed):
    plot = TimeSeries({"speed": speed})
    assert not plot.detail and plot.panels[0]["reduced"] is False
    ((x, _),) = plot.window(1.0, 2.0)
    np.testing.assert_allclose(x, speed.time.values[9:22])
    with pytest.raises(ValueError, match="width"):
        plot.window(1.0, 2.0, width=0)


def _ask(plot, request):
    """Send ``request`` as the page would and wait for the worker's answer."""
    plot.comm.receive(request)
    plot._last_request.result(timeout=60)


def _recording(hours: float, seed: int = 0):
    """An eye-like series: 340 Hz with jitter, runs of missing samples, pauses."""
    rng = np.random.default_rng(seed)
    n = int(hours * 3600 * 340)
    t = START + np.cumsum(rng.integers(2_800_000, 3_100_000, n)).astype(
        "timedelta64[ns]"
    )
    t[n // 3 :] += np.timedelta64(2, "s")  # a pause
    v = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    v[rng.random(n) < 0.03] = np.nan
    return xr.DataArray(v, dims=("time", "eye"), coords={"time": t, "eye": ["l", "r"]})


def test_overview_bytes_do_not_grow_with_the_recording():
    short, long = _recording(0.1), _recording(1.0)
    sizes = []
    for da in (short, long):
        plot = TimeSeries({"gaze": da})
        sizes.append(sum(len(b) for b in plot.comm.opened[1]))
        x, y = _decoded(plot, 0)
        # at most first, last, 2 x (min, max, first missing) per column (and
        # the pause's NaN row)
        assert x.size <= 8 * plot.overview_width + 1 and plot.detail
    assert sizes[1] < 1.2 * sizes[0]  # 10x the samples, about the same bytes
    assert long.nbytes > 40 * sizes[1]


def test_the_overview_draws_as_the_full_series_at_its_width():
    da = _recording(0.2, seed=3)
    width = 400
    plot = TimeSeries({"gaze": da}, overview_width=width)
    x, y = _decoded(plot, 0)
    full_x = (da.time.values - da.time.values[0]).astype(np.int64) / 1e9
    span = full_x[-1] - full_x[0]
    column = np.minimum((full_x * width / span).astype(int), width - 1)
    for c in range(2):
        values = da.values[:, c]
        full_min = np.full(width, np.inf)
        np.fmin.at(full_min, column, values)
        shown = np.full(width, np.inf)
        sent_column = np.minimum((x * width / span).astype(int), width - 1)
        np.fmin.at(shown, sent_column[np.isfinite(y[:, c])], y[np.isfinite(y[:, c]), c])
        np.testing.assert_array_equal(shown, full_min)  # every column's minimum
        full_max = np.full(width, -np.inf)
        np.fmax.at(full_max, column, values)
        top = np.full(width, -np.inf)
        np.fmax.at(top, sent_column[np.isfinite(y[:, c])], y[np.isfinite(y[:, c]), c])
        np.testing.assert_array_equal(top, full_max)  # and maximum
    # only recorded samples, each with its own value
    rows = np.flatnonzero(np.isin(full_x, x[~np.all(np.isnan(y), axis=1)]))
    finite = ~np.all(np.isnan(y), axis=1)
    np.testing.assert_array_equal(full_x[rows], np.unique(x[finite]))
    np.testing.assert_array_equal(y[finite], da.values[rows])


def test_a_view_asks_for_an_overview_at_its_own_width():
    plot = TimeSeries({"gaze": _recording(0.3)})
    plot.comm.sent.clear()
    request = {"type": "window", "id": 1, "view": "a", "start": -1.0, "end": 1e5}
    _ask(plot, {**request, "width": 200, "whole": True})
    ((message, buffers),) = plot.comm.sent
    assert message["content"]["whole"] and message["content"]["width"] == 200
    assert message["content"]["rows"][0] <= 8 * 200 + 1
    assert len(buffers) == 3


def test_a_superseded_request_is_cancelled_in_the_kernel(monkeypatch):
    """The kernel stops a request once a newer one from the same view came."""
    import threading

    from rbm_nb.widgets import _decimate

    plot = TimeSeries(
        {"a": _recording(0.2), "b": _recording(0.2, seed=1)}, overview_width=100
    )
    plot.comm.sent.clear()
    started, release = threading.Event(), threading.Event()
    calls = []
    m4 = _decimate.m4_rows

    def slow_m4(*args, **kwargs):
        calls.append(args[2:4])
        if len(calls) == 1:  # the first request's first panel waits
            started.set()
            release.wait(timeout=30)
        return m4(*args, **kwargs)

    monkeypatch.setattr("rbm_nb.widgets.timeseries_rows.m4_rows", slow_m4)
    old = {"type": "window", "view": "v", "start": 0.0, "end": 500.0, "width": 100}
    plot.comm.receive({**old, "id": 1})
    assert started.wait(timeout=30)  # the kernel is computing request 1
    plot.comm.receive({**old, "id": 2, "end": 400.0})
    plot.comm.receive({**old, "id": 3, "end": 300.0})
    # another view's request is not cancelled by this one's
    plot.comm.receive({**old, "id": 9, "view": "w"})
    release.set()
    plot._last_request.result(timeout=60)
    answered = sorted(
        (m["content"]["view"], m["content"]["id"]) for m, _ in plot.comm.sent
    )
    assert answered == [("v", 3), ("w", 9)]
    # 1 stopped after its first panel, 2 never started
    assert plot.window_requests == {"answered": 2, "cancelled": 2}
    assert len(calls) == 1 + 2 + 2


def test_the_kernel_keeps_no_copy_of_a_long_series():
    """Values and stamps are the caller's arrays; what stays is the overview."""
    import tracemalloc

    # the decimation kernel's code is loaded once per process (numba), not
    # kept per series: loaded before measuring
    TimeSeries({"warm": _recording(0.01)}).close()
    da = _recording(0.5)
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    plot = TimeSeries({"gaze": da})
    kept = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    assert np.shares_memory(plot._series[0].values, da.values)
    data = da.nbytes + da.time.values.nbytes
    assert kept < 0.05 * data, (kept, data)
