"""rbm_nb.quaternions and its kernels (rbm_nb/_kernels/rotations.py).

Kernels against their plain-numpy twins, the public functions' shapes and
types, algebraic properties with hypothesis, and bad input.
"""

from __future__ import annotations

import naive_estimators as naive
import numpy as np
import pytest
import quaternion
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import rbm_nb as rbm
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import rotations as rk
from rbm_nb.core.quaternions import (
    from_euler_angles,
    qinterp,
    qinv,
    qmean,
    qmul,
    rotate_vectors,
)

RNG = np.random.default_rng(20240611)


def random_quaternions(n, rng=RNG, unit=True):
    q = rng.standard_normal((n, 4))
    if unit:
        q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q


def smooth_quaternions(n, rng=RNG):
    """A sign-continuous series of unit quaternions (a random smooth motion)."""
    rpy = np.cumsum(rng.normal(0, 0.1, (n, 3)), axis=0)
    return from_euler_angles(rpy)


# ---------------------------------------------------------------------------
# kernels vs twins
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("nq,nv", [(7, 7), (1, 7), (7, 1), (1, 1), (0, 0)])
def test_rotate_vectors_kernel_matches_twin(nq, nv):
    q = random_quaternions(nq, unit=False)
    v = RNG.standard_normal((nv, 3))
    if nq > 2:
        q[2] = 0.0
    out, zero = rk.rotate_vectors_checked(q, v)
    out_n, zero_n = naive.rotate_vectors_checked(q, v)
    ok = np.arange(len(out)) != 2
    np.testing.assert_allclose(out[ok], out_n[ok], rtol=1e-12, atol=1e-12)
    assert zero == zero_n


@pytest.mark.parametrize(
    "kernel,twin",
    [
        (rk.qinv_checked, naive.qinv_checked),
    ],
)
def test_qinv_kernel_matches_twin(kernel, twin):
    q = random_quaternions(9, unit=False)
    q[4] = 0.0
    out, zero = kernel(q)
    out_n, zero_n = twin(q)
    ok = np.arange(9) != 4
    np.testing.assert_allclose(out[ok], out_n[ok], rtol=1e-13)
    assert zero == zero_n == 4


@pytest.mark.parametrize("zero_at", [None, 0, 5])
def test_first_zero_row_matches_twin(zero_at):
    q = random_quaternions(8)
    if zero_at is not None:
        q[zero_at] = 0.0
    assert rk.first_zero_row(q) == naive.first_zero_row(q)


@pytest.mark.parametrize("with_nan", [False, True])
def test_unflip_matches_twin(with_nan):
    q = smooth_quaternions(40)
    signs = RNG.choice([-1.0, 1.0], size=(40, 1))
    flipped = q * signs
    if with_nan:
        flipped[[3, 4, 20]] = np.nan
    out = kq.unflip(flipped)
    np.testing.assert_array_equal(out, naive.unflip(flipped))
    valid = ~np.isnan(out).any(axis=1)
    np.testing.assert_allclose(out[valid], q[valid] * signs[0])


@pytest.mark.parametrize(
    "q",
    [
        random_quaternions(20),
        random_quaternions(20, unit=False),
        np.array([[1.0, 0, 0, 0], [-1.0, 0, 0, 0], [-2.0, 0, 0, 0], [0.0, 0, 0, 1]]),
    ],
    ids=["unit", "non-unit", "special"],
)
def test_rotation_vectors_match_twin_and_numpy_quaternion(q):
    out = rk.rotation_vectors(q)
    np.testing.assert_allclose(out, naive.rotation_vectors(q), rtol=1e-12, atol=1e-14)
    expected = quaternion.as_rotation_vector(quaternion.as_quat_array(q))
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-14)


# ---------------------------------------------------------------------------
# rotate_vectors
# ---------------------------------------------------------------------------


