"""Resampling and chaining of transforms: numba kernels, unchecked.

Shapes follow ``quaternion.py``: translations (n, 3), rotations (n, 4) wxyz,
and an operand of length 1 is reused for every row. Times are float64
(``interp_linear``) or any sortable dtype of matching kind (``hold_last``).
"""

from __future__ import annotations

import numpy as np

from ._jit import F1, F2, F3, I1, B, kernel
from .quaternion import _qmul1, _rotate1, search_right


@kernel(F1, F2, F1)
def interp_linear(t_in, y_in, t_out):
    """Piecewise-linear resampling of (n, k) samples at times t_out.

    Parameters
    ----------
    t_in : ndarray, shape (n,), n >= 1
        Strictly increasing sample times.
    y_in : ndarray, shape (n, k)
    t_out : ndarray, shape (m,)
        Times inside [t_in[0], t_in[-1]] (outside, the end segments are
        extended linearly).

    Returns
    -------
    ndarray, shape (m, k)
        Exactly ``y_in[i]`` where ``t_out`` equals ``t_in[i]``.
    """
    n = t_in.shape[0]
    m = t_out.shape[0]
    k = y_in.shape[1]
    out = np.empty((m, k))
    if n == 1:
        for j in range(m):
            for c in range(k):
                out[j, c] = y_in[0, c]
        return out
    idx = search_right(t_in, t_out)
    for j in range(m):
        i = idx[j]
        if i >= 0 and t_out[j] == t_in[i]:
            for c in range(k):
                out[j, c] = y_in[i, c]
            continue
        if i < 0:
            i = 0
        elif i > n - 2:
            i = n - 2
        w = (t_out[j] - t_in[i]) / (t_in[i + 1] - t_in[i])
        for c in range(k):
            out[j, c] = y_in[i, c] + w * (y_in[i + 1, c] - y_in[i, c])
    return out


@kernel(F1, F2, F1)
def hold_last(t_events, y_events, t_out):
    """Discrete resampling: the last event at or before each time.

    Times before the first event take the first event's value. Binary
    search per output time, so O(m log n).

    Parameters
    ----------
    t_events : ndarray, shape (n,)
        Strictly increasing event times (int64 or float64).
    y_events : ndarray, shape (n, k)
    t_out : ndarray, shape (m,)
        Same dtype as ``t_events``.

    Returns
    -------
    ndarray, shape (m, k)
    """
    m = t_out.shape[0]
    k = y_events.shape[1]
    out = np.empty((m, k))
    idx = search_right(t_events, t_out)
    for j in range(m):
        i = idx[j]
        if i < 0:
            i = 0
        for c in range(k):
            out[j, c] = y_events[i, c]
    return out


@kernel(F2, F2, F2, F2, B)
def chain_step(t_acc, r_acc, t, r, inverse):
    """Append one transform to an accumulated transform.

    The accumulated transform maps points of the start frame into the
    current frame; (t, r) maps the current frame into the next one
    (``p_next = rot(r, p) + t``), or the other way round when ``inverse``.

    Parameters
    ----------
    t_acc : ndarray, shape (n, 3) or (1, 3)
    r_acc : ndarray, shape (n, 4) or (1, 4)
    t : ndarray, shape (n, 3) or (1, 3)
    r : ndarray, shape (n, 4) or (1, 4)
    inverse : bool

    Returns
    -------
    t_new : ndarray, shape (n, 3)
    r_new : ndarray, shape (n, 4)
    """
    n = max(t_acc.shape[0], r_acc.shape[0], t.shape[0], r.shape[0])
    s_ta = 1 if t_acc.shape[0] > 1 else 0
    s_ra = 1 if r_acc.shape[0] > 1 else 0
    s_t = 1 if t.shape[0] > 1 else 0
    s_r = 1 if r.shape[0] > 1 else 0
    t_new = np.empty((n, 3))
    r_new = np.empty((n, 4))
    for i in range(n):
        a = i * s_ta
        b = i * s_ra
        c = i * s_t
        d = i * s_r
        qw, qx, qy, qz = r[d, 0], r[d, 1], r[d, 2], r[d, 3]
        px, py, pz = t_acc[a, 0], t_acc[a, 1], t_acc[a, 2]
        if inverse:
            # rotating by q⁻¹ is rotating by conj(q): _rotate1 divides by |q|²
            x, y, z = _rotate1(
                qw, -qx, -qy, -qz, px - t[c, 0], py - t[c, 1], pz - t[c, 2]
            )
            k = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
            qw, qx, qy, qz = qw * k, -qx * k, -qy * k, -qz * k
        else:
            x, y, z = _rotate1(qw, qx, qy, qz, px, py, pz)
            x += t[c, 0]
            y += t[c, 1]
            z += t[c, 2]
        t_new[i, 0] = x
        t_new[i, 1] = y
        t_new[i, 2] = z
        w, x, y, z = _qmul1(
            qw, qx, qy, qz, r_acc[b, 0], r_acc[b, 1], r_acc[b, 2], r_acc[b, 3]
        )
        r_new[i, 0] = w
        r_new[i, 1] = x
        r_new[i, 2] = y
        r_new[i, 3] = z
    return t_new, r_new


