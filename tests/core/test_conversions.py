"""rbm_nb.conversions against plain-numpy twins, scipy, and themselves.

* every kernel has a naive numpy twin below (``naive_*``) and is compared
  with it on random and edge-case batches;
* scipy.spatial.transform is the external oracle: all 24 Euler variants,
  rotation vectors, matrices, rigid transforms;
* hypothesis checks the round trips;
* the polynomial sin/cos/atan2 inside the kernels are checked in ulps and
  the atan coefficients are re-derived from scratch.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import warnings
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit
from scipy.spatial.transform import RigidTransform, Rotation

import rbm_nb as rbm
from rbm_nb._kernels import euler as kern_euler
from rbm_nb._kernels import scalar
from rbm_nb.core import conversions as conv

ORDERS = conv.EULER_ORDERS
VARIANTS = [(o, e) for o in ORDERS for e in (False, True)]


def scipy_seq(order, extrinsic):
    return order if extrinsic else order.upper()


def to_scipy(q):
    return Rotation.from_quat(q, scalar_first=True)


def random_quaternions(n, seed=0):
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def same_rotation(q1, q2, atol=1e-12):
    """q1 and q2 equal up to sign, row by row."""
    d = np.minimum(np.abs(q1 - q2).max(axis=-1), np.abs(q1 + q2).max(axis=-1))
    return bool(np.all(d <= atol))


# ---------------------------------------------------------------------------
# naive numpy twins
# ---------------------------------------------------------------------------


def naive_qmul(p, q):
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def naive_canonical(q):
    """Of q and -q, the one with w > 0 or (w = 0 and first non-zero of xyz > 0)."""
    q = np.asarray(q, dtype=float)
    first = np.take_along_axis(q, np.argmax(q != 0, axis=-1)[..., None], -1)[..., 0]
    flip = (q[..., 0] < 0) | ((q[..., 0] == 0) & (first < 0))
    return np.where(flip[..., None], -q, q)


def naive_matrix_from_quaternion(q):
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack(
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1
            ),
            np.stack(
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1
            ),
            np.stack(
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1
            ),
        ],
        axis=-2,
    )


def naive_quaternion_from_matrix(m):
    """Largest eigenvector of the symmetric 4 x 4 matrix of Bar-Itzhack."""
    out = []
    for r in m.reshape(-1, 3, 3):
        k = (
            np.array(
                [
                    [
                        r[0, 0] + r[1, 1] + r[2, 2],
                        r[2, 1] - r[1, 2],
                        r[0, 2] - r[2, 0],
                        r[1, 0] - r[0, 1],
                    ],
                    [
                        r[2, 1] - r[1, 2],
                        r[0, 0] - r[1, 1] - r[2, 2],
                        r[0, 1] + r[1, 0],
                        r[0, 2] + r[2, 0],
                    ],
                    [
                        r[0, 2] - r[2, 0],
                        r[0, 1] + r[1, 0],
                        r[1, 1] - r[0, 0] - r[2, 2],
                        r[1, 2] + r[2, 1],
                    ],
                    [
                        r[1, 0] - r[0, 1],
                        r[0, 2] + r[2, 0],
                        r[1, 2] + r[2, 1],
                        r[2, 2] - r[0, 0] - r[1, 1],
                    ],
                ]
            )
            / 3.0
        )
        vals, vecs = np.linalg.eigh(k)
        out.append(naive_canonical(vecs[:, -1]))
    return np.array(out).reshape(m.shape[:-2] + (4,))


def naive_quaternion_from_rotation_vector(v):
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    # np.sinc(x) = sin(pi x) / (pi x): sin(a/2)/a = sinc(a / (2 pi)) / 2
    return np.concatenate([np.cos(angle / 2), v * np.sinc(angle / (2 * np.pi)) / 2], -1)


def naive_rotation_vector_from_quaternion(q):
    q = naive_canonical(q / np.linalg.norm(q, axis=-1, keepdims=True))
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2 * np.arctan2(s, q[..., :1])
    with np.errstate(all="ignore"):
        scale = np.where(s > 0, angle / s, 2.0)
    return q[..., 1:] * scale


def naive_quaternion_from_axis_angle(axis, angle):
    unit = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.asarray(angle)[..., None]
    return np.concatenate([np.cos(angle / 2), np.sin(angle / 2) * unit], -1)


def naive_axis_angle_from_quaternion(q):
    v = naive_rotation_vector_from_quaternion(q)
    angle = np.linalg.norm(v, axis=-1)
    with np.errstate(all="ignore"):
        axis = np.where(angle[..., None] > 0, v / angle[..., None], [1.0, 0.0, 0.0])
    return axis, angle


def naive_elementary(axis, angle):
    q = np.zeros(np.shape(angle) + (4,))
    q[..., 0] = np.cos(angle / 2)
    q[..., 1 + axis] = np.sin(angle / 2)
    return q


def naive_quaternion_from_euler(angles, order, extrinsic):
    axes = ["xyz".index(c) for c in order]
    q0, q1, q2 = (naive_elementary(axes[n], angles[..., n]) for n in range(3))
    if extrinsic:
        return naive_qmul(naive_qmul(q2, q1), q0)
    return naive_qmul(naive_qmul(q0, q1), q2)


def naive_euler_from_quaternion(q, order, extrinsic):
    """The same direct method as the kernel, in numpy with libm's arctan2."""
    i, j, k = ("xyz".index(c) for c in order)
    if not extrinsic:
        i, k = k, i
    proper = i == k
    if proper:
        k = 3 - i - j
    sign = (i - j) * (j - k) * (k - i) // 2
    w = q[..., 0]
    qi, qj, qk = q[..., 1 + i], q[..., 1 + j], q[..., 1 + k] * sign
    if proper:
        a, b, c, d = w, qi, qj, qk
    else:
        a, b, c, d = w - qj, qi + qk, qj + w, qk - qi
    middle = 2 * np.arctan2(np.hypot(c, d), np.hypot(a, b))
    hs, hd = np.arctan2(b, a), np.arctan2(d, c)
    first, last = hs - hd, hs + hd
    at0 = np.abs(middle) < kern_euler._GIMBAL_EPS
    atpi = np.abs(middle - np.pi) < kern_euler._GIMBAL_EPS
    if extrinsic:
        first = np.where(at0, 2 * hs, np.where(atpi, -2 * hd, first))
        last = np.where(at0 | atpi, 0.0, last)
    else:
        last = np.where(at0, 2 * hs, np.where(atpi, 2 * hd, last))
        first = np.where(at0 | atpi, 0.0, first)
    if not proper:
        last = last * sign
        middle = middle - np.pi / 2
    first = (first + np.pi) % (2 * np.pi) - np.pi
    last = (last + np.pi) % (2 * np.pi) - np.pi
    out = [first, middle, last] if extrinsic else [last, middle, first]
    return np.stack(out, -1)


