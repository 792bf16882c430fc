"""The quaternion kernels against their plain-numpy twins and numpy-quaternion."""

from __future__ import annotations

import naive
import numpy as np
import pytest
import quaternion as npq
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from rbm_nb._kernels import conversions as kc
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import rotations as rk
from rbm_nb._kernels import scalar

RNG = np.random.default_rng(20240601)


def unit(n, rng=RNG):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def walk(n, step=0.2, rng=RNG):
    """A continuous rotation time series (no sign flips)."""
    q = np.cumsum(rng.normal(scale=step, size=(n, 4)), axis=0) + [1.0, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for i in range(1, n):
        if q[i] @ q[i - 1] < 0:
            q[i] = -q[i]
    return q


def general(n, rng=RNG):
    return rng.normal(size=(n, 4)) * rng.uniform(0.2, 3.0, size=(n, 1))


# (test id, kernel name, argument factory)
CASES = [
    ("qmul", "qmul", lambda: (general(7), general(7))),
    ("qmul-broadcast-left", "qmul", lambda: (general(1), general(6))),
    ("qmul-broadcast-right", "qmul", lambda: (general(5), general(1))),
    ("qconj", "qconj", lambda: (general(6),)),
    ("rotate_vectors", "rotate_vectors", lambda: (general(8), RNG.normal(size=(8, 3)))),
    (
        "rotate_vectors-broadcast-q",
        "rotate_vectors",
        lambda: (general(1), RNG.normal(size=(8, 3))),
    ),
    (
        "rotate_vectors-broadcast-v",
        "rotate_vectors",
        lambda: (general(8), RNG.normal(size=(1, 3))),
    ),
    (
        "rotate_vectors_outer",
        "rotate_vectors_outer",
        lambda: (general(4), RNG.normal(size=(5, 3))),
    ),
    ("slerp", "slerp", lambda: (unit(6), unit(6), RNG.uniform(-0.5, 1.5, 6))),
    ("slerp-broadcast", "slerp", lambda: (unit(1), unit(6), RNG.uniform(0, 1, 1))),
    ("unflip", "unflip", lambda: (unit(40) * RNG.choice([-1.0, 1.0], size=(40, 1)),)),
]


@pytest.mark.parametrize(
    "name, make_args", [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_kernel_matches_naive_twin(name, make_args):
    args = [np.ascontiguousarray(a, dtype=float) for a in make_args()]
    got = getattr(kq, name)(*args)
    expected = getattr(naive, name)(*args)
    np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("step", [0.02, 0.2])
@pytest.mark.parametrize("n", [2, 3, 4, 7, 60])
def test_squad_equals_numpy_quaternion(n, step):
    rng = np.random.default_rng(n)
    q = walk(n, step=step, rng=rng)
    t = np.cumsum(rng.uniform(0.05, 1.0, n))
    # inside, at every sample, and past the end (within one more segment)
    t_out = np.sort(
        np.concatenate([rng.uniform(t[0], t[-1] + 0.5 * (t[-1] - t[-2]), 80), t])
    )
    np.testing.assert_allclose(
        kq.squad(q, t, t_out), naive.squad(q, t, t_out), rtol=0, atol=1e-12
    )
    # before the start numpy-quaternion extrapolates the *last* segment back
    # over the whole series (tau of order -n): ill-conditioned on both sides
    early = rng.uniform(t[0] - 1, t[0], 10)
    np.testing.assert_allclose(
        kq.squad(q, t, early), naive.squad(q, t, early), rtol=0, atol=1e-7
    )


def test_squad_hits_samples_exactly():
    q = walk(20)
    t = np.arange(20.0) * 0.005
    np.testing.assert_array_equal(kq.squad(q, t, t), q)


def test_squad_single_sample_is_constant():
    q = unit(1)
    out = kq.squad(q, np.array([1.0]), np.array([0.0, 1.0, 2.0]))
    np.testing.assert_array_equal(out, np.repeat(q, 3, axis=0))


def test_squad_coefficients_are_origin_invariant():
    q = walk(30)
    t = np.cumsum(RNG.uniform(0.1, 1, 30))
    a1, b1 = kq.squad_coefficients(q, t)
    a2, b2 = kq.squad_coefficients(q, t + 1e5)
    np.testing.assert_allclose(a1, a2, atol=1e-9)
    np.testing.assert_allclose(b1, b2, atol=1e-9)


def test_rotate_vectors_non_unit_keeps_norm():
    """The reference scales vectors by non-unit quaternions; q v q⁻¹ must not."""
    q = unit(10) * 3.0
    v = RNG.normal(size=(10, 3))
    out = kq.rotate_vectors(q, v)
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), np.linalg.norm(v, axis=1))
    qq = npq.as_quat_array(q)
    vv = npq.as_quat_array(np.column_stack([np.zeros(10), v]))
    np.testing.assert_allclose(out, npq.as_float_array(qq * vv / qq)[:, 1:], atol=1e-12)


def test_exp_log_slerp_equal_numpy_quaternion():
    q = general(20)
    qq = npq.as_quat_array(q)
    # the scalar helpers squad is built from, row by row
    q = np.vstack([q, [[0.3, 0, 0, 0], [-1.0, 1e-16, 0, 0], [2.0, 0, 0, 0]]])
    qq = npq.as_quat_array(q)
    exp = np.array([kq._qexp1(*row) for row in q])
    log = np.array([kq._qlog1(*row) for row in q])
    np.testing.assert_allclose(exp, npq.as_float_array(np.exp(qq)), atol=1e-12)
    np.testing.assert_allclose(log, npq.as_float_array(np.log(qq)), atol=1e-12)
    a, b, tau = unit(20), unit(20), RNG.uniform(0, 1, 20)
    expected = npq.as_float_array(
        np.slerp_vectorized(npq.as_quat_array(a), npq.as_quat_array(b), tau)
    )
    np.testing.assert_allclose(kq.slerp(a, b, tau), expected, atol=1e-12)


def test_small_angle_series_are_exact_to_rounding():
    """The Taylor shortcuts squad uses agree with libm to an ulp or two."""
    import math

    ys = np.concatenate([np.linspace(-0.2, 0.2, 4001), np.geomspace(1e-300, 0.2, 300)])
    for y in ys:
        s, c = kq._sincos(y)
        assert abs(s - math.sin(y)) <= 4.5e-16 * abs(math.sin(y))
        assert abs(c - math.cos(y)) <= 2.3e-16
    for y in np.concatenate(
        [np.linspace(0.0, 0.1, 2001), np.geomspace(1e-300, 0.1, 300)]
    ):
        for x in (0.3, 1.0, 2.0):
            expected = math.atan2(y * x, x)
            assert abs(scalar.atan2(y * x, x) - expected) <= 4.5e-16 * expected


def test_truncated_series_are_within_an_ulp_over_their_ranges():
    """atan(x)/x, cos(y) and sin(y)/y by their series, against long double,
    up to the thresholds below which the kernels take them."""
    x = np.linspace(0.0, scalar.SERIES_RATIO, 20001)[1:]
    y = np.linspace(0.0, scalar.SERIES_ANGLE, 20001)[1:]
    xl, yl = x.astype(np.longdouble), y.astype(np.longdouble)
    cases = [
        (scalar.atan_over_x, x, np.arctan(xl) / xl),
        (scalar.cos_series, y, np.cos(yl)),
        (scalar.sinc_series, y, np.sin(yl) / yl),
    ]
    for series, arg, exact in cases:
        got = np.array([series.py_func(v * v) for v in arg])
        want = exact.astype(np.float64)
        ulps = np.abs(got - want) / np.spacing(want)
        assert ulps.max() <= 1.0, series.__name__


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-4, 0.02, 0.09, 0.15, 0.5, 3.0])
def test_unit_slerp_shortcuts_equal_the_general_slerp(angle):
    """Small arcs use series, larger ones the great circle: both equal exp/log."""
    a = unit(30)
    axis = RNG.normal(size=(30, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    rot = np.column_stack([np.full(30, np.cos(angle / 2)), np.sin(angle / 2) * axis])
    b = naive.qmul(rot, a)
    for tau in (-0.7, 0.0, 0.3, 0.5, 1.0, 2.5):
        fast = np.array([kq._qslerp_unit1(*a[i], *b[i], tau) for i in range(30)])
        slow = np.array([kq._qslerp1(*a[i], *b[i], tau) for i in range(30)])
        np.testing.assert_allclose(fast, slow, rtol=0, atol=2e-15)


def test_quaternion_from_matrix_near_half_turns():
    """Shepperd's branch choice stays accurate where the trace is about -1."""
    axes = np.eye(3)
    q = np.column_stack([np.full(3, 1e-9), axes])
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    back = kc.quaternion_from_matrix(kc.matrix_from_quaternion(q, 1e-2)[0], 1e-9)[0]
    np.testing.assert_allclose(np.abs(np.sum(back * q, axis=1)), 1.0, atol=1e-12)
    assert (back[:, 0] >= 0).all()


finite = st.floats(-10, 10, allow_nan=False)
quats = arrays(np.float64, (5, 4), elements=finite).filter(
    lambda q: (np.linalg.norm(q, axis=1) > 1e-3).all()
)
vecs = arrays(np.float64, (5, 3), elements=finite)


@settings(max_examples=60, deadline=None)
@given(quats, quats, quats)
def test_qmul_is_associative(a, b, c):
    left = kq.qmul(kq.qmul(a, b), c)
    right = kq.qmul(a, kq.qmul(b, c))
    scale = (
        np.linalg.norm(a, axis=1)
        * np.linalg.norm(b, axis=1)
        * np.linalg.norm(c, axis=1)
    )
    np.testing.assert_allclose(left, right, atol=1e-12 * scale.max() + 1e-12)


@settings(max_examples=60, deadline=None)
@given(quats)
def test_qinv_times_q_is_identity(q):
    np.testing.assert_allclose(
        kq.qmul(rk.qinv_checked(q)[0], q), np.tile([1.0, 0, 0, 0], (5, 1)), atol=1e-12
    )


@settings(max_examples=60, deadline=None)
@given(quats, vecs)
def test_rotation_keeps_norms(q, v):
    out = kq.rotate_vectors(q, v)
    np.testing.assert_allclose(
        np.linalg.norm(out, axis=1), np.linalg.norm(v, axis=1), rtol=1e-10, atol=1e-10
    )


@settings(max_examples=60, deadline=None)
@given(quats)
def test_matrix_round_trip(q):
    unit_q = q / np.linalg.norm(q, axis=1, keepdims=True)
    back = kc.quaternion_from_matrix(kc.matrix_from_quaternion(q, np.inf)[0], 1e-9)[0]
    np.testing.assert_allclose(np.abs(np.sum(back * unit_q, axis=1)), 1.0, atol=1e-10)
