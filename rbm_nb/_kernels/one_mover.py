"""A chain of frames with one moving frame, composed row by row at its samples.

The scene looks a moving frame up in its base at the frame's own timestamps
(:class:`rbm_nb.scene.looked_up.LookedUpTrack`). When one frame of the chain
moves and the others are static, each composed row is the static part below
the mover, the mover's stored row, then the static part above it. These
kernels compose rows exactly as the engine's ``compose`` does with
``resample.chain_step`` (same operations in the same order: the same bits),
without its per-call arrays, so a whole recording is one pass:

* :func:`mover_poses`: the composed rows of chosen samples (the scene's
  coarse copy, a path's blocks), NaN across a row where anything is missing;
* :func:`mover_summary`: lowest, highest, sum and count of the composed
  translations that are not missing (the scene's bounds), allocating nothing
  per row.

The chain arrives as: ``t``/``rotation`` (n, 3)/(n, 4) the mover's stored
rows, ``missing`` (n,) or (0,) rows to treat as missing, ``below_t`` /
``below_r`` (1, 3)/(1, 4) the static part composed before the mover,
``raw`` whether the mover is the chain's first step taken forward (then the
engine uses its rows as they are, without a product), ``inverse`` the
mover's direction, ``above_t`` / ``above_r`` (k, 3)/(k, 4) and
``above_inverse`` (k,) the static steps after it, in order.
"""

from __future__ import annotations

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F2, B, helper, kernel
from .quaternion import _qmul1, _rotate1, _rotate1_inline

__all__ = ["mover_poses", "mover_summary", "mover_translations"]

B1 = "boolean[::1]"


@helper
def _step(tx, ty, tz, rw, rx, ry, rz, st, sr, j, inverse):
    """One row of ``resample.chain_step``: (t, r) accumulated, then step
    ``st[j]``, ``sr[j]`` (inverse or not); returns the new (t, r)."""
    qw, qx, qy, qz = sr[j, 0], sr[j, 1], sr[j, 2], sr[j, 3]
    if inverse:
        x, y, z = _rotate1(
            qw, -qx, -qy, -qz, tx - st[j, 0], ty - st[j, 1], tz - st[j, 2]
        )
        k = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
        qw, qx, qy, qz = qw * k, -qx * k, -qy * k, -qz * k
    else:
        x, y, z = _rotate1(qw, qx, qy, qz, tx, ty, tz)
        x += st[j, 0]
        y += st[j, 1]
        z += st[j, 2]
    w, a, b, c = _qmul1(qw, qx, qy, qz, rw, rx, ry, rz)
    return x, y, z, w, a, b, c


@helper
def _compose(
    t, rotation, i, below_t, below_r, raw, inverse, above_t, above_r, above_inverse
):
    """The composed row of sample ``i`` (7 floats: translation, rotation)."""
    if raw:
        x, y, z = t[i, 0], t[i, 1], t[i, 2]
        w, a, b, c = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
    else:
        x, y, z, w, a, b, c = _step(
            below_t[0, 0],
            below_t[0, 1],
            below_t[0, 2],
            below_r[0, 0],
            below_r[0, 1],
            below_r[0, 2],
            below_r[0, 3],
            t,
            rotation,
            i,
            inverse,
        )
    for j in range(above_t.shape[0]):
        x, y, z, w, a, b, c = _step(
            x, y, z, w, a, b, c, above_t, above_r, j, above_inverse[j]
        )
    return x, y, z, w, a, b, c


@helper
def _is_missing(missing, i, x, y, z, w, a, b, c):
    if missing.shape[0] > 0 and missing[i]:
        return True
    # NaN anywhere in the composed row (the scene hides the whole row)
    return (
        (x != x) or (y != y) or (z != z) or (w != w) or (a != a) or (b != b) or (c != c)
    )


