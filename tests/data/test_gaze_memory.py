"""What gaze.angles and gaze.rates keep: no copy of the timestamps (issue 35).

The explorer's plots keep its gaze series for as long as the dashboard lives;
a DataArray built anew copies every timestamp (xarray deep-copies index
coordinates), so each result used to hold its own copy of the eye's clock.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from memory_support import kept_by

import rbm_nb as rbm
from rbm_nb.core import gaze

N = 200_000


def _time_index_data(da) -> np.ndarray:
    return np.asarray(da.indexes["time"])


@pytest.fixture
def sight():
    rbm.clear_registry()
    rbm.register_frame("camera")
    t = np.datetime64("2020-02-02", "ns") + np.arange(N) * np.timedelta64(
        2_941_176, "ns"
    )
    pitch = np.deg2rad(20.0 * np.sin(np.arange(N) / 500.0))
    rbm.register_frame(
        "eye",
        parent="camera",
        rotation=rbm.from_euler_angles(pitch=pitch),
        timestamps=t,
    )
    yield gaze.directions("eye", "camera")
    rbm.clear_registry()


def test_angles_share_the_directions_time_index(sight):
    angles, kept = kept_by(lambda: gaze.angles(sight, "camera"))
    assert np.shares_memory(_time_index_data(angles), _time_index_data(sight))
    assert angles.dims == ("time", "angle")
    assert list(angles["angle"].values) == ["azimuth", "elevation"]
    assert angles.name is None and angles.attrs["reference_frame"] == "camera"
    np.testing.assert_array_equal(angles["time"].values, sight["time"].values)
    # the values (n, 2) and nothing per sample beside them
    times = sight["time"].values.nbytes
    assert kept < angles.values.nbytes + 0.1 * times, (kept, angles.values.nbytes)


def test_rates_share_the_angles_time_index(sight):
    angles = gaze.angles(sight, "camera")
    rate, kept = kept_by(lambda: gaze.rates(angles))
    assert np.shares_memory(_time_index_data(rate), _time_index_data(angles))
    times = angles["time"].values.nbytes
    assert kept < rate.values.nbytes + 0.1 * times, (kept, rate.values.nbytes)
    # and the angles are not changed by it
    assert angles.attrs["units"] == "deg" and rate.attrs["units"] == "deg/s"


def test_angles_of_directions_without_a_time_coordinate():
    values = np.tile([0.0, 0.0, 1.0], (4, 1))
    bare = xr.DataArray(
        values, dims=("time", "cartesian_axis"), attrs={"representation_frame": "c"}
    )
    rbm.clear_registry()
    rbm.register_frame("c")
    try:
        out = gaze.angles(bare, "c")
    finally:
        rbm.clear_registry()
    np.testing.assert_array_equal(out["time"].values, np.arange(4))
    np.testing.assert_allclose(out.values, 0.0)


def test_directions_share_the_confidence_time_index(sight):
    confidence = xr.DataArray(
        np.linspace(0.0, 1.0, N),
        dims="time",
        coords={"time": sight["time"].values, "extra": ("time", np.arange(N))},
        name="confidence",
    )
    out, kept = kept_by(lambda: gaze.directions("eye", "camera", confidence=confidence))
    assert np.shares_memory(_time_index_data(out), _time_index_data(confidence))
    assert out.dims == ("time", "cartesian_axis") and out.name is None
    assert list(out.coords) == ["time", "cartesian_axis"]
    assert list(out["cartesian_axis"].values) == ["x", "y", "z"]
    assert out.attrs["representation_frame"] == "camera"
    np.testing.assert_array_equal(out.values[confidence.values < 0.6], np.nan)
    expected = gaze.directions("eye", "camera").values
    trusted = confidence.values >= 0.6
    np.testing.assert_array_equal(out.values[trusted], expected[trusted])
    times = confidence["time"].values.nbytes
    assert kept < out.values.nbytes + 0.1 * times, (kept, out.values.nbytes)
    # rows inserted in a gap: new times, so a new index
    gapped = confidence.isel(time=np.r_[0:1000, 2000:N])
    out = gaze.directions("eye", "camera", confidence=gapped, max_gap=0.5)
    assert out.sizes["time"] == gapped.sizes["time"] + 1
    assert np.isnan(out.values[1000]).all()


def test_directions_on_the_eyes_own_frozen_times_share_them():
    # no confidence: the result is along the eye frame's timestamps; read-only
    # ones (the loaders' are) are the time index, not two copies of it
    stamps = np.datetime64("2020-02-02", "ns") + np.arange(N) * np.timedelta64(
        2_941_176, "ns"
    )
    stamps.setflags(write=False)
    rbm.clear_registry()
    rbm.register_frame("camera")
    pitch = np.deg2rad(20.0 * np.sin(np.arange(N) / 500.0))
    rbm.register_frame(
        "eye", parent="camera", rotation=rbm.from_euler_angles(pitch=pitch),
        timestamps=stamps,
    )  # fmt: skip
    try:
        frame_times = rbm.registry["eye"].timestamps
        out, kept = kept_by(lambda: gaze.directions("eye", "camera"))
        assert np.shares_memory(_time_index_data(out), frame_times)
        assert np.shares_memory(out["time"].values, frame_times)
        assert kept < out.values.nbytes + 0.1 * stamps.nbytes, (kept, out.values.nbytes)
    finally:
        rbm.clear_registry()
