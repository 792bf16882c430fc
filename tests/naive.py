"""Plain-numpy twins of the numba kernels, written for clarity, not speed.

Each kernel in ``rbm_nb._kernels`` has a twin here that computes the same
thing the obvious way (often by a different route); the kernel tests compare
them with ``parametrize``. Keep each engineer's twins in one block.
"""

from __future__ import annotations

import numpy as np

# ---------------------------------------------------------------------------
# H1: rbm_nb._kernels.quaternion and rbm_nb._kernels.resample
# ---------------------------------------------------------------------------


def _broadcast_rows(*arrays):
    n = max(len(a) for a in arrays)
    return [np.repeat(a, n, axis=0) if len(a) == 1 else a for a in arrays]


def qmul(p, q):
    p, q = _broadcast_rows(p, q)
    w1, v1 = p[:, 0], p[:, 1:]
    w2, v2 = q[:, 0], q[:, 1:]
    w = w1 * w2 - np.sum(v1 * v2, axis=1)
    v = w1[:, None] * v2 + w2[:, None] * v1 + np.cross(v1, v2)
    return np.column_stack([w, v])


def qconj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def qnorm(q):
    return np.linalg.norm(q, axis=1)


def qnormalize(q):
    return q / qnorm(q)[:, None]


def qinv(q):
    return qconj(q) / (qnorm(q) ** 2)[:, None]


def rotate_vectors(q, v):
    """q v q⁻¹ computed literally with quaternion products."""
    q, v = _broadcast_rows(q, v)
    pure = np.column_stack([np.zeros(len(v)), v])
    return qmul(qmul(q, pure), qinv(q))[:, 1:]


def rotate_vectors_outer(q, v):
    return np.stack([rotate_vectors(qi[None], v) for qi in q])


def qexp(q):
    w, v = q[:, 0], q[:, 1:]
    a = np.linalg.norm(v, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(a > 1e-14, np.sin(a) / a, 0.0)
    return np.exp(w)[:, None] * np.column_stack(
        [np.cos(np.where(a > 1e-14, a, 0)), s[:, None] * v]
    )


def qlog(q):
    out = np.empty_like(q)
    for i, (w, x, y, z) in enumerate(q):
        b = np.sqrt(x * x + y * y + z * z)
        norm = np.sqrt(w * w + b * b)
        if b <= 1e-14 * abs(w):
            out[i] = (np.log(abs(w)), np.pi if w < 0 else 0.0, 0.0, 0.0)
        else:
            angle = np.arccos(np.clip(w / norm, -1, 1))
            out[i] = (np.log(norm), *(angle / b * np.array([x, y, z])))
    return out


def slerp(q0, q1, tau):
    """sin-weighted slerp along the shorter arc (a different formula)."""
    q0, q1, tau = _broadcast_rows(q0, q1, np.asarray(tau, float)[:, None])
    tau = tau[:, 0]
    dot = np.sum(q0 * q1, axis=1)
    q1 = np.where(dot[:, None] < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1, 1))
    out = np.empty_like(q0)
    for i in range(len(q0)):
        if theta[i] < 1e-12:
            out[i] = q0[i]
        else:
            s = np.sin(theta[i])
            out[i] = (
                np.sin((1 - tau[i]) * theta[i]) / s * q0[i]
                + np.sin(tau[i] * theta[i]) / s * q1[i]
            )
    return out


def squad(q_in, t_in, t_out):
    """numpy-quaternion's own squad (the reference's resampler)."""
    import quaternion

    return quaternion.as_float_array(
        quaternion.squad(quaternion.as_quat_array(q_in), t_in, t_out)
    )


def matrix_from_quaternion(q):
    """Columns are the rotated basis vectors."""
    e = np.eye(3)
    return np.stack(
        [rotate_vectors(q, np.repeat(e[j][None], len(q), 0)) for j in range(3)], axis=-1
    )


