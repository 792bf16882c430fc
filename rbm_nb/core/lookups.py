"""Look up transforms, poses and velocities between frames of a tree.

Velocities are estimated from the looked-up transform by finite
differences (in :mod:`rbm_nb._engine.velocity`): the linear velocity comes
out represented in the reference frame, the angular velocity in the moving
frame, and both are then represented in ``represent_in``.

These functions resolve frame names, call the engine
(:mod:`rbm_nb._engine`) and shape the result (arrays, Dataset, matrices or
a :class:`~rbm_nb.Transform`).
"""

from __future__ import annotations

from typing import Any

from .._door import xarray as _xarray
from .._door.series import velocity_options
from .._engine import at_time as _at_time
from .._engine import chain as _chain
from .._engine import twist as _twist
from .conversions import homogeneous_from_transform
from .frames import FrameLike, ReferenceFrame, resolve_frame
from .rigid_transform import Transform

__all__ = [
    "lookup_transform",
    "lookup_pose",
    "lookup_twist",
    "lookup_linear_velocity",
    "lookup_angular_velocity",
]


def lookup_transform(
    outof: FrameLike,
    into: FrameLike,
    as_dataset: bool = False,
    return_timestamps: bool = False,
    *,
    time: Any = None,
    as_matrix: bool = False,
    as_transform: bool = False,
) -> Any:
    """Look up the transform that maps points wrt ``outof`` to points wrt ``into``.

    The transform is a rotation r followed by a translation t:
    ``p_into = rot(r, p_outof) + t``.

    Parameters
    ----------
    outof, into : str or ReferenceFrame
        Base and target frame.
    as_dataset : bool, default False
        Return an xarray Dataset with ``translation`` and ``rotation``.
    return_timestamps : bool, default False
        Also return the timestamps (if not ``as_dataset``).
    time : scalar or array_like, shape (m,), optional
        Look the transform up at these times (numeric or datetime64, any
        order) instead of the frames' own timestamps: each moving frame is
        interpolated there (discrete ones hold). A time outside a moving
        frame's range raises an error naming the frame; nothing is
        extrapolated (:class:`rbm_nb.errors.ExtrapolationError`). See
        :mod:`rbm_nb._engine.at_time`.
    as_matrix : bool, default False
        Return 4 x 4 homogeneous matrices, shape (4, 4) or (n, 4, 4).
    as_transform : bool, default False
        Return a :class:`rbm_nb.Transform`.

    Returns
    -------
    translation : ndarray, shape (3,) or (n, 3)
    rotation : ndarray, shape (4,) or (n, 4)
    timestamps : ndarray, shape (n,) or None, if ``return_timestamps``
    ds : xarray.Dataset, if ``as_dataset``
    matrices : ndarray, shape (4, 4) or (n, 4, 4), if ``as_matrix``
    transform : Transform, if ``as_transform``

    Notes
    -----
    Missing samples (NaN rows) make a row NaN only where a sample it needs
    is missing (docs/missing_data.md). A single frame looked up against its
    parent at its own timestamps returns its samples as stored, as
    rigid-body-motion does: a quaternion stored with a norm slightly off 1
    (within the tolerance frames accept, 1e-2; recordings round to 4-7
    digits) comes back bit for bit, not normalised, while transforms and
    interpolated lookups rotate by the unit quaternion.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.frames import ReferenceFrame
    >>> world = ReferenceFrame("world")
    >>> observer = ReferenceFrame("observer", parent=world, translation=(5, 0, 0),
    ...                           rotation=(np.sqrt(.5), 0, 0, np.sqrt(.5)))
    >>> t, r = lookup_transform(world, observer)
    >>> np.round(t, 6) + 0.0
    array([0., 5., 0.])
    """
    if (
        not (as_dataset or return_timestamps or as_matrix or as_transform)
        and time is None
    ):
        # the common call, in a handful of operations (widgets and the
        # tf2-style Transformer make it all the time, often on static chains)
        to_frame = resolve_frame(into, "into")  # named first, as lookup_at does
        t, r, _ = _chain.lookup_transform(resolve_frame(outof, "outof"), to_frame)
        return t, r
    return lookup_at(
        outof,
        into,
        time,
        as_matrix=as_matrix,
        as_transform=as_transform,
        as_dataset=as_dataset,
        return_timestamps=return_timestamps,
    )


