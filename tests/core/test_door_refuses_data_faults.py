"""Faults only the frames' data shows are refused at the door (issue 32, item 2).

No time overlap, no sample of the sampling track inside the overlap, too
few samples for a velocity or its low-pass filter, a static chain's
velocity, a frame without parent as the default reference, a linear
velocity's missing moving or reference frame: the door has the frames
(their first and last keys, their sample counts, the chain), so each call
raises before the engine is asked. Here the engine entry each facade calls
is replaced by one that fails the test if it runs; the messages are those
of ``tests/bad_input_cases.py`` (byte for byte where spelled out here).
"""

from __future__ import annotations

import numpy as np
import pytest
from bad_input_cases import setup_tree

import rbm_nb as rbm
from rbm_nb._engine import transform as engine_transform
from rbm_nb._engine import twist
from rbm_nb.core import estimators, frames, gaze, lookups


def _not_asked(*args, **kwargs):
    raise AssertionError("the engine was asked")


@pytest.fixture
def tree():
    rbm.clear_registry()
    setup_tree()
    yield
    rbm.clear_registry()


NO_SAMPLE = (
    "the time ranges overlap only from 5.01 to 5.09, and none of the 10 samples of "
    "frame 'moving' (which defines the timestamps of the result) falls within it "
    "(the last one before is 5.0; the first one after is 6.0); nothing can be "
    "returned (frame 'moving': 0.0 to 9.0; frame 'short': 5.01 to 5.09)"
)
NO_OVERLAP = (
    "the time ranges do not overlap, so there is no time at which the "
    "transformation and the data are both defined (frame 'moving': 0.0 to 9.0; "
    "array 0: 20.0 to 24.0)"
)
GAZE_NO_OVERLAP = (
    "the time ranges do not overlap, so there is no time at which the "
    "transformation and the data are both defined (frame 'late': 20.0 to 24.0; "
    "frame 'moving': 0.0 to 9.0; array 0: 20.0 to 24.0)"
)
TWO_SAMPLES = "arr needs at least 2 samples to estimate a velocity, got 1"
# the engine's last matching (the array with the looked-up terms) named them
# arrays 0..3: the door's check gives its message unchanged
LEVER = (
    "the time ranges overlap only from 5.01 to 5.09, and none of the 10 samples of "
    "array 0 (which defines the timestamps of the result) falls within it (the last "
    "one before is 5.0; the first one after is 6.0); nothing can be returned (array "
    "0: 0.0 to 9.0; array 1: 0.0 to 9.0; array 2: 0.0 to 9.0; array 3: 5.01 to 5.09)"
)
FILTER = "cutoff: the low-pass filter needs more than 24 samples, got 10"


def _register_late_eye():
    """A head and its eye at 20..24 s, after every sample of 'moving'."""
    q = np.tile([1.0, 0.0, 0.0, 0.0], (5, 1))
    late = np.arange(20.0, 25.0)
    rbm.register_frame(
        "late",
        translation=np.zeros((5, 3)),
        rotation=q,
        timestamps=late,
        parent="world",
    )
    rbm.register_frame("late_eye", rotation=q, timestamps=late, parent="late")


def _frame(name):
    return frames.resolve_frame(name)


