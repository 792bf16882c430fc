"""TimeSeries: a static plot whose cursor follows a Player."""

from __future__ import annotations

import io

import numpy as np
import pytest
import xarray as xr

from rbm_nb.widgets import Player, TimeSeries


@pytest.fixture
def speed():
    t = np.arange(0.0, 10.0, 0.1)
    return xr.DataArray(
        np.abs(np.sin(t)), dims="time", coords={"time": t}, attrs={"units": "m/s"}
    )


def _spine_columns(png: bytes) -> tuple[int, int]:
    """Columns of the left and right axes spines in the rendered image."""
    import matplotlib.image

    img = matplotlib.image.imread(io.BytesIO(png))[..., :3]
    dark = (img.sum(axis=2) < 0.6).sum(axis=0)  # dark pixels per column
    columns = np.flatnonzero(dark > 0.5 * dark.max())
    return int(columns.min()), int(columns.max())


def test_cursor_spans_the_time_axis_of_the_rendered_image(speed):
    plot = TimeSeries({"head speed": speed}, width=800)
    width = 800
    left, right = _spine_columns(plot.image.value)
    plot.set_time(0.0)
    assert abs(plot.cursor_fraction * width - left) <= 1.5
    plot.set_time(float(speed.time[-1]))
    assert abs(plot.cursor_fraction * width - right) <= 1.5
    assert f"left:{100 * plot.cursor_fraction:.3f}%" in plot.cursor.value


def test_cursor_moves_monotonically_and_clamps(speed):
    plot = TimeSeries({"speed": speed})
    fractions = []
    for t in (-5.0, 0.0, 2.5, 5.0, 9.9, 50.0):
        plot.set_time(t)
        fractions.append(plot.cursor_fraction)
    assert fractions[0] == fractions[1]  # before the data: at the start
    assert fractions[-1] == fractions[-2]  # after the data: at the end
    assert np.all(np.diff(fractions[1:-1]) > 0)


def test_readout_shows_latest_sample_at_or_before_t(speed):
    t = np.arange(0.0, 10.0, 1.0)
    angles = np.column_stack([t, -t])
    plot = TimeSeries(
        {"speed": speed, "gaze": (t + 2.0, angles, ["azimuth", "elevation"])}
    )
    plot.set_time(4.55)
    expected_speed = float(speed.sel(time=4.5, method="nearest"))
    assert f"speed: {expected_speed:.3g} m/s" in plot.readout.value
    assert "gaze: azimuth 2, elevation -2" in plot.readout.value
    plot.set_time(1.0)  # gaze starts at t = 2: not shown yet
    assert "gaze" not in plot.readout.value


def test_follows_a_player_with_datetime_timestamps():
    start = np.datetime64("2020-02-02T00:27:14", "ns")
    stamps = start + (np.arange(200) * 5_000_000).astype("timedelta64[ns]")
    da = xr.DataArray(np.arange(200.0), dims="time", coords={"time": stamps})
    player = Player(stamps, threaded=False)
    plot = TimeSeries({"count": da}, player=player)
    assert plot.time == pytest.approx(player.time)
    player.seek(120)
    assert plot.time == pytest.approx(player.time)
    assert "count: 120" in plot.readout.value
    assert "0.60 s since start" in plot.readout.value
    plot.set_time(stamps[10])  # a datetime64 works too
    assert "count: 10" in plot.readout.value
    player.close()
    plot.close()


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
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        TimeSeries(series)


def test_mixed_timestamp_kinds_are_rejected():
    stamps = np.datetime64("2020-01-01", "ns") + np.arange(3).astype("timedelta64[s]")
    with pytest.raises(ValueError, match="same kind of timestamps"):
        TimeSeries({"a": (stamps, np.ones(3)), "b": (np.arange(3.0), np.ones(3))})


def test_datetime_on_float_data_is_an_error(speed):
    plot = TimeSeries({"speed": speed})
    with pytest.raises(ValueError, match="TimeSeries.set_time"):
        plot.set_time(np.datetime64("2020-01-01"))
    with pytest.raises(ValueError, match="finite"):
        plot.set_time(float("nan"))
