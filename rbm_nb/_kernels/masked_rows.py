"""Checks and sign codes of a frame's rows with some rows masked as missing.

A frame built with ``missing=`` (the explorer's eyes: samples below the
tracker's confidence) keeps the caller's frozen arrays and the mask, and the
engine reads the masked rows as NaN (:class:`rbm_nb._engine.frame_data.Samples`).
Its checks and sign codes must be those of the masked arrays a caller would
make (``np.where(mask, nan, rows)``): :func:`masked_signs` reads the caller's
rows and the mask in one pass instead of making those copies (two arrays of
the recording's size at 3 h, and the passes to fill them).
:func:`kept_translations` reads such a frame's kept rows through a static
chain for the explorer's eye centres without a whole lookup.
"""

from __future__ import annotations

import math

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F2, S1, F, kernel
from .quaternion import _rotate1
from .rows import MAX_COORDINATE, unflip_step

# one bool per sample (True: the row is missing)
_MASK = "boolean[::1]"


@kernel(F2, F2, _MASK, F, S1, options=EXACT_VECTOR_KERNEL)
def masked_signs(t, q, mask, tol, codes):
    """``rows.moving_signs`` of ``t`` (n, 3) and ``q`` (n, 4) with the rows
    in ``mask`` all NaN, without making those arrays.

    A masked row counts as missing and gets the code +1 (a NaN row's sign
    in ``moving_signs``: its dot product is NaN, not negative); it is not
    read, so whatever it holds is neither checked nor carried to the next
    row's sign. Every other row goes through ``moving_signs``' operations in
    the same order, so ``codes`` and the counts are the same.

    Returns
    -------
    bad, missing : int
        As ``rows.moving_signs``: rows that fail a check, missing rotations.
    """
    n = q.shape[0]
    bad = 0
    missing = 0
    have = False
    pw = px = py = pz = 0.0
    for i in range(n):
        if mask[i]:
            missing += 1
            codes[i] = 1
            continue
        x, y, z = t[i, 0], t[i, 1], t[i, 2]
        nan = (x != x) + (y != y) + (z != z)
        inf = (abs(x) > MAX_COORDINATE) + (abs(y) > MAX_COORDINATE)
        inf += abs(z) > MAX_COORDINATE
        bad += ((nan != 0) & (nan != 3)) | (inf != 0)
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        nan = (w != w) + (x != x) + (y != y) + (z != z)
        inf = (abs(w) > MAX_COORDINATE) + (abs(x) > MAX_COORDINATE)
        inf += (abs(y) > MAX_COORDINATE) + (abs(z) > MAX_COORDINATE)
        bad += ((nan != 0) & (nan != 4)) | (inf != 0)
        missing += nan == 4
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        bad += abs(norm - 1.0) > tol
        d = 1.0 if (norm == 1.0) | (norm != norm) else norm
        w, x, y, z = w / d, x / d, y / d, z / d
        sign, _, _, _, _, pw, px, py, pz, have = unflip_step(
            w, x, y, z, pw, px, py, pz, have
        )
        codes[i] = -1 if sign < 0.0 else 1
    return bad, missing


@kernel(F2, _MASK, F2, F2, _MASK, F2, options=EXACT_VECTOR_KERNEL)
def kept_translations(t, mask, steps_t, steps_r, inverse, out):
    """The translations of the rows not in ``mask`` and not NaN, carried
    through static steps, into the first columns of ``out`` (3, n).

    ``t`` (n, 3) is a moving frame's translation wrt its parent; step ``k``
    (``steps_t[k]``, ``steps_r[k]``) maps that frame into the next one up
    the chain, or down it where ``inverse[k]`` (its transform inverted):
    ``resample.chain_step``'s translation arithmetic, in its order, so each
    value is the one a lookup composes (without its rotations). Returns how
    many columns were written (the rows kept, in order).
    """
    m = 0
    for i in range(t.shape[0]):
        if mask[i]:
            continue
        px, py, pz = t[i, 0], t[i, 1], t[i, 2]
        if px != px:  # a missing sample (NaN rows are all NaN)
            continue
        for k in range(steps_t.shape[0]):
            qw, qx, qy, qz = steps_r[k, 0], steps_r[k, 1], steps_r[k, 2], steps_r[k, 3]
            if inverse[k]:
                px, py, pz = _rotate1(
                    qw, -qx, -qy, -qz,
                    px - steps_t[k, 0], py - steps_t[k, 1], pz - steps_t[k, 2],
                )  # fmt: skip
            else:
                px, py, pz = _rotate1(qw, qx, qy, qz, px, py, pz)
                px += steps_t[k, 0]
                py += steps_t[k, 1]
                pz += steps_t[k, 2]
        out[0, m], out[1, m], out[2, m] = px, py, pz
        m += 1
    return m
