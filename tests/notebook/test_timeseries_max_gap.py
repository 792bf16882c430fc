"""A series' own max_gap, and pauses in a decimated overview (issue 35).

The explorer's gaze series used to carry a NaN row inserted in every pause
of the eye tracker longer than 0.1 s: a new copy of every eye timestamp,
kept as long as the dashboard. They keep the eye's own times now and say
``attrs["max_gap"] = 0.1``; the plot draws their longer pauses as gaps,
whatever its own ``gap`` rule, at full resolution and in the min/max
overview (where each column's first pause keeps both its sides, as the
column's first missing sample is kept).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from rbm_nb.widgets import TimeSeries
from rbm_nb.widgets._decimate import pause_sides

pytestmark = pytest.mark.usefixtures("recording_comm")


def _decoded(plot, panel=0):
    d = plot.data[panel]
    x = np.frombuffer(d["x"], dtype=np.float64)
    y = np.column_stack([np.frombuffer(b, dtype=np.float64) for b in d["y"]])
    return x, y


def _paused(dt: float, pause: float, n: int) -> np.ndarray:
    """``n`` samples ``dt`` apart with one pause of ``pause`` s in the middle."""
    t = np.arange(n) * dt
    t[n // 2 :] += pause
    return t


def test_a_series_max_gap_draws_shorter_pauses_than_the_plot_rule():
    # 30 Hz: the default rule (10 median intervals) would bridge 0.2 s
    t = _paused(1 / 30, 0.2, 60)
    bare = xr.DataArray(np.sin(t), dims="time", coords={"time": t})
    said = bare.assign_attrs(max_gap=0.1)
    x, y = _decoded(TimeSeries({"v": bare}))
    assert x.size == t.size  # bridged
    x, y = _decoded(TimeSeries({"v": said}))
    assert x.size == t.size + 1 and np.isnan(y[30, 0])
    assert t[29] < x[30] < t[30]
    # and a plot-wide gap that joins everything does not join it
    x, _ = _decoded(TimeSeries({"v": said}, gap=np.inf))
    assert x.size == t.size + 1
    # nothing stored in the series
    assert said.sizes["time"] == t.size


@pytest.mark.parametrize("value", [0, -1.0, np.nan, np.inf, "x", True])
def test_a_bad_max_gap_is_refused_by_name(value):
    t = np.arange(10.0)
    bad = xr.DataArray(t, dims="time", coords={"time": t}, attrs={"max_gap": value})
    with pytest.raises(ValueError) as err:
        TimeSeries({"speed": bad})
    assert str(err.value) == (
        f"TimeSeries: series 'speed' has attrs['max_gap'] = {value!r}; expected "
        "a positive number of seconds"
    )


def test_the_overview_keeps_both_sides_of_each_columns_first_pause():
    # 200k samples in 1000 columns: 200 per column; 40 pauses of 0.15 s,
    # each inside one column, not at its edges
    n, dt = 200_000, 0.005
    t = np.arange(n) * dt
    starts = np.arange(40) * 5000 + 2503
    for s in starts:
        t[s:] += 0.15
    values = np.sin(t / 3.0)
    said = xr.DataArray(values, dims="time", coords={"time": t}, attrs={"max_gap": 0.1})
    plot = TimeSeries({"v": said}, max_points=10_000, overview_width=1000)
    assert plot.panels[0]["reduced"]
    x, y = _decoded(plot)
    gaps = np.flatnonzero(np.isnan(y[:, 0]))
    assert gaps.size == starts.size
    # each NaN row sits in its pause, between the pause's own two samples
    for row, s in zip(gaps, starts, strict=True):
        assert x[row - 1] == t[s - 1] and x[row + 1] == t[s]


def test_pause_sides_are_two_rows_per_column_at_most():
    x = np.arange(100.0)
    pauses = np.array([3, 4, 5, 50, 98, 99])
    rows = pause_sides(x, pauses, 0.0, 100.0, 10)
    # columns of 10 rows: the first pause of columns 0, 5 and 9
    assert sorted(rows.tolist()) == [3, 4, 50, 51, 98, 99]
    assert pause_sides(x, np.empty(0, dtype=np.int64), 0.0, 100.0, 10).size == 0
