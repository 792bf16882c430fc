"""One block of a fused chain's output rows: every step of the chain over it.

A chain of frames between two frames is, once its static runs are composed,
``S0 M1 S1 M2 S2 ...``: static transforms ``S`` and up to :data:`SLOTS`
moving frames ``M`` (each possibly inverted). :func:`_chain_block` takes
the block's rows through each step in turn (the passes of
:mod:`.chain_rows`), leaving the block's transforms in the scratch.

A moving frame's arrays come in five tuples indexed by slot, one per
quantity (:data:`SLOT_TYPES`): sample times, translations, the sign codes
of the rotations free of sign flips (each row made from the stored one as
it is read: :mod:`.signed_rows`), rotations as stored, squad table. Changing :data:`SLOTS`
changes every kernel's declared signature with it.

For each row, a moving step finds the frame's segment (:func:`gallop`,
walking forward from the previous row's), then takes one of two routes:
the usual row (inside the samples, not one of the frame's own sample
times, not in a gap, a unit segment) is gathered for the vector squad pass;
any other row is evaluated at once by the general rules (constant and held
frames, own sample times, gaps, and by :func:`_squad_row` segments that are
not unit and times outside the samples). Both give a
row the same bits (tests/core/test_fused_rows.py).
"""

from __future__ import annotations

import math

from ._jit import F1, F2, S1, helper
from ._prefetch import prefetch
from .chain_rows import (
    _ACC,
    _DIV,
    _GATHERED,
    _GENERAL,
    _NEG,
    _P,
    _PATH,
    _Q,
    _STEP,
    _TAU,
    _TH1,
    _TH2,
    _U1,
    _U2,
    _WIDE_ROWS,
    AHEAD,
    BLOCK,
    _compose_rows,
    _compose_static_rows,
    _own_rows,
    _signed_unit_rows,
    _squad_rows,
    _wide_rows,
)
from .quaternion import _qslerp1, _qslerp_unit1, _sincos
from .scalar import SINCOS_LIMIT
from .search import gallop
from .signed_rows import signed_unit_row
from .squad_table import _DONE, DIVISOR_HIGH, RUN, TABLE_COLUMNS, _fill_run, is_unit

__all__ = ["SLOTS", "SLOT_TYPES", "STATIC", "SQUAD", "CONSTANT", "HELD"]

# moving frames a chain kernel takes; the one place to change it
SLOTS = 3
# the kinds of a plan's steps
STATIC = 0
SQUAD = 1
CONSTANT = 2
HELD = 3

# the declared types of the slot arguments: per quantity a tuple of SLOTS
# arrays (times, t, s, p, c). Tuples of arrays of one type: numba's prange
# passes them to its threads (a tuple of per-slot tuples it refuses).
SLOT_TYPES = (
    f"UniTuple({F1}, {SLOTS})",
    f"UniTuple({F2}, {SLOTS})",
    f"UniTuple({S1}, {SLOTS})",
    f"UniTuple({F2}, {SLOTS})",
    f"UniTuple({F2}, {SLOTS})",
)


