"""A result is missing only where a sample it needs is missing (issue 28).

The rule, checked on every route of the frame core against a naive twin:

- at a frame's own timestamps its own sample comes back, whatever its
  neighbours (NaN only where that sample is the missing one);
- between two present samples the result is finite: each run of samples
  between missing ones is interpolated as a recording of its own would be
  (numpy-quaternion's squad on the run alone: the end rule for the control
  points next to a missing sample), and linearly for translations;
- between a present and a missing sample, or across a gap longer than
  ``max_gap``, the result is NaN;
- velocities are NaN where the sample is missing or has no present
  neighbour (a derivative needs two samples), nowhere else.

The twin (:func:`expected_pose`) works sample by sample with numpy and
numpy-quaternion; the routes are the own-times lookup, the fused chain
kernels (serial and their prange twins), the step-by-step path (chains of
more moving frames than the fused kernels take), point-in-time lookups,
dask-backed arrays, ``qinterp`` and its three walk kernels, velocities and
``gaze.directions``. Runs of missing samples of length 1, 2 and 3 and at
both ends of the recording are in every series.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm
from rbm_nb._engine import fused as _fused
from rbm_nb._infra import parallel as _parallel
from rbm_nb._kernels import fused as kf
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import squad_walk as ksw
from rbm_nb.core import frames as _frames
from rbm_nb.core.lookups import lookup_at

naive = pytest.importorskip("naive")
quaternion = pytest.importorskip("quaternion")

# runs of missing samples: at the start (1), of length 1, 2, 3, one that
# leaves a single present sample between two missing ones, and at the end (2)
MISSING = [0, 5, 10, 11, 17, 18, 19, 25, 27, 38, 39]
N = 40


def _rotations(t: np.ndarray) -> np.ndarray:
    """Unit quaternions turning about a slowly changing axis, at a changing
    rate (so that squad differs from slerp by far more than rounding)."""
    angle = 0.9 * t + 0.35 * np.sin(1.7 * t)
    axis = np.column_stack([np.sin(0.3 * t), np.cos(0.3 * t), 0.4 + 0 * t])
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    return np.column_stack([np.cos(angle / 2), np.sin(angle / 2)[:, None] * axis])


def series(n: int = N, missing=MISSING, flip: int | None = 21, seed: int = 0):
    """(t, translation, rotation) at irregular times, NaN rows at ``missing``,
    and one stored sign flip (``flip``) that interpolation must undo."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.05, 0.15, n))
    translation = np.column_stack([np.sin(t), np.cos(2 * t), 0.3 * t])
    rotation = _rotations(t)
    if flip is not None:
        rotation[flip] *= -1.0
    translation[missing] = np.nan
    rotation[missing] = np.nan
    return t, translation, rotation


