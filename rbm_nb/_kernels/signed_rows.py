"""A moving frame's unit, sign-continuous rotations, made from its rotations as
kept and one byte per sample.

Interpolation needs each rotation divided by its norm and given the sign
that keeps it on the hemisphere of the sample before (``quaternion.unflip``).
Frames used to keep those rows, 32 bytes per sample beside the caller's
own. They keep a sign code per sample instead (int8), and the kernels make
each row when they read it (:func:`signed_unit_row`), by the operations
``rows.moving_samples`` makes them with, so every row has the same bits:

* ``+1`` / ``-1``: the row as stored divided by its norm (``unit_rows``:
  rows of norm exactly 1 and NaN rows as they are), times the sign;
* ``+2`` / ``-2``: the row as stored is the unit row already (an inverted
  frame keeps the conjugates of its unit rows): only the sign.

The stored rows the codes apply to are those the kernels get as the
frame's rotations (``Samples.rotation``: NaN in masked rows).
"""

from __future__ import annotations

import math

import numpy as np

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F2, S1, helper, kernel

__all__ = ["unit_divisor", "signed_unit_row", "signed_unit_rows", "sign_codes"]


@helper(inline=True)
def unit_divisor(p, s, i):
    """What row i of stored rows ``p`` (n, 4) with sign codes ``s`` (n,) is
    divided by to make it unit: its norm, or 1.0 where it is taken as it is
    (norm exactly 1, a NaN row, codes +-2)."""
    w, x, y, z = p[i, 0], p[i, 1], p[i, 2], p[i, 3]
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    # x / 1.0 is x (NaN payloads too): the rows unit_rows leaves as they are
    return 1.0 if (norm == 1.0) | (norm != norm) | (abs(s[i]) == 2) else norm


@helper(inline=True)
def signed_unit_row(p, s, i):
    """Row i of the unit, sign-continuous rotations of stored rows ``p`` (n, 4)
    with sign codes ``s`` (n,): (w, x, y, z)."""
    d = unit_divisor(p, s, i)
    sign = -1.0 if s[i] < 0 else 1.0
    return (
        sign * (p[i, 0] / d),
        sign * (p[i, 1] / d),
        sign * (p[i, 2] / d),
        sign * (p[i, 3] / d),
    )


@kernel(F2, S1, options=EXACT_VECTOR_KERNEL)
def signed_unit_rows(p, s):
    """Every row of :func:`signed_unit_row`, as an (n, 4) array (the engine's
    whole-array routes; the fused kernels read rows one at a time)."""
    n = p.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        w, x, y, z = signed_unit_row(p, s, i)
        out[i, 0] = w
        out[i, 1] = x
        out[i, 2] = y
        out[i, 3] = z
    return out


@helper(inline=True)
def _same(a, b):
    return a == b or (a != a and b != b)


@kernel(F2, F2, S1)
def sign_codes(p, r, out):
    """The codes that give rows ``r`` (n, 4) from the stored rows ``p``.

    For a frame that made its unit rows ``r`` itself (copies of writeable
    arrays, inverted frames): per row the first code of 1, -1, 2, -2 whose
    row equals r's (NaN where r is NaN) goes to ``out``.

    Returns
    -------
    int
        The first row no code gives, or -1.
    """
    for i in range(p.shape[0]):
        found = False
        for code in (1, -1, 2, -2):
            out[i] = code
            w, x, y, z = signed_unit_row(p, out, i)
            if (
                _same(w, r[i, 0])
                and _same(x, r[i, 1])
                and _same(y, r[i, 2])
                and _same(z, r[i, 3])
            ):
                found = True
                break
        if not found:
            return i
    return -1
