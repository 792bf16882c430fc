"""Frames of different trees are refused at the door, before the engine
builds their chain (issue 32: the engine checks no argument)."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._engine import chain as _chain


@pytest.fixture
def two_trees(monkeypatch):
    rbm.clear_registry()
    rbm.register_frame("world")
    t = np.arange(20) * 0.1
    rbm.register_frame("head", parent="world", translation=np.c_[t, t, t], timestamps=t)
    rbm.register_frame("eye", parent="head", translation=(0.03, 0.0, 0.0))
    rbm.register_frame("map")
    rbm.register_frame("robot", parent="map", translation=(1.0, 0.0, 0.0))
    built = []
    steps = _chain._steps
    monkeypatch.setattr(
        _chain, "_steps", lambda a, b: built.append((a.name, b.name)) or steps(a, b)
    )
    _chain.forget()
    yield built
    rbm.clear_registry()


CALLS = {
    "lookup_transform": lambda: rbm.lookup_transform("eye", "robot"),
    "lookup_transform at a time": lambda: rbm.lookup_transform(
        "eye", "robot", time=0.5
    ),
    "lookup_pose": lambda: rbm.lookup_pose("eye", "robot"),
    "transform_points (static chain)": lambda: rbm.transform_points(
        np.zeros(3), "robot", "world"
    ),
    "transform_points (moving chain)": lambda: rbm.transform_points(
        np.zeros((20, 3)), "eye", "map", timestamps=np.arange(20) * 0.1
    ),
    "lookup_twist": lambda: rbm.lookup_twist("eye", "robot"),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_frames_of_different_trees_are_refused_at_the_door(two_trees, name):
    with pytest.raises(ValueError, match="different trees"):
        CALLS[name]()
    # the engine never built a chain between the two trees
    assert not any({a, b} & {"map", "robot"} for a, b in two_trees), two_trees


def test_a_connected_pair_still_builds_its_chain_once(two_trees):
    rbm.lookup_transform("eye", "world")
    rbm.lookup_transform("eye", "world")
    assert two_trees.count(("eye", "world")) == 1
