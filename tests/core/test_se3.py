"""rbm_nb.se3 against spatialmath-python (test-only oracle), row by row."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rbm_nb.core import se3
from rbm_nb.core.conversions import matrix_from_quaternion

sb = pytest.importorskip("spatialmath.base")
from spatialmath.quaternion import Quaternion  # noqa: E402

N = 200
REPS = ["rpy/xyz", "rpy/zyx", "rpy/yxz", "eul", "exp"]
RPY_ORDER = {"rpy/xyz": "xyz", "rpy/zyx": "zyx", "rpy/yxz": "yxz"}


def _rng(seed=0):
    return np.random.default_rng(seed)


def random_poses(n, seed=0):
    rng = _rng(seed)
    q = rng.normal(size=(n, 4))
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = matrix_from_quaternion(q / np.linalg.norm(q, axis=1)[:, None])
    T[:, :3, 3] = rng.normal(scale=3, size=(n, 3))
    T[:, 3, 3] = 1.0
    return T


def oracle_rows(func, *arrays):
    return np.stack([func(*row) for row in zip(*arrays, strict=True)])


def singular_angles(rep, n=N, seed=1):
    """Random angles, a third of them exactly at the representation's singularity."""
    rng = _rng(seed)
    ang = rng.uniform(-np.pi, np.pi, size=(n, 3))
    if rep == "exp":
        ang *= 0.5
        return ang
    if rep == "eul":
        ang[::3, 1] = rng.choice([0.0, np.pi, -np.pi], size=ang[::3].shape[0])
    else:
        ang[::3, 1] = rng.choice([np.pi / 2, -np.pi / 2], size=ang[::3].shape[0])
    return ang


# --------------------------------------------------------------------------- skew / vex


def test_skew_vex_match_spatialmath():
    v = _rng().normal(size=(N, 3))
    S = se3.skew(v)
    np.testing.assert_array_equal(S, oracle_rows(sb.skew, v))
    M = _rng(2).normal(size=(N, 3, 3))
    np.testing.assert_allclose(se3.vex(M), oracle_rows(sb.vex, M), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(se3.vex(S), v)


def test_skew_is_cross_product_and_keeps_leading_shape():
    rng = _rng(3)
    v, u = rng.normal(size=(2, 5, 3)), rng.normal(size=(2, 5, 3))
    S = se3.skew(v)
    assert S.shape == (2, 5, 3, 3)
    np.testing.assert_allclose(
        np.einsum("...ij,...j->...i", S, u), np.cross(v, u), atol=1e-14
    )


# --------------------------------------------------------------------------- deltas, adjoint


def test_tr2delta_matches_spatialmath():
    T0, T1 = random_poses(N, 0), random_poses(N, 1)
    got = se3.tr2delta(T0, T1)
    np.testing.assert_allclose(
        got, oracle_rows(sb.tr2delta, T0, T1), rtol=0, atol=1e-13
    )
    got = se3.tr2delta(T0)
    np.testing.assert_allclose(got, oracle_rows(sb.tr2delta, T0), rtol=0, atol=1e-13)


def test_tr2delta_broadcasts_one_pose_against_a_stack():
    T0, T1 = random_poses(1, 0)[0], random_poses(N, 1)
    np.testing.assert_allclose(
        se3.tr2delta(T0, T1), oracle_rows(lambda b: sb.tr2delta(T0, b), T1), atol=1e-13
    )
    np.testing.assert_allclose(
        se3.tr2delta(T1, T0), oracle_rows(lambda a: sb.tr2delta(a, T0), T1), atol=1e-13
    )
    grid = se3.tr2delta(T1[:4, None], T1[None, :3])
    assert grid.shape == (4, 3, 6)
    np.testing.assert_allclose(grid[2, 1], sb.tr2delta(T1[2], T1[1]), atol=1e-13)


def test_delta2tr_matches_spatialmath_and_inverts_tr2delta_to_first_order():
    d = _rng(4).normal(size=(N, 6))
    np.testing.assert_array_equal(se3.delta2tr(d), oracle_rows(sb.delta2tr, d))
    small = 1e-4 * d
    np.testing.assert_allclose(
        se3.tr2delta(np.eye(4), se3.delta2tr(small)), small, atol=1e-15
    )


def test_tr2adjoint_matches_spatialmath_and_maps_twists():
    T = random_poses(N, 5)
    Ad = se3.tr2adjoint(T)
    np.testing.assert_allclose(Ad, oracle_rows(sb.tr2adjoint, T), rtol=0, atol=1e-14)
    # Ad(T) (v, w) is the twist T [v w]^ T⁻¹ expressed as a vector
    tw = _rng(6).normal(size=(N, 6))
    hat = np.zeros((N, 4, 4))
    hat[:, :3, :3] = se3.skew(tw[:, 3:])
    hat[:, :3, 3] = tw[:, :3]
    moved = T @ hat @ np.linalg.inv(T)
    expected = np.concatenate([moved[:, :3, 3], se3.vex(moved[:, :3, :3])], axis=1)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", Ad, tw), expected, atol=1e-12)
    R = T[:, :3, :3]
    np.testing.assert_array_equal(se3.tr2adjoint(R), R)


# --------------------------------------------------------------------------- Jacobians


@pytest.mark.parametrize("rep", REPS)
def test_forward_jacobians_match_spatialmath_including_singular_attitudes(rep):
    ang = singular_angles(rep)
    got = se3.rotvelxform(ang, representation=rep)
    want = oracle_rows(lambda a: sb.rotvelxform(a, representation=rep), ang)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)
    full = se3.rotvelxform(ang, full=True, representation=rep)
    np.testing.assert_allclose(
        full, oracle_rows(lambda a: sb.rotvelxform(a, full=True, representation=rep), ang),
        rtol=0, atol=1e-14,
    )  # fmt: skip
    named = {"eul": se3.eul2jac, "exp": se3.exp2jac}
    if rep in RPY_ORDER:
        order = RPY_ORDER[rep]
        np.testing.assert_allclose(se3.rpy2jac(ang, order), got, atol=0)
        np.testing.assert_allclose(
            got, oracle_rows(lambda a: sb.rpy2jac(a, order), ang), rtol=0, atol=1e-14
        )
    else:
        oracle = {"eul": sb.eul2jac, "exp": sb.exp2jac}[rep]
        np.testing.assert_allclose(named[rep](ang), got, atol=0)
        np.testing.assert_allclose(got, oracle_rows(oracle, ang), rtol=0, atol=1e-14)


