"""transform_* functions: axes, shapes, timestamps and DataArray handling."""

from __future__ import annotations

import warnings

import naive
import numpy as np
import pytest

import rbm_nb as rbm

xr = pytest.importorskip("xarray")

Q90Z = np.array([np.sqrt(0.5), 0, 0, np.sqrt(0.5)])


@pytest.fixture
def moving_tree():
    rbm.register_frame("world")
    rbm.register_frame("static", parent="world", translation=(1, 0, 0), rotation=Q90Z)
    ts = np.arange(0.0, 2.01, 0.1)
    n = len(ts)
    angle = np.linspace(0, 1, n)
    rot = np.column_stack(
        [np.cos(angle / 2), np.zeros(n), np.zeros(n), np.sin(angle / 2)]
    )
    trans = np.column_stack([ts, np.zeros(n), np.zeros(n)])
    rbm.register_frame(
        "moving", parent="world", translation=trans, rotation=rot, timestamps=ts
    )
    return ts, trans, rot


def test_static_point_through_moving_frame_gets_a_time_axis(moving_tree):
    ts, trans, rot = moving_tree
    out, out_ts = rbm.transform_points(
        np.zeros(3), into="world", outof="moving", return_timestamps=True
    )
    np.testing.assert_allclose(out, trans)
    np.testing.assert_array_equal(out_ts, ts)
    # several untimestamped points: one block per timestamp
    pts = np.eye(3)
    out = rbm.transform_points(pts, into="world", outof="moving")
    assert out.shape == (len(ts), 3, 3)
    np.testing.assert_allclose(
        out[:, 0], naive.rotate_vectors(rot, np.tile([1.0, 0, 0], (len(ts), 1))) + trans
    )


def test_axis_and_time_axis(moving_tree):
    ts, _, _ = moving_tree
    rng = np.random.default_rng(0)
    arr = rng.normal(size=(len(ts), 3))
    expected = rbm.transform_vectors(arr, into="world", outof="static", timestamps=ts)
    out = rbm.transform_vectors(
        arr.T, into="world", outof="static", axis=0, time_axis=1, timestamps=ts
    )
    np.testing.assert_allclose(out, expected.T)
    # extra axes: (time, k, 3) and (3, k, time)
    arr3 = rng.normal(size=(len(ts), 2, 3))
    out3 = rbm.transform_points(arr3, into="world", outof="moving", timestamps=ts)
    for k in range(2):
        np.testing.assert_allclose(
            out3[:, k],
            rbm.transform_points(
                arr3[:, k], into="world", outof="moving", timestamps=ts
            ),
        )
    out3t = rbm.transform_points(
        arr3.transpose(2, 1, 0),
        into="world",
        outof="moving",
        axis=0,
        time_axis=2,
        timestamps=ts,
    )
    np.testing.assert_allclose(out3t, out3.transpose(2, 1, 0))


def test_untimestamped_array_through_static_chain_keeps_its_shape():
    rbm.register_frame("world")
    rbm.register_frame("s", parent="world", rotation=Q90Z)
    arr = np.arange(24.0).reshape(2, 4, 3)
    out = rbm.transform_vectors(arr, into="world", outof="s")
    assert out.shape == arr.shape
    np.testing.assert_allclose(out[..., 0], -arr[..., 1])
    np.testing.assert_allclose(out[..., 1], arr[..., 0])


def test_quaternion_dtype_input(moving_tree):
    import quaternion

    ts, _, rot = moving_tree
    q = quaternion.as_quat_array(rot)
    out = rbm.transform_quaternions(q, into="world", outof="static", timestamps=ts)
    np.testing.assert_allclose(out, naive.qmul(np.tile(Q90Z, (len(ts), 1)), rot))


def test_timestamps_of_result_are_the_arrays_inside_the_frames_range(moving_tree):
    ts, _, _ = moving_tree
    arr_ts = np.arange(-0.55, 3.0, 0.1)
    arr = np.zeros((len(arr_ts), 3))
    out, out_ts = rbm.transform_points(
        arr, into="world", outof="moving", timestamps=arr_ts, return_timestamps=True
    )
    inside = (arr_ts >= ts[0]) & (arr_ts <= ts[-1])
    np.testing.assert_array_equal(out_ts, arr_ts[inside])
    np.testing.assert_allclose(out[:, 0], arr_ts[inside], atol=1e-12)


def test_datetime_timestamps_come_back_as_datetime():
    rbm.register_frame("world")
    t0 = np.datetime64("2020-02-02T00:27:14.300365210")
    ts = t0 + (np.arange(50) * 5_000_000).astype("timedelta64[ns]")
    trans = np.column_stack([np.arange(50) * 0.005, np.zeros(50), np.zeros(50)])
    rbm.register_frame("head", parent="world", translation=trans, timestamps=ts)
    arr_ts = t0 + (np.arange(30) * 7_000_000 + 1_234_567).astype("timedelta64[ns]")
    out, out_ts = rbm.transform_points(
        np.zeros((30, 3)), "world", "head", timestamps=arr_ts, return_timestamps=True
    )
    assert out_ts.dtype == arr_ts.dtype
    np.testing.assert_array_equal(out_ts, arr_ts[: len(out_ts)])
    # x moves 1 m/s: the interpolated position is the exact elapsed time,
    # which float epoch nanoseconds (the reference's way) cannot resolve
    elapsed = (out_ts - t0) / np.timedelta64(1, "s")
    np.testing.assert_allclose(out[:, 0], elapsed, rtol=0, atol=1e-12)


