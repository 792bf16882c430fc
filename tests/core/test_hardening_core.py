"""Frame-core defects of issue 12 (items 1-5, 12, 13) beyond the bad-input table.

Each test fails before the fix (strict xfail with the issue item) and passes
after it; the single-call cases are rows of ``tests/bad_input_cases.py``.
"""

from __future__ import annotations

import io
from contextlib import redirect_stdout

import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm


def _tree_text() -> str:
    buf = io.StringIO()
    with redirect_stdout(buf):
        out = rbm.render_tree("world")
    return buf.getvalue() + (out or "")


# -- item 1: one sample never reaches the spline kernel ----------------------


@pytest.mark.parametrize(
    "mode",
    ["quaternion", "rotation_vector"],
)
def test_one_sample_angular_velocity_is_refused_every_time(mode):
    """300 calls in the issue gave NaN, -inf, zeros, ZeroDivisionError or 9e13."""
    rng = np.random.default_rng(1)
    for _ in range(30):
        q = rng.normal(size=(1, 4))
        q /= np.linalg.norm(q)
        with pytest.raises(ValueError, match="at least 2 samples"):
            rbm.estimate_angular_velocity(q, timestamps=[rng.normal()], mode=mode)


def test_one_sample_frame_angular_velocity_is_refused():
    rbm.register_frame("world")
    rbm.register_frame(
        "one", parent="world", rotation=np.array([[1.0, 0, 0, 0]]), timestamps=[3.0]
    )
    for call in (rbm.lookup_angular_velocity, rbm.lookup_twist):
        with pytest.raises(ValueError, match="at least 2 samples"):
            call("one", "world")


def test_two_samples_are_enough():
    q = np.array([[1.0, 0, 0, 0], [np.cos(0.05), 0, 0, np.sin(0.05)]])
    w = rbm.estimate_angular_velocity(q, timestamps=[0.0, 1.0])
    np.testing.assert_allclose(w[:, 2], 0.1, rtol=1e-3)


# -- item 2: a failed registry change changes nothing --------------------------


def _abc_tree():
    rbm.register_frame("world")
    rbm.register_frame("a", parent="world", translation=[1.0, 0, 0])
    rbm.register_frame("b", parent="a", translation=[100.0, 0, 5])
    rbm.register_frame("c", parent="a", translation=[0.0, 1, 0])


def test_failed_update_leaves_the_tree_unchanged():
    _abc_tree()
    before_tree = _tree_text()
    old_a = rbm.registry["a"]
    with pytest.raises(ValueError, match="cycle"):
        rbm.register_frame("a", parent="b", translation=[1.0, 0, 0], update=True)
    np.testing.assert_allclose(rbm.lookup_transform("c", "world")[0], [1, 1, 0])
    assert rbm.registry["a"] is old_a
    assert rbm.registry["c"].parent is old_a
    assert sorted(ch.name for ch in old_a.children) == ["b", "c"]
    assert _tree_text() == before_tree


def test_failed_method_update_leaves_the_registry_unchanged():
    """A frame built under ``c`` and registered over ``a`` (c's parent) would
    make a cycle: the registry and every registered frame stay as they were.

    Building ``ReferenceFrame("a", parent="c")`` attaches the new, unregistered
    frame below ``c`` (as in rigid-body-motion); that is the user's frame and
    stays where they put it.
    """
    _abc_tree()
    old_a = rbm.registry["a"]
    parents = {name: frame.parent for name, frame in rbm.registry.items()}
    new_a = rbm.ReferenceFrame("a", parent="c", translation=[7.0, 0, 0])
    with pytest.raises(ValueError, match="cycle"):
        new_a.register(update=True)
    assert rbm.registry["a"] is old_a
    assert {name: frame.parent for name, frame in rbm.registry.items()} == parents
    assert sorted(ch.name for ch in old_a.children) == ["b", "c"]
    np.testing.assert_allclose(rbm.lookup_transform("c", "world")[0], [1, 1, 0])
    np.testing.assert_allclose(rbm.lookup_transform("b", "world")[0], [101, 0, 5])
    assert new_a.parent is rbm.registry["c"]


def test_failed_update_with_bad_arrays_changes_nothing():
    _abc_tree()
    before_tree = _tree_text()
    with pytest.raises(ValueError):
        rbm.register_frame("a", parent="world", translation=[1.0, 0], update=True)
    np.testing.assert_allclose(rbm.lookup_transform("c", "world")[0], [1, 1, 0])
    assert _tree_text() == before_tree


# -- item 3: a time dimension without a coordinate --------------------------


def _moving():
    rbm.register_frame("world")
    rbm.register_frame(
        "m",
        parent="world",
        translation=np.column_stack([np.arange(11.0), np.zeros(11), np.zeros(11)]),
        timestamps=np.arange(11.0),
    )


@pytest.mark.parametrize(
    "func, width",
    [
        (rbm.transform_points, 3),
        (rbm.transform_vectors, 3),
        (rbm.transform_quaternions, 4),
    ],
    ids=["points", "vectors", "quaternions"],
)
def test_time_dimension_without_coordinate_is_refused(func, width):
    _moving()
    values = np.zeros((101, width))
    if width == 4:
        values[:, 0] = 1.0
    axis = "cartesian_axis" if width == 3 else "quaternion_axis"
    da = xr.DataArray(values, dims=("time", axis))
    with pytest.raises(ValueError, match="time"):
        func(da, "world", "m", timestamps="time")


def test_estimators_refuse_a_time_dimension_without_coordinate():
    da = xr.DataArray(np.zeros((5, 3)), dims=("time", "cartesian_axis"))
    with pytest.raises(ValueError):
        rbm.estimate_linear_velocity(da, timestamps="time")


