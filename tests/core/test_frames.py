"""ReferenceFrame: construction, tree queries, the registry and render_tree."""

from __future__ import annotations

import io
from contextlib import redirect_stdout

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.core import frame_samples, frames


@pytest.fixture
def tree():
    """world -> (a -> (c, d -> e), b)"""
    world = rbm.ReferenceFrame("world")
    a = rbm.ReferenceFrame("a", parent=world, translation=(1, 0, 0))
    b = rbm.ReferenceFrame("b", parent=world)
    c = rbm.ReferenceFrame("c", parent=a)
    d = rbm.ReferenceFrame("d", parent=a)
    e = rbm.ReferenceFrame("e", parent=d)
    return world, a, b, c, d, e


def test_tree_queries(tree):
    world, a, b, c, d, e = tree
    assert world.children == (a, b)
    assert e.parent is d and world.parent is None
    assert e.ancestors == (world, a, d)
    assert e.path == (world, a, d, e)
    assert list(e.iter_path_reverse()) == [e, d, a, world]
    assert world.descendants == (a, c, d, e, b)
    assert e.root is world and world.root is world
    assert (world.depth, a.depth, e.depth) == (0, 1, 3)
    assert (world.height, a.height, e.height) == (3, 2, 0)
    assert world.is_root and not a.is_root
    assert e.is_leaf and not d.is_leaf
    assert world.leaves == (c, e, b)
    assert e.leaves == (e,)
    assert c.siblings == (d,) and world.siblings == ()


def test_reparenting_moves_the_subtree(tree):
    world, a, b, c, d, e = tree
    d.parent = b
    assert a.children == (c,) and b.children == (d,)
    assert e.path == (world, b, d, e)
    d.parent = None
    assert d.is_root and b.children == ()


def test_static_frame_arrays_are_stored_read_only():
    world = rbm.ReferenceFrame("world")
    f = rbm.ReferenceFrame("f", parent=world, translation=[1, 2, 3])
    np.testing.assert_array_equal(f.translation, [1, 2, 3])
    np.testing.assert_array_equal(f.rotation, [1, 0, 0, 0])
    assert f.timestamps is None and not f.discrete
    with pytest.raises(ValueError):
        f.translation[0] = 5.0
    assert world.translation is None and world.rotation is None


def test_rotation_within_tolerance_is_kept_and_normalised_inside():
    """Issue 11 item 1: the user's values come back; the math uses unit ones."""
    world = rbm.ReferenceFrame("world")
    q = np.array([1.004, 0.0, 0.0, 0.0])
    f = rbm.ReferenceFrame("f", parent=world, rotation=q)
    np.testing.assert_array_equal(f.rotation, q)
    np.testing.assert_allclose(
        rbm.transform_vectors([[0.0, 3.0, 4.0]], world, f), [[0.0, 3.0, 4.0]]
    )


def test_moving_frame_keeps_timestamps_exactly():
    world = rbm.ReferenceFrame("world")
    ts = np.array(
        ["2020-02-02T00:00:00.000000001", "2020-02-02T00:00:00.005000001"],
        dtype="datetime64[ns]",
    )
    f = rbm.ReferenceFrame(
        "f", parent=world, translation=np.zeros((2, 3)), timestamps=ts
    )
    assert f.timestamps.dtype == ts.dtype
    np.testing.assert_array_equal(f.timestamps, ts)
    np.testing.assert_array_equal(f.rotation, [[1, 0, 0, 0]] * 2)


def test_frames_keep_private_copies_and_hand_out_copies():
    world = rbm.ReferenceFrame("world")
    ts = np.arange(5.0)
    trans = np.zeros((5, 3))
    f = rbm.ReferenceFrame("f", parent=world, translation=trans, timestamps=ts)
    ts[0] = -100.0
    trans[:] = 7.0
    np.testing.assert_array_equal(f.timestamps, np.arange(5.0))
    np.testing.assert_array_equal(f.translation, 0.0)
    _, _, out_ts = f.lookup_transform(world)
    out_ts[:] = 0.0
    np.testing.assert_array_equal(f.timestamps, np.arange(5.0))
    with pytest.raises(ValueError):
        f.timestamps[0] = 1.0


