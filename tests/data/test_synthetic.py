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
        assert list(eye.data_vars) == ["confidence", "position", "orientation"]
        assert eye.position.dims == ("time", "cartesian_axis")
        assert eye.orientation.dims == ("time", "quaternion_axis")
        assert eye.confidence.attrs == {"long_name": "3d gaze mapper confidence"}
        assert eye.attrs["source"] == "synthetic (rbm_nb)"
        assert eye.attrs["scene_camera_rotation"].shape == (4,)
        for axis in ("cartesian_axis", "quaternion_axis"):
            assert eye[axis].dtype == np.dtype("<U1")
    # both eyes on one clock near 400 Hz, inside the head recording
    np.testing.assert_array_equal(rec.left_eye.time.values, rec.right_eye.time.values)
    np.testing.assert_array_equal(
        rec.left_eye.confidence.values, rec.right_eye.confidence.values
    )
    dt = np.diff(rec.left_eye.time.values) / np.timedelta64(1, "s")
    assert (dt > 0).all()
    assert 380 < 1 / np.median(dt) < 420
    assert 105_000 < rec.left_eye.sizes["time"] < 118_000
    assert (
        rec.head.time.values[0] < rec.left_eye.time.values[0]
        and rec.left_eye.time.values[-1] < rec.head.time.values[-1]
    )


def test_tracker_flaws_at_the_real_recordings_rates(rec):
    """NaN rows, low confidence and dropouts as in the real eye files."""
    for eye in (rec.left_eye, rec.right_eye):
        q = measures.tracker_quality(eye)
        # real: ~33,000-37,000 NaN rows of 113,373; 30-33 % below 0.6
        assert 0.25 < q["nan_rows"] / q["rows"] < 0.36
        assert 0.25 < q["low_confidence"] < 0.36
        assert q["gaps_over_0.1s"] >= 2
        # real: 0.5-0.7, ~4 and 11-14 mm; the eyeball centre varies a little
        assert (q["position_std"] > 2e-4).all() and (q["position_std"] < 0.02).all()
        orientation_nan = eye.orientation.isnull().any("quaternion_axis").values
        position_nan = eye.position.isnull().any("cartesian_axis").values
        # lost pupils: orientation missing where the eyeball centre is known
        assert (position_nan & ~orientation_nan).sum() == 0
        assert (orientation_nan & ~position_nan).sum() > 0.01 * q["rows"]
        assert (
            eye.confidence.values[orientation_nan & ~position_nan] == 0
        ).mean() > 0.9


def test_low_confidence_gaze_is_what_the_threshold_removes(rec):
    """Wild samples exist below 0.6 (as in the real data) and not above it."""
    for eye in (rec.left_eye, rec.right_eye):
        q = eye.orientation.values
        gaze_z = 1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2)
        eccentricity = np.degrees(np.arccos(np.clip(gaze_z, -1, 1)))
        confident = measures.usable_eye_rows(eye)
        low = np.isfinite(gaze_z) & ~confident
        assert np.mean(eccentricity[low] > 60) > 0.001
        assert np.mean(eccentricity[confident] > 60) < 0.001


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
        q = ds.orientation.values
        q = q[np.isfinite(q).all(axis=1)]
        assert len(q) > 0.6 * ds.sizes["time"]
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    for eye in (rec.left_eye, rec.right_eye):
        q = eye.orientation.values[measures.usable_eye_rows(eye)]
        # no torsion about the primary (camera z) direction: Listing's law
        np.testing.assert_array_equal(q[:, 3], 0.0)
        gaze_z = 1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2)
        # confident samples stay within the oculomotor range
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
    # both eyes blink together: runs of 80-400 ms with no data for either eye
    left = rec.left_eye.position.isnull().any("cartesian_axis").values
    right = rec.right_eye.position.isnull().any("cartesian_axis").values
    edges = np.diff(np.r_[0, (left & right).astype(int), 0])
    runs = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    duration = rec.head.sizes["time"] / 200.0
    assert 5 < (runs >= 20).sum() / duration * 60 < 30  # blinks per minute
    # T265 confidence levels as the real head.nc stores them (0-3)
    assert set(np.unique(rec.head.confidence.values)) <= {1.0, 2.0, 3.0}
    assert rec.head.confidence.attrs == {}


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
        left.dropna("time"),
        "position",
        "orientation",
        "time",
        parent="scene_camera",
        name="left_eye",
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
    with pytest.raises(ValueError, match="eye_rate must be a positive finite number"):
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
    # NaN rows included, bit for bit
    np.testing.assert_array_equal(
        right["orientation"], short.right_eye.orientation.values
    )
    assert np.isnan(right["orientation"]).any()
    assert (
        head.attrs["frame_id"] == "t265/world"
        and head.attrs["child_frame_id"] == "t265/tracker"
    )


