"""rbm_nb.estimators and its kernels (rbm_nb/_kernels/differences.py).

Kernels against their plain-numpy twins, exactness on motions whose velocity
is known, the seed guide's section 1.4 values, DataArray handling, the
array-level helpers used by the frame lookups, and bad input.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import naive_estimators as naive
import numpy as np
import pytest
import xarray as xr
from conftest import REPO
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from rbm_nb._engine.velocity import angular_velocity as _angular_velocity
from rbm_nb._engine.velocity import linear_velocity as _linear_velocity
from rbm_nb._kernels import differences as dk
from rbm_nb.core.estimators import (
    best_fit_rotation,
    best_fit_transform,
    estimate_angular_velocity,
    estimate_linear_velocity,
    iterative_closest_point,
    shortest_arc_rotation,
)
from rbm_nb.core.quaternions import from_euler_angles, qmul, rotate_vectors

RNG = np.random.default_rng(7)


def uneven_times(n, rng=RNG):
    return np.cumsum(rng.uniform(0.005, 0.02, n))


def same_rotation(a, b, atol=1e-10):
    """Quaternions equal up to sign."""
    a, b = np.asarray(a), np.asarray(b)
    return np.allclose(a, b, atol=atol) or np.allclose(a, -b, atol=atol)


# ---------------------------------------------------------------------------
# kernels vs twins
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6, 31])
@pytest.mark.parametrize(
    "kernel,twin",
    [(dk.gradient, naive.gradient), (dk.spline_derivative, naive.spline_derivative)],
    ids=["gradient", "spline_derivative"],
)
def test_derivative_kernels_match_twins(kernel, twin, n):
    t = uneven_times(n) * 100
    f = RNG.standard_normal((n, 4))
    np.testing.assert_allclose(kernel(f, t), twin(f, t), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("k", [1, 3, 4])
@pytest.mark.parametrize("n", [2, 3, 4, 97])
def test_gradient_is_numpys_bit_for_bit(n, k):
    """Every row route of the kernel (3 columns, any other) is numpy.gradient's."""
    rng = np.random.default_rng(n * 10 + k)  # (the module's RNG feeds later tests)
    t = uneven_times(n, rng) * 100
    f = rng.standard_normal((n, k))
    want = np.gradient(f, t, axis=0, edge_order=1)
    np.testing.assert_array_equal(dk.gradient(f, t), want)


@pytest.mark.parametrize("n", [1, 2, 3, 10])
def test_second_difference_score_matches_twin(n):
    x = RNG.standard_normal((n, 2, 3))
    if n == 10:
        x[4, 1] = np.nan
    np.testing.assert_allclose(
        dk.second_difference_score(x), naive.second_difference_score(x), equal_nan=True
    )


@pytest.mark.parametrize("pattern", ["middle", "ends", "runs", "none"])
def test_interpolate_rejected_matches_twin(pattern):
    n = 12
    t = uneven_times(n)
    values = RNG.standard_normal((n, 2, 3))
    keep = np.ones((n, 2), dtype=bool)
    if pattern == "middle":
        keep[5, 0] = False
    elif pattern == "ends":
        keep[[0, 1, 11], 1] = False
    elif pattern == "runs":
        keep[2:6, 0] = False
        keep[7:9, 1] = False
    np.testing.assert_allclose(
        dk.interpolate_rejected(t, values, keep),
        naive.interpolate_rejected(t, values, keep),
        rtol=1e-13,
        equal_nan=True,
    )


def test_angular_velocity_from_derivative_matches_twin():
    q = RNG.standard_normal((9, 4)) * RNG.uniform(0.5, 2, (9, 1))
    dq = RNG.standard_normal((9, 4))
    np.testing.assert_allclose(
        dk.angular_velocity_from_derivative(q, dq),
        naive.angular_velocity_from_derivative(q, dq),
        rtol=1e-12,
        atol=1e-14,
    )


