"""The synthetic head/eye recording: schema, determinism and physics.

The physical numbers are measured from the datasets by
``rbm_nb.data._measures`` (also printed by ``benchmarks/synthetic_checks.py``).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm
from rbm_nb.data import _measures as measures
from rbm_nb.data import load_example, synthetic_head_eye, write_synthetic_rosbag
from rbm_nb.data.fetch import ExampleDataStore
from rbm_nb.ros import RosbagReader


@pytest.fixture(scope="module")
def rec():
    """The default 5.5-minute recording, generated once for the module."""
    return synthetic_head_eye()


@pytest.fixture(scope="module")
def short():
    return synthetic_head_eye(duration=30.0, seed=3)


def test_schema_of_head_nc(rec):
    head = rec.head
    assert list(head.data_vars) == [
        "position",
        "linear_velocity",
        "angular_velocity",
        "confidence",
        "orientation",
    ]
    assert dict(head.sizes) == {
        "time": 66000,
        "cartesian_axis": 3,
        "quaternion_axis": 4,
    }
    assert head.time.dtype == np.dtype("datetime64[ns]")
    assert list(head.cartesian_axis.values) == ["x", "y", "z"]
    assert list(head.quaternion_axis.values) == ["w", "x", "y", "z"]
    for name in ("position", "linear_velocity", "angular_velocity"):
        assert head[name].dims == ("time", "cartesian_axis")
    assert head.orientation.dims == ("time", "quaternion_axis")
    assert head.confidence.dims == ("time",)
    assert head.position.attrs == {"long_name": "Position", "units": "m"}
    assert head.linear_velocity.attrs["units"] == "m/s"
    assert head.angular_velocity.attrs["units"] == "rad/s"
    assert head.attrs["source"] == "synthetic (rbm_nb)"
    assert str(head.time.values[0]) == "2020-02-02T00:27:14.300365210"


def test_schema_of_eye_datasets(rec):
    for eye in (rec.left_eye, rec.right_eye):
        assert list(eye.data_vars) == ["position", "orientation", "confidence"]
        assert eye.position.dims == ("time", "cartesian_axis")
        assert eye.orientation.dims == ("time", "quaternion_axis")
        assert eye.attrs["source"] == "synthetic (rbm_nb)"
        assert eye.attrs["scene_camera_rotation"].shape == (4,)
    # own rate (~343.5 Hz), own offsets, inside the head recording
    for eye in (rec.left_eye, rec.right_eye):
        dt = np.diff(eye.time.values) / np.timedelta64(1, "s")
        assert (dt > 0).all()
        assert abs(1 / dt.mean() - 343.5) < 0.5
        assert 113_000 < eye.sizes["time"] < 113_400
        assert (
            rec.head.time.values[0] < eye.time.values[0]
            and eye.time.values[-1] < rec.head.time.values[-1]
        )
    assert rec.left_eye.time.values[0] != rec.right_eye.time.values[0]


def test_netcdf_round_trip(short, tmp_path):
    for name, ds in short._asdict().items():
        ds.to_netcdf(tmp_path / f"{name}.nc")
        back = xr.load_dataset(tmp_path / f"{name}.nc")
        xr.testing.assert_identical(back.drop_attrs(), ds.drop_attrs())


def test_deterministic_for_a_seed():
    a, b = synthetic_head_eye(20.0, seed=7), synthetic_head_eye(20.0, seed=7)
    c = synthetic_head_eye(20.0, seed=8)
    for x, y, z in zip(a, b, c, strict=True):
        xr.testing.assert_identical(x, y)
        assert not np.array_equal(x.orientation.values, z.orientation.values)


def test_quaternions_are_unit_and_eyes_obey_listing(rec):
    for ds in rec:
        np.testing.assert_allclose(
            np.linalg.norm(ds.orientation.values, axis=1), 1.0, atol=1e-12
        )
    for eye in (rec.left_eye, rec.right_eye):
        # no torsion about the primary (camera z) direction: Listing's law
        np.testing.assert_array_equal(eye.orientation.values[:, 3], 0.0)
        gaze_z = 1.0 - 2.0 * (
            eye.orientation.values[:, 1] ** 2 + eye.orientation.values[:, 2] ** 2
        )
        # never beyond the oculomotor range
        assert gaze_z.min() > np.cos(np.deg2rad(60.0))


def test_t265_world_convention(rec):
    head = rec.head
    # world origin at the tracker's start, heading = initial facing (yaw 0)
    np.testing.assert_allclose(head.position.values[0], 0.0, atol=1e-12)
    q0 = head.orientation.values[0]
    forward = rbm.rotate_vectors(q0, np.array([0.0, 0.0, -1.0]))
    assert abs(forward[0]) < 1e-9 and forward[2] < -0.9
    # two laps: back where it started, having gone round a building
    assert np.linalg.norm(head.position.values[-1] - head.position.values[0]) < 1.0
    extent = np.ptp(head.position.values, axis=0)
    assert 30 < extent[0] < 80 and 40 < extent[2] < 100 and extent[1] < 0.1


def test_walking_speed(rec):
    assert 1.35 < measures.mean_walking_speed(rec.head) < 1.55


def test_guide_1_5_head_frame_velocity(rec):
    """Guide 1.5's finding: about -1.4 m/s along z in the head frame."""
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_dataset(
        rec.head, "position", "orientation", "time", parent="world", name="head"
    ).register()
    v_head = rbm.transform_linear_velocity(
        rec.head.linear_velocity,
        outof="world",
        into="head",
        what="representation_frame",
    )
    mean = np.asarray(v_head).mean(axis=0)
    assert -1.5 < mean[2] < -1.3
    assert abs(mean[0]) < 0.2 and abs(mean[1]) < 0.3
    np.testing.assert_allclose(measures.head_frame_velocity(rec.head), mean, rtol=1e-9)