@pytest.mark.slow
def test_synthetic_example_bag_is_built_once(tmp_path, monkeypatch):
    """Built once into the cache folder; nothing lands in the data folder."""
    monkeypatch.setenv("RBM_NB_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "data"))
    (tmp_path / "data").mkdir()
    store = ExampleDataStore(data_dir=tmp_path / "data")
    path = load_example("rosbag", source="synthetic", store=store)
    assert path.parent.parent == tmp_path / "cache" and path.suffix == ".bag"
    assert list((tmp_path / "data").iterdir()) == []
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


def _schema(ds) -> dict:
    """Everything about a dataset's layout, nothing about its values."""
    return {
        "variables": list(ds.data_vars),
        "coords": list(ds.coords),
        "sizes_keys": list(ds.sizes),
        **{
            f"{kind} {name}": (ds[name].dims, ds[name].dtype, ds[name].attrs)
            for kind, names in (("var", ds.data_vars), ("coord", ds.coords))
            for name in names
        },
        "axis labels": (
            list(ds.cartesian_axis.values),
            list(ds.quaternion_axis.values),
        ),
    }


def test_schema_equals_the_real_files_field_by_field(rec):
    """Every variable, coordinate, dtype and attribute as in the real .nc files."""
    from recordings import real_recording

    real = real_recording()
    if real is None:
        pytest.skip(
            "the real recordings are not beside the repo (../shared/data/rbm-data)"
        )
    for name, ours, theirs in zip(
        ("head", "left_eye", "right_eye"), rec, real, strict=True
    ):
        a, b = _schema(ours), _schema(theirs)
        assert a.keys() == b.keys(), name
        for key in a:
            assert a[key] == b[key], (
                f"{name}: {key}: synthetic {a[key]} != real {b[key]}"
            )
        # the only extras are the synthetic recording's provenance attributes
        assert theirs.attrs == {} and ours.attrs["source"] == "synthetic (rbm_nb)"


def test_tracker_flaws_close_to_the_real_recordings(rec):
    """Measured on both with the same code: rates within a few percent."""
    from recordings import real_recording

    real = real_recording()
    if real is None:
        pytest.skip(
            "the real recordings are not beside the repo (../shared/data/rbm-data)"
        )
    for ours, theirs in ((rec.left_eye, real[1]), (rec.right_eye, real[2])):
        a, b = measures.tracker_quality(ours), measures.tracker_quality(theirs)
        assert abs(a["nan_rows"] / a["rows"] - b["nan_rows"] / b["rows"]) < 0.05
        assert abs(a["low_confidence"] - b["low_confidence"]) < 0.05
        assert abs(a["rows_per_second"] / b["rows_per_second"] - 1) < 0.05
        assert abs(a["median_interval"] / b["median_interval"] - 1) < 0.1
        assert a["gaps_over_0.1s"] >= 1 and b["gaps_over_0.1s"] >= 1
        ratio = a["position_std"] / b["position_std"]
        assert ((ratio > 0.3) & (ratio < 3)).all(), ratio
