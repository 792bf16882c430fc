"""Points, vectors and quaternions carried from one resolved frame to another.

An array argument is rearranged to (n, k, c) blocks (time first, k
independent items, c components), matched with the chain's timestamps,
transformed by one kernel call and laid out again like the input.
"""

from __future__ import annotations

import numpy as np

from .. import _time
from .._door import float_array, kernel_array
from .._kernels import resample as kr
from .._kernels.rows import MAX_COORDINATE
from .._validation import (
    check_whole_rows,
    normalize_quaternions,
    resolve_axis,
)
from . import chain as _chain

__all__ = ["Blocks", "transform", "track_of", "SIZES"]

SIZES = {"points": 3, "vectors": 3, "quaternions": 4}


def _moveaxis(arr: np.ndarray, source, destination) -> np.ndarray:
    """``np.moveaxis``, or ``arr`` itself where no axis moves.

    The usual argument, (n, 3) with time first and coordinates last, moves
    nothing; numpy's argument handling alone costs about 5 µs a call, a
    tenth of a one-point transform.
    """
    n = arr.ndim
    if isinstance(source, tuple):
        for s, d in zip(source, destination, strict=True):
            if s % n != d % n:
                return np.moveaxis(arr, source, destination)
        return arr
    return (
        arr if source % n == destination % n else np.moveaxis(arr, source, destination)
    )


class Blocks:
    """An array argument rearranged to (n, k, c) blocks, and how to undo it."""

    __slots__ = ("data", "track", "moved_shape", "axis", "time_axis", "ndim")

    def __init__(self, arr, size: int, axis, time_axis, timestamps, kind: str):
        arr = float_array(arr, "arr")
        if arr.ndim == 0:
            raise ValueError(f"arr must have an axis of length {size}, got a scalar")
        self.ndim = arr.ndim
        self.axis = resolve_axis(axis, arr.ndim, "axis")
        if arr.shape[self.axis] != size:
            raise ValueError(
                f"arr must have length {size} along axis {axis} (the {kind}' "
                f"coordinates), got shape {arr.shape}"
            )
        # NaN rows are missing samples and pass through; infinities and
        # partly NaN rows are mistakes
        check_whole_rows(_moveaxis(arr, self.axis, -1), "arr")
        if size == 4:
            arr = normalize_quaternions(
                _moveaxis(arr, self.axis, -1), "arr", allow_nan=True
            )
            arr = _moveaxis(arr, -1, self.axis)
        if timestamps is None:
            self.track = None
            self.time_axis = None
            moved = _moveaxis(arr, self.axis, -1)
            self.data = kernel_array(moved.reshape(1, -1, size))
        else:
            self.time_axis = resolve_axis(time_axis, arr.ndim, "time_axis")
            if self.time_axis == self.axis:
                raise ValueError(
                    f"time_axis={time_axis} and axis={axis} are the same axis of arr"
                )
            if isinstance(timestamps, _time.Track):
                if len(timestamps) != arr.shape[self.time_axis]:
                    raise ValueError("timestamps and arr differ in length")
                self.track = timestamps
            else:
                self.track = _time.as_track(
                    timestamps,
                    "timestamps",
                    length=arr.shape[self.time_axis],
                    copy=False,
                )
            moved = _moveaxis(arr, (self.time_axis, self.axis), (0, -1))
            self.data = kernel_array(moved.reshape(moved.shape[0], -1, size))
        self.moved_shape = moved.shape

    def restore(self, out: np.ndarray, target: _chain.Target) -> np.ndarray:
        """Undo the rearrangement on a result of shape (m, k, c).

        Untimestamped input transformed by a moving chain gains a leading
        time axis (a leading axis of length 1 is replaced by it).
        """
        c = out.shape[-1]
        if self.track is not None:
            assert self.time_axis is not None  # set with the track
            out = out.reshape((out.shape[0],) + self.moved_shape[1:-1] + (c,))
            return _moveaxis(out, (0, -1), (self.time_axis, self.axis))
        if target.track is None:
            out = out.reshape(self.moved_shape[:-1] + (c,))
            if self.axis == self.ndim - 1:
                return out
            return np.moveaxis(out, -1, self.axis)
        out = out.reshape((out.shape[0],) + self.moved_shape[:-1] + (c,))
        out = np.moveaxis(out, -1, self.axis + 1)
        if self.ndim >= 2 and out.shape[1] == 1:
            out = out[:, 0]
        return out


def transform(
    frame,
    kind: str,
    arr,
    to_frame,
    axis=-1,
    time_axis=0,
    timestamps=None,
    timestamps_out: bool = True,
):
    """Transform ``arr`` (points, vectors or quaternions) out of ``frame``.

    Parameters
    ----------
    frame, to_frame : ReferenceFrame
        Resolved frames of one tree.
    kind : {"points", "vectors", "quaternions"}
    arr : array_like, shape (..., 3 or 4, ...)
    axis, time_axis : int
    timestamps : array_like, Track or None
    timestamps_out : bool, default True
        Whether the caller wants the result's timestamps (a copy as long as
        the result's time axis: False saves it).

    Returns
    -------
    out : ndarray
    ts : ndarray or None
        The timestamps of ``out`` (None if neither array nor chain has any,
        or if not ``timestamps_out``).
    """
    if timestamps is None and kind != "quaternions":
        fast = _static_rows(frame, kind, arr, to_frame, axis)
        if fast is not None:
            return fast, None
    blocks = Blocks(arr, SIZES[kind], axis, time_axis, timestamps, kind)
    steps = _chain.chain(frame, to_frame)
    target = _chain.match([f for f, _ in steps], [blocks.track])
    data = _chain.resample_array(
        blocks.data, blocks.track, target, kind == "quaternions"
    )
    out = _chain.apply(kind, steps, target, data)
    return blocks.restore(out, target), target.timestamps if timestamps_out else None


def _static_rows(frame, kind, arr, to_frame, axis):
    """The short way for (3,) or (n, 3) float64 rows through a static chain.

    Returns None when it does not apply (then the general path runs).
    """
    if (
        type(arr) is not np.ndarray
        or arr.dtype.kind not in "fiu"
        or arr.ndim > 2
        or arr.shape[-1:] != (3,)
    ):
        return None
    if axis != -1 and axis != arr.ndim - 1:
        return None
    static = _chain.static_transform(frame, to_frame)
    if static is None:
        return None
    t, r = static
    data = kernel_array(arr).reshape(1, -1, 3)
    # NaN, infinities and values beyond MAX_COORDINATE fail the comparison:
    # the general path names them (two reductions, nothing allocated)
    if data.size and not (
        -MAX_COORDINATE <= data.min() and data.max() <= MAX_COORDINATE
    ):
        return None
    out = kr.transform_blocks(r, t, data, kind == "points")
    return out.reshape(arr.shape)


def track_of(track, values):
    """The Track for ``values``, a contiguous run of ``track``'s timestamps."""
    if track is not None and len(values) == len(track):
        return track
    return _time.as_track(values)
