"""The engine owns its data (issue 32, item 3).

A frame hands the engine one immutable value (``ReferenceFrame.data``); the
engine's caches are keyed by those values, so a frame changed after lookups
(a new parent, ``discrete``, ``max_gap``, a name, a replacement registered
with ``update=True``) gives the results of a frame built that way, and the
engine reads no private attribute of a frame.
"""

from __future__ import annotations

import ast
import copy
import pickle
import weakref
from pathlib import Path

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._engine import chain as _chain
from rbm_nb._engine import fused as _fused
from rbm_nb._engine.frame_data import FrameData
from rbm_nb.core import frames as _frames

ENGINE = Path(_chain.__file__).parent
N = 50
TS = np.linspace(0.0, 4.9, N)


@pytest.fixture(autouse=True)
def _clean_registry():
    rbm.clear_registry()
    yield
    rbm.clear_registry()


@pytest.fixture(params=[True, False], ids=["forget", "no-forget"])
def forget(request, monkeypatch):
    """Run each test as is, and with the engine never told to forget: the
    results must not depend on it (the caches are keyed by values)."""
    if not request.param:
        monkeypatch.setattr(_chain, "forget", lambda: None)
    return request.param


def _moving(name, parent, seed, **kwargs):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(N, 4)) * 0.05 + [1.0, 0.0, 0.0, 0.0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return rbm.ReferenceFrame(
        name,
        parent,
        translation=rng.normal(size=(N, 3)),
        rotation=q,
        timestamps=TS,
        **kwargs,
    )


def _same(a, b):
    for x, y in zip(a, b, strict=True):
        if x is None or y is None:
            assert x is None and y is None
        else:
            np.testing.assert_array_equal(x, y)


def test_a_frame_hands_the_engine_one_immutable_value():
    world = rbm.ReferenceFrame("world")
    m = _moving("m", world, 1)
    data = m.data
    assert isinstance(data, FrameData) and data.parent is world.data
    np.testing.assert_array_equal(data.t, m.translation)
    np.testing.assert_array_equal(data.rotation, m.rotation)
    np.testing.assert_array_equal(data.timestamps, m.timestamps)
    for attribute in ("t", "parent", "max_gap", "samples"):
        with pytest.raises(AttributeError, match="immutable"):
            setattr(data, attribute, None)
    with pytest.raises(AttributeError, match="immutable"):
        data.samples.t = None


def test_frames_pickle_and_copy_with_their_value():
    world = rbm.ReferenceFrame("world")
    m = _moving("m", world, 9, max_gap=0.5)
    for copied in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m)):
        assert copied.data is not m.data and copied.max_gap == 0.5
        _same(copied.lookup_transform(copied.parent), m.lookup_transform(world))
    shallow = copy.copy(m)
    assert shallow.data is m.data


def test_reparenting_after_lookups(forget):
    world = rbm.ReferenceFrame("world")
    a = rbm.ReferenceFrame("a", world, translation=[1.0, 0.0, 0.0])
    b = rbm.ReferenceFrame("b", world, translation=[0.0, 5.0, 0.0])
    c = rbm.ReferenceFrame("c", a, translation=[0.0, 0.0, 2.0])
    point = np.array([0.5, 0.5, 0.5])
    assert rbm.transform_points(point, world, c).tolist() == [1.5, 0.5, 2.5]
    before = a.lookup_transform(world)
    a.parent = b  # c is below a: its chain to world changed too
    np.testing.assert_array_equal(
        rbm.transform_points(point, world, c), [1.5, 5.5, 2.5]
    )
    _same(c.lookup_transform(world)[:2], ([1.0, 5.0, 2.0], [1.0, 0.0, 0.0, 0.0]))
    _same(a.lookup_transform(world)[:2], ([1.0, 5.0, 0.0], before[1]))
    # a value handed out before the change still describes the old tree
    assert c.data.parent is a.data and a.data.parent is b.data


def test_moving_chain_reparented_after_lookups(forget):
    world = rbm.ReferenceFrame("world")
    m = _moving("m", world, 2)
    n = _moving("n", world, 3)
    eye = rbm.ReferenceFrame("eye", m, translation=[0.03, 0.0, 0.0])
    points = np.random.default_rng(4).normal(size=(N, 3))
    rbm.transform_points(points, world, eye, timestamps=TS)
    rbm.lookup_twist(eye, world)
    eye.parent = n
    fresh_world = rbm.ReferenceFrame("world")
    fresh_n = _moving("n", fresh_world, 3)
    fresh_eye = rbm.ReferenceFrame("eye", fresh_n, translation=[0.03, 0.0, 0.0])
    _same(
        rbm.transform_points(points, world, eye, timestamps=TS),
        rbm.transform_points(points, fresh_world, fresh_eye, timestamps=TS),
    )
    _same(eye.lookup_transform(world), fresh_eye.lookup_transform(fresh_world))
    _same(rbm.lookup_twist(eye, world), rbm.lookup_twist(fresh_eye, fresh_world))


