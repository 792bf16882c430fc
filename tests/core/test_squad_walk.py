"""The fused squad pass (rbm_nb._kernels.squad_walk) against the three-kernel path
it replaces in qinterp (unflip, squad, stored_signs), to 1e-12, NaN rows included."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._door.unpack import read_only
from rbm_nb._engine import time as _time
from rbm_nb._engine.chain import stored_signs
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import squad_walk as sw
from rbm_nb._kernels.times import seconds_since
from tests.recordings import recording

TOL = 1e-12


def previous(q, t_in, t_out):
    """What qinterp computed for one series before the fused pass."""
    q = np.ascontiguousarray(q, dtype=float)
    if len(q) < 2:
        return np.tile(q[0], (len(t_out), 1))
    unflipped = kq.unflip(q)
    out = kq.squad(unflipped, t_in, t_out)
    stored_signs(out, unflipped, q, t_in, t_out)
    return out


def series(rng, n, step, noise=0.0, flips=0.3, nan_rows=0):
    """n rotations a random walk apart (angle ~ step rad), with sign flips,
    norms off by up to ``noise`` and ``nan_rows`` missing samples."""
    axis = rng.normal(size=(n, 3))
    half = (
        0.5
        * step
        * rng.random(n)[:, None]
        * axis
        / np.linalg.norm(axis, axis=1)[:, None]
    )
    steps = np.c_[
        np.cos(np.linalg.norm(half, axis=1)),
        np.sinc(np.linalg.norm(half, axis=1) / np.pi)[:, None] * half,
    ]
    q = np.empty((n, 4))
    q[0] = rbm.from_euler_angles(rpy=rng.normal(size=3))
    for i in range(1, n):
        q[i] = kq.qmul(q[i - 1 : i], steps[i : i + 1])[0]
    q *= np.where(rng.random(n) < flips, -1.0, 1.0)[:, None]
    q *= 1.0 + noise * rng.uniform(-1.0, 1.0, size=(n, 1))
    if nan_rows:
        q[rng.choice(np.arange(1, n - 1), nan_rows, replace=False)] = np.nan
    return q


def times(rng, n, irregular=True):
    dt = rng.uniform(0.2, 3.0, n) if irregular else np.ones(n)
    return np.cumsum(dt) * 1e-2


def outputs(rng, t_in, m, exact_samples=True):
    t = np.sort(rng.uniform(t_in[0], t_in[-1], m))
    if exact_samples:  # sample times and both ends, where squad hits the samples
        t = np.sort(
            np.r_[t, t_in[rng.choice(len(t_in), min(5, len(t_in)))], t_in[0], t_in[-1]]
        )
    return t


def check(q, t_in, t_out):
    got = sw.squad_walk(q, t_in, t_out)
    want = previous(q, t_in, t_out)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got, want, rtol=0, atol=TOL, equal_nan=True)
    return got


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize(
    "step, noise",
    [(1e-3, 0.0), (1e-3, 1e-4), (0.05, 5e-3), (0.6, 1e-3), (2.5, 0.0), (3.0, 9e-3)],
)
def test_random_series_match_the_previous_path(seed, step, noise):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 400))
    q = series(rng, n, step, noise, nan_rows=int(rng.integers(0, 4)) if n > 8 else 0)
    t_in = times(rng, n, irregular=seed % 2 == 0)
    check(q, t_in, outputs(rng, t_in, int(rng.integers(0, 900))))


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_short_series(n):
    rng = np.random.default_rng(n)
    q = series(rng, n, 0.3, 1e-3)
    t_in = times(rng, n)
    check(q, t_in, outputs(rng, t_in, 50))


def test_unsorted_and_extrapolated_times():
    """Any order of output times; outside the samples squad's own edge rules
    (after the end: the last segment continued; before the start:
    numpy-quaternion's index -1) take the exact route."""
    rng = np.random.default_rng(7)
    q = series(rng, 60, 0.2, 1e-3, nan_rows=2)
    t_in = times(rng, 60)
    t_out = rng.permutation(outputs(rng, t_in, 300))
    check(q, t_in, t_out)
    span = t_in[-1] - t_in[0]
    check(q, t_in, np.r_[t_in[0] - 0.1 * span, t_out, t_in[-1] + 0.05 * span])


def test_slerp_direction_near_the_boundary_takes_the_exact_route():
    """Consecutive samples about 90 degrees apart in 4D (180 degree rotations)."""
    rng = np.random.default_rng(3)
    base = np.array([1.0, 0.0, 0.0, 0.0])
    turn = np.array([np.cos(np.pi / 4 + 1e-11), 0.0, 0.0, np.sin(np.pi / 4 + 1e-11)])
    q = np.array(
        [base, turn, kq.qmul(turn[None], turn[None])[0], base * 1.003, turn * 0.998]
    )
    t_in = np.arange(5.0)
    check(q, t_in, outputs(rng, t_in, 200))


def test_nan_rows_spread_as_before():
    rng = np.random.default_rng(11)
    q = series(rng, 40, 0.1, 1e-3)
    q[[0, 7, 8, 20, 39]] = np.nan
    q[30, 2] = np.nan  # partly missing: the row counts as missing
    t_in = times(rng, 40)
    got = check(q, t_in, outputs(rng, t_in, 400))
    assert np.isnan(got).any() and not np.isnan(got).all()


# the first test to call the parallel walk: with numba's cache emptied (any
# change to rbm_nb/ since the last warm-up) it compiles it first: 59 s here
# since the walk is no longer inlined, 201 s before (CI's set-up warms the
# cache, so there it takes seconds)
@pytest.mark.timeout(600)
def test_parallel_twin_equals_the_serial_kernel():
    rng = np.random.default_rng(5)
    q = series(rng, 3000, 0.01, 1e-3, nan_rows=5)
    t_in = times(rng, 3000)
    t_out = outputs(rng, t_in, 5000)
    np.testing.assert_array_equal(
        sw.squad_walk_parallel(q, t_in, t_out), sw.squad_walk(q, t_in, t_out)
    )
    t_out = rng.permutation(t_out)
    np.testing.assert_array_equal(
        sw.squad_walk_parallel(q, t_in, t_out), sw.squad_walk(q, t_in, t_out)
    )


def same_bits(a, b):
    """a and b hold the same float64 bit patterns (any NaN equal to any NaN)."""
    nan = np.isnan(a)
    np.testing.assert_array_equal(nan, np.isnan(b))
    np.testing.assert_array_equal(a.view(np.int64)[~nan], b.view(np.int64)[~nan])


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize(
    "step, noise",
    [(1e-3, 0.0), (1e-3, 2e-3), (0.05, 3e-4), (0.3, 1e-3), (2.5, 0.0), (3.0, 0.06)],
)
def test_vector_loops_give_the_bits_of_the_scalar_code(seed, step, noise):
    """squad_walk sets up segments and evaluates rows in vector loops over
    the common branches; squad_walk_scalar runs the scalar code (every
    branch) alone. Arcs from 1e-3 to 3 rad, norms off by up to 6 % (ln |q|
    off its series, scales beyond the fast route's limit), missing samples,
    uneven sampling, output times in order (whole blocks at once), shuffled,
    at the samples and outside them: the same bits everywhere."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(300, 700))
    q = series(rng, n, step, noise, nan_rows=int(rng.integers(0, 5)))
    t_in = times(rng, n, irregular=seed != 1)
    span = t_in[-1] - t_in[0]
    t_out = outputs(rng, t_in, int(rng.integers(500, 2500)))
    for t in (
        t_out,
        rng.permutation(t_out),
        np.r_[t_in[0] - 0.1 * span, t_out, t_in[-1] + 0.05 * span],
        t_in.copy(),
        np.sort(rng.uniform(t_in[0], t_in[-1], 3 * n)),
    ):
        same_bits(sw.squad_walk(q, t_in, t), sw.squad_walk_scalar(q, t_in, t))


def test_the_recording_as_qinterp_interpolates_it():
    """The head's and an eye's stored orientations (the eye with its NaN rows) at
    the other's timestamps, through the public qinterp."""
    head, eye, _, _ = recording()
    for src, dst in ((head, eye), (eye, head)):
        q = np.ascontiguousarray(src.orientation.values)
        ts = src.time.values
        t = dst.time.values
        t = t[(t >= ts[0]) & (t <= ts[-1])]
        got = rbm.qinterp(q, ts, t)
        t_in, t_out = _time.seconds_pair(ts, t)
        want = previous(q, t_in, t_out)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        np.testing.assert_allclose(got, want, rtol=0, atol=TOL, equal_nan=True)


def test_fast_door_equals_the_general_door():
    """(n, 4) float64 with datetimes takes the one-pass door; the transposed
    array takes the general one; both give the same."""
    rng = np.random.default_rng(2)
    q = series(rng, 200, 0.05, 1e-3, nan_rows=3)
    start = np.datetime64("2020-02-02T00:00:00", "ns")
    t_in = start + (times(rng, 200) * 1e9).astype("timedelta64[ns]")
    span = (t_in[-1] - t_in[0]).astype(np.int64)
    t_out = t_in[0] + np.sort(rng.integers(0, span, 300)).astype("timedelta64[ns]")
    fast = rbm.qinterp(q, t_in, t_out)
    general = rbm.qinterp(np.asfortranarray(q.T), t_in, t_out, axis=1, qaxis=0)
    np.testing.assert_allclose(fast, general.T, rtol=0, atol=TOL, equal_nan=True)


def test_seconds_since_is_numpys_arithmetic():
    keys = np.array(
        ["2020-01-01T00:00:00.000000001", "NaT", "2020-01-01T00:01:00"], "M8[ns]"
    )
    k = keys.view(np.int64)
    got = seconds_since(read_only(k.copy()), int(k[0]))
    want = np.where(np.isnat(keys), np.nan, (k - int(k[0])) / 1e9)
    np.testing.assert_array_equal(got, want)
    # and the time module converts with it
    np.testing.assert_array_equal(_time.seconds_pair(keys, keys)[1], want)


@pytest.mark.parametrize(
    "change, code",
    [
        (lambda q, ti, to: None, 0),
        (lambda q, ti, to: q.__setitem__((3, 1), np.inf), 1),
        (lambda q, ti, to: q.__setitem__(4, q[4] * 1.5), 1),
        (lambda q, ti, to: q.__setitem__(4, 0.0), 1),
        (lambda q, ti, to: q.__setitem__(4, np.nan), 0),
        (lambda q, ti, to: ti.__setitem__(5, ti[4]), 2),
        (lambda q, ti, to: ti.__setitem__(5, np.nan), 2),
        (lambda q, ti, to: to.__setitem__(0, ti[0] - 1.0), 3),
        (lambda q, ti, to: to.__setitem__(2, np.nan), 3),
    ],
)
def test_input_fault_codes(change, code):
    q = np.tile([1.0, 0.0, 0.0, 0.0], (10, 1))
    t_in = np.arange(10.0)
    t_out = np.linspace(0.0, 9.0, 7)
    change(q, t_in, t_out)
    assert sw.squad_input_fault(q, t_in, t_out, 1e-2) == code


@pytest.mark.parametrize(
    "bad, match",
    [
        ("inf", r"q\[2\] is not finite"),
        ("norm", r"q\[2\] is of norm"),
        ("order", "strictly increasing"),
        ("range", "within the range"),
    ],
)
def test_bad_input_still_named_on_the_fast_door(bad, match):
    q = np.tile([1.0, 0.0, 0.0, 0.0], (6, 1))
    t_in = np.arange(6.0)
    t_out = np.array([0.5, 1.5])
    if bad == "inf":
        q[2, 1] = np.inf
    elif bad == "norm":
        q[2] *= 2.0
    elif bad == "order":
        t_in[3] = t_in[2]
    else:
        t_out[1] = 9.0
    with pytest.raises(ValueError, match=match):
        rbm.qinterp(q, t_in, t_out)


def test_read_only_datetimes_take_the_fast_door():
    rng = np.random.default_rng(8)
    q = series(rng, 50, 0.05, 1e-3)
    start = np.datetime64("2020-02-02T00:00:00", "ns")
    t_in = start + (np.arange(50) * 10_000_000).astype("timedelta64[ns]")
    t_out = t_in[:-1] + np.timedelta64(3_000_000, "ns")
    want = rbm.qinterp(q, t_in, t_out)
    t_in.flags.writeable = False
    t_out.flags.writeable = False
    np.testing.assert_array_equal(rbm.qinterp(q, t_in, t_out), want)


@pytest.mark.parametrize("dtype", ["M8[ns]", "m8[ns]", "f8"])
def test_read_only_timestamps_are_checked_in_one_kernel_pass(monkeypatch, dtype):
    # timestamps from an xarray or pandas index come read-only: they take the
    # kernels' route (numpy's checks, _keys, only run to name a fault)
    values = (np.arange(1000) * 5_000_000).astype(dtype)
    want = _time.as_track(values.copy(), copy=False)
    values.flags.writeable = False

    def numpy_route(*args):
        raise AssertionError("read-only timestamps took numpy's checks")

    with monkeypatch.context() as m:
        m.setattr(_time, "_keys", numpy_route)
        got = _time.as_track(values, copy=False)
    np.testing.assert_array_equal(got.key, want.key)
    np.testing.assert_array_equal(got.base, want.base)
    assert got.origin == want.origin
    duplicate = values.copy()
    duplicate[7] = duplicate[6]
    duplicate.flags.writeable = False
    with pytest.raises(ValueError, match=r"timestamps\[7\] = .* is a duplicate of"):
        _time.as_track(duplicate, copy=False)
