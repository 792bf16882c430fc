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

from rbm_nb._kernels import fused as kf
from rbm_nb._kernels.quaternion import _qslerp_unit1, _sincos

B = kf.BLOCK


@numba.njit(cache=False)
def _scalar_route(w, out):
    """Each gathered row by the scalar route, into out (4, BLOCK)."""
    for b in range(B):
        tau = w[kf._TAU + b]
        sn, cs = _sincos(tau * w[kf._TH1 + b])
        s1 = [cs * w[kf._P + e * B + b] + sn * w[kf._U1 + e * B + b] for e in range(4)]
        sn, cs = _sincos(tau * w[kf._TH2 + b])
        s2 = [cs * w[kf._Q + e * B + b] + sn * w[kf._U2 + e * B + b] for e in range(4)]
        q = _qslerp_unit1(
            s1[0], s1[1], s1[2], s1[3], s2[0], s2[1], s2[2], s2[3],
            2.0 * tau * (1.0 - tau),
        )  # fmt: skip
        for e in range(4):
            out[e, b] = -q[e] if w[kf._NEG + b] != 0.0 else q[e]


@numba.njit(cache=False)
def _vector_route(w, wide_pass):
    """The passes as ``_chain_block`` runs them; returns rows per route."""
    wide = kf._squad_rows(w)
    marked = wide
    if wide_pass:
        wide = kf._wide_rows(w)
    for b in range(B):
        if w[kf._PATH + b] != kf._GENERAL:
            continue
        tau = w[kf._TAU + b]
        q = _qslerp_unit1(
            w[kf._P + b], w[kf._P + B + b], w[kf._P + 2 * B + b], w[kf._P + 3 * B + b],
            w[kf._Q + b], w[kf._Q + B + b], w[kf._Q + 2 * B + b], w[kf._Q + 3 * B + b],
            2.0 * tau * (1.0 - tau),
        )  # fmt: skip
        for e in range(4):
            w[kf._STEP + (3 + e) * B + b] = -q[e] if w[kf._NEG + b] != 0.0 else q[e]
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
    w = np.zeros(kf.WORK * B)
    rows = {
        kf._P: _unit(rng, B),
        kf._Q: _unit(rng, B),
    }
    rows[kf._U1] = _orthogonal_unit(rng, rows[kf._P])
    rows[kf._U2] = _orthogonal_unit(rng, rows[kf._Q])
    # the second circle starts near the first (as squad's a[g] near r[g])
    rows[kf._Q] = rows[kf._P] + arc * rng.normal(size=(B, 4))
    rows[kf._Q] /= np.linalg.norm(rows[kf._Q], axis=1)[:, None]
    rows[kf._U2] = _orthogonal_unit(rng, rows[kf._Q])
    rows[kf._Q][0] = rows[kf._P][0]  # equal starts
    rows[kf._Q][1] = -rows[kf._P][1]  # opposite starts
    rows[kf._Q][2] *= 1.001  # not unit
    rows[kf._P][3] = np.nan  # a missing sample
    for start, values in rows.items():
        for e in range(4):
            w[start + e * B : start + (e + 1) * B] = values[:, e]
    w[kf._TH1 : kf._TH1 + B] = rng.uniform(0.0, arc, B)
    w[kf._TH2 : kf._TH2 + B] = rng.uniform(0.0, arc, B)
    w[kf._TH1 + 4] = 0.0
    # fractions inside the segment, extrapolated, and far out
    tau = rng.uniform(0.0, 1.0, B)
    tau[::7] = rng.uniform(-3.0, 4.0, tau[::7].shape)
    tau[5] = 1e6
    w[kf._TH1 + 5] = w[kf._TH2 + 5] = 0.0
    w[kf._TAU : kf._TAU + B] = tau
    w[kf._NEG : kf._NEG + B] = rng.random(B) < 0.5
    # rows are gathered only while the inner angles are in sincos's range
    in_range = (
        np.maximum(
            abs(tau * w[kf._TH1 : kf._TH1 + B]), abs(tau * w[kf._TH2 : kf._TH2 + B])
        )
        < kf.SINCOS_LIMIT
    )
    path = np.where((rng.random(B) < 0.9) & in_range, kf._GATHERED, 0.0)
    w[kf._PATH : kf._PATH + B] = path
    # rows not gathered keep what the scalar pass wrote
    w[kf._STEP + 3 * B : kf._STEP + 7 * B] = rng.normal(size=4 * B)
    return w


@pytest.mark.parametrize("arc", [1e-3, 0.02, 0.3, 1.5, 3.0])
@pytest.mark.parametrize("wide_pass", [False, True])
def test_vector_passes_give_the_scalar_route(arc, wide_pass):
    rng = np.random.default_rng(int(arc * 1000) + wide_pass)
    counts = np.zeros(3, dtype=np.int64)
    for _ in range(20):
        w = _block(rng, arc)
        gathered = w[kf._PATH : kf._PATH + B] == kf._GATHERED
        before = w[kf._STEP + 3 * B : kf._STEP + 7 * B].reshape(4, B).copy()
        want = np.empty((4, B))
        _scalar_route(w.copy(), want)
        marked, left = _vector_route(w, wide_pass)
        got = w[kf._STEP + 3 * B : kf._STEP + 7 * B].reshape(4, B)
        np.testing.assert_array_equal(got[:, gathered], want[:, gathered])
        np.testing.assert_array_equal(got[:, ~gathered], before[:, ~gathered])
        counts += (gathered.sum() - marked, marked - left, left)
    # every route was taken: the series, the vector general branch (when
    # run), the scalar route
    assert counts[0] > 0 or arc > 1.0
    assert counts[2] > 0
    if wide_pass and arc >= 0.3:
        assert counts[1] > 0
