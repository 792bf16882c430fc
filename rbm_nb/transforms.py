"""Transform points, vectors, quaternions and velocities between frames.

Each public function unpacks its array argument, resolves the frames and
hands both to the engine (:mod:`rbm_nb._engine.transform` and
:mod:`rbm_nb._engine.twist`), which matches the array's timestamps with
those of the frames along the way (see :mod:`rbm_nb._engine.chain`) and
applies the chained transform with a numba kernel. DataArray input comes
back as a DataArray with coordinates and attributes kept and the frame
attributes updated.
"""

from __future__ import annotations

import warnings
from typing import Any

from . import _dask
from ._door import ArrayInput
from ._engine import transform as _engine_transform
from ._engine import twist as _twist
from ._frame_snapshot import FrameTree
from ._validation import check_what
from ._xarray import unpack, wrap
from .frames import FrameLike, resolve_frame

__all__ = [
    "transform_points",
    "transform_vectors",
    "transform_quaternions",
    "transform_angular_velocity",
    "transform_linear_velocity",
]


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
            return_timestamps, **kwargs,
        )  # fmt: skip
    unpacked = unpack(
        arr, dim=dim, axis=axis, time_axis=time_axis, timestamps=timestamps
    )
    attrs = None if unpacked.source is None else dict(unpacked.attrs)
    if outof is None:
        if attrs is not None and attr in attrs:
            outof = resolve_frame(attrs[attr], f"the DataArray's {attr} attribute")
        else:
            raise ValueError(
                f"outof must be given unless arr is a DataArray whose attrs name a "
                f"registered frame under {attr!r}"
            )
    else:
        outof = resolve_frame(outof, "outof")
        if attrs is not None and attr in attrs and attrs[attr] != outof.name:
            warnings.warn(
                f"transforming the {attr!r} of the array out of {outof.name!r}, but "
                f"its attrs say its {attr} is {attrs[attr]!r}",
                stacklevel=3,
            )
    into = resolve_frame(into, "into")
    if method in (_points, _vectors, _quaternions):
        # the result's timestamps are a copy as long as its time axis: only
        # made when they are returned or wrapped
        kwargs["timestamps_out"] = return_timestamps or attrs is not None
    out, ts_out = method(
        outof,
        unpacked.data,
        into,
        axis=unpacked.axis,
        time_axis=unpacked.time_axis,
        timestamps=unpacked.timestamps,
        **kwargs,
    )
    if attrs is not None:  # a DataArray came in: one goes out
        attrs[attr] = into.name
        attrs["representation_frame"] = into.name
        return wrap(unpacked, out, ts_out, attrs)
    if return_timestamps:
        return out, ts_out
    return out


def _lazy_transform(
    method, arr, into, outof, dim, axis, timestamps, time_axis, attr,
    return_timestamps, **kwargs,
):  # fmt: skip
    """The transform of dask-backed data, one task per time chunk (see _dask):
    the frames are resolved here, once, and the graph carries their values."""
    if kwargs.get("what", "representation_frame") != "representation_frame":
        # the frames' velocities are estimated once, not per chunk
        return _dask.velocity_transform(
            method is _frame_transform_linear_velocity_kw, arr, into, outof,
            dim=dim, axis=axis, timestamps=timestamps, time_axis=time_axis,
            return_timestamps=return_timestamps, resolve=resolve_frame,
            snapshot=FrameTree.of, **kwargs,
        )  # fmt: skip
    if method not in (_points, _vectors, _quaternions):
        # a velocity's representation frame changes as a vector's does
        method = _vectors
    return _dask.transform(
        method, arr, into, outof, dim, axis, timestamps, time_axis,
        return_timestamps, resolve_frame, FrameTree.of, attr, method is _quaternions,
    )  # fmt: skip


def _points(frame, arr, into, **kw):
    return _engine_transform.transform(frame, "points", arr, into, **kw)


def _vectors(frame, arr, into, **kw):
    return _engine_transform.transform(frame, "vectors", arr, into, **kw)


def _quaternions(frame, arr, into, **kw):
    return _engine_transform.transform(frame, "quaternions", arr, into, **kw)


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
        _vectors, arr, into, outof, dim, axis, timestamps, time_axis,
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
        _points, arr, into, outof, dim, axis, timestamps, time_axis,
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
        _quaternions, arr, into, outof, dim, axis, timestamps, time_axis,
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
    return _transform(
        _frame_transform_angular_velocity_kw, arr, into, outof, dim, axis, timestamps,
        time_axis, what, return_timestamps, what=what, cutoff=cutoff,
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
    return _transform(
        _frame_transform_linear_velocity_kw, arr, into, outof, dim, axis, timestamps,
        time_axis, what, return_timestamps, what=what, moving_frame=moving_frame,
        reference_frame=reference_frame, cutoff=cutoff, outlier_thresh=outlier_thresh,
    )  # fmt: skip


def _frame_transform_angular_velocity_kw(
    frame, arr, into, axis, time_axis, timestamps, what, cutoff
):
    return _twist.transform_angular_velocity(
        frame, arr, into, what, axis, time_axis, timestamps, cutoff
    )


def _frame_transform_linear_velocity_kw(
    frame, arr, into, axis, time_axis, timestamps, what, moving_frame, reference_frame,
    cutoff, outlier_thresh,
):  # fmt: skip
    moving_frame = (
        None if moving_frame is None else resolve_frame(moving_frame, "moving_frame")
    )
    reference_frame = (
        None
        if reference_frame is None
        else resolve_frame(reference_frame, "reference_frame")
    )
    return _twist.transform_linear_velocity(
        frame, arr, into, what, moving_frame, reference_frame, axis, time_axis,
        timestamps, outlier_thresh, cutoff,
    )  # fmt: skip