def lookup_at(
    outof: FrameLike,
    into: FrameLike,
    time: Any = None,
    *,
    as_matrix: bool = False,
    as_transform: bool = False,
    as_dataset: bool = False,
    return_timestamps: bool = False,
) -> Any:
    """``lookup_transform`` with every option (keyword-only beyond ``time``).

    Returns
    -------
    (translation, rotation[, timestamps]), matrices[, timestamps],
    Transform[, timestamps], or Dataset
    """
    if (as_matrix or as_transform) and (as_dataset or (as_matrix and as_transform)):
        chosen = [k for k, v in (("as_matrix", as_matrix), ("as_transform", as_transform),
                                 ("as_dataset", as_dataset)) if v]  # fmt: skip
        raise ValueError(f"choose at most one of {', '.join(chosen)}")
    into = resolve_frame(into, "into")
    outof = resolve_frame(outof, "outof")
    if time is None:
        t, r, timestamps = _chain.lookup_transform(outof, into)
    else:
        t, r, timestamps = _at_time.transform_at_times(outof, into, time)
    if as_dataset:
        return _xarray.transform_dataset(t, r, outof.name, timestamps)
    out: Any
    if as_matrix:
        out = homogeneous_from_transform(t, r)
    elif as_transform:
        out = Transform(t, r)
    else:
        return (t, r, timestamps) if return_timestamps else (t, r)
    return (out, timestamps) if return_timestamps else out


def lookup_pose(
    frame: FrameLike,
    reference: FrameLike,
    as_dataset: bool = False,
    return_timestamps: bool = False,
) -> Any:
    """Look up the position and orientation of ``frame`` wrt ``reference``.

    Parameters
    ----------
    frame, reference : str or ReferenceFrame
    as_dataset : bool, default False
        Return an xarray Dataset with ``position`` and ``orientation``.
    return_timestamps : bool, default False
        Also return the timestamps (if not ``as_dataset``).

    Returns
    -------
    position : ndarray, shape (3,) or (n, 3)
    orientation : ndarray, shape (4,) or (n, 4)
    timestamps : ndarray, shape (n,) or None, if ``return_timestamps``
    ds : xarray.Dataset, if ``as_dataset``
    """
    reference = resolve_frame(reference, "reference")
    frame = resolve_frame(frame, "frame")
    position, orientation, timestamps = _chain.lookup_transform(frame, reference)
    if as_dataset:
        return _xarray.transform_dataset(
            position, orientation, reference.name, timestamps, pose=True
        )
    if return_timestamps:
        return position, orientation, timestamps
    return position, orientation


def _public_frames(
    frame: FrameLike, reference: FrameLike | None, represent_in: FrameLike | None
) -> tuple[ReferenceFrame, ReferenceFrame, ReferenceFrame]:
    frame = resolve_frame(frame, "frame")
    if reference is None:
        if frame.parent is None:
            raise ValueError(
                f"frame {frame.name!r} has no parent; pass the reference frame explicitly"
            )
        reference = frame.parent
    reference = resolve_frame(reference, "reference")
    represent_in = resolve_frame(
        represent_in if represent_in is not None else reference, "represent_in"
    )
    return frame, reference, represent_in