def naive_homogeneous_from_transform(t, q):
    h = np.zeros(np.broadcast_shapes(t.shape[:-1], q.shape[:-1]) + (4, 4))
    h[..., :3, :3] = naive_matrix_from_quaternion(q)
    h[..., :3, 3] = t
    h[..., 3, 3] = 1.0
    return h


def angles_close(a, b, atol=1e-12):
    """Equal as angles (so -pi and pi match)."""
    d = np.abs((np.asarray(a) - b + np.pi) % (2 * np.pi) - np.pi)
    return bool(np.all(d <= atol))


# ---------------------------------------------------------------------------
# kernels against their twins
# ---------------------------------------------------------------------------


def _edge_quaternions():
    s = math.sqrt(0.5)
    q = [
        [1, 0, 0, 0], [-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1],
        [s, s, 0, 0], [0, s, s, 0], [0, 0, -s, s], [0.5, 0.5, 0.5, 0.5],
        [1, 1e-9, 0, 0], [1, 0, -1e-12, 1e-12], [1e-9, 1, 0, 0],
    ]  # fmt: skip
    q = np.array(q, dtype=float)
    return np.concatenate(
        [q / np.linalg.norm(q, axis=1, keepdims=True), random_quaternions(200)]
    )


EDGE_Q = _edge_quaternions()


@pytest.mark.parametrize(
    "name",
    ["matrix", "rotvec", "axis_angle", "homogeneous"],
)
def test_quaternion_kernels_match_twins(name):
    q = EDGE_Q
    if name == "matrix":
        np.testing.assert_allclose(
            conv.matrix_from_quaternion(q), naive_matrix_from_quaternion(q), atol=1e-14
        )
    elif name == "rotvec":
        np.testing.assert_allclose(
            conv.rotation_vector_from_quaternion(q),
            naive_rotation_vector_from_quaternion(q),
            atol=1e-13,
        )
    elif name == "axis_angle":
        axis, angle = conv.axis_angle_from_quaternion(q)
        naxis, nangle = naive_axis_angle_from_quaternion(q)
        np.testing.assert_allclose(angle, nangle, atol=1e-13)
        np.testing.assert_allclose(axis, naxis, atol=1e-12)
    else:
        t = np.random.default_rng(3).normal(size=(len(q), 3))
        np.testing.assert_allclose(
            conv.homogeneous_from_transform(t, q),
            naive_homogeneous_from_transform(t, q),
            atol=1e-14,
        )


def test_matrix_kernel_matches_eigenvector_twin():
    m = naive_matrix_from_quaternion(EDGE_Q)
    ours = conv.quaternion_from_matrix(m)
    twin = naive_quaternion_from_matrix(m)
    assert same_rotation(ours, twin, atol=1e-12)
    assert np.all(ours[:, 0] >= 0)


def test_transform_from_homogeneous_matches_twin():
    t = np.random.default_rng(4).normal(size=(len(EDGE_Q), 3))
    h = naive_homogeneous_from_transform(t, EDGE_Q)
    tt, qq = conv.transform_from_homogeneous(h)
    np.testing.assert_array_equal(tt, t)
    assert same_rotation(qq, naive_quaternion_from_matrix(h[:, :3, :3]))


