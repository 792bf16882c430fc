"""The fused kernels' prange twins give the serial kernels' results, bit for bit.

Every comparison runs the same call twice on fresh squad tables: once
serially (``RBM_NB_NUM_THREADS=1``) and once through the parallel twins with
two threads (``_parallel.MIN_ROWS`` lowered so that short test calls qualify;
a spy checks that the twin really ran, with two threads). The parallel call
fills its tables beforehand (``prefill_chain``) and the twin must then only
read them: checked by calling the kernels directly.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._engine import chain as _chain
from rbm_nb._engine import fused as _fused
from rbm_nb._infra import parallel as _parallel
from rbm_nb._kernels import chain_rows as kr
from rbm_nb._kernels import fused as kf
from rbm_nb.core import frames as _frames

pytestmark = pytest.mark.skipif(
    numba.config.NUMBA_NUM_THREADS < 2,  # type: ignore[attr-defined]
    reason="numba has a single thread here",
)


@numba.njit(parallel=True, cache=False)
def _thread_ids(n):
    out = np.empty(n, dtype=np.int64)
    for i in numba.prange(n):
        out[i] = numba.get_thread_id()
    return out


class _Spy:
    """Records each parallel twin call and the threads numba had for it."""

    def __init__(self, monkeypatch):
        self.calls: list[tuple[str, int]] = []
        for name in ("lookup_chain_parallel", "transform_chain_parallel"):
            monkeypatch.setattr(kf, name, self._wrap(name, getattr(kf, name)))

    def _wrap(self, name, kernel):
        def call(*args):
            self.calls.append((name, numba.get_num_threads()))
            return kernel(*args)

        return call


@pytest.fixture
def modes(monkeypatch, ignore_load):
    """``modes(fn)``: fn() run serially and in parallel, each on fresh tables."""
    spy = _Spy(monkeypatch)

    def run(fn):
        results = []
        for threads, min_rows in (("1", 10**12), ("2", 1)):
            _forget_tables()
            monkeypatch.setenv(_parallel.ENV_THREADS, threads)
            monkeypatch.setattr(_parallel, "MIN_ROWS", min_rows)
            before = len(spy.calls)
            results.append(fn())
            ran = spy.calls[before:]
            if threads == "1":
                assert not ran
            else:
                assert ran and all(n == 2 for _, n in ran), ran
        return results

    return run


def _forget_tables():
    """Empty every registered frame's squad table (as if just registered)."""
    for frame in _frames.registry.values():
        table = _fused._TABLES.get(frame.data.samples)
        if table is not None:
            table.clear()


def _identical(a, b):
    """Bit-identical arrays (NaN where NaN)."""
    for x, y in zip(a, b, strict=True):
        x, y = np.asarray(x), np.asarray(y)
        assert x.shape == y.shape and x.dtype == y.dtype
        np.testing.assert_array_equal(x.view(np.int64), y.view(np.int64))


def test_numba_runs_prange_loops_on_two_threads():
    numba.set_num_threads(2)
    try:
        assert len(set(_thread_ids(10_000).tolist())) == 2
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]


# ---------------------------------------------------------------------------
# random trees
# ---------------------------------------------------------------------------


