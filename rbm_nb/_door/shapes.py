"""The door's shape rules for the facades' array arguments, each written once.

The transforms lay their arguments out as blocks (:mod:`rbm_nb._door.inputs`);
the other facades (conversions, se3, quaternions, coordinates, the
rigid transform, the plots) take arrays whose last axes have a fixed shape,
or a spatial axis of a fixed length anywhere. What they check is here, so
that every facade words the same mistake the same way:

* :func:`with_tail`: numbers whose last axes have the shape ``tail``
  (``(..., 3, 3)``), as float64;
* :func:`rows`: the same flattened to C-contiguous ``(n, *tail)`` rows plus
  the leading shape they came from (``finite=True``: and no NaN or
  infinity, naming the first bad row by its index in the argument);
* :func:`rows_within`: rows of matrices and the tolerance they are tested with;
* :func:`paired_rows`: two such arguments over their broadcast leading shape;
* :func:`last_axis`: numbers with a last axis of length ``size``;
* :func:`one_or_many`: one row ``(width,)`` or ``(N, width)`` rows;
* :func:`along_axis`: an axis of length ``length`` anywhere (the one axis
  rule, :func:`rbm_nb._door.unpack.resolve_axis`), moved last, no infinities;
* :func:`where`: ``[i, j]`` of a flat row index in a leading shape, the way
  every message names a row.

Rotation and homogeneous matrices are checked by :mod:`rbm_nb._door.poses`
(apart, so that only what takes them loads their kernels).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .unpack import float_array, kernel_array, moveaxis, resolve_axis
from .validation import check_last_axis, check_no_inf, check_tolerance

__all__ = [
    "with_tail",
    "rows",
    "rows_within",
    "paired_rows",
    "last_axis",
    "one_or_many",
    "with_tails",
    "along_axis",
    "where",
]


def where(lead: tuple, flat: int) -> str:
    """``[i, j]`` of a flat row index in the leading shape (empty for a scalar)."""
    if lead == ():
        return ""
    return "[" + ", ".join(str(int(i)) for i in np.unravel_index(flat, lead)) + "]"


def with_tail(value: Any, name: str, tail: tuple[int, ...]) -> np.ndarray:
    """``value`` as float64 whose last axes have the shape ``tail``.

    Raises
    ------
    ValueError
        ``{name} must have shape (..., 3, 3), got (2, 3)``; or not numeric.
    """
    arr = float_array(value, name)
    k = len(tail)
    if arr.ndim < k or arr.shape[arr.ndim - k :] != tail:
        expected = "(..., " + ", ".join(map(str, tail)) + ")" if tail else "(...)"
        raise ValueError(f"{name} must have shape {expected}, got {arr.shape}")
    return arr


def rows(
    value: Any, name: str, tail: tuple[int, ...], finite: bool = False
) -> tuple[np.ndarray, tuple]:
    """``value`` as C-contiguous float64 rows ``(n, *tail)`` and its leading shape.

    With ``finite`` a row holding NaN or an infinity raises, naming it.
    """
    arr = with_tail(value, name, tail)
    lead = arr.shape[: arr.ndim - len(tail)]
    flat = kernel_array(arr.reshape((-1,) + tail))
    if finite:
        bad = ~np.isfinite(flat.reshape(flat.shape[0], -1)).all(axis=1)
        if bad.any():
            raise ValueError(f"{name}{where(lead, int(np.argmax(bad)))} is not finite")
    return flat, lead


def rows_within(
    value: Any, name: str, tail: tuple[int, ...], tol: Any
) -> tuple[np.ndarray, tuple, float]:
    """:func:`rows` of matrices to be tested against a tolerance ``tol``
    (checked first, as a finite number >= 0), and ``tol`` as a float."""
    tol = check_tolerance(tol)
    flat, lead = rows(value, name, tail)
    return flat, lead, tol


def paired_rows(
    a: Any, a_name: str, a_tail: tuple[int, ...],
    b: Any, b_name: str, b_tail: tuple[int, ...],
) -> tuple[np.ndarray, np.ndarray, tuple]:  # fmt: skip
    """Two arguments as rows over their broadcast leading shape."""
    a = with_tail(a, a_name, a_tail)
    b = with_tail(b, b_name, b_tail)
    a_lead = a.shape[: a.ndim - len(a_tail)]
    b_lead = b.shape[: b.ndim - len(b_tail)]
    try:
        lead = np.broadcast_shapes(a_lead, b_lead)
    except ValueError:
        raise ValueError(
            f"{a_name} of shape {a.shape} and {b_name} of shape {b.shape} do not "
            f"broadcast: their leading shapes {a_lead} and {b_lead} must be compatible"
        ) from None
    a = kernel_array(np.broadcast_to(a, lead + a_tail)).reshape((-1,) + a_tail)
    b = kernel_array(np.broadcast_to(b, lead + b_tail)).reshape((-1,) + b_tail)
    return a, b, lead


def last_axis(value: Any, name: str, size: int) -> np.ndarray:
    """Numbers whose last axis has length ``size`` (any leading shape), float64.

    Raises
    ------
    ValueError
        ``{name} must have length 3 along its last axis, got shape (2,)``.
    """
    arr = float_array(value, name)
    check_last_axis(arr, size, name)
    return arr


def one_or_many(value: Any, name: str, width: int) -> np.ndarray:
    """One row ``(width,)`` or ``(N, width)`` rows, as float64 ``(N, width)``."""
    arr = float_array(value, name)
    if arr.ndim == 1:
        arr = arr[np.newaxis, :]
    if arr.ndim != 2 or arr.shape[1] != width:
        raise ValueError(
            f"{name} must have shape ({width},) or (N, {width}), got {np.shape(value)}"
        )
    return arr


def with_tails(
    value: Any, base: Any, name: str, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """``plot.vectors``' arrows: :func:`one_or_many` rows ``(N, width)`` of
    ``value`` and their tails ``(N, width)`` (see :func:`tails`); ``name``
    starts the messages."""
    arr = one_or_many(value, f"{name}: arr", width)
    return arr, tails(base, len(arr), name, width)


def triads(value: Any, base: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``plot.quaternions``' input: finite, non-zero quaternion rows ``(N, 4)``
    of ``value`` and the triads' origins ``(N, 3)`` (see :func:`tails`)."""
    q = one_or_many(value, f"{name}: arr", 4)
    # (any non-zero norm: the kernel normalises)
    if not np.isfinite(q).all() or not np.einsum("ij,ij->i", q, q).all():
        raise ValueError(f"{name} must be finite and non-zero")
    return q, tails(base, len(q), name, 3)


