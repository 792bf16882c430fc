"""Lines of sight from eye-tracking frames: directions and gaze angles.

An eye tracker reports, per sample, the orientation of each eye; its line of
sight is one axis of the eye frame (the z axis for Pupil Core and every
camera-convention tracker: x right, y down, z forward). Real recordings have
samples with no data (blinks, lost pupil: NaN rows) and samples whose pupil
detection is unreliable (low confidence). :func:`directions` turns an eye
frame into unit line-of-sight vectors in any frame of the tree, with NaN
wherever the sample must not be drawn or analysed; :func:`angles` turns them
into azimuth and elevation relative to a frame's forward axis.

Examples
--------
>>> import numpy as np, rbm_nb as rbm
>>> from rbm_nb import gaze
>>> rbm.clear_registry()
>>> rbm.register_frame("camera")
>>> q = rbm.from_euler_angles(pitch=np.deg2rad([0.0, 10.0, 20.0]))
>>> rbm.register_frame("eye", parent="camera", rotation=q, timestamps=[0.0, 0.1, 0.2])
>>> sight = gaze.directions("eye", "camera", confidence=[0.9, 0.3, 0.8])
>>> np.round(gaze.angles(sight, "camera").values, 1)
array([[ 0.,  0.],
       [nan, nan],
       [20.,  0.]])
>>> rbm.clear_registry()
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .._door import gaze as _door
from .._engine import transform as _engine_transform
from .._engine.time import sort_keys
from .._engine.transform import Blocks
from .._infra.frozen import kernel_readable as _readable
from .._infra.time_index import dataarray_on
from .._kernels import gaze_rows as _gk
from .._kernels._arrays import kernel_array
from .frames import resolve_frame

if TYPE_CHECKING:
    import xarray as xr

    from .frames import FrameLike

__all__ = ["directions", "angles", "rates", "OCULOMOTOR_RANGE"]

# Degrees. The eyes turn at most about this far from straight ahead in the
# head: the oculomotor range is 45-55 deg horizontally and less vertically
# (Guitton & Volle 1987, J Neurophysiol 58:427); beyond it people turn the
# head. An eye tracker's sample further out than this from the line-of-sight
# axis of the eye's parent frame is a mis-detection, not an eye position.
OCULOMOTOR_RANGE = 50.0
# the eye frame's axis that is the line of sight (camera convention)
_LINE_OF_SIGHT = np.array([0.0, 0.0, 1.0])


def directions(
    eye_frame: FrameLike,
    into: FrameLike,
    *,
    confidence: npt.ArrayLike | xr.DataArray | None = None,
    min_confidence: float = 0.6,
    max_gap: float | None = None,
    max_angle: float | None = None,
) -> xr.DataArray:
    """Unit line-of-sight vectors of an eye, represented in another frame.

    The line of sight is the eye frame's z axis (camera convention: x right,
    y down, z forward, as Pupil Core reports eye orientations). One vector is
    returned per sample of the eye frame; the eye's measurements are never
    interpolated, only the frames between the eye's parent and ``into`` are
    (by the frame core, at the eye's sample times).

    Parameters
    ----------
    eye_frame : str or ReferenceFrame
        A moving frame (or the name of a registered one) whose rotation is
        the eye's orientation. NaN rows of its rotation are missing samples.
    into : str or ReferenceFrame
        The frame to represent the directions in.
    confidence : array_like, shape (n,), or DataArray with dim ``time``, optional
        Detection confidence per sample. An array is aligned with the eye
        frame's timestamps. A DataArray's ``time`` coordinate becomes the time
        axis of the result: its times that are not samples of the eye frame
        (e.g. rows dropped with ``dropna``) are missing samples, NaN.
    min_confidence : float, default 0.6
        Samples with a confidence below this (or NaN) are set to NaN; 0.6 is
        Pupil Core's usual threshold. Ignored without ``confidence``.
    max_gap : float, optional
        Seconds. Where two consecutive times of the result are more than
        ``max_gap`` apart (the tracker recorded nothing in between), a NaN row
        is inserted halfway, so that plots and players show the gap instead
        of drawing across it. Default: no rows inserted.
    max_angle : float, optional
        Degrees. Samples whose line of sight is further than this from the z
        axis of the eye frame's parent (the straight-ahead of the scene
        camera it is measured in) are physiologically impossible and set to
        NaN. :data:`OCULOMOTOR_RANGE` (50) is the usual choice; on the real
        example recording it flags 92 of the left eye's 53184 confident
        samples and 25 of the right eye's 52197 (up to 81 and 88 deg). Default: no sample is flagged for its angle.

    Returns
    -------
    xarray.DataArray, dims (time, cartesian_axis), shape (m, 3)
        Unit vectors, NaN where the sample is missing, below
        ``min_confidence``, beyond ``max_angle``, inserted in a gap, or outside the time range of
        the frames between the eye and ``into``. ``attrs`` has
        ``representation_frame`` (the name of ``into``), which
        :func:`angles` and the ``transform_*`` functions read.

    Raises
    ------
    ValueError
        If a frame is not registered, the eye frame is static and no
        confidence DataArray gives the times, ``confidence`` has the wrong
        shape, or ``min_confidence``/``max_gap`` is not a finite number
        (``max_gap`` positive, ``max_angle`` in (0, 180]).
    """
    args = _door.sight(
        resolve_frame, eye_frame, into, confidence, min_confidence, max_gap, max_angle
    )
    times, valid = args.times, args.valid
    out = np.full((len(times), 3), np.nan)
    count = int(np.count_nonzero(valid))
    if count:
        # the valid rows' unit lines of sight in one pass (no copy of the
        # rows); beyond max_angle from the parent's z axis (where the eye
        # looks ahead) they are NaN
        sight = np.empty((count, 3))
        check = args.max_angle is not None
        min_z = 0.0
        if args.max_angle is not None:
            min_z = float(np.cos(np.radians(args.max_angle)))
        _gk.sight_rows(
            _readable(args.rotation), np.ascontiguousarray(valid),
            _LINE_OF_SIGHT, min_z, check, sight,
        )  # fmt: skip
        out[valid] = _represent(sight, args.track, args.eye.parent, args.into)
    sampled = times
    if args.max_gap is not None:
        times, out = _insert_gap_rows(times, out, args.max_gap)
    # on the confidence's own times (no row inserted): share its time index
    like = args.like if times is sampled else None
    return _vectors_dataarray(out, times, args.into.name, like)


def angles(
    directions: xr.DataArray,
    reference: FrameLike,
    *,
    forward: str = "z",
    up: str = "-y",
) -> xr.DataArray:
    """Azimuth and elevation of directions relative to a frame's forward axis.

    Parameters
    ----------
    directions : DataArray, dims (time, cartesian_axis), shape (n, 3)
        Directions as returned by :func:`directions`; its attribute
        ``representation_frame`` names the frame they are represented in.
        NaN rows stay NaN.
    reference : str or ReferenceFrame
        The frame whose axes the angles are measured in; the directions are
        first represented in it (moving frames interpolated at their times).
    forward, up : str, default "z" and "-y"
        The reference frame's forward and up axes as an axis letter with an
        optional sign. The defaults are the camera convention (x right, y
        down, z forward); use ``forward="x", up="z"`` for ROS axes.

    Returns
    -------
    xarray.DataArray, dims (time, angle), shape (n, 2)
        ``azimuth`` (positive to the right, i.e. along forward x up) and
        ``elevation`` (positive up), in degrees; azimuth is in (-180, 180],
        elevation in [-90, 90].

    Raises
    ------
    ValueError
        If ``directions`` lacks the dims or frame attribute, ``forward`` and
        ``up`` are not two different axes, or a frame is not registered.
    """
    args = _door.angle_arguments(resolve_frame, directions, reference, forward, up)
    values, valid = args.values, args.valid
    local = values  # in the reference's axes already: read as they are
    if args.track is not None:
        local = np.full(values.shape, np.nan)
        if valid.any():
            local[valid] = _represent(
                values[valid], args.track, args.source, args.reference
            )
    (f_axis, f_sign), (u_axis, u_sign) = args.forward, args.up
    fwd = np.zeros(3)
    fwd[f_axis] = f_sign
    upv = np.zeros(3)
    upv[u_axis] = u_sign
    right = np.cross(fwd, upv)
    # the components along right, forward and up in one pass; the arc
    # tangents by numpy, in place (its own arctan2, not libm's)
    xyz = np.empty((3, len(values)))
    _gk.axis_components(
        _readable(local), np.ascontiguousarray(valid), right, fwd, upv, xyz
    )
    elevation = np.hypot(xyz[0], xyz[1])
    np.arctan2(xyz[2], elevation, out=elevation)
    azimuth = np.arctan2(xyz[0], xyz[1], out=xyz[2])
    out = np.empty((len(values), 2))
    np.degrees(azimuth, out=out[:, 0])
    np.degrees(elevation, out=out[:, 1])
    del xyz, elevation
    return _on_times_of(
        directions,
        out,
        ("angle", ["azimuth", "elevation"]),
        {
            "long_name": "Gaze angles",
            "units": "deg",
            "reference_frame": args.reference.name,
        },
    )


def rates(angles: xr.DataArray, *, window: float = 0.02) -> xr.DataArray:
    """Angular velocity (deg/s) of gaze angles, from valid samples only.

    Each sample's rate is the slope between the first and the last valid
    sample within ``window`` seconds centred on it, so one missing
    neighbour does not remove a rate and noise is averaged over the
    window; a saccade (30-100 ms) keeps most of its peak with the default
    20 ms. Where the valid samples in the window span less than half of it,
    the rate is NaN, as it is at missing samples.

    Parameters
    ----------
    angles : DataArray, dims (time, ...), numeric or datetime64 ``time``
        Angles in degrees, e.g. from :func:`angles`; NaN rows are missing.
    window : float, default 0.02
        Seconds.

    Returns
    -------
    xarray.DataArray
        Same dims and coordinates, ``units`` "deg/s".

    Raises
    ------
    ValueError
        If ``angles`` has no ``time`` dimension, its times are out of order
        or ``window`` is not positive.
    """
    args = _door.rate_arguments(angles, window)
    out = np.empty(args.values.shape)
    half = args.window / 2
    # (half the window, less a rounding error of the times)
    min_span = args.window / 2 * (1 - 1e-9)
    _gk.windowed_slopes(
        kernel_array(args.t), _readable(args.values), half, min_span, out
    )
    # a shallow copy: the result shares the angles' time index (a deep copy
    # would hold a second copy of every timestamp for as long as it lives)
    result = args.arr.copy(deep=False, data=out.reshape(args.arr.shape))
    result.attrs = {"long_name": "Gaze angular velocity", "units": "deg/s"}
    return result.transpose(*angles.dims)


# -- helpers ----------------------------------------------------------------


def _represent(vectors, track, outof, into) -> np.ndarray:
    """Vectors (n, 3) given in ``outof`` at ``track``'s times, represented in ``into``.

    ``track`` is None when ``outof`` is ``into``. NaN at the times the frames
    between them do not cover: the engine keeps only the run of times that
    every moving frame on the way covers.
    """
    if track is None:
        return vectors
    moved, times = _engine_transform.transform(
        outof, "vectors", Blocks.of_rows(vectors, track), into
    )
    if len(moved) == len(vectors):
        return moved
    out = np.full(vectors.shape, np.nan)
    # the result's times are some of the given ones (the same values)
    out[np.searchsorted(track.values, times)] = moved
    return out


def _insert_gap_rows(times, values, max_gap):
    keys = sort_keys(times, "times")
    scale = 1e9 if np.issubdtype(np.asarray(times).dtype, np.datetime64) else 1.0
    gaps = np.flatnonzero(np.diff(keys) > max_gap * scale)
    if gaps.size == 0:
        return times, values
    t = np.asarray(times)
    middle = t[gaps] + (t[gaps + 1] - t[gaps]) / 2
    at = gaps + 1
    return (
        np.insert(t, at, middle),
        np.insert(values, at, np.full((gaps.size, values.shape[1]), np.nan), axis=0),
    )


def _on_times_of(directions, values, column, attrs):
    """``values`` (n, 2) as a DataArray along ``directions``' time and ``column``.

    Built from a shallow copy of ``directions``, so the result shares its
    time index: a new DataArray would copy every timestamp (xarray's
    constructor deep-copies index coordinates), and the explorer's plots
    keep these results for as long as the dashboard lives.
    """
    import xarray as xr

    dim, labels = column
    if "time" not in directions.indexes:  # no time coordinate to share
        return xr.DataArray(
            values,
            dims=("time", dim),
            coords={"time": directions["time"].values, dim: labels},
            attrs=attrs,
        )
    template = directions.transpose("time", "cartesian_axis").isel(
        cartesian_axis=slice(0, values.shape[1])
    )
    template = template.drop_vars([c for c in template.coords if c != "time"])
    out = template.copy(deep=False, data=values).rename(cartesian_axis=dim)
    out = out.assign_coords({dim: labels})
    out.name, out.attrs = None, attrs
    return out


def _vectors_dataarray(values, times, frame_name, like=None):
    """The line-of-sight DataArray; on ``like``'s time index when given (1-d,
    along ``time``, with the same times): a shallow copy of it shares the
    index, where a new DataArray would copy every timestamp. Else on
    ``times`` themselves when nobody can change them (the frames' are such):
    see :mod:`rbm_nb._infra.time_index`."""
    axes = np.array(["x", "y", "z"])
    attrs = {
        "long_name": "Line of sight",
        "units": "1",
        "representation_frame": frame_name,
    }
    if like is None or "time" not in like.indexes:
        return dataarray_on(
            values, times, ("time", "cartesian_axis"), {"cartesian_axis": axes},
            attrs=attrs,
        )  # fmt: skip
    template = like.drop_vars([c for c in like.coords if c != "time"])
    out = template.expand_dims(cartesian_axis=3, axis=1).copy(deep=False, data=values)
    out = out.assign_coords(cartesian_axis=axes)
    out.name, out.attrs = None, attrs
    return out
