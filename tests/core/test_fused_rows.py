"""The fused kernels' vector passes give the scalar route's rotations, bit for bit.

``_squad_rows`` (inner great circles and the outer slerp's small-arc series)
and ``_wide_rows`` (the outer slerp's general branch) evaluate a block of
gathered squad rows without branches; the rows they cannot take are left
marked for the scalar route. Here blocks of random segments (short and
wide arcs, extrapolated fractions, equal and opposite arguments, arguments
that are not unit, NaN) go through the passes as ``_chain_block`` sends
them, and every row is compared with the scalar route (``_sincos``,
``_qslerp_unit1``), which the kernels used for every row before.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest

from rbm_nb._engine.frame_data import _sign_codes
from rbm_nb._kernels import chain_rows as kr
from rbm_nb._kernels import fused as kf
from rbm_nb._kernels.quaternion import _qslerp_unit1, _sincos

B = kr.BLOCK


@numba.njit(cache=False)
def _scalar_route(w, out):
    """Each gathered row by the scalar route, into out (4, BLOCK)."""
    for b in range(B):
        tau = w[kr._TAU + b]
        sn, cs = _sincos(tau * w[kr._TH1 + b])
        s1 = [cs * w[kr._P + e * B + b] + sn * w[kr._U1 + e * B + b] for e in range(4)]
        sn, cs = _sincos(tau * w[kr._TH2 + b])
        s2 = [cs * w[kr._Q + e * B + b] + sn * w[kr._U2 + e * B + b] for e in range(4)]
        q = _qslerp_unit1(
            s1[0], s1[1], s1[2], s1[3], s2[0], s2[1], s2[2], s2[3],
            2.0 * tau * (1.0 - tau),
        )  # fmt: skip
        for e in range(4):
            out[e, b] = -q[e] if w[kr._NEG + b] != 0.0 else q[e]


@numba.njit(cache=False)
def _vector_route(w, wide_pass):
    """The passes as ``_chain_block`` runs them; returns rows per route."""
    wide = kr._squad_rows(w)
    marked = wide
    if wide_pass:
        wide = kr._wide_rows(w)
    for b in range(B):
        if w[kr._PATH + b] != kr._GENERAL:
            continue
        tau = w[kr._TAU + b]
        q = _qslerp_unit1(
            w[kr._P + b], w[kr._P + B + b], w[kr._P + 2 * B + b], w[kr._P + 3 * B + b],
            w[kr._Q + b], w[kr._Q + B + b], w[kr._Q + 2 * B + b], w[kr._Q + 3 * B + b],
            2.0 * tau * (1.0 - tau),
        )  # fmt: skip
        for e in range(4):
            w[kr._STEP + (3 + e) * B + b] = -q[e] if w[kr._NEG + b] != 0.0 else q[e]
    return marked, wide


def _unit(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def _orthogonal_unit(rng, p):
    """Unit quaternions orthogonal to the rows of p."""
    u = rng.normal(size=p.shape)
    u -= np.sum(u * p, axis=1)[:, None] * p
    return u / np.linalg.norm(u, axis=1)[:, None]


def _block(rng, arc):
    """A block of gathered rows: segments with arcs of about ``arc`` radians."""
    w = np.zeros(kr.WORK * B)
    rows = {
        kr._P: _unit(rng, B),
        kr._Q: _unit(rng, B),
    }
    rows[kr._U1] = _orthogonal_unit(rng, rows[kr._P])
    rows[kr._U2] = _orthogonal_unit(rng, rows[kr._Q])
    # the second circle starts near the first (as squad's a[g] near r[g])
    rows[kr._Q] = rows[kr._P] + arc * rng.normal(size=(B, 4))
    rows[kr._Q] /= np.linalg.norm(rows[kr._Q], axis=1)[:, None]
    rows[kr._U2] = _orthogonal_unit(rng, rows[kr._Q])
    rows[kr._Q][0] = rows[kr._P][0]  # equal starts
    rows[kr._Q][1] = -rows[kr._P][1]  # opposite starts
    rows[kr._Q][2] *= 1.001  # not unit
    rows[kr._P][3] = np.nan  # a missing sample
    for start, values in rows.items():
        for e in range(4):
            w[start + e * B : start + (e + 1) * B] = values[:, e]
    w[kr._TH1 : kr._TH1 + B] = rng.uniform(0.0, arc, B)
    w[kr._TH2 : kr._TH2 + B] = rng.uniform(0.0, arc, B)
    w[kr._TH1 + 4] = 0.0
    # fractions inside the segment, extrapolated, and far out
    tau = rng.uniform(0.0, 1.0, B)
    tau[::7] = rng.uniform(-3.0, 4.0, tau[::7].shape)
    tau[5] = 1e6
    w[kr._TH1 + 5] = w[kr._TH2 + 5] = 0.0
    w[kr._TAU : kr._TAU + B] = tau
    w[kr._NEG : kr._NEG + B] = rng.random(B) < 0.5
    # rows are gathered only while the inner angles are in sincos's range
    in_range = (
        np.maximum(
            abs(tau * w[kr._TH1 : kr._TH1 + B]), abs(tau * w[kr._TH2 : kr._TH2 + B])
        )
        < kr.SINCOS_LIMIT
    )
    path = np.where((rng.random(B) < 0.9) & in_range, kr._GATHERED, 0.0)
    w[kr._PATH : kr._PATH + B] = path
    # rows not gathered keep what the scalar pass wrote
    w[kr._STEP + 3 * B : kr._STEP + 7 * B] = rng.normal(size=4 * B)
    return w


@pytest.mark.parametrize("arc", [1e-3, 0.02, 0.3, 1.5, 3.0])
@pytest.mark.parametrize("wide_pass", [False, True])
def test_vector_passes_give_the_scalar_route(arc, wide_pass):
    rng = np.random.default_rng(int(arc * 1000) + wide_pass)
    counts = np.zeros(3, dtype=np.int64)
    for _ in range(20):
        w = _block(rng, arc)
        gathered = w[kr._PATH : kr._PATH + B] == kr._GATHERED
        before = w[kr._STEP + 3 * B : kr._STEP + 7 * B].reshape(4, B).copy()
        want = np.empty((4, B))
        _scalar_route(w.copy(), want)
        marked, left = _vector_route(w, wide_pass)
        got = w[kr._STEP + 3 * B : kr._STEP + 7 * B].reshape(4, B)
        np.testing.assert_array_equal(got[:, gathered], want[:, gathered])
        np.testing.assert_array_equal(got[:, ~gathered], before[:, ~gathered])
        counts += (gathered.sum() - marked, marked - left, left)
    # every route was taken: the series, the vector general branch (when
    # run), the scalar route
    assert counts[0] > 0 or arc > 1.0
    assert counts[2] > 0
    if wide_pass and arc >= 0.3:
        assert counts[1] > 0


# ---------------------------------------------------------------------------
# the frame's own sample times: whole blocks copied (``_own_rows``)
# ---------------------------------------------------------------------------


@numba.njit(cache=False)
def _own_blocks(times, t, r, target, i0, rotation_only):
    """``_own_rows`` over the target's blocks: (steps (m, 7), taken (blocks,))."""
    m = target.shape[0]
    w = np.empty(kr.WORK * B)
    out = np.full((m, 7), np.nan)
    taken = np.zeros((m + B - 1) // B, dtype=np.bool_)
    for j0 in range(0, m, B):
        nb = min(B, m - j0)
        taken[j0 // B] = kr._own_rows(
            w, times, t, r, target, i0 + j0, j0, nb, rotation_only, kr._STEP
        )
        if taken[j0 // B]:
            for e in range(7):
                for b in range(nb):
                    out[j0 + b, e] = w[kr._STEP + e * B + b]
    return out, taken


def _own_frame(n, rng):
    times = np.cumsum(rng.uniform(0.5, 1.5, n))
    t = rng.normal(size=(n, 3))
    r = _unit(rng, n)
    return times, t, r


@pytest.mark.parametrize("rotation_only", [False, True])
def test_own_blocks_are_the_stored_samples_or_left_to_the_scalar_pass(rotation_only):
    rng = np.random.default_rng(5)
    n = 10 * B + 17
    times, t, r = _own_frame(n, rng)
    # missing samples next to and inside blocks: a row is its stored sample
    # whatever its neighbours (issue 28), so they change nothing here
    r[3 * B + 1] = np.nan
    t[5 * B - 1] = np.nan
    r[7 * B + 40] = np.nan
    start = 30
    target = times[start : start + 9 * B].copy()
    target[8 * B + 3] += 1e-9  # not a sample time
    steps, taken = _own_blocks(times, t, r, target, start, rotation_only)
    # the blocks that are not all samples are left to the scalar pass
    want_taken = []
    for j0 in range(0, len(target), B):
        i = np.arange(start + j0, start + min(j0 + B, len(target)))
        want_taken.append(np.array_equal(target[i - start], times[i]))
    np.testing.assert_array_equal(taken, want_taken)
    assert taken.sum() == 8 and (~taken).sum() == 1
    rows = np.repeat(taken, B)[: len(target)]
    i = np.arange(start, start + len(target))[rows]
    want_t = np.zeros((len(i), 3)) if rotation_only else t[i]
    np.testing.assert_array_equal(steps[rows, :3], want_t)
    np.testing.assert_array_equal(steps[rows, 3:], r[i])
    # a run that would end past the samples, or start before them
    assert not _own_blocks(times, t, r, times[n - 50 :], n - 40, False)[1].any()
    assert not _own_blocks(times, t, r, times[:50], -1, False)[1].any()


@pytest.mark.parametrize("missing", [False, True])
def test_own_runs_give_the_scalar_own_rule_bit_for_bit(missing):
    """A lookup told the right first sample equals one told a wrong one
    (which the scalar pass takes), and both are the own-times rule."""
    from rbm_nb._engine import fused as _fused

    rng = np.random.default_rng(6)
    n = 20 * B + 5
    times, t, r = _own_frame(n, rng)
    if missing:
        for k in rng.choice(n, 12, replace=False):
            (r if k % 2 else t)[k] = np.nan
    plan = np.array([kf.SQUAD, 0, 0], dtype=np.int64)
    table = np.zeros((n, kf.TABLE_COLUMNS))
    empty = _fused._EMPTY_SLOT
    start = 7
    target = times[start : n - 3]
    results = []
    for own in (start + 1, start + 2):
        slots = kf.pack_slots([(times, t, _sign_codes(r, r), r, table), empty, empty])
        got = kf.lookup_chain(
            plan, np.zeros((1, 7)), np.zeros(kf.SLOTS), np.full(kf.SLOTS, np.inf),
            np.array([own, 0, 0]), *slots, target, False,
        )  # fmt: skip
        results.append(got[:2])
    for a, b in zip(results[0], results[1], strict=True):
        np.testing.assert_array_equal(a, b)
    # the rule: the stored sample, NaN only where it is missing itself
    i = np.arange(start, n - 3)
    np.testing.assert_array_equal(results[0][0], t[i])
    np.testing.assert_array_equal(results[0][1], r[i])
    assert np.isnan(r[i]).any() == missing