@pytest.mark.parametrize("scale", [1e-12, 1e-7, 1.0, 3.0, 12.0])
def test_exponential_kernel_matches_twin(scale):
    v = np.random.default_rng(5).normal(size=(300, 3)) * scale
    np.testing.assert_allclose(
        conv.quaternion_from_rotation_vector(v),
        naive_quaternion_from_rotation_vector(v),
        atol=1e-15,
        rtol=1e-13,
    )


@pytest.mark.parametrize("scale", [1e-9, 1.0, 7.0])
def test_axis_angle_kernel_matches_twin(scale):
    rng = np.random.default_rng(6)
    axis = rng.normal(size=(300, 3)) * rng.uniform(0.1, 10, (300, 1))
    angle = rng.normal(size=300) * scale
    np.testing.assert_allclose(
        conv.quaternion_from_axis_angle(axis, angle),
        naive_quaternion_from_axis_angle(axis, angle),
        atol=1e-15,
        rtol=1e-13,
    )


@pytest.mark.parametrize("order,extrinsic", VARIANTS)
def test_euler_kernels_match_twins(order, extrinsic):
    angles = np.random.default_rng(7).uniform(-7, 7, size=(200, 3))
    np.testing.assert_allclose(
        conv.quaternion_from_euler(angles, order, extrinsic=extrinsic),
        naive_quaternion_from_euler(angles, order, extrinsic),
        atol=1e-14,
    )
    got = conv.euler_from_quaternion(EDGE_Q, order, extrinsic=extrinsic)
    assert angles_close(
        got, naive_euler_from_quaternion(EDGE_Q, order, extrinsic), 1e-12
    )


def test_empty_batches():
    assert conv.matrix_from_quaternion(np.empty((0, 4))).shape == (0, 3, 3)
    assert conv.quaternion_from_matrix(np.empty((0, 3, 3))).shape == (0, 4)
    assert conv.euler_from_quaternion(np.empty((2, 0, 4)), "zyz").shape == (2, 0, 3)
    axis, angle = conv.axis_angle_from_quaternion(np.empty((0, 4)))
    assert axis.shape == (0, 3) and angle.shape == (0,)


# ---------------------------------------------------------------------------
# scipy as the oracle
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("order,extrinsic", VARIANTS)
def test_euler_matches_scipy_all_24_variants(order, extrinsic):
    q = random_quaternions(2000, seed=11).reshape(40, 50, 4)
    seq = scipy_seq(order, extrinsic)
    got = conv.euler_from_quaternion(q, order, extrinsic=extrinsic)
    ref = to_scipy(q.reshape(-1, 4)).as_euler(seq).reshape(40, 50, 3)
    assert got.shape == (40, 50, 3)
    assert angles_close(got, ref, 1e-12)

    angles = np.random.default_rng(12).uniform(-4, 4, (40, 50, 3))
    ours = conv.quaternion_from_euler(angles, order, extrinsic=extrinsic)
    theirs = Rotation.from_euler(seq, angles.reshape(-1, 3)).as_quat(scalar_first=True)
    assert same_rotation(ours.reshape(-1, 4), theirs)


@pytest.mark.parametrize("order,extrinsic", VARIANTS)
def test_euler_gimbal_lock_matches_scipy(order, extrinsic):
    seq = scipy_seq(order, extrinsic)
    singular = [0.0, np.pi] if order[0] == order[2] else [-np.pi / 2, np.pi / 2]
    angles = np.array(
        [[a, m, b] for m in singular for a, b in [(0.3, -0.7), (2.5, 1.9), (0, 0)]]
    )
    q = conv.quaternion_from_euler(angles, order, extrinsic=extrinsic)
    got = conv.euler_from_quaternion(q, order, extrinsic=extrinsic)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # scipy's gimbal lock warning
        ref = to_scipy(q).as_euler(seq)
    assert angles_close(got, ref, 1e-9)
    # the third angle is the one set to zero, and the rotation survives
    np.testing.assert_array_equal(got[:, 2], 0.0)
    back = conv.quaternion_from_euler(got, order, extrinsic=extrinsic)
    assert same_rotation(back, q, atol=1e-12)


def test_matrix_conversions_match_scipy():
    q = random_quaternions(5000, seed=13).reshape(5, 1000, 4)
    m = conv.matrix_from_quaternion(q)
    ref = to_scipy(q.reshape(-1, 4)).as_matrix().reshape(5, 1000, 3, 3)
    np.testing.assert_allclose(m, ref, atol=1e-15)
    back = conv.quaternion_from_matrix(ref)
    assert same_rotation(back.reshape(-1, 4), q.reshape(-1, 4), atol=1e-15 * 4)


def test_rotation_vectors_match_scipy():
    q = np.concatenate([EDGE_Q, random_quaternions(3000, seed=14)])
    np.testing.assert_allclose(
        conv.rotation_vector_from_quaternion(q), to_scipy(q).as_rotvec(), atol=2e-15
    )
    v = np.random.default_rng(15).normal(size=(3000, 3)) * 4
    ours = conv.quaternion_from_rotation_vector(v)
    theirs = Rotation.from_rotvec(v).as_quat(scalar_first=True)
    assert same_rotation(ours, theirs, atol=1e-14)


