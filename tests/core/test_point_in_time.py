"""Point-in-time lookups (``lookup_at``, rbm_nb._engine.at_time) against
rigid_body_motion and naive twins."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb._door import at_times
from rbm_nb._engine import at_time
from rbm_nb._engine import time as _time
from rbm_nb.core.frames import ReferenceFrame, resolve_frame
from rbm_nb.core.lookups import lookup_at
from rbm_nb.errors import ExtrapolationError

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import rigid_body_motion as ref


def latest_common_time(outof, into):
    """The door's latest common time of two frames given by name or object."""
    return at_times.latest_common_time(
        resolve_frame(outof, "outof"), resolve_frame(into, "into")
    )


def walk(n, seed, rot_scale=0.1):
    rng = np.random.default_rng(seed)
    r = Rotation.from_rotvec(
        np.cumsum(rng.normal(scale=rot_scale, size=(n, 3)), axis=0)
    )
    return np.cumsum(rng.normal(size=(n, 3)), axis=0), r.as_quat(scalar_first=True)


HEAD_TS = np.linspace(0.0, 4.9, 50)
OBJ_TS = np.linspace(0.5, 6.0, 40)
HEAD_T, HEAD_R = walk(50, 1)
OBJ_T, OBJ_R = walk(40, 2)
EYE_R = Rotation.from_euler("y", 0.2).as_quat(scalar_first=True)


def build(lib, head_ts=HEAD_TS, obj_ts=OBJ_TS):
    """world -> head (moving) -> eye (static); world -> obj (moving, inverse)."""
    lib.clear_registry()
    lib.register_frame("world")
    lib.register_frame(
        "head", parent="world", translation=HEAD_T, rotation=HEAD_R, timestamps=head_ts
    )
    lib.register_frame(
        "eye", parent="head", translation=[0.03, 0.0, 0.0], rotation=EYE_R
    )
    lib.register_frame(
        "obj", parent="world", translation=OBJ_T, rotation=OBJ_R, timestamps=obj_ts,
        inverse=True,
    )  # fmt: skip


@pytest.fixture
def tree():
    build(rbm)
    yield
    ref.clear_registry()


def oracle(outof, into, times):
    """rigid_body_motion, resampling the chain at the times of a dummy array."""
    n = len(times)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        build(ref)
        t = ref.transform_points(
            np.zeros((n, 3)), outof=outof, into=into, timestamps=times
        )
        r = ref.transform_quaternions(
            np.tile([1.0, 0, 0, 0], (n, 1)), outof=outof, into=into, timestamps=times
        )
    return t, r


def same_rotation(q1, q2, atol=1e-12):
    d = np.minimum(np.abs(q1 - q2).max(axis=-1), np.abs(q1 + q2).max(axis=-1))
    return bool(np.all(d <= atol))


# ---------------------------------------------------------------------------
# values
# ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "outof,into", [("eye", "obj"), ("obj", "eye"), ("head", "world"), ("world", "eye")]
)
def test_matches_rigid_body_motion_at_arbitrary_times(tree, outof, into):
    times = np.array([0.7, 1.234, 2.0, 2.05, 3.0, 4.5, 4.9])
    t, r = lookup_at(outof, into, times)
    rt, rr = oracle(outof, into, times)
    np.testing.assert_allclose(t, rt, atol=1e-12)
    assert same_rotation(r, rr, 1e-12)


def test_any_order_repeats_and_scalars(tree):
    times = np.array([3.3, 0.9, 3.3, 2.2, 0.9])
    t, r = lookup_at("eye", "obj", times)
    order = np.argsort(times)
    ts, rs = lookup_at("eye", "obj", times[order])
    np.testing.assert_array_equal(t[order], ts)
    np.testing.assert_array_equal(r[order], rs)
    t1, r1 = lookup_at("eye", "obj", 2.2)
    assert t1.shape == (3,) and r1.shape == (4,)
    np.testing.assert_array_equal(t1, t[3])
    assert lookup_at("eye", "obj", [2.2])[0].shape == (1, 3)
    assert lookup_at("eye", "obj", np.float32(2.25))[0].shape == (3,)


