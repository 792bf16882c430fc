"""The gaze calls' per-sample arithmetic, one pass each (issue 35).

:func:`rbm_nb.gaze.directions`, :func:`~rbm_nb.gaze.angles` and
:func:`~rbm_nb.gaze.rates` made several numpy passes and (n, k)
temporaries per call (norms, a masked copy of the valid rows, three matrix
products, ``arctan2``/``hypot``/``degrees``, ``column_stack``, four
``searchsorted``); at 3 h of the explorer's recording (3.7 M samples per
eye) those passes were most of building its plots. Each kernel here does
the same operations in the same order on one row at a time, so the values
are numpy's bit for bit (the arc tangents stay numpy's own) (``tests/core/test_gaze_rows.py`` compares them
with the numpy versions they replace).
"""

from __future__ import annotations

import math

from .._infra.config import EXACT_VECTOR_KERNEL
from ._jit import F1, F2, B, F, kernel
from .quaternion import _rotate1

B1 = "boolean[::1]"


@kernel(F2, B1, F1, F, B, F2, options=EXACT_VECTOR_KERNEL)
def sight_rows(rotation, valid, axis, min_z, check_angle, out):
    """Unit lines of sight of the ``valid`` rows of ``rotation`` (n, 4).

    Row ``k`` of ``out`` (m, 3; m valid rows) is the ``k``-th valid
    quaternion, divided by its norm (as ``np.linalg.norm``: the squares
    summed in order, one square root), applied to ``axis`` (3,); with
    ``check_angle``, NaN where its z component is below ``min_z`` (the
    cosine of the largest angle from the z axis) or NaN.
    """
    k = 0
    for i in range(rotation.shape[0]):
        if not valid[i]:
            continue
        w, x, y, z = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        sx, sy, sz = _rotate1(w, x, y, z, axis[0], axis[1], axis[2])
        if check_angle and not sz >= min_z:
            sx = sy = sz = math.nan
        out[k, 0], out[k, 1], out[k, 2] = sx, sy, sz
        k += 1


@kernel(F2, B1, F1, F1, F1, F2, options=EXACT_VECTOR_KERNEL)
def axis_components(vectors, valid, right, forward, up, out):
    """The components of ``vectors`` (n, 3) along ``right``, ``forward`` and
    ``up`` into the rows of ``out`` (3, n); NaN where not ``valid``.

    The angles themselves are left to numpy (``np.arctan2`` on these rows):
    its ``arctan2`` is not libm's on every machine (SVML where the CPU has
    AVX-512), and it is faster than a scalar call per sample.
    """
    for i in range(vectors.shape[0]):
        if not valid[i]:
            out[0, i] = out[1, i] = out[2, i] = math.nan
            continue
        vx, vy, vz = vectors[i, 0], vectors[i, 1], vectors[i, 2]
        out[0, i] = vx * right[0] + vy * right[1] + vz * right[2]
        out[1, i] = vx * forward[0] + vy * forward[1] + vz * forward[2]
        out[2, i] = vx * up[0] + vy * up[1] + vz * up[2]


@kernel(F1, F2, F, F, F2, options=EXACT_VECTOR_KERNEL)
def windowed_slopes(t, values, half, min_span, out):
    """Each column's slope between the first and the last finite sample within
    ``half`` of each finite sample (times ``t``, non-decreasing), into ``out``.

    NaN where the sample is not finite or the samples found span less than
    ``min_span``. ``np.searchsorted``'s answers among the finite samples,
    found by two pointers that only move forward (the times are in order).
    """
    n, columns = values.shape
    for c in range(columns):
        first = 0  # the first finite row with a time >= t - half
        scan = 0  # the first row with a time > t + half
        last = -1  # the last finite row before scan
        for i in range(n):
            out[i, c] = math.nan
            if not math.isfinite(values[i, c]):
                continue
            lo = t[i] - half
            hi = t[i] + half
            while not math.isfinite(values[first, c]) or t[first] < lo:
                first += 1  # (stops at i at the latest)
            while scan < n and t[scan] <= hi:
                if math.isfinite(values[scan, c]):
                    last = scan
                scan += 1
            span = t[last] - t[first]
            if last > first and span >= min_span:
                out[i, c] = (values[last, c] - values[first, c]) / span


@kernel(F2, B1, F1, F, F1, F, B, F1, F1, F1, F2, options=EXACT_VECTOR_KERNEL)
def sight_components(
    rotation, missing, confidence, min_confidence, axis, min_z, check, r, right,
    forward, out,
):  # fmt: skip
    """``gaze.directions`` then ``gaze.angles``' components in one pass, for
    an eye whose parent reaches the reference through static frames only.

    Row ``i`` of ``rotation`` (n, 4) is a sample where it is not
    ``missing``, finite and its ``confidence`` is at least
    ``min_confidence``; its line of sight is made as :func:`sight_rows`
    does (NaN beyond ``min_z`` when ``check``), represented in the
    reference by the static rotation ``r`` (4,) as ``resample.transform_blocks``
    does, and its components along ``right`` and ``forward`` go to
    ``out[0, i]`` and ``out[1, i]`` (NaN for any other row, and where the
    line of sight is NaN: ``gaze.angles`` leaves such rows NaN).
    """
    for i in range(rotation.shape[0]):
        out[0, i] = out[1, i] = math.nan
        if missing[i] or not confidence[i] >= min_confidence:
            continue
        w, x, y, z = rotation[i, 0], rotation[i, 1], rotation[i, 2], rotation[i, 3]
        if not (
            math.isfinite(w) and math.isfinite(x) and math.isfinite(y)
            and math.isfinite(z)
        ):  # fmt: skip
            continue
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        sx, sy, sz = _rotate1(w, x, y, z, axis[0], axis[1], axis[2])
        if check and not sz >= min_z:
            continue
        vx, vy, vz = _rotate1(r[0], r[1], r[2], r[3], sx, sy, sz)
        if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(vz)):
            continue
        out[0, i] = vx * right[0] + vy * right[1] + vz * right[2]
        out[1, i] = vx * forward[0] + vy * forward[1] + vz * forward[2]
