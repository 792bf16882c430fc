"""Transform points, vectors, quaternions and velocities between frames.

Each public function resolves the frames, matches the array's timestamps
with those of the frames along the way (see :mod:`rbm_nb._matching`),
applies the chained transform with a numba kernel and, for DataArray input,
returns a DataArray with coordinates and attributes kept and the frame
attributes updated.
"""

from __future__ import annotations

import warnings

import numpy as np

from . import _dask, _matching, _timestamps
from ._kernels import resample as kr
from ._validation import (
    as_float_array,
    check_what,
    normalize_quaternions,
    resolve_axis,
)
from ._xarray import unpack, wrap
from .frames import _resolve

__all__ = [
    "transform_points",
    "transform_vectors",
    "transform_quaternions",
    "transform_angular_velocity",
    "transform_linear_velocity",
]

_SIZES = {"points": 3, "vectors": 3, "quaternions": 4}


# ---------------------------------------------------------------------------
# array layout: (time, ..., component) <-> (n, k, c) blocks
# ---------------------------------------------------------------------------


class _Blocks:
    """An array argument rearranged to (n, k, c) blocks, and how to undo it."""

    __slots__ = ("data", "track", "moved_shape", "axis", "time_axis", "ndim")

    def __init__(self, arr, size, axis, time_axis, timestamps, kind):
        arr = as_float_array(arr, "arr")
        if arr.ndim == 0:
            raise ValueError(f"arr must have an axis of length {size}, got a scalar")
        self.ndim = arr.ndim
        self.axis = resolve_axis(axis, arr.ndim, "axis")
        if arr.shape[self.axis] != size:
            raise ValueError(
                f"arr must have length {size} along axis {axis} (the {kind}' "
                f"coordinates), got shape {arr.shape}"
            )
        if size == 4:
            arr = normalize_quaternions(
                np.moveaxis(arr, self.axis, -1), "arr", allow_nan=True
            )
            arr = np.moveaxis(arr, -1, self.axis)
        if timestamps is None:
            self.track = None
            self.time_axis = None
            moved = np.moveaxis(arr, self.axis, -1)
            self.data = np.ascontiguousarray(moved.reshape(1, -1, size))
        else:
            self.time_axis = resolve_axis(time_axis, arr.ndim, "time_axis")
            if self.time_axis == self.axis:
                raise ValueError(
                    f"time_axis={time_axis} and axis={axis} are the same axis of arr"
                )
            if isinstance(timestamps, _timestamps.Track):
                if len(timestamps) != arr.shape[self.time_axis]:
                    raise ValueError("timestamps and arr differ in length")
                self.track = timestamps
            else:
                self.track = _timestamps.as_track(
                    timestamps,
                    "timestamps",
                    length=arr.shape[self.time_axis],
                    copy=False,
                )
            moved = np.moveaxis(arr, (self.time_axis, self.axis), (0, -1))
            self.data = np.ascontiguousarray(moved.reshape(moved.shape[0], -1, size))
        self.moved_shape = moved.shape

    def restore(self, out: np.ndarray, target) -> np.ndarray:
        """Undo the rearrangement on a result of shape (m, k, c).

        Untimestamped input transformed by a moving chain gains a leading
        time axis (a leading axis of length 1 is replaced by it).
        """
        c = out.shape[-1]
        if self.track is not None:
            out = out.reshape((out.shape[0],) + self.moved_shape[1:-1] + (c,))
            return np.moveaxis(out, (0, -1), (self.time_axis, self.axis))
        if target.track is None:
            out = out.reshape(self.moved_shape[:-1] + (c,))
            return np.moveaxis(out, -1, self.axis)
        out = out.reshape((out.shape[0],) + self.moved_shape[:-1] + (c,))
        out = np.moveaxis(out, -1, self.axis + 1)
        if self.ndim >= 2 and out.shape[1] == 1:
            out = out[:, 0]
        return out