def test_times_are_evaluated_on_the_segments_they_read():
    """The fused kernels: squad table rows around the requested times only,
    not the spline coefficients of every sample (the step-by-step route),
    with the step-by-step route's values."""
    from rbm_nb._engine import chain
    from rbm_nb._engine import fused as _fused
    from rbm_nb._kernels import squad_table

    n = 5000
    ts = np.linspace(0.0, 50.0, n)
    t, r = walk(n, 3, rot_scale=0.02)
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame("head", parent="world", translation=t, rotation=r, timestamps=ts)
    rbm.register_frame("eye", parent="head", translation=[0.03, 0, 0], rotation=EYE_R)
    times = np.array([10.005, 10.012, 33.3, 0.0, 50.0])
    got_t, got_r = lookup_at("eye", "world", times)
    head = resolve_frame("head")
    # no coefficients for all 5000 samples
    assert head.data.samples not in chain._COEFFICIENTS
    computed = int(np.count_nonzero(_fused._TABLES[head.data.samples].rows[:, -1]))
    assert 0 < computed <= 4 * squad_table.RUN, computed
    steps = chain.chain(resolve_frame("eye"), resolve_frame("world"))
    track, inverse, _, _ = _time.requested_times(times)  # sorted, unique
    want_t, want_r = chain.compose(steps, chain.Target(track))
    np.testing.assert_allclose(got_t, want_t[inverse], rtol=0, atol=1e-12)
    assert same_rotation(got_r, want_r[inverse], 1e-12)
    # one time, as the tf2-style Transformer asks, many times over
    for k, when in enumerate(np.linspace(0.01, 49.99, 40)):
        one_t, one_r = lookup_at("eye", "world", when)
        want_t, want_r = chain.compose(
            steps, chain.Target(_time.requested_times(when)[0])
        )
        np.testing.assert_allclose(one_t, want_t[0], rtol=0, atol=1e-12, err_msg=k)
        assert same_rotation(one_r, want_r[0], 1e-12), k


def test_sample_times_give_the_samples(tree):
    t, r = lookup_at("head", "world", HEAD_TS)
    np.testing.assert_array_equal(t, HEAD_T)
    assert same_rotation(r, HEAD_R, 1e-15)
    # and agree with the matched lookup on the frame's own timestamps
    t2, r2 = rbm.lookup_transform("head", "world")
    np.testing.assert_array_equal(t, t2)


def test_translation_is_linear_between_samples(tree):
    """Naive twin: np.interp per axis for a single moving frame."""
    times = np.random.default_rng(3).uniform(HEAD_TS[0], HEAD_TS[-1], 200)
    t, _ = lookup_at("head", "world", times)
    twin = np.stack([np.interp(times, HEAD_TS, HEAD_T[:, k]) for k in range(3)], axis=1)
    np.testing.assert_allclose(t, twin, atol=1e-12)


def test_static_chain_any_time(tree):
    t, r = lookup_at("eye", "head", [-1e9, 0.0, 1e9])
    np.testing.assert_array_equal(t, np.tile([0.03, 0.0, 0.0], (3, 1)))
    assert same_rotation(r, np.tile(EYE_R, (3, 1)), 1e-15)
    assert latest_common_time("eye", "head") is None


def test_discrete_frames_hold_their_events():
    world = ReferenceFrame("world")
    events = np.array([1.0, 2.0, 4.0])
    values = np.array([[1.0, 0, 0], [2.0, 0, 0], [4.0, 0, 0]])
    mode = ReferenceFrame(
        "mode", parent=world, translation=values, timestamps=events, discrete=True
    )
    times = np.array([0.0, 1.0, 1.5, 2.0, 3.99, 4.0, 10.0])
    t, _ = lookup_at(mode, world, times)
    # naive twin: the last event at or before each time (the first one before it)
    idx = np.clip(np.searchsorted(events, times, side="right") - 1, 0, None)
    np.testing.assert_array_equal(t, values[idx])
    assert latest_common_time(mode, world) == 4.0


