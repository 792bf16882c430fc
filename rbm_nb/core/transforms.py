"""Transform points, vectors, quaternions and velocities between frames.

Each public function hands its arguments to the door
(:func:`rbm_nb._door.inputs.arguments`: the array unpacked, checked and laid out,
the frames resolved) and what comes back to the engine (:mod:`rbm_nb._engine.transform` and
:mod:`rbm_nb._engine.twist`), which matches the array's timestamps with
those of the frames along the way (see :mod:`rbm_nb._engine.chain`) and
applies the chained transform with a numba kernel. DataArray input comes
back as a DataArray with coordinates and attributes kept and the frame
attributes updated.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from .._door import coverage as _coverage
from .._door import dask_blocks as _dask
from .._door import inputs as _inputs
from .._door.series import velocity_options as _velocity_options
from .._door.unpack import ArrayInput
from .._door.validation import check_what
from .._engine import transform as _engine_transform
from .._engine import twist as _twist
from ._frame_snapshot import FrameTree
from .frames import FrameLike, resolve_frame

__all__ = [
    "transform_points",
    "transform_vectors",
    "transform_quaternions",
    "transform_angular_velocity",
    "transform_linear_velocity",
]


def _transform(
    kind, arr, into, outof, dim, axis, timestamps, time_axis, attr, return_timestamps,
    velocity=None,
):  # fmt: skip
    """One door call (:func:`rbm_nb._door.inputs.arguments`), one engine call.

    ``kind`` is "points", "vectors" or "quaternions"; ``velocity``, for a
    change of a velocity's reference or moving frame, ``(linear, options)``.
    """
    if velocity is not None:
        _velocity_options(velocity[1].get("outlier_thresh"), velocity[1]["cutoff"])
    if type(arr) is not np.ndarray and _dask.is_dask(arr):
        return _lazy_transform(
            kind, arr, into, outof, dim, axis, timestamps, time_axis, attr,
            return_timestamps, velocity,
        )  # fmt: skip
    args = _inputs.arguments(
        kind, arr, into, outof, dim, axis, timestamps, time_axis, attr, resolve_frame,
        velocity is not None,
    )  # fmt: skip
    if args.rows is not None:  # the short way: a static chain, plain rows
        out = _engine_transform.transform_static(kind, args.static, args.rows)
        out = out.reshape(args.shape)
        return (out, None) if return_timestamps else out
    if velocity is None:
        # the result's timestamps are a copy as long as its time axis: only
        # made when they are returned or wrapped
        out, ts_out = _engine_transform.transform(
            args.outof, kind, args.blocks, args.into,
            return_timestamps or args.attrs is not None,
        )  # fmt: skip
    else:
        out, ts_out = _velocity(args, attr, *velocity)
    return args.result(out, ts_out, attr, return_timestamps)


def _velocity(args, what, linear, options):
    if not linear:
        _coverage.velocity_transform(
            args.outof, args.into, args.blocks.track, what, False,
            cutoff=options["cutoff"],
        )  # fmt: skip
        return _twist.transform_angular_velocity(
            args.outof, args.blocks, args.into, what, options["cutoff"]
        )
    moving = _optional(options["moving_frame"], "moving_frame")
    reference = _optional(options["reference_frame"], "reference_frame")
    _coverage.velocity_transform(
        args.outof, args.into, args.blocks.track, what, True, moving, reference,
        options["outlier_thresh"], options["cutoff"],
    )  # fmt: skip
    return _twist.transform_linear_velocity(
        args.outof, args.blocks, args.into, what, moving, reference,
        options["outlier_thresh"], options["cutoff"],
    )  # fmt: skip


def _optional(frame, argument):
    return None if frame is None else resolve_frame(frame, argument)


def _lazy_transform(
    kind, arr, into, outof, dim, axis, timestamps, time_axis, attr,
    return_timestamps, velocity,
):  # fmt: skip
    """The transform of dask-backed data, one task per time chunk (see _dask):
    the frames are resolved here, once, and the graph carries their values;
    each block goes through the door and the engine as an eager call does."""
    source, to_frame = _inputs.frames(resolve_frame, outof, into, _attrs_of(arr), attr)
    if velocity is not None and attr != "representation_frame":
        # the frames' velocities are estimated once, not per chunk
        linear, options = velocity
        moving = _optional(options.get("moving_frame"), "moving_frame")
        reference = _optional(options.get("reference_frame"), "reference_frame")
        _coverage.velocity_terms(
            source, to_frame, attr, linear, moving, reference,
            options.get("outlier_thresh"), options["cutoff"],
        )  # fmt: skip
        extras = _twist.velocity_terms(
            linear, source, to_frame, attr, moving, reference,
            options.get("outlier_thresh"), options["cutoff"],
        )  # fmt: skip
        return _dask.velocity_transform(
            arr, source, to_frame, extras, dim, axis, timestamps, time_axis,
            return_timestamps, FrameTree.of,
            functools.partial(_inputs.velocity_block, what=attr),
        )  # fmt: skip
    block = functools.partial(_inputs.transform_block, kind=kind)
    return _dask.transform(
        block, arr, source, to_frame, dim, axis, timestamps, time_axis,
        return_timestamps, FrameTree.of, attr, kind == "quaternions",
    )  # fmt: skip


def _attrs_of(arr):
    return dict(arr.attrs) if hasattr(arr, "attrs") else None


def transform_vectors(
    arr: ArrayInput,
    into: FrameLike,
    outof: FrameLike | None = None,
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    return_timestamps: bool = False,
) -> Any:
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

    Notes
    -----
    Without ``timestamps``, through frames that move, the *whole* array is
    transformed at every sample time of the frames and the result gets a
    new leading time axis: a (7, 3) cloud through a frame of 10 samples
    gives (10, 7, 3), and so does a (10, 3) array (its rows are not taken as
    samples). A row of NaN is a missing sample and stays NaN; a row with
    only some NaN raises. To transform one sample per row, pass
    ``timestamps`` (one per row). The reference implementation raises for
    a (n, 3) array in this case instead.
    """
    return _transform(
        "vectors", arr, into, outof, dim, axis, timestamps, time_axis,
        "representation_frame", return_timestamps,
    )  # fmt: skip


