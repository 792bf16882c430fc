"""gaze.directions(max_angle=...) and gaze.rates (issue 29)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm
from rbm_nb.core import gaze


@pytest.fixture
def eye():
    rbm.clear_registry()
    rbm.register_frame("camera")
    pitch = np.deg2rad([0.0, 30.0, 49.0, 51.0, 89.0, 10.0])
    q = rbm.from_euler_angles(pitch=pitch)
    rbm.register_frame(
        "eye", parent="camera", rotation=q, timestamps=np.arange(6) * 0.01
    )
    yield "eye"
    rbm.clear_registry()


def test_max_angle_flags_gaze_beyond_the_oculomotor_range(eye):
    loose = gaze.directions(eye, "camera")
    strict = gaze.directions(eye, "camera", max_angle=gaze.OCULOMOTOR_RANGE)
    assert np.isfinite(loose.values).all()
    np.testing.assert_array_equal(
        np.isfinite(strict.values).all(axis=1), [True, True, True, False, False, True]
    )
    with pytest.raises(ValueError, match="max_angle"):
        gaze.directions(eye, "camera", max_angle=0.0)
    with pytest.raises(ValueError, match="max_angle"):
        gaze.directions(eye, "camera", max_angle=float("nan"))


def test_rates_are_slopes_over_valid_samples():
    t = np.arange(0.0, 0.1, 0.003)  # no sample on a window edge
    angle = 200.0 * t  # 200 deg/s
    angle[[5, 6, 20]] = np.nan  # missing samples: rates there are NaN, not around
    da = xr.DataArray(np.c_[angle, -angle], dims=("time", "eye"), coords={"time": t})
    rate = gaze.rates(da)
    assert rate.attrs["units"] == "deg/s" and rate.dims == ("time", "eye")
    finite = np.isfinite(angle)
    # at the two ends the valid samples span less than half the window: NaN
    inner = finite.copy()
    inner[[0, -1]] = False
    np.testing.assert_allclose(rate.values[inner, 0], 200.0, rtol=1e-9)
    np.testing.assert_allclose(rate.values[inner, 1], -200.0, rtol=1e-9)
    assert np.isnan(rate.values[~inner]).all()
    # datetime times give the same rates
    stamps = np.datetime64("2020-02-02", "ns") + np.round(t * 1e9).astype(
        "timedelta64[ns]"
    )
    rate_dt = gaze.rates(da.assign_coords(time=stamps))
    np.testing.assert_allclose(rate_dt.values, rate.values, rtol=1e-6)
    with pytest.raises(ValueError, match="window"):
        gaze.rates(da, window=0.0)
    with pytest.raises(ValueError, match="time"):
        gaze.rates(xr.DataArray(angle, dims=("t",)))