def lookup_twist(
    frame: FrameLike,
    reference: FrameLike | None = None,
    represent_in: FrameLike | None = None,
    outlier_thresh: float | None = None,
    cutoff: float | None = None,
    mode: str = "quaternion",
    as_dataset: bool = False,
    return_timestamps: bool = False,
) -> Any:
    """Estimate the linear and angular velocity of ``frame`` wrt ``reference``.

    Parameters
    ----------
    frame : str or ReferenceFrame
        The moving frame.
    reference : str or ReferenceFrame, optional
        Defaults to the parent of ``frame``.
    represent_in : str or ReferenceFrame, optional
        Defaults to ``reference``.
    outlier_thresh : float, optional
        Drop samples whose second difference of position exceeds this and
        interpolate them (1e-3 suits the RealSense T265).
    cutoff : float, optional
        Low-pass cutoff as a fraction of the Nyquist frequency.
    mode : {"quaternion", "rotation_vector"}
        How the angular velocity is differentiated (the stencils of
        :func:`~rbm_nb.estimate_angular_velocity`).
    as_dataset : bool, default False
    return_timestamps : bool, default False

    Returns
    -------
    linear, angular : ndarray, shape (n, 3)
    timestamps : ndarray, shape (n,), if ``return_timestamps``
    ds : xarray.Dataset, if ``as_dataset``

    Notes
    -----
    The pose of ``frame`` in ``reference`` is looked up at the timestamps of
    the chain's moving frames and differentiated as
    :func:`~rbm_nb.estimate_linear_velocity` (numpy's gradient: samples
    i-1, i, i+1, one-sided at the ends) and
    :func:`~rbm_nb.estimate_angular_velocity` do. A missing sample of a
    frame in the chain (a NaN row) splits the series there: the velocity is
    missing at that sample and at a present one with no present neighbour,
    nowhere else, and nothing is differenced across it (nor across a gap
    longer than a frame's ``max_gap``).
    """
    frame, reference, represent_in = _public_frames(frame, reference, represent_in)
    linear, angular, timestamps = _twist.lookup_twist(
        frame,
        reference,
        represent_in,
        outlier_thresh,
        cutoff,
        velocity_options(outlier_thresh, cutoff, mode=mode),
    )
    if as_dataset:
        return _xarray.twist_dataset(
            linear, angular, frame.name, reference.name, represent_in.name, timestamps
        )
    if return_timestamps:
        return linear, angular, timestamps
    return linear, angular


def lookup_linear_velocity(
    frame: FrameLike,
    reference: FrameLike | None = None,
    represent_in: FrameLike | None = None,
    outlier_thresh: float | None = None,
    cutoff: float | None = None,
    as_dataarray: bool = False,
    return_timestamps: bool = False,
) -> Any:
    """Estimate the linear velocity of ``frame`` wrt ``reference``.

    Parameters are those of :func:`lookup_twist` (``as_dataarray`` returns
    an xarray DataArray with dims time and cartesian_axis).

    Returns
    -------
    linear : ndarray, shape (n, 3), or DataArray
    timestamps : ndarray, shape (n,), if ``return_timestamps``
    """
    frame, reference, represent_in = _public_frames(frame, reference, represent_in)
    velocity_options(outlier_thresh, cutoff)
    linear, timestamps = _twist.lookup_linear_velocity(
        frame, reference, represent_in, outlier_thresh, cutoff
    )
    if as_dataarray:
        return _xarray.velocity_dataarray(
            linear, "linear", frame.name, reference.name, represent_in.name, timestamps
        )
    if return_timestamps:
        return linear, timestamps
    return linear


def lookup_angular_velocity(
    frame: FrameLike,
    reference: FrameLike | None = None,
    represent_in: FrameLike | None = None,
    outlier_thresh: float | None = None,
    cutoff: float | None = None,
    mode: str = "quaternion",
    as_dataarray: bool = False,
    return_timestamps: bool = False,
) -> Any:
    """Estimate the angular velocity of ``frame`` wrt ``reference``.

    Parameters are those of :func:`lookup_twist`; ``outlier_thresh`` here
    applies to the second differences of the rotation.

    Returns
    -------
    angular : ndarray, shape (n, 3), or DataArray
    timestamps : ndarray, shape (n,), if ``return_timestamps``
    """
    frame, reference, represent_in = _public_frames(frame, reference, represent_in)
    angular, timestamps = _twist.lookup_angular_velocity(
        frame,
        reference,
        represent_in,
        outlier_thresh,
        cutoff,
        velocity_options(outlier_thresh, cutoff, mode=mode),
    )
    if as_dataarray:
        return _xarray.velocity_dataarray(
            angular,
            "angular",
            frame.name,
            reference.name,
            represent_in.name,
            timestamps,
        )
    if return_timestamps:
        return angular, timestamps
    return angular