def test_discrete_frame_holds_events():
    rbm.register_frame("world")
    events = np.array([0.0, 1.0, 2.5])
    trans = np.array([[1.0, 0, 0], [2, 0, 0], [3, 0, 0]])
    rbm.register_frame(
        "d", parent="world", translation=trans, timestamps=events, discrete=True
    )
    arr_ts = np.linspace(-1, 4, 51)
    out, out_ts = rbm.transform_points(
        np.zeros((51, 3)), "world", "d", timestamps=arr_ts, return_timestamps=True
    )
    np.testing.assert_array_equal(
        out_ts, arr_ts
    )  # discrete frames do not limit the range
    np.testing.assert_allclose(out, naive.hold_last(events, trans, arr_ts))
    # without arrays, the events themselves are the timestamps
    t, r, ts = rbm.lookup_transform("d", "world", return_timestamps=True)
    np.testing.assert_array_equal(ts, events)
    np.testing.assert_allclose(t, trans)


def _da(ts, frame_attr="reference_frame", frame="static"):
    rng = np.random.default_rng(1)
    return xr.DataArray(
        rng.normal(size=(len(ts), 3)),
        coords={
            "time": ts,
            "cartesian_axis": ["x", "y", "z"],
            "label": ("time", np.arange(len(ts)).astype(str)),
        },
        dims=("time", "cartesian_axis"),
        name="v",
        attrs={frame_attr: frame, "units": "m"},
    )


def test_dataarray_in_dataarray_out(moving_tree):
    ts, _, _ = moving_tree
    da = _da(ts)
    out = rbm.transform_points(da, into="world")
    assert isinstance(out, xr.DataArray)
    assert out.dims == da.dims and out.name == "v"
    assert out.attrs == {
        "reference_frame": "world",
        "representation_frame": "world",
        "units": "m",
    }
    np.testing.assert_array_equal(out.label.values, da.label.values)
    np.testing.assert_allclose(
        out.values, rbm.transform_points(da.values, "world", "static", timestamps=ts)
    )
    assert da.attrs["reference_frame"] == "static"  # input untouched


def test_dataarray_timestamps_change_and_coords_follow(moving_tree):
    ts, _, _ = moving_tree
    arr_ts = np.arange(-0.45, 2.6, 0.1)
    da = _da(arr_ts, frame="moving")
    da = da.assign_coords(quality=("time", np.linspace(0, 1, len(arr_ts))))
    out = rbm.transform_points(da, into="world")
    kept = (arr_ts >= 0) & (arr_ts <= 2.0 + 1e-12)
    np.testing.assert_array_equal(out.time.values, arr_ts[kept])
    np.testing.assert_allclose(out.quality.values, da.quality.values[kept])
    np.testing.assert_array_equal(out.label.values, da.label.values[kept])


def test_dataarray_dim_and_named_timestamps(moving_tree):
    ts, _, _ = moving_tree
    da = _da(ts).transpose("cartesian_axis", "time")
    out = rbm.transform_vectors(
        da, into="world", outof="static", dim="cartesian_axis", timestamps="time"
    )
    assert out.dims == ("cartesian_axis", "time")
    expected = rbm.transform_vectors(da.values.T, "world", "static")
    np.testing.assert_allclose(out.values, expected.T)


def test_single_vector_dataarray_through_moving_frame_gains_time(moving_tree):
    ts, _, _ = moving_tree
    da = xr.DataArray(
        [1.0, 0, 0],
        coords={"cartesian_axis": list("xyz")},
        dims="cartesian_axis",
        attrs={"representation_frame": "moving"},
    )
    out = rbm.transform_vectors(da, into="world")
    assert out.dims == ("time", "cartesian_axis")
    np.testing.assert_array_equal(out.time.values, ts)


def test_outof_differs_from_attrs_warns(moving_tree):
    ts, _, _ = moving_tree
    with pytest.warns(UserWarning, match="attrs say"):
        rbm.transform_points(_da(ts, frame="static"), into="world", outof="moving")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rbm.transform_points(_da(ts, frame="static"), into="world", outof="static")


def test_velocity_dataarray_attrs(moving_tree):
    ts, _, _ = moving_tree
    da = _da(ts, frame_attr="reference_frame", frame="static").assign_attrs(
        moving_frame="moving"
    )
    out = rbm.transform_angular_velocity(da, into="world", what="reference_frame")
    assert out.attrs["reference_frame"] == "world"
    assert out.attrs["representation_frame"] == "world"
    out = rbm.transform_linear_velocity(
        da.assign_attrs(representation_frame="static"),
        into="world",
        what="representation_frame",
    )
    assert out.attrs["representation_frame"] == "world"
    np.testing.assert_allclose(
        out.values, rbm.transform_vectors(da.values, "world", "static")
    )


def test_angular_velocity_reference_frame_adds_the_frames_rotation_rate(moving_tree):
    ts, _, _ = moving_tree
    # "moving" turns about z at 0.5 rad/s wrt world (1 rad over 2 s)
    w = np.zeros((len(ts), 3))
    out = rbm.transform_angular_velocity(w, into="world", outof="moving", timestamps=ts)
    np.testing.assert_allclose(out, np.tile([0, 0, 0.5], (len(ts), 1)), atol=1e-3)