def quaternion_from_matrix(m):
    """Bar-Itzhack: the dominant eigenvector of the symmetric 4x4 K matrix."""
    out = np.empty((len(m), 4))
    for i, r in enumerate(m):
        k = (
            np.array(
                [
                    [
                        r[0, 0] - r[1, 1] - r[2, 2],
                        r[1, 0] + r[0, 1],
                        r[2, 0] + r[0, 2],
                        r[2, 1] - r[1, 2],
                    ],
                    [
                        r[1, 0] + r[0, 1],
                        r[1, 1] - r[0, 0] - r[2, 2],
                        r[2, 1] + r[1, 2],
                        r[0, 2] - r[2, 0],
                    ],
                    [
                        r[2, 0] + r[0, 2],
                        r[2, 1] + r[1, 2],
                        r[2, 2] - r[0, 0] - r[1, 1],
                        r[1, 0] - r[0, 1],
                    ],
                    [
                        r[2, 1] - r[1, 2],
                        r[0, 2] - r[2, 0],
                        r[1, 0] - r[0, 1],
                        r[0, 0] + r[1, 1] + r[2, 2],
                    ],
                ]
            )
            / 3.0
        )
        vals, vecs = np.linalg.eigh(k)
        x, y, z, w = vecs[:, np.argmax(vals)]
        q = np.array([w, x, y, z])
        out[i] = q if w >= 0 else -q
    return out


def interp_linear(t_in, y_in, t_out):
    return np.column_stack(
        [np.interp(t_out, t_in, y_in[:, c]) for c in range(y_in.shape[1])]
    )


def hold_last(t_events, y_events, t_out):
    """The reference's loop: every event overwrites the times at or after it."""
    out = np.tile(y_events[0], (len(t_out), 1)).astype(float)
    for value, t in zip(y_events, t_events, strict=True):
        out[t_out >= t] = value
    return out


def chain_step(t_acc, r_acc, t, r, inverse):
    t_acc, r_acc, t, r = _broadcast_rows(t_acc, r_acc, t, r)
    if inverse:
        ri = qinv(r)
        return rotate_vectors(ri, t_acc - t), qmul(ri, r_acc)
    return rotate_vectors(r, t_acc) + t, qmul(r, r_acc)


def transform_blocks(r, t, v, translate):
    n = max(len(r), len(v), len(t) if translate else 1)
    out = np.empty((n, v.shape[1], 3))
    for i in range(n):
        ri = r[i if len(r) > 1 else 0][None]
        vi = v[i if len(v) > 1 else 0]
        out[i] = rotate_vectors(ri, vi)
        if translate:
            out[i] += t[i if len(t) > 1 else 0]
    return out


def qmul_blocks(r, q):
    n = max(len(r), len(q))
    out = np.empty((n, q.shape[1], 4))
    for i in range(n):
        out[i] = qmul(r[i if len(r) > 1 else 0][None], q[i if len(q) > 1 else 0])
    return out


def unflip(q):
    out = q.copy()
    last = None
    for i in range(len(q)):
        if np.isnan(q[i]).any():
            continue
        if last is not None and np.dot(out[i], out[last]) < 0:
            out[i] = -out[i]
        last = i
    # rows with NaN keep the current sign convention (they stay NaN anyway)
    return out


def hold_index(t_events, t_out):
    return np.maximum(np.searchsorted(t_events, t_out, side="right") - 1, 0)


def transform_blocks_held(r, t, idx, v, translate):
    return transform_blocks(
        r[idx], t[idx], np.broadcast_to(v, (len(idx),) + v.shape[1:]), translate
    )


def qmul_blocks_held(r, idx, q):
    return qmul_blocks(r[idx], np.broadcast_to(q, (len(idx),) + q.shape[1:]))


def first_unordered(key):
    bad = np.flatnonzero(~(np.diff(key) > 0))
    return int(bad[0]) + 1 if bad.size else -1


def search_right(t_in, t_out):
    return np.searchsorted(t_in, t_out, side="right") - 1


# ---------------------------------------------------------------------------
# (other engineers' twins go below, in their own block)
# ---------------------------------------------------------------------------