def _rotations(rng, n, step):
    q = np.cumsum(rng.normal(scale=step, size=(n, 4)), axis=0) + [1.0, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[rng.random(n) < 0.2] *= -1.0  # stored signs flipped here and there
    return q


def _times(rng, n, rate, start, kind):
    t = start + np.arange(n) / rate + rng.uniform(0, 0.2 / rate, n)
    if kind == "float":
        return t
    ns = np.round(t * 1e9).astype(np.int64) + 1_580_603_234_300_365_210
    return ns.astype("datetime64[ns]")


def _with_nan_rows(rng, arr, count):
    arr = arr.copy()
    arr[rng.choice(len(arr), count, replace=False)] = np.nan
    return arr


def _tree(rng, kind, missing):
    """world -> a (moving) -> b (static) -> c (moving); d (discrete) -> e.

    Thousands of samples, so that calls span many chunks. With ``missing``,
    a and c have NaN rows and c long gaps beyond its ``max_gap``.
    """
    na, nc, nd = rng.integers(2000, 4000), rng.integers(3000, 6000), 40
    t_a, r_a = rng.normal(size=(na, 3)), _rotations(rng, na, 0.05)
    t_c, r_c = rng.normal(size=(nc, 3)), _rotations(rng, nc, 0.08)
    ts_c = _times(rng, nc, 31.3, 0.13, kind)
    if missing:
        t_a, r_a = _with_nan_rows(rng, t_a, 30), _with_nan_rows(rng, r_a, 40)
        t_c, r_c = _with_nan_rows(rng, t_c, 40), _with_nan_rows(rng, r_c, 30)
        gap = np.zeros(nc)
        gap[rng.choice(np.arange(1, nc), 20, replace=False)] = 0.1
        gap = np.cumsum(gap)
        ts_c = ts_c + (gap if kind == "float" else (gap * 1e9).astype("m8[ns]"))
    rbm.register_frame("world")
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
        timestamps=_times(rng, nd, 0.5, 0.05, kind),
        discrete=True,
    )
    rbm.register_frame(
        "e", parent="d", translation=rng.normal(size=3), rotation=(0.0, 0.0, 1.0, 0.0)
    )


# one, two and three moving frames, both directions, discrete ones included
PAIRS = [
    ("a", "world"),
    ("world", "a"),
    ("c", "world"),
    ("world", "c"),
    ("c", "a"),
    ("b", "world"),
    ("c", "e"),
    ("e", "c"),
    ("a", "e"),
]


def _engine_lookup(outof, into):
    a, b = _frames.resolve_frame(outof), _frames.resolve_frame(into)
    steps = _chain.chain(a, b)
    target = _chain.match([f for f, _ in steps])
    plan, own = _chain.fused_plan(steps, target)
    assert plan is not None
    return steps, target, plan, own


@pytest.mark.parametrize("missing", [False, True])
@pytest.mark.parametrize("kind", ["float", "datetime64"])
@pytest.mark.parametrize("seed", range(2))
def test_lookups_on_random_trees(modes, kind, seed, missing):
    rng = np.random.default_rng(seed)
    _tree(rng, kind, missing)
    nan_rows = 0
    for outof, into in PAIRS:
        _, target, plan, own = _engine_lookup(outof, into)
        assert len(target) > 10 * kr.BLOCK

        def lookup(plan=plan, target=target, own=own):
            t, r = _fused.lookup(plan, target, own)
            _, r_only = _fused.lookup(plan, target, own, rotation_only=True)
            return t, r, r_only

        serial, parallel = modes(lookup)
        _identical(serial, parallel)
        nan_rows += int(np.isnan(serial[1]).any(axis=1).sum())
    assert (nan_rows > 0) == missing


@pytest.mark.parametrize("missing", [False, True])
@pytest.mark.parametrize("kind", ["float", "datetime64"])
def test_transforms_on_random_trees(modes, kind, missing):
    rng = np.random.default_rng(40 + missing)
    _tree(rng, kind, missing)
    for outof, into in PAIRS:
        _, target, plan, own = _engine_lookup(outof, into)
        m = len(target)
        for what, size in (("points", 3), ("vectors", 3), ("quaternions", 4)):
            for rows in (m, 1):
                data = rng.normal(size=(rows, 2, size))
                if size == 4:
                    data /= np.linalg.norm(data, axis=-1, keepdims=True)
                serial, parallel = modes(
                    lambda data=data, what=what, plan=plan, target=target, own=own: (
                        _fused.transform(plan, target, own, data, what),
                    )
                )
                _identical(serial, parallel)


def test_public_calls_and_velocities(modes):
    """What users call, velocities included (they go through the fused chains)."""
    rng = np.random.default_rng(5)
    _tree(rng, "datetime64", True)
    ts = _frames.resolve_frame("c").timestamps[5:-5] + np.timedelta64(1234567, "ns")
    points = rng.normal(size=(len(ts), 3))

    def calls():
        return (
            *rbm.lookup_transform("c", "world")[:2],
            rbm.transform_points(points, "world", "c", timestamps=ts),
            rbm.transform_vectors(points, "e", "c", timestamps=ts),
            rbm.lookup_angular_velocity("c", "world"),
            rbm.lookup_linear_velocity("c", "world"),
            *rbm.lookup_twist("a", "c")[:2],
        )

    serial, parallel = modes(calls)
    _identical(serial, parallel)