# -- item 4: one rule for quaternion norms --------------------------------------


def _turning(n=6, scale_row=None, scale=1.0):
    a = 0.2 * np.arange(n)
    q = np.column_stack([np.cos(a / 2), np.zeros(n), np.zeros(n), np.sin(a / 2)])
    if scale_row is not None:
        q[scale_row] *= scale
    return q


def _norm_calls(q):
    t = np.arange(float(len(q)))
    rbm.register_frame("world")
    rbm.register_frame("s", parent="world", rotation=[1.0, 0, 0, 0])
    return {
        "ReferenceFrame": lambda: rbm.ReferenceFrame(
            "f", parent="world", rotation=q, timestamps=t
        ),
        "transform_quaternions": lambda: rbm.transform_quaternions(q, "world", "s"),
        "estimate_angular_velocity": lambda: rbm.estimate_angular_velocity(
            q, timestamps=t
        ),
        "qinterp": lambda: rbm.qinterp(q, t, t[:-1] + 0.5),
        "qmean": lambda: rbm.qmean(q),
        "qinv": lambda: rbm.qinv(q),
        "qmul": lambda: rbm.qmul(q, q),
    }


@pytest.mark.parametrize(
    "name",
    [
        "ReferenceFrame",
        "transform_quaternions",
        "estimate_angular_velocity",
        "qinterp",
        "qmean",
    ],
)
def test_far_from_unit_quaternion_is_refused_everywhere(name):
    call = _norm_calls(_turning(scale_row=2, scale=3.0))[name]
    with pytest.raises(ValueError, match=r"\[2\] is of norm 3"):
        call()


@pytest.mark.parametrize(
    "name",
    [
        "ReferenceFrame",
        "transform_quaternions",
        "estimate_angular_velocity",
        "qinterp",
        "qmean",
        "qinv",
        "qmul",
    ],
)
def test_quaternions_stored_to_1e4_are_accepted_everywhere(name):
    """Real recordings store quaternions rounded to 1e-4 (|q| - 1 up to ~8e-5)."""
    q = np.round(_turning(), 4)
    q[3] *= 1 + 8e-5
    out = _norm_calls(q)[name]()
    assert out is not None


# -- item 5: non-finite input, the same clear error everywhere -----------------


def test_non_finite_input_never_returns_nan():
    rbm.register_frame("world")
    rbm.register_frame("s", parent="world", translation=[1.0, 2, 3])
    calls = {
        "transform_points": lambda: rbm.transform_points(
            [[np.inf, 1, 1]], "world", "s"
        ),
        "transform_vectors": lambda: rbm.transform_vectors(
            [[1, -np.inf, 1]], "world", "s"
        ),
        "shortest_arc_rotation": lambda: rbm.shortest_arc_rotation(
            [np.nan, 0, 0], [0, 1, 0]
        ),
        "from_euler_angles": lambda: rbm.from_euler_angles(roll=np.nan),
        "qinterp": lambda: rbm.qinterp(
            np.array([[1.0, 0, 0, 0], [np.inf, 0, 0, 0]]), [0, 1], [0.5]
        ),
    }
    silent = {}
    for name, call in calls.items():
        try:
            out = call()
        except ValueError as err:
            assert "finite" in str(err), f"{name}: {err}"
        else:
            silent[name] = out
    assert not silent, f"returned instead of raising: {silent}"


# -- item 12: 'no sample in the window' is not 'do not overlap' ----------------


def _body_and_short():
    rbm.register_frame("world")
    rbm.register_frame(
        "body",
        parent="world",
        translation=np.zeros((11, 3)),
        timestamps=np.arange(11.0),
    )
    rbm.register_frame(
        "short",
        parent="world",
        translation=np.zeros((3, 3)),
        timestamps=[5.01, 5.05, 5.09],
    )


def test_no_sample_in_window_message():
    _body_and_short()
    with pytest.raises(ValueError) as info:
        rbm.lookup_transform("body", "short")
    message = str(info.value)
    assert "do not overlap" not in message
    assert "body" in message and "short" in message
    assert "5.01" in message and "5.09" in message


def test_truly_disjoint_ranges_still_say_do_not_overlap():
    rbm.register_frame("world")
    rbm.register_frame(
        "early", parent="world", translation=np.zeros((3, 3)), timestamps=[0.0, 1, 2]
    )
    rbm.register_frame(
        "late", parent="world", translation=np.zeros((3, 3)), timestamps=[5.0, 6, 7]
    )
    with pytest.raises(ValueError, match="do not overlap"):
        rbm.lookup_transform("early", "late")


# -- item 13: ICP validates at the door ---------------------------------------


@pytest.mark.parametrize(
    "kwargs, argument",
    [
        (
            {"init_transform": (np.array([np.nan, 0, 0]), np.array([1.0, 0, 0, 0]))},
            "init_transform",
        ),
        (
            {"init_transform": (np.zeros(3), np.array([np.inf, 0, 0, 0]))},
            "init_transform",
        ),
        ({"max_iterations": np.nan}, "max_iterations"),
        ({"max_iterations": np.inf}, "max_iterations"),
    ],
    ids=[
        "init-translation-nan",
        "init-rotation-inf",
        "iterations-nan",
        "iterations-inf",
    ],
)
def test_icp_names_the_bad_argument(kwargs, argument):
    pts = np.random.default_rng(3).normal(size=(30, 3))
    with pytest.raises(ValueError, match=argument):
        rbm.iterative_closest_point(pts, pts + 0.1, **kwargs)
