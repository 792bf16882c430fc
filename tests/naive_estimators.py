"""Plain-numpy twins of the kernels in rbm_nb/_kernels/differences.py and
rbm_nb/_kernels/rotations.py.

Written for clarity, not speed: explicit loops or dense linear algebra that
can be checked by eye against the textbook formulas. The tests compare every
kernel with its twin (``parametrize`` over both in the test modules).
"""

from __future__ import annotations

import numpy as np

# ---------------------------------------------------------------------------
# quaternion helpers
# ---------------------------------------------------------------------------


def hamilton(p, q):
    """Hamilton product of (..., 4) arrays, written from the definition."""
    pw, pv = p[..., 0], p[..., 1:]
    qw, qv = q[..., 0], q[..., 1:]
    w = pw * qw - np.sum(pv * qv, axis=-1)
    v = pw[..., None] * qv + qw[..., None] * pv + np.cross(pv, qv)
    return np.concatenate((w[..., None], v), axis=-1)


def conjugate(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def inverse(q):
    return conjugate(q) / np.sum(q * q, axis=-1, keepdims=True)


def rotate(q, v):
    """q v q⁻¹ with v embedded as a pure quaternion."""
    pure = np.concatenate((np.zeros(v.shape[:-1] + (1,)), v), axis=-1)
    return hamilton(hamilton(q, pure), inverse(q))[..., 1:]


def rotation_matrix(q):
    """Rotation matrix of a non-zero quaternion (normalised first)."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


# ---------------------------------------------------------------------------
# twins of rbm_nb/_kernels/rotations.py
# ---------------------------------------------------------------------------


def rotate_vectors_checked(q, v):
    n = max(len(q), len(v))
    qb = np.broadcast_to(q, (n, 4))
    vb = np.broadcast_to(v, (n, 3))
    with np.errstate(invalid="ignore"):  # zero quaternions give NaN rows
        out = np.array(
            [rotation_matrix(qi) @ vi for qi, vi in zip(qb, vb, strict=True)]
        )
    zeros = np.flatnonzero(~q.any(axis=1))
    return out.reshape(n, 3), int(zeros[0]) if len(zeros) else -1


def qinv_checked(q):
    zeros = np.flatnonzero(~q.any(axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return inverse(q), int(zeros[0]) if len(zeros) else -1


def first_zero_row(q):
    zeros = np.flatnonzero(~q.any(axis=1))
    return int(zeros[0]) if len(zeros) else -1


def unflip(q):
    out = q.copy()
    last = None
    for i in range(len(q)):
        if np.isnan(q[i]).any():
            continue
        if last is not None and np.dot(out[last], q[i]) < 0:
            out[i] = -q[i]
        last = i
    return out


def rotation_vectors(q):
    """2 log(q): angle 2 atan2(|v|, w) about v / |v| (beyond pi for w < 0)."""
    out = np.zeros((len(q), 3))
    for i, (w, *v) in enumerate(q):
        v = np.array(v)
        b = np.linalg.norm(v)
        if b <= 1e-14 * abs(w):
            if w < 0:
                out[i] = (2 * np.pi, 0.0, 0.0)
            continue
        out[i] = 2 * np.arctan2(b, w) * v / b
    return out


# ---------------------------------------------------------------------------
# twins of rbm_nb/_kernels/differences.py
# ---------------------------------------------------------------------------


def gradient(f, t):
    return np.gradient(f, t, axis=0)


def spline_derivative(f, t):
    """Slopes of the not-a-knot cubic spline from a dense (n+...)-unknown system.

    Unknowns are the four polynomial coefficients of every segment; the rows
    are interpolation at both segment ends, C1 and C2 continuity at interior
    samples, and C3 continuity at the second and second-to-last samples.
    Fewer than four samples: the interpolating polynomial of degree n-1.
    """
    n = len(t)
    if n < 4:
        coef = np.polyfit(t - t[0], f, n - 1)
        deriv = np.array([np.polyder(coef[:, j]) for j in range(f.shape[1])])
        return np.array([[np.polyval(d, ti - t[0]) for d in deriv] for ti in t])
    segs = n - 1
    size = 4 * segs
    a = np.zeros((size, size))
    rhs = np.zeros((size, f.shape[1]))
    row = 0
    h = np.diff(t)
    for s in range(segs):  # p_s(x) = c0 + c1 d + c2 d² + c3 d³ with d = x - t[s]
        a[row, 4 * s] = 1.0
        rhs[row] = f[s]
        row += 1
        a[row, 4 * s : 4 * s + 4] = [1.0, h[s], h[s] ** 2, h[s] ** 3]
        rhs[row] = f[s + 1]
        row += 1
    for s in range(segs - 1):
        # first and second derivatives agree at t[s+1]
        a[row, 4 * s : 4 * s + 4] = [0.0, 1.0, 2 * h[s], 3 * h[s] ** 2]
        a[row, 4 * s + 5] = -1.0
        row += 1
        a[row, 4 * s : 4 * s + 4] = [0.0, 0.0, 2.0, 6 * h[s]]
        a[row, 4 * s + 6] = -2.0
        row += 1
    a[row, 3] = 1.0  # not-a-knot: third derivatives agree at t[1] ...
    a[row, 7] = -1.0
    row += 1
    a[row, 4 * (segs - 2) + 3] = 1.0  # ... and at t[n-2]
    a[row, 4 * (segs - 1) + 3] = -1.0
    coef = np.linalg.solve(a, rhs)
    slopes = np.empty_like(f, dtype=float)
    for s in range(segs):
        slopes[s] = coef[4 * s + 1]
    last = 4 * (segs - 1)
    slopes[n - 1] = (
        coef[last + 1] + 2 * coef[last + 2] * h[-1] + 3 * coef[last + 3] * h[-1] ** 2
    )
    return slopes


def second_difference_score(x):
    n, nb, _ = x.shape
    d = (
        np.linalg.norm(x[2:] - 2 * x[1:-1] + x[:-2], axis=-1)
        if n > 2
        else np.zeros((0, nb))
    )
    score = np.zeros((n, nb))
    score[: n - 2] += d
    score[1 : n - 1] += d
    return score


def interpolate_rejected(t, values, keep):
    out = np.empty(values.shape)
    for b in range(values.shape[1]):
        kt = t[keep[:, b]]
        for j in range(values.shape[2]):
            kv = values[keep[:, b], b, j]
            out[:, b, j] = np.interp(t, kt, kv, left=np.nan, right=np.nan)
            out[keep[:, b], b, j] = kv
    return out


def angular_velocity_from_derivative(q, dq):
    return 2 * hamilton(inverse(q), dq)[:, 1:]
