"""What ``Transform``'s arguments become before any arithmetic: checked arrays.

The checks of :class:`rbm_nb.core.rigid_transform.Transform` (translations,
rotations, ratios and angles, per-axis masks) and the two array habits every
method shares: batch rows flattened to ``(n, width)`` for the kernels and
read-only storage.
"""

from __future__ import annotations

import numpy as np

from .._door import shapes as _shapes
from .._door.unpack import kernel_array
from .._door.validation import check_finite, normalize_quaternions

AXES = "xyz"


def unit_rotation(rotation) -> np.ndarray:
    return normalize_quaternions(_shapes.last_axis(rotation, "rotation", 4), "rotation")


def finite_translation(translation) -> np.ndarray:
    t = _shapes.last_axis(translation, "translation", 3)
    check_finite(t, "translation")
    return t


def finite_numbers(ratio, name: str = "ratio") -> np.ndarray:
    """A ratio or an angle: any shape, finite."""
    try:
        r = np.asarray(ratio, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be a number or an array of numbers") from err
    if not np.isfinite(r).all():
        raise ValueError(f"{name} must be finite, got {ratio!r}")
    return r


def axis_mask(mask, name: str) -> np.ndarray:
    """A 0/1 weight per axis from True/False/None, 'xz'-style strings or 3 flags."""
    if mask is True:
        return np.ones(3)
    if mask is False or mask is None:
        return np.zeros(3)
    if isinstance(mask, str):
        letters = mask.lower()
        if not letters or any(c not in AXES for c in letters):
            raise ValueError(f"{name} must use the letters x, y, z, got {mask!r}")
        return np.array([float(c in letters) for c in AXES])
    arr = np.asarray(mask)
    if arr.shape != (3,) or not np.isin(arr, (0, 1)).all():
        raise ValueError(
            f"{name} must be True, False, None, a string of axes such as 'xy' or "
            f"three 0/1 flags, got {mask!r}"
        )
    return arr.astype(np.float64)


def mirror_axis(rotation_mirror: str) -> int:
    """The index of the axis named by ``rotation_mirror`` ("x", "y" or "z")."""
    if rotation_mirror not in ("x", "y", "z"):
        raise ValueError(
            f"rotation_mirror must be 'x', 'y', 'z' or None, got {rotation_mirror!r}"
        )
    return AXES.index(rotation_mirror)


def rows(arr: np.ndarray, shape: tuple, width: int) -> np.ndarray:
    """``arr`` broadcast to the batch ``shape`` as kernel rows ``(n, width)``."""
    return kernel_array(np.broadcast_to(arr, shape + (width,))).reshape(-1, width)


def read_only(arr: np.ndarray) -> np.ndarray:
    arr = np.ascontiguousarray(arr)
    arr.flags.writeable = False
    return arr


def array_text(arr: np.ndarray, prefix: str) -> str:
    return np.array2string(
        arr,
        precision=6,
        suppress_small=True,
        separator=", ",
        threshold=12,
        edgeitems=2,
        prefix=prefix,
    )