def explicit_rotation(q, v):
    """q v q⁻¹ through numpy-quaternion's own product and inverse."""
    qq = quaternion.as_quat_array(q)
    vq = quaternion.from_vector_part(v)
    return quaternion.as_vector_part(qq * vq / qq)


def test_rotate_vectors_is_correct_for_non_unit_quaternions():
    q = random_quaternions(50, unit=False) * RNG.uniform(0.1, 10, (50, 1))
    v = RNG.standard_normal((50, 3))
    out = rotate_vectors(q, v)
    np.testing.assert_allclose(out, explicit_rotation(q, v), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), np.linalg.norm(v, axis=1))


@pytest.mark.parametrize("rows", [7, 60_001])  # 60k: the prange twins run on 2+ threads
@pytest.mark.parametrize("case", ["n x n", "1 x n", "n x 1"])
def test_row_kernels_every_broadcast_case(rows, case):
    """rotate_vectors, qmul and qinv through their flat-indexed row loops.

    Each broadcast case has its own loop (so that every index has a constant
    stride); each is checked against numpy-quaternion, with the single row
    on either side, and an infinity in a single row is still reported.
    """
    rng = np.random.default_rng(rows)
    nq, nv = {"n x n": (rows, rows), "1 x n": (1, rows), "n x 1": (rows, 1)}[case]
    q = random_quaternions(nq, rng, unit=False)
    p = random_quaternions(nv, rng, unit=False)
    v = rng.standard_normal((nv, 3))
    wide = lambda a: a.repeat(rows, 0) if len(a) == 1 else a  # noqa: E731
    np.testing.assert_allclose(
        rotate_vectors(q, v),
        explicit_rotation(wide(q), wide(v)),
        rtol=1e-12,
        atol=1e-12,
    )
    np.testing.assert_allclose(
        qmul(q, p), naive.hamilton(wide(q), wide(p)), rtol=1e-14, atol=1e-14
    )
    np.testing.assert_allclose(
        qinv(wide(q)), quaternion.as_float_array(1 / quaternion.as_quat_array(wide(q)))
    )
    bad_v = v.copy()
    bad_v[-1, 1] = np.inf
    with pytest.raises(ValueError, match="v"):
        rotate_vectors(q, bad_v)
    bad_q = q.copy()
    bad_q[-1, 2] = -np.inf
    with pytest.raises(ValueError, match="q"):
        rotate_vectors(bad_q, v)
    with pytest.raises(ValueError, match="finite|inf"):
        qmul(p, bad_q)


def test_rotate_vectors_shapes_and_axes():
    q = random_quaternions(6)
    v = RNG.standard_normal((6, 3))
    expected = explicit_rotation(q, v)
    np.testing.assert_allclose(rotate_vectors(q.T, v.T, axis=0, qaxis=0), expected.T)
    np.testing.assert_allclose(
        rotate_vectors(q[:1], v), explicit_rotation(q[:1].repeat(6, 0), v)
    )
    np.testing.assert_allclose(
        rotate_vectors(q[0], v), explicit_rotation(q[:1].repeat(6, 0), v)
    )
    # one_to_one with broadcasting over several axes
    q3 = random_quaternions(12).reshape(3, 4, 4)  # a (3, 4) grid of quaternions
    v3 = RNG.standard_normal((3, 1, 3))
    out = rotate_vectors(q3, v3)
    assert out.shape == (3, 4, 3)
    for i in range(3):
        np.testing.assert_allclose(out[i], explicit_rotation(q3[i], v3[i].repeat(4, 0)))
    # vector axis in the middle of a 3-d array, quaternion axis first
    v_mid = RNG.standard_normal((2, 3, 5))
    q_first = random_quaternions(10).reshape(2, 5, 4).transpose(2, 0, 1)  # (4, 2, 5)
    out = rotate_vectors(q_first, v_mid, axis=1, qaxis=0)
    assert out.shape == (2, 3, 5)
    for i in range(2):
        for j in range(5):
            np.testing.assert_allclose(
                out[i, :, j],
                explicit_rotation(q_first[:, i, j][None], v_mid[i, :, j][None])[0],
            )


