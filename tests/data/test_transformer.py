"""rbm.ros.Transformer: a tf2-style buffer on rbm_nb's core, no ROS needed."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb.core.frames import ReferenceFrame
from rbm_nb.core.lookups import lookup_at
from rbm_nb.ros.transformer import (
    DEFAULT_CACHE_TIME,
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    Transformer,
)


def quat(seq, angles):
    return Rotation.from_euler(seq, angles).as_quat(scalar_first=True)


def moving(n, t0, t1, seed):
    rng = np.random.default_rng(seed)
    r = Rotation.from_rotvec(np.cumsum(rng.normal(scale=0.1, size=(n, 3)), axis=0))
    return (
        np.linspace(t0, t1, n),
        np.cumsum(rng.normal(size=(n, 3)), 0),
        r.as_quat(scalar_first=True),
    )


@pytest.fixture
def tree():
    """world -> head (moving 0..5 s) -> eye (static); world -> table (static)
    -> cup (moving 1..8 s, given inverse); world -> light (discrete)."""
    world = ReferenceFrame("world")
    ts, t, r = moving(51, 0.0, 5.0, 1)
    head = ReferenceFrame(
        "head", parent=world, translation=t, rotation=r, timestamps=ts
    )
    ReferenceFrame(
        "eye", parent=head, translation=[0.03, 0.0, 0.05], rotation=quat("y", 0.2)
    )
    table = ReferenceFrame(
        "table", parent=world, translation=[1.0, 2.0, 0.7], rotation=quat("z", 1.0)
    )
    ts, t, r = moving(36, 1.0, 8.0, 2)
    ReferenceFrame(
        "cup", parent=table, translation=t, rotation=r, timestamps=ts, inverse=True
    )
    ReferenceFrame(
        "light", parent=world, translation=[[0, 0, 1.0], [0, 0, 2.0]], timestamps=[0.5, 3.0],
        discrete=True,
    )  # fmt: skip
    return world


def frame(world, name):
    return next(f for f in (world,) + world.descendants if f.name == name)


def same_rotation(q1, q2, atol=1e-12):
    q1, q2 = np.asarray(q1), np.asarray(q2)
    return min(np.abs(q1 - q2).max(), np.abs(q1 + q2).max()) <= atol


# ---------------------------------------------------------------------------
# lookups agree with the core
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "target,source,time",
    [
        ("world", "eye", 2.34),
        ("eye", "cup", 4.2),
        ("cup", "light", 1.0),
        ("table", "cup", 7.5),
    ],
)
def test_lookup_matches_core_at_time(tree, target, source, time):
    tf = Transformer.from_reference_frame(tree)
    t, r = tf.lookup_transform(target, source, time)
    assert isinstance(t, tuple) and len(t) == 3 and isinstance(t[0], float)
    assert isinstance(r, tuple) and len(r) == 4 and isinstance(r[0], float)
    ct, cr = lookup_at(frame(tree, source), frame(tree, target), time)
    np.testing.assert_allclose(t, ct, atol=1e-12)
    assert same_rotation(r, cr, 1e-12)


def test_time_zero_is_the_latest_common_time(tree):
    tf = Transformer.from_reference_frame(tree)
    # head ends at 5 s, cup at 8 s: the chain eye -> cup is covered up to 5 s
    t0, r0 = tf.lookup_transform("cup", "eye")
    t5, r5 = tf.lookup_transform("cup", "eye", 5.0)
    assert t0 == t5 and r0 == r5
    # only cup moves on this chain
    assert tf.lookup_transform("world", "cup") == tf.lookup_transform(
        "world", "cup", 8.0
    )
    # static chains need no time at all
    assert tf.lookup_transform("head", "eye", 0.0) == tf.lookup_transform(
        "head", "eye", 123.0
    )
    # discrete frames hold: light's last event counts as the latest time
    assert tf.lookup_transform("world", "light")[0] == (0.0, 0.0, 2.0)
    assert tf.lookup_transform("world", "light", 100.0)[0] == (0.0, 0.0, 2.0)


def test_transform_point_vector_quaternion_pose(tree):
    tf = Transformer.from_reference_frame(tree)
    t, r = tf.lookup_transform("world", "eye", 1.5)
    rot = Rotation.from_quat(r, scalar_first=True)
    p = np.array([0.1, -0.2, 0.3])
    np.testing.assert_allclose(
        tf.transform_point(p, "world", "eye", 1.5), rot.apply(p) + t, atol=1e-12
    )
    np.testing.assert_allclose(
        tf.transform_vector(p, "world", "eye", 1.5), rot.apply(p), atol=1e-12
    )
    q = quat("xyz", [0.1, 0.2, 0.3])
    expected_q = (rot * Rotation.from_quat(q, scalar_first=True)).as_quat(
        scalar_first=True
    )
    assert same_rotation(tf.transform_quaternion(q, "world", "eye", 1.5), expected_q)
    pt, ot = tf.transform_pose(p, q, "world", "eye", 1.5)
    np.testing.assert_allclose(pt, rot.apply(p) + t, atol=1e-12)
    assert same_rotation(ot, expected_q)
    assert all(isinstance(x, tuple) for x in (pt, ot)) and (len(pt), len(ot)) == (3, 4)
    # a round trip through the inverse lookup
    back = tf.transform_point(
        tf.transform_point(p, "cup", "eye", 3.0), "eye", "cup", 3.0
    )
    np.testing.assert_allclose(back, p, atol=1e-12)
    with pytest.raises(ValueError, match="p must have length 3"):
        tf.transform_point([1.0, 2.0], "world", "eye")
    with pytest.raises(ValueError, match="q is of norm 2; rotations must be unit"):
        tf.transform_quaternion([2.0, 0, 0, 0], "world", "eye")


# ---------------------------------------------------------------------------
# failures, tf2 style
# ---------------------------------------------------------------------------


def test_can_transform_and_errors(tree):
    tf = Transformer.from_reference_frame(tree)
    assert tf.can_transform("cup", "eye")
    assert tf.can_transform("cup", "eye", 2.0)
    assert not tf.can_transform("cup", "eye", 6.0)  # head has no data after 5 s
    assert not tf.can_transform("cup", "eye", 0.5)  # cup has none before 1 s
    assert not tf.can_transform("cup", "nose")
    with pytest.raises(
        ExtrapolationError, match=r"'head' has data from 0.0 to 5.0.*6.0.*future"
    ):
        tf.lookup_transform("cup", "eye", 6.0)
    with pytest.raises(ExtrapolationError, match=r"'cup'.*1.0 to 8.0.*0.5.*past"):
        tf.lookup_transform("cup", "eye", 0.5)
    with pytest.raises(
        FrameNotFoundError,
        match=r"source_frame 'ey' does not exist.*did you mean 'eye'",
    ):
        tf.lookup_transform("world", "ey")
    tf.set_transform([0, 0, 0], [1, 0, 0, 0], "map", "odom")
    with pytest.raises(
        ConnectivityError, match=r"'odom' and 'world'.*roots 'map' and 'world'"
    ):
        tf.lookup_transform("world", "odom")
    assert not tf.can_transform("world", "odom")
    with pytest.raises(ValueError, match="non-empty frame name"):
        tf.can_transform("", "odom")
    with pytest.raises(ValueError, match="number of seconds"):
        tf.can_transform("map", "odom", time="now")


def test_empty_buffer():
    tf = Transformer()
    assert tf.cache_time == DEFAULT_CACHE_TIME and tf.frames == ()
    with pytest.raises(FrameNotFoundError, match="the buffer is empty"):
        tf.lookup_transform("a", "b")
    assert "0 frames" in repr(tf)


# ---------------------------------------------------------------------------
# filling the buffer
# ---------------------------------------------------------------------------


def test_set_transform_raw_merge_and_newer_wins():
    tf = Transformer(cache_time=100.0)
    tf.set_transform(
        [[0, 0, 0], [2, 0, 0]], [[1, 0, 0, 0]] * 2, "world", "robot", [0.0, 2.0]
    )
    assert tf.lookup_transform("world", "robot", 1.0)[0] == (1.0, 0.0, 0.0)
    # more samples, out of order, one replacing the sample at t = 2
    tf.set_transform(
        [[4, 0, 0], [3, 0, 0]], [[1, 0, 0, 0]] * 2, "world", "robot", [3.0, 2.0]
    )
    assert tf.lookup_transform("world", "robot", 2.0)[0] == (3.0, 0.0, 0.0)
    assert tf.lookup_transform("world", "robot", 2.5)[0] == (3.5, 0.0, 0.0)
    assert tf.lookup_transform("world", "robot")[0] == (4.0, 0.0, 0.0)
    # a single sample
    tf.set_transform([0, 1, 0], quat("z", 0.5), "robot", "arm", 2.0)
    assert tf.can_transform("world", "arm", 2.0) and not tf.can_transform(
        "world", "arm", 2.5
    )
    # static replaces moving
    tf.set_transform([9, 9, 9], [1, 0, 0, 0], "world", "robot")
    assert tf.lookup_transform("world", "robot", 1e6)[0] == (9.0, 9.0, 9.0)
    with pytest.raises(ValueError, match=r"shapes \(2, 3\) and \(2, 4\)"):
        tf.set_transform([0, 0, 0], [1, 0, 0, 0], "a", "b", [1.0, 2.0])
    with pytest.raises(ValueError, match="rotation is of norm 3"):
        tf.set_transform([0, 0, 0], [3, 0, 0, 0], "a", "b")


def test_cache_time_drops_old_samples():
    tf = Transformer(cache_time=2.0)
    times = np.arange(0.0, 10.0)
    tf.set_transform(
        np.zeros((10, 3)), np.tile([1.0, 0, 0, 0], (10, 1)), "w", "b", times
    )
    assert not tf.can_transform("w", "b", 6.5)
    assert tf.can_transform("w", "b", 7.0) and tf.can_transform("w", "b", 9.0)
    with pytest.raises(ExtrapolationError, match="7.0 to 9.0"):
        tf.lookup_transform("w", "b", 6.0)


def test_changes_rebuild_the_private_tree(tree):
    tf = Transformer.from_reference_frame(tree)
    before = tf.lookup_transform("world", "eye", 2.0)
    tf.lookup_transform("cup", "eye", 2.0)
    head_frame = tf._frame("head")
    # move the head's parent link: everything below must see it
    tf.set_transform([0, 0, 10.0], [1, 0, 0, 0], "world", "head")
    after = tf.lookup_transform("world", "eye", 2.0)
    assert after[0][2] == pytest.approx(10.05) and after != before
    assert head_frame.parent is None  # the old frame left the tree
    tf.lookup_transform("light", "cup", 3.0)
    names = sorted(c.name for c in tf._frame("world").children)
    assert names == ["head", "light", "table"]  # no stale copies
    # the global registry is untouched
    assert "head" not in rbm.registry


def test_cycles_and_bad_frames_are_refused(tree):
    tf = Transformer.from_reference_frame(tree)
    with pytest.raises(ValueError, match="close a loop"):
        tf.set_transform([0, 0, 0], [1, 0, 0, 0], "eye", "world")
    with pytest.raises(ValueError, match="own parent"):
        tf.set_transform([0, 0, 0], [1, 0, 0, 0], "a", "a")
    with pytest.raises(ValueError, match="no parent"):
        tf.set_transform_static(tree)
    with pytest.raises(ValueError, match="moving.*set_transforms"):
        tf.set_transform_static(frame(tree, "head"))
    with pytest.raises(ValueError, match="static.*set_transform_static"):
        tf.set_transforms(frame(tree, "eye"))
    world = ReferenceFrame("w")
    ReferenceFrame(None, parent=world)
    with pytest.raises(ValueError, match="needs a name"):
        Transformer.from_reference_frame(world)
    with pytest.raises(ValueError, match="cache_time must be >= 0"):
        Transformer(cache_time=-1)


def test_from_registered_names_and_datetime64():
    start = np.datetime64("2024-01-01T00:00:00", "ns")
    ts = start + np.arange(5) * np.timedelta64(1, "s")
    rbm.register_frame("world")
    rbm.register_frame(
        "head", parent="world", translation=np.arange(15.0).reshape(5, 3), timestamps=ts
    )
    tf = Transformer.from_reference_frame("head")
    assert tf.frames == ("head", "world")
    epoch = (ts[0] - np.datetime64("1970-01-01T00:00:00", "ns")) / np.timedelta64(
        1, "s"
    )
    t, _ = tf.lookup_transform("world", "head", epoch + 1.5)
    np.testing.assert_allclose(t, [4.5, 5.5, 6.5], atol=1e-6)
    assert tf.lookup_transform("world", "head", ts[2])[0] == (6.0, 7.0, 8.0)
    assert tf.lookup_transform("world", "head")[0] == (12.0, 13.0, 14.0)
    # cache covers the whole recording even beyond the default 10 s
    long = ReferenceFrame("w")
    ReferenceFrame(
        "b", parent=long, translation=np.zeros((2, 3)), timestamps=[0.0, 100.0]
    )
    assert Transformer.from_reference_frame(long).cache_time == 100.0


def test_reference_frames_added_one_by_one(tree):
    tf = Transformer(cache_time=60)
    for node in tree.descendants:
        if node.timestamps is None:
            tf.set_transform_static(node)
        else:
            tf.set_transforms(node)
    full = Transformer.from_reference_frame(tree)
    for target, source in [("world", "eye"), ("cup", "light")]:
        assert tf.lookup_transform(target, source, 2.0) == full.lookup_transform(
            target, source, 2.0
        )
    assert "6 frames" in repr(tf) and "3 moving" in repr(tf)


def test_exported_in_ros_namespace():
    assert rbm.ros.Transformer is Transformer


def test_docstring_examples_run():
    import doctest
    import importlib

    module = importlib.import_module("rbm_nb.ros.transformer")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


# ---------------------------------------------------------------------------
# signs: the numbers the reference returns, not just the same rotations
# ---------------------------------------------------------------------------


def hamilton(p, q):
    """The Hamilton product p * q, written out (w, x, y, z)."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return np.array(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ]
    )