# ---------------------------------------------------------------------------
# the kernels directly: unsorted targets, targets outside the samples, prefill
# ---------------------------------------------------------------------------


def _kernel_args(plan, offsets, own) -> tuple[Any, ...]:
    own_slots = np.zeros(kf.SLOTS, dtype=np.int64)
    own_slots[: len(own)] = own
    return (plan.code, plan.statics, offsets, plan.gaps(), own_slots) + plan.slots()


@pytest.mark.parametrize("seed", range(3))
def test_unsorted_targets_beyond_the_samples(seed):
    """Shuffled targets reaching before the first and after the last sample."""
    rng = np.random.default_rng(60 + seed)
    _tree(rng, "float", seed == 1)
    numba.set_num_threads(2)
    try:
        for outof, into in PAIRS:
            steps, target, plan, own = _engine_lookup(outof, into)
            base = target.track.base
            span = base[-1] - base[0]
            times = rng.uniform(base[0] - 0.2 * span, base[-1] + 0.2 * span, 20_000)
            if seed == 2:  # sorted runs, then shuffled blocks of them
                times = np.sort(times).reshape(40, -1)[rng.permutation(40)].ravel()
            args = _kernel_args(plan, np.zeros(kf.SLOTS), [False] * len(own))
            _forget_tables()
            t_s, r_s, _ = kf.lookup_chain(*(*args, times, False))
            rows_serial = [t.rows.copy() for t in plan.tables if t is not None]
            _forget_tables()
            filled, _ = kf.prefill_chain(*(*args, times))
            t_p, r_p, late = kf.lookup_chain_parallel(*(*args, times, False))
            assert late == 0  # the twin only read the tables
            _identical((t_s, r_s), (t_p, r_p))
            data = rng.normal(size=(len(times), 1, 3))
            out_p, late = kf.transform_chain_parallel(*(*args, times, data, 0))
            assert late == 0
            _forget_tables()
            out_s, _ = kf.transform_chain(*(*args, times, data, 0))
            _identical((out_s,), (out_p,))
            # every row the serial call computed, the prefill computed equally
            tables = [t for t in plan.tables if t is not None]
            assert (filled > 0) == bool(tables)
            for table, serial_rows in zip(tables, rows_serial, strict=True):
                done = serial_rows[:, -1] != 0.0
                _identical((table.rows[done],), (serial_rows[done],))
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]


def _one_moving_frame(rng, ts, max_gap=None):
    """The plan of frame "m" (random samples at ``ts``) in "world"."""
    n = len(ts)
    rbm.register_frame("world")
    rbm.register_frame(
        "m",
        parent="world",
        translation=rng.normal(size=(n, 3)),
        rotation=_rotations(rng, n, 0.05),
        timestamps=ts,
        max_gap=max_gap,
    )
    steps = _chain.chain(_frames.resolve_frame("m"), _frames.resolve_frame("world"))
    plan = _fused.plan(steps, _chain._compose_static)
    assert plan is not None
    return plan


def test_prefill_fills_only_the_segments_read():
    """A target range in the middle fills rows around it, not the whole table."""
    rng = np.random.default_rng(9)
    n = 20_000
    ts = np.arange(n) * 0.01
    plan = _one_moving_frame(rng, ts)
    table = plan.tables[0]
    assert table is not None
    args = _kernel_args(plan, np.zeros(kf.SLOTS), [False])
    times = np.linspace(50.0, 60.0, 30_000)  # segments 5000 .. 6000
    filled, intervals = kf.prefill_chain(*(*args, times))
    done = np.flatnonzero(table.rows[:, -1])
    assert filled == len(done) == 1001
    assert done[0] == 5000 and done[-1] == 6000
    assert intervals.tolist() == [[0, 5000, 6001]]
    # at the frame's own times (own = 1) no squad row is read at all
    table.rows[:] = 0.0
    own = np.array([1, 0, 0], dtype=np.int64)
    args = (plan.code, plan.statics, np.zeros(kf.SLOTS), plan.gaps(), own)
    assert kf.prefill_chain(*(*args, *plan.slots(), ts[100:9000].copy()))[0] == 0
    # a target before the first sample reads the last segment (n - 1)
    filled, intervals = kf.prefill_chain(
        *(*args, *plan.slots(), np.array([-1.0, 0.005]))
    )
    assert filled == 2 and intervals.tolist() == [[0, 0, 1], [0, n - 1, n]]
    assert np.flatnonzero(table.rows[:, -1]).tolist() == [0, n - 1]