def tails(base: Any, n: int, name: str, width: int) -> np.ndarray:
    """Where ``n`` arrows start: ``base`` as one row (broadcast) or one per
    arrow, ``(n, width)``; None: the origin."""
    if base is None:
        return np.zeros((n, width))
    rows = one_or_many(base, f"{name}: base", width)
    if len(rows) == 1 and n > 1:
        rows = np.repeat(rows, n, axis=0)
    if rows.shape != (n, width):
        raise ValueError(
            f"{name}: base must have shape ({width},) or {(n, width)}, "
            f"got {np.shape(base)}"
        )
    return rows


def along_axis(
    value: Any,
    name: str,
    axis: Any,
    length: int,
    what: str,
    axis_name: str = "axis",
    finite: bool = False,
) -> tuple[np.ndarray, int]:
    """``value`` with an axis of length ``length`` (``what`` it holds) at ``axis``.

    Returns the float64 array with that axis moved last, and the axis made
    non-negative. NaN passes (a missing sample) unless ``finite``;
    infinities raise naming the row.

    Raises
    ------
    ValueError
        ``{name} must have an axis of length 4 (w, x, y, z), got a scalar``;
        ``axis=2 is out of range ...``; ``{name} must have length 4
        (w, x, y, z) along axis=0, got shape (4, 3)``.
    """
    arr = float_array(value, name)
    if arr.ndim == 0:
        raise ValueError(
            f"{name} must have an axis of length {length} ({what}), got a scalar"
        )
    ax = resolve_axis(axis, arr.ndim, axis_name)
    if arr.shape[ax] != length:
        raise ValueError(
            f"{name} must have length {length} ({what}) along {axis_name}={axis}, "
            f"got shape {arr.shape}"
        )
    moved = moveaxis(arr, ax, -1)
    if finite:
        ok = np.isfinite(moved)
        if not ok.all():
            bad = np.argwhere(~ok)[0][:-1]
            raise ValueError(
                f"{name} must be finite; {name}{_index(bad)} is not finite"
            )
    else:
        check_no_inf(moved, name)
    return moved, ax


def _index(idx: Any) -> str:
    return "[" + ", ".join(str(int(i)) for i in idx) + "]" if len(idx) else ""
