"""Pose-pair selection and pose errors for trajectory evaluation: numba kernels.

Unchecked: positions are C-contiguous float64 (n, 3), quaternions (n, 4)
``w, x, y, z`` of unit norm, pair lists int64 (m, 2). The pair rules are
those of evo's ``filters`` module, written so that ties resolve the same way.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import F2, F, helper, kernel

# (m, 2) index pairs, C-contiguous
I2 = "int64[:, ::1]"


@helper(inline=True)
def _relative_angle(q, i, j):
    """Rotation angle of ``conj(q_i) q_j`` in [0, pi]."""
    aw, ax, ay, az = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
    bw, bx, by, bz = q[j, 0], q[j, 1], q[j, 2], q[j, 3]
    w = aw * bw + ax * bx + ay * by + az * bz
    x = aw * bx - ax * bw - ay * bz + az * by
    y = aw * by + ax * bz - ay * bw - az * bx
    z = aw * bz - ax * by + ay * bx - az * bw
    return 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))


@helper
def _segment_lengths(p):
    n = p.shape[0]
    out = np.empty(max(n - 1, 0))
    for i in range(n - 1):
        dx = p[i + 1, 0] - p[i, 0]
        dy = p[i + 1, 1] - p[i, 1]
        dz = p[i + 1, 2] - p[i, 2]
        out[i] = math.sqrt(dx * dx + dy * dy + dz * dz)
    return out


@helper
def _consecutive(steps, delta):
    """Pairs of consecutive ids where the accumulated step reaches ``delta``."""
    ids = np.empty(steps.shape[0] + 1, dtype=np.int64)
    ids[0] = 0
    m = 1
    acc = 0.0
    for i in range(steps.shape[0]):
        acc += steps[i]
        if acc >= delta:
            ids[m] = i + 1
            m += 1
            acc = 0.0
    pairs = np.empty((max(m - 1, 0), 2), dtype=np.int64)
    for k in range(m - 1):
        pairs[k, 0] = ids[k]
        pairs[k, 1] = ids[k + 1]
    return pairs


@kernel(F2, F)
def path_pairs(p, delta):
    """Consecutive pairs whose path length (summed segment by segment) reaches delta."""
    return _consecutive(_segment_lengths(p), delta)


@kernel(F2, F)
def angle_pairs(q, delta):
    """Consecutive pairs whose accumulated rotation angle reaches delta (radians)."""
    n = q.shape[0]
    steps = np.empty(max(n - 1, 0))
    for i in range(n - 1):
        steps[i] = _relative_angle(q, i, i + 1)
    return _consecutive(steps, delta)


@helper
def _first_at_least(d, lo, value):
    """First index k in [lo, len(d)] with d[k] >= value (d non-decreasing)."""
    hi = d.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if d[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@kernel(F2, F, F)
def all_path_pairs(p, delta, tol):
    """For each i, the j > i whose path distance from i is closest to delta.

    Path distances are the accumulated segment lengths (a cumulative sum, as
    evo computes them); the closest j is the first one among equals; the
    pair is kept only if its distance is within ``tol`` of ``delta``.
    """
    n = p.shape[0]
    steps = _segment_lengths(p)
    d = np.zeros(n)
    acc = 0.0
    for i in range(n - 1):
        acc += steps[i]
        d[i + 1] = acc
    pairs = np.empty((max(n - 1, 0), 2), dtype=np.int64)
    m = 0
    for i in range(n - 1):
        # d[j] - d[i] is non-decreasing in j: the closest value to delta sits
        # next to the first j where it reaches delta
        k = _first_at_least(d, i + 1, d[i] + delta)
        while k < n and d[k] - d[i] < delta:
            k += 1  # rounding of d[i] + delta vs d[k] - d[i]
        while k > i + 1 and d[k - 1] - d[i] >= delta:
            k -= 1
        best = -1
        best_err = np.inf
        if k - 1 >= i + 1:
            below = _first_at_least(d, i + 1, d[k - 1])
            best = below
            best_err = abs((d[below] - d[i]) - delta)
        if k < n:
            err = abs((d[k] - d[i]) - delta)
            if err < best_err:
                best = k
                best_err = err
        if best >= 0 and best_err <= tol:
            pairs[m, 0] = i
            pairs[m, 1] = best
            m += 1
    return pairs[:m].copy()


@kernel(F2, F, F)
def all_angle_pairs(q, delta, tol):
    """Every pair i < j whose relative rotation angle lies in [delta - tol, delta + tol].

    Quadratic in the number of poses, as it is in evo.
    """
    n = q.shape[0]
    lo = delta - tol
    hi = delta + tol
    count = 0
    for i in range(n - 1):
        for j in range(i + 1, n):
            a = _relative_angle(q, i, j)
            if lo <= a <= hi:
                count += 1
    pairs = np.empty((count, 2), dtype=np.int64)
    m = 0
    for i in range(n - 1):
        for j in range(i + 1, n):
            a = _relative_angle(q, i, j)
            if lo <= a <= hi:
                pairs[m, 0] = i
                pairs[m, 1] = j
                m += 1
    return pairs


@helper
def _rotate_inverse(w, x, y, z, vx, vy, vz):
    """conj(q) v q: v expressed in the frame rotated by q."""
    # t = 2 (u x v) with u = -(x, y, z); v' = v + w t + u x t
    tx = 2.0 * (-y * vz + z * vy)
    ty = 2.0 * (-z * vx + x * vz)
    tz = 2.0 * (-x * vy + y * vx)
    return (
        vx + w * tx + (-y * tz + z * ty),
        vy + w * ty + (-z * tx + x * tz),
        vz + w * tz + (-x * ty + y * tx),
    )


@kernel(F2, F2, F2, F2, I2)
def relative_pose_errors(p_ref, q_ref, p_est, q_est, pairs):
    """``inv(inv(Q_i) Q_j) inv(P_i) P_j`` for each pair (i, j): Q reference, P estimate.

    Returns the error translations (m, 3) and rotation angles (m,) in radians.
    """
    m = pairs.shape[0]
    trans = np.empty((m, 3))
    angle = np.empty(m)
    for k in range(m):
        i, j = pairs[k, 0], pairs[k, 1]
        # relative motions in the first pose's frame
        qw, qx, qy, qz = q_ref[i, 0], q_ref[i, 1], q_ref[i, 2], q_ref[i, 3]
        rx, ry, rz = _rotate_inverse(
            qw, qx, qy, qz,
            p_ref[j, 0] - p_ref[i, 0], p_ref[j, 1] - p_ref[i, 1], p_ref[j, 2] - p_ref[i, 2],
        )  # fmt: skip
        pw, px, py, pz = q_est[i, 0], q_est[i, 1], q_est[i, 2], q_est[i, 3]
        ex, ey, ez = _rotate_inverse(
            pw, px, py, pz,
            p_est[j, 0] - p_est[i, 0], p_est[j, 1] - p_est[i, 1], p_est[j, 2] - p_est[i, 2],
        )  # fmt: skip
        # relative rotations a = conj(q_i) q_j (reference), b (estimate)
        bw_, bx_, by_, bz_ = q_ref[j, 0], q_ref[j, 1], q_ref[j, 2], q_ref[j, 3]
        aw = qw * bw_ + qx * bx_ + qy * by_ + qz * bz_
        ax = qw * bx_ - qx * bw_ - qy * bz_ + qz * by_
        ay = qw * by_ + qx * bz_ - qy * bw_ - qz * bx_
        az = qw * bz_ - qx * by_ + qy * bx_ - qz * bw_
        cw, cx, cy, cz = q_est[j, 0], q_est[j, 1], q_est[j, 2], q_est[j, 3]
        bw = pw * cw + px * cx + py * cy + pz * cz
        bx = pw * cx - px * cw - py * cz + pz * cy
        by = pw * cy + px * cz - py * cw - pz * cx
        bz = pw * cz - px * cy + py * cx - pz * cw
        # E = inv(A) B: translation conj(a) (t_B - t_A), rotation conj(a) b
        tx, ty, tz = _rotate_inverse(aw, ax, ay, az, ex - rx, ey - ry, ez - rz)
        trans[k, 0] = tx
        trans[k, 1] = ty
        trans[k, 2] = tz
        w = aw * bw + ax * bx + ay * by + az * bz
        x = aw * bx - ax * bw - ay * bz + az * by
        y = aw * by + ax * bz - ay * bw - az * bx
        z = aw * bz - ax * by + ay * bx - az * bw
        angle[k] = 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))
    return trans, angle


@kernel(F2, F2, F2, F2)
def absolute_pose_errors(p_ref, q_ref, p_est, q_est):
    """``inv(P_i) Q_i`` for each i: error translations (n, 3) and angles (n,)."""
    n = p_ref.shape[0]
    trans = np.empty((n, 3))
    angle = np.empty(n)
    for i in range(n):
        pw, px, py, pz = q_est[i, 0], q_est[i, 1], q_est[i, 2], q_est[i, 3]
        tx, ty, tz = _rotate_inverse(
            pw, px, py, pz,
            p_ref[i, 0] - p_est[i, 0], p_ref[i, 1] - p_est[i, 1], p_ref[i, 2] - p_est[i, 2],
        )  # fmt: skip
        trans[i, 0] = tx
        trans[i, 1] = ty
        trans[i, 2] = tz
        cw, cx, cy, cz = q_ref[i, 0], q_ref[i, 1], q_ref[i, 2], q_ref[i, 3]
        x = pw * cx - px * cw - py * cz + pz * cy
        y = pw * cy + px * cz - py * cw - pz * cx
        z = pw * cz - px * cy + py * cx - pz * cw
        w = pw * cw + px * cx + py * cy + pz * cz
        angle[i] = 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w))
    return trans, angle