@kernel(F2, F2, B1, F2, F2, B, B, F2, F2, B1)
def mover_poses(
    t,
    rotation,
    missing,
    below_t,
    below_r,
    raw,
    inverse,
    above_t,
    above_r,
    above_inverse,
):
    """Composed translations (n, 3) and rotations (n, 4) of every row of
    ``t``/``rotation``; both NaN across a missing row."""
    n = t.shape[0]
    t_out = np.empty((n, 3))
    r_out = np.empty((n, 4))
    for i in range(n):
        x, y, z, w, a, b, c = _compose(
            t,
            rotation,
            i,
            below_t,
            below_r,
            raw,
            inverse,
            above_t,
            above_r,
            above_inverse,
        )
        if _is_missing(missing, i, x, y, z, w, a, b, c):
            x = y = z = w = a = b = c = np.nan
        t_out[i, 0] = x
        t_out[i, 1] = y
        t_out[i, 2] = z
        r_out[i, 0] = w
        r_out[i, 1] = a
        r_out[i, 2] = b
        r_out[i, 3] = c
    return t_out, r_out


@helper
def _static_steps(above_t, above_r, above_inverse):
    """The row-independent terms of ``quaternion._rotate1`` for each static
    step after the mover, as it computes them (the same operations: the same
    values): (k, 8) of w, x, y, z (conjugated for an inverse step), 1 / |q|²,
    s, 2w and 1.0 for an inverse step (0.0 otherwise)."""
    out = np.empty((above_t.shape[0], 8))
    for j in range(above_t.shape[0]):
        w, x, y, z = above_r[j, 0], above_r[j, 1], above_r[j, 2], above_r[j, 3]
        if above_inverse[j]:
            x, y, z = -x, -y, -z
        n2 = w * w + x * x + y * y + z * z
        out[j, 0] = w
        out[j, 1] = x
        out[j, 2] = y
        out[j, 3] = z
        out[j, 4] = 1.0 / n2
        out[j, 5] = w * w - (x * x + y * y + z * z)
        out[j, 6] = 2.0 * w
        out[j, 7] = 1.0 if above_inverse[j] else 0.0
    return out


@helper(inline=True)
def _translation(t, rotation, i, below_t, raw, inverse, above_t, terms):
    """The composed translation of sample ``i``: :func:`_compose`'s, with the
    static steps' terms computed once (``terms``, :func:`_static_steps`)."""
    x, y, z = t[i, 0], t[i, 1], t[i, 2]
    if not raw:
        qw, qx, qy, qz = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
        px, py, pz = below_t[0, 0], below_t[0, 1], below_t[0, 2]
        # resample.chain_step's translation
        if inverse:
            x, y, z = _rotate1_inline(qw, -qx, -qy, -qz, px - x, py - y, pz - z)
        else:
            rx, ry, rz = _rotate1_inline(qw, qx, qy, qz, px, py, pz)
            x = rx + x
            y = ry + y
            z = rz + z
    for j in range(terms.shape[0]):
        qx, qy, qz = terms[j, 1], terms[j, 2], terms[j, 3]
        inverse_step = terms[j, 7] != 0.0
        if inverse_step:
            vx = x - above_t[j, 0]
            vy = y - above_t[j, 1]
            vz = z - above_t[j, 2]
        else:
            vx, vy, vz = x, y, z
        # _rotate1_inline with the row-independent terms computed once
        d = qx * vx + qy * vy + qz * vz
        cx = qy * vz - qz * vy
        cy = qz * vx - qx * vz
        cz = qx * vy - qy * vx
        s = terms[j, 5]
        k = terms[j, 4]
        d2 = 2.0 * d
        w2 = terms[j, 6]
        x = (s * vx + d2 * qx + w2 * cx) * k
        y = (s * vy + d2 * qy + w2 * cy) * k
        z = (s * vz + d2 * qz + w2 * cz) * k
        if not inverse_step:
            x += above_t[j, 0]
            y += above_t[j, 1]
            z += above_t[j, 2]
    return x, y, z


@helper(inline=True)
def _row_missing(t, rotation, missing, i, x, y, z):
    """A row the scene hides: masked, or NaN in the composed translation or
    in the mover's rotation (the composed rotation is NaN exactly there: the
    static steps' rotations are finite)."""
    if missing.shape[0] > 0 and missing[i]:
        return True
    w, a, b, c = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
    return (
        (x != x) or (y != y) or (z != z) or (w != w) or (a != a) or (b != b) or (c != c)
    )