def test_rotate_vectors_outer_shape():
    q = random_quaternions(4)
    v = RNG.standard_normal((3, 5))
    out = rotate_vectors(q, v, axis=0, one_to_one=False)
    assert out.shape == (4, 3, 5)
    for i in range(4):
        np.testing.assert_allclose(
            out[i], explicit_rotation(q[i : i + 1].repeat(5, 0), v.T).T
        )
    assert rotate_vectors(q, v[:, 0], one_to_one=False).shape == (4, 3)


def test_rotate_vectors_quaternion_dtype_and_dataarray():
    q = random_quaternions(5)
    v = RNG.standard_normal((5, 3))
    expected = explicit_rotation(q, v)
    np.testing.assert_allclose(rotate_vectors(quaternion.as_quat_array(q), v), expected)
    da = xr.DataArray(
        v,
        {"time": np.arange(5.0), "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
        name="position",
        attrs={"units": "m"},
    )
    out = rotate_vectors(q, da)
    assert isinstance(out, xr.DataArray)
    assert out.name == "position" and out.attrs == {"units": "m"}
    np.testing.assert_allclose(out.values, expected)


def test_rotate_vectors_fast_path_does_not_copy_input():
    q = random_quaternions(4)
    v = RNG.standard_normal((4, 3))
    q_before, v_before = q.copy(), v.copy()
    rotate_vectors(q, v)
    np.testing.assert_array_equal(q, q_before)
    np.testing.assert_array_equal(v, v_before)


# ---------------------------------------------------------------------------
# qinv, qmul, qmean
# ---------------------------------------------------------------------------


def test_qinv_axes_dtypes_and_dataarray():
    q = random_quaternions(6, unit=False)
    expected = naive.inverse(q)
    np.testing.assert_allclose(qinv(q), expected)
    np.testing.assert_allclose(qinv(q.T, qaxis=0), expected.T)
    qd = qinv(quaternion.as_quat_array(q))
    assert qd.dtype == np.quaternion
    np.testing.assert_allclose(quaternion.as_float_array(qd), expected)
    da = xr.DataArray(q, dims=("time", "quaternion_axis"), attrs={"a": 1})
    out = qinv(da)
    assert isinstance(out, xr.DataArray) and out.attrs == {"a": 1}
    np.testing.assert_allclose(out.values, expected)


def test_qmul_chains_left_to_right_and_broadcasts():
    a, b, c = (random_quaternions(5) for _ in range(3))
    expected = naive.hamilton(naive.hamilton(a, b), c)
    np.testing.assert_allclose(qmul(a, b, c), expected)
    np.testing.assert_allclose(qmul(a.T, b.T, c.T, qaxis=0), expected.T)
    np.testing.assert_allclose(qmul(a[0], b), naive.hamilton(a[:1], b))
    grid = qmul(a[:, None, :], b[None, :, :])
    assert grid.shape == (5, 5, 4)
    np.testing.assert_allclose(grid[2, 3], naive.hamilton(a[2], b[3]))
    qd = qmul(quaternion.as_quat_array(a), quaternion.as_quat_array(b))
    assert qd.dtype == np.quaternion
    np.testing.assert_allclose(quaternion.as_float_array(qd), naive.hamilton(a, b))


def test_qmean_is_the_dominant_eigenvector_and_sign_blind():
    q0 = from_euler_angles([0.3, -0.2, 1.0])
    q = qmul(q0, from_euler_angles(RNG.normal(0, 0.05, (200, 3))))
    q *= RNG.choice([-1.0, 1.0], size=(200, 1))
    m = qmean(q)
    outer = np.einsum("ni,nj->ij", q, q) / len(q)
    vals, vecs = np.linalg.eigh(outer)
    np.testing.assert_allclose(abs(m @ vecs[:, -1]), 1.0, rtol=1e-12)
    assert m[0] >= 0
    assert abs(m @ q0) > 0.999


def test_qmean_axes():
    q = smooth_quaternions(24).reshape(2, 3, 4, 4)
    m = qmean(q, axis=1)
    assert m.shape == (2, 4, 4)
    for i in range(2):
        for j in range(4):
            np.testing.assert_allclose(m[i, j], qmean(q[i, :, j]))
    assert qmean(q, axis=(0, 2)).shape == (3, 4)
    qt = np.moveaxis(q, -1, 0)  # components first
    np.testing.assert_allclose(qmean(qt, axis=1, qaxis=0), np.moveaxis(m, -1, 0))
    qd = qmean(quaternion.as_quat_array(q), axis=1)
    np.testing.assert_allclose(quaternion.as_float_array(qd), m)
    nan = q.copy()
    nan[0, 0, 0] = np.nan
    out = qmean(nan, axis=1)
    assert (
        np.isnan(out[0, 0]).all()
        and np.isfinite(out[1:]).all()
        and np.isfinite(out[0, 1:]).all()
    )


def test_qmean_dataarray_keeps_other_coords():
    q = smooth_quaternions(12).reshape(3, 4, 4)
    da = xr.DataArray(
        q,
        {"run": [1, 2, 3], "time": np.arange(4.0), "quaternion_axis": list("wxyz")},
        ("run", "time", "quaternion_axis"),
    )
    out = qmean(da, axis=1)
    assert isinstance(out, xr.DataArray)
    assert out.dims == ("run", "quaternion_axis")
    np.testing.assert_array_equal(out.run, [1, 2, 3])
    np.testing.assert_allclose(out.values, qmean(q, axis=1))


# ---------------------------------------------------------------------------
# qinterp
# ---------------------------------------------------------------------------


def test_qinterp_hits_samples_and_stays_unit():
    q = smooth_quaternions(30)
    t = np.cumsum(RNG.uniform(0.5, 1.5, 30))
    np.testing.assert_allclose(qinterp(q, t, t), q, atol=1e-12)
    t_out = np.linspace(t[0], t[-1], 111)
    out = qinterp(q, t, t_out)
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, rtol=1e-12)