def conj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def kdl_get_quaternion(m):
    """PyKDL's Rotation::GetQuaternion (frames.cpp), returned as w, x, y, z."""
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 1e-12:
        s = 0.5 / np.sqrt(trace + 1.0)
        w, x = 0.25 / s, (m[2, 1] - m[1, 2]) * s
        y, z = (m[0, 2] - m[2, 0]) * s, (m[1, 0] - m[0, 1]) * s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        w, x = (m[2, 1] - m[1, 2]) / s, 0.25 * s
        y, z = (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        w, x = (m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s
        y, z = 0.25 * s, (m[1, 2] + m[2, 1]) / s
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        w, x = (m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s
        y, z = (m[1, 2] + m[2, 1]) / s, 0.25 * s
    return np.array([w, x, y, z])


def _random_quaternions(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)  # both signs of w


def test_transform_quaternion_and_pose_have_the_references_sign():
    """do_transform_pose multiplies KDL frames and reads the matrix back."""
    rng = np.random.default_rng(11)
    flipped_products = 0
    pairs = zip(
        _random_quaternions(rng, 200), _random_quaternions(rng, 200), strict=True
    )
    for r_stored, q in pairs:
        tf = Transformer()
        tf.set_transform([0.1, 0.2, 0.3], r_stored, "a", "b")
        _, r = tf.lookup_transform("a", "b")
        np.testing.assert_allclose(r, r_stored, atol=1e-15)  # tf2 keeps the stored sign
        product = hamilton(r_stored, q)
        m = (
            Rotation.from_quat(r_stored, scalar_first=True).as_matrix()
            @ Rotation.from_quat(q, scalar_first=True).as_matrix()
        )
        expected = kdl_get_quaternion(m)
        out = np.array(tf.transform_quaternion(q, "a", "b"))
        np.testing.assert_allclose(out, expected, atol=1e-12)
        assert min(np.abs(out - product).max(), np.abs(out + product).max()) < 1e-14
        flipped_products += np.abs(out + product).max() < 1e-14
        _, o = tf.transform_pose([1.0, 0.0, 0.0], q, "a", "b")
        np.testing.assert_array_equal(o, out)
    # the grid covers both signs of the algebraic product
    assert 20 < flipped_products < 180


def test_lookup_transform_has_tf2s_composition_sign():
    """Stored quaternions multiplied up the tree, as tf2's TransformAccum does."""
    rng = np.random.default_rng(5)
    q = _random_quaternions(rng, 6)
    times = np.array([1.0, 2.0, 3.0])  # time 0 means "latest" in tf2
    moving_q = _random_quaternions(rng, 3)
    tf = Transformer()
    tf.set_transform([0, 0, 1.0], q[0], "world", "a")
    tf.set_transform([1.0, 0, 0], q[1], "a", "b")
    tf.set_transform(np.zeros((3, 3)), moving_q, "b", "c", time=times)
    tf.set_transform([0, 1.0, 0], q[2], "world", "d")
    tf.set_transform([0, 0, 2.0], q[3], "d", "e")
    for i, when in enumerate(times):
        c_to_world = hamilton(q[0], hamilton(q[1], moving_q[i]))
        cases = {
            ("world", "c"): c_to_world,  # target above source
            ("a", "c"): hamilton(q[1], moving_q[i]),
            ("c", "a"): conj(hamilton(q[1], moving_q[i])),  # source above target
            # full path: conj(target_to_root) * source_to_root
            ("e", "c"): hamilton(conj(hamilton(q[2], q[3])), c_to_world),
            ("c", "e"): hamilton(conj(c_to_world), hamilton(q[2], q[3])),
        }
        for (target, source), expected in cases.items():
            _, r = tf.lookup_transform(target, source, when)
            np.testing.assert_allclose(
                r, expected, atol=1e-12, err_msg=f"{target}<-{source}"
            )
    # between samples: on the hemisphere of the earlier sample
    _, r = tf.lookup_transform("b", "c", 1.5)
    assert np.dot(r, moving_q[0]) > 0