# ---------------------------------------------------------------------------
# frame-level implementation (ReferenceFrame.transform_* forward here)
# ---------------------------------------------------------------------------


def _apply(kind, steps, target, data):
    """Apply the chain's transform to (n|1, k, c) data at the target times."""
    discrete = _matching.held(steps, target)
    if discrete is not None:
        t, r, idx = discrete
        if kind == "quaternions":
            return kr.qmul_blocks_held(r, idx, data)
        return kr.transform_blocks_held(r, t, idx, data, kind == "points")
    t, r = _matching.compose(steps, target)
    if kind == "quaternions":
        return kr.qmul_blocks(r, data)
    return kr.transform_blocks(r, t, data, kind == "points")


def _frame_transform(frame, kind, arr, to_frame, axis=-1, time_axis=0, timestamps=None):
    """Transform ``arr`` (points, vectors or quaternions) out of ``frame``.

    Returns
    -------
    out : ndarray
    ts : ndarray or None
        The timestamps of ``out`` (None if neither array nor chain has any).
    """
    to_frame = _resolve(to_frame, "to_frame")
    blocks = _Blocks(arr, _SIZES[kind], axis, time_axis, timestamps, kind)
    steps = _matching.chain(frame, to_frame)
    target = _matching.match([f for f, _ in steps], [blocks.track])
    data = _matching.resample_array(
        blocks.data, blocks.track, target, kind == "quaternions"
    )
    out = _apply(kind, steps, target, data)
    return blocks.restore(out, target), target.timestamps


def _velocity_parts(arr_blocks, frame, to_frame, extra):
    """Represent the input in ``to_frame`` and match it with looked-up terms.

    ``extra`` is a list of (array of shape (3,) or (n, 3), Track or None).
    Returns the matched (n, k, 3) input, the matched extras as (n|1, 1, 3)
    arrays, and the target.
    """
    steps = _matching.chain(frame, to_frame)
    target = _matching.match([f for f, _ in steps], [arr_blocks.track])
    data = _matching.resample_array(arr_blocks.data, arr_blocks.track, target, False)
    rotated = _apply("vectors", steps, target, data)
    ext_blocks = [
        np.ascontiguousarray(np.reshape(e, (-1, 1, 3)), dtype=float) for e, _ in extra
    ]
    ext_tracks = [track for _, track in extra]
    final = _matching.match([], [target.track] + ext_tracks)
    rotated = _matching.resample_array(rotated, target.track, final, False)
    ext = [
        _matching.resample_array(b, track, final, False)
        for b, track in zip(ext_blocks, ext_tracks, strict=True)
    ]
    return rotated, ext, final


def _frame_transform_angular_velocity(
    frame,
    arr,
    to_frame,
    what="reference_frame",
    axis=-1,
    time_axis=0,
    timestamps=None,
    cutoff=None,
):
    from .lookups import _frame_lookup_angular_velocity

    check_what(what)
    to_frame = _resolve(to_frame, "to_frame")
    if what == "representation_frame":
        return _frame_transform(
            frame, "vectors", arr, to_frame, axis, time_axis, timestamps
        )
    if what == "reference_frame":
        # w_M/R' = w_M/R + w_R/R'
        angular, ang_ts = _frame_lookup_angular_velocity(
            frame, to_frame, to_frame, None, cutoff, "quaternion", True, as_track=True
        )
    else:
        # w_M'/R = w_M/R + w_M'/M
        angular, ang_ts = _frame_lookup_angular_velocity(
            to_frame, frame, to_frame, None, cutoff, "quaternion", True, as_track=True
        )
    blocks = _Blocks(arr, 3, axis, time_axis, timestamps, "vectors")
    rotated, (w,), final = _velocity_parts(blocks, frame, to_frame, [(angular, ang_ts)])
    return blocks.restore(rotated + w, final), final.timestamps


