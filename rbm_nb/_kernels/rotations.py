"""Quaternion kernels for the public utilities: numba, unchecked.

The algebra itself lives in :mod:`rbm_nb._kernels.quaternion`; the kernels here
add what the validated public functions need in the same pass over the data
(the index of the first zero quaternion, so that rejecting bad input costs no
second sweep), plus sign continuity and the rotation-vector convention of
numpy-quaternion that the velocity estimators reproduce.

Quaternions are float64 (n, 4) arrays in ``w, x, y, z`` order, vectors (n, 3),
both C-contiguous; where two operands are given their first dimensions are
equal or one of them is 1.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numba import prange

from .._infra.config import VECTOR_KERNEL
from ._jit import F2, helper, kernel
from .quaternion import _qinv1, _qlog1, _rotate1, _rotate1_inline

# The prange twins of the branch-free loops (launched by rbm_nb._infra.parallel).
_PARALLEL_VECTOR = dataclasses.replace(VECTOR_KERNEL, parallel=True)
# blocks of rows a parallel twin splits its rows into
_BLOCKS = 64


@kernel(F2, F2)
def rotate_vectors_checked(q, v):
    """q v q⁻¹ row by row, and the first row whose quaternion is zero.

    Parameters
    ----------
    q : ndarray, shape (n, 4) or (1, 4)
    v : ndarray, shape (n, 3) or (1, 3)

    Returns
    -------
    out : ndarray, shape (n, 3)
        NaN in rows rotated by a zero quaternion.
    zero_idx : int
        Index (into ``q``) of the first zero quaternion, or -1.
    """
    n = 0 if q.shape[0] == 0 or v.shape[0] == 0 else max(q.shape[0], v.shape[0])
    sq = 1 if q.shape[0] > 1 else 0
    sv = 1 if v.shape[0] > 1 else 0
    out = np.empty((n, 3))
    zero_idx = -1
    for i in range(n):
        a = i * sq
        b = i * sv
        w, x, y, z = q[a, 0], q[a, 1], q[a, 2], q[a, 3]
        if w == 0.0 and x == 0.0 and y == 0.0 and z == 0.0:
            # numba raises on division by zero; the caller reports the row
            if zero_idx < 0:
                zero_idx = a
            out[i, 0] = out[i, 1] = out[i, 2] = np.nan
            continue
        rx, ry, rz = _rotate1(w, x, y, z, v[b, 0], v[b, 1], v[b, 2])
        out[i, 0] = rx
        out[i, 1] = ry
        out[i, 2] = rz
    return out, zero_idx


@helper(inline=True)
def _flat(a):
    """The rows of a C-contiguous 2-D array as one 1-D view.

    The row loops index these views as ``4 i + k``: numba indexes a 2-D
    array's rows with its row stride, a runtime value, and LLVM vectorises
    no loop over such rows, while with constant strides it does (1M
    rotations on 1 thread: 3.4 -> 1.9 ms). The parallel twins take the views
    once, before their ``prange`` loop, and hand them to every block.
    """
    return a.reshape(-1)


@helper(inline=True, options=VECTOR_KERNEL)
def _rotate_rows(qf, nq, vf, nv, of, lo, hi):
    """Rotate rows lo..hi-1 into ``of``; count zero quaternions and infinities.

    Branch-free, so that LLVM vectorises the loop: a zero quaternion gives
    NaN through 0 * (1 / 0) (``error_model="numpy"``) and is counted, not
    tested. Infinities are counted in ``v`` and in ``q`` (through |q|²).
    ``qf``, ``vf`` and ``of`` are flat views of the (nq, 4), (nv, 3) and
    output (n, 3) arrays (see :func:`_flat`); ``q`` or ``v`` may hold a
    single row (nq or nv 1) that every output row reuses.
    """
    zeros = 0
    infs = 0
    if nq == 1 and nv != 1:
        w, x, y, z = qf[0], qf[1], qf[2], qf[3]
        n2 = w * w + x * x + y * y + z * z
        zeros += hi > lo and n2 == 0.0
        infs += hi > lo and abs(n2) == np.inf
        for i in range(lo, hi):
            vx, vy, vz = vf[3 * i], vf[3 * i + 1], vf[3 * i + 2]
            infs += (abs(vx) == np.inf) + (abs(vy) == np.inf) + (abs(vz) == np.inf)
            rx, ry, rz = _rotate1_inline(w, x, y, z, vx, vy, vz)
            of[3 * i] = rx
            of[3 * i + 1] = ry
            of[3 * i + 2] = rz
        return zeros, infs
    if nv == 1 and nq != 1:
        vx, vy, vz = vf[0], vf[1], vf[2]
        infs += hi > lo and (
            (abs(vx) == np.inf) + (abs(vy) == np.inf) + (abs(vz) == np.inf)
        )
        for i in range(lo, hi):
            w, x, y, z = qf[4 * i], qf[4 * i + 1], qf[4 * i + 2], qf[4 * i + 3]
            n2 = w * w + x * x + y * y + z * z
            zeros += n2 == 0.0
            infs += abs(n2) == np.inf
            rx, ry, rz = _rotate1_inline(w, x, y, z, vx, vy, vz)
            of[3 * i] = rx
            of[3 * i + 1] = ry
            of[3 * i + 2] = rz
        return zeros, infs
    for i in range(lo, hi):
        w, x, y, z = qf[4 * i], qf[4 * i + 1], qf[4 * i + 2], qf[4 * i + 3]
        vx, vy, vz = vf[3 * i], vf[3 * i + 1], vf[3 * i + 2]
        n2 = w * w + x * x + y * y + z * z
        zeros += n2 == 0.0
        infs += (abs(n2) == np.inf) + (abs(vx) == np.inf) + (abs(vy) == np.inf)
        infs += abs(vz) == np.inf
        rx, ry, rz = _rotate1_inline(w, x, y, z, vx, vy, vz)
        of[3 * i] = rx
        of[3 * i + 1] = ry
        of[3 * i + 2] = rz
    return zeros, infs


@kernel(F2, F2, F2, options=VECTOR_KERNEL)
def rotate_vectors_into(q, v, out):
    """q v q⁻¹ row by row into ``out``, counting zero quaternions and infinities.

    ``out`` comes from the caller (numpy allocates large arrays on huge
    pages: a fresh output then costs a few page faults instead of one per
    4 kB, which on first touch is most of the time of a memory-bound loop).

    Parameters
    ----------
    q : ndarray, shape (n, 4) or (1, 4)
    v : ndarray, shape (n, 3) or (1, 3)
    out : ndarray, shape (n, 3)
        n = max of the two (0 if either is empty); NaN in rows rotated by a
        zero quaternion.

    Returns
    -------
    zeros : int
        How many rows of ``q`` used are zero (the caller finds the first).
    infs : int
        How many infinities ``v`` and ``q`` hold (idem).
    """
    return _rotate_rows(
        _flat(q), q.shape[0], _flat(v), v.shape[0], _flat(out), 0, out.shape[0]
    )


@kernel(F2, F2, F2, options=_PARALLEL_VECTOR)
def rotate_vectors_into_parallel(q, v, out):
    """:func:`rotate_vectors_into` with blocks of rows on numba's threads."""
    n = out.shape[0]
    # plain loops that LLVM vectorises, more of them than threads (numba's
    # thread count is not read here: that would keep the kernel out of the
    # on-disk cache)
    size = (n + _BLOCKS - 1) // _BLOCKS
    qf, vf, of = _flat(q), _flat(v), _flat(out)  # outside the loop: see _flat
    nq, nv = q.shape[0], v.shape[0]
    zeros = 0
    infs = 0
    for b in prange(_BLOCKS):
        lo, hi = min(b * size, n), min((b + 1) * size, n)
        z, f = _rotate_rows(qf, nq, vf, nv, of, lo, hi)
        zeros += z
        infs += f
    return zeros, infs


