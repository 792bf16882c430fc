"""DataArrays along frozen timestamps keep them as their index (issue 35).

``xr.DataArray(values, coords={"time": times})`` holds two copies of the
times with pandas 3 (the index's and the coordinate's deep copy).
``_infra.time_index.dataarray_on`` builds the same DataArray with the times
themselves as its index when nobody can change them, and copies them (as
xarray does) when the caller still can.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from memory_support import kept_by

from rbm_nb._infra.time_index import dataarray_on

N = 300_000


def _times(frozen: bool) -> np.ndarray:
    t = np.datetime64("2020-02-02", "ns") + np.arange(N) * np.timedelta64(5, "ms")
    t.setflags(write=not frozen)
    return t


@pytest.mark.parametrize("frozen", [True, False])
def test_the_same_dataarray_as_xarrays_constructor(frozen):
    times, values = _times(frozen), np.arange(2.0 * N).reshape(N, 2)
    out = dataarray_on(
        values, times, ("time", "eye"), {"eye": ["left", "right"]},
        attrs={"units": "deg"}, name="yaw",
    )  # fmt: skip
    expected = xr.DataArray(
        values, coords={"time": times, "eye": ["left", "right"]},
        dims=("time", "eye"), attrs={"units": "deg"}, name="yaw",
    )  # fmt: skip
    xr.testing.assert_identical(out, expected)
    assert np.shares_memory(out.values, values)
    assert out.sel(time=times[7]).values.tolist() == [14.0, 15.0]


def test_frozen_times_are_the_index_and_no_copy_is_kept():
    times, values = _times(True), np.zeros(N)
    dataarray_on(values[:3], times[:3], ("time",))  # xarray's first-use imports
    out, kept = kept_by(lambda: dataarray_on(values, times, ("time",)))
    assert np.shares_memory(np.asarray(out.indexes["time"]), times)
    assert np.shares_memory(out["time"].values, times)
    assert kept < 0.1 * times.nbytes, kept


def test_writeable_times_are_copied():
    times, values = _times(False), np.zeros(N)
    out = dataarray_on(values, times, ("time",))
    assert not np.shares_memory(out["time"].values, times)
    first = times[0].copy()
    times[:] = times[-1]  # the caller's array changes; the result does not
    assert out["time"].values[0] == first