def test_inverse_frame_stores_the_inverted_transform():
    world = rbm.ReferenceFrame("world")
    r = np.array([np.sqrt(0.5), 0, 0, np.sqrt(0.5)])
    f = rbm.ReferenceFrame(
        "f", parent=world, translation=(1, 0, 0), rotation=r, inverse=True
    )
    np.testing.assert_allclose(f.rotation, [np.sqrt(0.5), 0, 0, -np.sqrt(0.5)])
    np.testing.assert_allclose(f.translation, [0, 1, 0], atol=1e-15)
    # f -> world followed by the transform given (world wrt f) is the identity
    t, q = rbm.lookup_transform(f, world)
    p = rbm.rotate_vectors(r, rbm.rotate_vectors(q, np.array([0.3, -2, 5])) + t) + [
        1,
        0,
        0,
    ]
    np.testing.assert_allclose(p, [0.3, -2, 5], atol=1e-12)


def test_from_rotation_matrix():
    world = rbm.ReferenceFrame("world")
    mat = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    f = rbm.ReferenceFrame.from_rotation_matrix(mat, world, name="f")
    np.testing.assert_allclose(
        f.rotation, [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-15
    )
    g = rbm.ReferenceFrame.from_rotation_matrix(mat, world, name="g", inverse=True)
    np.testing.assert_allclose(
        g.rotation, [np.sqrt(0.5), 0, 0, -np.sqrt(0.5)], atol=1e-15
    )


def _dataset(n=20):
    xr = pytest.importorskip("xarray")
    rng = np.random.default_rng(3)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return xr.Dataset(
        {
            "position": (["time", "cartesian_axis"], rng.normal(size=(n, 3))),
            "orientation": (["time", "quaternion_axis"], q),
        },
        {
            "time": np.arange(n) * 0.1,
            "cartesian_axis": ["x", "y", "z"],
            "quaternion_axis": list("wxyz"),
        },
    )


def test_from_dataset_and_dataarrays():
    ds = _dataset()
    rbm.register_frame("world")
    f = rbm.ReferenceFrame.from_dataset(
        ds, "position", "orientation", "time", "world", name="f"
    )
    np.testing.assert_array_equal(f.translation, ds.position.values)
    np.testing.assert_array_equal(f.timestamps, ds.time.values)
    g = rbm.ReferenceFrame.from_translation_dataarray(
        ds.position, "time", "world", name="g"
    )
    np.testing.assert_array_equal(g.translation, ds.position.values)
    np.testing.assert_array_equal(g.rotation[:, 0], 1.0)
    h = rbm.ReferenceFrame.from_rotation_dataarray(
        ds.orientation, "time", "world", name="h", discrete=True
    )
    assert h.discrete
    np.testing.assert_allclose(
        np.abs(np.sum(h.rotation * ds.orientation.values, axis=1)), 1.0
    )


def test_registry_mapping_and_repr():
    rbm.register_frame("world")
    rbm.register_frame("child", parent="world", translation=(0, 1, 0))
    assert list(rbm.registry) == ["world", "child"]
    assert "child" in rbm.registry and len(rbm.registry) == 2
    assert rbm.registry["child"].parent is rbm.registry["world"]
    assert (
        repr(rbm.registry)
        == "{'world': <ReferenceFrame 'world'>, 'child': <ReferenceFrame 'child'>}"
    )
    assert str(rbm.registry["world"]) == "<ReferenceFrame 'world'>"
    rbm.deregister_frame("child")
    assert list(rbm.registry) == ["world"]
    rbm.registry["world"].deregister()
    assert len(rbm.registry) == 0


def test_register_frame_returns_nothing_and_clear_registry_empties():
    assert rbm.register_frame("world") is None
    rbm.clear_registry()
    assert dict(rbm.registry) == {}


def test_update_replaces_frame_and_moves_children():
    rbm.register_frame("world")
    rbm.register_frame("head", parent="world", translation=(1, 0, 0))
    rbm.register_frame("eye", parent="head", translation=(0, 1, 0))
    old = rbm.registry["head"]
    rbm.register_frame("head", parent="world", translation=(2, 0, 0), update=True)
    new = rbm.registry["head"]
    assert new is not old and old.parent is None
    assert rbm.registry["eye"].parent is new
    assert rbm.registry["world"].children == (new,)
    t, _ = rbm.lookup_transform("eye", "world")
    np.testing.assert_allclose(t, [2, 1, 0])


def test_registry_observers():
    events = []
    callback = frames.on_registry_change(
        lambda event, name: events.append((event, name))
    )
    try:
        rbm.register_frame("world")
        rbm.deregister_frame("world")
        rbm.clear_registry()
    finally:
        frames.remove_registry_callback(callback)
    rbm.register_frame("x")
    assert events == [("register", "world"), ("deregister", "world"), ("clear", None)]
    with pytest.raises(ValueError, match="not a registry callback"):
        frames.remove_registry_callback(callback)


def _render(root):
    buf = io.StringIO()
    with redirect_stdout(buf):
        rbm.render_tree(root)
    return buf.getvalue()


def test_render_tree_matches_the_reference_layout(tree):
    expected = "world\n├── a\n│   ├── c\n│   └── d\n│       └── e\n└── b\n"
    assert _render(tree[0]) == expected
    anytree = pytest.importorskip("anytree")
    # the same drawing anytree's RenderTree produces, which the reference prints
    world = anytree.Node("world")
    a = anytree.Node("a", parent=world)
    anytree.Node("c", parent=a)
    d = anytree.Node("d", parent=a)
    anytree.Node("e", parent=d)
    anytree.Node("b", parent=world)
    assert (
        "".join(f"{pre}{node.name}\n" for pre, _, node in anytree.RenderTree(world))
        == expected
    )


def test_render_tree_by_name():
    rbm.register_frame("world")
    rbm.register_frame("only", parent="world")
    assert _render("world") == "world\n└── only\n"


def test_get_transformation_is_a_deprecated_alias():
    world = rbm.ReferenceFrame("world")
    f = rbm.ReferenceFrame("f", parent=world, translation=(1, 2, 3))
    with pytest.warns(DeprecationWarning):
        t, r, ts = f.get_transformation(world)
    np.testing.assert_allclose(t, [1, 2, 3])
    assert ts is None


def test_frame_methods_return_conventions():
    world = rbm.ReferenceFrame("world")
    f = rbm.ReferenceFrame(
        "f",
        parent=world,
        translation=np.arange(12.0).reshape(4, 3),
        timestamps=np.arange(4.0),
    )
    t, r, ts = f.lookup_transform(world)
    assert t.shape == (4, 3) and r.shape == (4, 4)
    np.testing.assert_array_equal(ts, np.arange(4.0))
    out = f.transform_points(np.zeros(3), world)
    np.testing.assert_allclose(out, np.arange(12.0).reshape(4, 3))
    out, ts = f.transform_vectors(np.ones(3), world, return_timestamps=True)
    np.testing.assert_allclose(out, np.ones((4, 3)))
    lin = f.lookup_linear_velocity()
    np.testing.assert_allclose(lin, np.full((4, 3), 3.0))
    lin, ang, ts = f.lookup_twist(return_timestamps=True)
    np.testing.assert_allclose(ang, 0.0, atol=1e-12)
    ang = f.lookup_angular_velocity(world, world)
    np.testing.assert_allclose(ang, 0.0, atol=1e-12)


def test_cached_chains_follow_tree_changes():
    """Resolved chains are cached per pair of frames and forgotten on any change."""
    world = rbm.ReferenceFrame("world")
    a = rbm.ReferenceFrame("a", parent=world, translation=(1.0, 0, 0))
    b = rbm.ReferenceFrame("b", parent=world, translation=(0, 2.0, 0))
    c = rbm.ReferenceFrame("c", parent=a, translation=(0, 0, 3.0))
    origin = np.zeros(3)
    np.testing.assert_allclose(rbm.transform_points(origin, world, c), [1, 0, 3])
    c.parent = b
    np.testing.assert_allclose(rbm.transform_points(origin, world, c), [0, 2, 3])
    t, _ = rbm.lookup_transform(c, world)
    t[0] = 99.0  # the caller owns what it gets; the cache keeps its own
    np.testing.assert_allclose(rbm.lookup_transform(c, world)[0], [0, 2, 3])
    rbm.register_frame("w2")
    rbm.register_frame("moved", parent="w2", translation=(5.0, 0, 0))
    np.testing.assert_allclose(rbm.transform_points(origin, "w2", "moved"), [5, 0, 0])
    rbm.register_frame("moved", parent="w2", translation=(6.0, 0, 0), update=True)
    np.testing.assert_allclose(rbm.transform_points(origin, "w2", "moved"), [6, 0, 0])


@pytest.mark.parametrize("unit", [True, False])
def test_a_moving_frame_keeps_its_own_copies(unit):
    """Changing the arrays a frame was registered with changes nothing."""
    rng = np.random.default_rng(8)
    n = 50
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    if unit:
        q[:] = [[1.0, 0.0, 0.0, 0.0]] * n  # norms exactly 1: nothing to normalise
    t = rng.normal(size=(n, 3))
    ts = np.arange(n) * 0.1
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame("m", parent="world", translation=t, rotation=q, timestamps=ts)
    before = [
        a.copy() for a in rbm.lookup_transform("m", "world", return_timestamps=True)
    ]
    q[:] = [0.0, 0.0, 0.0, 1.0]
    t[:] = 7.0
    ts[:] += 3.0
    after = rbm.lookup_transform("m", "world", return_timestamps=True)
    for a, b in zip(before, after, strict=True):
        np.testing.assert_array_equal(a, b)
    rbm.clear_registry()


def _recording(n, seed):
    """Moving-frame arrays as trackers give them: 4 digits, sign flips, gaps."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q = np.round(q / np.linalg.norm(q, axis=1, keepdims=True), 4)
    q[rng.random(n) < 0.2] *= -1.0
    q[rng.random(n) < 0.05] = np.nan
    t = rng.normal(size=(n, 3))
    t[rng.random(n) < 0.05] = np.nan
    return t, q, np.arange(n) / 200.0


@pytest.mark.parametrize("n", [2, 300, 5000])
@pytest.mark.parametrize("with_translation", [True, False])
def test_one_pass_registration_stores_what_the_checks_one_at_a_time_do(
    monkeypatch, n, with_translation
):
    t, q, ts = _recording(n, n)
    t = t if with_translation else None
    taken = []
    one_pass = frame_samples.moving_samples
    monkeypatch.setattr(
        frame_samples,
        "moving_samples",
        lambda *a: taken.append(one_pass(*a)) or taken[-1],
    )
    fused = rbm.ReferenceFrame("f", parent=rbm.ReferenceFrame("w"), translation=t,
                               rotation=q, timestamps=ts)  # fmt: skip
    assert len(taken) == 1 and taken[0] is not None  # the one-pass route ran
    monkeypatch.setattr(frame_samples, "moving_samples", lambda t, q: None)
    stepwise = rbm.ReferenceFrame("f", parent=rbm.ReferenceFrame("w"), translation=t,
                                  rotation=q, timestamps=ts)  # fmt: skip
    for name in ("t", "r", "rotation"):
        got, want = getattr(fused.data, name), getattr(stepwise.data, name)
        assert got.flags.c_contiguous and got.dtype == np.float64
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
    assert (
        fused.data.missing_rotations
        == stepwise.data.missing_rotations
        == bool(np.isnan(q).any())
    )
    # private copies: changing the caller's arrays changes nothing
    q[:] = 0.0
    np.testing.assert_array_equal(
        fused.rotation.view(np.int64), stepwise.rotation.view(np.int64)
    )


@pytest.mark.parametrize(
    "which, row, value, match",
    [
        ("translation", 7, [np.nan, 0.0, 0.0], r"'f': translation\[7\] is not finite"),
        ("translation", 0, [np.inf, 0.0, 0.0], r"'f': translation\[0\] is not finite"),
        ("rotation", 299, [0.0, np.nan, 0.0, 1.0], r"rotation\[299\] is not finite"),
        (
            "rotation",
            256,
            [0.0, 0.0, 0.0, 0.0],
            r"rotation\[256\] is a zero quaternion",
        ),
        ("rotation", 3, [0.9, 0.0, 0.0, 0.0], r"rotation\[3\] is of norm 0.9"),
    ],
)
def test_one_pass_registration_names_the_bad_row(which, row, value, match):
    t, q, ts = _recording(300, 1)
    (t if which == "translation" else q)[row] = value
    with pytest.raises(ValueError, match=match):
        rbm.ReferenceFrame("f", parent=rbm.ReferenceFrame("w"), translation=t,
                           rotation=q, timestamps=ts)  # fmt: skip
