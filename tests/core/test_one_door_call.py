"""Each facade of the spec calls the door once (issue 32, item 2).

A *door call* is a call from a module of :mod:`rbm_nb.core` into a function
(or a class's constructor) of a module of :mod:`rbm_nb._door`, as
``benchmarks/door_route.py --facades`` counts them: the profiler
(``sys.setprofile``) sees every Python call, its module and its caller's
module. Methods of a value the door returned (``args.result(out)``) are the
facade using that value, not another door call. A facade that unpacks, checks options and wraps its result
with several door helpers makes several such calls; one that hands its
arguments to one door entry (which returns a checked, frozen value) makes
one, whatever the door does inside.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm


def _is_entry(code) -> bool:
    """A door function or a door class's constructor, not a method of a value
    the door returned (``args.result(out)`` uses the clean value it got)."""
    qualname = code.co_qualname
    return "." not in qualname or qualname.endswith(".__init__")


def door_calls(call) -> int:
    """Calls from rbm_nb.core.* into rbm_nb._door.* made while ``call()`` runs."""
    count = 0

    def profile(frame, event, arg):
        nonlocal count
        if event != "call" or frame.f_back is None:
            return
        module = frame.f_globals.get("__name__", "")
        caller = frame.f_back.f_globals.get("__name__", "")
        if (
            module.startswith("rbm_nb._door")
            and caller.startswith("rbm_nb.core.")
            and _is_entry(frame.f_code)
        ):
            count += 1

    sys.setprofile(profile)
    try:
        call()
    finally:
        sys.setprofile(None)
    return count


def _register_moving() -> None:
    rbm.clear_registry()
    rbm.register_frame("world")
    t = np.arange(100) * 0.01
    half = 0.5 * t
    rbm.register_frame(
        "head",
        translation=np.c_[t, np.zeros_like(t), np.ones_like(t)],
        rotation=np.c_[np.cos(half), 0 * t, 0 * t, np.sin(half)],
        timestamps=t,
        parent="world",
    )
    rbm.register_frame(
        "eye", translation=(0.03, 0.1, 0.0), rotation=(1.0, 0, 0, 0), parent="head"
    )


_RNG = np.random.default_rng(0)
_T = np.arange(50) * 0.01
_X = _RNG.normal(size=(50, 3))
_Q = rbm.quaternion_from_euler(_RNG.normal(size=(50, 3)) * 0.1, "xyz")
_POSES = rbm.homogeneous_from_transform(_X[:5], _Q[:5])
_TRANSFORM = rbm.Transform([1.0, 0, 0], [1.0, 0, 0, 0])
_POINTS = xr.DataArray(
    _X,
    {"time": _T},
    ("time", "cartesian_axis"),
    attrs={"coordinate_system": "cartesian"},
)
_QUATERNIONS = xr.DataArray(_Q, {"time": _T}, ("time", "quaternion_axis"))
_DIRECTIONS = xr.DataArray(
    np.tile([0.0, 0.0, 1.0], (50, 1)), dims=("time", "cartesian_axis"),
    coords={"time": _T}, attrs={"representation_frame": "world"},
)  # fmt: skip

# trajectories for ape/rpe: a Dataset and a tuple (the registered "head" too)
_TRAJ = (_T, np.c_[_T, np.sin(_T), _T * _T], _Q)
_TRAJ_DS = xr.Dataset(
    {"position": (("time", "cartesian_axis"), _TRAJ[1] + 0.01 * _X),
     "orientation": (("time", "quaternion_axis"), _Q)},
    coords={"time": _T},
)  # fmt: skip

# (label, call): the calls a user makes most, on plain arrays unless named;
# benchmarks/door_route.py --facades traces the same list
FACADE_CALLS = [
    ("estimate_linear_velocity", lambda: rbm.estimate_linear_velocity(_X, timestamps=_T)),
    ("estimate_linear_velocity cutoff",
     lambda: rbm.estimate_linear_velocity(_X, timestamps=_T, cutoff=0.3)),
    ("estimate_linear_velocity DataArray", lambda: rbm.estimate_linear_velocity(_POINTS)),
    ("estimate_angular_velocity", lambda: rbm.estimate_angular_velocity(_Q, timestamps=_T)),
    ("shortest_arc_rotation", lambda: rbm.shortest_arc_rotation(_X, _X[::-1])),
    ("best_fit_rotation", lambda: rbm.best_fit_rotation(_X, _X[::-1])),
    ("best_fit_transform", lambda: rbm.best_fit_transform(_X, _X + 1)),
    ("iterative_closest_point", lambda: rbm.iterative_closest_point(_X, _X + 0.01)),
    ("quaternion_from_matrix", lambda: rbm.quaternion_from_matrix(np.eye(3))),
    ("matrix_from_quaternion", lambda: rbm.matrix_from_quaternion(_Q)),
    ("quaternion_from_euler", lambda: rbm.quaternion_from_euler(_X, "xyz")),
    ("euler_from_quaternion", lambda: rbm.euler_from_quaternion(_Q, "xyz")),
    ("quaternion_from_axis_angle", lambda: rbm.quaternion_from_axis_angle(_X, _T)),
    ("homogeneous_from_transform", lambda: rbm.homogeneous_from_transform(_X, _Q)),
    ("transform_from_homogeneous", lambda: rbm.transform_from_homogeneous(_POSES)),
    ("se3.skew", lambda: rbm.se3.skew(_X)),
    ("se3.tr2adjoint", lambda: rbm.se3.tr2adjoint(np.eye(4))),
    ("se3.tr2delta", lambda: rbm.se3.tr2delta(_POSES, _POSES)),
    ("se3.trnorm", lambda: rbm.se3.trnorm(_POSES)),
    ("se3.trinterp", lambda: rbm.se3.trinterp(_POSES[0], _POSES[1], 0.5)),
    ("se3.rotvelxform", lambda: rbm.se3.rotvelxform(_X[0])),
    ("se3.rotvelxform matrices", lambda: rbm.se3.rotvelxform(np.eye(3))),
    ("se3.qlog", lambda: rbm.se3.qlog(_Q)),
    ("cartesian_to_spherical", lambda: rbm.cartesian_to_spherical(_X)),
    ("transform_coordinates", lambda: rbm.transform_coordinates(_X, "spherical", "cartesian")),
    ("transform_coordinates DataArray",
     lambda: rbm.transform_coordinates(_POINTS, "spherical")),
    ("qinv", lambda: rbm.qinv(_Q)),
    ("qmul", lambda: rbm.qmul(_Q, _Q)),
    ("qmean", lambda: rbm.qmean(_Q)),
    ("rotate_vectors", lambda: rbm.rotate_vectors(_Q, _X)),
    ("qinterp", lambda: rbm.qinterp(_Q, _T, _T[1:-1] + 0.001)),
    ("qinterp DataArray", lambda: rbm.qinterp(_QUATERNIONS, _T, _T[1:-1] + 0.001)),
    ("qinterp accessor", lambda: _QUATERNIONS.rbm.qinterp(time=_T[1:-1] + 0.001)),
    ("from_euler_angles", lambda: rbm.from_euler_angles(_X)),
    ("Transform.apply", lambda: _TRANSFORM.apply(_X)),
    ("Transform.from_matrix", lambda: rbm.Transform.from_matrix(np.eye(4))),
    ("gaze.angles", lambda: rbm.gaze.angles(_DIRECTIONS, "world")),
    ("transform_points", lambda: rbm.transform_points(_X[:1], "world", "eye")),
    ("transform_vectors", lambda: rbm.transform_vectors(_X, "world", "eye")),
    ("transform_quaternions", lambda: rbm.transform_quaternions(_Q[:1], "world", "eye")),
    ("lookup_transform", lambda: rbm.lookup_transform("eye", "world")),
    ("lookup_transform as_matrix",
     lambda: rbm.lookup_transform("eye", "world", as_matrix=True)),
    ("lookup_transform as_matrix moving",
     lambda: rbm.lookup_transform("head", "world", as_matrix=True)),
    ("lookup_pose", lambda: rbm.lookup_pose("eye", "world")),
    ("lookup_twist", lambda: rbm.lookup_twist("head", "world")),
    ("lookup_linear_velocity", lambda: rbm.lookup_linear_velocity("head", "world")),
    ("lookup_angular_velocity", lambda: rbm.lookup_angular_velocity("head", "world")),
    ("evaluation.ape", lambda: rbm.evaluation.ape(_TRAJ, _TRAJ_DS)),
    ("evaluation.ape sim3 full",
     lambda: rbm.evaluation.ape(_TRAJ, _TRAJ_DS, align=True, correct_scale=True,
                                pose_relation="full")),
    ("evaluation.ape frame",
     lambda: rbm.evaluation.ape("head", _TRAJ_DS, pose_relation="angle_deg")),
    ("evaluation.rpe", lambda: rbm.evaluation.rpe(_TRAJ, _TRAJ_DS, delta=2)),
    ("evaluation.rpe degrees all pairs",
     lambda: rbm.evaluation.rpe("head", _TRAJ, delta=5, delta_unit="degrees",
                                pairs_from_reference=True,
                                all_pairs=True, pose_relation="angle_deg")),
    ("evaluation.umeyama_alignment",
     lambda: rbm.evaluation.umeyama_alignment(_X, _X[::-1], with_scale=True)),
]  # fmt: skip


@pytest.mark.parametrize("label, call", FACADE_CALLS, ids=[c[0] for c in FACADE_CALLS])
def test_each_facade_calls_the_door_once(label, call):
    _register_moving()
    call()  # compile, fill the caches
    assert door_calls(call) == 1, label


def test_the_count_sees_several_door_calls():
    # the counter itself: a core function calling two door helpers counts 2
    from rbm_nb._door import shapes
    from rbm_nb.core import conversions

    def two_calls():
        # run as if from a facade module: exec in its globals
        exec("_s.last_axis([1.0, 2.0, 3.0], 'v', 3); _s.last_axis([1.0], 'v', 1)",
             {**vars(conversions), "_s": shapes})  # fmt: skip

    assert door_calls(two_calls) == 2


@pytest.mark.parametrize(
    "lookup",
    [rbm.lookup_linear_velocity, rbm.lookup_angular_velocity, rbm.lookup_twist],
    ids=["linear", "angular", "twist"],
)
def test_a_static_chain_is_refused_before_the_engine_runs(lookup, monkeypatch):
    # known from the frames alone: the door says so, the engine is not asked
    from rbm_nb._engine import chain, twist

    _register_moving()

    def not_called(*args, **kwargs):
        raise AssertionError("the engine was asked")

    monkeypatch.setattr(twist, "_moving_lookup", not_called)
    monkeypatch.setattr(twist, "_chain_rates", not_called)
    monkeypatch.setattr(chain, "lookup", not_called)
    with pytest.raises(ValueError) as err:
        lookup("eye", "head")
    assert str(err.value) == (
        "the transform between 'eye' and 'head' is static; a velocity needs "
        "timestamps (pass allow_static=True for zeros)"
    )


def test_plot_vectors_with_a_base_calls_the_door_once():
    # (not in FACADE_CALLS: its result is an artist, not arrays to compare)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rbm_nb.core import plot

    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    try:
        for base in (_X[0], _X[:5]):
            plot.vectors(_X[:5], base=base, ax=ax)
            assert door_calls(lambda b=base: plot.vectors(_X[:5], base=b, ax=ax)) == 1
    finally:
        plt.close(fig)


def test_plot_quaternions_with_a_base_calls_the_door_once():
    # (it drew three plot.vectors, each through the door again: 4 calls)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rbm_nb.core import plot

    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    try:
        for base in (None, _X[0], _X[:5]):
            plot.quaternions(_Q[:5], base=base, ax=ax)
            calls = door_calls(lambda b=base: plot.quaternions(_Q[:5], base=b, ax=ax))
            assert calls == 1
    finally:
        plt.close(fig)


def _lazy_calls():
    import dask.array as dsa

    q = dsa.from_array(_Q, chunks=(25, 4))
    qda = xr.DataArray(q, {"time": _T}, ("time", "quaternion_axis"))
    x = dsa.from_array(_X, chunks=(25, 3))
    xda = xr.DataArray(x, {"time": _T}, ("time", "cartesian_axis"))
    return [
        ("qinv dask", lambda: rbm.qinv(q).compute()),
        ("qinv dask DataArray", lambda: rbm.qinv(qda).compute()),
        ("cartesian_to_spherical dask", lambda: rbm.cartesian_to_spherical(x).compute()),
        ("cartesian_to_spherical dask DataArray",
         lambda: rbm.cartesian_to_spherical(xda).compute()),
        ("spherical_to_cartesian dask", lambda: rbm.spherical_to_cartesian(x).compute()),
        ("estimate_linear_velocity dask DataArray",
         lambda: rbm.estimate_linear_velocity(xda).compute()),
        ("estimate_linear_velocity dask cutoff",
         lambda: rbm.estimate_linear_velocity(x, timestamps=_T, cutoff=0.3).compute()),
        ("estimate_angular_velocity dask DataArray",
         lambda: rbm.estimate_angular_velocity(qda).compute()),
    ]  # fmt: skip


_LAZY_IDS = [
    "qinv dask", "qinv dask DataArray", "cartesian_to_spherical dask",
    "cartesian_to_spherical dask DataArray", "spherical_to_cartesian dask",
    "estimate_linear_velocity dask DataArray", "estimate_linear_velocity dask cutoff",
    "estimate_angular_velocity dask DataArray",
]  # fmt: skip


@pytest.mark.parametrize("index", range(len(_LAZY_IDS)), ids=_LAZY_IDS)
def test_a_lazy_call_enters_the_door_once_with_all_its_chunks(index):
    # the chunks come through the door from the door's own block entry,
    # not from the facade again (issue 32, item 2: the dask path starts at
    # the same door); computed inside the count, so each chunk is seen
    label, call = _lazy_calls()[index]
    call()
    assert door_calls(call) == 1, label
