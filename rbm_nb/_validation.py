"""Checks shared by the public functions: everything is validated here, once.

Each checker converts its argument (``np.asarray``), checks shape and values
and raises a ``ValueError`` that names the argument and says what was
expected. What comes out is C-contiguous float64, ready for the kernels.
"""

from __future__ import annotations

import operator

import numpy as np

from ._config import UNIT_QUATERNION_TOLERANCE

WHAT_MODES = ("reference_frame", "moving_frame", "representation_frame")


def as_float_array(arr, name: str) -> np.ndarray:
    """``arr`` as a float64 ndarray, accepting numpy-quaternion dtype.

    Quaternion-dtype arrays gain a trailing axis of length 4 (w, x, y, z).
    """
    arr = getattr(arr, "data", arr) if _is_xarray(arr) else arr
    arr = np.asarray(arr)
    if arr.dtype.name == "quaternion":
        # numpy-quaternion stores four contiguous float64 per element
        return np.ascontiguousarray(arr).view(np.float64).reshape(arr.shape + (4,))
    if arr.dtype.kind not in "iufb":
        raise ValueError(f"{name} must be numeric, got dtype {arr.dtype}")
    return np.asarray(arr, dtype=np.float64)


def _is_xarray(obj) -> bool:
    return type(obj).__module__.startswith("xarray.")


def resolve_axis(axis, ndim: int, name: str = "axis") -> int:
    """Turn a possibly negative axis into a valid non-negative one."""
    try:
        axis = operator.index(axis)
    except TypeError:
        raise ValueError(f"{name} must be an integer, got {axis!r}") from None
    if not -ndim <= axis < ndim:
        raise ValueError(
            f"{name}={axis} is out of range for an array with {ndim} dimension(s)"
        )
    return axis % ndim


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
    norms = np.sqrt(np.einsum("...i,...i->...", q, q))
    nan = np.isnan(norms)
    if nan.any():
        if not allow_nan or np.isinf(q).any():
            bad = np.argwhere(~np.isfinite(norms))[0]
            raise ValueError(f"{name}{_index(bad)} is not finite: {q[tuple(bad)]}")
    off = np.abs(norms - 1.0) > UNIT_QUATERNION_TOLERANCE
    if off.any():
        bad = np.argwhere(off)[0]
        norm = norms[tuple(bad)]
        kind = "a zero quaternion" if norm == 0 else f"of norm {norm:.6g}"
        raise ValueError(
            f"{name}{_index(bad)} is {kind}; rotations must be unit quaternions "
            f"(norm within {UNIT_QUATERNION_TOLERANCE} of 1)"
        )
    if np.all((norms == 1.0) | nan):
        return np.ascontiguousarray(q, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        return np.ascontiguousarray(q / norms[..., None])


def check_finite(arr: np.ndarray, name: str) -> None:
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.argwhere(~finite)[0]
        raise ValueError(
            f"{name}{_index(bad[:-1] if arr.ndim > 1 else bad)} is not finite"
        )


def check_what(what) -> str:
    if what not in WHAT_MODES:
        raise ValueError(
            f"what must be one of {', '.join(repr(m) for m in WHAT_MODES)}, got {what!r}"
        )
    return what


def check_mode(mode) -> str:
    if mode not in ("quaternion", "rotation_vector"):
        raise ValueError(
            f"mode must be 'quaternion' or 'rotation_vector', got {mode!r}"
        )
    return mode


def _index(idx) -> str:
    idx = [int(i) for i in np.atleast_1d(idx)]
    return "[" + ", ".join(str(i) for i in idx) + "]" if idx else ""