def test_prefill_of_increasing_times_searches_instead_of_walking():
    """Increasing times take the rows between two searches per chunk, any
    other order a walk over the rows: the same rows here (a gap's row, which
    no time reads, is inside a short hole the walk's intervals fill too), and
    the same results as the serial kernel."""
    rng = np.random.default_rng(12)
    ts = np.arange(1000) * 0.01
    ts[500:] += 1.0  # samples 499 and 500 are 1.01 s apart
    plan = _one_moving_frame(rng, ts, max_gap=0.1)
    assert plan.tables[0] is not None
    args = _kernel_args(plan, np.zeros(kf.SLOTS), [False])
    times = np.linspace(4.0, 6.495, 2000)  # segments 400 .. 499 (the gap) .. 549
    assert ((times > ts[499]) & (times < ts[500])).any()
    numba.set_num_threads(2)
    rows = []
    try:
        for order in (np.arange(len(times)), rng.permutation(len(times))):
            _forget_tables()
            filled, intervals = kf.prefill_chain(*(*args, times[order]))
            rows.append(np.flatnonzero(plan.tables[0].rows[:, -1]))
            assert filled == len(rows[-1]) and intervals.tolist() == [[0, 400, 550]]
            t_p, r_p, late = kf.lookup_chain_parallel(*(*args, times[order], False))
            assert late == 0  # the prefill left no row the twin reads
            _forget_tables()
            _identical(kf.lookup_chain(*(*args, times[order], False))[:2], (t_p, r_p))
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    assert rows[0].tolist() == rows[1].tolist() == list(range(400, 550))
    # a chunk that starts inside the gap: the searches take the gap's row in,
    # the walk (any other order) leaves it out
    times = np.concatenate([[5.5], np.linspace(6.005, 6.495, 50)])
    for order, gap_row in ((slice(None), True), (slice(None, None, -1), False)):
        _forget_tables()
        kf.prefill_chain(*(*args, times[order].copy()))
        filled_rows = np.flatnonzero(plan.tables[0].rows[:, -1])
        assert (499 in filled_rows) == gap_row
        assert filled_rows[-1] == 549


# ---------------------------------------------------------------------------
# the real recording
# ---------------------------------------------------------------------------


def test_real_recording(modes, shared_data):
    xr = pytest.importorskip("xarray")
    head = xr.open_dataset(shared_data / "rbm-data" / "head.nc")
    eye = xr.open_dataset(shared_data / "rbm-data" / "left_eye.nc")
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
    # the eye tracker's missing samples stay in (NaN rows)
    rbm.register_frame(
        "left_eye",
        parent="scene_cam",
        rotation=eye.orientation.values,
        timestamps=eye.time.values,
    )
    gaze = np.random.default_rng(0).normal(size=(eye.sizes["time"], 3))

    def calls():
        return (
            *rbm.lookup_transform("left_eye", "world")[:2],
            *rbm.lookup_transform("world", "left_eye")[:2],
            *rbm.lookup_transform("head", "left_eye")[:2],
            rbm.transform_points(gaze, "world", "left_eye", timestamps=eye.time.values),
            rbm.transform_vectors(
                gaze[::2], "left_eye", "world", timestamps=eye.time.values[::2]
            ),
            rbm.lookup_angular_velocity("left_eye", "world"),
        )

    serial, parallel = modes(calls)
    assert np.isnan(serial[1]).any() and not np.isnan(serial[1]).all()
    _identical(serial, parallel)