def test_qinterp_undoes_sign_flips():
    q = smooth_quaternions(30)
    t = np.arange(30.0)
    flipped = q * RNG.choice([-1.0, 1.0], size=(30, 1))
    t_out = np.linspace(0, 29, 90)
    a, b = qinterp(q, t, t_out), qinterp(flipped, t, t_out)
    np.testing.assert_allclose(np.abs(np.sum(a * b, axis=1)), 1.0, rtol=1e-12)


def test_qinterp_axes_scalar_and_datetime():
    q = smooth_quaternions(20)
    t = np.arange(20.0)
    t_out = np.linspace(0, 19, 7)
    expected = qinterp(q, t, t_out)
    np.testing.assert_allclose(qinterp(q.T, t, t_out, axis=1, qaxis=0), expected.T)
    stacked = np.stack([q, q[::-1]], axis=1)  # (20, 2, 4)
    out = qinterp(stacked, t, t_out)
    np.testing.assert_allclose(out[:, 0], expected)
    np.testing.assert_allclose(out[:, 1], qinterp(q[::-1], t, t_out))
    np.testing.assert_allclose(qinterp(q, t, 3.25), qinterp(q, t, [3.25])[0])
    stamps = np.datetime64("2021-05-01T12:00:00", "ns") + (t * 1e9).astype(
        "timedelta64[ns]"
    )
    out_stamps = np.datetime64("2021-05-01T12:00:00", "ns") + (t_out * 1e9).astype(
        "timedelta64[ns]"
    )
    np.testing.assert_allclose(qinterp(q, stamps, out_stamps), expected, atol=1e-12)
    qd = qinterp(quaternion.as_quat_array(q), t, t_out)
    assert qd.dtype == np.quaternion