@kernel(F2, F2, F3, B)
def transform_blocks(r, t, v, translate):
    """Apply per-time transforms to blocks of vectors.

    Parameters
    ----------
    r : ndarray, shape (n, 4) or (1, 4)
    t : ndarray, shape (n, 3) or (1, 3)
        Ignored unless ``translate``.
    v : ndarray, shape (n, k, 3) or (1, k, 3)
        k vectors per time step.
    translate : bool
        Points (rotate, then add t) or vectors (rotate only).

    Returns
    -------
    ndarray, shape (n, k, 3)
    """
    n = max(r.shape[0], v.shape[0])
    if translate:
        n = max(n, t.shape[0])
    k = v.shape[1]
    s_r = 1 if r.shape[0] > 1 else 0
    s_t = 1 if t.shape[0] > 1 else 0
    s_v = 1 if v.shape[0] > 1 else 0
    out = np.empty((n, k, 3))
    for i in range(n):
        a = i * s_r
        b = i * s_v
        c = i * s_t
        qw, qx, qy, qz = r[a, 0], r[a, 1], r[a, 2], r[a, 3]
        for j in range(k):
            x, y, z = _rotate1(qw, qx, qy, qz, v[b, j, 0], v[b, j, 1], v[b, j, 2])
            if translate:
                x += t[c, 0]
                y += t[c, 1]
                z += t[c, 2]
            out[i, j, 0] = x
            out[i, j, 1] = y
            out[i, j, 2] = z
    return out


@kernel(F2, F3)
def qmul_blocks(r, q):
    """Left-multiply blocks of quaternions by per-time rotations.

    Parameters
    ----------
    r : ndarray, shape (n, 4) or (1, 4)
    q : ndarray, shape (n, k, 4) or (1, k, 4)

    Returns
    -------
    ndarray, shape (n, k, 4)
    """
    n = max(r.shape[0], q.shape[0])
    k = q.shape[1]
    s_r = 1 if r.shape[0] > 1 else 0
    s_q = 1 if q.shape[0] > 1 else 0
    out = np.empty((n, k, 4))
    for i in range(n):
        a = i * s_r
        b = i * s_q
        for j in range(k):
            w, x, y, z = _qmul1(
                r[a, 0], r[a, 1], r[a, 2], r[a, 3],
                q[b, j, 0], q[b, j, 1], q[b, j, 2], q[b, j, 3],
            )  # fmt: skip
            out[i, j, 0] = w
            out[i, j, 1] = x
            out[i, j, 2] = y
            out[i, j, 3] = z
    return out


@kernel(F1, F1)
def hold_index(t_events, t_out):
    """Index of the last event at or before each time (0 before the first)."""
    idx = search_right(t_events, t_out)
    for j in range(idx.shape[0]):
        if idx[j] < 0:
            idx[j] = 0
    return idx


@kernel(F2, F2, I1, F3, B)
def transform_blocks_held(r, t, idx, v, translate):
    """:func:`transform_blocks` with row i using transform ``idx[i]``.

    For piecewise-constant (discrete) transforms: the few distinct
    transforms are composed once and each time step refers to one of them,
    instead of materialising a transform per time step.

    Parameters
    ----------
    r : ndarray, shape (e, 4)
    t : ndarray, shape (e, 3)
    idx : ndarray of int64, shape (n,)
    v : ndarray, shape (n, k, 3) or (1, k, 3)
    translate : bool

    Returns
    -------
    ndarray, shape (n, k, 3)
    """
    n = idx.shape[0]
    k = v.shape[1]
    s_v = 1 if v.shape[0] > 1 else 0
    out = np.empty((n, k, 3))
    for i in range(n):
        a = idx[i]
        b = i * s_v
        qw, qx, qy, qz = r[a, 0], r[a, 1], r[a, 2], r[a, 3]
        for j in range(k):
            x, y, z = _rotate1(qw, qx, qy, qz, v[b, j, 0], v[b, j, 1], v[b, j, 2])
            if translate:
                x += t[a, 0]
                y += t[a, 1]
                z += t[a, 2]
            out[i, j, 0] = x
            out[i, j, 1] = y
            out[i, j, 2] = z
    return out


@kernel(F2, I1, F3)
def qmul_blocks_held(r, idx, q):
    """:func:`qmul_blocks` with row i using rotation ``idx[i]``."""
    n = idx.shape[0]
    k = q.shape[1]
    s_q = 1 if q.shape[0] > 1 else 0
    out = np.empty((n, k, 4))
    for i in range(n):
        a = idx[i]
        b = i * s_q
        for j in range(k):
            w, x, y, z = _qmul1(
                r[a, 0], r[a, 1], r[a, 2], r[a, 3],
                q[b, j, 0], q[b, j, 1], q[b, j, 2], q[b, j, 3],
            )  # fmt: skip
            out[i, j, 0] = w
            out[i, j, 1] = x
            out[i, j, 2] = y
            out[i, j, 3] = z
    return out
