"""Bad input to the frame core gives a clear ValueError, never NaN or garbage."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm


@pytest.fixture
def world():
    rbm.register_frame("world")
    return rbm.registry["world"]


@pytest.fixture
def moving(world):
    ts = np.arange(10.0)
    rbm.register_frame(
        "moving", parent="world", translation=np.zeros((10, 3)), timestamps=ts
    )
    return ts


def test_unknown_frame_name_suggests_close_names(world):
    rbm.register_frame("head", parent="world")
    with pytest.raises(
        ValueError, match=r"'haed' not found in registry; did you mean 'head'\?"
    ):
        rbm.lookup_transform("haed", "world")
    with pytest.raises(ValueError, match="into: frame 'wrld'.*did you mean 'world'"):
        rbm.transform_points(np.zeros(3), into="wrld", outof="head")
    with pytest.raises(ValueError, match=r"registered: 'world', 'head'"):
        rbm.lookup_pose("zzzzzz", "world")
    with pytest.raises(ValueError, match="parent: frame 'wordl'"):
        rbm.register_frame("x", parent="wordl")
    with pytest.raises(ValueError, match="not found"):
        rbm.deregister_frame("nope")


def test_frame_of_wrong_type(world):
    with pytest.raises(TypeError, match="ReferenceFrame or the name"):
        rbm.lookup_transform(3, "world")


def test_frames_in_different_trees(world):
    rbm.register_frame("other_root")
    rbm.register_frame("leaf", parent="other_root")
    with pytest.raises(
        ValueError, match="different trees.*roots 'other_root' and 'world'"
    ):
        rbm.lookup_transform("leaf", "world")


def test_duplicate_registration_needs_update(world):
    with pytest.raises(ValueError, match="already registered; pass update=True"):
        rbm.register_frame("world")
    with pytest.raises(ValueError, match="without a name"):
        rbm.ReferenceFrame().register()


def test_parent_cycle_is_refused(world):
    rbm.register_frame("a", parent="world")
    rbm.register_frame("b", parent="a")
    with pytest.raises(ValueError, match="cycle"):
        world.parent = rbm.registry["b"]
    with pytest.raises(ValueError, match="cycle"):
        world.parent = world
    assert world.parent is None and rbm.registry["b"].path[0] is world


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (
            {"translation": np.zeros((5, 3)), "timestamps": np.arange(4.0)},
            r"translation must have shape \(4, 3\), got \(5, 3\)",
        ),
        (
            {"rotation": np.tile([1.0, 0, 0, 0], (3, 1)), "timestamps": np.arange(4.0)},
            r"rotation must have shape \(4, 4\)",
        ),
        ({"translation": np.zeros(4)}, r"translation must have shape \(3,\)"),
        ({"rotation": np.zeros(3)}, r"rotation must have shape \(4,\)"),
        ({"translation": np.zeros((4, 3))}, "needs timestamps"),
        (
            {"translation": np.zeros((4, 3)), "timestamps": np.zeros((4, 1))},
            "one-dimensional",
        ),
        (
            {"translation": np.zeros((0, 3)), "timestamps": np.zeros(0)},
            "must not be empty",
        ),
        ({"translation": [0.0, np.nan, 0.0]}, r"translation\[1\] is not finite"),
        ({"translation": ["a", "b", "c"]}, "must be numeric"),
    ],
)
def test_arrays_of_wrong_shape_or_values(world, kwargs, match):
    with pytest.raises(ValueError, match=match):
        rbm.ReferenceFrame("f", parent="world", **kwargs)


@pytest.mark.parametrize(
    "ts, match",
    [
        (
            np.array([0.0, 1.0, np.nan, 3.0]),
            r"timestamps\[2\] is nan; timestamps must be finite",
        ),
        (np.array([0.0, np.inf, 2.0, 3.0]), r"timestamps\[1\] is inf"),
        (
            np.array([0.0, 2.0, 1.0, 3.0]),
            r"strictly increasing: .*timestamps\[2\] = 1.0 is earlier than .*timestamps\[1\] = 2.0",
        ),
        (
            np.array([0.0, 1.0, 1.0, 3.0]),
            r"timestamps\[2\] = 1.0 is a duplicate of .*timestamps\[1\]",
        ),
        (
            np.array(
                ["2020-01-01", "NaT", "2020-01-03", "2020-01-04"],
                dtype="datetime64[ns]",
            ),
            r"timestamps\[1\] is NaT",
        ),
        (np.array(["a", "b", "c", "d"]), "numeric or datetime64"),
    ],
)
def test_bad_frame_timestamps(world, ts, match):
    with pytest.raises(ValueError, match=match):
        rbm.ReferenceFrame(
            "f", parent="world", translation=np.zeros((4, 3)), timestamps=ts
        )


def test_bad_array_timestamps(moving):
    arr = np.zeros((4, 3))
    with pytest.raises(
        ValueError, match=r"timestamps\[3\] = 2.0 is earlier than timestamps\[2\] = 3.0"
    ):
        rbm.transform_points(arr, "world", "moving", timestamps=[0.0, 1.0, 3.0, 2.0])
    with pytest.raises(ValueError, match=r"timestamps\[1\] = 0.0 is a duplicate"):
        rbm.transform_points(arr, "world", "moving", timestamps=[0.0, 0.0, 3.0, 4.0])
    with pytest.raises(ValueError, match="has 3 entries but the data has 4 samples"):
        rbm.transform_points(arr, "world", "moving", timestamps=[0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match=r"timestamps\[0\] is nan"):
        rbm.transform_vectors(
            arr, "world", "moving", timestamps=[np.nan, 1.0, 2.0, 3.0]
        )


@pytest.mark.parametrize(
    "rotation, match",
    [
        ([0.0, 0.0, 0.0, 0.0], "is a zero quaternion"),
        ([1.2, 0.0, 0.0, 0.0], "is of norm 1.2; rotations must be unit quaternions"),
        ([[1.0, 0, 0, 0], [0.5, 0, 0, 0]], r"rotation\[1\] is of norm 0.5"),
        ([[1.0, 0, 0, 0], [np.nan, 0, 0, 0]], r"rotation\[1\] is not finite"),
    ],
)
def test_zero_or_far_from_unit_quaternions(world, rotation, match):
    rotation = np.asarray(rotation)
    ts = np.arange(float(len(rotation))) if rotation.ndim == 2 else None
    with pytest.raises(ValueError, match=match):
        rbm.ReferenceFrame("f", parent="world", rotation=rotation, timestamps=ts)


def test_quaternion_arrays_are_checked_too(world):
    rbm.register_frame("f", parent="world")
    with pytest.raises(ValueError, match=r"arr\[1\] is of norm 2"):
        rbm.transform_quaternions(
            np.array([[1.0, 0, 0, 0], [2.0, 0, 0, 0]]), "world", "f"
        )
    with pytest.raises(ValueError, match=r"length 4 along axis -1"):
        rbm.transform_quaternions(np.zeros((2, 3)), "world", "f")
    with pytest.raises(ValueError, match=r"length 3 along axis -1"):
        rbm.transform_points(np.zeros((2, 4)), "world", "f")
    with pytest.raises(ValueError, match="axis=2 is out of range"):
        rbm.transform_points(np.zeros((2, 3)), "world", "f", axis=2)


def test_no_overlap_between_array_and_frames(moving):
    arr = np.zeros((5, 3))
    with pytest.raises(
        ValueError,
        match=r"do not overlap.*frame 'moving': 0.0 to 9.0; array 0: 20.0 to 24.0",
    ):
        rbm.transform_points(arr, "world", "moving", timestamps=np.arange(20.0, 25.0))


def test_no_overlap_between_frames(world):
    rbm.register_frame(
        "early",
        parent="world",
        translation=np.zeros((3, 3)),
        timestamps=[0.0, 1.0, 2.0],
    )
    rbm.register_frame(
        "late", parent="world", translation=np.zeros((3, 3)), timestamps=[5.0, 6.0, 7.0]
    )
    with pytest.raises(ValueError, match="do not overlap"):
        rbm.lookup_transform("early", "late")


def test_datetime_mixed_with_float(moving):
    ts = np.arange(4).astype("datetime64[s]")
    with pytest.raises(
        ValueError, match="cannot match datetime64 timestamps with numeric"
    ):
        rbm.transform_points(np.zeros((4, 3)), "world", "moving", timestamps=ts)
    rbm.register_frame(
        "dated", parent="world", translation=np.zeros((4, 3)), timestamps=ts
    )
    with pytest.raises(ValueError, match="cannot match datetime64"):
        rbm.lookup_transform("dated", "moving")


def test_what_outside_the_three_modes(moving):
    arr = np.zeros((10, 3))
    for func in (rbm.transform_angular_velocity, rbm.transform_linear_velocity):
        with pytest.raises(
            ValueError,
            match="what must be one of 'reference_frame', 'moving_frame', 'representation_frame', got 'frame'",
        ):
            func(arr, "world", "moving", what="frame", timestamps=np.arange(10.0))
    with pytest.raises(ValueError, match="what must be one of"):
        rbm.registry["moving"].transform_angular_velocity(arr, "world", what="nope")


def test_missing_frames_for_velocity_transforms(moving):
    arr = np.zeros((10, 3))
    with pytest.raises(ValueError, match="moving_frame must be given"):
        rbm.transform_linear_velocity(
            arr, "world", "moving", timestamps=np.arange(10.0)
        )
    with pytest.raises(ValueError, match="reference_frame must be given"):
        rbm.transform_linear_velocity(
            arr, "world", "moving", what="moving_frame", timestamps=np.arange(10.0)
        )


def test_root_frames_and_discrete_without_timestamps(world):
    with pytest.raises(ValueError, match="translation given without a parent"):
        rbm.ReferenceFrame("r", translation=(1, 0, 0))
    with pytest.raises(ValueError, match="discrete=True needs timestamps"):
        rbm.ReferenceFrame("d", parent="world", discrete=True)
    with pytest.raises(ValueError, match="name must be a string"):
        rbm.ReferenceFrame(5)
    with pytest.raises(ValueError, match="has no parent"):
        rbm.lookup_twist("world")


def test_outof_needed_and_dim_needs_dataarray(moving):
    with pytest.raises(ValueError, match="outof must be given"):
        rbm.transform_points(np.zeros(3), "world")
    with pytest.raises(
        ValueError, match="dim can only be given when arr is a DataArray"
    ):
        rbm.transform_points(np.zeros(3), "world", "moving", dim="x")
    with pytest.raises(ValueError, match="same axis"):
        rbm.transform_points(
            np.zeros((3, 3)),
            "world",
            "moving",
            axis=0,
            time_axis=0,
            timestamps=np.arange(3.0),
        )


def test_unknown_velocity_mode(moving):
    with pytest.raises(ValueError, match="mode must be"):
        rbm.lookup_angular_velocity("moving", mode="euler")


def test_dataarray_argument_errors(moving):
    xr = pytest.importorskip("xarray")
    da = xr.DataArray(
        np.zeros((10, 3)),
        coords={"time": np.arange(10.0)},
        dims=("time", "cartesian_axis"),
        attrs={"reference_frame": "moving"},
    )
    with pytest.raises(ValueError, match="dim='space' is not a dimension"):
        rbm.transform_points(da, "world", dim="space")
    with pytest.raises(ValueError, match="either dim or axis"):
        rbm.transform_points(da, "world", dim="cartesian_axis", axis=-1)
    with pytest.raises(ValueError, match="the name of a dimension"):
        rbm.transform_points(da, "world", timestamps=np.arange(10.0))
    ds = xr.Dataset({"p": da})
    with pytest.raises(ValueError, match="rotation='orientation' is not a variable"):
        rbm.ReferenceFrame.from_dataset(ds, "p", "orientation", "time", "world")


def test_rotation_matrix_checks(world):
    with pytest.raises(ValueError, match=r"shape \(3, 3\)"):
        rbm.ReferenceFrame.from_rotation_matrix(np.eye(4), world)
    with pytest.raises(
        ValueError, match=r"mat: .*not a rotation matrix.*reflection.*tol"
    ):
        rbm.ReferenceFrame.from_rotation_matrix(np.diag([1.0, 1.0, -1.0]), world)
    with pytest.raises(ValueError, match=r"mat: .*not a rotation matrix"):
        rbm.ReferenceFrame.from_rotation_matrix(2 * np.eye(3), world)
