"""Sampling intervals too small for a velocity's formulas, and angular series
with fewer than two samples without NaN, are refused at the
door, for estimates and for lookups, before the engine runs (issue 32)."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._engine import chain as _chain
from rbm_nb._engine import twist as _twist
from rbm_nb._engine import velocity as _velocity
from rbm_nb.core import estimators as _estimators

STEPS = np.arange(5) * 1e-300


@pytest.fixture
def engine_calls(monkeypatch):
    called = []
    # the engine's functions, where the facades and the engine look them up
    for module, name, attribute in [
        (_velocity, "linear_series", "linear_series"),
        (_velocity, "angular_series", "angular_series"),
        (_estimators, "linear_series", "_linear_series"),
        (_estimators, "angular_series", "_angular_series"),
        (_twist, "lookup_twist", "lookup_twist"),
        (_twist, "lookup_linear_velocity", "lookup_linear_velocity"),
        (_twist, "lookup_angular_velocity", "lookup_angular_velocity"),
    ]:
        original = getattr(module, attribute)
        monkeypatch.setattr(
            module,
            attribute,
            lambda *a, _f=original, _n=name, **k: called.append(_n) or _f(*a, **k),
        )
    rbm.clear_registry()
    rbm.register_frame("world")
    _chain.forget()
    yield called
    rbm.clear_registry()


def test_an_estimate_from_underflowing_intervals_never_reaches_the_engine(
    engine_calls,
):
    x = np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)])
    with pytest.raises(ValueError, match=r"timestamps: samples \d and \d are 1e-300"):
        rbm.estimate_linear_velocity(x, timestamps=STEPS)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (5, 1))
    with pytest.raises(ValueError, match=r"samples \d and \d are 1e-300 s apart"):
        rbm.estimate_angular_velocity(q, timestamps=STEPS)
    assert engine_calls == []
    rbm.estimate_linear_velocity(x, timestamps=np.arange(5.0))
    assert "linear_series" in engine_calls


@pytest.mark.parametrize(
    "lookup", ["lookup_twist", "lookup_linear_velocity", "lookup_angular_velocity"]
)
def test_a_lookup_of_underflowing_intervals_never_reaches_the_engine(
    engine_calls, lookup
):
    rbm.register_frame(
        "fine",
        parent="world",
        timestamps=STEPS,
        translation=np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]),
    )
    with pytest.raises(
        ValueError, match=r"timestamps of 'fine' wrt 'world': samples \d and \d"
    ):
        getattr(rbm, lookup)("fine", "world")
    assert engine_calls == []
    # the same lookup of a frame sampled every 10 ms does reach it
    rbm.register_frame(
        "coarse",
        parent="world",
        timestamps=np.arange(5) * 0.01,
        translation=np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]),
    )
    getattr(rbm, lookup)("coarse", "world")
    assert lookup in engine_calls


def test_an_angular_estimate_with_one_sample_left_never_reaches_the_engine(
    engine_calls,
):
    q = np.tile([1.0, 0.0, 0.0, 0.0], (6, 1))
    q[1:] = np.nan  # one sample without NaN: no spline through it
    with pytest.raises(
        ValueError, match="arr needs at least 2 samples without NaN to estimate"
    ):
        rbm.estimate_angular_velocity(q, timestamps=np.arange(6.0))
    assert engine_calls == []
    q[1] = (1.0, 0.0, 0.0, 0.0)  # two in a row: a velocity there (NaN elsewhere)
    w = rbm.estimate_angular_velocity(q, timestamps=np.arange(6.0))
    assert "angular_series" in engine_calls
    assert not np.isnan(w[:2]).any() and np.isnan(w[2:]).all()
