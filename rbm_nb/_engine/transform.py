"""Points, vectors and quaternions carried from one resolved frame to another.

The door (:mod:`rbm_nb._door.inputs`) hands over an array argument checked and
rearranged to (n, k, c) blocks (time first, k independent items, c
components); here they are matched with the chain's timestamps, transformed
by one kernel call and laid out again like the input. Nothing is validated
here.
"""

from __future__ import annotations

import numpy as np

from .._kernels import resample as kr
from .._kernels._arrays import kernel_array, moveaxis
from . import chain as _chain
from . import time as _time

__all__ = ["Blocks", "transform", "transform_static", "track_of", "SIZES"]

SIZES = {"points": 3, "vectors": 3, "quaternions": 4}


class Blocks:
    """An array argument laid out as (n, k, c) blocks, and how to undo it.

    Built by the door (:func:`rbm_nb._door.inputs.blocks`), which validated the
    values and resolved the axes; the engine only reads and restores them.
    """

    __slots__ = ("data", "track", "moved_shape", "axis", "time_axis", "ndim")

    def __init__(self, data, track, moved_shape, axis: int, time_axis, ndim: int):
        self.data = data  # (n, k, c) float64, C-contiguous
        self.track = track  # a Track, or None for untimestamped input
        self.moved_shape = moved_shape  # the input's shape, time first, c last
        self.axis = axis
        self.time_axis = time_axis
        self.ndim = ndim

    @classmethod
    def of_rows(cls, rows: np.ndarray, track) -> Blocks:
        """Blocks of rows the engine computed itself ((3,) or (n, 3), clean)."""
        if track is None:
            data = kernel_array(rows.reshape(1, -1, 3))
            return cls(data, None, rows.shape, rows.ndim - 1, None, rows.ndim)
        return cls(kernel_array(rows.reshape(-1, 1, 3)), track, rows.shape, 1, 0, 2)

    def restore(self, out: np.ndarray, target: _chain.Target) -> np.ndarray:
        """Undo the rearrangement on a result of shape (m, k, c).

        Untimestamped input transformed by a moving chain gains a leading
        time axis (a leading axis of length 1 is replaced by it).
        """
        c = out.shape[-1]
        if self.track is not None:
            assert self.time_axis is not None  # set with the track
            out = out.reshape((out.shape[0],) + self.moved_shape[1:-1] + (c,))
            return moveaxis(out, (0, -1), (self.time_axis, self.axis))
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


def transform(frame, kind: str, blocks: Blocks, to_frame, timestamps_out: bool = True):
    """Transform ``blocks`` (points, vectors or quaternions) out of ``frame``.

    Parameters
    ----------
    frame, to_frame : ReferenceFrame
        Resolved frames of one tree.
    kind : {"points", "vectors", "quaternions"}
    blocks : Blocks
        The array argument as the door laid it out.
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
    steps = _chain.chain(frame, to_frame)
    target = _chain.match([f for f, _ in steps], [blocks.track])
    data = _chain.resample_array(
        blocks.data, blocks.track, target, kind == "quaternions"
    )
    out = _chain.apply(kind, steps, target, data)
    return blocks.restore(out, target), target.timestamps if timestamps_out else None


def transform_static(kind: str, static, rows: np.ndarray) -> np.ndarray:
    """Points or vectors, (1, n, 3) rows the door checked, through a static chain.

    ``static`` is ``chain.static_transform(frame, to_frame)`` (not None): one
    kernel call, no matching, the short way of one-point calls.
    """
    t, r = static
    return kr.transform_blocks(r, t, rows, kind == "points")


def track_of(track, values):
    """The Track for ``values``, a contiguous run of ``track``'s timestamps."""
    if track is not None and len(values) == len(track):
        return track
    return _time.as_track(values)