@helper
def _chain_block(
    plan, statics, offsets, gaps, own, slot_times, slot_t, slot_s, slot_p, slot_c,
    target, j0, j1, work, cur, rotation_only,
):  # fmt: skip
    """The chain at target[j0:j1], into the scratch ``work`` (WORK * BLOCK,).

    Row b's transform (tx, ty, tz, w, x, y, z) ends in ``work[_ACC + q *
    BLOCK + b]`` for q = 0..6. ``cur`` (SLOTS,) holds each
    slot's segment of the previous row and is updated. Returns the number
    of squad table rows computed.
    """
    computed = 0
    nb = j1 - j0
    for q in range(j1, min(j1 + BLOCK, target.shape[0]), 8):
        prefetch(target, q)  # the next block's times (8 per cache line)
    if plan[2] != 0:
        # the identity, for a first step taken inverted (a first step taken
        # forward is written over the rows as it is)
        for b in range(BLOCK):
            work[_ACC + b] = 0.0
            work[_ACC + BLOCK + b] = 0.0
            work[_ACC + 2 * BLOCK + b] = 0.0
            work[_ACC + 3 * BLOCK + b] = 1.0
            work[_ACC + 4 * BLOCK + b] = 0.0
            work[_ACC + 5 * BLOCK + b] = 0.0
            work[_ACC + 6 * BLOCK + b] = 0.0
    for s in range(plan.shape[0] // 3):
        kind = plan[3 * s]
        slot = plan[3 * s + 1]
        inverse = plan[3 * s + 2] != 0
        # the chain's first step, forward, is its accumulated transform
        first = s == 0 and not inverse
        if kind == STATIC:
            _compose_static_rows(work, statics, slot, inverse, first, rotation_only)
            continue
        # the slot's arrays, picked once per block
        times, tr, sg = slot_times[slot], slot_t[slot], slot_s[slot]
        rp, c = slot_p[slot], slot_c[slot]
        off = offsets[slot]
        into = _ACC if first else _STEP
        i0 = own[slot] - 1 + j0
        if (
            kind == SQUAD
            and own[slot] != 0
            and off == 0.0
            and _own_rows(work, times, tr, rp, target, i0, j0, nb, rotation_only, into)
        ):
            cur[slot] = own[slot] - 1 + j1 - 1
            if not first:
                _compose_rows(work, inverse, False)
            continue
        i, filled = _moving_rows(
            kind, own[slot], gaps[slot], off, times, tr, sg, rp, c,
            target, j0, nb, work, cur[slot], rotation_only,
        )  # fmt: skip
        cur[slot] = i
        computed += filled
        _compose_rows(work, inverse, first)
    return computed


@helper
def _moving_rows(
    kind, own, gap, off, times, tr, sg, rp, c, target, j0, nb, work, i, rotation_only
):
    """A moving frame at target[j0:j0+nb] + off, into the step's rows.

    ``i``: the frame's segment at the previous row. Returns the segment at
    the block's last row and the number of squad table rows computed.

    Each row in one loop, without calls that take arrays (numba counts
    references of every array handed to a function, inlined or not: 10-25 %
    of a lookup through the head/eye chain when the two routes below were
    helpers): the usual row is gathered for the vector squad pass, any
    other row evaluated by the general rules (:func:`_squad_row` only for
    the rare rows outside the usual route of a continuous frame).
    """
    computed = 0
    n = times.shape[0]
    gathered = 0
    for b in range(nb):
        t = target[j0 + b] + off
        if kind == SQUAD:
            i = gallop(times, t, i)
            if 0 <= i < n - 1:
                if i + AHEAD < n:
                    # the segment of a row further on: its table row
                    # (15 values, over two cache lines) and samples
                    g = i + AHEAD
                    prefetch(c, TABLE_COLUMNS * g)
                    prefetch(c, TABLE_COLUMNS * g + 8)
                    prefetch(rp, 4 * g)
                    prefetch(tr, 3 * g)
                if c[i, _DONE] == 0.0:  # first use of the segment
                    computed += _fill_run(sg, rp, times, c, i, RUN)
                # the usual row, in few operations and branches: inside the
                # samples, not a sample time of the frame's own times nor
                # inside a gap, its segment's table row unit (the same
                # operations as the general rules below, which take the rest)
                ti = times[i]
                dt = times[i + 1] - ti
                at_sample = t == ti
                tau = (t - ti) / dt
                # a unit row whose state holds its sample's divisor
                # (squad_table: the usual rows of every registered frame)
                state = c[i, _DONE]
                if (
                    (not at_sample or own == 0)
                    and (at_sample or not dt > gap)
                    and abs(state) < DIVISOR_HIGH
                    and abs(tau * c[i, 4]) < SINCOS_LIMIT
                    and abs(tau * c[i, 9]) < SINCOS_LIMIT
                ):
                    work[_TAU + b] = tau
                    # the stored sample's sign
                    work[_NEG + b] = 1.0 if state < 0.0 else 0.0
                    work[_PATH + b] = _GATHERED
                    if rotation_only:
                        tx = ty = tz = 0.0
                    elif at_sample:
                        tx, ty, tz = tr[i, 0], tr[i, 1], tr[i, 2]
                    else:
                        tx = tr[i, 0] + tau * (tr[i + 1, 0] - tr[i, 0])
                        ty = tr[i, 1] + tau * (tr[i + 1, 1] - tr[i, 1])
                        tz = tr[i, 2] + tau * (tr[i + 1, 2] - tr[i, 2])
                    work[_TH1 + b] = c[i, 4]
                    work[_TH2 + b] = c[i, 9]
                    # r[i] as stored, and its signed divisor: made unit and
                    # signed for the whole block at once (_signed_unit_rows)
                    work[_DIV + b] = state
                    for e in range(4):
                        work[_P + e * BLOCK + b] = rp[i, e]
                        work[_U1 + e * BLOCK + b] = c[i, 5 + e]
                        work[_Q + e * BLOCK + b] = c[i, e]
                        work[_U2 + e * BLOCK + b] = c[i, 10 + e]
                    work[_STEP + b] = tx
                    work[_STEP + BLOCK + b] = ty
                    work[_STEP + 2 * BLOCK + b] = tz
                    gathered += 1
                    continue
        # the general rules
        tx = ty = tz = 0.0
        qw = qx = qy = qz = 0.0
        if kind == CONSTANT:
            if not rotation_only:
                tx, ty, tz = tr[0, 0], tr[0, 1], tr[0, 2]
            qw, qx, qy, qz = rp[0, 0], rp[0, 1], rp[0, 2], rp[0, 3]
        else:
            i = gallop(times, t, i)
            k = i if i >= 0 else 0
            if kind == HELD:
                if not rotation_only:
                    tx, ty, tz = tr[k, 0], tr[k, 1], tr[k, 2]
                qw, qx, qy, qz = rp[k, 0], rp[k, 1], rp[k, 2], rp[k, 3]
            elif own != 0 and i >= 0 and t == times[i]:
                # the frame's own times: the stored sample (NaN where it
                # is missing), whatever its neighbours
                qw, qx, qy, qz = rp[i, 0], rp[i, 1], rp[i, 2], rp[i, 3]
                if not rotation_only:
                    tx, ty, tz = tr[i, 0], tr[i, 1], tr[i, 2]
            elif 0 <= i < n - 1 and t != times[i] and times[i + 1] - times[i] > gap:
                # inside a gap longer than the frame's max_gap
                tx = ty = tz = qw = qx = qy = qz = math.nan
            else:
                tx, ty, tz, qw, qx, qy, qz, filled = _squad_row(
                    t, i, k, times, tr, sg, rp, c, rotation_only
                )
                computed += filled
        work[_PATH + b] = 0.0  # (evaluated here)
        work[_STEP + b] = tx
        work[_STEP + BLOCK + b] = ty
        work[_STEP + 2 * BLOCK + b] = tz
        work[_STEP + 3 * BLOCK + b] = qw
        work[_STEP + 4 * BLOCK + b] = qx
        work[_STEP + 5 * BLOCK + b] = qy
        work[_STEP + 6 * BLOCK + b] = qz
    for b in range(nb, BLOCK):  # past the end of a short last block
        work[_PATH + b] = 0.0
    wide = 0
    if gathered > 0:
        _signed_unit_rows(work)
        wide = _squad_rows(work)
    if wide >= _WIDE_ROWS:
        wide = _wide_rows(work)
    if wide > 0:
        _general_slerps(work, nb)
    return i, computed


@helper(inline=True)
def _squad_row(t, i, k, times, tr, sg, rp, c, rotation_only):
    """A continuous frame at t by the scalar route, any segment, any time.

    Linear translation and squad rotation in segment g (``i``, or the last
    segment before the start: numpy-quaternion indexes with -1), with the
    sign of the stored sample the segment starts from. Returns
    (tx, ty, tz, w, x, y, z, squad table rows computed).
    """
    computed = 0
    n = times.shape[0]
    tx = ty = tz = 0.0
    if k > n - 2:
        k = n - 2
    g = i if i >= 0 else n - 1
    if c[g, _DONE] == 0.0:  # first use of the segment
        computed += _fill_run(sg, rp, times, c, g, RUN)
    if g < n - 1:
        dt = times[g + 1] - times[g]
    else:
        dt = (times[n - 1] + (times[n - 1] - times[n - 2])) - times[n - 1]
    tau = (t - times[g]) / dt
    if not rotation_only and i >= 0 and t == times[i]:
        tx, ty, tz = tr[i, 0], tr[i, 1], tr[i, 2]
    elif not rotation_only:
        # inside the samples k == g: the translation's weight
        # is tau (the same operations)
        if 0 <= i < n - 1:
            w = tau
        else:
            w = (t - times[k]) / (times[k + 1] - times[k])
        tx = tr[k, 0] + w * (tr[k + 1, 0] - tr[k, 0])
        ty = tr[k, 1] + w * (tr[k + 1, 1] - tr[k, 1])
        tz = tr[k, 2] + w * (tr[k + 1, 2] - tr[k, 2])
    # the sign of the stored sample the segment starts from
    kw, kx, ky, kz = signed_unit_row(rp, sg, k)
    neg = (kw * rp[k, 0] + kx * rp[k, 1] + ky * rp[k, 2] + kz * rp[k, 3]) < 0.0
    rw, rx, ry, rz = signed_unit_row(rp, sg, g)
    # (rows inside the samples with a unit segment took the short route,
    # into the squad pass; here the rest, by the scalar route, which the
    # squad pass equals bit for bit: tests/core/test_fused_rows.py)
    if is_unit(c[g, _DONE]):
        sn, cs = _sincos(tau * c[g, 4])
        s1w = cs * rw + sn * c[g, 5]
        s1x = cs * rx + sn * c[g, 6]
        s1y = cs * ry + sn * c[g, 7]
        s1z = cs * rz + sn * c[g, 8]
        sn, cs = _sincos(tau * c[g, 9])
        s2w = cs * c[g, 0] + sn * c[g, 10]
        s2x = cs * c[g, 1] + sn * c[g, 11]
        s2y = cs * c[g, 2] + sn * c[g, 12]
        s2z = cs * c[g, 3] + sn * c[g, 13]
    else:  # not unit: b in columns 4:8
        if g < n - 1:
            nw, nx, ny, nz = signed_unit_row(rp, sg, g + 1)
        else:
            nw, nx, ny, nz = c[n - 1, 4], c[n - 1, 5], c[n - 1, 6], c[n - 1, 7]
        s1w, s1x, s1y, s1z = _qslerp1(rw, rx, ry, rz, nw, nx, ny, nz, tau)
        s2w, s2x, s2y, s2z = _qslerp1(
            c[g, 0], c[g, 1], c[g, 2], c[g, 3], c[g, 4], c[g, 5], c[g, 6], c[g, 7],
            tau,
        )  # fmt: skip
    qw, qx, qy, qz = _qslerp_unit1(
        s1w, s1x, s1y, s1z, s2w, s2x, s2y, s2z, 2.0 * tau * (1.0 - tau)
    )
    if neg:
        qw, qx, qy, qz = -qw, -qx, -qy, -qz
    if i >= 0 and t == times[i] and math.isnan(qw):
        # at a sample whose next one is missing (no segment
        # to evaluate): the sample itself
        qw, qx, qy, qz = rp[i, 0], rp[i, 1], rp[i, 2], rp[i, 3]
    return tx, ty, tz, qw, qx, qy, qz, computed


@helper
def _general_slerps(work, nb):
    """The outer slerps the vector passes left (marked ``_GENERAL``), one by one."""
    for b in range(nb):
        if work[_PATH + b] != _GENERAL:
            continue
        tau = work[_TAU + b]
        qw, qx, qy, qz = _qslerp_unit1(
            work[_P + b], work[_P + BLOCK + b], work[_P + 2 * BLOCK + b], work[_P + 3 * BLOCK + b],
            work[_Q + b], work[_Q + BLOCK + b], work[_Q + 2 * BLOCK + b], work[_Q + 3 * BLOCK + b],
            2.0 * tau * (1.0 - tau),
        )  # fmt: skip
        if work[_NEG + b] != 0.0:
            qw, qx, qy, qz = -qw, -qx, -qy, -qz
        work[_STEP + 3 * BLOCK + b] = qw
        work[_STEP + 4 * BLOCK + b] = qx
        work[_STEP + 5 * BLOCK + b] = qy
        work[_STEP + 6 * BLOCK + b] = qz