def test_homogeneous_matches_scipy_rigid_transform():
    rng = np.random.default_rng(16)
    q = random_quaternions(500, seed=16)
    t = rng.normal(size=(500, 3))
    ref = RigidTransform.from_components(t, to_scipy(q)).as_matrix()
    np.testing.assert_allclose(conv.homogeneous_from_transform(t, q), ref, atol=1e-15)
    tt, qq = conv.transform_from_homogeneous(ref)
    np.testing.assert_allclose(tt, t)
    assert same_rotation(qq, q, atol=1e-15 * 4)


def test_axis_angle_matches_scipy_rotvec():
    q = random_quaternions(1000, seed=17)
    axis, angle = conv.axis_angle_from_quaternion(q)
    np.testing.assert_allclose(
        axis * angle[:, None], to_scipy(q).as_rotvec(), atol=2e-15
    )
    np.testing.assert_allclose(np.linalg.norm(axis, axis=1), 1.0, atol=1e-15)
    assert np.all((angle >= 0) & (angle <= np.pi))


# ---------------------------------------------------------------------------
# edge cases
# ---------------------------------------------------------------------------


def test_half_turns():
    axes = np.random.default_rng(18).normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    axes = np.concatenate([np.eye(3), -np.eye(3), axes])
    q = conv.quaternion_from_axis_angle(axes, np.pi)
    np.testing.assert_allclose(q[:, 0], 0.0, atol=1e-16)
    m = conv.matrix_from_quaternion(q)
    np.testing.assert_allclose(m, to_scipy(q).as_matrix(), atol=1e-15)
    # 180° matrices: the quaternion is determined up to sign only
    back = conv.quaternion_from_matrix(m)
    assert same_rotation(back, q, atol=1e-15 * 4)
    v = conv.rotation_vector_from_quaternion(q)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), np.pi, rtol=1e-15)
    axis, angle = conv.axis_angle_from_quaternion(q)
    np.testing.assert_allclose(angle, np.pi, rtol=1e-15)
    assert same_rotation(conv.quaternion_from_rotation_vector(v), q)


def test_q_and_minus_q_are_the_same_rotation():
    q = random_quaternions(500, seed=19)
    np.testing.assert_allclose(
        conv.matrix_from_quaternion(-q), conv.matrix_from_quaternion(q), atol=1e-15
    )
    np.testing.assert_allclose(
        conv.rotation_vector_from_quaternion(-q),
        conv.rotation_vector_from_quaternion(q),
        atol=1e-15,
    )
    a1, t1 = conv.axis_angle_from_quaternion(q)
    a2, t2 = conv.axis_angle_from_quaternion(-q)
    np.testing.assert_allclose(a1, a2, atol=1e-15)
    np.testing.assert_allclose(t1, t2, atol=1e-15)
    for order, extrinsic in VARIANTS[::5]:
        e1 = conv.euler_from_quaternion(q, order, extrinsic=extrinsic)
        e2 = conv.euler_from_quaternion(-q, order, extrinsic=extrinsic)
        assert angles_close(e1, e2, 1e-12)