@kernel(F2)
def qinv_checked(q):
    """conj(q) / |q|² row by row, and the first row that is zero (or -1).

    Parameters
    ----------
    q : ndarray, shape (n, 4)

    Returns
    -------
    out : ndarray, shape (n, 4)
        NaN in zero rows.
    zero_idx : int
    """
    n = q.shape[0]
    out = np.empty((n, 4))
    zero_idx = -1
    for i in range(n):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        if w == 0.0 and x == 0.0 and y == 0.0 and z == 0.0:
            if zero_idx < 0:
                zero_idx = i
            out[i, 0] = out[i, 1] = out[i, 2] = out[i, 3] = np.nan
            continue
        iw, ix, iy, iz = _qinv1(w, x, y, z)
        out[i, 0] = iw
        out[i, 1] = ix
        out[i, 2] = iy
        out[i, 3] = iz
    return out, zero_idx


@kernel(F2)
def first_zero_row(q):
    """Index of the first all-zero row of ``q`` (n, k), or -1."""
    for i in range(q.shape[0]):
        zero = True
        for j in range(q.shape[1]):
            if q[i, j] != 0.0:
                zero = False
                break
        if zero:
            return i
    return -1


@kernel(F2)
def rotation_vectors(q):
    """2 log(q), vector part: numpy-quaternion's ``as_rotation_vector``.

    Unlike a shortest-angle conversion this keeps the sign of ``q``: a
    quaternion with w < 0 maps to an angle beyond pi. For a sign-continuous
    series the result is then continuous too, which is what differentiating
    it requires.

    Parameters
    ----------
    q : ndarray, shape (n, 4)

    Returns
    -------
    ndarray, shape (n, 3)
    """
    n = q.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        _, x, y, z = _qlog1(q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        out[i, 0] = 2.0 * x
        out[i, 1] = 2.0 * y
        out[i, 2] = 2.0 * z
    return out


@helper(inline=True)
def _qmul_flat(pf, a, qf, b, of, i):
    """Row i of ``of`` = p[a] * q[b] (flat views, rows of 4); the number of
    infinities in the two operand rows."""
    aw, ax, ay, az = pf[a], pf[a + 1], pf[a + 2], pf[a + 3]
    bw, bx, by, bz = qf[b], qf[b + 1], qf[b + 2], qf[b + 3]
    infs = (abs(aw) == np.inf) + (abs(ax) == np.inf) + (abs(ay) == np.inf)
    infs += (abs(az) == np.inf) + (abs(bw) == np.inf) + (abs(bx) == np.inf)
    infs += (abs(by) == np.inf) + (abs(bz) == np.inf)
    of[4 * i] = aw * bw - ax * bx - ay * by - az * bz
    of[4 * i + 1] = aw * bx + ax * bw + ay * bz - az * by
    of[4 * i + 2] = aw * by - ax * bz + ay * bw + az * bx
    of[4 * i + 3] = aw * bz + ax * by - ay * bx + az * bw
    return infs


@helper(inline=True, options=VECTOR_KERNEL)
def _qmul_rows(pf, np_, qf, nq, of, lo, hi):
    """p * q for rows lo..hi-1 into ``of`` (flat views, see :func:`_flat`;
    either operand may be one row, np_ or nq 1); the number of infinities in
    the operands' rows used. Branch-free, one loop per broadcast case, so
    that every index has a constant stride."""
    infs = 0
    if np_ == nq:
        for i in range(lo, hi):
            infs += _qmul_flat(pf, 4 * i, qf, 4 * i, of, i)
    elif np_ == 1:
        for i in range(lo, hi):
            infs += _qmul_flat(pf, 0, qf, 4 * i, of, i)
    else:
        for i in range(lo, hi):
            infs += _qmul_flat(pf, 4 * i, qf, 0, of, i)
    return infs


@kernel(F2, F2, F2, options=VECTOR_KERNEL)
def qmul_into(p, q, out):
    """Hamilton product p * q row by row ((n|1, 4) x (n|1, 4)) into ``out``
    (n, 4) (allocated by the caller, see :func:`rotate_vectors_into`); how
    many infinities the operands hold (the caller names one)."""
    return _qmul_rows(
        _flat(p), p.shape[0], _flat(q), q.shape[0], _flat(out), 0, out.shape[0]
    )


@kernel(F2, F2, F2, options=_PARALLEL_VECTOR)
def qmul_into_parallel(p, q, out):
    """:func:`qmul_into` with blocks of rows on numba's threads."""
    n = out.shape[0]
    size = (n + _BLOCKS - 1) // _BLOCKS
    pf, qf, of = _flat(p), _flat(q), _flat(out)  # outside the loop: see _flat
    np_, nq = p.shape[0], q.shape[0]
    infs = 0
    for b in prange(_BLOCKS):
        lo, hi = min(b * size, n), min((b + 1) * size, n)
        infs += _qmul_rows(pf, np_, qf, nq, of, lo, hi)
    return infs


@helper(inline=True, options=VECTOR_KERNEL)
def _qinv_rows(qf, of, lo, hi):
    """conj(q) / |q|² for rows lo..hi-1 into ``out``; counts of zero rows and
    of infinities. Branch-free: a zero row gives NaN through 0 * (1 / 0)."""
    zeros = 0
    infs = 0
    for i in range(lo, hi):
        w, x, y, z = qf[4 * i], qf[4 * i + 1], qf[4 * i + 2], qf[4 * i + 3]
        n2 = w * w + x * x + y * y + z * z
        zeros += n2 == 0.0
        infs += (abs(w) == np.inf) + (abs(x) == np.inf) + (abs(y) == np.inf)
        infs += abs(z) == np.inf
        k = 1.0 / n2  # one division per row, not four (within an ulp)
        of[4 * i] = w * k
        of[4 * i + 1] = -x * k
        of[4 * i + 2] = -y * k
        of[4 * i + 3] = -z * k
    return zeros, infs


@kernel(F2, F2, options=VECTOR_KERNEL)
def qinv_into(q, out):
    """Inverses of (n, 4) quaternions into ``out`` (n, 4) (allocated by the
    caller, see :func:`rotate_vectors_into`; NaN in zero rows); counts of
    zero rows and of infinities."""
    return _qinv_rows(_flat(q), _flat(out), 0, q.shape[0])


@kernel(F2, F2, options=_PARALLEL_VECTOR)
def qinv_into_parallel(q, out):
    """:func:`qinv_into` with blocks of rows on numba's threads."""
    n = q.shape[0]
    size = (n + _BLOCKS - 1) // _BLOCKS
    qf, of = _flat(q), _flat(out)  # outside the loop: see _flat
    zeros = 0
    infs = 0
    for b in prange(_BLOCKS):
        z, f = _qinv_rows(qf, of, min(b * size, n), min((b + 1) * size, n))
        zeros += z
        infs += f
    return zeros, infs
