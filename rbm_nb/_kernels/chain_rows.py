"""The fused chain's scratch of one block of rows, and the passes over it.

The chain kernels (:mod:`.fused`) evaluate their output rows in blocks of
:data:`BLOCK`; :mod:`.chain_block` runs each step of the chain over a block,
with the passes here: copying a frame's own samples (:func:`_own_rows`),
squad at the gathered rows (:func:`_squad_rows`, :func:`_wide_rows`),
composing a step into the block's transforms (:func:`_compose_rows`,
:func:`_compose_static_rows`), and writing the block's result
(:func:`_store_lookup`, :func:`_apply_block`). The layout of the scratch
``work`` is the offsets below.
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import helper
from ._prefetch import prefetch, prefetch_for_write
from .quaternion import _SQRT2, _is_unit, _qmul1, _rotate1
from .scalar import (
    SERIES_ANGLE,
    SERIES_RATIO,
    SINCOS_LIMIT,
    atan2,
    atan_over_x,
    cos_series,
    sinc_series,
    sincos,
)

__all__ = ["BLOCK", "AHEAD", "WORK"]
# Rows are evaluated in blocks: for each block, each step of the chain is
# applied to all its rows before the next step. The block's accumulated
# transforms stay in a small scratch array (in L1 cache), and a step's
# arrays are picked once per block, not once per row: numba counts
# references whenever an array is assigned or handed to a function, and
# per-row reference counting costs more than the arithmetic.
#
# The scratch ``work`` holds each quantity for the block's rows side by
# side (structure of arrays), so that the arithmetic of a step is a loop
# over contiguous rows without branches or calls, which LLVM vectorises (8
# rows per instruction with AVX-512). A moving step runs in passes: whole
# blocks at the frame's own sample times are copied (:func:`_own_rows`);
# otherwise a scalar pass finds each row's segment and either gathers its
# squad segment into the scratch (the usual row: inside the samples, no
# gap, a unit segment, in a short route of its own) or evaluates the row
# (held and constant frames, own sample times, gaps, segments that are not
# unit, arguments beyond the polynomial sine's range, times outside the
# samples); the vector pass :func:`_squad_rows` evaluates
# the gathered rows (both inner great circles and the outer slerp's
# small-arc series) and marks the rows whose outer slerp needs the general
# branch, which :func:`_wide_rows` (another vector pass, for blocks with
# many) and then a scalar pass (``_qslerp_unit1``) take;
# :func:`_compose_rows` composes the step into the block's transforms.
# Every row gets exactly the operations of the scalar code, in the same
# order (no fastmath): results are bit for bit those of a row-by-row loop
# (tests/core/test_fused_rows.py).
#
# 96 rows: the scratch (27 kB) and the rows streamed through stay in L1
# (256 rows were 1.4x slower, 64 rows 1.05x, 128 rows 1-2 % faster but
# their scratch, one per thread in the prange twins, took a 20k-row
# transform over 1.5x its output's memory).
BLOCK = 96

# Rows ahead whose samples the short route asks for (``_prefetch``). A
# lookup left_eye -> world on one thread, after 64 MB were streamed through
# the caches, took 3.1-3.3 ms with no hints; with hints 16 rows ahead
# 2.8 ms, 48 rows 2.7 ms (no better at 96).
AHEAD = 48

# ``work`` (WORK * BLOCK,): quantity q of row b at q * BLOCK + b. One flat
# array with fixed offsets (and loops over whole blocks), so that LLVM sees
# that the quantities do not overlap and vectorises without runtime checks.
# Every row a pass uses is written first; the vector passes also compute on
# the rows a block does not use (results kept, never read). So the scratch
# starts as zeros, not uninitialised: whatever the allocator hands back
# (denormal numbers, say) would be computed on at a hundred times the cost.
# A lookup of one time through the head/eye chain took 80 µs in the kernel
# with np.empty, 13 µs once a full block had left sane values there.
_ACC = 0  # 0:7 the block's accumulated transforms (tx, ty, tz, w, x, y, z)
_STEP = 7 * BLOCK  # 7:14 the step's transform at each row
_TAU = 14 * BLOCK  # squad's fraction τ of the row's segment g
_TH1 = 15 * BLOCK  # θ of the great circle r[g] -> r[g+1] (table column 4)
_TH2 = 16 * BLOCK  # θ of the great circle a[g] -> b[g] (table column 9)
# 17:21 r[g] (gathered as stored, made unit and signed by _signed_unit_rows);
# after the squad pass the inner slerp r[g] -> r[g+1]
_P = 17 * BLOCK
_U1 = 21 * BLOCK  # 21:25 u of the first great circle (table columns 5:9)
_Q = 25 * BLOCK  # 25:29 a[g]; after the squad pass the inner slerp a[g] -> b[g]
_U2 = 29 * BLOCK  # 29:33 u of the second great circle (table columns 10:14)
_NEG = 33 * BLOCK  # 1.0 where the result takes the opposite sign (the stored sample's)
# 1.0 rows gathered for the squad pass, 0.0 rows already evaluated; the
# squad pass turns 1.0 into 2.0 where the outer slerp needs the general route
_PATH = 34 * BLOCK
_DIV = 35 * BLOCK  # r[g]'s signed divisor (its squad table state, squad_table)
WORK = 36
_GATHERED = 1.0
_GENERAL = 2.0

# The chain's vector passes use the table fill's options (EXACT_VECTOR_KERNEL);
# their quaternion helpers are the ones of :mod:`.quaternion`, inlined with
# those options.
_rotate_rows = helper(inline=True, options=EXACT_VECTOR_KERNEL)(_rotate1.py_func)
_qmul_rows = helper(inline=True, options=EXACT_VECTOR_KERNEL)(_qmul1.py_func)
_is_unit_rows = helper(inline=True, options=EXACT_VECTOR_KERNEL)(_is_unit.py_func)


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _compose(ax, ay, az, aw, bx, by, bz, tx, ty, tz, qw, qx, qy, qz, inverse):
    """Accumulated transform followed by (t, q), as ``resample.chain_step``.

    Arguments: the accumulated translation (ax, ay, az) and rotation
    (aw, bx, by, bz), then the step's translation and rotation.
    """
    if inverse:
        x, y, z = _rotate_rows(qw, -qx, -qy, -qz, ax - tx, ay - ty, az - tz)
        k = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
        qw, qx, qy, qz = qw * k, -qx * k, -qy * k, -qz * k
    else:
        x, y, z = _rotate_rows(qw, qx, qy, qz, ax, ay, az)
        x += tx
        y += ty
        z += tz
    w, rx, ry, rz = _qmul_rows(qw, qx, qy, qz, aw, bx, by, bz)
    return x, y, z, w, rx, ry, rz


@helper(options=EXACT_VECTOR_KERNEL)
def _compose_rows(work, inverse, first):
    """The step's transforms (rows _STEP) composed into the block's (rows _ACC).

    Over the whole block (rows past the block's end hold stale values,
    never read). ``first``: the chain's first step, not inverted, is taken
    as it is (``chain.compose`` does the same).
    """
    a, s = _ACC, _STEP
    if first:
        for b in range(7 * BLOCK):
            work[a + b] = work[s + b]
        return
    for b in range(BLOCK):
        x, y, z, w, rx, ry, rz = _compose(
            work[a + b], work[a + BLOCK + b], work[a + 2 * BLOCK + b],
            work[a + 3 * BLOCK + b], work[a + 4 * BLOCK + b],
            work[a + 5 * BLOCK + b], work[a + 6 * BLOCK + b],
            work[s + b], work[s + BLOCK + b], work[s + 2 * BLOCK + b],
            work[s + 3 * BLOCK + b], work[s + 4 * BLOCK + b],
            work[s + 5 * BLOCK + b], work[s + 6 * BLOCK + b],
            inverse,
        )  # fmt: skip
        work[a + b] = x
        work[a + BLOCK + b] = y
        work[a + 2 * BLOCK + b] = z
        work[a + 3 * BLOCK + b] = w
        work[a + 4 * BLOCK + b] = rx
        work[a + 5 * BLOCK + b] = ry
        work[a + 6 * BLOCK + b] = rz


@helper(options=EXACT_VECTOR_KERNEL)
def _compose_static_rows(work, statics, k, inverse, first, rotation_only):
    """Static transform ``statics[k]`` composed into the block's (rows _ACC).

    :func:`_compose_rows` with the same step at every row, taken as scalars
    (no step rows written and read again).
    """
    tx, ty, tz = statics[k, 0], statics[k, 1], statics[k, 2]
    if rotation_only:
        tx = ty = tz = 0.0
    qw, qx, qy, qz = statics[k, 3], statics[k, 4], statics[k, 5], statics[k, 6]
    a = _ACC
    if first:
        for e, v in enumerate((tx, ty, tz, qw, qx, qy, qz)):
            for b in range(BLOCK):
                work[a + e * BLOCK + b] = v
        return
    for b in range(BLOCK):
        x, y, z, w, rx, ry, rz = _compose(
            work[a + b], work[a + BLOCK + b], work[a + 2 * BLOCK + b],
            work[a + 3 * BLOCK + b], work[a + 4 * BLOCK + b],
            work[a + 5 * BLOCK + b], work[a + 6 * BLOCK + b],
            tx, ty, tz, qw, qx, qy, qz, inverse,
        )  # fmt: skip
        work[a + b] = x
        work[a + BLOCK + b] = y
        work[a + 2 * BLOCK + b] = z
        work[a + 3 * BLOCK + b] = w
        work[a + 4 * BLOCK + b] = rx
        work[a + 5 * BLOCK + b] = ry
        work[a + 6 * BLOCK + b] = rz


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _arc_rows(work, theta, start, u):
    """Rows ``start`` (4 quantities) moved along their great circles towards ``u``.

    cos(τθ) start + sin(τθ) u, over the block, into the rows of ``start``.
    """
    for b in range(BLOCK):
        y = work[_TAU + b] * work[theta + b]
        # (in range for the gathered rows; the others, whatever the scratch
        # holds, are kept in it too: out of range sincos's rounding to an
        # integer would be undefined)
        sn, cs = sincos(y if abs(y) < SINCOS_LIMIT else 0.0)
        for e in range(4):
            work[start + e * BLOCK + b] = (
                cs * work[start + e * BLOCK + b] + sn * work[u + e * BLOCK + b]
            )


@helper(options=EXACT_VECTOR_KERNEL)
def _signed_unit_rows(work):
    """The gathered rows' r[g] (rows _P), from the stored rows gathered there
    and their signed divisors (row _DIV, the squad table's state):
    ``signed_rows.signed_unit_row``'s row, as sign * (p / d) = p / (sign * d)
    exactly, in a loop LLVM vectorises (the divisor read from the table, not
    made again from the row: its square root cost 1-2 % of a lookup through
    the head/eye chain). Rows not gathered keep their values (divided by 1)."""
    for b in range(BLOCK):
        d = work[_DIV + b] if work[_PATH + b] == _GATHERED else 1.0
        for e in range(4):
            work[_P + e * BLOCK + b] = work[_P + e * BLOCK + b] / d


@helper(options=EXACT_VECTOR_KERNEL)
def _squad_rows(work):
    """Squad at the gathered rows of the block, into their step rotations.

    Rows with ``work[_PATH + b] == _GATHERED``: the inner slerps along the
    segment's unit great circles (``sincos``, whose range the gathering
    checked), then ``_qslerp_unit1``'s small-arc branch, without branches;
    where that branch does not apply (an argument not unit, a wide arc),
    the row is marked ``_GENERAL``, its inner slerps kept in rows _P and _Q
    for the scalar route. Returns the number of rows marked.

    In several loops, each short: an iteration of one long loop would fill
    the processor's reorder window, and its long chains of dependent
    operations (the polynomials) would then run one after another.
    """
    # the inner slerps, into rows _P and _Q
    _arc_rows(work, _TH1, _P, _U1)
    _arc_rows(work, _TH2, _Q, _U2)
    # _qslerp_unit1(p, q, h): q taken the shorter way round; the arc's
    # d = p.q and the part o of q orthogonal to p (into rows _U1), the
    # conditions of its small-arc branch so far (into _TH1) and x² = tan²
    # of the arc (into _TH2), 1/d (into _U2)
    for b in range(BLOCK):
        aw, ax = work[_P + b], work[_P + BLOCK + b]
        ay, az = work[_P + 2 * BLOCK + b], work[_P + 3 * BLOCK + b]
        bw, bx = work[_Q + b], work[_Q + BLOCK + b]
        by, bz = work[_Q + 2 * BLOCK + b], work[_Q + 3 * BLOCK + b]
        unit = _is_unit_rows(aw, ax, ay, az) & _is_unit_rows(bw, bx, by, bz)
        dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
        far = dw * dw + dx * dx + dy * dy + dz * dz > _SQRT2 * _SQRT2
        cw = -bw if far else bw
        cx = -bx if far else bx
        cy = -by if far else by
        cz = -bz if far else bz
        d = aw * cw + ax * cx + ay * cy + az * cz
        ow, ox, oy, oz = cw - d * aw, cx - d * ax, cy - d * ay, cz - d * az
        o2 = ow * ow + ox * ox + oy * oy + oz * oz
        inv_d = 1.0 / d
        work[_U1 + b] = ow
        work[_U1 + BLOCK + b] = ox
        work[_U1 + 2 * BLOCK + b] = oy
        work[_U1 + 3 * BLOCK + b] = oz
        small = unit & (d > 0.0) & (o2 < (SERIES_RATIO * d) ** 2)
        work[_TH1 + b] = 1.0 if small else 0.0
        work[_TH2 + b] = o2 * inv_d * inv_d
        work[_U2 + b] = inv_d
    # the series, and the result where they apply
    general = 0
    for b in range(BLOCK):
        tau = work[_TAU + b]
        h = 2.0 * tau * (1.0 - tau)
        x2 = work[_TH2 + b]
        p = atan_over_x(x2)
        y2 = h * h * x2 * p * p
        c = cos_series(y2)
        k = sinc_series(y2) * h * p * work[_U2 + b]
        sign = -1.0 if work[_NEG + b] != 0.0 else 1.0
        series = (work[_TH1 + b] != 0.0) & (y2 < SERIES_ANGLE * SERIES_ANGLE)
        gathered = work[_PATH + b] == _GATHERED
        done = gathered & series
        redo = gathered & ~series
        general += redo
        # only the gathered rows change (the others were evaluated already)
        for e in range(4):
            q = c * work[_P + e * BLOCK + b] + k * work[_U1 + e * BLOCK + b]
            q = -q if sign < 0.0 else q
            at = _STEP + (3 + e) * BLOCK + b
            work[at] = q if done else work[at]
        work[_PATH + b] = _GENERAL if redo else work[_PATH + b]
    return general


# A block with at least this many outer slerps off the small-arc series
# takes them in a vector pass (:func:`_wide_rows`), fewer one by one.
_WIDE_ROWS = 8


@helper(options=EXACT_VECTOR_KERNEL)
def _wide_rows(work):
    """The outer slerps marked ``_GENERAL``, along their great circles.

    ``_qslerp_unit1``'s general branch (with ``_geodesic1``), without
    branches, for the rows whose arguments (rows _P and _Q) are unit, not
    equal and whose angle is in ``sincos``'s range; their rotations go into
    the step's rows and their mark is lifted. Returns the number of rows
    left marked (for the scalar route).
    """
    left = 0
    for b in range(BLOCK):
        aw, ax = work[_P + b], work[_P + BLOCK + b]
        ay, az = work[_P + 2 * BLOCK + b], work[_P + 3 * BLOCK + b]
        bw, bx = work[_Q + b], work[_Q + BLOCK + b]
        by, bz = work[_Q + 2 * BLOCK + b], work[_Q + 3 * BLOCK + b]
        unit = _is_unit_rows(aw, ax, ay, az) & _is_unit_rows(bw, bx, by, bz)
        # the shorter way round, tested by _qslerp_unit1 and again by
        # _geodesic1
        for _ in range(2):
            dw, dx, dy, dz = aw - bw, ax - bx, ay - by, az - bz
            far = dw * dw + dx * dx + dy * dy + dz * dz > _SQRT2 * _SQRT2
            bw = -bw if far else bw
            bx = -bx if far else bx
            by = -by if far else by
            bz = -bz if far else bz
        d = aw * bw + ax * bx + ay * by + az * bz
        ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
        so = math.sqrt(ow * ow + ox * ox + oy * oy + oz * oz)
        k = 1.0 / so
        theta = atan2(so, d)
        tau = work[_TAU + b]
        h = 2.0 * tau * (1.0 - tau)
        y = h * theta
        sn, cs = sincos(y if abs(y) < SINCOS_LIMIT else 0.0)  # (as in _arc_rows)
        sign = -1.0 if work[_NEG + b] != 0.0 else 1.0
        wide = work[_PATH + b] == _GENERAL
        done = wide & unit & (so != 0.0) & (abs(y) < SINCOS_LIMIT)
        left += wide & ~done
        for e, (a_e, o_e) in enumerate(((aw, ow), (ax, ox), (ay, oy), (az, oz))):
            q = cs * a_e + sn * (o_e * k)
            q = -q if sign < 0.0 else q
            at = _STEP + (3 + e) * BLOCK + b
            work[at] = q if done else work[at]
        work[_PATH + b] = _GATHERED if done else work[_PATH + b]
    return left


@helper(options=EXACT_VECTOR_KERNEL)
def _own_rows(work, times, tr, rp, target, i0, j0, nb, rotation_only, into):
    """Rows j0 .. j0+nb at the frame's own samples i0 .., copied into the step.

    The scalar pass's own-times rule for a whole block at once, in loops
    LLVM vectorises: taken when the block's target times are exactly
    times[i0:i0+nb], so that every row is its stored sample (a missing
    sample's NaN included). ``into``: the scratch's rows to write (_STEP,
    or _ACC for the chain's first step). Returns False otherwise, and the
    scalar pass takes the block (the rows written here are then all written
    again).
    """
    n = times.shape[0]
    if i0 < 0 or j0 < 0 or i0 + nb > n:
        return False
    rf = rp.reshape(-1)
    tf = tr.reshape(-1)
    # the next block's samples, on their way while this block is copied
    ahead = min(n - (i0 + nb), BLOCK)
    for q in range(0, 4 * ahead, 8):
        prefetch(rf, 4 * (i0 + nb) + q)
    if not rotation_only:
        for q in range(0, 3 * ahead, 8):
            prefetch(tf, 3 * (i0 + nb) + q)
    for q in range(0, ahead, 8):
        prefetch(times, i0 + nb + q)
    # (loop counters from 0 and bases known non-negative: LLVM vectorises
    # only loops whose indices it can bound)
    odd = 0
    for b in range(nb):
        odd += np.int64(target[j0 + b] != times[i0 + b])
    if odd != 0:
        return False
    for b in range(nb):
        k = 4 * (i0 + b)
        work[into + 3 * BLOCK + b] = rf[k]
        work[into + 4 * BLOCK + b] = rf[k + 1]
        work[into + 5 * BLOCK + b] = rf[k + 2]
        work[into + 6 * BLOCK + b] = rf[k + 3]
    if rotation_only:
        for b in range(3 * BLOCK):
            work[into + b] = 0.0
    else:
        for b in range(nb):
            k = 3 * (i0 + b)
            work[into + b] = tf[k]
            work[into + BLOCK + b] = tf[k + 1]
            work[into + 2 * BLOCK + b] = tf[k + 2]
    for b in range(BLOCK):
        work[_PATH + b] = 0.0
    return True


@helper
def _store_lookup(work, t_out, r_out, j0, j1, rotation_only):
    """Rows j0:j1 of a lookup's result from the block's transforms in ``work``."""
    nb = j1 - j0
    # the next block's rows, to be written (their lines fetched meanwhile)
    m = r_out.shape[0]
    for q in range(4 * j1, 4 * min(j1 + BLOCK, m), 8):
        prefetch_for_write(r_out, q)
    if not rotation_only:
        for q in range(3 * j1, 3 * min(j1 + BLOCK, m), 8):
            prefetch_for_write(t_out, q)
    # flat views of the block's rows: constant strides, so that the copy
    # from the scratch's columns vectorises (LLVM's interleaved stores)
    r = r_out.reshape(-1)[4 * j0 : 4 * j1]
    for b in range(nb):
        r[4 * b] = work[_ACC + 3 * BLOCK + b]
        r[4 * b + 1] = work[_ACC + 4 * BLOCK + b]
        r[4 * b + 2] = work[_ACC + 5 * BLOCK + b]
        r[4 * b + 3] = work[_ACC + 6 * BLOCK + b]
    if not rotation_only:
        t = t_out.reshape(-1)[3 * j0 : 3 * j1]
        for b in range(nb):
            t[3 * b] = work[_ACC + b]
            t[3 * b + 1] = work[_ACC + BLOCK + b]
            t[3 * b + 2] = work[_ACC + 2 * BLOCK + b]


@helper(options=EXACT_VECTOR_KERNEL)
def _apply_rows(work, d, out, nb, mode):
    """:func:`_apply_block` for one item per row: ``d`` and ``out`` (nb * c,) flat."""
    w, x, y, z = _ACC + 3 * BLOCK, _ACC + 4 * BLOCK, _ACC + 5 * BLOCK, _ACC + 6 * BLOCK
    if mode == 2:
        for b in range(nb):
            ow, ox, oy, oz = _qmul_rows(
                work[w + b], work[x + b], work[y + b], work[z + b],
                d[4 * b], d[4 * b + 1], d[4 * b + 2], d[4 * b + 3],
            )  # fmt: skip
            out[4 * b] = ow
            out[4 * b + 1] = ox
            out[4 * b + 2] = oy
            out[4 * b + 3] = oz
        return
    for b in range(nb):
        px, py, pz = _rotate_rows(
            work[w + b], work[x + b], work[y + b], work[z + b],
            d[3 * b], d[3 * b + 1], d[3 * b + 2],
        )  # fmt: skip
        if mode == 0:
            px += work[_ACC + b]
            py += work[_ACC + BLOCK + b]
            pz += work[_ACC + 2 * BLOCK + b]
        out[3 * b] = px
        out[3 * b + 1] = py
        out[3 * b + 2] = pz


@helper
def _apply_block(work, data, out, j0, j1, mode):
    """Rows j0:j1 of ``data`` carried by the block's transforms in ``work``.

    ``data`` (m|1, k, c) as for :func:`transform_chain`.
    """
    k = data.shape[1]
    # the next block's items (unless one is reused for every row) and results
    # (as _store_lookup)
    w = k * data.shape[2]
    m = out.shape[0]
    per_row = data.shape[0] > 1
    for q in range(w * j1, w * min(j1 + BLOCK, m), 8):
        if per_row:
            prefetch(data, q)
        prefetch_for_write(out, q)
    if k == 1 and data.shape[0] > 1:
        # one item per row (the usual case): flat views, vectorised
        c = data.shape[2]
        d = data.reshape(-1)[c * j0 : c * j1]
        _apply_rows(work, d, out.reshape(-1)[c * j0 : c * j1], j1 - j0, mode)
        return
    s_d = 1 if data.shape[0] > 1 else 0
    for b in range(j1 - j0):
        j = j0 + b
        row = j * s_d
        w, qx, qy, qz = (
            work[_ACC + 3 * BLOCK + b],
            work[_ACC + 4 * BLOCK + b],
            work[_ACC + 5 * BLOCK + b],
            work[_ACC + 6 * BLOCK + b],
        )
        if mode == 2:
            for e in range(k):
                ow, ox, oy, oz = _qmul1(
                    w, qx, qy, qz, data[row, e, 0], data[row, e, 1],
                    data[row, e, 2], data[row, e, 3],
                )  # fmt: skip
                out[j, e, 0] = ow
                out[j, e, 1] = ox
                out[j, e, 2] = oy
                out[j, e, 3] = oz
        else:
            for e in range(k):
                px, py, pz = _rotate1(
                    w, qx, qy, qz, data[row, e, 0], data[row, e, 1], data[row, e, 2]
                )
                if mode == 0:
                    px += work[_ACC + b]
                    py += work[_ACC + BLOCK + b]
                    pz += work[_ACC + 2 * BLOCK + b]
                out[j, e, 0] = px
                out[j, e, 1] = py
                out[j, e, 2] = pz