def test_datetime64_times():
    start = np.datetime64("2024-05-01T12:00:00", "ns")
    head_ts = start + (HEAD_TS * 1e9).astype("timedelta64[ns]")
    obj_ts = start + (OBJ_TS * 1e9).astype("timedelta64[ns]")
    build(rbm, head_ts, obj_ts)
    times = start + (np.array([0.7, 2.5, 4.0]) * 1e9).astype("timedelta64[ns]")
    t, r = lookup_at("eye", "obj", times)
    build(rbm)
    t_num, r_num = lookup_at("eye", "obj", [0.7, 2.5, 4.0])
    np.testing.assert_allclose(t, t_num, atol=1e-9)
    assert same_rotation(r, r_num, 1e-9)
    build(rbm, head_ts, obj_ts)
    assert latest_common_time("eye", "obj") == head_ts[-1]
    with pytest.raises(ValueError, match="datetime64"):
        lookup_at("eye", "obj", 1.0)


# ---------------------------------------------------------------------------
# no extrapolation
# ---------------------------------------------------------------------------


def test_future_names_frame_range_and_time(tree):
    with pytest.raises(ExtrapolationError) as info:
        lookup_at("eye", "obj", [1.0, 5.5])
    msg = str(info.value)
    assert "'head'" in msg and "0.0 to 4.9" in msg and "5.5" in msg and "future" in msg


def test_past_names_frame_range_and_time(tree):
    with pytest.raises(
        ExtrapolationError, match=r"'obj' has data from 0.5 to 6.0.*0.2.*past"
    ):
        lookup_at("eye", "obj", 0.2)
    # ExtrapolationError is a ValueError
    with pytest.raises(ValueError):
        lookup_at("world", "head", -1.0)


def test_edges_of_the_range_are_inside(tree):
    t, _ = lookup_at("world", "head", [0.0, 4.9])
    assert t.shape == (2, 3)
    latest = latest_common_time("eye", "obj")
    assert latest == 4.9
    lookup_at("eye", "obj", latest)


def test_no_common_time_and_other_errors():
    world = ReferenceFrame("world")
    a = ReferenceFrame(
        "a", parent=world, translation=np.zeros((2, 3)), timestamps=[0.0, 1.0]
    )
    b = ReferenceFrame(
        "b", parent=world, translation=np.zeros((2, 3)), timestamps=[2.0, 3.0]
    )
    with pytest.raises(
        ExtrapolationError, match=r"no common time: frame 'b' starts at 2.0"
    ):
        latest_common_time(a, b)
    other = ReferenceFrame("other")
    with pytest.raises(ValueError, match="different trees"):
        lookup_at(a, other, 0.5)
    with pytest.raises(ValueError, match="time\\[1\\] is nan"):
        lookup_at(a, world, [0.5, np.nan])
    with pytest.raises(ValueError, match="numeric or datetime64"):
        lookup_at(a, world, "noon")
    with pytest.raises(ValueError, match="one-dimensional"):
        lookup_at(a, world, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="empty"):
        lookup_at(a, world, [])


@pytest.mark.parametrize(
    "time, message",
    [([0.5, np.nan], r"time\[1\] is nan"), ("noon", "numeric or datetime64"),
     (np.zeros((2, 2)), "one-dimensional"), ([], "empty")],
)  # fmt: skip
def test_the_times_asked_for_are_checked_at_the_door(tree, monkeypatch, time, message):
    # the engine is handed checked times only: a bad one never reaches it
    entered = []
    identity = (np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), None)
    monkeypatch.setattr(
        at_time, "transform_at_times", lambda *args: entered.append(args) or identity
    )
    with pytest.raises(ValueError, match=message):
        rbm.lookup_transform("eye", "world", time=time)
    assert entered == []
    rbm.lookup_transform("eye", "world", time=1.0)  # a good one does
    assert len(entered) == 1
    assert isinstance(entered[0][2], at_time.Requested)


# ---------------------------------------------------------------------------
# output forms
# ---------------------------------------------------------------------------