def test_qinterp_dataarray():
    q = smooth_quaternions(10)
    da = xr.DataArray(
        q,
        {"time": np.arange(10.0), "quaternion_axis": list("wxyz")},
        ("time", "quaternion_axis"),
        name="orientation",
        attrs={"long_name": "Orientation"},
    )
    out = qinterp(da, da.time.values, [1.5, 2.5])
    assert isinstance(out, xr.DataArray) and out.name == "orientation"
    np.testing.assert_array_equal(out.time, [1.5, 2.5])
    np.testing.assert_allclose(out.values, qinterp(q, np.arange(10.0), [1.5, 2.5]))


# ---------------------------------------------------------------------------
# from_euler_angles
# ---------------------------------------------------------------------------


def test_from_euler_angles_composes_elementary_rotations():
    r, p, y = 0.3, -0.7, 2.1
    rx = np.array([np.cos(r / 2), np.sin(r / 2), 0, 0])
    ry = np.array([np.cos(p / 2), 0, np.sin(p / 2), 0])
    rz = np.array([np.cos(y / 2), 0, 0, np.sin(y / 2)])
    np.testing.assert_allclose(
        from_euler_angles([r, p, y]), naive.hamilton(naive.hamilton(rx, ry), rz)
    )
    np.testing.assert_allclose(
        from_euler_angles(roll=r, pitch=p, yaw=y, order="ypr"),
        naive.hamilton(naive.hamilton(rz, ry), rx),
    )
    np.testing.assert_allclose(from_euler_angles(pitch=p), ry)
    rpy = RNG.standard_normal((3, 6))
    out = from_euler_angles(rpy, axis=0)
    assert out.shape == (4, 6)
    np.testing.assert_allclose(out.T, from_euler_angles(rpy.T))
    assert from_euler_angles(yaw=[0.1, 0.2], roll=0.5).shape == (2, 4)
    qd = from_euler_angles(yaw=[0.1, 0.2], return_quaternion=True)
    assert qd.dtype == np.quaternion and qd.shape == (2,)


def test_top_level_exports_are_these_functions():
    assert rbm.qmul is qmul and rbm.rotate_vectors is rotate_vectors
    assert rbm.from_euler_angles is from_euler_angles and rbm.qmean is qmean


# ---------------------------------------------------------------------------
# properties
# ---------------------------------------------------------------------------

quats = arrays(np.float64, 4, elements=st.floats(-10, 10)).filter(
    lambda q: np.linalg.norm(q) > 1e-3
)
vecs = arrays(np.float64, 3, elements=st.floats(-1e3, 1e3))