def _frame_transform_linear_velocity(
    frame,
    arr,
    to_frame,
    what="reference_frame",
    moving_frame=None,
    reference_frame=None,
    axis=-1,
    time_axis=0,
    timestamps=None,
    outlier_thresh=None,
    cutoff=None,
):
    from .lookups import (
        _frame_lookup_angular_velocity,
        _frame_lookup_linear_velocity,
        _frame_lookup_twist,
        _lookup,
    )

    check_what(what)
    to_frame = _resolve(to_frame, "to_frame")
    if what == "representation_frame":
        return _frame_transform(
            frame, "vectors", arr, to_frame, axis, time_axis, timestamps
        )
    if what == "reference_frame":
        # v_M/R' = v_M/R + v_R/R' + w_R/R' x t_M/R
        if moving_frame is None:
            raise ValueError(
                "moving_frame must be given to transform the reference frame of a "
                "linear velocity (its position enters the three-term formula)"
            )
        moving_frame = _resolve(moving_frame, "moving_frame")
        linear, angular, twist_ts = _frame_lookup_twist(
            frame,
            to_frame,
            to_frame,
            outlier_thresh,
            cutoff,
            "quaternion",
            True,
            as_track=True,
        )
        lin_ts = ang_ts = twist_ts
        translation, _, trans_target = _lookup(moving_frame, frame)
    else:
        # v_M'/R = v_M/R + v_M'/M + w_M/R x t_M'/M
        if reference_frame is None:
            raise ValueError(
                "reference_frame must be given to transform the moving frame of a "
                "linear velocity (its angular velocity enters the three-term formula)"
            )
        reference_frame = _resolve(reference_frame, "reference_frame")
        linear, lin_ts = _frame_lookup_linear_velocity(
            to_frame, frame, to_frame, outlier_thresh, cutoff, True, as_track=True
        )
        angular, ang_ts = _frame_lookup_angular_velocity(
            frame,
            reference_frame,
            to_frame,
            None,
            cutoff,
            "quaternion",
            True,
            as_track=True,
        )
        translation, _, trans_target = _lookup(to_frame, frame)
    # the lever arm, represented in to_frame like everything else
    trans, trans_ts = _frame_transform(
        frame, "vectors", translation, to_frame, -1, 0, trans_target.track
    )
    trans_track = None if trans_ts is None else _track_of(trans_target.track, trans_ts)
    blocks = _Blocks(arr, 3, axis, time_axis, timestamps, "vectors")
    rotated, (v, w, lever), final = _velocity_parts(
        blocks,
        frame,
        to_frame,
        [(linear, lin_ts), (angular, ang_ts), (trans, trans_track)],
    )
    out = rotated + v + np.cross(w, lever)
    return blocks.restore(out, final), final.timestamps


def _track_of(track, values):
    """The Track for ``values``, a contiguous run of ``track``'s timestamps."""
    if track is not None and len(values) == len(track):
        return track
    return _timestamps.as_track(values)


# ---------------------------------------------------------------------------
# public functions
# ---------------------------------------------------------------------------


def _transform(
    method,
    arr,
    into,
    outof,
    dim,
    axis,
    timestamps,
    time_axis,
    attr,
    return_timestamps,
    **kwargs,
):
    """Unpack, resolve frames (``outof`` may come from ``attrs[attr]``), wrap."""
    if _dask.is_dask(arr):
        return _lazy_transform(
            method, arr, into, outof, dim, axis, timestamps, time_axis, attr,
            return_timestamps,
        )  # fmt: skip
    unpacked = unpack(
        arr, dim=dim, axis=axis, time_axis=time_axis, timestamps=timestamps
    )
    attrs = None if unpacked.source is None else dict(unpacked.attrs)
    if outof is None:
        if attrs is not None and attr in attrs:
            outof = _resolve(attrs[attr], f"the DataArray's {attr} attribute")
        else:
            raise ValueError(
                f"outof must be given unless arr is a DataArray whose attrs name a "
                f"registered frame under {attr!r}"
            )
    else:
        outof = _resolve(outof, "outof")
        if attrs is not None and attr in attrs and attrs[attr] != outof.name:
            warnings.warn(
                f"transforming the {attr!r} of the array out of {outof.name!r}, but "
                f"its attrs say its {attr} is {attrs[attr]!r}",
                stacklevel=3,
            )
    into = _resolve(into, "into")
    out, ts_out = method(
        outof,
        unpacked.data,
        into,
        axis=unpacked.axis,
        time_axis=unpacked.time_axis,
        timestamps=unpacked.timestamps,
        **kwargs,
    )
    if unpacked.source is not None:
        attrs[attr] = into.name
        attrs["representation_frame"] = into.name
        return wrap(unpacked, out, ts_out, attrs)
    if return_timestamps:
        return out, ts_out
    return out


