"""The DataArray.rbm accessor (rbm_nb/core/accessors.py)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest
import xarray as xr
from conftest import REPO

from rbm_nb.core.accessors import DataArrayAccessor
from rbm_nb.core.quaternions import from_euler_angles, qinterp, qinv

RNG = np.random.default_rng(11)


@pytest.fixture(autouse=True)
def _our_accessor():
    """Make sure ``DataArray.rbm`` is ours.

    rigid-body-motion registers an accessor under the same name when it is
    imported (other test modules use it as an oracle); whichever registers
    last wins, so re-register ours for these tests.
    """
    if not isinstance(xr.DataArray([0.0]).rbm, DataArrayAccessor):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            xr.register_dataarray_accessor("rbm")(DataArrayAccessor)
    yield


def orientation(n=20, time=None):
    q = from_euler_angles(np.cumsum(RNG.normal(0, 0.1, (n, 3)), axis=0))
    time = np.arange(n) * 0.1 if time is None else time
    return xr.DataArray(
        q,
        {
            "time": time,
            "quaternion_axis": list("wxyz"),
            "confidence": ("time", np.linspace(0, 1, n)),
            "source": ("time", [f"s{i}" for i in range(n)]),
        },
        ("time", "quaternion_axis"),
        name="orientation",
        attrs={"long_name": "Orientation"},
    )


@pytest.mark.parametrize("order", ["rbm_nb first", "xarray first"])
def test_accessor_is_registered_in_a_fresh_interpreter(order):
    imports = (
        "import rbm_nb\nimport xarray as xr"
        if order == "rbm_nb first"
        else ("import xarray as xr\nimport rbm_nb")
    )
    script = imports + textwrap.dedent(
        """
        import sys
        assert "rbm_nb.core.quaternions" not in sys.modules  # registering loads no numerics
        da = xr.DataArray([[0.0, 0.0, 0.0, 2.0]], dims=("time", "quaternion_axis"))
        out = da.rbm.qinv()
        assert type(da.rbm).__module__ == "rbm_nb.core.accessors"
        print(out.values.tolist())
        """
    )
    env = dict(os.environ, PYTHONPATH=str(REPO))
    result = subprocess.run(
        [sys.executable, "-c", script],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[[0.0, -0.0, -0.0, -0.5]]"


def test_accessor_stores_only_the_object():
    da = orientation()
    accessor = DataArrayAccessor(da)
    assert vars(accessor) == {"_obj": da}


def test_qinv():
    da = orientation()
    out = da.rbm.qinv()
    assert out.name == "orientation" and out.attrs == da.attrs
    xr.testing.assert_identical(out.coords.to_dataset(), da.coords.to_dataset())
    np.testing.assert_allclose(out.values, qinv(da.values))
    transposed = da.T.rbm.qinv()
    np.testing.assert_allclose(transposed.values, out.values.T)
    renamed = da.rename(quaternion_axis="q")
    np.testing.assert_allclose(renamed.rbm.qinv(qdim="q").values, out.values)


def test_qinterp_values_and_coords():
    da = orientation()
    new_time = np.linspace(0.02, 1.82, 13)  # no ties between two old samples
    out = da.rbm.qinterp(time=new_time)
    assert out.dims == da.dims and out.name == "orientation" and out.attrs == da.attrs
    np.testing.assert_array_equal(out.time, new_time)
    np.testing.assert_allclose(out.values, qinterp(da.values, da.time.values, new_time))
    np.testing.assert_allclose(
        out.confidence, np.interp(new_time, da.time, da.confidence)
    )
    nearest = [f"s{int(i)}" for i in np.round(new_time / 0.1)]
    assert list(out.source.values) == nearest
    xr.testing.assert_identical(da.rbm.qinterp({"time": new_time}), out)


def test_qinterp_datetime_dataarray_coordinate_and_scalar():
    start = np.datetime64("2020-02-02T00:27:14.300365210", "ns")
    time = start + (np.arange(20) * 1e8).astype("timedelta64[ns]")
    da = orientation(time=time)
    target = xr.DataArray(
        time[:-1] + np.timedelta64(50, "ms"), dims="time", name="time"
    )
    out = da.rbm.qinterp(time=target)
    np.testing.assert_array_equal(out.time.values, target.values)
    seconds = np.arange(20) * 0.1
    np.testing.assert_allclose(
        out.values, qinterp(da.values, seconds, seconds[:-1] + 0.05), atol=1e-12
    )
    single = da.rbm.qinterp(time=time[3])
    assert single.dims == ("quaternion_axis",)
    np.testing.assert_allclose(single.values, da.values[3], atol=1e-12)


def test_qinterp_out_of_range_gives_nan_like_interp():
    da = orientation()
    out = da.rbm.qinterp(time=[-0.5, 0.5, 5.0])
    assert np.isnan(out.values[[0, 2]]).all()
    np.testing.assert_allclose(
        out.values[1], qinterp(da.values, da.time.values, [0.5])[0]
    )
    expected_conf = da.confidence.interp(time=[-0.5, 0.5, 5.0]).values
    np.testing.assert_array_equal(
        np.isnan(out.confidence.values), np.isnan(expected_conf)
    )


def test_qinterp_other_layouts():
    da = orientation()
    stacked = xr.concat([da, da], dim="body").transpose(
        "quaternion_axis", "body", "time"
    )
    out = stacked.rbm.qinterp(time=[0.25, 0.75])
    assert out.dims == ("quaternion_axis", "body", "time")
    expected = da.rbm.qinterp(time=[0.25, 0.75]).values.T
    np.testing.assert_allclose(out.values[:, 1, :], expected)


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda da: da.rbm.qinterp(), "exactly one dimension"),
        (lambda da: da.rbm.qinterp(time=[0.1], quaternion_axis=[0]), "exactly one"),
        (lambda da: da.rbm.qinterp({"time": [0.1]}, time=[0.2]), "either as coords"),
        (lambda da: da.rbm.qinterp(frame=[0.1]), "not a dimension"),
        (lambda da: da.rbm.qinterp(time=[0.1], qdim="q"), "qdim 'q'"),
        (lambda da: da.rbm.qinterp(quaternion_axis=[0.1]), "quaternion dimension"),
        (lambda da: da.rbm.qinterp(time=[[0.1, 0.2]]), "one-dimensional"),
        (
            lambda da: da.isel(quaternion_axis=[0, 1, 2]).rbm.qinterp(time=[0.1]),
            "length 4",
        ),
        (lambda da: da.rbm.qinv(qdim="q"), "qdim 'q'"),
        (lambda da: (0 * da).rbm.qinv(), "zero quaternion"),
        (lambda da: da.drop_vars("time").rbm.qinterp(time=[0.1]), "no coordinate"),
    ],
)
def test_bad_input_raises_value_error(call, match):
    with pytest.raises(ValueError, match=match):
        call(orientation())
