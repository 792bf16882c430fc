"""rbm_nb.Transform against homogeneous-matrix twins, scipy and the algebra axioms."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import RigidTransform, Rotation, Slerp

import rbm_nb as rbm
from rbm_nb.core.rigid_transform import Transform


def random_transforms(shape, seed=0):
    rng = np.random.default_rng(seed)
    n = int(np.prod(shape))
    q = (
        Rotation.random(n, rng=rng)
        .as_quat(scalar_first=True)
        .reshape(tuple(shape) + (4,))
    )
    t = rng.normal(size=tuple(shape) + (3,))
    return Transform(t, q)


def naive_matrix(tf):
    """[[R, t], [0, 1]] built with scipy's rotation matrices."""
    rot = Rotation.from_quat(np.asarray(tf.rotation).reshape(-1, 4), scalar_first=True)
    h = np.zeros((rot.as_matrix().shape[0], 4, 4))
    h[:, :3, :3] = rot.as_matrix()
    h[:, :3, 3] = np.asarray(tf.translation).reshape(-1, 3)
    h[:, 3, 3] = 1.0
    return h.reshape(tf.shape + (4, 4))


def naive_apply(tf, points):
    h = naive_matrix(tf)
    return np.einsum("...ij,...j->...i", h[..., :3, :3], points) + h[..., :3, 3]


def same_rotation(q1, q2, atol=1e-12):
    d = np.minimum(np.abs(q1 - q2).max(axis=-1), np.abs(q1 + q2).max(axis=-1))
    return bool(np.all(d <= atol))


def rot_x(angle):
    return Rotation.from_euler("x", angle).as_quat(scalar_first=True)


# ---------------------------------------------------------------------------
# construction, immutability, array behaviour
# ---------------------------------------------------------------------------


def test_default_is_identity_and_exported():
    assert rbm.Transform is Transform
    tf = Transform()
    assert tf.shape == () and tf.ndim == 0
    np.testing.assert_array_equal(tf.translation, [0, 0, 0])
    np.testing.assert_array_equal(tf.rotation, [1, 0, 0, 0])
    assert tf == Transform.identity()
    assert Transform.identity(4).shape == (4,)
    assert Transform.identity((2, 3)).shape == (2, 3)


def test_broadcast_and_normalise_on_construction():
    tf = Transform(np.zeros((5, 3)), [2**-0.5 * 1.001, 2**-0.5 * 1.001, 0, 0])
    assert tf.shape == (5,)
    np.testing.assert_allclose(np.linalg.norm(tf.rotation, axis=1), 1.0, rtol=1e-15)
    assert Transform([1.0, 2.0, 3.0], np.tile([1.0, 0, 0, 0], (2, 3, 1))).shape == (
        2,
        3,
    )