def _lazy_transform(
    method, arr, into, outof, dim, axis, timestamps, time_axis, attr, return_timestamps
):
    if method not in (_points, _vectors, _quaternions):
        raise NotImplementedError(
            "velocity transforms of dask-backed arrays are not lazy yet (each "
            "chunk would re-estimate the frames' velocities); call .compute() "
            "on the array first"
        )

    def eager(block, into, outof, dim, axis, timestamps):
        return _transform(
            method, block, into, outof, dim, axis, timestamps, None, attr, False
        )

    return _dask.transform(
        eager, arr, into, outof, dim, axis, timestamps, time_axis,
        return_timestamps, _resolve, attr, method is _quaternions,
    )  # fmt: skip


def _points(frame, arr, into, **kw):
    return _frame_transform(frame, "points", arr, into, **kw)


def _vectors(frame, arr, into, **kw):
    return _frame_transform(frame, "vectors", arr, into, **kw)


def _quaternions(frame, arr, into, **kw):
    return _frame_transform(frame, "quaternions", arr, into, **kw)


def transform_vectors(
    arr,
    into,
    outof=None,
    dim=None,
    axis=None,
    timestamps=None,
    time_axis=None,
    return_timestamps=False,
):
    """Represent vectors given in one frame in another (rotation only).

    Parameters
    ----------
    arr : array_like or DataArray, shape (..., 3, ...)
        The vectors.
    into : str or ReferenceFrame
        The frame to represent them in.
    outof : str or ReferenceFrame, optional
        The frame they are represented in now; defaults to a DataArray's
        ``representation_frame`` attribute.
    dim : str, optional
        The spatial dimension of a DataArray.
    axis : int, optional
        The spatial axis (default: the last).
    timestamps : array_like or str, optional
        Timestamps along ``time_axis`` (for a DataArray: the name of the
        time coordinate; default: its first dimension's coordinate).
    time_axis : int, optional
        The time axis (default: the first).
    return_timestamps : bool, default False
        Also return the timestamps of the result (plain arrays only).

    Returns
    -------
    arr_transformed : ndarray or DataArray
    ts : ndarray, optional
        The timestamps after matching with the frames' timestamps.
    """
    return _transform(
        _vectors, arr, into, outof, dim, axis, timestamps, time_axis,
        "representation_frame", return_timestamps,
    )  # fmt: skip


def transform_points(
    arr,
    into,
    outof=None,
    dim=None,
    axis=None,
    timestamps=None,
    time_axis=None,
    return_timestamps=False,
):
    """Express points given wrt one frame wrt another (rotation + translation).

    Parameters and returns are those of :func:`transform_vectors`, except
    that ``outof`` defaults to a DataArray's ``reference_frame`` attribute.
    """
    return _transform(
        _points, arr, into, outof, dim, axis, timestamps, time_axis,
        "reference_frame", return_timestamps,
    )  # fmt: skip


def transform_quaternions(
    arr,
    into,
    outof=None,
    dim=None,
    axis=None,
    timestamps=None,
    time_axis=None,
    return_timestamps=False,
):
    """Express orientations (unit quaternions, axis of length 4) wrt another frame.

    Parameters and returns are those of :func:`transform_points`.
    """
    return _transform(
        _quaternions, arr, into, outof, dim, axis, timestamps, time_axis,
        "reference_frame", return_timestamps,
    )  # fmt: skip


