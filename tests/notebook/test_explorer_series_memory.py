"""The explorer's plot series hold no copy of the recording's clocks (issue 35).

The dashboard keeps its series (``board.series``) and the TimeSeries views
them for as long as it lives. The gaze yaw and its rate used to hold a copy
of every eye timestamp each (a new DataArray, then a deep copy); then one
shared copy (NaN rows inserted in the pauses); now they are on the eye
dataset's own time index, the head's rate on the head dataset's, and the
TimeSeries views those.
"""

from __future__ import annotations

import numpy as np
from memory_support import kept_by

import rbm_nb as rbm
from rbm_nb.app import explorer


def _index(da) -> np.ndarray:
    return np.asarray(da.indexes["time"])


def test_gaze_yaw_and_its_rate_share_one_time_index(monkeypatch, tmp_path):
    (tmp_path / "no-data").mkdir()
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "no-data"))
    head, left_eye, right_eye, _ = explorer.load_head_eye("synthetic")
    try:
        board = explorer.dashboard(head, left_eye, right_eye)
        try:
            series = board.series
            yaw, rate = series["gaze yaw"], series["gaze yaw rate"]
            assert np.shares_memory(_index(yaw), _index(rate))
            # and the plot's stamps are those (views, no copy)
            plot = board.plot
            stamps = {s.label: s.timestamps for s in plot._series}
            assert np.shares_memory(stamps["gaze yaw"], _index(yaw))
            assert np.shares_memory(stamps["gaze yaw rate"], _index(yaw))
            np.testing.assert_array_equal(rate["time"].values, yaw["time"].values)
        finally:
            explorer.close_dashboard(board)
    finally:
        rbm.clear_registry()


def _shares_clock(da, times) -> bool:
    return np.shares_memory(_index(da), times)


def test_the_series_keep_the_recordings_own_clocks(monkeypatch, tmp_path):
    # the eyes' series used to get a NaN row inserted in each pause longer
    # than 0.1 s (a new time index: a copy of every eye timestamp), and the
    # head's rate two copies of the head's timestamps (xarray's constructor)
    (tmp_path / "no-data").mkdir()
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "no-data"))
    head, left_eye, right_eye, _ = explorer.load_head_eye("synthetic")
    # a pause of 0.5 s in the eyes' recording (rows dropped from both)
    keep = np.r_[0:3000, 3200 : left_eye.sizes["time"]]
    left_eye, right_eye = (eye.isel(time=keep) for eye in (left_eye, right_eye))
    try:
        explorer.register_head_eye_frames(head, left_eye, right_eye)
        # once first: the frames' tables are built by the first lookups
        explorer.explorer_series(head, left_eye, right_eye)
        series, kept = kept_by(
            lambda: explorer.explorer_series(head, left_eye, right_eye)
        )
        assert _shares_clock(series["head yaw rate"], head.time.values)
        for name in ("gaze yaw", "gaze yaw rate"):
            assert _shares_clock(series[name], left_eye.time.values), name
            assert series[name].sizes["time"] == left_eye.sizes["time"], name
            assert series[name].attrs["max_gap"] == explorer.MAX_EYE_GAP
        # the plotted values and nothing per sample beside them
        values = sum(da.values.nbytes for da in series.values())
        clocks = head.time.values.nbytes + left_eye.time.values.nbytes
        assert kept < values + 0.1 * clocks, (kept, values, clocks)
    finally:
        rbm.clear_registry()


def test_the_plot_draws_the_eyes_pause_from_their_max_gap(monkeypatch, tmp_path):
    (tmp_path / "no-data").mkdir()
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "no-data"))
    head, left_eye, right_eye, _ = explorer.load_head_eye("synthetic")
    keep = np.r_[0:3000, 3200 : left_eye.sizes["time"]]
    left_eye, right_eye = (eye.isel(time=keep) for eye in (left_eye, right_eye))
    try:
        board = explorer.dashboard(head, left_eye, right_eye)
        try:
            plot = board.plot
            start = plot.timebase.seconds(left_eye.time.values[2999:3001])
            x, y = plot.window(start[0] - 0.05, start[1] + 0.05)[1]
            inside = (x > start[0]) & (x < start[1])
            assert inside.sum() == 1 and np.isnan(y[inside]).all()
        finally:
            explorer.close_dashboard(board)
    finally:
        rbm.clear_registry()


def test_eyes_on_two_clocks_keep_their_own_times(monkeypatch, tmp_path):
    (tmp_path / "no-data").mkdir()
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "no-data"))
    head, left_eye, right_eye, _ = explorer.load_head_eye("synthetic")
    right_eye = right_eye.isel(time=np.r_[0:1000, 1500 : right_eye.sizes["time"]])
    try:
        explorer.register_head_eye_frames(head, left_eye, right_eye)
        yaw = explorer.gaze_yaw(left_eye, right_eye, max_angle=50.0)
        assert yaw.dims == ("time", "eye")
        assert list(yaw["eye"].values) == ["left eye", "right eye"]
        np.testing.assert_array_equal(yaw["time"].values, left_eye.time.values)
        for eye, name, ds in (("left eye", "left_eye", left_eye),
                              ("right eye", "right_eye", right_eye)):  # fmt: skip
            alone = explorer.gaze_angles(ds, name, max_angle=50.0)
            column = yaw.sel(eye=eye).sel(time=alone["time"].values)
            np.testing.assert_array_equal(
                column.values, -alone.sel(angle="azimuth").values
            )
        assert np.isnan(yaw.sel(eye="right eye").values[1000:1500]).all()
        assert yaw.attrs["max_gap"] == explorer.MAX_EYE_GAP
    finally:
        rbm.clear_registry()