def test_construction_errors():
    with pytest.raises(
        ValueError, match=r"translation must have length 3 along its last axis"
    ):
        Transform([1.0, 2.0])
    with pytest.raises(
        ValueError, match=r"rotation must have length 4 along its last axis"
    ):
        Transform(rotation=[1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"rotation\[1\] is of norm 2"):
        Transform(rotation=[[1.0, 0, 0, 0], [2.0, 0, 0, 0]])
    with pytest.raises(ValueError, match="rotation is not finite"):
        Transform(rotation=[np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match=r"translation\[2\] is not finite"):
        Transform(np.array([[0, 0, 0], [0, 0, 0], [np.inf, 0, 0]]))
    with pytest.raises(ValueError, match="do not broadcast"):
        Transform(np.zeros((3, 3)), np.tile([1.0, 0, 0, 0], (2, 1)))
    with pytest.raises(ValueError, match="numeric"):
        Transform(["a", "b", "c"])


def test_immutable():
    tf = random_transforms((3,))
    with pytest.raises(AttributeError, match="immutable"):
        tf.translation = np.zeros(3)
    with pytest.raises(AttributeError, match="immutable"):
        tf._rotation = None
    with pytest.raises(ValueError):
        tf.translation[0, 0] = 5.0
    with pytest.raises(ValueError):
        tf.rotation[...] = 0.0
    # input arrays are copied, not aliased
    t = np.zeros(3)
    tf = Transform(t)
    t[0] = 1.0
    assert tf.translation[0] == 0.0


def test_len_getitem_iter():
    tf = random_transforms((4, 5), seed=1)
    assert len(tf) == 4
    row = tf[2]
    assert row.shape == (5,)
    np.testing.assert_array_equal(row.translation, tf.translation[2])
    one = tf[2, 3]
    assert one.shape == ()
    np.testing.assert_array_equal(one.rotation, tf.rotation[2, 3])
    assert tf[:, ::2].shape == (4, 3)
    assert tf[np.array([True, False, True, False])].shape == (2, 5)
    assert tf[..., 0].shape == (4,)
    assert [t.shape for t in tf] == [(5,)] * 4
    with pytest.raises(IndexError):
        tf[1, 2, 0]
    with pytest.raises(IndexError):
        tf[7]
    with pytest.raises(TypeError, match="len"):
        len(tf[0, 0])
    with pytest.raises(IndexError, match="cannot be indexed"):
        tf[0, 0][0]


def test_repr_shows_values_and_batch_shape():
    text = repr(Transform([1.5, -2.0, 0.25]))
    assert text.startswith("Transform(translation=[ 1.5 , -2.  ,  0.25]")
    assert "rotation=[1., 0., 0., 0.]" in text
    batch = repr(Transform.identity(100))
    assert batch.startswith("Transform(shape=(100,),") and "..." in batch
    assert len(batch.splitlines()) < 15


def test_equality_allclose_and_pickle():
    tf = random_transforms((6,), seed=2)
    flipped = Transform(tf.translation, -np.asarray(tf.rotation))
    assert tf == flipped  # q and -q are the same rotation
    assert tf != Transform(tf.translation + 1e-9, tf.rotation)
    assert tf.allclose(Transform(tf.translation + 1e-13, tf.rotation))
    assert not tf.allclose(Transform(tf.translation + 1e-9, tf.rotation))
    assert tf != random_transforms((5,))
    assert (tf == "x") is False
    with pytest.raises(TypeError):
        hash(tf)
    assert pickle.loads(pickle.dumps(tf)) == tf
    assert copy.deepcopy(tf) == tf and copy.copy(tf) == tf


# ---------------------------------------------------------------------------
# against homogeneous matrices and scipy
# ---------------------------------------------------------------------------


def test_apply_matches_matrix_twin():
    tf = random_transforms((7,), seed=3)
    p = np.random.default_rng(4).normal(size=(7, 3))
    np.testing.assert_allclose(tf.apply(p), naive_apply(tf, p), atol=1e-14)
    np.testing.assert_allclose(
        tf.apply_vectors(p), naive_apply(Transform(rotation=tf.rotation), p), atol=1e-14
    )
    # a single transformation on many points, many on one point
    np.testing.assert_allclose(tf[0].apply(p), naive_apply(tf[0], p), atol=1e-14)
    assert tf.apply([1.0, 2.0, 3.0]).shape == (7, 3)
    assert tf[0].apply(np.zeros((2, 9, 3))).shape == (2, 9, 3)
    with pytest.raises(ValueError, match="do not broadcast"):
        tf.apply(np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"points must have length 3"):
        tf.apply([1.0, 2.0])


def test_composition_matches_matrix_products_and_scipy():
    a = random_transforms((9,), seed=5)
    b = random_transforms((9,), seed=6)
    ab = a @ b
    np.testing.assert_allclose(
        ab.as_matrix(), naive_matrix(a) @ naive_matrix(b), atol=1e-14
    )
    ref = RigidTransform.from_matrix(naive_matrix(a)) * RigidTransform.from_matrix(
        naive_matrix(b)
    )
    np.testing.assert_allclose(ab.as_matrix(), ref.as_matrix(), atol=1e-14)
    p = np.random.default_rng(7).normal(size=(9, 3))
    np.testing.assert_allclose(ab.apply(p), a.apply(b.apply(p)), atol=1e-14)
    # a single transform composes with a batch
    assert (a[0] @ b).shape == (9,)
    with pytest.raises(ValueError, match="cannot compose"):
        a @ random_transforms((4,))
    with pytest.raises(TypeError):
        a @ np.eye(4)


def test_inverse_matches_matrix_inverse():
    tf = random_transforms((3, 4), seed=8)
    np.testing.assert_allclose(
        tf.inv().as_matrix(), np.linalg.inv(naive_matrix(tf)), atol=1e-14
    )
    assert (tf @ tf.inv()).allclose(Transform.identity((3, 4)))
    assert (tf.inv() @ tf).allclose(Transform.identity((3, 4)))


def test_matrix_round_trip():
    tf = random_transforms((10,), seed=9)
    h = tf.as_matrix()
    np.testing.assert_allclose(h, naive_matrix(tf), atol=1e-15)
    assert Transform.from_matrix(h).allclose(tf, atol=1e-15)
    with pytest.raises(ValueError, match="tol=1e-06"):
        Transform.from_matrix(h * 1.01)
    assert Transform.from_matrix(h[0]).shape == ()


def test_slerp_matches_scipy_and_interpolates_translation():
    a = random_transforms((), seed=10)
    b = random_transforms((), seed=11)
    ratios = np.linspace(0.0, 1.0, 11)
    mid = a.slerp(b, ratios)
    assert mid.shape == (11,)
    key = Rotation.from_quat(np.stack([a.rotation, b.rotation]), scalar_first=True)
    ref = Slerp([0.0, 1.0], key)(ratios).as_quat(scalar_first=True)
    assert same_rotation(mid.rotation, ref, atol=1e-14)
    np.testing.assert_allclose(
        mid.translation,
        a.translation + ratios[:, None] * (b.translation - a.translation),
    )
    assert a.slerp(b, 0.0).allclose(a) and a.slerp(b, 1.0).allclose(b)
    # constant angular speed along the shorter arc
    steps = np.linalg.norm(
        (mid[:-1].inv() @ mid[1:]).difference(Transform.identity())[1], axis=1
    )
    np.testing.assert_allclose(steps, steps[0], rtol=1e-10)
    assert steps.sum() <= np.pi + 1e-12
    with pytest.raises(ValueError, match="finite"):
        a.slerp(b, np.nan)


def test_lerp_endpoints_shorter_arc_and_unit_norm():
    a = Transform([0, 0, 0], rot_x(0.1))
    b = Transform([2, 2, 2], -rot_x(0.5))  # same rotation, opposite sign
    mid = a.lerp(b, 0.5)
    np.testing.assert_allclose(mid.translation, [1, 1, 1])
    assert same_rotation(mid.rotation, rot_x(0.3), atol=1e-15)
    assert a.lerp(b, 0.0).allclose(a) and a.lerp(b, 1.0).allclose(b)
    r = a.lerp(b, np.linspace(0, 1, 7))
    np.testing.assert_allclose(np.linalg.norm(r.rotation, axis=1), 1.0, rtol=1e-15)
    # same as slerp for a rotation about one axis, up to the speed profile
    assert same_rotation(a.lerp(b, 0.5).rotation, a.slerp(b, 0.5).rotation, atol=1e-15)


def test_difference_examples_from_scikit_robot_docs():
    c1 = Transform([0.1, 0.2, 0.3], rot_x(np.pi / 3))
    c2 = Transform(
        [0.3, -0.3, 0.1], Rotation.from_euler("y", np.pi / 2).as_quat(scalar_first=True)
    )
    np.testing.assert_allclose(
        c1.difference(c2)[0], [0.2, -0.42320508, 0.3330127], atol=1e-8
    )
    c1 = Transform([0.1, 0.2, 0.3])
    c2 = Transform([0.3, -0.3, 0.1], rot_x(np.pi / 3))
    np.testing.assert_allclose(c1.difference(c2)[0], [0.2, -0.5, -0.2], atol=1e-15)
    np.testing.assert_allclose(
        c1.difference(c2, position_mask="z")[0], [0, 0, -0.2], atol=1e-15
    )

    rpy = Rotation.from_euler("ZYX", [np.pi / 2, np.pi / 3, np.pi / 5])
    c2 = Transform(rotation=rpy.as_quat(scalar_first=True))
    rot = Transform().difference(c2)[1]
    np.testing.assert_allclose(rot, [-0.32855112, 1.17434985, 1.05738936], atol=1e-8)
    np.testing.assert_array_equal(
        Transform().difference(c2, rotation_mask=False)[1], 0.0
    )
    np.testing.assert_allclose(
        Transform().difference(c2, rotation_mask="yz")[1],
        [0, 1.17434985, 1.05738936],
        atol=1e-8,
    )
    np.testing.assert_allclose(
        Transform().difference(c2, rotation_mask=[1, 0, 1])[1],
        [-0.32855112, 0, 1.05738936],
        atol=1e-8,
    )
    flipped = Transform(rotation=rot_x(np.pi))
    assert np.linalg.norm(Transform().difference(flipped)[1]) == pytest.approx(np.pi)
    np.testing.assert_allclose(
        Transform().difference(flipped, rotation_mirror="x")[1], 0.0, atol=1e-15
    )


def test_difference_reconstructs_other_and_validates_masks():
    a = random_transforms((20,), seed=12)
    b = random_transforms((20,), seed=13)
    dpos, drot = a.difference(b)
    step = Transform(dpos, rbm.quaternion_from_rotation_vector(drot))
    assert (a @ step).allclose(b, atol=1e-13)
    assert np.all(np.linalg.norm(drot, axis=1) <= np.pi + 1e-15)
    with pytest.raises(ValueError, match="position_mask"):
        a.difference(b, position_mask="xw")
    with pytest.raises(ValueError, match="rotation_mask"):
        a.difference(b, rotation_mask=[1, 2, 0])
    with pytest.raises(ValueError, match="rotation_mirror"):
        a.difference(b, rotation_mirror="w")


# ---------------------------------------------------------------------------
# axioms (hypothesis)
# ---------------------------------------------------------------------------

unit = st.floats(-1.0, 1.0, allow_nan=False)
coord = st.floats(-100.0, 100.0, allow_nan=False)
transforms = st.builds(
    lambda q, t: Transform(t, np.array(q) / np.linalg.norm(q)),
    st.tuples(unit, unit, unit, unit).filter(lambda q: sum(c * c for c in q) > 1e-2),
    st.tuples(coord, coord, coord),
)
points = st.tuples(coord, coord, coord).map(np.array)


@settings(max_examples=150, deadline=None)
@given(a=transforms, b=transforms, c=transforms)
def test_composition_is_associative(a, b, c):
    assert ((a @ b) @ c).allclose(a @ (b @ c), atol=1e-11)


@settings(max_examples=150, deadline=None)
@given(a=transforms, p=points, v=points)
def test_inverse_and_isometry(a, p, v):
    np.testing.assert_allclose(a.inv().apply(a.apply(p)), p, atol=1e-11)
    assert (a.inv().inv()).allclose(a, atol=1e-12)
    assert np.linalg.norm(a.apply_vectors(v)) == pytest.approx(
        np.linalg.norm(v), rel=1e-14, abs=1e-12
    )
    assert np.linalg.norm(a.apply(p) - a.apply(v)) == pytest.approx(
        np.linalg.norm(p - v), rel=1e-14, abs=1e-11
    )


@settings(max_examples=100, deadline=None)
@given(a=transforms, b=transforms, r=st.floats(0.0, 1.0))
def test_interpolation_stays_between(a, b, r):
    for mid in (a.slerp(b, r), a.lerp(b, r)):
        # the angle to each end adds up to the angle between the ends
        to_a = np.linalg.norm(a.difference(mid)[1])
        to_b = np.linalg.norm(mid.difference(b)[1])
        total = np.linalg.norm(a.difference(b)[1])
        assert to_a + to_b == pytest.approx(total, abs=1e-9)


@pytest.mark.parametrize(
    "name", ["rbm_nb.core.rigid_transform", "rbm_nb.core.pose_methods"]
)
def test_docstring_examples_run(name):
    import doctest
    import importlib

    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