def test_kernels_run_without_jit():
    """Coverage of the kernels' Python source (NUMBA_DISABLE_JIT=1)."""
    script = textwrap.dedent(
        """
        import numpy as np
        import naive_estimators as naive
        from rbm_nb._kernels import differences as dk, quaternion as kq, rotations as rk
        rng = np.random.default_rng(1)
        t = np.cumsum(rng.uniform(0.1, 1, 8)); f = rng.standard_normal((8, 4))
        for k, n in ((dk.gradient, naive.gradient), (dk.spline_derivative, naive.spline_derivative)):
            for m in (2, 3, 8):
                assert np.allclose(k(f[:m], t[:m]), n(f[:m], t[:m]))
        x = rng.standard_normal((8, 1, 3)); keep = np.ones((8, 1), bool); keep[3] = False
        assert np.allclose(dk.second_difference_score(x), naive.second_difference_score(x))
        assert np.allclose(dk.interpolate_rejected(t, x, keep), naive.interpolate_rejected(t, x, keep))
        assert np.allclose(dk.angular_velocity_from_derivative(f, f[::-1]),
                           naive.angular_velocity_from_derivative(f, f[::-1]))
        q = f.copy(); q[2] = 0
        assert rk.first_zero_row(q) == 2 and rk.qinv_checked(q)[1] == 2
        out, z = rk.rotate_vectors_checked(q, x[:, 0]); ref, _ = naive.rotate_vectors_checked(q, x[:, 0])
        assert z == 2 and np.allclose(np.delete(out, 2, 0), np.delete(ref, 2, 0))
        assert np.allclose(kq.unflip(-f), naive.unflip(-f))
        assert np.allclose(rk.rotation_vectors(f), naive.rotation_vectors(f))
        print("ok")
        """
    )
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "tests"), str(REPO)])
    result = subprocess.run(
        [sys.executable, "-c", script],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


# ---------------------------------------------------------------------------
# velocities of known motions
# ---------------------------------------------------------------------------


def test_linear_velocity_exact_for_linear_and_quadratic_motion():
    t = uneven_times(50)
    v0, a = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.0, -1.0])
    x = v0 * t[:, None] + 0.5 * a * t[:, None] ** 2
    v = estimate_linear_velocity(x, timestamps=t)
    # numpy's uneven three-point formula is exact for quadratics inside
    np.testing.assert_allclose(v[1:-1], v0 + a * t[1:-1, None], rtol=1e-9)
    np.testing.assert_allclose(
        estimate_linear_velocity(v0 * t[:, None], timestamps=t),
        np.tile(v0, (50, 1)),
        rtol=1e-10,
    )


def test_angular_velocity_of_constant_body_rate():
    """q(t) = q0 exp(w t / 2) turns at the constant rate w in the rotated frame."""
    w = np.array([0.4, -1.1, 0.7])
    t = np.linspace(0, 3, 301)
    q0 = from_euler_angles([0.5, 0.2, -1.0])
    rotvec = w * t[:, None]
    angle = np.linalg.norm(rotvec, axis=1, keepdims=True)
    axis = np.tile(w / np.linalg.norm(w), (len(t), 1))
    increments = np.concatenate((np.cos(angle / 2), np.sin(angle / 2) * axis), axis=1)
    q = qmul(q0, increments)
    est = estimate_angular_velocity(q, timestamps=t)
    np.testing.assert_allclose(est, np.tile(w, (301, 1)), atol=1e-6)
    # sign flips in the data do not matter
    flipped = q * RNG.choice([-1.0, 1.0], size=(301, 1))
    np.testing.assert_allclose(
        estimate_angular_velocity(flipped, timestamps=t), est, atol=1e-12
    )
    # rotation about a fixed axis: the rotation-vector gradient is exact too
    fixed = from_euler_angles(yaw=0.9 * t)
    np.testing.assert_allclose(
        estimate_angular_velocity(fixed, timestamps=t, mode="rotation_vector"),
        np.tile([0, 0, 0.9], (301, 1)),
        atol=1e-9,
    )


def test_angular_velocity_ignores_the_quaternions_scale():
    t = uneven_times(40)
    q = from_euler_angles(np.stack([np.sin(3 * t), t, t**2], axis=1))
    w = estimate_angular_velocity(q, timestamps=t)
    # one rule for quaternions everywhere (issue 12 item 4): far from unit
    # norm is refused, as ReferenceFrame refuses it
    with pytest.raises(ValueError, match=r"arr\[0\] is of norm 3.7"):
        estimate_angular_velocity(3.7 * q, timestamps=t)
    # a drifting norm only adds discretisation error (2 q* dq would scale by |q|²)
    drifting = q * (1 + 0.01 * np.sin(7 * t))[:, None]
    np.testing.assert_allclose(
        estimate_angular_velocity(drifting, timestamps=t), w, atol=1e-3
    )