@pytest.mark.parametrize("rep", REPS)
def test_inverse_jacobians_match_spatialmath_away_from_singularity(rep):
    ang = _rng(7).uniform(-1.2, 1.2, size=(N, 3))
    if rep == "eul":
        ang[:, 1] = np.abs(ang[:, 1]) + 0.1
    got = se3.rotvelxform(ang, inverse=True, representation=rep)
    want = oracle_rows(
        lambda a: sb.rotvelxform(a, inverse=True, representation=rep), ang
    )
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
    fwd = se3.rotvelxform(ang, representation=rep)
    np.testing.assert_allclose(
        got @ fwd, np.broadcast_to(np.eye(3), got.shape), atol=1e-12
    )


@pytest.mark.parametrize("rep", REPS)
def test_rotation_matrix_input_matches_spatialmath(rep):
    R = random_poses(N, 8)[:, :3, :3]
    if rep == "exp":
        # spatialmath's trlog loses ~7 digits of the rotation vector within
        # 0.05 rad of a half turn (rbm_nb's stays exact: see the next test)
        angle = np.arccos(np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1))
        R = R[angle < np.pi - 0.05]
    for inverse in (False, True):
        got = se3.rotvelxform(R, inverse=inverse, representation=rep)
        want = oracle_rows(
            lambda r, inv=inverse: sb.rotvelxform(r, inverse=inv, representation=rep),
            R,
        )
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_rotation_vector_of_matrix_input_is_exact_near_a_half_turn():
    from rbm_nb.core.conversions import quaternion_from_rotation_vector

    axis = _rng(19).normal(size=(N, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    v = axis * np.linspace(np.pi - 0.05, np.pi - 1e-6, N)[:, None]
    R = matrix_from_quaternion(quaternion_from_rotation_vector(v))
    np.testing.assert_allclose(
        se3.exp2jac(v), se3.rotvelxform(R, representation="exp"), atol=1e-9
    )


@pytest.mark.parametrize(
    ("rep", "angles", "name", "degrees"),
    [
        ("rpy/xyz", [0.3, np.pi / 2, 0.1], "pitch", "90"),
        ("rpy/zyx", [0.3, -np.pi / 2, 0.1], "pitch", "-90"),
        ("rpy/yxz", [0.0, np.pi / 2, 0.0], "pitch", "90"),
        ("eul", [0.3, 0.0, 0.1], "theta", "0"),
        ("eul", [0.3, np.pi, 0.1], "theta", "180"),
        ("exp", [2 * np.pi, 0.0, 0.0], "rotation angle", "360"),
    ],
)
def test_inverse_jacobian_raises_at_singularity_naming_index_and_angle(
    rep, angles, name, degrees
):
    ang = np.array([[0.1, 0.2, 0.3], [0.2, 0.4, 0.3], angles, angles])
    if rep == "eul":
        ang[:2, 1] = 1.0
    with pytest.raises(se3.SingularityError, match=rf"Γ\[2\]: {name} = {degrees}°"):
        se3.rotvelxform(ang, inverse=True, representation=rep)
    # spatialmath itself divides by zero there: inf/nan, huge values or an error
    with np.errstate(all="ignore"):
        try:
            oracle = sb.rotvelxform(np.array(angles), inverse=True, representation=rep)
        except ZeroDivisionError:
            return
    assert not np.isfinite(oracle).all() or np.abs(oracle).max() > 1e12


def test_exp_jacobians_are_exact_at_and_near_zero():
    for v in ([0.0, 0.0, 0.0], [1e-9, -2e-9, 3e-9], [3e-5, 0, 0]):
        fwd = se3.exp2jac(v)
        inv = se3.rotvelxform(v, inverse=True, representation="exp")
        np.testing.assert_allclose(fwd @ inv, np.eye(3), atol=1e-15)
    np.testing.assert_array_equal(se3.exp2jac([0, 0, 0]), sb.exp2jac([0, 0, 0]))
    # both sides of the small-angle switch agree with spatialmath to rounding
    for t in (0.99e-4, 1.01e-4):
        np.testing.assert_allclose(
            se3.exp2jac([t, 0, 0]), sb.exp2jac([t, 0, 0]), atol=1e-12
        )


def test_jacobian_is_the_derivative_of_the_rotation():
    """omega = A(Γ) dΓ/dt, checked by finite differences of the rotation."""
    from rbm_nb.core.conversions import (
        quaternion_from_euler,
        quaternion_from_rotation_vector,
    )

    rng = _rng(9)
    g, gd = rng.uniform(-1, 1, 3), rng.normal(size=3)
    h = 1e-6

    def rot(rep, x):
        if rep == "exp":
            return matrix_from_quaternion(quaternion_from_rotation_vector(x))
        if rep == "eul":
            return matrix_from_quaternion(quaternion_from_euler(x, "zyz"))
        order = RPY_ORDER[rep]
        return matrix_from_quaternion(quaternion_from_euler(x[::-1], order))

    for rep in REPS:
        R0 = rot(rep, g)
        Rdot = (rot(rep, g + h * gd) - rot(rep, g - h * gd)) / (2 * h)
        omega = se3.vex(Rdot @ R0.T)
        np.testing.assert_allclose(
            se3.rotvelxform(g, representation=rep) @ gd, omega, atol=1e-8
        )


# --------------------------------------------------------------------------- trnorm / trinterp


def test_trnorm_matches_spatialmath():
    T = random_poses(N, 10)
    T[:, :3, :3] += _rng(11).normal(scale=1e-3, size=(N, 3, 3))
    got = se3.trnorm(T)
    np.testing.assert_allclose(got, oracle_rows(sb.trnorm, T), rtol=0, atol=1e-15)
    R = T[:, :3, :3]
    np.testing.assert_allclose(
        se3.trnorm(R), oracle_rows(sb.trnorm, R), rtol=0, atol=1e-15
    )
    np.testing.assert_allclose(np.linalg.det(got[:, :3, :3]), 1.0, atol=1e-14)


def test_trinterp_matches_spatialmath():
    T0, T1 = random_poses(N, 12), random_poses(N, 13)
    s = _rng(14).uniform(0, 1, N)
    s[:3] = [0.0, 1.0, 0.5]
    got = se3.trinterp(T0, T1, s)
    np.testing.assert_allclose(
        got, oracle_rows(sb.trinterp, T0, T1, s), rtol=0, atol=1e-12
    )
    got = se3.trinterp(None, T1, s)
    np.testing.assert_allclose(
        got,
        oracle_rows(lambda b, f: sb.trinterp(None, b, f), T1, s),
        rtol=0,
        atol=1e-12,
    )
    R0, R1 = T0[:, :3, :3], T1[:, :3, :3]
    np.testing.assert_allclose(
        se3.trinterp(R0, R1, s), oracle_rows(sb.trinterp, R0, R1, s), rtol=0, atol=1e-12
    )
    long = se3.trinterp(T0, T1, s, shortest=False)
    np.testing.assert_allclose(
        long, oracle_rows(lambda a, b, f: sb.trinterp(a, b, f, shortest=False), T0, T1, s),
        rtol=0, atol=1e-12,
    )  # fmt: skip


def test_trinterp_steps_and_broadcasting():
    T0, T1 = random_poses(2, 15)
    path = se3.trinterp(T0, T1, 5)
    assert path.shape == (5, 4, 4)
    for k, f in enumerate(np.linspace(0, 1, 5)):
        np.testing.assert_allclose(path[k], sb.trinterp(T0, T1, f), atol=1e-12)
    assert se3.trinterp(T0, T1, 1).shape == (4, 4)  # integer 1 is a fraction
    np.testing.assert_allclose(se3.trinterp(T0, T1, 1), T1, atol=1e-12)
    stack = random_poses(6, 16)
    assert se3.trinterp(stack, T1, 0.3).shape == (6, 4, 4)
    assert se3.trinterp(stack[:, None], T1, np.linspace(0, 1, 4)).shape == (6, 4, 4, 4)


# --------------------------------------------------------------------------- quaternion exp/log


def test_qexp_qlog_match_spatialmath():
    q = _rng(17).normal(size=(N, 4))
    np.testing.assert_allclose(
        se3.qexp(q),
        np.stack([Quaternion(r).exp().vec for r in q]),
        rtol=1e-14,
        atol=1e-14,
    )
    np.testing.assert_allclose(
        se3.qlog(q),
        np.stack([Quaternion(r).log().vec for r in q]),
        rtol=1e-14,
        atol=1e-14,
    )
    np.testing.assert_allclose(se3.qexp(se3.qlog(q)), q, atol=1e-13)


def test_qlog_of_unit_quaternion_is_half_the_rotation_vector():
    from rbm_nb.core.conversions import quaternion_from_rotation_vector

    v = _rng(18).uniform(-1, 1, size=(N, 3))
    lg = se3.qlog(quaternion_from_rotation_vector(v))
    np.testing.assert_allclose(lg[:, 0], 0, atol=1e-15)
    np.testing.assert_allclose(lg[:, 1:], v / 2, atol=1e-14)


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: se3.skew([1, 2]), r"v must have shape \(\.\.\., 3\)"),
        (lambda: se3.skew([[1, 2, 3], [np.nan, 0, 0]]), r"v\[1\] is not finite"),
        (lambda: se3.tr2delta(np.ones((4, 4))), r"T0 is not a homogeneous matrix"),
        (lambda: se3.tr2adjoint(np.diag([2, 1, 1, 1.0])), r"T is not a rotation"),
        (
            lambda: se3.tr2delta(
                np.zeros((2, 4, 4)) + np.eye(4), np.zeros((3, 4, 4)) + np.eye(4)
            ),
            "do not broadcast",
        ),
        (
            lambda: se3.rotvelxform([0, 0, 0], representation="rpy"),
            "representation must be",
        ),
        (lambda: se3.rpy2jac([0, 0, 0], order="zxy"), "order must be"),
        (lambda: se3.trinterp(np.eye(4), np.eye(4), 1.5), r"s must lie in \[0, 1\]"),
        (lambda: se3.trinterp(np.eye(3), np.eye(4), 0.5), "both be rotations"),
        (lambda: se3.trnorm(np.zeros((4, 4))), "cannot be normalised"),
        (lambda: se3.qlog([[1, 0, 0, 0], [0, 0, 0, 0]]), r"q\[1\] is zero"),
        (lambda: se3.rotvelxform(np.ones((3, 3))), r"Γ is not a rotation.*\(3, 1, 3\)"),
    ],
)
def test_bad_input_is_named(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_three_angle_triples_pass_as_shape_3_1_3():
    ang = _rng(20).uniform(-1, 1, size=(3, 3))
    np.testing.assert_array_equal(
        se3.rotvelxform(ang[:, None, :])[:, 0], se3.rotvelxform(np.r_[ang, ang])[:3]
    )


def test_single_values_give_single_values():
    T = random_poses(1)[0]
    assert se3.tr2delta(T, T).shape == (6,)
    assert se3.tr2adjoint(T).shape == (6, 6)
    assert se3.delta2tr(np.zeros(6)).shape == (4, 4)
    assert se3.trnorm(T).shape == (4, 4)
    assert se3.rotvelxform([0.1, 0.2, 0.3], full=True).shape == (6, 6)
    assert se3.qexp([1, 0, 0, 0]).shape == (4,)


def test_docstring_examples_run():
    import doctest

    result = doctest.testmod(se3, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 10 and result.failed == 0


# --------------------------------------------------------------------------- algebra (hypothesis)


_unit = st.floats(-1.0, 1.0, allow_nan=False)
_quat = st.tuples(_unit, _unit, _unit, _unit).filter(lambda q: 0.1 < np.linalg.norm(q))
_vec = st.tuples(*[st.floats(-5.0, 5.0, allow_nan=False)] * 3)


def _pose(q, t):
    T = np.eye(4)
    T[:3, :3] = matrix_from_quaternion(np.asarray(q) / np.linalg.norm(q))
    T[:3, 3] = t
    return T


@settings(max_examples=60, deadline=None)
@given(_quat, _vec, _quat, _vec)
def test_adjoint_of_a_product_is_the_product_of_adjoints(q1, t1, q2, t2):
    A, B = _pose(q1, t1), _pose(q2, t2)
    np.testing.assert_allclose(
        se3.tr2adjoint(A @ B), se3.tr2adjoint(A) @ se3.tr2adjoint(B), atol=1e-11
    )
    np.testing.assert_allclose(
        se3.tr2adjoint(np.linalg.inv(A)), np.linalg.inv(se3.tr2adjoint(A)), atol=1e-10
    )


@settings(max_examples=60, deadline=None)
@given(_quat, _vec, _quat, _vec, st.floats(0.0, 1.0))
def test_trinterp_hits_its_endpoints_and_stays_a_pose(q1, t1, q2, t2, s):
    A, B = _pose(q1, t1), _pose(q2, t2)
    ends = se3.trinterp(A, B, np.array([0.0, 1.0]))
    np.testing.assert_allclose(ends[0], A, atol=1e-12)
    np.testing.assert_allclose(ends[1], B, atol=1e-12)
    mid = se3.trinterp(A, B, s)
    np.testing.assert_allclose(mid[:3, :3].T @ mid[:3, :3], np.eye(3), atol=1e-12)
    np.testing.assert_allclose(
        mid[:3, 3], (1 - s) * A[:3, 3] + s * B[:3, 3], atol=1e-12
    )


@settings(max_examples=60, deadline=None)
@given(_vec)
def test_exp_jacobian_inverse_undoes_it_below_a_full_turn(v):
    v = np.asarray(v)
    norm = np.linalg.norm(v)
    if norm > 6.0:
        v = v * 6.0 / norm
    fwd = se3.exp2jac(v)
    inv = se3.rotvelxform(v, inverse=True, representation="exp")
    np.testing.assert_allclose(inv @ fwd, np.eye(3), atol=1e-9)
    np.testing.assert_array_equal(se3.vex(se3.skew(v)), v)
