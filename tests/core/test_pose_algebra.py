"""Transform's pose algebra against scikit-robot's Coordinates (test-only oracle)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rbm_nb.core.rigid_transform import Transform

skrobot_coords = pytest.importorskip("skrobot.coordinates")
Coordinates = skrobot_coords.Coordinates

N = 40
NAMED = ["x", "y", "z", "-x", "-y", "-z", "xy", "yz", "xz", "xyz"]


def random_transforms(n, seed=0):
    rng = np.random.default_rng(seed)
    q = Rotation.random(n, rng=rng).as_quat(scalar_first=True)
    return Transform(rng.normal(size=(n, 3)), q)


def to_skrobot(tf: Transform) -> Coordinates:
    rot = Rotation.from_quat(np.asarray(tf.rotation), scalar_first=True).as_matrix()
    return Coordinates(pos=np.array(tf.translation), rot=rot)


def matrix(tf: Transform) -> np.ndarray:
    return tf.as_matrix()


def assert_same_pose(ours: Transform, theirs: Coordinates, atol=1e-12):
    np.testing.assert_allclose(matrix(ours), theirs.T(), atol=atol)


# -- translate -----------------------------------------------------------------


@pytest.mark.parametrize("wrt", ["local", "world", "parent", "transform"])
def test_translate_matches_skrobot(wrt):
    tfs = random_transforms(N, seed=1)
    others = random_transforms(N, seed=2)
    vecs = np.random.default_rng(3).normal(size=(N, 3))
    ref = others if wrt == "transform" else wrt
    moved = tfs.translate(vecs, wrt=ref)
    assert moved.shape == (N,)
    for i in range(N):
        c = to_skrobot(tfs[i])
        c.translate(vecs[i], wrt=to_skrobot(others[i]) if wrt == "transform" else wrt)
        assert_same_pose(moved[i], c)


def test_translate_broadcasts_one_vector_over_a_batch():
    tfs = random_transforms(5)
    moved = tfs.translate([0.0, 0.0, 1.0])
    np.testing.assert_allclose(
        moved.translation - tfs.translation, tfs.apply_vectors([0.0, 0.0, 1.0])
    )
    np.testing.assert_array_equal(moved.rotation, tfs.rotation)


# -- rotate ---------------------------------------------------------------------


@pytest.mark.parametrize("wrt", ["local", "world", "transform"])
@pytest.mark.parametrize("axis", NAMED + ["vector"])
def test_rotate_matches_skrobot(wrt, axis):
    tfs = random_transforms(N, seed=4)
    others = random_transforms(N, seed=5)
    rng = np.random.default_rng(6)
    angles = rng.uniform(-2 * np.pi, 2 * np.pi, N)
    axes = rng.normal(size=(N, 3)) if axis == "vector" else axis
    ref = others if wrt == "transform" else wrt
    turned = tfs.rotate(angles, axes, wrt=ref)
    for i in range(N):
        c = to_skrobot(tfs[i])
        ax = axes[i] if axis == "vector" else axis
        c.rotate(
            angles[i], ax, wrt=to_skrobot(others[i]) if wrt == "transform" else wrt
        )
        assert_same_pose(turned[i], c)


def test_rotate_docstring_example_of_skrobot():
    # Coordinates().translate([0.1, 0.2, 0.3]).rotate(pi / 2, 'y')
    tf = Transform().translate([0.1, 0.2, 0.3]).rotate(np.pi / 2, "y")
    expected = np.array(
        [
            [0.0, 0.0, 1.0, 0.1],
            [0.0, 1.0, 0.0, 0.2],
            [-1.0, 0.0, 0.0, 0.3],
            [0, 0, 0, 1],
        ]
    )
    np.testing.assert_allclose(tf.as_matrix(), expected, atol=1e-15)


# -- transform_vector / inverse_transform_vector --------------------------------


def test_transform_vectors_match_skrobot_for_a_cloud_and_per_row():
    tfs = random_transforms(N, seed=7)
    pts = np.random.default_rng(8).normal(size=(N, 3))
    c = to_skrobot(tfs[0])
    np.testing.assert_allclose(
        tfs[0].transform_vector(pts), c.transform_vector(pts), atol=1e-12
    )
    np.testing.assert_allclose(
        tfs[0].inverse_transform_vector(pts),
        c.inverse_transform_vector(pts),
        atol=1e-12,
    )
    fwd = tfs.transform_vector(pts)
    back = tfs.inverse_transform_vector(pts)
    for i in range(N):
        c = to_skrobot(tfs[i])
        np.testing.assert_allclose(fwd[i], c.transform_vector(pts[i]), atol=1e-12)
        np.testing.assert_allclose(
            back[i], c.inverse_transform_vector(pts[i]), atol=1e-12
        )


# -- differences ------------------------------------------------------------------

MASKS = [True, False, None, "x", "yz", "xz", "xyz", [1, 0, 1], np.array([0, 1, 0])]


@pytest.mark.parametrize("mask", MASKS, ids=repr)
def test_difference_position_matches_skrobot(mask):
    a, b = random_transforms(N, seed=9), random_transforms(N, seed=10)
    ours = a.difference_position(b, position_mask=mask)
    for i in range(N):
        theirs = to_skrobot(a[i]).difference_position(
            to_skrobot(b[i]), position_mask=mask
        )
        np.testing.assert_allclose(ours[i], theirs, atol=1e-12)


@pytest.mark.parametrize("mirror", [None, "x", "y", "z"])
@pytest.mark.parametrize("mask", MASKS, ids=repr)
def test_difference_rotation_matches_skrobot(mask, mirror):
    a, b = random_transforms(N, seed=11), random_transforms(N, seed=12)
    ours = a.difference_rotation(b, rotation_mask=mask, rotation_mirror=mirror)
    for i in range(N):
        theirs = to_skrobot(a[i]).difference_rotation(
            to_skrobot(b[i]), rotation_mask=mask, rotation_mirror=mirror
        )
        np.testing.assert_allclose(ours[i], theirs, atol=1e-9)


@pytest.mark.parametrize("mirror", ["x", "y", "z"])
def test_difference_rotation_mirror_degenerate_cases_match_skrobot(mirror):
    # equal or exactly half-turned axes: scikit-robot's rule meets a zero
    # cross product, where it always uses the mirrored target
    base = [Transform(), random_transforms(1, seed=13)[0]]
    for a in base:
        for b in (a, a.rotate(np.pi, mirror), Transform().rotate(np.pi, mirror)):
            if b is not a and a is not base[0]:
                continue  # rounding makes skrobot's cross product non-zero
            ours = a.difference_rotation(b, rotation_mirror=mirror)
            theirs = to_skrobot(a).difference_rotation(
                to_skrobot(b), rotation_mirror=mirror
            )
            # at a half turn the rotation vector's sign is a tie: compare rotations
            np.testing.assert_allclose(
                Rotation.from_rotvec(ours).as_matrix(),
                Rotation.from_rotvec(theirs).as_matrix(),
                atol=1e-9,
            )


@pytest.mark.parametrize("mirror", ["x", "y", "z"])
def test_difference_rotation_mirror_forgives_a_half_turn_about_the_axis(mirror):
    a = random_transforms(20, seed=18)
    b = a.rotate(np.pi, mirror)
    np.testing.assert_allclose(
        a.difference_rotation(b, rotation_mirror=mirror), 0, atol=1e-7
    )
    assert np.allclose(
        np.linalg.norm(a.difference_rotation(b), axis=1), np.pi, atol=1e-7
    )


def test_skrobot_docstring_examples_of_differences():
    c1 = Transform().translate([0.1, 0.2, 0.3]).rotate(np.pi / 3, "x")
    c2 = Transform().translate([0.3, -0.3, 0.1]).rotate(np.pi / 2, "y")
    np.testing.assert_allclose(
        c1.difference_position(c2), [0.2, -0.42320508, 0.3330127], atol=1e-8
    )
    rpy = Rotation.from_euler("ZYX", [np.pi / 2, np.pi / 3, np.pi / 5]).as_quat(
        scalar_first=True
    )
    c3 = Transform(rotation=rpy)
    np.testing.assert_allclose(
        Transform().difference_rotation(c3),
        [-0.32855112, 1.17434985, 1.05738936],
        atol=1e-8,
    )
    np.testing.assert_allclose(
        Transform().difference_rotation(c3, rotation_mask="yz"),
        [0.0, 1.17434985, 1.05738936],
        atol=1e-8,
    )


# -- align_axis_to_direction ------------------------------------------------------


@pytest.mark.parametrize("wrt", ["world", "local", "transform"])
@pytest.mark.parametrize("axis", ["x", "y", "z", "-z", "xy", "vector"])
def test_align_axis_to_direction_matches_skrobot(wrt, axis):
    tfs = random_transforms(N, seed=14)
    others = random_transforms(N, seed=15)
    rng = np.random.default_rng(16)
    dirs = rng.normal(size=(N, 3)) * rng.uniform(0.1, 10, (N, 1))
    axes = rng.normal(size=(N, 3)) if axis == "vector" else axis
    ref = others if wrt == "transform" else wrt
    aligned = tfs.align_axis_to_direction(dirs, axis=axes, wrt=ref)
    for i in range(N):
        c = to_skrobot(tfs[i])
        ax = axes[i] if axis == "vector" else axis
        c.align_axis_to_direction(
            dirs[i], axis=ax, wrt=to_skrobot(others[i]) if wrt == "transform" else wrt
        )
        assert_same_pose(aligned[i], c, atol=1e-9)


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_align_axis_parallel_and_antiparallel_match_skrobot(axis):
    e = np.zeros(3)
    e["xyz".index(axis)] = 1.0
    tfs = random_transforms(5, seed=17)
    for i in range(5):
        world_axis = tfs[i].apply_vectors(e)
        for d in (world_axis, -world_axis, e, -e):
            ours = tfs[i].align_axis_to_direction(d, axis=axis)
            c = to_skrobot(tfs[i])
            c.align_axis_to_direction(d, axis=axis)
            assert_same_pose(ours, c, atol=1e-9)
            np.testing.assert_allclose(
                ours.apply_vectors(e), d / np.linalg.norm(d), atol=1e-12
            )


# -- properties --------------------------------------------------------------------

finite = st.floats(-10, 10, allow_nan=False)
vec3 = st.tuples(finite, finite, finite).map(np.array)
quat = (
    st.tuples(finite, finite, finite, finite)
    .filter(lambda q: np.linalg.norm(q) > 1e-2)
    .map(lambda q: np.array(q) / np.linalg.norm(q))
)
poses = st.builds(Transform, vec3, quat)
axes = vec3.filter(lambda v: np.linalg.norm(v) > 1e-2)
angles = st.floats(-3.0, 3.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(poses, vec3)
def test_translate_is_composition(tf, v):
    assert tf.translate(v).allclose(tf @ Transform(v), atol=1e-9)
    assert tf.translate(v, wrt="world").allclose(Transform(v) @ tf, atol=1e-9)
    np.testing.assert_allclose(tf.difference_position(tf.translate(v)), v, atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(poses, angles, axes)
def test_rotate_is_composition_about_the_origin(tf, theta, n):
    turn = Transform.identity().rotate(theta, n)
    assert tf.rotate(theta, n).allclose(tf @ turn, atol=1e-9)
    world = tf.rotate(theta, n, wrt="world")
    np.testing.assert_array_equal(world.translation, tf.translation)
    np.testing.assert_allclose(
        world.rotation,
        (turn @ tf).rotation * np.sign(world.rotation @ (turn @ tf).rotation),
        atol=1e-9,
    )
    rv = tf.difference_rotation(tf.rotate(theta, n))
    np.testing.assert_allclose(rv, theta * n / np.linalg.norm(n), atol=1e-8)


@settings(max_examples=60, deadline=None)
@given(poses, vec3)
def test_inverse_transform_vector_undoes_transform_vector(tf, p):
    np.testing.assert_allclose(
        tf.inverse_transform_vector(tf.transform_vector(p)), p, atol=1e-9
    )


@settings(max_examples=60, deadline=None)
@given(poses, axes, axes)
def test_align_points_the_axis_and_keeps_the_origin(tf, d, ax):
    out = tf.align_axis_to_direction(d, axis=ax)
    np.testing.assert_allclose(
        out.apply_vectors(ax / np.linalg.norm(ax)), d / np.linalg.norm(d), atol=1e-9
    )
    np.testing.assert_array_equal(out.translation, tf.translation)


def test_align_is_exact_next_to_a_half_turn():
    # current axis and target 1e-8 rad from anti-parallel: the arc angle must
    # not come from arccos of a cosine that rounds to -1 (hypothesis found it)
    q = np.array([0.0, 1.0, 0.0, 1e-8]) / np.hypot(1.0, 1e-8)
    d = np.array([0.0, 4.0, 0.5])
    out = Transform([0.0, 0.0, 0.0], q).align_axis_to_direction(d, axis=d)
    u = d / np.linalg.norm(d)
    np.testing.assert_allclose(out.apply_vectors(u), u, rtol=0, atol=1e-14)


# -- bad input -------------------------------------------------------------------------


def test_bad_input_is_refused_with_a_message_naming_the_argument():
    tf = Transform()
    with pytest.raises(ValueError, match="wrt"):
        tf.translate([1, 2, 3], wrt="body")
    with pytest.raises(ValueError, match="axis"):
        tf.rotate(1.0, "w")
    with pytest.raises(ValueError, match="axis"):
        tf.rotate(1.0, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="angle"):
        tf.rotate(np.nan, "x")
    with pytest.raises(ValueError, match="direction"):
        tf.align_axis_to_direction([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="position_mask"):
        tf.difference_position(tf, position_mask="q")
    with pytest.raises(ValueError, match="rotation_mirror"):
        tf.difference_rotation(tf, rotation_mirror="w")
    with pytest.raises(ValueError, match="translation"):
        tf.translate([1.0, np.inf, 0.0])
    with pytest.raises(ValueError, match="broadcast"):
        random_transforms(3).translate(np.zeros((4, 3)))
    with pytest.raises(TypeError, match="Transform"):
        tf.difference_position(np.zeros(3))


def test_methods_return_new_transforms():
    tf = Transform([1.0, 0.0, 0.0])
    before = tf.as_matrix()
    tf.translate([1, 1, 1])
    tf.rotate(1.0, "z")
    tf.align_axis_to_direction([1, 0, 0])
    np.testing.assert_array_equal(tf.as_matrix(), before)
