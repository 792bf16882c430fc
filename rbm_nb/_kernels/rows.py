"""Validation of sample rows in one pass (frames' data at registration).

The numpy versions in :mod:`rbm_nb._door.validation` make several temporaries
per check (``isnan``, ``isinf``, ``any``/``all`` along rows, norms); for
recordings of 1e5-1e7 samples those passes dominate registering a frame.
These kernels answer "is every row fine?" in one pass without
temporaries; only when the answer is no does the caller run the numpy
version, which names the offending row in its error.
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F1, F2, S1, B, F, helper, kernel

# Coordinates beyond this are refused with the infinities: no physical
# position comes near (the observable universe is ~1e27 m), and sums and
# products of larger ones overflow to inf when frames are composed.
MAX_COORDINATE = 1e150


@kernel(F1, options=EXACT_VECTOR_KERNEL)
def infinities(f):
    """How many values of ``f`` are infinite (one vectorised pass)."""
    count = 0
    for i in range(f.shape[0]):
        count += np.int64(abs(f[i]) == np.inf)
    return count


@helper(inline=True)
def _first_bad_row_scalar(a):
    n, k = a.shape
    for i in range(n):
        nan = 0
        for j in range(k):
            v = a[i, j]
            if math.isnan(v):
                nan += 1
            elif abs(v) > MAX_COORDINATE:  # an infinity too
                return i
        if nan != 0 and nan != k:
            return i
    return -1


@kernel(F2, options=EXACT_VECTOR_KERNEL)
def first_bad_row(a):
    """The first row of (n, k) ``a`` that is partly NaN or holds an infinity
    (or a value beyond :data:`MAX_COORDINATE`).

    Rows entirely NaN (missing samples) and finite rows are fine. For k of 3
    or 4 a vectorised pass counts the bad rows first (flat, constant-stride
    indexing), and only when there is one does a second pass find it.

    Returns
    -------
    int
        Its index, or -1 if every row is fine.
    """
    n, k = a.shape
    if k != 3 and k != 4:
        return _first_bad_row_scalar(a)
    f = a.reshape(-1)
    bad = 0
    if k == 3:
        for i in range(n):
            x, y, z = f[3 * i], f[3 * i + 1], f[3 * i + 2]
            nan = (x != x) + (y != y) + (z != z)
            inf = (abs(x) > MAX_COORDINATE) + (abs(y) > MAX_COORDINATE)
            inf += abs(z) > MAX_COORDINATE
            bad += ((nan != 0) & (nan != 3)) | (inf != 0)
    else:
        for i in range(n):
            w, x, y, z = f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]
            nan = (w != w) + (x != x) + (y != y) + (z != z)
            inf = (abs(w) > MAX_COORDINATE) + (abs(x) > MAX_COORDINATE)
            inf += (abs(y) > MAX_COORDINATE) + (abs(z) > MAX_COORDINATE)
            bad += ((nan != 0) & (nan != 4)) | (inf != 0)
    return -1 if bad == 0 else _first_bad_row_scalar(a)


@helper(inline=True)
def _first_unacceptable(q, tol, allow_nan):
    for i in range(q.shape[0]):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        if math.isinf(w) or math.isinf(x) or math.isinf(y) or math.isinf(z):
            return i
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if math.isnan(norm):
            if not allow_nan:
                return i
        elif abs(norm - 1.0) > tol:
            return i
    return -1


@kernel(F2, F, B, options=EXACT_VECTOR_KERNEL)
def unit_rows(q, tol, allow_nan):
    """Quaternions (n, 4) divided by their norms, if every row is acceptable.

    A row is acceptable if its norm is within ``tol`` of 1, or (with
    ``allow_nan``) if it contains NaN and no infinity. One vectorised pass
    normalises every row and counts the unacceptable ones; only when there
    is one does a second pass find the first.

    Returns
    -------
    out : ndarray, shape (n, 4)
        Rows divided by their norms (rows of norm exactly 1 and NaN rows
        copied as they are); not meaningful when ``bad`` >= 0.
    bad : int
        The first row that is not acceptable, or -1.
    """
    n = q.shape[0]
    out = np.empty((n, 4))
    f = q.reshape(-1)
    o = out.reshape(-1)
    count = 0
    for i in range(n):
        w, x, y, z = f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        inf = (abs(w) == np.inf) | (abs(x) == np.inf) | (abs(y) == np.inf)
        inf |= abs(z) == np.inf
        nan = norm != norm
        count += inf | (nan & (not allow_nan)) | (abs(norm - 1.0) > tol)
        # rows of norm 1 and NaN rows as they are (x / 1.0 is x)
        d = 1.0 if (norm == 1.0) | nan else norm
        o[4 * i] = w / d
        o[4 * i + 1] = x / d
        o[4 * i + 2] = y / d
        o[4 * i + 3] = z / d
    return out, -1 if count == 0 else _first_unacceptable(q, tol, allow_nan)


# rows per block of moving_samples: its vectorised loop normalises them into
# a scratch array that the serial sign pass reads back from L1 (8 kB)
_SAMPLES_BLOCK = 256


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def _checked_block(tb, qb, m, tol, unit):
    """The registration checks of one block of ``m`` rows, and its unit rows.

    ``tb`` (3 m,) and ``qb`` (4 m,) are the block's translations and
    rotations, flat; ``unit`` (4 m, or longer) gets the rotations divided
    by their norms as ``unit_rows`` makes them (rows of norm 1 and NaN rows
    as they are). Shared by :func:`moving_samples` and :func:`moving_signs`
    (inlined: each of its two loops is one LLVM vectorises).

    Returns
    -------
    bad : int
        How many rows of ``tb`` or ``qb`` are partly NaN or hold an
        infinity, plus how many finite rows of ``qb`` are not of unit norm
        within ``tol``.
    missing : int
        How many rows of ``qb`` are all NaN (missing samples).
    """
    bad = 0
    missing = 0
    for i in range(m):
        x, y, z = tb[3 * i], tb[3 * i + 1], tb[3 * i + 2]
        nan = (x != x) + (y != y) + (z != z)
        inf = (abs(x) > MAX_COORDINATE) + (abs(y) > MAX_COORDINATE)
        inf += abs(z) > MAX_COORDINATE
        bad += ((nan != 0) & (nan != 3)) | (inf != 0)
    for i in range(m):
        w, x, y, z = qb[4 * i], qb[4 * i + 1], qb[4 * i + 2], qb[4 * i + 3]
        nan = (w != w) + (x != x) + (y != y) + (z != z)
        inf = (abs(w) > MAX_COORDINATE) + (abs(x) > MAX_COORDINATE)
        inf += (abs(y) > MAX_COORDINATE) + (abs(z) > MAX_COORDINATE)
        bad += ((nan != 0) & (nan != 4)) | (inf != 0)
        missing += nan == 4
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        # NaN rows pass (missing samples): NaN > tol is false
        bad += abs(norm - 1.0) > tol
        # unit_rows: rows of norm 1 and NaN rows as they are
        d = 1.0 if (norm == 1.0) | (norm != norm) else norm
        unit[4 * i], unit[4 * i + 1] = w / d, x / d
        unit[4 * i + 2], unit[4 * i + 3] = y / d, z / d
    return bad, missing


@helper(inline=True, options=EXACT_VECTOR_KERNEL)
def unflip_step(w, x, y, z, pw, px, py, pz, have):
    """``quaternion.unflip``'s step for one unit row: the row negated if its
    dot product with the last valid row (``pw``.. ``pz``, once ``have``) is
    negative; ``sign * v`` is ``v`` or ``-v`` exactly, as there.

    Returns the sign (-1.0 or 1.0), the row as corrected, and the last valid
    row and ``have`` for the next row (this row, unless it holds a NaN).
    Shared by :func:`moving_samples`, :func:`moving_signs` and
    ``masked_rows.masked_signs`` (inlined into their serial loops).
    """
    d = 0.0
    if have:
        d = pw * w + px * x + py * y + pz * z
    sign = -1.0 if d < 0.0 else 1.0
    w, x, y, z = sign * w, sign * x, sign * y, sign * z
    if math.isnan(w + x + y + z):
        return sign, w, x, y, z, pw, px, py, pz, have
    return sign, w, x, y, z, w, x, y, z, True


@kernel(F2, F2, F, F2, F2, F2, options=EXACT_VECTOR_KERNEL)
def moving_samples(t, q, tol, t_out, q_out, r_out):
    """A moving frame's private arrays and every registration check, in one pass.

    What ``first_bad_row`` on ``t`` and on ``q``, ``unit_rows(q, tol, True)``,
    copies of ``t`` and ``q`` and ``quaternion.unflip`` of the unit rows give,
    without their four temporaries and six passes: the copies go to
    ``t_out`` (n, 3) and ``q_out`` (n, 4), the unit quaternions without sign
    flips to ``r_out`` (n, 4), bit for bit as those functions make them.
    Each block of rows is copied, checked and normalised in a loop LLVM
    vectorises, then given unflip's signs in a serial loop (each row's sign
    depends on the one before) while it is still in cache.

    Returns
    -------
    bad : int
        Nonzero if a row of ``t`` or ``q`` is partly NaN or holds an
        infinity, or a row of ``q`` is finite but not of unit norm within
        ``tol``: the outputs are then not meaningful, and the caller's
        one-check-at-a-time route names the row.
    missing : int
        How many rows of ``q`` are all NaN (missing samples).
    """
    n = q.shape[0]
    tf, qf = t.reshape(-1), q.reshape(-1)
    to, qo, ro = t_out.reshape(-1), q_out.reshape(-1), r_out.reshape(-1)
    # The block's unit quaternions. The loops that check and normalise write
    # only this array of their own (outputs that might overlap the inputs as
    # far as LLVM knows keep it from vectorising) and index views of the
    # block from 0 (an index that numba cannot prove non-negative gets a
    # wraparound select, which does too).
    unit = np.empty(4 * _SAMPLES_BLOCK)
    bad = 0
    missing = 0
    have = False  # a valid (non-NaN) row seen yet: its corrected values below
    pw = px = py = pz = 0.0
    for start in range(0, n, _SAMPLES_BLOCK):
        m = min(_SAMPLES_BLOCK, n - start)
        tb = tf[3 * start : 3 * (start + m)]
        qb = qf[4 * start : 4 * (start + m)]
        block_bad, block_missing = _checked_block(tb, qb, m, tol, unit)
        bad += block_bad
        missing += block_missing
        to[3 * start : 3 * (start + m)] = tb
        qo[4 * start : 4 * (start + m)] = qb
        # unflip's signs (each row's depends on the row before)
        rb = ro[4 * start : 4 * (start + m)]
        for i in range(m):
            w, x, y, z = unit[4 * i], unit[4 * i + 1], unit[4 * i + 2], unit[4 * i + 3]
            _, w, x, y, z, pw, px, py, pz, have = unflip_step(
                w, x, y, z, pw, px, py, pz, have
            )
            rb[4 * i], rb[4 * i + 1], rb[4 * i + 2], rb[4 * i + 3] = w, x, y, z
    return bad, missing


@kernel(F2, F2, F, S1, options=EXACT_VECTOR_KERNEL)
def moving_signs(t, q, tol, codes):
    """:func:`moving_samples`' checks of a frame that keeps ``t`` and ``q``
    themselves, and the sign codes of its unit rows (``signed_rows``).

    The frame keeps the caller's arrays (nobody can change them) and one
    byte per sample instead of copies and the unit rows: ``codes`` (n,)
    gets +1 or -1, the sign ``moving_samples`` gives the row in ``r_out``,
    found by the same operations, so that ``signed_rows.signed_unit_row``
    makes that row bit for bit.

    Returns
    -------
    bad, missing : int
        As :func:`moving_samples`.
    """
    n = q.shape[0]
    tf, qf = t.reshape(-1), q.reshape(-1)
    unit = np.empty(4 * _SAMPLES_BLOCK)
    bad = 0
    missing = 0
    have = False
    pw = px = py = pz = 0.0
    for start in range(0, n, _SAMPLES_BLOCK):
        m = min(_SAMPLES_BLOCK, n - start)
        tb = tf[3 * start : 3 * (start + m)]
        qb = qf[4 * start : 4 * (start + m)]
        block_bad, block_missing = _checked_block(tb, qb, m, tol, unit)
        bad += block_bad
        missing += block_missing
        # moving_samples' sign pass, keeping the sign instead of the row
        cb = codes[start : start + m]
        for i in range(m):
            w, x, y, z = unit[4 * i], unit[4 * i + 1], unit[4 * i + 2], unit[4 * i + 3]
            sign, _, _, _, _, pw, px, py, pz, have = unflip_step(
                w, x, y, z, pw, px, py, pz, have
            )
            cb[i] = -1 if sign < 0.0 else 1
    return bad, missing