def test_head_bob_at_step_frequency(rec):
    frequency, rms = measures.bob(rec.head)
    assert 1.8 <= frequency <= 2.0
    assert 0.005 < rms < 0.03


def test_saccades_follow_the_main_sequence(rec):
    for eye in (rec.left_eye, rec.right_eye):
        s = measures.saccades(eye, rec.head)
        assert 1.5 < s["rate"] < 4.5
        assert 250 < s["peak_median"] < 500
        assert s["peak_p95"] > 400 and s["peak_max"] < 800
        assert s["peak_amplitude_correlation"] > 0.7


def test_vor_keeps_gaze_still_during_head_turns(rec):
    for eye in (rec.left_eye, rec.right_eye):
        assert 0.9 < measures.vor_gain(eye, rec.head) < 1.1


def test_blinks(rec):
    for eye in (rec.left_eye, rec.right_eye):
        conf = eye.confidence.values
        assert conf.min() >= 0.0 and conf.max() <= 1.0
        assert 0.01 < measures.blink_fraction(eye) < 0.06
    # both eyes blink together
    left = np.interp(
        rec.right_eye.time.values.astype(np.int64),
        rec.left_eye.time.values.astype(np.int64),
        rec.left_eye.confidence.values,
    )
    both = (left < 0.5) == (rec.right_eye.confidence.values < 0.5)
    assert both.mean() > 0.99
    assert set(np.unique(rec.head.confidence.values)) <= {1 / 3, 2 / 3, 1.0}


def test_velocities_agree_with_estimators(rec):
    lin_rms, ang_rms = measures.estimator_consistency(rec.head)
    assert lin_rms < 1e-3  # m/s, against speeds of ~1.4
    assert ang_rms < 1e-3  # rad/s, against head turns of ~1


def test_velocities_agree_with_lookups(short):
    head = short.head
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_dataset(
        head, "position", "orientation", "time", parent="world", name="head"
    ).register()
    v = rbm.lookup_linear_velocity("head", "world")
    w = rbm.lookup_angular_velocity("head", "world", represent_in="world")
    np.testing.assert_allclose(np.asarray(v), head.linear_velocity.values, atol=2e-3)
    np.testing.assert_allclose(np.asarray(w), head.angular_velocity.values, atol=2e-3)


def test_eye_frames_chain_into_world(short):
    """The eye datasets plug into a frame tree through the documented camera pose."""
    head, left = short.head, short.left_eye
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_dataset(
        head, "position", "orientation", "time", parent="world", name="head"
    ).register()
    rbm.register_frame(
        "scene_camera",
        parent="head",
        translation=left.attrs["scene_camera_translation"],
        rotation=left.attrs["scene_camera_rotation"],
    )
    rbm.ReferenceFrame.from_dataset(
        left, "position", "orientation", "time", parent="scene_camera", name="left_eye"
    ).register()
    gaze = rbm.transform_vectors(
        np.array([0.0, 0.0, 1.0]), outof="left_eye", into="world"
    )
    # people look ahead and down at the path, not behind or at the sky
    assert np.median(np.asarray(gaze)[..., 1]) < 0.0