def test_nan_samples_are_skipped_in_quaternion_mode():
    t = uneven_times(30)
    q = from_euler_angles(yaw=2.0 * t)
    q[[5, 17]] = np.nan
    w = estimate_angular_velocity(q, timestamps=t)
    assert np.isnan(w[[5, 17]]).all()
    valid = np.setdiff1d(np.arange(30), [5, 17])
    np.testing.assert_allclose(w[valid], np.tile([0, 0, 2.0], (28, 1)), atol=1e-6)


def test_outlier_rejection_replaces_the_jump():
    t = np.arange(100) * 0.01
    x = np.stack([t, np.zeros(100), np.zeros(100)], axis=1)
    x[50:] += [0.02, 0, 0]  # a tracker correction
    v = estimate_linear_velocity(x, timestamps=t, outlier_thresh=1e-3)
    np.testing.assert_allclose(v[1:-1], np.tile([1.0, 0, 0], (98, 1)), atol=1e-9)
    raw = estimate_linear_velocity(x, timestamps=t)
    assert raw[50, 0] > 1.5


def test_outlier_rejection_matches_twin_pipeline():
    t = uneven_times(60)
    x = np.stack([np.sin(5 * t), np.cos(3 * t), t], axis=1)
    x[[10, 11, 40]] += 0.01
    thresh = 5e-3
    score = naive.second_difference_score(x[:, None, :])
    expected = naive.interpolate_rejected(
        t, naive.gradient(x, t)[:, None, :], score <= thresh
    )[:, 0, :]
    np.testing.assert_allclose(
        estimate_linear_velocity(x, timestamps=t, outlier_thresh=thresh),
        expected,
        rtol=1e-12,
    )


def test_lowpass_filters_nan_free_stretches_separately():
    from scipy.signal import butter, filtfilt, sosfiltfilt

    t = np.arange(200) * 0.01
    x = np.stack([np.sin(3 * t), np.cos(2 * t), t], axis=1) + RNG.normal(
        0, 1e-4, (200, 3)
    )
    x[100] = np.nan
    v = estimate_linear_velocity(x, timestamps=t, cutoff=0.2)
    # the missing sample splits the series; each side is differenced (one-
    # sided at the missing sample) and filtered on its own
    assert np.isnan(v[100]).all() and np.isfinite(v[99]).all()
    assert np.isfinite(v[101]).all()
    before = np.gradient(x[:100], t[:100], axis=0)
    after = np.gradient(x[101:], t[101:], axis=0)
    sos = butter(7, 0.2, output="sos")
    np.testing.assert_allclose(v[:100], sosfiltfilt(sos, before, axis=0), rtol=1e-12)
    np.testing.assert_allclose(v[101:], sosfiltfilt(sos, after, axis=0), rtol=1e-12)
    # the reference's transfer-function form is the same filter, to its rounding
    b, a = butter(7, 0.2)
    np.testing.assert_allclose(v[:100], filtfilt(b, a, before, axis=0), rtol=1e-9)
    np.testing.assert_allclose(v[101:], filtfilt(b, a, after, axis=0), rtol=1e-9)


def test_datetime_timestamps_are_converted_exactly():
    t = np.arange(50) * 0.01
    x = np.stack([np.sin(t), t**2, t], axis=1)
    expected = estimate_linear_velocity(x, timestamps=t)
    start = np.datetime64("2020-02-02T00:27:14.300365210", "ns")
    for unit in ("ns", "us"):
        stamps = (start + (t * 1e9).astype("timedelta64[ns]")).astype(
            f"datetime64[{unit}]"
        )
        np.testing.assert_allclose(
            estimate_linear_velocity(x, timestamps=stamps), expected, rtol=1e-9
        )
    # converting epoch nanoseconds to float first (the reference's way) is
    # off by up to 256 ns per stamp here; relative to the first stamp it is not
    stamps = start + (t * 1e9).astype("timedelta64[ns]")
    naive_seconds = stamps.astype(float) / 1e9
    err_naive = np.abs(np.gradient(x, naive_seconds, axis=0) - expected).max()
    err_ours = np.abs(estimate_linear_velocity(x, timestamps=stamps) - expected).max()
    assert err_ours < 1e-9 < err_naive