def _runs(valid: np.ndarray):
    """(first, last) of each run of consecutive True, inclusive."""
    edges = np.diff(np.concatenate([[0], valid.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return list(zip(starts, ends, strict=True))


def expected_pose(t, translation, rotation, query, max_gap=math.inf):
    """The rule, sample by sample: (translation (m, 3), rotation (m, 4))."""
    m = len(query)
    out_t = np.full((m, 3), np.nan)
    out_r = np.full((m, 4), np.nan)
    valid_t = ~np.isnan(translation).any(axis=1)
    valid_r = ~np.isnan(rotation).any(axis=1)
    run_of = np.full(len(t), -1)
    runs = _runs(valid_r)
    for k, (a, b) in enumerate(runs):
        run_of[a : b + 1] = k
    for j, tau in enumerate(query):
        i = int(np.searchsorted(t, tau, side="right")) - 1
        if t[i] == tau:
            out_t[j], out_r[j] = translation[i], rotation[i]
            continue
        if t[i + 1] - t[i] > max_gap:
            continue
        if valid_t[i] and valid_t[i + 1]:
            w = (tau - t[i]) / (t[i + 1] - t[i])
            out_t[j] = translation[i] + w * (translation[i + 1] - translation[i])
        if valid_r[i] and valid_r[i + 1]:
            a, b = runs[run_of[i]]
            out_r[j] = naive.squad(
                naive.unflip(rotation[a : b + 1]), t[a : b + 1], np.array([tau])
            )[0]
    return out_t, out_r


def query_times(t: np.ndarray, seed: int = 1) -> np.ndarray:
    """Every sample time, every midpoint and random times in between, sorted."""
    rng = np.random.default_rng(seed)
    mid = 0.5 * (t[:-1] + t[1:])
    inside = rng.uniform(t[0], t[-1], 3 * len(t))
    return np.unique(np.concatenate([t, mid, inside]))


def assert_rotations(got, expected, atol=1e-12, where=""):
    """Same NaN rows; the same rotations elsewhere (q and -q alike)."""
    got = np.asarray(got, dtype=float)
    missing = np.isnan(expected).any(axis=1)
    np.testing.assert_array_equal(np.isnan(got).any(axis=1), missing, err_msg=where)
    g, e = got[~missing], expected[~missing]
    sign = np.where(np.sum(g * e, axis=1) < 0.0, -1.0, 1.0)[:, None]
    np.testing.assert_allclose(g * sign, e, rtol=0, atol=atol, err_msg=where)


def assert_rows(got, expected, atol=1e-12, where=""):
    got = np.asarray(got, dtype=float)
    missing = np.isnan(expected).any(axis=1)
    np.testing.assert_array_equal(np.isnan(got).any(axis=1), missing, err_msg=where)
    np.testing.assert_allclose(
        got[~missing], expected[~missing], rtol=0, atol=atol, err_msg=where
    )


def _register(name="f", parent="world", data=None, **kwargs):
    t, translation, rotation = series() if data is None else data
    if parent not in _frames.registry:
        rbm.register_frame(parent)
    rbm.register_frame(
        name,
        parent=parent,
        timestamps=t,
        translation=translation,
        rotation=rotation,
        **kwargs,
    )
    return t, translation, rotation


def _identity_frame(name, parent, t):
    """A moving frame that does nothing (so a chain through it gives f)."""
    n = len(t)
    rbm.register_frame(
        name,
        parent=parent,
        timestamps=t,
        translation=np.zeros((n, 3)),
        rotation=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
    )


# -- the twin itself -------------------------------------------------------------


def test_the_twin_has_teeth():
    """On this series the rule's answer differs from the reference's (NaN
    around every missing sample) and from slerp (squad's control points)."""
    t, translation, rotation = series()
    q = query_times(t)
    _, rot = expected_pose(t, translation, rotation, q)
    # rows within one sample of a missing one are finite between two present
    # samples: e.g. half-way between samples 1 and 2 (sample 0 is missing)
    assert np.isfinite(rot[np.searchsorted(q, 0.5 * (t[1] + t[2]))]).all()
    # squad is not slerp here: the control points matter
    mid = 0.5 * (t[13] + t[14])
    slerp = naive.slerp(
        naive.unflip(rotation[12:16])[1:2],
        naive.unflip(rotation[12:16])[2:3],
        np.array([0.5]),
    )[0]
    got = rot[np.searchsorted(q, mid)]
    assert min(np.abs(got - slerp).max(), np.abs(got + slerp).max()) > 1e-6


# -- own times -------------------------------------------------------------------


def test_own_times_give_each_sample_itself():
    t, translation, rotation = _register()
    got_t, got_r = rbm.lookup_transform("f", "world")
    np.testing.assert_array_equal(got_t, translation)
    np.testing.assert_array_equal(got_r, rotation)


def test_own_times_through_an_interpolated_parent():
    """The fused kernels' own-times rule: f at its own times below a moving
    frame sampled on another clock."""
    t, translation, rotation = series()
    rbm.register_frame("world")
    _identity_frame("p", "world", np.linspace(t[0] - 1, t[-1] + 1, 57))
    _register("f", parent="p", data=(t, translation, rotation))
    for where, (got_t, got_r) in {
        "lookup_transform": rbm.lookup_transform("f", "world"),
        "lookup_transform(time=own)": rbm.lookup_transform("f", "world", time=t),
    }.items():
        exp_t, exp_r = expected_pose(t, translation, rotation, t)
        assert_rows(got_t, exp_t, where=where)
        assert_rotations(got_r, exp_r, where=where)
    points = rbm.transform_points(
        np.zeros((N, 3)), outof="f", into="world", timestamps=t
    )
    assert_rows(points, expected_pose(t, translation, rotation, t)[0])


# -- between samples: fused, step-by-step, point in time --------------------------


@pytest.mark.parametrize("max_gap", [None, 0.12])
def test_fused_chain_between_samples(max_gap):
    t, translation, rotation = _register(max_gap=max_gap)
    q = query_times(t)
    exp_t, exp_r = expected_pose(
        t, translation, rotation, q, math.inf if max_gap is None else max_gap
    )
    if max_gap is not None:
        assert (
            np.isnan(exp_r).any(axis=1).sum()
            > np.isnan(expected_pose(t, translation, rotation, q)[1]).any(axis=1).sum()
        )  # the gap rule has teeth
    points = rbm.transform_points(
        np.zeros((len(q), 3)), outof="f", into="world", timestamps=q
    )
    assert_rows(points, exp_t, where="transform_points")
    quats = rbm.transform_quaternions(
        np.tile([1.0, 0.0, 0.0, 0.0], (len(q), 1)),
        outof="f",
        into="world",
        timestamps=q,
    )
    assert_rotations(quats, exp_r, where="transform_quaternions")
    vectors = rbm.transform_vectors(
        np.tile([0.0, 0.0, 1.0], (len(q), 1)), outof="f", into="world", timestamps=q
    )
    sight = np.full((len(q), 3), np.nan)
    ok = ~np.isnan(exp_r).any(axis=1)
    sight[ok] = naive.rotate_vectors(
        naive.qnormalize(exp_r[ok]), np.array([[0, 0, 1.0]])
    )
    assert_rows(vectors, sight, where="transform_vectors")


def test_point_in_time_lookups():
    t, translation, rotation = _register()
    q = query_times(t)
    exp_t, exp_r = expected_pose(t, translation, rotation, q)
    got_t, got_r = rbm.lookup_transform("f", "world", time=q)
    assert_rows(got_t, exp_t, where="lookup_transform(time=array)")
    assert_rotations(got_r, exp_r, where="lookup_transform(time=array)")
    for j in range(0, len(q), 7):  # one time per call: the small-call door
        one_t, one_r = rbm.lookup_transform("f", "world", time=q[j])
        assert_rows(one_t[None], exp_t[j : j + 1], where=f"time={q[j]}")
        assert_rotations(one_r[None], exp_r[j : j + 1], where=f"time={q[j]}")
    at = lookup_at("f", "world", q[::5])
    assert_rows(np.asarray(at[0]), exp_t[::5], where="lookup_at")
    assert_rotations(np.asarray(at[1]), exp_r[::5], where="lookup_at")


def test_the_transformer():
    """The tf2-style buffer: a frame's samples set with set_transforms."""
    from rbm_nb.ros import Transformer

    t, translation, rotation = _register()
    buffer = Transformer()
    buffer.set_transforms("f")
    q = query_times(t)[::3]
    exp_t, exp_r = expected_pose(t, translation, rotation, q)
    got_t = np.empty((len(q), 3))
    got_r = np.empty((len(q), 4))
    for j, time in enumerate(q):
        got_t[j], got_r[j] = buffer.lookup_transform("world", "f", float(time))
    assert_rows(got_t, exp_t, where="Transformer.lookup_transform")
    assert_rotations(got_r, exp_r, where="Transformer.lookup_transform")


def test_step_by_step_chain():
    """Four moving frames: more than the fused kernels' slots, so each frame
    is resampled on its own (``chain.resample_frame``, ``squad_evaluate``)."""
    assert kf.SLOTS < 4
    t, translation, rotation = series()
    rbm.register_frame("world")
    clock = np.linspace(t[0] - 1, t[-1] + 1, 61)
    _identity_frame("a", "world", clock)
    _identity_frame("b", "a", clock)
    _identity_frame("c", "b", clock)
    _register("f", parent="c", data=(t, translation, rotation))
    q = query_times(t)
    exp_t, exp_r = expected_pose(t, translation, rotation, q)
    got_t, got_r = rbm.lookup_transform("f", "world", time=q)
    assert_rows(got_t, exp_t, where="step-by-step lookup")
    assert_rotations(got_r, exp_r, where="step-by-step lookup")


def test_the_step_by_step_kernels_directly():
    t, _, rotation = series()
    q = query_times(t)
    _, exp_r = expected_pose(t, np.zeros((N, 3)), rotation, q)
    r = kq.unflip(rotation)
    assert_rotations(kq.squad(r, t, q), exp_r, where="quaternion.squad")


# -- the prange twins -------------------------------------------------------------


@pytest.mark.skipif(
    numba.config.NUMBA_NUM_THREADS < 2,  # type: ignore[attr-defined]
    reason="numba has a single thread here",
)
def test_parallel_twins(monkeypatch, ignore_load):
    """Long calls through the prange twins: the serial kernel's bits, and
    the rule (the missing pattern repeated over 600 samples)."""
    n = 600
    missing = [k + 40 * p for p in range(n // 40) for k in MISSING]
    data = series(n=n, missing=missing, flip=None, seed=3)
    t, translation, rotation = _register(data=data)
    q = query_times(t, seed=4)
    exp_t, exp_r = expected_pose(t, translation, rotation, q)
    calls = []
    twin = kf.transform_chain_parallel

    def spy(*args):
        calls.append(numba.get_num_threads())
        return twin(*args)

    monkeypatch.setattr(kf, "transform_chain_parallel", spy)
    results = []
    for threads, min_rows in (("1", 10**12), ("2", 1)):
        table = _fused._TABLES.get(_frames.registry["f"].data.samples)
        if table is not None:
            table.clear()  # each mode fills the table itself
        monkeypatch.setenv(_parallel.ENV_THREADS, threads)
        monkeypatch.setattr(_parallel, "MIN_ROWS", min_rows)
        results.append(
            rbm.transform_quaternions(
                np.tile([1.0, 0.0, 0.0, 0.0], (len(q), 1)),
                outof="f",
                into="world",
                timestamps=q,
            )
        )
    assert calls and all(c == 2 for c in calls), calls
    np.testing.assert_array_equal(results[0].view(np.int64), results[1].view(np.int64))
    assert_rotations(results[1], exp_r, where="transform_chain_parallel")


# -- dask -------------------------------------------------------------------------


def test_dask_backed_arrays():
    pytest.importorskip("dask")
    t, translation, rotation = _register()
    q = query_times(t)
    exp_t, _ = expected_pose(t, translation, rotation, q)
    points = xr.DataArray(
        np.zeros((len(q), 3)),
        dims=("time", "cartesian_axis"),
        coords={"time": q},
    )
    lazy = rbm.transform_points(
        points.chunk(time=23), outof="f", into="world", dim="cartesian_axis"
    )
    assert lazy.chunks is not None  # still lazy
    assert_rows(lazy.values, exp_t, where="dask transform_points")


# -- qinterp and its walk kernels -------------------------------------------------


def test_qinterp_and_the_walk_kernels():
    t, _, rotation = series()
    q = query_times(t)
    _, exp_r = expected_pose(t, np.zeros((N, 3)), rotation, q)
    assert_rotations(rbm.qinterp(rotation, t, q), exp_r, where="qinterp")
    for kernel in (ksw.squad_walk, ksw.squad_walk_scalar, ksw.squad_walk_parallel):
        got = kernel(rotation, t, q)
        assert_rotations(got, exp_r, where=kernel.__name__)
    # unsorted times take the walk's sparse route
    order = np.random.default_rng(5).permutation(len(q))
    got = ksw.squad_walk(rotation, t, q[order])
    assert_rotations(got, exp_r[order], where="squad_walk, unsorted")


def test_segments_with_all_four_samples_are_unchanged():
    """Where samples i-1 .. i+2 are present the curve is the complete
    series' bit for bit, so squad's C¹ continuity holds there."""
    t, _, rotation = series()
    complete = _rotations(t)
    complete[21] *= -1.0
    q = query_times(t)
    seg = np.searchsorted(t, q, side="right") - 1
    present = ~np.isnan(rotation).any(axis=1)
    four = np.array(
        [
            1 <= i <= N - 3 and present[i - 1 : i + 3].all() and q[j] != t[i]
            for j, i in enumerate(seg)
        ]
    )
    assert four.sum() > 50
    for kernel in (ksw.squad_walk, lambda r, a, b: kq.squad(kq.unflip(r), a, b)):
        a = kernel(rotation, t, q)[four]
        b = kernel(complete, t, q)[four]
        sign = np.where(np.sum(a * b, axis=1) < 0, -1.0, 1.0)[:, None]
        np.testing.assert_array_equal(a * sign, b)


# -- velocities ---------------------------------------------------------------------


def _alone(valid: np.ndarray) -> np.ndarray:
    paired = np.zeros_like(valid)
    paired[1:] |= valid[:-1]
    paired[:-1] |= valid[1:]
    return valid & ~paired


@pytest.mark.parametrize("mode", ["quaternion", "rotation_vector"])
def test_velocities_are_missing_only_without_two_samples(mode):
    t, translation, rotation = _register()
    missing = np.isnan(rotation).any(axis=1)
    no_velocity = missing | _alone(~missing)
    assert _alone(~missing).any()  # sample 26 stands alone
    angular = rbm.lookup_angular_velocity("f", "world", mode=mode)
    np.testing.assert_array_equal(np.isnan(angular).any(axis=1), no_velocity)
    linear, angular = rbm.lookup_twist("f", "world", mode=mode)
    np.testing.assert_array_equal(np.isnan(linear).any(axis=1), no_velocity)
    np.testing.assert_array_equal(np.isnan(angular).any(axis=1), no_velocity)


def test_transformed_velocities_are_missing_only_without_two_samples():
    """Changing the reference frame to one with missing samples adds its
    velocity terms, which are missing only where they are."""
    t, translation, rotation = _register()
    rbm.register_frame("c", parent="f", translation=(0.1, 0.0, 0.0))
    missing = np.isnan(rotation).any(axis=1)
    no_velocity = missing | _alone(~missing)
    zeros = np.zeros((N, 3))
    angular = rbm.transform_angular_velocity(
        zeros, into="world", outof="f", what="reference_frame", timestamps=t
    )
    np.testing.assert_array_equal(np.isnan(angular).any(axis=1), no_velocity)
    linear = rbm.transform_linear_velocity(
        zeros,
        into="world",
        outof="f",
        what="reference_frame",
        moving_frame="c",
        timestamps=t,
    )
    np.testing.assert_array_equal(np.isnan(linear).any(axis=1), no_velocity)


# -- the real recording -------------------------------------------------------------


@pytest.fixture(scope="module")
def real(shared_data):
    folder = shared_data / "rbm-data"
    return tuple(
        xr.load_dataset(folder / f"{n}.nc") for n in ("head", "left_eye", "right_eye")
    )


def _register_real(head, left, right):
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_dataset(
        head, "position", "orientation", "time", parent="world", name="head"
    ).register()
    rbm.register_frame(
        "scene_cam",
        parent="head",
        translation=(0.0, 0.05, 0.08),
        rotation=(0.5, -0.5, 0.5, -0.5),
    )
    for name, eye in (("left_eye", left), ("right_eye", right)):
        rbm.ReferenceFrame.from_dataset(
            eye, "position", "orientation", "time", parent="scene_cam", name=name
        ).register()


@pytest.mark.parametrize("eye, raw", [("left_eye", 0.325), ("right_eye", 0.311)])
def test_real_eyes_lose_only_their_missing_samples(real, eye, raw):
    head, left, right = real
    _register_real(head, left, right)
    ds = {"left_eye": left, "right_eye": right}[eye]
    own = ds.orientation.values
    missing = np.isnan(own).any(axis=1)
    # (the file's positions are missing on a subset of those rows: a
    # translation is missing where its own sample is, independently)
    missing_position = np.isnan(ds.position.values).any(axis=1)
    assert missing.mean() == pytest.approx(raw, abs=5e-4)
    assert not (missing_position & ~missing).any()
    for into in ("scene_cam", "world"):
        # (eye -> world: the eye's times within the head's, 3 fewer)
        tr, rot, times = rbm.lookup_transform(eye, into, return_timestamps=True)
        rows = np.searchsorted(ds.time.values, times)
        assert len(rows) >= len(own) - 3
        np.testing.assert_array_equal(np.isnan(rot).any(axis=1), missing[rows])
        np.testing.assert_array_equal(np.isnan(tr).any(axis=1), missing_position[rows])
    sight, times = rbm.transform_vectors(
        np.tile([0.0, 0.0, 1.0], (len(own), 1)),
        outof=eye,
        into="world",
        timestamps=ds.time.values,
        return_timestamps=True,
    )
    rows = np.searchsorted(ds.time.values, times)
    np.testing.assert_array_equal(np.isnan(sight).any(axis=1), missing[rows])
    # a present sample comes back as itself
    _, rot = rbm.lookup_transform(eye, "scene_cam")
    a = rot[~missing] / np.linalg.norm(rot[~missing], axis=1)[:, None]
    b = own[~missing] / np.linalg.norm(own[~missing], axis=1)[:, None]
    assert (np.abs(np.sum(a * b, axis=1)) > 1 - 1e-12).all()


def test_real_half_way_between_samples_whose_neighbours_are_missing(real):
    head, left, right = real
    _register_real(head, left, right)
    q = left.orientation.values
    t = left.time.values
    present = ~np.isnan(q).any(axis=1)
    # i, i+1 present and i-1, i+2 missing: the reference gives NaN here
    i = np.flatnonzero(present[1:-2] & present[2:-1] & ~present[:-3] & ~present[3:]) + 1
    assert len(i) > 100
    mid = t[i] + (t[i + 1] - t[i]) / 2
    _, rot = rbm.lookup_transform("left_eye", "scene_cam", time=mid)
    assert np.isfinite(rot).all()
    unit = lambda x: x / np.linalg.norm(x, axis=1)[:, None]  # noqa: E731
    r, a, b = unit(rot), unit(q[i]), unit(q[i + 1])
    between = np.abs(np.sum(a * b, axis=1))
    # lies between its two samples: no farther from either than they are
    # from each other (cosines, to rounding)
    assert (np.abs(np.sum(r * a, axis=1)) >= between - 1e-12).all()
    assert (np.abs(np.sum(r * b, axis=1)) >= between - 1e-12).all()


def test_real_gaze_directions_lose_only_missing_samples(real):
    from rbm_nb.core import gaze

    head, left, right = real
    _register_real(head, left, right)
    missing = np.isnan(left.orientation.values).any(axis=1)
    sight = gaze.directions("left_eye", "scene_cam")
    np.testing.assert_array_equal(np.isnan(sight.values).any(axis=1), missing)
    # in the world, also where the head has no pose (2 eye samples before or
    # after the head's first and last)
    t, head_t = left.time.values, head.time.values
    outside = (t < head_t[0]) | (t > head_t[-1])
    assert 0 < outside.sum() <= 3
    sight = gaze.directions("left_eye", "world")
    np.testing.assert_array_equal(np.isnan(sight.values).any(axis=1), missing | outside)