def test_rows_known_to_be_filled_need_no_second_prefill(monkeypatch, ignore_load):
    """A parallel call records what its prefill filled; calls inside it skip the prefill."""
    rng = np.random.default_rng(10)
    n = 20_000
    rbm.register_frame("world")
    rbm.register_frame(
        "m",
        parent="world",
        translation=rng.normal(size=(n, 3)),
        rotation=_rotations(rng, n, 0.05),
        timestamps=np.arange(n) * 0.01,
    )
    prefills = []
    prefill = kf.prefill_chain

    def spy(*args):
        prefills.append(args[-1].shape[0])
        return prefill(*args)

    monkeypatch.setattr(kf, "prefill_chain", spy)
    monkeypatch.setattr(_parallel, "MIN_ROWS", 1)
    monkeypatch.setenv(_parallel.ENV_THREADS, "2")
    points = rng.normal(size=(3000, 3))

    def transform(lo, hi):
        ts = np.linspace(lo, hi, len(points))
        return rbm.transform_points(points, "world", "m", timestamps=ts)

    first = transform(50.0, 60.0)
    table = _fused._TABLES[_frames.resolve_frame("m").data.samples]
    assert prefills == [3000] and table.filled == [(5000, 6001)]
    assert not table.complete
    np.testing.assert_array_equal(transform(50.0, 60.0), first)
    transform(52.0, 58.5)  # inside: read-only, no lock, no prefill
    assert len(prefills) == 1
    transform(55.0, 70.0)  # beyond: the missing rows are filled, the record grows
    assert len(prefills) == 2 and table.filled == [(5000, 7001)]
    monkeypatch.setenv(_parallel.ENV_THREADS, "1")
    np.testing.assert_array_equal(transform(50.0, 60.0), first)  # serial reads too


def test_filled_intervals_merge_and_cover():
    table = _fused._Table(100)
    table.add(10, 20)
    table.add(30, 40)
    assert table.filled == [(10, 20), (30, 40)]
    assert table.covers(12, 20) and not table.covers(15, 35)
    table.add(20, 30)  # touching both: one interval
    assert table.filled == [(10, 40)] and table.covers(15, 35)
    table.add(0, 5)
    assert table.filled == [(0, 5), (10, 40)]
    assert not table.covers(0, 12)


def test_a_table_is_complete_by_the_kernels_count_or_by_a_scan(monkeypatch):
    """Long calls that may fill one table alone add the kernel's count of
    new rows (no pass over the table); once a short call filled rows of an
    unknown table, the next count is a scan. Either way ``complete`` says
    exactly whether every row is computed."""
    n = 12_000
    ts = np.arange(n) * 0.01
    _one_moving_frame(np.random.default_rng(13), ts)
    monkeypatch.setenv(_parallel.ENV_THREADS, "1")
    scans = []
    update = _fused._Table.update
    monkeypatch.setattr(
        _fused._Table, "update", lambda self: scans.append(1) or update(self)
    )
    long = max(_parallel.MIN_ROWS, 2 * n)

    def lookup(lo, hi, rows):
        points = np.zeros((rows, 3))
        rbm.transform_points(points, "world", "m", timestamps=np.linspace(lo, hi, rows))
        return _fused._TABLES[_frames.resolve_frame("m").data.samples]

    def scanned(table):
        return int(np.count_nonzero(table.rows[:, -1]))

    table = lookup(10.0, 50.0, long)  # segments 1000 .. 5000, and a run beyond
    assert table.counted and table.computed == scanned(table) > 4000
    assert not table.complete and scans == []
    table = lookup(0.0, ts[-1], long)  # every segment
    assert table.complete and table.computed == n == scanned(table)
    assert scans == []

    table.clear()
    lookup(30.0, 30.5, 3)  # a short call: rows filled, not counted
    assert not table.counted and scanned(table) > 0
    lookup(0.0, ts[-1], long)
    assert scans == [1]
    assert table.complete and table.counted and table.computed == n


def test_no_rows_and_fewer_rows_than_a_block():
    rng = np.random.default_rng(12)
    _tree(rng, "float", False)
    _, target, plan, own = _engine_lookup("c", "world")
    args = _kernel_args(plan, np.zeros(kf.SLOTS), [False] * len(own))
    for m in (0, 1, kr.BLOCK - 1, kr.BLOCK + 1):
        times = np.ascontiguousarray(target.track.base[:m])
        _forget_tables()
        serial = kf.lookup_chain(*(*args, times, False))[:2]
        kf.prefill_chain(*(*args, times))
        _identical(serial, kf.lookup_chain_parallel(*(*args, times, False))[:2])
