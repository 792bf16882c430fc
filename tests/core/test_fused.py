"""Fused chain kernels (rbm_nb._kernels.fused) against the unfused engine.

The engine path (``_engine.chain``: resample every frame, compose step by
step, then apply) is the reference: the fused kernels must give the same
transforms, points, vectors and quaternions to 1e-12 on random trees
(static, moving, inverted and discrete frames; float and datetime64 times;
different rates) and on the real head/eye recording. Missing samples (NaN
rows) are checked against the rule of the module docstring.
"""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._engine import chain as _chain
from rbm_nb._engine import fused as _fused
from rbm_nb._engine import time as _time
from rbm_nb._engine.frame_data import _sign_codes
from rbm_nb._kernels import fused as kf
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import resample as kr
from rbm_nb._kernels import squad_table as kst
from rbm_nb.core import frames as _frames

TOL = 1e-12
NO_GAPS = np.full(kf.SLOTS, np.inf)
OWN = np.zeros(kf.SLOTS, dtype=np.int64)


def _rotations(rng, n, step):
    q = np.cumsum(rng.normal(scale=step, size=(n, 4)), axis=0) + [1.0, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    # some stored signs flipped: interpolation must follow the stored signs
    flip = rng.random(n) < 0.2
    q[flip] *= -1.0
    return q


def _times(rng, n, rate, start, kind):
    t = start + np.arange(n) / rate + rng.uniform(0, 0.2 / rate, n)
    if kind == "float":
        return t
    ns = np.round(t * 1e9).astype(np.int64) + 1_580_603_234_300_365_210
    return ns.astype("datetime64[ns]")


def _missing(rng, arr, count):
    """A copy of arr with ``count`` NaN rows (missing samples)."""
    arr = arr.copy()
    arr[rng.choice(len(arr), count, replace=False)] = np.nan
    return arr


def _random_tree(rng, kind, missing=False):
    """world -> a (moving) -> b (static) -> c (moving, inverse); d (discrete); e.

    With ``missing``, a and c have NaN rows (translations and rotations
    apart) and c a ``max_gap``.
    """
    rbm.register_frame("world")
    na, nc, nd = rng.integers(40, 90), rng.integers(60, 140), rng.integers(5, 12)
    t_a, r_a = rng.normal(size=(na, 3)), _rotations(rng, na, 0.05)
    t_c, r_c = rng.normal(size=(nc, 3)), _rotations(rng, nc, 0.08)
    if missing:
        t_a, r_a = _missing(rng, t_a, 3), _missing(rng, r_a, 4)
        t_c, r_c = _missing(rng, t_c, 4), _missing(rng, r_c, 3)
    rbm.register_frame(
        "a",
        parent="world",
        translation=t_a,
        rotation=r_a,
        timestamps=_times(rng, na, 20.0, 0.0, kind),
    )
    rbm.register_frame(
        "b",
        parent="a",
        translation=rng.normal(size=3),
        rotation=_rotations(rng, 1, 1.0)[0],
    )
    ts_c = _times(rng, nc, 31.3, 0.13, kind)
    if missing:  # a few long gaps
        step = np.zeros(nc, dtype=ts_c.dtype if kind == "float" else np.int64)
        step[rng.choice(np.arange(1, nc), 3, replace=False)] = 1
        gap = np.cumsum(step) * (0.1 if kind == "float" else 100_000_000)
        ts_c = ts_c + (gap if kind == "float" else gap.astype("timedelta64[ns]"))
    rbm.register_frame(
        "c",
        parent="b",
        translation=t_c,
        rotation=r_c,
        timestamps=ts_c,
        inverse=not missing,
        max_gap=0.06 if missing else None,
    )
    rbm.register_frame(
        "d",
        parent="world",
        translation=rng.normal(size=(nd, 3)),
        rotation=_rotations(rng, nd, 0.5),
        timestamps=_times(rng, nd, 3.0, 0.05, kind),
        discrete=True,
    )
    rbm.register_frame(
        "e", parent="d", translation=rng.normal(size=3), rotation=(0.0, 0.0, 1.0, 0.0)
    )


PAIRS = [
    ("c", "world"),
    ("world", "c"),
    ("a", "world"),
    ("c", "a"),
    ("b", "world"),
    ("c", "e"),
    ("e", "c"),
    ("d", "world"),
    ("e", "world"),
    ("a", "e"),
]


def _resolved(outof, into):
    a, b = _frames.resolve_frame(outof), _frames.resolve_frame(into)
    steps = _chain.chain(a, b)
    target = _chain.match([f for f, _ in steps])
    return a, b, steps, target


def _unfused_lookup(steps, target):
    """The engine's step-by-step path: resample each frame, then compose."""
    t, r = _chain.compose(steps, target)
    n = len(target)
    if t.shape[0] != n:
        t, r = np.repeat(t, n, axis=0), np.repeat(r, n, axis=0)
    return t, r


def _unfused_apply(kind, steps, target, data):
    """The engine's unfused transform: held events or composed, then applied."""
    data = np.ascontiguousarray(data)
    discrete = _chain.held(steps, target)
    if discrete is not None:
        t, r, idx = discrete
        if kind == "quaternions":
            return kr.qmul_blocks_held(r, idx, data)
        return kr.transform_blocks_held(r, t, idx, data, kind == "points")
    t, r = _chain.compose(steps, target)
    if kind == "quaternions":
        return kr.qmul_blocks(r, data)
    return kr.transform_blocks(r, t, data, kind == "points")


def _plan(steps, target):
    plan, own = _chain.fused_plan(steps, target)
    assert plan is not None
    return plan, own


def _close(x, y):
    """Equal to TOL (relative to the largest value); NaN exactly where y has NaN."""
    assert x.shape == y.shape
    np.testing.assert_array_equal(np.isnan(x), np.isnan(y))
    scale = max(1.0, float(np.nanmax(np.abs(y))))
    np.testing.assert_allclose(x, y, rtol=0, atol=TOL * scale)


@pytest.mark.parametrize("missing", [False, True])
@pytest.mark.parametrize("kind", ["float", "datetime64"])
@pytest.mark.parametrize("seed", range(4))
def test_lookup_equals_the_engine_on_random_trees(kind, seed, missing):
    rng = np.random.default_rng(seed)
    _random_tree(rng, kind, missing)
    nan_rows = 0
    for outof, into in PAIRS:
        _, _, steps, target = _resolved(outof, into)
        plan, own = _plan(steps, target)
        t_ref, r_ref = _unfused_lookup(steps, target)
        t, r = _fused.lookup(plan, target, own)
        _close(t, t_ref)
        _close(r, r_ref)
        nan_rows += int(np.isnan(r).any(axis=1).sum())
        t0, r_only = _fused.lookup(plan, target, own, rotation_only=True)
        assert t0.shape == (0, 3)
        _close(r_only, r_ref)
    assert (nan_rows > 0) == missing


@pytest.mark.parametrize("missing", [False, True])
@pytest.mark.parametrize("kind", ["float", "datetime64"])
@pytest.mark.parametrize("seed", range(3))
def test_transforms_equal_the_engine_on_random_trees(kind, seed, missing):
    rng = np.random.default_rng(100 + seed)
    _random_tree(rng, kind, missing)
    for outof, into in PAIRS:
        _, _, steps, target = _resolved(outof, into)
        plan, own = _plan(steps, target)
        m = len(target)
        for what, size in (("points", 3), ("vectors", 3), ("quaternions", 4)):
            for rows in (m, 1):
                data = rng.normal(size=(rows, 2, size))
                if size == 4:
                    data /= np.linalg.norm(data, axis=-1, keepdims=True)
                ref = _unfused_apply(what, steps, target, data)
                _close(_fused.transform(plan, target, own, data, what), ref)
                _close(_chain.apply(what, steps, target, data), ref)


@pytest.mark.parametrize("missing", [False, True])
def test_an_item_gets_the_same_bits_in_any_layout(missing):
    # one item per row takes the vectorised loop; several per row, or one
    # for every row, a loop over the items: the same bits either way
    rng = np.random.default_rng(40)
    _random_tree(rng, "float", missing)
    for outof, into in PAIRS:
        _, _, steps, target = _resolved(outof, into)
        plan, own = _plan(steps, target)
        m = len(target)
        for what, size in (("points", 3), ("vectors", 3), ("quaternions", 4)):
            pairs = rng.normal(size=(m, 2, size))
            one = rng.normal(size=(1, 1, size))
            if size == 4:
                pairs /= np.linalg.norm(pairs, axis=-1, keepdims=True)
                one /= np.linalg.norm(one)
            each = _fused.transform(plan, target, own, pairs[:, :1].copy(), what)
            both = _fused.transform(plan, target, own, pairs, what)
            np.testing.assert_array_equal(both[:, :1], each)
            shared = _fused.transform(plan, target, own, one, what)
            tiled = _fused.transform(plan, target, own, np.repeat(one, m, axis=0), what)
            np.testing.assert_array_equal(shared, tiled)


def test_a_target_of_an_arrays_own_times_is_not_compared_again(monkeypatch):
    # the target is the array's track or a slice of it (the overlap with the
    # frames): its run is known without comparing the times
    track = _time.as_track(np.arange(1000) * 0.01)
    other = _time.as_track(np.arange(1000) * 0.01)  # equal, other memory

    def compared(a, b):
        raise AssertionError("times compared")

    with monkeypatch.context() as m:
        m.setattr(_chain.np, "array_equal", compared)
        assert _chain._same_times(track, track) == slice(0, 1000)
        assert _chain._same_times(track, track.slice(3, 900)) == slice(3, 900)
        with pytest.raises(AssertionError, match="times compared"):
            _chain._same_times(track, other.slice(3, 900))
    assert _chain._same_times(track, other.slice(3, 900)) == slice(3, 900)
    shifted = _time.as_track(np.arange(3, 900) * 0.01 + 1e-9)
    assert _chain._same_times(track, shifted) is None


def test_timestamped_arrays_match_like_the_engine():
    """The public transform with timestamps on another clock than the chain's."""
    rng = np.random.default_rng(7)
    _random_tree(rng, "datetime64")
    c = _frames.resolve_frame("c")
    ts = c.timestamps[3:-3] + np.timedelta64(1234567, "ns")
    points = rng.normal(size=(len(ts), 3))
    a, b = c, _frames.resolve_frame("world")
    steps = _chain.chain(b, a)
    from rbm_nb._door.inputs import blocks as door_blocks

    blocks = door_blocks(points, 3, -1, 0, ts, "points")
    target = _chain.match([f for f, _ in steps], [blocks.track])
    data = _chain.resample_array(blocks.data, blocks.track, target, False)
    ref = _unfused_apply("points", steps, target, data)
    plan, own = _plan(steps, target)
    _close(_fused.transform(plan, target, own, data, "points"), ref)


def test_unsorted_target_times_give_the_same_rows():
    rng = np.random.default_rng(3)
    _random_tree(rng, "float")
    _, _, steps, target = _resolved("c", "e")
    plan, own = _plan(steps, target)
    t, r = _fused.lookup(plan, target, own)
    order = rng.permutation(len(target))
    shuffled = _chain.Target(target.track.slice(0, len(target)))
    shuffled.track.base = np.ascontiguousarray(target.track.base[order])
    t2, r2 = _fused.lookup(plan, shuffled, [False] * len(own))
    np.testing.assert_array_equal(t2, t[order])
    np.testing.assert_array_equal(r2, r[order])


def test_the_usual_rows_divisor_gives_the_scalar_routes_bits():
    """The usual row makes r[g] from the stored row and the divisor its table
    row keeps (the state column, ``squad_table``); a unit row that keeps no
    divisor (state 4.0) takes the scalar route, which makes r[g] from the
    stored row and its sign code (``signed_rows.signed_unit_row``): the
    results are the same bit for bit."""
    rng = np.random.default_rng(11)
    _random_tree(rng, "float")
    calls = []
    for outof, into in (("c", "world"), ("world", "c"), ("c", "a")):
        _, _, steps, target = _resolved(outof, into)
        plan, own = _plan(steps, target)
        calls.append((plan, target, own, _fused.lookup(plan, target, own)))
    # every unit row that keeps its divisor, told to keep none
    tables = {id(t): t for c in calls for t in c[0].tables if t is not None}
    kept = 0
    for table in tables.values():
        state = table.rows[:, 14]
        near = (state != 0.0) & (np.abs(state) < kst.DIVISOR_HIGH)
        kept += int(near.sum())
        state[near] = np.sign(state[near]) * kst._UNIT_FAR
    assert kept > 0
    for plan, target, own, (t, r) in calls:
        t2, r2 = _fused.lookup(plan, target, own)
        np.testing.assert_array_equal(t2, t)
        np.testing.assert_array_equal(r2, r)


def test_squad_table_equals_the_engine_coefficients():
    rng = np.random.default_rng(5)
    not_unit = 0
    for n in (2, 3, 4, 50, 50):
        r = kq.unflip(_rotations(rng, n, 0.3))
        if n == 50 and not_unit == 0:  # some samples far from unit norm
            r[rng.choice(n, 5, replace=False)] *= 1.5
        t = np.cumsum(rng.uniform(0.5, 1.5, n))
        a, b = kq.squad_coefficients(r, t)
        seg = kq.squad_segments(r, a, b)
        # stored with some signs flipped (r is their unflipped series)
        sign = np.where(rng.uniform(size=n) < 0.4, -1.0, 1.0)
        stored = sign[:, None] * r
        table = kf.squad_table(_sign_codes(stored, r), stored, t)
        # exp/log by short series for small arcs: within a few ulp of 1
        tol = 4 * np.finfo(float).eps
        np.testing.assert_allclose(table[:, 0:4], a, rtol=0, atol=tol)
        # unit segments keep the great circles, the others b
        unit = seg[:, 10] == 0.0
        # the state: unit (the sample's divisor: stored / divisor is r bit for
        # bit) or not (2.0), negative where the stored sample is -r
        codes = _sign_codes(stored, r)
        divisor = np.where(
            np.abs(codes) == 2, 1.0, np.sqrt((stored * stored).sum(axis=1))
        )
        near = (divisor >= 0.5) & (divisor < 1.5)
        state = np.where(unit, np.where(near, divisor, 4.0), 2.0)
        np.testing.assert_array_equal(table[:, 14], sign * state)
        near &= unit
        np.testing.assert_array_equal(stored[near] / table[near, 14][:, None], r[near])
        got, want = table[unit, 4:14], seg[unit, 0:10]
        for theta, u in ((0, slice(1, 5)), (5, slice(6, 10))):
            np.testing.assert_allclose(got[:, theta], want[:, theta], rtol=0, atol=tol)
            # u = o / |o| with o = b - (a·b) a, which cancels down to |o| ~ θ:
            # the engine's u carries rounding of eps / θ (the table's u of
            # the first arc comes from the log, which does not cancel), and
            # squad uses u only times sin(τθ)
            scale = np.maximum(want[:, theta], 1e-300)[:, None]
            assert np.all(np.abs(got[:, u] - want[:, u]) <= tol / scale)
            np.testing.assert_allclose(
                got[:, u] * np.sin(got[:, theta])[:, None],
                want[:, u] * np.sin(want[:, theta])[:, None],
                rtol=0,
                atol=tol,
            )
        np.testing.assert_allclose(table[~unit, 4:8], b[~unit], rtol=0, atol=tol)
        not_unit += int((~unit).sum())
    assert not_unit > 0


def _repeated(rng, n, step):
    """Unit rotations of an eye tracker: runs of 1-3 exact repeats of a sample
    (30 % of the real eye recording's steps are zero)."""
    r = kq.unflip(_rotations(rng, n, step))
    repeat = rng.random(n) < 0.3
    repeat[0] = False
    for i in np.flatnonzero(repeat):
        r[i] = r[i - 1]
    return r


def test_squad_table_of_repeated_samples():
    """A recording with runs of repeated samples, whose zero steps the table's
    blocks compute in their vector loops (zero logs, zero control-point
    vectors, arcs of length 0): the same bits as the row-by-row scalar
    route, within 4 ulp of the engine's coefficients. (The speed-up is
    measured, not tested: the eye recording's table, 7.5 ms from 10.1.)"""
    rng = np.random.default_rng(21)
    n = 700
    r = _repeated(rng, n, 0.01)
    steps = np.all(r[1:] == r[:-1], axis=1)
    assert 0.25 < steps.mean() < 0.35 and np.any(steps[1:] & steps[:-1])
    t = np.cumsum(rng.uniform(0.004, 0.006, n))
    stored = np.where(rng.uniform(size=n) < 0.3, -1.0, 1.0)[:, None] * r
    codes = _sign_codes(stored, r)
    table = kf.squad_table(codes, stored, t)
    one_by_one = np.zeros_like(table)
    for i in range(n):
        kst._fill_row(codes, stored, t, one_by_one, i)
    np.testing.assert_array_equal(table.view(np.int64), one_by_one.view(np.int64))
    a, b = kq.squad_coefficients(r, t)
    seg = kq.squad_segments(r, a, b)
    tol = 4 * np.finfo(float).eps
    np.testing.assert_allclose(table[:, 0:4], a, rtol=0, atol=tol)
    assert np.all(seg[:, 10] == 0.0)  # every segment unit
    np.testing.assert_allclose(table[:, 4], seg[:, 0], rtol=0, atol=tol)
    np.testing.assert_allclose(table[:, 9], seg[:, 5], rtol=0, atol=tol)
    # and squad through the table gives the engine's values between samples
    rbm.register_frame("world")
    rbm.register_frame("m", parent="world", rotation=stored, timestamps=t)
    between = t[:-1] + np.diff(t) * rng.uniform(0.05, 0.95, n - 1)
    got = rbm.lookup_transform("m", "world", time=between)[1]
    m = _frames.resolve_frame("m")
    want = _chain.resample_frame(m.data, _chain.Target(_time.as_track(between)))[1]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def test_series_exp_and_log_are_within_4_ulp_of_libm():
    """The table's exp/log (short series below the thresholds) against libm's."""
    rng = np.random.default_rng(8)
    n = 5_000
    scale = 10.0 ** rng.uniform(-12, np.log10(0.0999), n)
    v = rng.normal(size=(n, 3))
    v *= (scale / np.linalg.norm(v, axis=1))[:, None]
    w = rng.normal(scale=1e-3, size=n)
    for i in range(n):
        got = np.array(kst._qexp_table(w[i], *v[i]))
        want = np.array(kq._qexp1(w[i], *v[i]))
        np.testing.assert_array_max_ulp(got, want, maxulp=4)
    # logs of near-unit quaternions, arcs up to the series' limit
    ratio = 10.0 ** rng.uniform(-12, np.log10(0.0499), n)
    w = 1.0 + rng.normal(scale=1e-3, size=n)
    v = rng.normal(size=(n, 3))
    v *= (ratio * w / np.linalg.norm(v, axis=1))[:, None]
    for i in range(n):
        got = np.array(kst._qlog_table(w[i], *v[i]))
        want = np.array(kq._qlog1(w[i], *v[i]))
        assert got[0] == want[0]
        np.testing.assert_array_max_ulp(got[1:], want[1:], maxulp=4)


def test_exp_and_log_near_the_identity_are_within_4_ulp_of_libm():
    """exp(w) of w ~ 1e-16 (sums of log-norms) and log of unit quaternions' norms."""
    rng = np.random.default_rng(18)
    n = 5_000
    w = rng.normal(scale=1e-16, size=n) * 10.0 ** rng.uniform(-3, 8, n)  # to ~1e-8
    v = rng.normal(size=(n, 3))
    v *= (10.0 ** rng.uniform(-9, -1.1, n) / np.linalg.norm(v, axis=1))[:, None]
    for i in range(n):
        got = np.array(kst._qexp_table(w[i], *v[i]))
        want = np.array(kq._qexp1(w[i], *v[i]))
        np.testing.assert_array_max_ulp(got, want, maxulp=4)
    # unit quaternions of small arcs: norm² within rounding of 1
    q = np.column_stack([np.ones(n), v * 0.4])
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    tiny = 0
    for i in range(n):
        got = np.array(kst._qlog_table(*q[i]))
        want = np.array(kq._qlog1(*q[i]))
        np.testing.assert_array_max_ulp(got, want, maxulp=4)
        tiny += got[0] != 0.0
    assert tiny > n // 10  # norms not exactly 1 took the short series
    # zero vector parts (repeated samples): the short series too, vector part 0.
    # A unit sample times its own inverse is 1 to within a few ulp (the
    # series' log of the norm is within 4 ulp of libm's there, not for norms
    # further off, which no zero step of unit samples gives)
    units = rng.normal(size=(2000, 4))
    units /= np.linalg.norm(units, axis=1, keepdims=True)
    as_is = np.array([2, 2], dtype=np.int8)  # the rows themselves (signed_rows)
    ws = np.array([kst._log_step(as_is, np.array([q, q]), 0)[0] for q in units])
    assert np.all(np.abs(ws) < 8 * 2.0**-52)  # log |q⁻¹ q|: zero to a few ulp
    own = np.array([kq._qmul1(*kq._qinv1(*q), *q)[0] for q in units])
    assert np.all(np.abs(own - 1.0) <= 4 * 2.0**-52)
    ulps = np.arange(-8, 9)
    for w in np.concatenate([1.0 + ulps * 2.0**-53, 1.0 + ulps[4:-4] * 2.0**-52]):
        got = np.array(kst._qlog_table(w, 0.0, 0.0, 0.0))
        want = np.array(kq._qlog1(w, 0.0, 0.0, 0.0))
        np.testing.assert_array_max_ulp(got, want, maxulp=4)
        assert np.all(got[1:] == 0.0)
    for w in np.concatenate([ulps * 2.0**-60, rng.normal(scale=1e-9, size=50)]):
        got = np.array(kst._qexp_table(w, 0.0, 0.0, 0.0))
        want = np.array(kq._qexp1(w, 0.0, 0.0, 0.0))
        np.testing.assert_array_max_ulp(got, want, maxulp=4)


def test_squad_rows_are_computed_only_for_the_segments_used():
    """Rows come in runs from the first segment used (each log computed once)."""
    rng = np.random.default_rng(11)
    n = 1000
    ts = np.arange(n) * 0.01
    rbm.register_frame("world")
    rbm.register_frame(
        "m",
        parent="world",
        translation=rng.normal(size=(n, 3)),
        rotation=_rotations(rng, n, 0.05),
        timestamps=ts,
    )
    m = _frames.resolve_frame("m")
    steps = _chain.chain(m, _frames.resolve_frame("world"))
    plan, _ = _plan(steps, _chain.Target(m.data.track))
    table = plan.tables[0]
    assert not table.rows.any()  # nothing computed by registering

    def computed():
        return set(np.flatnonzero(table.rows[:, kf.TABLE_COLUMNS - 1]).tolist())

    _fused.lookup(plan, _chain.Target(m.data.track), [True])  # its own times
    assert computed() == set()
    times = np.array([0.0205, 0.0213, 5.5551])  # segments 2, 2, 555
    _fused.lookup(plan, _chain.Target(_time.as_track(times)), [False])
    run = set(range(2, 2 + kst.RUN)) | set(range(555, 555 + kst.RUN))
    assert computed() == run
    # a run stops before rows already there
    _fused.lookup(plan, _chain.Target(_time.as_track(np.array([5.0]))), [False])
    assert computed() == run | set(range(500, 555))
    full = kf.squad_table(m.data.signs, m.data.rotation, m.data.track.base)
    rows = sorted(computed())
    np.testing.assert_array_equal(table.rows[rows], full[rows])
    assert not table.complete


# ---------------------------------------------------------------------------
# missing samples
# ---------------------------------------------------------------------------


def _one_slot(times, t, r, kind):
    plan = np.array([kind, 0, 0], dtype=np.int64)
    statics = np.zeros((1, 7))
    codes = _sign_codes(r, kq.unflip(r))
    table = np.zeros((len(times), kf.TABLE_COLUMNS))
    empty = (np.zeros(1), np.zeros((1, 3)), np.ones(1, dtype=np.int8), np.zeros((1, 4)))
    empty = empty + (np.ones((1, kf.TABLE_COLUMNS)),)
    return plan, statics, kf.pack_slots([(times, t, codes, r, table), empty, empty])


def _expected_nan_rows(times, bad, target, window, at_samples):
    """Rows whose evaluation needs a bad sample.

    Between samples i and i+1: samples i + lo .. i + hi (``window``); at a
    sample's time: i + lo .. i + hi of ``at_samples``.
    """
    n = len(times)
    i = np.searchsorted(times, target, side="right") - 1
    hit = times[np.clip(i, 0, n - 1)] == target
    out = np.zeros(len(target), dtype=bool)
    for j, (seg, exact) in enumerate(zip(i, hit, strict=True)):
        lo_off, hi_off = at_samples if exact else window
        lo, hi = max(seg + lo_off, 0), min(seg + hi_off, n - 1)
        out[j] = bad[lo : hi + 1].any()
    return out


@pytest.mark.parametrize("own", [0, 1])
@pytest.mark.parametrize("kind", [kf.SQUAD, kf.HELD])
def test_nan_rows_reach_exactly_the_rows_that_need_them(kind, own):
    """The engine's rule (issue 28): a result is missing only where a sample
    it needs is missing: at a sample's time that sample, between samples i
    and i+1 those two (squad's control points take the end rule next to a
    missing sample), whether or not the times are the frame's own."""
    rng = np.random.default_rng(2)
    n = 60
    times = np.arange(n) * 0.1
    t = rng.normal(size=(n, 3))
    r = _rotations(rng, n, 0.05)
    bad = np.zeros(n, dtype=bool)
    bad[[0, 17, 18, 40, n - 1]] = True
    t[bad] = np.nan
    r[bad] = np.nan
    plan, statics, slots = _one_slot(times, t, r, kind)
    # midpoints, quarter points and the sample times themselves
    target = np.sort(np.concatenate([times, times[:-1] + 0.05, times[:-1] + 0.025]))
    own_slots = np.array([own, 0, 0], dtype=np.int64)
    t_out, r_out, _ = kf.lookup_chain(
        plan, statics, np.zeros(kf.SLOTS), NO_GAPS, own_slots, *slots, target, False
    )
    if kind == kf.SQUAD:
        want_r = want_t = _expected_nan_rows(times, bad, target, (0, 1), (0, 0))
    else:
        want_r = want_t = bad[np.searchsorted(times, target, side="right") - 1]
    # (a sample next to a missing one comes back at its own time)
    next_to_bad = np.isin(target, times[1:][bad[:-1]])
    assert want_r.any() and (~want_r).any() and (~want_r[next_to_bad]).any()
    np.testing.assert_array_equal(np.isnan(r_out).any(axis=1), want_r)
    np.testing.assert_array_equal(np.isnan(r_out).all(axis=1), want_r)
    np.testing.assert_array_equal(np.isnan(t_out).all(axis=1), want_t)
    np.testing.assert_array_equal(np.isnan(t_out).any(axis=1), want_t)


def test_nan_rows_of_the_real_eye_recording(shared_data):
    """The eye tracker's missing samples, evaluated at the head's times."""
    xr = pytest.importorskip("xarray")
    eye = xr.open_dataset(shared_data / "rbm-data" / "left_eye.nc")
    head = xr.open_dataset(shared_data / "rbm-data" / "head.nc")
    ns = eye.time.values.astype("datetime64[ns]").view(np.int64)
    times = (ns - ns[0]) / 1e9
    r = np.ascontiguousarray(eye.orientation.values, dtype=np.float64)
    bad = np.isnan(r).any(axis=1)
    r[bad] = np.nan
    ok = ~bad
    r[ok] /= np.linalg.norm(r[ok], axis=1, keepdims=True)
    t = np.zeros((len(times), 3))
    t[bad] = np.nan
    hn = head.time.values.astype("datetime64[ns]").view(np.int64)
    target = (hn - ns[0]) / 1e9
    target = np.ascontiguousarray(target[(target >= times[0]) & (target <= times[-1])])
    plan, statics, slots = _one_slot(times, t, r, kf.SQUAD)
    _, r_out, _ = kf.lookup_chain(
        plan, statics, np.zeros(kf.SLOTS), NO_GAPS, OWN, *slots, target, False
    )
    want = _expected_nan_rows(times, bad, target, (0, 1), (0, 0))
    assert want.sum() > 1000 and (~want).sum() > 1000
    np.testing.assert_array_equal(np.isnan(r_out).any(axis=1), want)


# ---------------------------------------------------------------------------
# the real head/eye recording
# ---------------------------------------------------------------------------


def _register_recording(shared_data):
    xr = pytest.importorskip("xarray")
    head = xr.open_dataset(shared_data / "rbm-data" / "head.nc")
    eye = xr.open_dataset(shared_data / "rbm-data" / "left_eye.nc")
    keep = ~np.isnan(eye.orientation.values).any(axis=1)
    rbm.register_frame("world")
    rbm.register_frame(
        "t265/world", parent="world", rotation=(np.sqrt(0.5), np.sqrt(0.5), 0, 0)
    )
    rbm.register_frame(
        "head",
        parent="t265/world",
        translation=head.position.values,
        rotation=head.orientation.values,
        timestamps=head.time.values,
    )
    rbm.register_frame(
        "scene_cam",
        parent="head",
        translation=(0.0, -0.05, 0.02),
        rotation=np.array((0.99, 0.1, 0.0, 0.0)) / np.linalg.norm((0.99, 0.1, 0, 0)),
    )
    rbm.register_frame(
        "left_eye",
        parent="scene_cam",
        rotation=eye.orientation.values[keep],
        timestamps=eye.time.values[keep],
    )


def test_real_recording_lookups_and_transforms(shared_data):
    _register_recording(shared_data)
    rng = np.random.default_rng(0)
    for outof, into in [
        ("left_eye", "world"),
        ("world", "left_eye"),
        ("head", "world"),
        ("left_eye", "head"),
    ]:
        a, b, steps, target = _resolved(outof, into)
        plan, own = _plan(steps, target)
        t_ref, r_ref = _unfused_lookup(steps, target)
        t, r = _fused.lookup(plan, target, own)
        _close(t, t_ref)
        _close(r, r_ref)
        t_pub, r_pub, _ = _chain.lookup(a, b)  # the engine's path is the fused one
        _close(t_pub, t_ref)
        _close(r_pub, r_ref)
        data = rng.normal(size=(len(target), 1, 3))
        for what in ("points", "vectors"):
            ref = _unfused_apply(what, steps, target, data)
            _close(_fused.transform(plan, target, own, data, what), ref)


def test_threads_filling_one_table_get_the_same_results():
    """Concurrent first lookups (kernels release the GIL) share a table safely."""
    import threading

    rng = np.random.default_rng(21)
    _random_tree(rng, "float")
    _, _, steps, target = _resolved("c", "world")
    t_ref, r_ref = _unfused_lookup(steps, target)
    c, a = _frames.resolve_frame("c"), _frames.resolve_frame("a")
    plan = _fused.plan(steps, _chain._compose_static)
    table = plan.tables[plan.frames.index(a.data)]  # a is interpolated at c's times
    assert table is not None and not table.rows.any()
    start = threading.Barrier(4)
    results = []

    def run():
        start.wait()
        results.append(_chain.lookup(c, _frames.resolve_frame("world"))[:2])

    threads = [threading.Thread(target=run) for _ in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert len(results) == 4 and table.rows[:, kf.TABLE_COLUMNS - 1].any()
    for t, r in results:
        _close(t, t_ref)
        _close(r, r_ref)