def test_discrete_set_after_lookups(forget):
    """A frame made discrete after a lookup holds its events from then on."""
    world = rbm.ReferenceFrame("world")
    m = _moving("m", world, 5)
    times = np.linspace(0.1, 4.8, 17)
    interpolated = rbm.lookup_transform(m, world, time=times)
    m.discrete = True
    held = rbm.lookup_transform(m, world, time=times)
    fresh = _moving("m", rbm.ReferenceFrame("world"), 5, discrete=True)
    _same(held, rbm.lookup_transform(fresh, fresh.parent, time=times))
    assert not np.array_equal(held[0], interpolated[0])
    m.discrete = False
    _same(rbm.lookup_transform(m, world, time=times), interpolated)
    static = rbm.ReferenceFrame("s", world)
    with pytest.raises(ValueError, match="discrete=True needs timestamps"):
        static.discrete = True


def test_max_gap_set_after_lookups(forget):
    world = rbm.ReferenceFrame("world")
    m = _moving("m", world, 6)
    times = np.array([0.05, 1.05, 2.3])
    assert not np.isnan(rbm.lookup_transform(m, world, time=times)[0]).any()
    m.max_gap = 0.01  # shorter than every gap: only sample times are defined
    t, r = rbm.lookup_transform(m, world, time=times)
    assert np.isnan(t).all() and np.isnan(r).all()
    m.max_gap = None
    assert not np.isnan(rbm.lookup_transform(m, world, time=times)[0]).any()
    with pytest.raises(ValueError, match="max_gap must be a positive number"):
        m.max_gap = -1.0


def test_renamed_frame_is_named_in_errors(forget):
    world = rbm.ReferenceFrame("world")
    m = rbm.ReferenceFrame("m", world, translation=[1.0, 0.0, 0.0])
    other = rbm.ReferenceFrame("lab")
    with pytest.raises(ValueError, match="frames 'm' and 'lab'"):
        m.lookup_transform(other)
    m.name = "moved"
    assert m.name == "moved" and m.data.name == "moved"
    with pytest.raises(ValueError, match="frames 'moved' and 'lab'"):
        m.lookup_transform(other)


def test_registered_replacement_after_lookups(forget):
    """update=True: the children of the replaced frame see the new data."""
    rbm.register_frame("world")
    rbm.register_frame("head", parent="world", translation=[1.0, 0.0, 0.0])
    rbm.register_frame("eye", parent="head", translation=[0.0, 0.1, 0.0])
    assert rbm.lookup_transform("eye", "world")[0].tolist() == [1.0, 0.1, 0.0]
    rbm.register_frame("head", parent="world", translation=[2.0, 0.0, 0.0], update=True)
    assert rbm.lookup_transform("eye", "world")[0].tolist() == [2.0, 0.1, 0.0]
    rbm.register_frame(
        "head",
        parent="world",
        translation=np.tile([3.0, 0.0, 0.0], (N, 1)),
        timestamps=TS,
        update=True,
    )
    t, _, ts = rbm.lookup_transform("eye", "world", return_timestamps=True)
    np.testing.assert_array_equal(t, np.tile([3.0, 0.1, 0.0], (N, 1)))
    np.testing.assert_array_equal(ts, TS)


def test_a_squad_table_stays_with_the_samples():
    """Tables are keyed by a frame's samples, which survive a new parent."""
    world = rbm.ReferenceFrame("world")
    lab = rbm.ReferenceFrame("lab", world, translation=[1.0, 0.0, 0.0])
    m = _moving("m", world, 7)
    rbm.lookup_transform(m, world, time=np.array([1.01, 2.02]))
    table = _fused._TABLES[m.data.samples]
    assert table.rows[:, -1].any()
    m.parent = lab
    rbm.lookup_transform(m, world, time=np.array([1.01]))
    assert _fused._TABLES[m.data.samples] is table
    # and goes with them: the frame detached and dropped, nothing holds them
    samples, tables = weakref.ref(m.data.samples), len(_fused._TABLES)
    m.parent = None
    del m, table
    assert samples() is None and len(_fused._TABLES) == tables - 1


def _private_frame_attributes() -> set[str]:
    world = rbm.ReferenceFrame("world")
    frame = _moving("m", world, 8)
    return {name for name in vars(frame) if name.startswith("_")} | {"__dict__"}


def test_the_engine_reads_no_private_attribute_of_a_frame():
    private = _private_frame_attributes()
    private |= {
        name
        for name, value in vars(_frames.ReferenceFrame).items()
        if name.startswith("_") and not name.startswith("__")
    }
    assert "_data" in private
    found = []
    for path in sorted(ENGINE.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and node.attr in private:
                found.append(f"{path.name}:{node.lineno} .{node.attr}")
    assert found == []
