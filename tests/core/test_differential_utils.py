"""Differential tests against rigid-body-motion 0.9.3 (the oracle).

Every public function of rbm_nb.quaternions, rbm_nb.estimators,
rbm_nb.coordinates and the DataArray accessor is compared with its namesake on
randomised inputs over fixed seeds and shapes (including axis/qaxis variants
and DataArrays): same values to rtol 1e-6, quaternions up to sign. Where the
reference is wrong (its qmean, extrapolating squad, NaN for opposite vectors,
...) the tests elsewhere check the correct behaviour; here a few tests pin down
those differences explicitly.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import quaternion
import xarray as xr

import rbm_nb as rbm
from rbm_nb.core.accessors import DataArrayAccessor

SEEDS = [0, 1, 2]
RTOL = 1e-6


@pytest.fixture(scope="module")
def ref():
    """The reference package, imported without losing our DataArray.rbm."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import rigid_body_motion

        # importing it registers its own accessor under the same name
        xr.register_dataarray_accessor("rbm")(DataArrayAccessor)
    return rigid_body_motion


def close(actual, expected, rtol=RTOL, atol=1e-12):
    np.testing.assert_allclose(
        np.asarray(actual), np.asarray(expected), rtol=rtol, atol=atol
    )


def close_up_to_sign(actual, expected, qaxis=-1, atol=1e-10):
    """Quaternions equal up to a sign per quaternion."""
    a = np.moveaxis(np.asarray(actual, dtype=float), qaxis, -1)
    b = np.moveaxis(np.asarray(expected, dtype=float), qaxis, -1)
    sign = np.where(np.sum(a * b, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    np.testing.assert_allclose(a, sign * b, rtol=RTOL, atol=atol)


def smooth_quaternions(rng, n):
    rpy = np.cumsum(rng.normal(0, 0.08, (n, 3)), axis=0)
    return rbm.from_euler_angles(rpy)


def random_unit(rng, shape):
    q = rng.standard_normal(shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


# ---------------------------------------------------------------------------
# quaternion utilities
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_qinv(ref, seed):
    rng = np.random.default_rng(seed)
    q = rng.standard_normal((7, 4)) * rng.uniform(0.2, 3, (7, 1))
    close(rbm.qinv(q), ref.qinv(q))
    close(rbm.qinv(q.T, qaxis=0), ref.qinv(q.T, qaxis=0))
    q3 = rng.standard_normal((2, 4, 5))
    close(rbm.qinv(q3, qaxis=1), ref.qinv(q3, qaxis=1))
    qq = quaternion.as_quat_array(q)
    out = rbm.qinv(qq)
    assert out.dtype == ref.qinv(qq).dtype == np.quaternion
    close(quaternion.as_float_array(out), quaternion.as_float_array(ref.qinv(qq)))


@pytest.mark.parametrize("seed", SEEDS)
def test_qmul(ref, seed):
    rng = np.random.default_rng(seed)
    a, b, c = (rng.standard_normal((6, 4)) for _ in range(3))
    close(rbm.qmul(a, b), ref.qmul(a, b))
    close(rbm.qmul(a, b, c), ref.qmul(a, b, c))
    close(rbm.qmul(a.T, b.T, qaxis=0), ref.qmul(a.T, b.T, qaxis=0))
    close(rbm.qmul(a[:1], b), ref.qmul(a[:1], b))
    close(rbm.qmul(a[0], b), ref.qmul(a[0], b))
    a3, b3 = rng.standard_normal((3, 4, 2)), rng.standard_normal((3, 4, 2))
    close(rbm.qmul(a3, b3, qaxis=1), ref.qmul(a3, b3, qaxis=1))
    qa, qb = quaternion.as_quat_array(a), quaternion.as_quat_array(b)
    close(
        quaternion.as_float_array(rbm.qmul(qa, qb)),
        quaternion.as_float_array(ref.qmul(qa, qb)),
    )


def test_qmean_differs_where_the_reference_is_wrong(ref):
    """The reference returns a permuted eigenvector; ours is the eigenvector."""
    rng = np.random.default_rng(0)
    q0 = np.array([0.9, 0.1, 0.3, -0.2]) / np.linalg.norm([0.9, 0.1, 0.3, -0.2])
    q = q0 + 0.01 * rng.standard_normal((50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    outer = q.T @ q / len(q)
    ours, theirs = rbm.qmean(q), ref.qmean(q)
    top = np.linalg.eigvalsh(outer)[-1]
    np.testing.assert_allclose(outer @ ours, top * ours, atol=1e-12)
    assert np.linalg.norm(outer @ theirs - top * theirs) > 1e-3
    assert abs(ours @ q0) > 0.999 > abs(theirs @ q0)


@pytest.mark.parametrize("seed", SEEDS)
def test_qinterp(ref, seed):
    rng = np.random.default_rng(seed)
    n = 25
    q = smooth_quaternions(rng, n)
    t_in = np.cumsum(rng.uniform(0.5, 1.5, n))
    t_out = np.sort(rng.uniform(t_in[0], t_in[-1], 40))
    t_out[[0, -1]] = t_in[[0, -1]]
    close_up_to_sign(rbm.qinterp(q, t_in, t_out), ref.qinterp(q, t_in, t_out))
    close_up_to_sign(
        rbm.qinterp(q.T, t_in, t_out, axis=1, qaxis=0),
        ref.qinterp(q.T, t_in, t_out, axis=1, qaxis=0),
        qaxis=0,
    )
    stacked = np.stack([q, smooth_quaternions(rng, n)], axis=1)  # (n, 2, 4)
    close_up_to_sign(
        rbm.qinterp(stacked, t_in, t_out), ref.qinterp(stacked, t_in, t_out)
    )
    qq = quaternion.as_quat_array(q)
    close_up_to_sign(
        quaternion.as_float_array(rbm.qinterp(qq, t_in, t_out)),
        quaternion.as_float_array(ref.qinterp(qq, t_in, t_out)),
    )
    # datetimes close to the epoch, where the reference's float conversion is exact
    stamps = (t_in * 1e9).astype("int64").astype("datetime64[ns]")
    stamps_out = (t_out * 1e9).astype("int64").astype("datetime64[ns]")
    close_up_to_sign(
        rbm.qinterp(q, stamps, stamps_out),
        ref.qinterp(q, stamps, stamps_out),
        atol=1e-9,
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_rotate_vectors(ref, seed):
    rng = np.random.default_rng(seed)
    q = random_unit(rng, (8,))
    v = rng.standard_normal((8, 3))
    close(rbm.rotate_vectors(q, v), ref.rotate_vectors(q, v))
    close(
        rbm.rotate_vectors(q.T, v.T, axis=0, qaxis=0),
        ref.rotate_vectors(q.T, v.T, axis=0, qaxis=0),
    )
    close(rbm.rotate_vectors(q[:1], v), ref.rotate_vectors(q[:1], v))
    close(rbm.rotate_vectors(q[0], v), ref.rotate_vectors(q[0], v))
    close(rbm.rotate_vectors(q, v[:1]), ref.rotate_vectors(q, v[:1]))
    close(
        rbm.rotate_vectors(q, v[0], one_to_one=False),
        ref.rotate_vectors(q, v[0], one_to_one=False),
    )
    close(
        rbm.rotate_vectors(q, v, one_to_one=False),
        ref.rotate_vectors(q, v, one_to_one=False),
    )
    close(
        rbm.rotate_vectors(q[:3], v.T, axis=0, one_to_one=False),
        ref.rotate_vectors(q[:3], v.T, axis=0, one_to_one=False),
    )
    q3, v3 = random_unit(rng, (2, 5)), rng.standard_normal((2, 5, 3))
    close(rbm.rotate_vectors(q3, v3), ref.rotate_vectors(q3, v3))
    close(rbm.rotate_vectors(q3[:, :1], v3), ref.rotate_vectors(q3[:, :1], v3))
    qq = quaternion.as_quat_array(q)
    close(rbm.rotate_vectors(qq, v), ref.rotate_vectors(qq, v))
    da = xr.DataArray(v, {"time": np.arange(8)}, ("time", "cartesian_axis"))
    out = rbm.rotate_vectors(q, da)
    assert isinstance(out, xr.DataArray)
    close(out.values, ref.rotate_vectors(q, da))


def test_rotate_vectors_non_unit_differs_from_the_reference(ref):
    """The reference divides by |q| instead of |q|²: it scales the vectors."""
    rng = np.random.default_rng(5)
    q = 2.0 * random_unit(rng, (6,))
    v = rng.standard_normal((6, 3))
    close(rbm.rotate_vectors(q, v), ref.rotate_vectors(q / 2.0, v))
    assert not np.allclose(ref.rotate_vectors(q, v), ref.rotate_vectors(q / 2.0, v))


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("order", ["rpy", "ypr", "pry"])
def test_from_euler_angles(ref, seed, order):
    rng = np.random.default_rng(seed)
    rpy = rng.uniform(-np.pi, np.pi, (6, 3))
    close(
        rbm.from_euler_angles(rpy, order=order), ref.from_euler_angles(rpy, order=order)
    )
    close(
        rbm.from_euler_angles(rpy.T, axis=0, order=order),
        ref.from_euler_angles(rpy.T, axis=0, order=order),
    )
    r, p, y = rpy.T
    close(
        rbm.from_euler_angles(roll=r, pitch=p, yaw=y, order=order),
        ref.from_euler_angles(roll=r, pitch=p, yaw=y, order=order),
    )
    close(rbm.from_euler_angles(yaw=y), ref.from_euler_angles(yaw=y))
    close(
        rbm.from_euler_angles(pitch=p[0], roll=r[0]),
        ref.from_euler_angles(pitch=p[0], roll=r[0]),
    )
    close(
        quaternion.as_float_array(rbm.from_euler_angles(rpy, return_quaternion=True)),
        quaternion.as_float_array(ref.from_euler_angles(rpy, return_quaternion=True)),
    )


# ---------------------------------------------------------------------------
# velocity estimators
# ---------------------------------------------------------------------------


def trajectory(rng, n):
    # nearly even sampling, so that 1e-3 separates smooth motion from jumps
    t = np.cumsum(rng.uniform(0.0099, 0.0101, n))
    f = rng.uniform(0.5, 1.5, 3)
    x = np.stack([np.sin(f[0] * t), np.cos(f[1] * t), t * f[2]], axis=1)
    q = rbm.from_euler_angles(
        np.stack([np.sin(f[1] * t), 0.5 * t, np.cos(f[2] * t)], axis=1)
    )
    return t, x, q


OPTIONS = [
    {},
    {"outlier_thresh": 1e-3},
    {"cutoff": 0.3},
    {"outlier_thresh": 1e-3, "cutoff": 0.3},
]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("options", OPTIONS, ids=lambda o: "-".join(o) or "plain")
def test_estimate_linear_velocity(ref, seed, options):
    rng = np.random.default_rng(seed)
    t, x, _ = trajectory(rng, 120)
    x[[30, 31, 77]] += 3e-3  # tracker jumps for the outlier suppression
    close(
        rbm.estimate_linear_velocity(x, timestamps=t, **options),
        ref.estimate_linear_velocity(x, timestamps=t, **options),
        atol=1e-9,
    )


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("mode", ["quaternion", "rotation_vector"])
@pytest.mark.parametrize("options", OPTIONS, ids=lambda o: "-".join(o) or "plain")
def test_estimate_angular_velocity(ref, seed, mode, options):
    rng = np.random.default_rng(seed)
    t, _, q = trajectory(rng, 120)
    if "outlier_thresh" in options:
        options = dict(options, outlier_thresh=1e-2)  # rotation vectors bend more
        q[[40, 90]] = rbm.qmul(q[[40, 90]], rbm.from_euler_angles(yaw=[0.05, -0.05]))
    close(
        rbm.estimate_angular_velocity(q, timestamps=t, mode=mode, **options),
        ref.estimate_angular_velocity(q, timestamps=t, mode=mode, **options),
        atol=1e-8,
    )


def test_rejected_first_sample_does_not_blank_the_filtered_velocity(ref):
    """The reference low-passes the NaN left at a rejected end into every sample.

    rbm_nb refuses the call instead, naming outlier_thresh: a rejected run at
    the start has nothing before it to be interpolated from (issue 11 item 1:
    one behaviour for lookups and estimators, the clear one).
    """
    t = np.arange(200) * 0.01
    x = np.stack([np.sin(t), np.cos(t), t], axis=1)
    x[1] += 0.01  # the jump rejects samples 0-2, and nothing precedes sample 0
    theirs = ref.estimate_linear_velocity(
        x, timestamps=t, outlier_thresh=1e-3, cutoff=0.3
    )
    assert np.isnan(theirs).all()
    for cutoff in (0.3, None):
        with pytest.raises(ValueError, match=r"outlier_thresh=0.001 rejects the first"):
            rbm.estimate_linear_velocity(
                x, timestamps=t, outlier_thresh=1e-3, cutoff=cutoff
            )


@pytest.mark.parametrize("seed", SEEDS)
def test_estimators_axes_and_dataarrays(ref, seed):
    rng = np.random.default_rng(seed)
    t, x, q = trajectory(rng, 60)
    _, x2, q2 = trajectory(rng, 60)
    # (The reference reads axis=0 as "last axis" (``axis or -1``), so the
    # spatial axis is never first here.)
    xs, qs = np.stack([x, x2], axis=2), np.stack([q, q2], axis=2)  # (time, xyz, body)
    close(
        rbm.estimate_linear_velocity(xs, timestamps=t, axis=1),
        ref.estimate_linear_velocity(xs, timestamps=t, axis=1),
    )
    close(
        rbm.estimate_angular_velocity(qs, timestamps=t, axis=1),
        ref.estimate_angular_velocity(qs, timestamps=t, axis=1),
    )
    xt, qt = np.moveaxis(xs, 2, 0), np.moveaxis(qs, 2, 0)  # (body, time, xyz)
    close(
        rbm.estimate_linear_velocity(xt, timestamps=t, time_axis=1),
        ref.estimate_linear_velocity(xt, timestamps=t, time_axis=1),
    )
    close(
        rbm.estimate_angular_velocity(qt, timestamps=t, time_axis=1),
        ref.estimate_angular_velocity(qt, timestamps=t, time_axis=1),
    )
    # datetimes near the epoch: the reference's ns -> float conversion is exact there
    time = (t * 1e9).astype("int64").astype("datetime64[ns]")
    pos = xr.DataArray(
        x,
        {"time": time, "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
        name="position",
        attrs={"units": "m"},
    )
    ori = xr.DataArray(
        q,
        {"time": time, "quaternion_axis": list("wxyz")},
        ("time", "quaternion_axis"),
        name="orientation",
        attrs={"long_name": "Orientation"},
    )
    for ours, theirs in (
        (rbm.estimate_linear_velocity(pos), ref.estimate_linear_velocity(pos)),
        (rbm.estimate_angular_velocity(ori), ref.estimate_angular_velocity(ori)),
        (
            rbm.estimate_linear_velocity(
                pos.T, dim="cartesian_axis", timestamps="time"
            ),
            ref.estimate_linear_velocity(
                pos.T, dim="cartesian_axis", timestamps="time"
            ),
        ),
    ):
        assert ours.dims == theirs.dims and ours.name == theirs.name
        assert ours.attrs == theirs.attrs
        assert set(ours.coords) == set(theirs.coords)
        for c in ours.coords:
            np.testing.assert_array_equal(ours[c].values, theirs[c].values)
        close(ours.values, theirs.values, atol=1e-9)


# ---------------------------------------------------------------------------
# rotations and transforms from data
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_shortest_arc_rotation(ref, seed):
    rng = np.random.default_rng(seed)
    v1, v2 = rng.standard_normal((10, 3)), rng.standard_normal((10, 3))
    close(rbm.shortest_arc_rotation(v1, v2), ref.shortest_arc_rotation(v1, v2))
    close(rbm.shortest_arc_rotation(v1[0], v2), ref.shortest_arc_rotation(v1[0], v2))
    close(
        rbm.shortest_arc_rotation(v1[0], v2[0]), ref.shortest_arc_rotation(v1[0], v2[0])
    )
    v1_mid, v2_mid = (
        v1.reshape(2, 5, 3).transpose(0, 2, 1),
        v2.reshape(2, 5, 3).transpose(0, 2, 1),
    )
    close(
        rbm.shortest_arc_rotation(v1_mid, v2_mid, axis=1),
        ref.shortest_arc_rotation(v1_mid, v2_mid, axis=1),
    )
    da = xr.DataArray(
        v1,
        {"time": np.arange(10.0), "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
        name="gaze",
    )
    ours, theirs = rbm.shortest_arc_rotation(da, v2), ref.shortest_arc_rotation(da, v2)
    assert ours.dims == theirs.dims and ours.name == theirs.name
    assert list(ours.quaternion_axis.values) == list(theirs.quaternion_axis.values)
    close(ours.values, theirs.values)


@pytest.mark.parametrize("seed", SEEDS)
def test_best_fit_rotation_and_transform(ref, seed):
    rng = np.random.default_rng(seed)
    r = random_unit(rng, ())
    t = rng.uniform(-2, 2, 3)
    p1 = rng.standard_normal((30, 3))
    p2 = rbm.rotate_vectors(r, p1, one_to_one=False) + t + rng.normal(0, 0.01, (30, 3))
    close_up_to_sign(rbm.best_fit_rotation(p1, p2), ref.best_fit_rotation(p1, p2))
    ours, theirs = rbm.best_fit_transform(p1, p2), ref.best_fit_transform(p1, p2)
    close(ours[0], theirs[0])
    close_up_to_sign(ours[1], theirs[1])
    # several leading axes are flattened in the same order for v1 and v2
    p1_3d, p2_3d = p1.reshape(5, 6, 3), p2.reshape(5, 6, 3)
    ours, theirs = (
        rbm.best_fit_transform(p1_3d, p2_3d),
        ref.best_fit_transform(p1_3d, p2_3d),
    )
    close(ours[0], theirs[0])
    close_up_to_sign(ours[1], theirs[1])
    p1_mid, p2_mid = p1_3d.transpose(0, 2, 1), p2_3d.transpose(0, 2, 1)
    ours = rbm.best_fit_transform(p1_mid, p2_mid, axis=1)
    theirs = ref.best_fit_transform(p1_mid, p2_mid, axis=1)
    close(ours[0], theirs[0])
    close_up_to_sign(ours[1], theirs[1])
    da = xr.DataArray(p1, dims=("point", "cartesian_axis"))
    ours, theirs = rbm.best_fit_transform(da, p2), ref.best_fit_transform(da, p2)
    for a, b in zip(ours, theirs, strict=True):
        assert a.dims == b.dims and a.name == b.name
    close(ours[0].values, theirs[0].values)
    close_up_to_sign(ours[1].values, theirs[1].values)
    ours, theirs = rbm.best_fit_rotation(da, p2), ref.best_fit_rotation(da, p2)
    assert ours.dims == theirs.dims and ours.name == theirs.name


@pytest.mark.parametrize("seed", SEEDS)
def test_iterative_closest_point(ref, seed):
    rng = np.random.default_rng(seed)
    p1 = rng.uniform(-1, 1, (80, 3)) * [3, 2, 1]
    r = rbm.from_euler_angles(rng.normal(0, 0.1, 3))
    p2 = rng.permutation(
        rbm.rotate_vectors(r, p1, one_to_one=False) + rng.normal(0, 0.05, 3)
    )[:60]
    ours, theirs = (
        rbm.iterative_closest_point(p1, p2),
        ref.iterative_closest_point(p1, p2),
    )
    close(ours[0], theirs[0], atol=1e-9)
    close_up_to_sign(ours[1], theirs[1], atol=1e-9)
    init = (np.array([0.01, 0, 0]), rbm.from_euler_angles(yaw=0.02))
    ours = rbm.iterative_closest_point(
        p1, p2, init_transform=init, max_iterations=5, tolerance=1e-6
    )
    theirs = ref.iterative_closest_point(
        p1, p2, init_transform=init, max_iterations=5, tolerance=1e-6
    )
    close(ours[0], theirs[0], atol=1e-9)
    close_up_to_sign(ours[1], theirs[1], atol=1e-9)


# ---------------------------------------------------------------------------
# coordinate systems
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_coordinate_conversions(ref, seed):
    rng = np.random.default_rng(seed)
    xy, xyz = rng.standard_normal((9, 2)), rng.standard_normal((9, 3))
    for name, arr in (
        ("cartesian_to_polar", xy),
        ("polar_to_cartesian", xy),
        ("cartesian_to_spherical", xyz),
        ("spherical_to_cartesian", xyz),
    ):
        close(getattr(rbm, name)(arr), getattr(ref, name)(arr))
        close(getattr(rbm, name)(arr.T, axis=0), getattr(ref, name)(arr.T, axis=0))
    close(
        rbm.transform_coordinates(xyz, "spherical", outof="cartesian"),
        ref.transform_coordinates(xyz, "spherical", outof="cartesian"),
    )
    close(
        rbm.transform_coordinates(xy.T[None], "polar", outof="cartesian", axis=1),
        ref.transform_coordinates(xy.T[None], "polar", outof="cartesian", axis=1),
    )


@pytest.mark.parametrize("replace_dim", [True, False])
@pytest.mark.parametrize("into", ["spherical", "cartesian"])
def test_transform_coordinates_dataarray(ref, replace_dim, into):
    rng = np.random.default_rng(4)
    system = "cartesian" if into == "spherical" else "spherical"
    da = xr.DataArray(
        rng.standard_normal((6, 3)),
        {"time": np.arange(6.0), "axis_label": ("space", ["a", "b", "c"])},
        ("time", "space"),
        name="gaze",
        attrs={"coordinate_system": system, "units": "m"},
    )
    ours = rbm.transform_coordinates(da, into, replace_dim=replace_dim)
    theirs = ref.transform_coordinates(da, into, replace_dim=replace_dim)
    assert ours.dims == theirs.dims and ours.name == theirs.name
    assert ours.attrs == theirs.attrs
    assert set(ours.coords) == set(theirs.coords)
    for c in ours.coords:
        np.testing.assert_array_equal(ours[c].values, theirs[c].values)
    close(ours.values, theirs.values)


# ---------------------------------------------------------------------------
# accessor
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_accessor(ref, seed):
    from rigid_body_motion.accessors import DataArrayAccessor as RefAccessor

    rng = np.random.default_rng(seed)
    n = 30
    time = (
        (np.cumsum(rng.uniform(0.5, 1.5, n)) * 1e9)
        .astype("int64")
        .astype("datetime64[ns]")
    )
    da = xr.DataArray(
        smooth_quaternions(rng, n),
        {
            "time": time,
            "quaternion_axis": list("wxyz"),
            "confidence": ("time", rng.uniform(0, 1, n)),
        },
        ("time", "quaternion_axis"),
        name="orientation",
        attrs={"long_name": "Orientation"},
    )
    ours, theirs = DataArrayAccessor(da).qinv(), RefAccessor(da).qinv()
    xr.testing.assert_allclose(ours, theirs, rtol=RTOL)
    assert ours.attrs == theirs.attrs
    new_time = np.sort(
        rng.choice(np.arange(time[0], time[-1], np.timedelta64(100, "ms")), 25)
    )
    ours = DataArrayAccessor(da).qinterp(time=new_time)
    theirs = RefAccessor(da).qinterp(time=new_time)
    assert (
        ours.dims == theirs.dims
        and ours.attrs == theirs.attrs
        and ours.name == theirs.name
    )
    np.testing.assert_array_equal(ours.time.values, theirs.time.values)
    close(ours.confidence.values, theirs.confidence.values)
    close_up_to_sign(ours.values, theirs.values, atol=1e-9)
