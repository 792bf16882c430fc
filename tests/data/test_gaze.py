"""rbm_nb.gaze: lines of sight with missing and low-confidence samples masked."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from recordings import recording

import rbm_nb as rbm
from rbm_nb.core import gaze
from rbm_nb.core.quaternions import rotate_vectors

T = np.arange(6) * 0.1


def _eye_tree(yaw_head=None):
    """world -> head (turning about z) -> eye (pitching about y)."""
    rbm.register_frame("world")
    yaw_head = np.linspace(0.0, 1.0, T.size) if yaw_head is None else yaw_head
    rbm.register_frame(
        "head", parent="world", timestamps=T,
        translation=np.c_[T, 0 * T, 0 * T], rotation=rbm.from_euler_angles(yaw=yaw_head),
    )  # fmt: skip
    pitch = np.deg2rad(np.linspace(-20.0, 30.0, T.size))
    q_eye = rbm.from_euler_angles(pitch=pitch)
    rbm.register_frame("eye", parent="head", timestamps=T, rotation=q_eye)
    return rbm.from_euler_angles(yaw=yaw_head), q_eye


def test_directions_equal_the_explicit_rotation_chain():
    q_head, q_eye = _eye_tree()
    out = gaze.directions("eye", "world")
    z = np.array([0.0, 0.0, 1.0])
    expected = rotate_vectors(q_head, rotate_vectors(q_eye, z, one_to_one=False))
    assert out.dims == ("time", "cartesian_axis")
    assert out.attrs["representation_frame"] == "world"
    np.testing.assert_allclose(out.values, expected, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(out.values, axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(out.time.values, T)


def test_low_and_nan_confidence_are_masked_and_the_rest_untouched():
    _eye_tree()
    full = gaze.directions("eye", "head")
    conf = np.array([0.9, 0.59, 0.6, np.nan, 1.0, 0.1])
    out = gaze.directions("eye", "head", confidence=conf)
    masked = np.isnan(out.values).all(axis=1)
    np.testing.assert_array_equal(masked, [False, True, False, True, False, True])
    np.testing.assert_array_equal(out.values[~masked], full.values[~masked])
    lower = gaze.directions("eye", "head", confidence=conf, min_confidence=0.05)
    np.testing.assert_array_equal(np.isnan(lower.values).all(1), np.isnan(conf))


def test_times_missing_from_the_frame_are_nan_on_the_confidence_clock():
    """A frame registered after dropna: the dropped rows come back as NaN."""
    rbm.register_frame("cam")
    t_all = np.arange(8) * 0.01
    keep = np.array([1, 1, 0, 1, 0, 0, 1, 1], bool)
    q = rbm.from_euler_angles(yaw=np.linspace(0, 0.3, 8))
    rbm.register_frame("eye", parent="cam", timestamps=t_all[keep], rotation=q[keep])
    conf = xr.DataArray(np.full(8, 0.9), dims="time", coords={"time": t_all})
    out = gaze.directions("eye", "cam", confidence=conf)
    np.testing.assert_array_equal(out.time.values, t_all)
    np.testing.assert_array_equal(np.isnan(out.values).all(1), ~keep)
    expected = rotate_vectors(q[keep], np.array([0, 0, 1.0]), one_to_one=False)
    np.testing.assert_allclose(out.values[keep], expected, atol=1e-14)


def test_max_gap_inserts_one_nan_row_per_gap():
    rbm.register_frame("cam")
    t = np.array([0.0, 0.01, 0.02, 0.5, 0.51, 1.7])
    rbm.register_frame(
        "eye", parent="cam", timestamps=t, rotation=np.tile([1.0, 0, 0, 0], (6, 1))
    )
    out = gaze.directions("eye", "cam", max_gap=0.1)
    np.testing.assert_allclose(
        out.time.values, [0, 0.01, 0.02, 0.26, 0.5, 0.51, 1.105, 1.7]
    )
    np.testing.assert_array_equal(np.isnan(out.values).all(1), [0, 0, 0, 1, 0, 0, 1, 0])
    assert gaze.directions("eye", "cam", max_gap=2.0).sizes["time"] == 6


def test_max_gap_with_datetime_times():
    rbm.register_frame("cam")
    t = np.datetime64("2020-01-01T00:00:00", "ns") + np.array(
        [0, 10, 900, 910], "timedelta64[ms]"
    )
    rbm.register_frame(
        "eye", parent="cam", timestamps=t, rotation=np.tile([1.0, 0, 0, 0], (4, 1))
    )
    out = gaze.directions("eye", "cam", max_gap=0.1)
    assert out.sizes["time"] == 5
    assert out.time.values[2] == t[1] + np.timedelta64(445, "ms")


def test_angles_camera_and_ros_conventions():
    rbm.register_frame("cam")
    # azimuth 30 deg right, elevation 10 deg up in camera axes (y down)
    az, el = np.deg2rad(30.0), np.deg2rad(10.0)
    d_cam = np.array([np.sin(az) * np.cos(el), -np.sin(el), np.cos(az) * np.cos(el)])
    da = xr.DataArray(
        np.vstack([d_cam, [np.nan] * 3]), dims=("time", "cartesian_axis"),
        coords={"time": [0.0, 1.0]}, attrs={"representation_frame": "cam"},
    )  # fmt: skip
    out = gaze.angles(da, "cam")
    np.testing.assert_allclose(out.values[0], [30.0, 10.0], atol=1e-12)
    assert np.isnan(out.values[1]).all()
    # a ROS frame (x forward, y left, z up) looking along the camera's z axis
    r_ros = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    rbm.ReferenceFrame.from_rotation_matrix(r_ros, parent="cam", name="ros").register()
    np.testing.assert_allclose(
        gaze.angles(da, "ros", forward="x", up="z").values[0], [30.0, 10.0], atol=1e-12
    )


def test_angles_in_a_moving_reference():
    q_head, q_eye = _eye_tree(yaw_head=np.zeros(T.size))
    sight = gaze.directions("eye", "world")
    # pitch about y tips z towards x: azimuth = pitch in camera convention
    out = gaze.angles(sight, "eye", forward="z", up="-y")
    np.testing.assert_allclose(out.values, 0.0, atol=1e-10)
    in_head = gaze.angles(sight, "head")
    np.testing.assert_allclose(
        in_head.sel(angle="azimuth"), np.linspace(-20, 30, T.size), atol=1e-10
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"confidence": [0.1, 0.2]}, "confidence must have shape"),
        ({"min_confidence": float("nan")}, "min_confidence must be finite"),
        ({"max_gap": 0.0}, "max_gap must be positive"),
        ({"max_gap": "1s"}, "max_gap must be a number"),
    ],
)
def test_directions_bad_arguments(kwargs, match):
    _eye_tree()
    with pytest.raises(ValueError, match=match):
        gaze.directions("eye", "world", **kwargs)


def test_bad_frames_and_directions():
    _eye_tree()
    with pytest.raises(ValueError, match="eye_frame.*not_there|not_there"):
        gaze.directions("not_there", "world")
    with pytest.raises(ValueError, match="root frame"):
        gaze.directions("world", "world")
    rbm.register_frame("fixed", parent="world", rotation=(1.0, 0, 0, 0))
    with pytest.raises(ValueError, match="static"):
        gaze.directions("fixed", "world")
    sight = gaze.directions("eye", "world")
    with pytest.raises(ValueError, match="representation_frame"):
        gaze.angles(sight.copy(data=sight.values).drop_attrs(), "world")
    with pytest.raises(ValueError, match="different axes"):
        gaze.angles(sight, "world", forward="z", up="-z")
    with pytest.raises(ValueError, match="one of x, y, z"):
        gaze.angles(sight, "world", forward="w")


def test_recording_gaze_is_masked_and_within_60_degrees():
    """On the real recording (else synthetic): the issue's acceptance numbers."""
    from rbm_nb.app.explorer import register_head_eye_frames

    head, left, right, source = recording()
    register_head_eye_frames(head, left, right)
    for name, eye in (("left_eye", left), ("right_eye", right)):
        sight = gaze.directions(
            f"pupil/{name}", "pupil/scene_cam", confidence=eye.confidence
        )
        np.testing.assert_array_equal(sight.time.values, eye.time.values)
        drawn = np.isfinite(sight.values).all(axis=1)
        missing = eye.orientation.isnull().any("quaternion_axis").values
        missing |= eye.position.isnull().any("cartesian_axis").values  # dropna'd rows
        np.testing.assert_array_equal(drawn, ~missing & (eye.confidence.values >= 0.6))
        eccentricity = np.degrees(np.arccos(np.clip(sight.values[drawn, 2], -1, 1)))
        assert np.mean(eccentricity > 60.0) <= 0.001, (source, name)
        np.testing.assert_allclose(
            np.linalg.norm(sight.values[drawn], axis=1), 1.0, atol=1e-12
        )
        in_world = gaze.directions(f"pupil/{name}", "world", confidence=eye.confidence)
        both = drawn & np.isfinite(in_world.values).all(axis=1)
        assert both.sum() > 0.9 * drawn.sum()
        # the angle between gaze and head forward does not depend on the frame
        fwd = gaze.angles(in_world, "pupil/scene_cam")
        np.testing.assert_allclose(
            fwd.values[both],
            gaze.angles(sight, "pupil/scene_cam").values[both],
            atol=1e-8,
        )


def test_nan_rows_of_the_eye_frame_are_missing_samples():
    """Frames that keep NaN rows (missing data) give NaN there."""
    rbm.register_frame("world")
    rbm.register_frame(
        "head", parent="world", timestamps=T, rotation=rbm.from_euler_angles(yaw=T)
    )
    q = rbm.from_euler_angles(pitch=np.linspace(0.0, 0.5, T.size))
    with_gaps = q.copy()
    with_gaps[[1, 4]] = np.nan
    rbm.register_frame("eye", parent="head", timestamps=T, rotation=with_gaps)
    out = gaze.directions("eye", "world", confidence=np.full(T.size, 0.9))
    np.testing.assert_array_equal(np.isnan(out.values).any(1), [0, 1, 0, 0, 1, 0])
    np.testing.assert_array_equal(np.isnan(out.values).all(1), [0, 1, 0, 0, 1, 0])
    z = np.array([0.0, 0.0, 1.0])
    expected = rotate_vectors(
        rbm.from_euler_angles(yaw=T), rotate_vectors(q, z, one_to_one=False)
    )
    keep = [0, 2, 3, 5]
    np.testing.assert_allclose(out.values[keep], expected[keep], atol=1e-12)