@helper(inline=True)
def _translations_into(
    out, t, rotation, missing, below_t, raw, inverse, above_t, terms
):
    for i in range(t.shape[0]):
        x, y, z = _translation(t, rotation, i, below_t, raw, inverse, above_t, terms)
        if _row_missing(t, rotation, missing, i, x, y, z):
            x = y = z = np.nan
        out[i, 0] = x
        out[i, 1] = y
        out[i, 2] = z


@helper(inline=True)
def _summarise(t, rotation, missing, below_t, raw, inverse, above_t, terms):
    # scalars, not arrays, in the loop (registers: ~3x faster)
    low_x = low_y = low_z = np.inf
    high_x = high_y = high_z = -np.inf
    total_x = total_y = total_z = 0.0
    count = 0
    for i in range(t.shape[0]):
        x, y, z = _translation(t, rotation, i, below_t, raw, inverse, above_t, terms)
        if _row_missing(t, rotation, missing, i, x, y, z):
            continue
        low_x = min(low_x, x)
        low_y = min(low_y, y)
        low_z = min(low_z, z)
        high_x = max(high_x, x)
        high_y = max(high_y, y)
        high_z = max(high_z, z)
        total_x += x
        total_y += y
        total_z += z
        count += 1
    return low_x, low_y, low_z, high_x, high_y, high_z, total_x, total_y, total_z, count


# The loops are written once and inlined three times, ``raw`` and
# ``inverse`` constants in each: a loop testing them per row is ~3x slower.
# (error_model="numpy", no fused multiply-add: a division carries no
# ZeroDivisionError branch; the arithmetic is chain_step's. A zero
# quaternion, which frames refuse, would give NaN here, not an error)
@kernel(F2, F2, B1, F2, F2, B, B, F2, F2, B1, options=EXACT_VECTOR_KERNEL)
def mover_translations(
    t,
    rotation,
    missing,
    below_t,
    below_r,
    raw,
    inverse,
    above_t,
    above_r,
    above_inverse,
):
    """The composed translations (n, 3) of :func:`mover_poses` alone (a
    path's positions), NaN rows where missing; ``below_r`` is not read (a
    rotation below the mover turns no translation)."""
    terms = _static_steps(above_t, above_r, above_inverse)
    out = np.empty((t.shape[0], 3))
    if raw:
        _translations_into(
            out, t, rotation, missing, below_t, True, False, above_t, terms
        )
    elif inverse:
        _translations_into(
            out, t, rotation, missing, below_t, False, True, above_t, terms
        )
    else:
        _translations_into(
            out, t, rotation, missing, below_t, False, False, above_t, terms
        )
    return out


@kernel(F2, F2, B1, F2, F2, B, B, F2, F2, B1, options=EXACT_VECTOR_KERNEL)
def mover_summary(
    t,
    rotation,
    missing,
    below_t,
    below_r,
    raw,
    inverse,
    above_t,
    above_r,
    above_inverse,
):
    """(low (3,), high (3,), total (3,), count) of the composed translations
    of the rows that are not missing (NaN low/high and count 0 if none).

    ``total`` adds the rows in order from 0.0, as numpy's axis-0 reduction
    of the rows does (the scene's mean is made of it).
    """
    terms = _static_steps(above_t, above_r, above_inverse)
    if raw:
        got = _summarise(t, rotation, missing, below_t, True, False, above_t, terms)
    elif inverse:
        got = _summarise(t, rotation, missing, below_t, False, True, above_t, terms)
    else:
        got = _summarise(t, rotation, missing, below_t, False, False, above_t, terms)
    low = np.array([got[0], got[1], got[2]])
    high = np.array([got[3], got[4], got[5]])
    total = np.array([got[6], got[7], got[8]])
    count = got[9]
    if count == 0:
        low[:] = np.nan
        high[:] = np.nan
    return low, high, total, count