def transform_angular_velocity(
    arr,
    into,
    outof=None,
    what="reference_frame",
    dim=None,
    axis=None,
    timestamps=None,
    time_axis=None,
    cutoff=None,
    return_timestamps=False,
):
    """Change the reference, moving or representation frame of angular velocities.

    With ``what="reference_frame"`` (R -> R'): w_M/R' = w_M/R + w_R/R';
    with ``what="moving_frame"`` (M -> M'): w_M'/R = w_M/R + w_M'/M;
    with ``what="representation_frame"`` the vectors are only re-represented.
    The input must be represented in the frame being changed and comes out
    represented in the new one.

    Parameters
    ----------
    arr : array_like or DataArray, shape (..., 3, ...)
    into, outof : str or ReferenceFrame
        The new and the current frame (``outof`` defaults to the DataArray
        attribute named by ``what``).
    what : {"reference_frame", "moving_frame", "representation_frame"}
    dim, axis, timestamps, time_axis, return_timestamps
        As for :func:`transform_vectors`.
    cutoff : float, optional
        Low-pass cutoff (fraction of Nyquist) for the looked-up velocity.
    """
    check_what(what)
    return _transform(
        _frame_transform_angular_velocity_kw, arr, into, outof, dim, axis, timestamps,
        time_axis, what, return_timestamps, what=what, cutoff=cutoff,
    )  # fmt: skip


def transform_linear_velocity(
    arr,
    into,
    outof=None,
    what="reference_frame",
    moving_frame=None,
    reference_frame=None,
    dim=None,
    axis=None,
    timestamps=None,
    time_axis=None,
    cutoff=None,
    outlier_thresh=None,
    return_timestamps=False,
):
    """Change the reference, moving or representation frame of linear velocities.

    With ``what="reference_frame"`` (R -> R', needs ``moving_frame``):
    v_M/R' = v_M/R + v_R/R' + w_R/R' x t_M/R; with ``what="moving_frame"``
    (M -> M', needs ``reference_frame``): v_M'/R = v_M/R + v_M'/M + w_M/R x
    t_M'/M; with ``what="representation_frame"`` the vectors are only
    re-represented. The input must be represented in the frame being changed
    and comes out represented in the new one.

    Parameters
    ----------
    arr : array_like or DataArray, shape (..., 3, ...)
    into, outof : str or ReferenceFrame
    what : {"reference_frame", "moving_frame", "representation_frame"}
    moving_frame, reference_frame : str or ReferenceFrame, optional
    dim, axis, timestamps, time_axis, return_timestamps
        As for :func:`transform_vectors`.
    cutoff : float, optional
        Low-pass cutoff (fraction of Nyquist) for the looked-up velocities.
    outlier_thresh : float, optional
        Outlier suppression threshold for the looked-up linear velocity.
    """
    check_what(what)
    return _transform(
        _frame_transform_linear_velocity_kw, arr, into, outof, dim, axis, timestamps,
        time_axis, what, return_timestamps, what=what, moving_frame=moving_frame,
        reference_frame=reference_frame, cutoff=cutoff, outlier_thresh=outlier_thresh,
    )  # fmt: skip


def _frame_transform_angular_velocity_kw(
    frame, arr, into, axis, time_axis, timestamps, what, cutoff
):
    return _frame_transform_angular_velocity(
        frame, arr, into, what, axis, time_axis, timestamps, cutoff
    )


def _frame_transform_linear_velocity_kw(
    frame, arr, into, axis, time_axis, timestamps, what, moving_frame, reference_frame,
    cutoff, outlier_thresh,
):  # fmt: skip
    return _frame_transform_linear_velocity(
        frame, arr, into, what, moving_frame, reference_frame, axis, time_axis,
        timestamps, outlier_thresh, cutoff,
    )  # fmt: skip
