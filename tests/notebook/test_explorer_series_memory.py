"""The explorer's plot series hold one copy of the eyes' clock (issue 35).

The dashboard keeps its series (``board.series``) and the TimeSeries views
them for as long as it lives. The gaze yaw and its rate used to hold a copy
of every eye timestamp each (a new DataArray, then a deep copy); they share
one time index now, and the TimeSeries views that.
"""

from __future__ import annotations

import numpy as np

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