def transform_points(
    arr: ArrayInput,
    into: FrameLike,
    outof: FrameLike | None = None,
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    return_timestamps: bool = False,
) -> Any:
    """Express points given wrt one frame wrt another (rotation + translation).

    Parameters and returns are those of :func:`transform_vectors`, except
    that ``outof`` defaults to a DataArray's ``reference_frame`` attribute.
    """
    return _transform(
        "points", arr, into, outof, dim, axis, timestamps, time_axis,
        "reference_frame", return_timestamps,
    )  # fmt: skip


def transform_quaternions(
    arr: ArrayInput,
    into: FrameLike,
    outof: FrameLike | None = None,
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    return_timestamps: bool = False,
) -> Any:
    """Express orientations (unit quaternions, axis of length 4) wrt another frame.

    Parameters and returns are those of :func:`transform_points`.
    """
    return _transform(
        "quaternions", arr, into, outof, dim, axis, timestamps, time_axis,
        "reference_frame", return_timestamps,
    )  # fmt: skip


def transform_angular_velocity(
    arr: ArrayInput,
    into: FrameLike,
    outof: FrameLike | None = None,
    what: str = "reference_frame",
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    cutoff: float | None = None,
    return_timestamps: bool = False,
) -> Any:
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
    velocity = None if what == "representation_frame" else (False, {"cutoff": cutoff})
    return _transform(
        "vectors", arr, into, outof, dim, axis, timestamps, time_axis, what,
        return_timestamps, velocity,
    )  # fmt: skip


def transform_linear_velocity(
    arr: ArrayInput,
    into: FrameLike,
    outof: FrameLike | None = None,
    what: str = "reference_frame",
    moving_frame: FrameLike | None = None,
    reference_frame: FrameLike | None = None,
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    cutoff: float | None = None,
    outlier_thresh: float | None = None,
    return_timestamps: bool = False,
) -> Any:
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
    options = {
        "moving_frame": moving_frame,
        "reference_frame": reference_frame,
        "cutoff": cutoff,
        "outlier_thresh": outlier_thresh,
    }
    velocity = None if what == "representation_frame" else (True, options)
    return _transform(
        "vectors", arr, into, outof, dim, axis, timestamps, time_axis, what,
        return_timestamps, velocity,
    )  # fmt: skip
