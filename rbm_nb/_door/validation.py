"""Checks shared by the public functions: everything is validated here, once.

Each checker converts its argument (``np.asarray``), checks shape and values
and raises a ``ValueError`` that names the argument and says what was
expected. What comes out is C-contiguous float64, ready for the kernels.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._infra import memory as _memory
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._kernels import rows as _rows
from .._kernels._arrays import is_scalar, kernel_array, kernel_ready
from .unpack import resolve_axis

__all__ = [
    "resolve_axis",
    "is_scalar",
    "check_last_axis",
    "normalize_quaternions",
    "check_finite",
    "check_coordinates",
    "check_no_inf",
    "check_missing_rows",
    "check_whole_rows",
    "moving_samples",
    "check_unit_norms",
    "check_tolerance",
    "check_what",
]

WHAT_MODES = ("reference_frame", "moving_frame", "representation_frame")


def check_last_axis(arr: np.ndarray, size: int, name: str) -> None:
    if arr.ndim == 0 or arr.shape[-1] != size:
        raise ValueError(
            f"{name} must have length {size} along its last axis, got shape {arr.shape}"
        )


def normalize_quaternions(
    q: np.ndarray, name: str, allow_nan: bool = False
) -> np.ndarray:
    """Unit quaternions from (..., 4) floats, within the unit tolerance.

    Quaternions whose norm is within ``UNIT_QUATERNION_TOLERANCE`` of 1 are
    divided by their norm; zero or far-from-unit ones raise, naming the
    first offending index. With ``allow_nan`` rows containing NaN are passed
    through (missing samples in recordings); infinities always raise.

    Returns
    -------
    ndarray, shape like ``q``, C-contiguous float64
    """
    if q.ndim == 2 and q.shape[1] == 4:
        # one pass when every row is fine; the checks below name a bad one
        out, first_bad = _rows.unit_rows(
            kernel_array(q), UNIT_QUATERNION_TOLERANCE, allow_nan
        )
        if first_bad < 0:
            return out
    inf = np.isinf(q).any(axis=-1)
    if inf.any():
        bad = np.argwhere(inf)[0]
        raise ValueError(f"{name}{_index(bad)} is not finite: {q[tuple(bad)]}")
    norms = np.sqrt(np.einsum("...i,...i->...", q, q))
    nan = np.isnan(norms)
    if nan.any() and not allow_nan:
        bad = np.argwhere(nan)[0]
        raise ValueError(f"{name}{_index(bad)} is not finite: {q[tuple(bad)]}")
    check_unit_norms(q, name)  # the one rule (NaN rows pass it)
    if np.all((norms == 1.0) | nan):
        return kernel_array(q)
    with np.errstate(invalid="ignore"):
        return kernel_array(q / norms[..., None])


def check_no_inf(arr: np.ndarray, name: str, row_axis: bool = True) -> None:
    """Raise for infinities (NaN passes: a missing sample, not a mistake).

    With ``row_axis`` the message names the row (all but the last index).
    """
    if kernel_ready(arr) and arr.dtype == np.float64:
        if _rows.infinities(arr.reshape(-1)) == 0:
            return  # one pass when there is none; below: where the first is
    inf = np.isinf(arr)
    if inf.any():
        bad = np.argwhere(inf)[0]
        where = bad[:-1] if row_axis and arr.ndim > 1 else bad
        raise ValueError(f"{name}{_index(where)} is not finite")


def check_whole_rows(arr: np.ndarray, name: str) -> None:
    """Rows (components last, any leading shape) are finite or all NaN.

    As :func:`check_missing_rows` for frames' data, for the arrays given to
    the transforms: a row of NaN is a missing sample and passes, a row with
    only some NaN (``[nan, 0, 0]``) or an infinity raises, naming the row by
    its index in ``arr``.
    """
    if arr.ndim == 0 or arr.size == 0:
        return
    flat = arr.reshape(-1, arr.shape[-1])
    try:
        check_missing_rows(kernel_array(flat), name)
    except ValueError:
        nan = np.isnan(flat)
        bad = (nan.any(axis=-1) & ~nan.all(axis=-1)) | np.isinf(flat).any(axis=-1)
        if not bad.any():
            check_coordinates(arr, name)  # finite, but too large
        row = np.unravel_index(int(np.argmax(bad)), arr.shape[:-1])
        raise ValueError(
            f"{name}{_index(row)} is not finite: {arr[row]} (a missing sample "
            "is a row of NaN only)"
        ) from None


def check_unit_norms(q: np.ndarray, name: str) -> np.ndarray:
    """The one rule for quaternion arguments: unit norm within the tolerance.

    Rows of ``q`` (components last) farther than ``UNIT_QUATERNION_TOLERANCE``
    from unit norm, or zero, raise naming the first one; NaN rows (missing
    samples) pass. Nothing is changed: the math normalises where it needs to.
    Returns the rows' norms (shape ``q.shape[:-1]``, NaN where a row is
    missing), for a caller that also counts the missing rows.
    """
    with np.errstate(invalid="ignore"):
        norms = np.sqrt(np.einsum("...i,...i->...", q, q))
        off = np.abs(norms - 1.0) > UNIT_QUATERNION_TOLERANCE
    if off.any():
        bad = np.argwhere(off)[0]
        norm = norms[tuple(bad)]
        kind = "a zero quaternion" if norm == 0 else f"of norm {norm:.6g}"
        raise ValueError(
            f"{name}{_index(bad)} is {kind}; rotations must be unit quaternions "
            f"(norm within {UNIT_QUATERNION_TOLERANCE} of 1)"
        )
    return norms


def check_missing_rows(arr: np.ndarray, name: str) -> bool:
    """Rows of (n, k) data are finite or entirely NaN (a missing sample).

    A partly NaN row or an infinity is a mistake, not missing data: raise
    naming the first such row. Returns whether a row is missing.
    """
    if arr.ndim == 2 and _rows.first_bad_row(kernel_array(arr)) < 0:
        # one pass when every row is fine (below: which one is not); a row
        # is then all NaN or none, so its first column tells
        return bool(np.isnan(arr[:, 0]).any())
    nan = np.isnan(arr)
    partial = nan.any(axis=-1) & ~nan.all(axis=-1)
    bad = partial | np.isinf(arr).any(axis=-1)
    if bad.any():
        row = np.argwhere(bad)[0]
        raise ValueError(
            f"{name}{_index(row)} is not finite (a missing sample is a row of NaN only)"
        )
    check_coordinates(arr, name)
    return bool(nan.any())


def check_coordinates(arr: np.ndarray, name: str, row_axis: bool = True) -> None:
    """Refuse finite values beyond ``MAX_COORDINATE`` (1e150), naming the first.

    No position comes near it, and composing frames adds and multiplies
    coordinates: beyond it the results overflow to inf.
    """
    with np.errstate(invalid="ignore"):
        huge = np.abs(arr) > _rows.MAX_COORDINATE
    if huge.any():
        bad = np.argwhere(huge)[0]
        where = bad[:-1] if row_axis and arr.ndim > 1 else bad
        raise ValueError(
            f"{name}{_index(where)} holds {arr[tuple(bad)]:g}, beyond "
            f"±{_rows.MAX_COORDINATE:g}: coordinates that large overflow when "
            "frames are composed"
        )


def moving_samples(
    t: np.ndarray, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool] | None:
    """A moving frame's private arrays, if its (n, 3) ``t`` and (n, 4) ``q`` pass.

    The checks of ``check_missing_rows`` on both and of
    ``normalize_quaternions(q, allow_nan=True)``, in one kernel pass that
    also makes the frame's copies (``rows.moving_samples``).

    Returns
    -------
    (t, q, r, missing) or None
        Copies of ``t`` and ``q``, the unit quaternions of ``q`` without sign
        flips, and whether a rotation row is missing (all NaN); None if a
        row fails a check: the caller's checks then name it.
    """
    # One huge page aligned buffer for the three (_memory.zeros). Registering
    # the five head/eye frames (benchmarks/bench_fused.py --only
    # registration, best of 5): 6.5-8.5 ms in 6 of 7 runs; 11.8-14.4 ms
    # before, check by check; 12.7-16.4 ms with a plain np.empty per array.
    n = len(q)
    flat = _memory.zeros((11 * n,))
    t_out = flat[: 3 * n].reshape(n, 3)
    q_out = flat[3 * n : 7 * n].reshape(n, 4)
    r_out = flat[7 * n :].reshape(n, 4)
    bad, missing = _rows.moving_samples(
        kernel_array(t), kernel_array(q), UNIT_QUATERNION_TOLERANCE, t_out, q_out, r_out
    )
    if bad:
        return None
    return t_out, q_out, r_out, bool(missing)


def check_finite(arr: np.ndarray, name: str, row_axis: bool = True) -> None:
    """Raise for NaN or infinities, naming the first bad row (or element)."""
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.argwhere(~finite)[0]
        where = bad[:-1] if row_axis and arr.ndim > 1 else bad
        raise ValueError(f"{name}{_index(where)} is not finite")


def check_tolerance(value: Any, name: str = "tol") -> float:
    """A tolerance argument: a finite number >= 0 (the one rule for all of them)."""
    if not is_scalar(value) or not 0 <= value < np.inf:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def check_what(what: Any) -> str:
    if what not in WHAT_MODES:
        raise ValueError(
            f"what must be one of {', '.join(repr(m) for m in WHAT_MODES)}, got {what!r}"
        )
    return what


def _index(idx) -> str:
    idx = [int(i) for i in np.atleast_1d(idx)]
    return "[" + ", ".join(str(i) for i in idx) + "]" if idx else ""