# (id, engine module, engine names replaced, call, message)
CASES = [
    ("transform_points no overlap", engine_transform, ["transform"],
     lambda: rbm.transform_points(np.zeros((5, 3)), "world", "moving",
                                  timestamps=np.arange(20.0, 25.0)), NO_OVERLAP),
    ("frame.transform_points no overlap", engine_transform, ["transform"],
     lambda: _frame("world").transform_points(
         np.zeros((5, 3)), "moving", timestamps=np.arange(20.0, 25.0)), NO_OVERLAP),
    ("lookup_transform no sample", lookups._chain, ["lookup_transform"],
     lambda: rbm.lookup_transform("moving", "short"), NO_SAMPLE),
    ("frame.lookup_transform no sample", frames._chain, ["lookup_transform"],
     lambda: _frame("moving").lookup_transform("short"), NO_SAMPLE),
    ("lookup_pose no sample", lookups._chain, ["lookup_transform"],
     lambda: rbm.lookup_pose("moving", "short"), NO_SAMPLE),
    ("lookup_linear_velocity no sample", twist, ["lookup_linear_velocity"],
     lambda: rbm.lookup_linear_velocity("moving", "short"), NO_SAMPLE),
    ("lookup_twist filter", twist, ["lookup_twist"],
     lambda: rbm.lookup_twist("moving", "world", cutoff=0.5), FILTER),
    ("lookup_twist one sample", twist, ["lookup_twist"],
     lambda: rbm.lookup_twist("one", "world"), TWO_SAMPLES),
    ("lookup_angular_velocity one sample", twist, ["lookup_angular_velocity"],
     lambda: rbm.lookup_angular_velocity("one", "world"), TWO_SAMPLES),
    ("frame.lookup_twist filter", twist, ["lookup_twist"],
     lambda: _frame("moving").lookup_twist(cutoff=0.5), FILTER),
    ("frame.lookup_linear_velocity one sample", twist, ["lookup_linear_velocity"],
     lambda: _frame("one").lookup_linear_velocity(), TWO_SAMPLES),
    ("frame.lookup_angular_velocity static", twist, ["lookup_angular_velocity"],
     lambda: _frame("static").lookup_angular_velocity(),
     "the transform between 'static' and 'world' is static; a velocity needs "
     "timestamps (pass allow_static=True for zeros)"),
    ("frame.lookup_linear_velocity no parent", twist, ["lookup_linear_velocity"],
     lambda: _frame("world").lookup_linear_velocity(),
     "frame 'world' has no parent; pass the reference frame explicitly"),
    ("transform_angular_velocity one sample", twist, ["transform_angular_velocity"],
     lambda: rbm.transform_angular_velocity(np.zeros((1, 3)), "world", "one",
                                            timestamps=[0.0]), TWO_SAMPLES),
    ("transform_linear_velocity no moving_frame", twist, ["transform_linear_velocity"],
     lambda: rbm.transform_linear_velocity(np.zeros((10, 3)), "world", "moving",
                                           timestamps=np.arange(10.0)),
     "moving_frame must be given to transform the reference frame of a linear "
     "velocity (its position enters the three-term formula)"),
    ("frame.transform_linear_velocity no reference_frame", twist,
     ["transform_linear_velocity"],
     lambda: _frame("world").transform_linear_velocity(
         np.zeros((10, 3)), "moving", what="moving_frame", timestamps=np.arange(10.0)),
     "reference_frame must be given to transform the moving frame of a linear "
     "velocity (its angular velocity enters the three-term formula)"),
    ("transform_linear_velocity lever no sample", twist, ["transform_linear_velocity"],
     lambda: rbm.transform_linear_velocity(np.zeros((10, 3)), "moving", "world",
                                           timestamps=np.arange(10.0),
                                           moving_frame="short"), LEVER),
    ("transform_angular_velocity no overlap", twist, ["transform_angular_velocity"],
     lambda: rbm.transform_angular_velocity(np.zeros((5, 3)), "moving", "world",
                                            timestamps=np.arange(20.0, 25.0)),
     NO_OVERLAP),
    ("transform_linear_velocity filter of a term", twist, ["transform_linear_velocity"],
     lambda: rbm.transform_linear_velocity(
         np.zeros((10, 3)), "world", "moving", what="moving_frame",
         reference_frame="short", timestamps=np.arange(10.0), cutoff=0.2), FILTER),
    ("estimate_linear_velocity one sample", estimators, ["_linear_series"],
     lambda: rbm.estimate_linear_velocity(np.zeros((1, 3)), timestamps=[0.0]),
     TWO_SAMPLES),
    ("estimate_angular_velocity one sample", estimators, ["_angular_series"],
     lambda: rbm.estimate_angular_velocity(np.array([[1.0, 0, 0, 0]]), timestamps=[0.0]),
     TWO_SAMPLES),
    ("gaze.directions no overlap", gaze._engine_transform, ["transform"],
     lambda: rbm.gaze.directions("late_eye", "moving"), GAZE_NO_OVERLAP),
    ("gaze.angles no overlap", gaze._engine_transform, ["transform"],
     # (the directions in the eye's own head: no engine call)
     lambda: rbm.gaze.angles(rbm.gaze.directions("late_eye", "late"), "moving"),
     GAZE_NO_OVERLAP),
]  # fmt: skip


@pytest.mark.parametrize(
    "module, names, call, message", [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_refused_before_the_engine_runs(
    tree, monkeypatch, module, names, call, message
):
    _register_late_eye()
    for name in names:
        monkeypatch.setattr(module, name, _not_asked)
    with pytest.raises(ValueError) as err:
        call()
    assert str(err.value) == message


def test_one_parent_default_for_velocities_and_trajectory(tree):
    # plot.trajectory and the velocity lookups default the reference to the
    # parent by one rule of the door, with one message
    from rbm_nb.core import plot

    with pytest.raises(ValueError) as traj:
        plot.trajectory("world")
    with pytest.raises(ValueError) as lookup:
        rbm.lookup_twist("world")
    assert str(traj.value) == "trajectory: " + str(lookup.value)
    assert str(lookup.value) == (
        "frame 'world' has no parent; pass the reference frame explicitly"
    )


def test_the_chain_part_kept_with_the_chain_decides_as_the_whole_rule(tree):
    # the door keeps the chain's own span with the cached chain: later
    # calls must decide as the whole rule does, inside and outside the span
    inside = rbm.transform_points(
        np.zeros((3, 3)), "world", "moving", timestamps=[1.0, 2.0, 3.0]
    )
    assert inside.shape == (3, 3)
    with pytest.raises(ValueError) as err:
        rbm.transform_points(
            np.zeros((5, 3)), "world", "moving", timestamps=np.arange(20.0, 25.0)
        )
    assert str(err.value) == NO_OVERLAP
    # 'moving' has no sample within 'short''s span, an array may: twice, so
    # that the second call finds what the first kept
    for _ in range(2):
        out = rbm.transform_points(
            np.zeros((1, 3)), "short", "moving", timestamps=[5.05]
        )
        assert out.shape == (1, 3)
        with pytest.raises(ValueError) as err:
            rbm.lookup_transform("moving", "short")
        assert str(err.value) == NO_SAMPLE