def test_identity():
    one = np.array([1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(conv.matrix_from_quaternion(one), np.eye(3))
    np.testing.assert_array_equal(conv.quaternion_from_matrix(np.eye(3)), one)
    np.testing.assert_array_equal(
        conv.rotation_vector_from_quaternion(one), np.zeros(3)
    )
    np.testing.assert_array_equal(
        conv.quaternion_from_rotation_vector(np.zeros(3)), one
    )
    axis, angle = conv.axis_angle_from_quaternion(one)
    np.testing.assert_array_equal(axis, [1.0, 0.0, 0.0])
    assert angle == 0.0
    np.testing.assert_array_equal(conv.quaternion_from_axis_angle([0, 0, 0], 0.0), one)
    for order, extrinsic in VARIANTS:
        np.testing.assert_array_equal(
            conv.euler_from_quaternion(one, order, extrinsic=extrinsic), 0
        )
        np.testing.assert_array_equal(
            conv.quaternion_from_euler([0, 0, 0], order, extrinsic=extrinsic), one
        )
    np.testing.assert_array_equal(
        conv.homogeneous_from_transform([0, 0, 0], one), np.eye(4)
    )


@pytest.mark.parametrize(
    "angle", [1e-300, 1e-15, 1e-10, 1e-7, 1e-6, 1.0000001e-6, 1e-4]
)
def test_tiny_angles_keep_full_relative_precision(angle):
    axis = np.array([0.48, -0.6, 0.64])
    v = axis * angle
    q = conv.quaternion_from_rotation_vector(v)
    np.testing.assert_allclose(
        q, Rotation.from_rotvec(v).as_quat(scalar_first=True), rtol=1e-15, atol=0
    )
    back = conv.rotation_vector_from_quaternion(q)
    np.testing.assert_allclose(back, v, rtol=1e-14, atol=0)
    ax, an = conv.axis_angle_from_quaternion(q)
    np.testing.assert_allclose(an, angle, rtol=1e-14)
    np.testing.assert_allclose(ax, axis, rtol=1e-14)
    # Tait-Bryan middle angles come out of (something - pi/2): absolute accuracy
    e = conv.euler_from_quaternion(q, "xyz", extrinsic=True)
    np.testing.assert_allclose(e, to_scipy(q).as_euler("xyz"), atol=1e-15)
    e = conv.euler_from_quaternion(q, "zxz")
    assert same_rotation(conv.quaternion_from_euler(e, "zxz"), q, 1e-15)


def test_huge_angles_use_exact_argument_reduction():
    big = np.array([1e5, -3.3e5, 2e7, 1e12, 123456.789])
    angles = np.stack([big, big[::-1], np.roll(big, 2)], axis=1)
    for order, extrinsic in [("xyz", False), ("zxz", True)]:
        ours = conv.quaternion_from_euler(angles, order, extrinsic=extrinsic)
        ref = Rotation.from_euler(scipy_seq(order, extrinsic), angles).as_quat(
            scalar_first=True
        )
        assert same_rotation(ours, ref, atol=1e-12)
    v = angles / np.sqrt(3)
    assert same_rotation(
        conv.quaternion_from_rotation_vector(v),
        Rotation.from_rotvec(v).as_quat(scalar_first=True),
        atol=1e-9,  # scipy builds the angle from |v| with its own rounding
    )
    axis = np.ones((5, 3))
    np.testing.assert_allclose(
        conv.quaternion_from_axis_angle(axis, big),
        naive_quaternion_from_axis_angle(axis, big),
        atol=1e-15,
    )


@pytest.mark.parametrize("scale", [1e-320, 1e-200, 1e-160, 1e160, 1e300])
def test_axis_lengths_that_under_or_overflow_when_squared(scale):
    axis = np.array([[0.48, -0.6, 0.64], [0.0, 0.0, 0.0]]) * scale
    q = conv.quaternion_from_axis_angle(axis, [1.2, 0.0])
    # subnormal input is itself rounded: compare with the direction it has
    ref = naive_quaternion_from_axis_angle(axis[0] / np.abs(axis[0]).max(), 1.2)
    np.testing.assert_allclose(q[0], ref, atol=1e-15)
    np.testing.assert_array_equal(q[1], [1.0, 0.0, 0.0, 0.0])


def test_axis_of_a_rotation_by_a_subnormal_angle():
    q = np.array([[1.0, 3e-310, -4e-310, 0.0], [1.0, 0.0, 0.0, 0.0]])
    axis, angle = conv.axis_angle_from_quaternion(q)
    np.testing.assert_allclose(axis, [[0.6, -0.8, 0.0], [1.0, 0.0, 0.0]], rtol=1e-6)
    np.testing.assert_allclose(angle, [1e-309, 0.0], rtol=1e-6)


def test_degrees_and_scalar_shapes():
    q = conv.quaternion_from_euler([10.0, 20.0, 30.0], "zyx", degrees=True)
    assert q.shape == (4,)
    ref = Rotation.from_euler("ZYX", [10, 20, 30], degrees=True).as_quat(
        scalar_first=True
    )
    assert same_rotation(q[None], ref[None])
    np.testing.assert_allclose(
        conv.euler_from_quaternion(q, "zyx", degrees=True), [10, 20, 30]
    )
    assert conv.matrix_from_quaternion(q).shape == (3, 3)
    axis, angle = conv.axis_angle_from_quaternion(q)
    assert axis.shape == (3,) and np.ndim(angle) == 0


def test_broadcasting_of_paired_inputs():
    t = np.zeros((2, 5, 3))
    q = random_quaternions(5)
    assert conv.homogeneous_from_transform(t, q).shape == (2, 5, 4, 4)
    assert conv.quaternion_from_axis_angle([0, 0, 1], np.linspace(0, 1, 7)).shape == (
        7,
        4,
    )


def test_slightly_off_input_is_normalised_far_off_is_refused():
    q = random_quaternions(10) * 1.005
    np.testing.assert_allclose(
        conv.matrix_from_quaternion(q), naive_matrix_from_quaternion(q), atol=1e-15
    )
    # a matrix off by less than tol gives a quaternion off by about as much
    m = naive_matrix_from_quaternion(random_quaternions(10)) * (1 + 2e-7)
    assert same_rotation(
        conv.quaternion_from_matrix(m), naive_quaternion_from_matrix(m), 1e-6
    )


# ---------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------


def test_reflection_names_tolerance_index_and_determinant():
    m = np.tile(np.eye(3), (2, 3, 1, 1))
    m[1, 2] = np.diag([1.0, 1.0, -1.0])
    m[0, 1] = np.diag([1.0, 1.0 + 1e-3, 1.0])
    with pytest.raises(
        ValueError,
        match=r"matrix\[1, 2\] is not a rotation matrix.*det = -1, a reflection.*tol=1e-06",
    ):
        conv.quaternion_from_matrix(m)


def test_non_orthonormal_reports_worst_index():
    m = np.tile(np.eye(3), (6, 1, 1))
    m[1] *= 1.0001
    m[4, 0, 1] = 0.01  # worse
    with pytest.raises(
        ValueError, match=r"matrix\[4\] is not.*= 0\.01.*worst in the batch.*tol=1e-06"
    ):
        conv.quaternion_from_matrix(m)
    # a looser tolerance accepts the same matrices
    assert conv.quaternion_from_matrix(m, tol=0.05).shape == (6, 4)
    with pytest.raises(ValueError, match="tol must be"):
        conv.quaternion_from_matrix(m, tol=-1)


def test_homogeneous_errors():
    h = np.tile(np.eye(4), (3, 1, 1))
    h[2, 3, 0] = 1.0
    with pytest.raises(
        ValueError, match=r"matrix\[2\] has bottom row \[1.0, 0.0, 0.0, 1.0\]"
    ):
        conv.transform_from_homogeneous(h)
    h = np.eye(4)
    h[0, 3] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        conv.transform_from_homogeneous(h)
    with pytest.raises(ValueError, match=r"translation\[1\] is \[inf"):
        conv.homogeneous_from_transform([[0, 0, 0], [np.inf, 0, 0]], [1, 0, 0, 0])
    with pytest.raises(ValueError, match=r"rotation\[0\] has norm 2"):
        conv.homogeneous_from_transform([0, 0, 0], [[2, 0, 0, 0]])


def test_unknown_euler_order_lists_all_24():
    with pytest.raises(ValueError) as info:
        conv.quaternion_from_euler([0, 0, 0], "xxy")
    message = str(info.value)
    assert "24" in message and "extrinsic=True" in message
    for order in ORDERS:
        assert order in message
    with pytest.raises(ValueError, match="unknown Euler order"):
        conv.euler_from_quaternion([1, 0, 0, 0], "abc")
    with pytest.raises(ValueError, match="unknown Euler order"):
        conv.euler_from_quaternion([1, 0, 0, 0], 3)


def test_upper_case_order_is_explained():
    with pytest.raises(ValueError, match=r"order='zyx', extrinsic=False"):
        conv.quaternion_from_euler([0, 0, 0], "ZYX")


@pytest.mark.parametrize(
    "func",
    [
        conv.matrix_from_quaternion,
        conv.rotation_vector_from_quaternion,
        conv.axis_angle_from_quaternion,
        lambda q: conv.euler_from_quaternion(q, "zyz"),
    ],
)
def test_non_unit_and_nan_quaternions_are_refused(func):
    q = random_quaternions(8).reshape(2, 4, 4)
    q[1, 1] *= 1.5
    q[0, 2] *= 1.2
    with pytest.raises(
        ValueError, match=r"quaternion\[1, 1\] has norm 1\.5.*within 0\.01"
    ):
        func(q)
    q = random_quaternions(3)
    q[2, 0] = np.nan
    with pytest.raises(ValueError, match=r"quaternion\[2\] has norm nan"):
        func(q)
    with pytest.raises(ValueError, match="has norm 0"):
        func([0.0, 0.0, 0.0, 0.0])


def test_non_finite_vectors_and_angles_are_refused():
    with pytest.raises(ValueError, match=r"rotation_vector\[1\] is \[nan"):
        conv.quaternion_from_rotation_vector([[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ValueError, match=r"angles\[0\] is \[0.0, inf"):
        conv.quaternion_from_euler([[0, np.inf, 0]], "zyx")
    with pytest.raises(
        ValueError, match=r"axis\[1\] is \[0.0, 0.0, 0.0\] with angle 0.5"
    ):
        conv.quaternion_from_axis_angle([[1, 0, 0], [0, 0, 0]], [0.5, 0.5])
    with pytest.raises(ValueError, match="angle nan"):
        conv.quaternion_from_axis_angle([1, 0, 0], np.nan)


def test_shape_errors_name_the_argument():
    with pytest.raises(
        ValueError, match=r"quaternion must have shape \(\.\.\., 4\), got \(3,\)"
    ):
        conv.matrix_from_quaternion([1, 0, 0])
    with pytest.raises(ValueError, match=r"matrix must have shape \(\.\.\., 3, 3\)"):
        conv.quaternion_from_matrix(np.eye(4))
    with pytest.raises(ValueError, match=r"matrix must have shape \(\.\.\., 4, 4\)"):
        conv.transform_from_homogeneous(np.eye(3))
    with pytest.raises(ValueError, match="angles must have shape"):
        conv.quaternion_from_euler([1, 2])
    with pytest.raises(ValueError, match="do not broadcast"):
        conv.quaternion_from_axis_angle(np.ones((3, 3)), [1.0, 2.0])
    with pytest.raises(ValueError, match="numeric"):
        conv.matrix_from_quaternion(["a", "b", "c", "d"])


def test_public_names_are_exported_lazily():
    for name in [
        "quaternion_from_matrix", "matrix_from_quaternion", "quaternion_from_rotation_vector",
        "rotation_vector_from_quaternion", "quaternion_from_axis_angle", "axis_angle_from_quaternion",
        "quaternion_from_euler", "euler_from_quaternion", "homogeneous_from_transform",
        "transform_from_homogeneous",
    ]:  # fmt: skip
        assert getattr(rbm, name) is getattr(conv, name)


# ---------------------------------------------------------------------------
# hypothesis round trips
# ---------------------------------------------------------------------------

finite = st.floats(-1.0, 1.0, allow_nan=False)
quaternions = (
    st.tuples(finite, finite, finite, finite)
    .filter(lambda c: sum(x * x for x in c) > 1e-2)
    .map(lambda c: np.array(c) / np.linalg.norm(c))
)


@settings(max_examples=200, deadline=None)
@given(q=quaternions)
def test_roundtrip_matrix(q):
    assert same_rotation(
        conv.quaternion_from_matrix(conv.matrix_from_quaternion(q)), q, 4e-15
    )
    m = conv.matrix_from_quaternion(q)
    np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(m) == pytest.approx(1.0, abs=1e-14)


@settings(max_examples=200, deadline=None)
@given(q=quaternions)
def test_roundtrip_rotation_vector_and_axis_angle(q):
    v = conv.rotation_vector_from_quaternion(q)
    assert np.linalg.norm(v) <= np.pi + 1e-15
    assert same_rotation(conv.quaternion_from_rotation_vector(v), q, 1e-14)
    axis, angle = conv.axis_angle_from_quaternion(q)
    assert same_rotation(conv.quaternion_from_axis_angle(axis, angle), q, 1e-14)


@settings(max_examples=300, deadline=None)
@given(q=quaternions, variant=st.sampled_from(VARIANTS))
def test_roundtrip_euler(q, variant):
    order, extrinsic = variant
    e = conv.euler_from_quaternion(q, order, extrinsic=extrinsic)
    lo = 0.0 if order[0] == order[2] else -np.pi / 2
    assert lo - 1e-15 <= e[1] <= lo + np.pi + 1e-15
    assert np.all(np.abs(e) <= np.pi + 1e-15)
    assert same_rotation(
        conv.quaternion_from_euler(e, order, extrinsic=extrinsic), q, 2e-13
    )


@settings(max_examples=100, deadline=None)
@given(
    q=quaternions,
    t=st.tuples(*[st.floats(-1e6, 1e6, allow_nan=False)] * 3).map(np.array),
)
def test_roundtrip_homogeneous(q, t):
    h = conv.homogeneous_from_transform(t, q)
    tt, qq = conv.transform_from_homogeneous(h)
    np.testing.assert_array_equal(tt, t)
    assert same_rotation(qq, q, 4e-15)
    p = np.array([0.3, -1.0, 2.0])
    np.testing.assert_allclose(
        (h @ np.append(p, 1.0))[:3],
        naive_matrix_from_quaternion(q) @ p + t,
        rtol=1e-12,
        atol=1e-9,
    )


@settings(max_examples=100, deadline=None)
@given(
    angles=st.tuples(*[st.floats(-50, 50, allow_nan=False)] * 3).map(np.array),
    variant=st.sampled_from(VARIANTS),
)
def test_extrinsic_is_reversed_intrinsic(angles, variant):
    order, _ = variant
    a = conv.quaternion_from_euler(angles, order, extrinsic=True)
    b = conv.quaternion_from_euler(angles[::-1], order[::-1], extrinsic=False)
    assert same_rotation(a, b, 1e-14)


# ---------------------------------------------------------------------------
# the polynomial math inside the kernels
# ---------------------------------------------------------------------------


@njit
def _sincos_array(x):
    s = np.empty_like(x)
    c = np.empty_like(x)
    for i in range(x.size):
        s[i], c[i] = scalar.sincos(x[i])
    return s, c


@njit
def _atan2_array(y, x):
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = scalar.atan2(y[i], x[i])
    return out


@pytest.mark.parametrize("limit", [1.0, 10.0, 1e3, 0.99e5])
def test_sincos_within_two_ulps(limit):
    x = np.random.default_rng(20).uniform(-limit, limit, 200_000)
    s, c = _sincos_array(x)
    for ours, ref in [(s, np.sin(x)), (c, np.cos(x))]:
        # errors in units of the last place of the largest possible value (1)
        assert np.max(np.abs(ours - ref)) <= 2 * np.spacing(1.0)


def test_atan2_within_four_ulps_and_signed_zeros():
    rng = np.random.default_rng(21)
    y = rng.normal(size=300_000) * np.exp(rng.uniform(-40, 40, 300_000))
    x = rng.normal(size=300_000) * np.exp(rng.uniform(-40, 40, 300_000))
    ref = np.arctan2(y, x)
    assert np.max(np.abs(_atan2_array(y, x) - ref) / np.spacing(np.abs(ref))) <= 4
    y = np.array([0.0, -0.0, 0.0, -0.0, 1.0, -1.0, 0.0, 2.0, -2.0])
    x = np.array([1.0, 1.0, -1.0, -1.0, 0.0, 0.0, 0.0, 2.0, -2.0])
    np.testing.assert_array_equal(_atan2_array(y, x), np.arctan2(y, x))


def _economised_atan_coefficients(degree=11, interval=Fraction(1716, 10000), terms=80):
    """Chebyshev economisation of sum((-s)^n / (2n+1)) on [0, interval], exactly."""
    taylor = [Fraction((-1) ** n, 2 * n + 1) for n in range(terms)]
    half = interval / 2
    # s = half (1 + x): coefficients in x
    in_x = [Fraction(0)] * terms
    for n, c in enumerate(taylor):
        for k in range(n + 1):
            in_x[k] += c * half**n * math.comb(n, k)
    # x^n = 2^(1-n) sum_k C(n, k) T_(n-2k), with T_0 counted once
    cheb = [Fraction(0)] * terms
    for n, c in enumerate(in_x):
        for k in range(n // 2 + 1):
            weight = Fraction(math.comb(n, k), 2**n) * (1 if n == 2 * k else 2)
            cheb[n - 2 * k] += c * weight
    dropped = sum(abs(c) for c in cheb[degree + 1 :])
    t_polys = [[Fraction(1)], [Fraction(0), Fraction(1)]]
    for m in range(2, degree + 1):
        a = [Fraction(0)] + [2 * v for v in t_polys[m - 1]]
        b = t_polys[m - 2] + [Fraction(0)] * (len(a) - len(t_polys[m - 2]))
        t_polys.append([u - v for u, v in zip(a, b, strict=True)])
    kept_x = [Fraction(0)] * (degree + 1)
    for m in range(degree + 1):
        for k, v in enumerate(t_polys[m]):
            kept_x[k] += cheb[m] * v
    # back to s: x = s / half - 1
    in_s = [Fraction(0)] * (degree + 1)
    for k, v in enumerate(kept_x):
        for j in range(k + 1):
            in_s[j] += v * math.comb(k, j) * (1 / half) ** j * (-1) ** (k - j)
    return [float(c) for c in in_s], float(dropped)


def test_atan_coefficients_rederived():
    coefficients, dropped = _economised_atan_coefficients()
    assert tuple(coefficients) == scalar.ATAN_P
    assert dropped < 1.3e-18
    assert scalar.TAN_PI_8**2 <= 0.1716


# ---------------------------------------------------------------------------
# the same code without numba (coverage runs use NUMBA_DISABLE_JIT=1)
# ---------------------------------------------------------------------------

_PURE_PYTHON_SCRIPT = r"""
import json, sys
import numpy as np
import rbm_nb.conversions as conv
q = np.array(json.loads(sys.argv[1]))
out = {
    "m": conv.matrix_from_quaternion(q).tolist(),
    "qm": conv.quaternion_from_matrix(conv.matrix_from_quaternion(q)).tolist(),
    "v": conv.rotation_vector_from_quaternion(q).tolist(),
    "qv": conv.quaternion_from_rotation_vector(conv.rotation_vector_from_quaternion(q)).tolist(),
    "aa": conv.axis_angle_from_quaternion(q)[1].tolist(),
    "qaa": conv.quaternion_from_axis_angle([[0, 0, 0], [1, 1, 0]], [0.0, 3e5]).tolist(),
    "e": conv.euler_from_quaternion(q, "zxz", extrinsic=True).tolist(),
    "qe": conv.quaternion_from_euler([[0.1, 0.2, 0.3], [1e6, 0, 0]], "yxz").tolist(),
    "h": conv.transform_from_homogeneous(conv.homogeneous_from_transform([1, 2, 3], q))[1].tolist(),
}
print(json.dumps(out))
"""


@pytest.mark.slow
def test_pure_python_mode_gives_the_same_results():
    q = np.concatenate([EDGE_Q[:12], random_quaternions(4)])
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    proc = subprocess.run(
        [sys.executable, "-c", _PURE_PYTHON_SCRIPT, json.dumps(q.tolist())],
        env=env, capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    pure = json.loads(proc.stdout)
    expected = {
        "m": conv.matrix_from_quaternion(q),
        "qm": conv.quaternion_from_matrix(conv.matrix_from_quaternion(q)),
        "v": conv.rotation_vector_from_quaternion(q),
        "qv": conv.quaternion_from_rotation_vector(
            conv.rotation_vector_from_quaternion(q)
        ),
        "aa": conv.axis_angle_from_quaternion(q)[1],
        "qaa": conv.quaternion_from_axis_angle([[0, 0, 0], [1, 1, 0]], [0.0, 3e5]),
        "e": conv.euler_from_quaternion(q, "zxz", extrinsic=True),
        "qe": conv.quaternion_from_euler([[0.1, 0.2, 0.3], [1e6, 0, 0]], "yxz"),
        "h": conv.transform_from_homogeneous(
            conv.homogeneous_from_transform([1, 2, 3], q)
        )[1],
    }
    for key, value in expected.items():
        np.testing.assert_allclose(np.array(pure[key]), value, atol=1e-14, err_msg=key)


def test_docstring_examples_run():
    import doctest
    import importlib

    module = importlib.import_module("rbm_nb.conversions")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