def test_lookup_at_matrix_transform_and_timestamps(tree):
    times = np.array([1.0, 2.5, 4.0])
    t, r = lookup_at("eye", "obj", times)
    m = lookup_at("eye", "obj", times, as_matrix=True)
    assert m.shape == (3, 4, 4)
    np.testing.assert_allclose(m, rbm.homogeneous_from_transform(t, r))
    tf = lookup_at("eye", "obj", times, as_transform=True)
    assert isinstance(tf, rbm.Transform) and tf.shape == (3,)
    assert tf.allclose(rbm.Transform(t, r))
    one = lookup_at("eye", "obj", 2.5, as_transform=True)
    assert one.shape == () and one.allclose(tf[1])
    m1, ts = lookup_at("eye", "obj", 2.5, as_matrix=True, return_timestamps=True)
    assert m1.shape == (4, 4) and ts is None
    t2, r2, ts = lookup_at("eye", "obj", times, return_timestamps=True)
    np.testing.assert_array_equal(ts, times)
    # without a time: the matched timestamps of the frames
    full, ts = lookup_at("eye", "obj", as_matrix=True, return_timestamps=True)
    tt, rr, ts2 = rbm.lookup_transform("eye", "obj", return_timestamps=True)
    np.testing.assert_array_equal(ts, ts2)
    np.testing.assert_allclose(full, rbm.homogeneous_from_transform(tt, rr))
    with pytest.raises(ValueError, match="at most one of as_matrix, as_transform"):
        lookup_at("eye", "obj", 1.0, as_matrix=True, as_transform=True)


def test_lookup_at_dataset(tree):
    pytest.importorskip("xarray")
    ds = lookup_at("eye", "obj", [1.0, 2.0], as_dataset=True)
    np.testing.assert_array_equal(ds.time.values, [1.0, 2.0])
    np.testing.assert_allclose(
        ds.translation.values, lookup_at("eye", "obj", [1.0, 2.0])[0]
    )


# ---------------------------------------------------------------------------
# the public lookup_transform keywords
# ---------------------------------------------------------------------------


def test_lookup_transform_time_keyword(tree):
    times = np.array([1.0, 2.5, 4.0])
    t, r = rbm.lookup_transform("eye", "obj", time=times)
    ct, cr = lookup_at("eye", "obj", times)
    np.testing.assert_array_equal(t, ct)
    np.testing.assert_array_equal(r, cr)
    t, r, ts = rbm.lookup_transform("eye", "obj", return_timestamps=True, time=2.5)
    assert t.shape == (3,) and ts is None
    m = rbm.lookup_transform("eye", "obj", time=times, as_matrix=True)
    np.testing.assert_allclose(m, rbm.homogeneous_from_transform(ct, cr))
    tf = rbm.lookup_transform("eye", "obj", time=times, as_transform=True)
    assert tf.allclose(rbm.Transform(ct, cr))
    with pytest.raises(ExtrapolationError, match="'head'"):
        rbm.lookup_transform("eye", "obj", time=9.0)
    # without the new keywords: the head's timestamps inside the common range
    t0, r0, ts0 = rbm.lookup_transform("eye", "obj", return_timestamps=True)
    np.testing.assert_array_equal(ts0, HEAD_TS[HEAD_TS >= OBJ_TS[0]])
    # ... and the time keyword at those timestamps agrees
    t1, r1 = rbm.lookup_transform("eye", "obj", time=ts0)
    np.testing.assert_allclose(t1, t0, atol=1e-12)
    assert same_rotation(r1, r0, 1e-12)


def test_lookup_transform_as_matrix_of_a_static_chain(tree):
    m = rbm.lookup_transform("eye", "head", as_matrix=True)
    assert m.shape == (4, 4)
    np.testing.assert_allclose(m[:3, 3], [0.03, 0.0, 0.0])
    tf = rbm.lookup_transform("eye", "head", as_transform=True)
    assert tf.shape == () and tf.allclose(rbm.Transform.from_matrix(m))
