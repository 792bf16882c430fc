"""rbm_nb.evaluation against evo (test-only oracle) on the same trajectories."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.core import evaluation as ev
from rbm_nb.core.conversions import quaternion_from_rotation_vector
from rbm_nb.core.quaternions import qmul

evo_metrics = pytest.importorskip("evo.core.metrics")
from evo.core import geometry, sync, trajectory  # noqa: E402

PR = evo_metrics.PoseRelation
RELATIONS = {
    "translation": PR.translation_part,
    "rotation": PR.rotation_part,
    "full": PR.full_transformation,
    "angle_deg": PR.rotation_angle_deg,
    "angle_rad": PR.rotation_angle_rad,
    "point_distance": PR.point_distance,
}
STAT_KEYS = ("rmse", "mean", "median", "std", "min", "max", "sse")


def random_walk(n, seed=0, dt=0.01):
    rng = np.random.default_rng(seed)
    t = 100.0 + dt * np.arange(n)
    p = np.cumsum(rng.normal(scale=0.02, size=(n, 3)), axis=0)
    q = quaternion_from_rotation_vector(
        np.cumsum(rng.normal(scale=0.03, size=(n, 3)), axis=0)
    )
    return t, p, np.asarray(q)


def corrupt(t, p, q, seed=1, scale=1.0):
    """A drifting, noisy, rotated and scaled copy (what an odometry gives)."""
    rng = np.random.default_rng(seed)
    tt = (t - t[0])[:, None]
    drift = np.cumsum(rng.normal(scale=2e-3, size=p.shape), axis=0) + 0.01 * tt * [
        1,
        -0.5,
        0.2,
    ]
    offset = quaternion_from_rotation_vector([0.1, -0.2, 0.3])
    rot_noise = quaternion_from_rotation_vector(
        np.cumsum(rng.normal(scale=1e-3, size=p.shape), axis=0)
    )
    pe = rbm.rotate_vectors(offset, scale * (p + drift)) + [0.5, -1.0, 2.0]
    qe = qmul(offset, qmul(rot_noise, q))
    return t, np.asarray(pe), np.asarray(qe)


def evo_pair(ref, est, max_diff=0.01, method=None):
    a = trajectory.PoseTrajectory3D(
        positions_xyz=ref[1], orientations_quat_wxyz=ref[2], timestamps=ref[0]
    )
    b = trajectory.PoseTrajectory3D(
        positions_xyz=est[1], orientations_quat_wxyz=est[2], timestamps=est[0]
    )
    kwargs = {"max_diff": max_diff}
    if method is not None:
        kwargs["sync_method"] = method
    return sync.associate_trajectories(a, b, **kwargs)


def evo_ape(ref, est, relation, align=False, correct_scale=False, n=-1, **sync_kw):
    tr, te = evo_pair(ref, est, **sync_kw)
    if align or correct_scale:
        te.align(tr, correct_scale=correct_scale,
                 correct_only_scale=correct_scale and not align, n=n)  # fmt: skip
    metric = evo_metrics.APE(RELATIONS[relation])
    metric.process_data((tr, te))
    return metric


def assert_same(result, metric, atol):
    np.testing.assert_allclose(result.error.values, metric.error, rtol=0, atol=atol)
    stats = metric.get_all_statistics()
    for key in STAT_KEYS:
        assert result.stats[key] == pytest.approx(stats[key], rel=1e-10, abs=atol), key


@pytest.fixture(scope="module")
def walk():
    ref = random_walk(400)
    return ref, corrupt(*ref)


# --------------------------------------------------------------------------- alignment


@pytest.mark.parametrize("with_scale", [False, True])
def test_umeyama_matches_evo(walk, with_scale):
    ref, est = walk
    R, t, s = ev.umeyama_alignment(est[1], ref[1], with_scale=with_scale)
    r2, t2, s2 = geometry.umeyama_alignment(est[1].T, ref[1].T, with_scale)
    np.testing.assert_allclose(R, r2, atol=1e-12)
    np.testing.assert_allclose(t, t2, atol=1e-12)
    assert s == pytest.approx(s2, rel=1e-12)


def test_umeyama_recovers_a_similarity_and_refuses_collinear_points():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(50, 3))
    R = np.asarray(rbm.conversions.matrix_from_quaternion(
        quaternion_from_rotation_vector([0.3, -1.0, 2.0])))  # fmt: skip
    y = 1.7 * x @ R.T + [1, 2, 3]
    R1, t1, s1 = ev.umeyama_alignment(x, y, with_scale=True)
    np.testing.assert_allclose(R1, R, atol=1e-12)
    np.testing.assert_allclose(t1, [1, 2, 3], atol=1e-12)
    assert s1 == pytest.approx(1.7, rel=1e-12)
    line = np.outer(np.arange(5.0), [1, 2, 3])
    with pytest.raises(ValueError, match="degenerate"):
        ev.umeyama_alignment(line, line + 1)


# --------------------------------------------------------------------------- APE


@pytest.mark.parametrize("relation", list(RELATIONS))
@pytest.mark.parametrize(
    ("align", "correct_scale"),
    [(False, False), (True, False), (True, True), (False, True)],
)
def test_ape_matches_evo(walk, relation, align, correct_scale):
    ref, est = walk
    got = ev.ape(
        ref, est, align=align, correct_scale=correct_scale, pose_relation=relation
    )
    want = evo_ape(ref, est, relation, align, correct_scale)
    assert_same(got, want, atol=1e-12)
    assert got.unit == ev.POSE_RELATIONS[relation]


def test_ape_first_n_alignment_matches_evo(walk):
    ref, est = walk
    got = ev.ape(ref, est, align=True, correct_scale=True, n_to_align=50)
    assert_same(got, evo_ape(ref, est, "translation", True, True, n=50), atol=1e-12)
    assert (
        got.alignment["scale"]
        != ev.ape(ref, est, align=True, correct_scale=True).alignment["scale"]
    )


def test_ape_alignment_removes_an_exact_similarity():
    ref = random_walk(300, seed=5)
    _, pe, qe = corrupt(*ref, scale=0.5)
    # same similarity without drift or noise: sim3 alignment makes it exact
    offset = quaternion_from_rotation_vector([0.1, -0.2, 0.3])
    pe = np.asarray(rbm.rotate_vectors(offset, 0.5 * ref[1])) + [0.5, -1.0, 2.0]
    qe = np.asarray(qmul(offset, ref[2]))
    for relation in ("translation", "full", "angle_deg"):
        res = ev.ape(ref, (ref[0], pe, qe), align=True, correct_scale=True,
                     pose_relation=relation)  # fmt: skip
        assert res.stats["max"] < 1e-6, relation
    assert res.alignment["scale"] == pytest.approx(2.0, rel=1e-12)


def test_reference_subsampled_matches_evo_nearest_association(walk):
    ref, est = walk
    sub = tuple(a[::3] for a in ref)
    got = ev.ape(sub, est, pose_relation="full")
    assert len(got.error) == len(sub[0])
    assert_same(got, evo_ape(sub, est, "full"), atol=1e-12)


def test_differently_sampled_estimate_is_interpolated_like_evo_positions(walk):
    """Estimate sampled 4x denser and shifted: both interpolate positions linearly."""
    ref, _ = walk
    rng = np.random.default_rng(8)
    t_est = np.linspace(ref[0][0] - 0.004, ref[0][-1] - 0.02, 4 * len(ref[0]))
    p_est = np.stack([np.interp(t_est, ref[0], ref[1][:, k]) for k in range(3)], axis=1)
    p_est += np.cumsum(rng.normal(scale=1e-3, size=p_est.shape), axis=0)
    q_est = np.tile([1.0, 0, 0, 0], (len(t_est), 1))
    est = (t_est, p_est, q_est)
    got = ev.ape(ref, est)
    # evo interpolates the longer trajectory at the shorter one's timestamps
    want = evo_ape(
        ref, est, "translation", max_diff=0.01, method=sync.SyncMethod.interpolation
    )
    inside = ref[0] <= t_est[-1]
    assert len(got.error) == inside.sum()
    np.testing.assert_allclose(got.error.values, want.error[: inside.sum()], atol=1e-12)


# --------------------------------------------------------------------------- RPE

RPE_CASES = [
    (1, "frames", False),
    (7, "frames", False),
    (7, "frames", True),
    (0.1, "meters", False),
    (0.1, "meters", True),
    (10, "degrees", False),
    (0.2, "radians", False),
    (8, "degrees", True),
]


@pytest.mark.parametrize(("delta", "unit", "all_pairs"), RPE_CASES)
@pytest.mark.parametrize(
    "relation", ["translation", "rotation", "full", "angle_deg", "point_distance",
                 "point_distance_error_ratio"],
)  # fmt: skip
def test_rpe_matches_evo(walk, delta, unit, all_pairs, relation):
    ref, est = walk
    got = ev.rpe(ref, est, delta=delta, delta_unit=unit, all_pairs=all_pairs,
                 pose_relation=relation)  # fmt: skip
    tr, te = evo_pair(ref, est)
    evo_rel = RELATIONS.get(relation, PR.point_distance_error_ratio)
    metric = evo_metrics.RPE(evo_rel, delta=delta, delta_unit=evo_metrics.Unit[unit],
                             all_pairs=all_pairs)  # fmt: skip
    metric.process_data((tr, te))
    np.testing.assert_array_equal(got.pairs[:, 1], metric.delta_ids)
    np.testing.assert_array_equal(got.error["time"].values, ref[0][metric.delta_ids])
    assert_same(got, metric, atol=1e-11)


def test_rpe_pairs_from_reference_match_evo(walk):
    ref, est = walk
    got = ev.rpe(ref, est, delta=0.2, delta_unit="meters", pairs_from_reference=True)
    tr, te = evo_pair(ref, est)
    metric = evo_metrics.RPE(PR.translation_part, delta=0.2, delta_unit=evo_metrics.Unit.meters,
                             pairs_from_reference=True)  # fmt: skip
    metric.process_data((tr, te))
    assert_same(got, metric, atol=1e-12)


# --------------------------------------------------------------------------- the real head track


@pytest.fixture(scope="module")
def head(shared_data):
    xr = pytest.importorskip("xarray")
    ds = xr.load_dataset(shared_data / "rbm-data" / "head.nc")
    t, p, q = corrupt(
        (ds.time.values - ds.time.values[0]) / np.timedelta64(1, "s"),
        ds.position.values, ds.orientation.values / np.linalg.norm(
            ds.orientation.values, axis=1, keepdims=True),
        seed=11, scale=1.05,
    )  # fmt: skip
    drifted = ds[["position", "orientation"]].copy()
    drifted["position"] = (("time", "cartesian_axis"), p)
    drifted["orientation"] = (("time", "quaternion_axis"), q)
    return ds, drifted


def _seconds(ds):
    t = (ds.time.values - ds.time.values[0]) / np.timedelta64(1, "s")
    q = ds.orientation.values
    return t, ds.position.values, q / np.linalg.norm(q, axis=1, keepdims=True)


def test_head_track_ape_sim3_matches_evo(head):
    ds, drifted = head
    got = ev.ape(ds, drifted, align=True, correct_scale=True)
    assert got.error["time"].dtype.kind == "M" and len(got.error) == ds.sizes["time"]
    want = evo_ape(_seconds(ds), _seconds(drifted), "translation", True, True)
    assert_same(got, want, atol=1e-12)
    assert got.alignment["scale"] == pytest.approx(1 / 1.05, rel=0.05)


def test_head_track_ape_angle_and_rpe_match_evo(head):
    # every third sample: evo's rotation relations loop over 4x4 matrices in Python
    ds, drifted = (d.isel(time=slice(None, None, 3)) for d in head)
    ref, est = _seconds(ds), _seconds(drifted)
    got = ev.ape(ds, drifted, align=True, pose_relation="angle_deg")
    assert_same(got, evo_ape(ref, est, "angle_deg", True), atol=1e-10)
    got = ev.rpe(ds, drifted, delta=200, pose_relation="full")
    tr, te = evo_pair(ref, est)
    metric = evo_metrics.RPE(PR.full_transformation, delta=200)
    metric.process_data((tr, te))
    assert_same(got, metric, atol=1e-12)


# --------------------------------------------------------------------------- frames, results


def test_frame_names_and_register_aligned(walk):
    ref, est = walk
    rbm.register_frame("world")
    rbm.register_frame("truth", parent="world", translation=ref[1], rotation=ref[2],
                       timestamps=ref[0])  # fmt: skip
    rbm.register_frame("odometry", parent="world", translation=est[1], rotation=est[2],
                       timestamps=est[0])  # fmt: skip
    by_name = ev.ape("truth", "odometry", align=True, pose_relation="full")
    by_tuple = ev.ape(ref, est, align=True, pose_relation="full")
    np.testing.assert_array_equal(by_name.error.values, by_tuple.error.values)
    frame = by_name.register_aligned("odometry_aligned", "world")
    assert rbm.registry["odometry_aligned"] is frame
    p, _ = rbm.lookup_pose("odometry_aligned", "world")
    aligned = ev.ape(ref, est, align=True)
    np.testing.assert_allclose(
        np.linalg.norm(p - ref[1], axis=1), aligned.error.values, atol=1e-12
    )
    # the aligned frame is on the reference within the APE
    assert ev.ape("truth", "odometry_aligned").stats["rmse"] == pytest.approx(
        aligned.stats["rmse"], rel=1e-12
    )


def test_plot_draws_error_and_statistics(walk):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    result = ev.rpe(*walk, delta=5)
    ax = result.plot()
    assert len(ax.lines) == 4 and ax.get_title() == "RPE w.r.t. translation"
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), result.error.values)
    plt.close(ax.figure)
    assert "rmse" in repr(result) and "delta = 5 frames" in repr(result)


def test_evo_pose_relation_names_are_accepted(walk):
    a = ev.ape(*walk, pose_relation="rotation angle in degrees")
    b = ev.ape(*walk, pose_relation="angle_deg")
    np.testing.assert_array_equal(a.error.values, b.error.values)


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda r, e: ev.ape(r, e, pose_relation="yaw"), ValueError, "pose_relation must be"),
        (lambda r, e: ev.ape(r, e, pose_relation="point_distance_error_ratio"), ValueError,
         "pose_relation must be"),
        (lambda r, e: ev.ape(r, (e[0] + 100, e[1], e[2])), ValueError, "overlap in 0"),
        (lambda r, e: ev.ape(r, (e[0], e[1][:, :2], e[2])), ValueError, "estimate"),
        (lambda r, e: ev.ape(r, e, n_to_align=2, align=True), ValueError, "n_to_align"),
        (lambda r, e: ev.ape(r, e, n_to_align=10), ValueError, "needs align"),
        (lambda r, e: ev.ape(r, 42), TypeError, "estimate must be"),
        (lambda r, e: ev.ape("nope", e), ValueError, "reference"),
        (lambda r, e: ev.rpe(r, e, delta=1.5), ValueError, "positive integer"),
        (lambda r, e: ev.rpe(r, e, delta=1, delta_unit="seconds"), ValueError, "delta_unit"),
        (lambda r, e: ev.rpe(r, e, delta=1e6, delta_unit="meters"), ValueError, "no pose pairs"),
        (lambda r, e: ev.rpe(r, e, delta=-1), ValueError, "positive number"),
        (lambda r, e: ev.ape(r, ((e[0] * 1e3).astype("datetime64[ms]"), e[1], e[2])), ValueError,
         "both be datetime64"),
    ],
)  # fmt: skip
def test_bad_input_is_named(walk, call, error, match):
    with pytest.raises(error, match=match):
        call(*walk)


def test_static_frame_and_bad_dataset_are_refused(walk):
    xr = pytest.importorskip("xarray")
    rbm.register_frame("world")
    rbm.register_frame("fixed", parent="world", translation=[1, 0, 0])
    with pytest.raises(ValueError, match="'fixed' is static"):
        ev.ape("fixed", walk[1])
    ds = xr.Dataset({"position": (("time", "cartesian_axis"), walk[0][1])},
                    coords={"time": walk[0][0]})  # fmt: skip
    with pytest.raises(ValueError, match="no orientation variable"):
        ev.ape(ds, walk[1])


def test_collinear_alignment_is_refused():
    t = np.arange(10.0)
    p = np.c_[t, 2 * t, 3 * t]
    q = np.tile([1.0, 0, 0, 0], (10, 1))
    with pytest.raises(ValueError, match="degenerate"):
        ev.ape((t, p, q), (t, p + 1, q), align=True)


def test_docstring_examples_run():
    import doctest

    result = doctest.testmod(ev, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 5 and result.failed == 0


def test_frame_argument_looks_both_up_in_another_frame(walk):
    ref, est = walk
    rbm.register_frame("world")
    rbm.register_frame("map", parent="world", translation=[1.0, 2.0, 3.0],
                       rotation=quaternion_from_rotation_vector([0.0, 0.4, 1.0]))  # fmt: skip
    rbm.register_frame("truth", parent="world", translation=ref[1], rotation=ref[2],
                       timestamps=ref[0])  # fmt: skip
    rbm.register_frame("odometry", parent="world", translation=est[1], rotation=est[2],
                       timestamps=est[0])  # fmt: skip
    in_world = ev.ape("truth", "odometry", pose_relation="full")
    in_map = ev.ape("truth", "odometry", pose_relation="full", frame="map")
    # a common rigid change of frame leaves every pose error unchanged
    np.testing.assert_allclose(in_map.error.values, in_world.error.values, atol=1e-12)
    p_map, _ = rbm.lookup_pose("truth", "map")
    np.testing.assert_allclose(in_map.reference.positions, p_map, atol=1e-12)


def test_aligned_frame_goes_into_a_scene_next_to_the_reference(walk, tmp_path):
    from rbm_nb.scene import Scene

    ref, est = walk
    rbm.register_frame("world")
    rbm.register_frame("truth", parent="world", translation=ref[1], rotation=ref[2],
                       timestamps=ref[0])  # fmt: skip
    ev.ape("truth", est, align=True).register_aligned("estimate_aligned", "world")
    with Scene("world") as scene:
        truth = scene.add_path("truth")
        aligned = scene.add_path("estimate_aligned", color="#ff8000")
        # the two drawn paths are the reference and the aligned estimate
        np.testing.assert_allclose(truth.positions, ref[1], atol=1e-12)
        p, _ = rbm.lookup_pose("estimate_aligned", "world")
        np.testing.assert_allclose(aligned.positions, p, atol=1e-12)
        scene.add_frame("estimate_aligned")
        scene.to_html(tmp_path / "both.html")
    assert "estimate_aligned" in (tmp_path / "both.html").read_text()