def test_bad_arguments():
    with pytest.raises(ValueError, match="duration must be at least 15 s"):
        synthetic_head_eye(duration=5.0)
    with pytest.raises(ValueError, match="head_rate must be a positive finite number"):
        synthetic_head_eye(duration=20.0, head_rate=0.0)
    with pytest.raises(ValueError, match="eye_rate"):
        synthetic_head_eye(duration=20.0, eye_rate=float("nan"))
    with pytest.raises(ValueError, match="laps must be a positive integer"):
        synthetic_head_eye(duration=20.0, laps=1.5)


def test_synthetic_rosbag_has_the_example_topics(tmp_path, short):
    path = write_synthetic_rosbag(tmp_path / "walk.bag", duration=30.0, seed=3)
    with RosbagReader(path) as reader:
        assert reader.get_topics_and_types() == {
            "/pupil/left_eye/transform": "geometry_msgs/TransformStamped",
            "/pupil/right_eye/transform": "geometry_msgs/TransformStamped",
            "/t265/transform": "geometry_msgs/TransformStamped",
        }
        head = reader.load_dataset("/t265/transform")
        right = reader.load_messages("/pupil/right_eye/transform")
    np.testing.assert_array_equal(head.position.values, short.head.position.values)
    np.testing.assert_array_equal(head.time.values, short.head.time.values)
    np.testing.assert_array_equal(
        right["orientation"], short.right_eye.orientation.values
    )
    assert (
        head.attrs["frame_id"] == "t265/world"
        and head.attrs["child_frame_id"] == "t265/tracker"
    )


@pytest.mark.slow
def test_synthetic_example_bag_is_built_once(tmp_path, monkeypatch):
    store = ExampleDataStore(data_dir=tmp_path)
    path = load_example("rosbag", source="synthetic", store=store)
    assert path.parent.parent == tmp_path and path.suffix == ".bag"
    stamp = path.stat().st_mtime_ns
    assert load_example("rosbag", source="synthetic", store=store) == path
    assert path.stat().st_mtime_ns == stamp
    with RosbagReader(path) as reader:
        assert len(reader.load_messages("/t265/transform")["timestamps"]) == 66000


def test_guide_1_6_runs_offline_on_the_synthetic_bag(tmp_path, capsys):
    """Guide 1.6's cells up to the ROS-only part, unchanged, on the synthetic bag."""
    import pandas as pd

    path = write_synthetic_rosbag(tmp_path / "example.bag", duration=30.0)
    reader = rbm.ros.RosbagReader(path)
    with reader:
        info = reader.get_topics_and_types()
    assert info == {
        "/pupil/left_eye/transform": "geometry_msgs/TransformStamped",
        "/pupil/right_eye/transform": "geometry_msgs/TransformStamped",
        "/t265/transform": "geometry_msgs/TransformStamped",
    }
    with reader:
        head = reader.load_messages("/t265/transform")
    assert sorted(head) == ["orientation", "position", "timestamps"]
    rbm.register_frame("world")
    R_T265_ROS = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    rbm.ReferenceFrame.from_rotation_matrix(
        R_T265_ROS, parent="world", name="t265/world"
    ).register()
    rbm.register_frame(
        "t265/tracker",
        parent="t265/world",
        translation=head["position"],
        rotation=head["orientation"],
        timestamps=pd.to_datetime(head["timestamps"], unit="s"),
    )
    rbm.ReferenceFrame.from_rotation_matrix(
        R_T265_ROS, parent="t265/tracker", name="head", inverse=True
    ).register()
    rbm.render_tree("world")
    tree = capsys.readouterr().out
    for name in ("world", "t265/world", "t265/tracker", "head"):
        assert name in tree
    # in ROS convention (x forward) the walk goes along the head's +x
    v = rbm.lookup_linear_velocity("head", "world", represent_in="head")
    mean = np.asarray(v).mean(axis=0)
    assert 0.9 < mean[0] < 1.5 and abs(mean[1]) < 0.3 and abs(mean[2]) < 0.3