@settings(max_examples=60, deadline=None)
@given(quats)
def test_property_inverse(q):
    np.testing.assert_allclose(qmul(qinv(q), q), [1, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(qmul(q, qinv(q)), [1, 0, 0, 0], atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(quats, quats, quats)
def test_property_associativity(a, b, c):
    left = qmul(qmul(a, b), c)
    right = qmul(a, qmul(b, c))
    scale = np.linalg.norm(a) * np.linalg.norm(b) * np.linalg.norm(c)
    np.testing.assert_allclose(left / scale, right / scale, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(quats, vecs)
def test_property_rotation_keeps_norms(q, v):
    out = rotate_vectors(q, v)
    np.testing.assert_allclose(
        np.linalg.norm(out), np.linalg.norm(v), rtol=1e-12, atol=1e-9
    )


@settings(max_examples=60, deadline=None)
@given(quats, quats, vecs)
def test_property_rotation_composes_like_the_product(a, b, v):
    np.testing.assert_allclose(
        rotate_vectors(qmul(a, b), v),
        rotate_vectors(a, rotate_vectors(b, v)),
        atol=1e-8,
    )


@settings(max_examples=30, deadline=None)
@given(quats, st.integers(0, 2**32 - 1))
def test_property_qmean_is_rotation_equivariant(p, seed):
    rng = np.random.default_rng(seed)
    q = qmul(
        from_euler_angles(rng.normal(0, 0.3, (10, 3))),
        from_euler_angles([0.1, 0.2, 0.3]),
    )
    p = p / np.linalg.norm(p)
    m1 = qmean(qmul(p, q))
    m2 = qmul(p, qmean(q))
    np.testing.assert_allclose(abs(m1 @ m2), 1.0, atol=1e-10)


# ---------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call,match",
    [
        (
            lambda: rotate_vectors(np.ones((3, 3)), np.ones((3, 3))),
            "q must have length 4",
        ),
        (
            lambda: rotate_vectors(np.ones((3, 4)), np.ones((3, 4))),
            "v must have length 3",
        ),
        (
            lambda: rotate_vectors(np.zeros(4), np.ones(3)),
            "q contains a zero quaternion",
        ),
        (
            lambda: rotate_vectors(np.zeros((2, 4)), np.ones((2, 3))),
            "q contains a zero quaternion",
        ),
        (lambda: rotate_vectors(np.ones((3, 4)), np.ones((2, 3))), "q and v"),
        (lambda: rotate_vectors(np.ones((3, 4)), np.ones(3)), "one_to_one"),
        (lambda: rotate_vectors(np.ones((2, 4)), np.ones((2, 3)), axis=5), "axis=5"),
        (
            lambda: rotate_vectors(np.zeros((2, 4)), np.ones((2, 3)), one_to_one=False),
            "zero",
        ),
        (lambda: qinv(np.zeros((2, 4))), "q contains a zero quaternion"),
        (lambda: qinv(np.ones((2, 3))), "q must have length 4"),
        (lambda: qinv(np.ones((2, 4)), qaxis=2), "qaxis=2"),
        (lambda: qmul(np.ones(4)), "at least 2"),
        (lambda: qmul(np.ones(4), np.ones(3)), r"q\[1\] must have length 4"),
        (lambda: qmul(np.ones((2, 4)), np.ones((3, 4))), "broadcast"),
        (
            lambda: qmul(np.ones(4), quaternion.as_quat_array(np.ones(4))),
            "quaternion dtype",
        ),
        (lambda: qmean(np.zeros((3, 4))), "zero"),
        (lambda: qmean(np.ones((3, 4)), axis=1), "axis=1"),
        (lambda: qmean(np.ones((0, 4))), "no quaternions"),
        (
            lambda: qinterp(np.ones((3, 4)), [0, 1], [0.5]),
            "t_in must be one-dimensional",
        ),
        (lambda: qinterp(np.ones((3, 4)), [0, 2, 1], [0.5]), "strictly increasing"),
        (lambda: qinterp(np.ones((3, 4)), [0, 1, 2], [2.5]), "t_out must lie within"),
        (lambda: qinterp(np.ones((3, 4)), [0, 1, 2], [-0.5]), "t_out must lie within"),
        (lambda: qinterp(np.ones((3, 4)), [0, 1, 2], [np.nan]), "t_out must be finite"),
        (lambda: qinterp(np.zeros((3, 4)), [0, 1, 2], [0.5]), "zero quaternion"),
        (lambda: qinterp(np.ones((4, 4)), [0, 1, 2, 3], [0.5], axis=1), "same axis"),
        (
            lambda: qinterp(
                np.ones((2, 4)), [0.0, 1.0], np.array(["2020-01-01"], "M8[ns]")
            ),
            "both be datetimes",
        ),
        (lambda: from_euler_angles(), "at least one"),
        (lambda: from_euler_angles([1, 2, 3], roll=1), "not both"),
        (lambda: from_euler_angles([1, 2]), "rpy must have length 3"),
        (lambda: from_euler_angles(roll=1, order="rpp"), "order"),
        (lambda: from_euler_angles(roll=[1, 2], yaw=[1, 2, 3]), "yaw"),
    ],
)
def test_bad_input_raises_value_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()
