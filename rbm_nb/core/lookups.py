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

from .._door import lookups as _door
from .._engine import at_time as _at_time
from .._engine import chain as _chain
from .._engine import twist as _twist
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._kernels import conversions as _kc
from .._kernels._arrays import kernel_array
from .conversions import homogeneous_from_transform
from .frames import FrameLike, resolve_frame
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
        t, r, _ = _chain.lookup_transform(*_door.frames(resolve_frame, outof, into))
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
    pair = _door.transform_frames(
        resolve_frame, outof, into, as_matrix, as_transform, as_dataset, time
    )
    outof, into = pair.outof, pair.into
    if pair.at is None:  # (time None: the frames' own times)
        t, r, timestamps = _chain.lookup_transform(outof, into)
    else:
        t, r, timestamps = _at_time.transform_at_times(outof, into, pair.at)
    if as_dataset:
        return pair.dataset(t, r, timestamps)
    out: Any
    if as_matrix:
        out = _matrices(t, r)
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
    pair = _door.pose_frames(resolve_frame, frame, reference)
    position, orientation, timestamps = _chain.lookup_transform(pair.outof, pair.into)
    if as_dataset:
        return pair.dataset(position, orientation, timestamps, pose=True)
    if return_timestamps:
        return position, orientation, timestamps
    return position, orientation


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
    args = _door.velocity_frames(
        resolve_frame, frame, reference, represent_in, outlier_thresh, cutoff, mode
    )
    linear, angular, timestamps = _twist.lookup_twist(
        args.frame, args.reference, args.represent_in, outlier_thresh, cutoff,
        args.mode, as_track=as_dataset,
    )  # fmt: skip
    if as_dataset:
        # the Track's own times: the Dataset's index holds them, immutable,
        # no copy (the arrays' callers get one)
        return args.twist_dataset(linear, angular, timestamps.values)
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
    args = _door.velocity_frames(
        resolve_frame, frame, reference, represent_in, outlier_thresh, cutoff
    )
    linear, timestamps = _twist.lookup_linear_velocity(
        args.frame, args.reference, args.represent_in, outlier_thresh, cutoff
    )
    if as_dataarray:
        return args.dataarray(linear, "linear", timestamps)
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
    args = _door.velocity_frames(
        resolve_frame, frame, reference, represent_in, outlier_thresh, cutoff, mode
    )
    angular, timestamps = _twist.lookup_angular_velocity(
        args.frame, args.reference, args.represent_in, outlier_thresh, cutoff,
        args.mode,
    )  # fmt: skip
    if as_dataarray:
        return args.dataarray(angular, "angular", timestamps)
    if return_timestamps:
        return angular, timestamps
    return angular


def _matrices(t: Any, r: Any) -> Any:
    """Homogeneous matrices of the engine's (t, r), (3,)/(4,) or (n, 3)/(n, 4):
    the conversion kernel, as ``homogeneous_from_transform`` calls it after
    its door (the engine's rows need none)."""
    lead = t.shape[:-1]
    out, bad_q, bad_t = _kc.homogeneous_from_transform(
        kernel_array(t.reshape(-1, 3)),
        kernel_array(r.reshape(-1, 4)),
        UNIT_QUATERNION_TOLERANCE,
    )
    if bad_q or bad_t:
        # a missing sample (NaN row): the conversion's own refusal, as before
        return homogeneous_from_transform(t, r)
    return out.reshape(lead + (4, 4))