# ---------------------------------------------------------------------------
# DataArrays, axes and the array-level helpers
# ---------------------------------------------------------------------------


def make_dataarrays(n=40):
    time = np.datetime64("2021-01-01", "ns") + (np.arange(n) * 1e7).astype(
        "timedelta64[ns]"
    )
    t = np.arange(n) * 0.01
    pos = xr.DataArray(
        np.stack([np.sin(t), np.cos(t), t], axis=1),
        {"time": time, "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
        name="position",
        attrs={"units": "m"},
    )
    ori = xr.DataArray(
        from_euler_angles(yaw=0.5 * t),
        {
            "time": time,
            "quaternion_axis": list("wxyz"),
            "quality": ("time", np.ones(n)),
        },
        ("time", "quaternion_axis"),
        name="orientation",
        attrs={"long_name": "Orientation"},
    )
    return pos, ori, t


def test_dataarray_linear_velocity_keeps_coords():
    pos, _, t = make_dataarrays()
    v = estimate_linear_velocity(pos)
    assert isinstance(v, xr.DataArray)
    assert v.dims == pos.dims and v.name == "position" and v.attrs == {"units": "m"}
    np.testing.assert_array_equal(v.time, pos.time)
    np.testing.assert_allclose(
        v.values, estimate_linear_velocity(pos.values, timestamps=t)
    )
    np.testing.assert_allclose(estimate_linear_velocity(pos, timestamps="time"), v)
    np.testing.assert_allclose(estimate_linear_velocity(pos, dim="cartesian_axis"), v)
    transposed = estimate_linear_velocity(
        pos.T, dim="cartesian_axis", timestamps="time"
    )
    assert transposed.dims == ("cartesian_axis", "time")
    np.testing.assert_allclose(transposed.values, v.values.T)


def test_dataarray_angular_velocity_replaces_quaternion_dim():
    _, ori, t = make_dataarrays()
    w = estimate_angular_velocity(ori)
    assert w.dims == ("time", "cartesian_axis")
    assert list(w.cartesian_axis.values) == ["x", "y", "z"]
    assert "quality" in w.coords and w.name == "orientation"
    np.testing.assert_allclose(w.values, np.tile([0, 0, 0.5], (40, 1)), atol=1e-6)


def test_time_axis_and_extra_axes():
    t = uneven_times(30)
    x = np.stack([np.sin(t), t, t**2], axis=1)
    v = estimate_linear_velocity(x, timestamps=t)
    np.testing.assert_allclose(
        estimate_linear_velocity(x.T, timestamps=t, axis=0, time_axis=1), v.T
    )
    stacked = np.stack([x, 2 * x], axis=1)  # (time, body, xyz)
    out = estimate_linear_velocity(
        stacked, timestamps=t, outlier_thresh=1.0, cutoff=None
    )
    np.testing.assert_allclose(out[:, 1], 2 * v)
    q = from_euler_angles(np.stack([t, -t, 0.5 * t], axis=1))
    w = estimate_angular_velocity(q, timestamps=t)
    np.testing.assert_allclose(
        estimate_angular_velocity(q.T, timestamps=t, axis=0, time_axis=1),
        w.T,
        rtol=1e-12,
    )


def test_array_level_helpers_for_the_frame_engine():
    t = uneven_times(60)
    x = np.stack([np.sin(t), t, t**2], axis=1)
    q = from_euler_angles(np.stack([t, -t, 0.5 * t], axis=1))
    lin = _linear_velocity(x, t, None, None)
    ang = _angular_velocity(q, t, "quaternion", None, None)
    assert lin.shape == ang.shape == (60, 3)
    np.testing.assert_allclose(lin, estimate_linear_velocity(x, timestamps=t))
    np.testing.assert_allclose(ang, estimate_angular_velocity(q, timestamps=t))
    np.testing.assert_allclose(
        _angular_velocity(q, t, "rotation_vector", 1.0, 0.5),
        estimate_angular_velocity(
            q, timestamps=t, mode="rotation_vector", outlier_thresh=1.0, cutoff=0.5
        ),
    )


# ---------------------------------------------------------------------------
# shortest arc, best fit, ICP
# ---------------------------------------------------------------------------

unit_vecs = arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(
    lambda v: np.linalg.norm(v) > 1e-2
)


@settings(max_examples=80, deadline=None)
@given(unit_vecs, unit_vecs)
def test_property_shortest_arc_turns_v1_onto_v2(v1, v2):
    r = shortest_arc_rotation(v1, v2)
    np.testing.assert_allclose(np.linalg.norm(r), 1.0)
    np.testing.assert_allclose(
        rotate_vectors(r, v1) / np.linalg.norm(v1), v2 / np.linalg.norm(v2), atol=1e-7
    )
    # the axis is perpendicular to both: no rotation wasted about v1 or v2
    assert abs(np.dot(r[1:], v1)) < 1e-7 and abs(np.dot(r[1:], v2)) < 1e-7


def test_shortest_arc_for_opposite_vectors_is_a_half_turn():
    for v in ([1.0, 0, 0], [0, 0, -2.0], [1.0, 2.0, 3.0]):
        r = shortest_arc_rotation(v, -np.asarray(v))
        assert np.isfinite(r).all() and abs(r[0]) < 1e-12
        np.testing.assert_allclose(rotate_vectors(r, v), -np.asarray(v), atol=1e-12)


def test_shortest_arc_axis_and_dataarray():
    v1 = RNG.standard_normal((5, 3))
    v2 = RNG.standard_normal((5, 3))
    r = shortest_arc_rotation(v1, v2)
    np.testing.assert_allclose(shortest_arc_rotation(v1.T, v2.T, axis=0), r.T)
    da = xr.DataArray(
        v1,
        {"time": np.arange(5), "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
    )
    out = shortest_arc_rotation(da, v2)
    assert out.dims == ("time", "quaternion_axis")
    assert list(out.quaternion_axis.values) == list("wxyz")
    np.testing.assert_allclose(out.values, r)
    np.testing.assert_allclose(
        shortest_arc_rotation(da, v2, dim="cartesian_axis").values, r
    )


@settings(max_examples=40, deadline=None)
@given(
    arrays(np.float64, 3, elements=st.floats(-np.pi, np.pi)), st.integers(0, 2**32 - 1)
)
def test_property_best_fit_recovers_a_transform(rpy, seed):
    rng = np.random.default_rng(seed)
    r = from_euler_angles(rpy)
    t = rng.uniform(-5, 5, 3)
    p1 = rng.standard_normal((20, 3))
    p2 = rotate_vectors(r, p1, one_to_one=False) + t
    t_est, r_est = best_fit_transform(p1, p2)
    np.testing.assert_allclose(t_est, t, atol=1e-9)
    assert same_rotation(r_est, r, atol=1e-9)
    assert r_est[0] >= 0
    assert same_rotation(best_fit_rotation(p1, p2 - t), r, atol=1e-9)


def test_best_fit_rotation_never_returns_a_reflection():
    v1 = RNG.standard_normal((10, 3))
    mirrored = v1 * [1, 1, -1]
    r = best_fit_rotation(v1, mirrored)
    np.testing.assert_allclose(np.linalg.norm(r), 1.0)
    # the best proper rotation leaves less residual than any other we try
    residual = np.linalg.norm(rotate_vectors(r, v1, one_to_one=False) - mirrored)
    for other in from_euler_angles(RNG.uniform(-np.pi, np.pi, (200, 3))):
        assert (
            residual
            <= np.linalg.norm(rotate_vectors(other, v1, one_to_one=False) - mirrored)
            + 1e-9
        )


def test_icp_recovers_a_small_transform_without_correspondences():
    p1 = RNG.uniform(-1, 1, (200, 3)) * [3, 2, 1]
    r = from_euler_angles([0.05, -0.03, 0.1])
    t = np.array([0.05, -0.02, 0.03])
    p2 = RNG.permutation(rotate_vectors(r, p1, one_to_one=False) + t)
    t_est, r_est = iterative_closest_point(p1, p2, tolerance=1e-10, max_iterations=100)
    np.testing.assert_allclose(t_est, t, atol=1e-6)
    assert same_rotation(r_est, r, atol=1e-6)
    # a good initial guess is used as such
    t0, r0 = iterative_closest_point(p1, p2, init_transform=(t, r), max_iterations=0)
    np.testing.assert_allclose(t0, t, atol=1e-12)
    assert same_rotation(r0, r, atol=1e-12)


def test_fit_dataarray_outputs():
    p1 = xr.DataArray(RNG.standard_normal((10, 3)), dims=("point", "cartesian_axis"))
    p2 = p1.values + [1.0, 2.0, 3.0]
    t, r = best_fit_transform(p1, p2)
    assert t.name == "translation" and t.dims == ("cartesian_axis",)
    assert r.name == "rotation" and list(r.quaternion_axis.values) == list("wxyz")
    t, r = iterative_closest_point(p1, p2)
    assert isinstance(t, xr.DataArray) and isinstance(r, xr.DataArray)
    assert best_fit_rotation(p1, p1).name == "rotation"


# ---------------------------------------------------------------------------
# the seed's guide, section 1.4 (values printed there)
# ---------------------------------------------------------------------------


def test_guide_1_4_values():
    v1 = (1, 0, 0)
    v2 = (np.sqrt(2) / 2, np.sqrt(2) / 2, 0)
    np.testing.assert_allclose(
        shortest_arc_rotation(v1, v2), [0.92387953, 0.0, 0.0, 0.38268343], atol=1e-8
    )
    r = from_euler_angles(yaw=np.linspace(0, np.pi / 8, 10))
    v2_arr = rotate_vectors(r, v2, one_to_one=False)
    arcs = shortest_arc_rotation(v1, v2_arr)
    expected_w = [0.92387953, 0.91531148, 0.90630779, 0.89687274, 0.88701083,
                  0.87672676, 0.8660254, 0.85491187, 0.84339145, 0.83146961]  # fmt: skip
    expected_z = [0.38268343, 0.40274669, 0.42261826, 0.44228869, 0.46174861,
                  0.48098877, 0.5, 0.51877326, 0.53729961, 0.55557023]  # fmt: skip
    np.testing.assert_allclose(arcs[:, 0], expected_w, atol=1e-8)
    np.testing.assert_allclose(arcs[:, 3], expected_z, atol=1e-8)
    np.testing.assert_allclose(arcs[:, 1:3], 0, atol=1e-12)
    v1_arr = rotate_vectors(r, v1, one_to_one=False)
    np.testing.assert_allclose(
        best_fit_rotation(v1_arr, v2_arr), [0.92387953, 0, 0, 0.38268343], atol=1e-8
    )
    # ICP from the identity reaches the 45 degree yaw only for some draws of
    # the cloud (the guide shows one that does); these seeds give such a draw
    p1_arr = 0.1 * np.random.default_rng(4).standard_normal((100, 3))
    t = np.array((1, 1, 0))
    r = from_euler_angles(yaw=np.pi / 4)
    p2_arr = rotate_vectors(r, p1_arr, one_to_one=False) + t
    translation, rotation = best_fit_transform(p1_arr, p2_arr)
    np.testing.assert_allclose(translation, [1, 1, 0], atol=1e-12)
    np.testing.assert_allclose(rotation, [0.923879533, 0, 0, 0.382683432], atol=1e-9)
    translation, rotation = iterative_closest_point(
        p1_arr, np.random.default_rng(104).permutation(p2_arr)
    )
    np.testing.assert_allclose(translation, [1, 1, 0], atol=1e-6)
    np.testing.assert_allclose(rotation, [0.923879533, 0, 0, 0.382683432], atol=1e-6)


# ---------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------

T10 = np.arange(10.0)
X10 = np.zeros((10, 3))
Q10 = np.tile([1.0, 0, 0, 0], (10, 1))


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: estimate_linear_velocity(X10), "timestamps must be given"),
        (
            lambda: estimate_linear_velocity(X10, timestamps=T10[:9]),
            "one entry per sample",
        ),
        (
            lambda: estimate_linear_velocity(X10, timestamps=T10[::-1]),
            "strictly increasing",
        ),
        (
            lambda: estimate_linear_velocity(X10, timestamps=np.r_[0, 0, T10[2:]]),
            "strictly increasing",
        ),
        (
            lambda: estimate_linear_velocity(X10, timestamps=np.r_[np.nan, T10[1:]]),
            "finite",
        ),
        (lambda: estimate_linear_velocity(X10, timestamps="time"), "DataArray"),
        (lambda: estimate_linear_velocity(X10, timestamps=T10, dim="x"), "dim"),
        (lambda: estimate_linear_velocity(X10, timestamps=T10, axis=0), "both axis 0"),
        (lambda: estimate_linear_velocity(X10, timestamps=T10, axis=3), "axis=3"),
        (lambda: estimate_linear_velocity(X10[:1], timestamps=T10[:1]), "at least 2"),
        (lambda: estimate_linear_velocity(X10, timestamps=T10, cutoff=1.5), "cutoff"),
        (
            lambda: estimate_linear_velocity(X10, timestamps=T10, cutoff=0.5),
            "more than 24",
        ),
        (
            lambda: estimate_linear_velocity(X10, timestamps=T10, outlier_thresh=-1),
            "outlier_thresh",
        ),
        (
            lambda: estimate_linear_velocity(
                np.outer(T10**3, [1, 1, 1]), timestamps=T10, outlier_thresh=1e-9
            ),
            "outlier_thresh",
        ),
        (
            lambda: estimate_linear_velocity(np.ones(10), timestamps=T10),
            "time axis and a spatial",
        ),
        (lambda: estimate_angular_velocity(Q10, timestamps=T10, mode="euler"), "mode"),
        (lambda: estimate_angular_velocity(X10, timestamps=T10), "length 4"),
        (lambda: estimate_angular_velocity(0 * Q10, timestamps=T10), "zero quaternion"),
        (
            lambda: estimate_angular_velocity(Q10 * np.nan, timestamps=T10),
            "without NaN",
        ),
        (lambda: _angular_velocity(Q10, T10[:5]), "one entry per sample"),
        (lambda: shortest_arc_rotation([1, 0], [0, 1]), "v1 must have length 3"),
        (
            lambda: shortest_arc_rotation([1, 0, 0], [0, 0, 0]),
            "v2 contains a zero vector",
        ),
        (lambda: shortest_arc_rotation(np.ones((2, 3)), np.ones((3, 3))), "broadcast"),
        (lambda: best_fit_rotation(np.ones((4, 3)), np.ones((5, 3))), "same shape"),
        (lambda: best_fit_rotation(np.ones(3), np.ones(3)), "at least 2 dimensions"),
        (
            lambda: best_fit_rotation(
                np.outer([1, 2, 3], [1, 0, 0]), np.outer([1, 2, 3], [0, 1, 0])
            ),
            "collinear",
        ),
        (lambda: best_fit_transform(np.eye(3)[:2], np.eye(3)[:2]), "at least 3 points"),
        (
            lambda: best_fit_transform(np.ones((4, 3)) * np.nan, np.ones((4, 3))),
            "v1 must be finite",
        ),
        (
            lambda: iterative_closest_point(np.eye(3)[:2], np.eye(3)),
            "v1 needs at least 3 points",
        ),
        (
            lambda: iterative_closest_point(np.eye(3), np.eye(3)[:2]),
            "v2 needs at least 3 points",
        ),
        (
            lambda: iterative_closest_point(np.outer(T10, [1, 1, 1]), np.eye(3)),
            "collinear",
        ),
        (
            lambda: iterative_closest_point(
                np.eye(3), np.eye(3), init_transform=(1, 2)
            ),
            "init_transform",
        ),
        (
            lambda: iterative_closest_point(np.eye(3), np.eye(3), max_iterations=-1),
            "max_iterations",
        ),
        (
            lambda: iterative_closest_point(np.eye(3), np.eye(3), tolerance=-1),
            "tolerance",
        ),
    ],
)
def test_bad_input_raises_value_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_dataarray_bad_input():
    pos, _, _ = make_dataarrays()
    with pytest.raises(ValueError, match="not a dimension"):
        estimate_linear_velocity(pos, dim="spherical_axis")
    with pytest.raises(ValueError, match="not a coordinate"):
        estimate_linear_velocity(pos, timestamps="stamp")
    with pytest.raises(ValueError, match="either dim or axis"):
        estimate_linear_velocity(pos, dim="cartesian_axis", axis=-1)
    bare = xr.DataArray(pos.values, dims=("time", "cartesian_axis"))
    with pytest.raises(ValueError, match="has no coordinate"):
        estimate_linear_velocity(bare)
