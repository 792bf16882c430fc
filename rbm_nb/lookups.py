"""Look up transforms, poses and velocities between frames of a tree.

Velocities are estimated from the looked-up transform by finite
differences (in :mod:`rbm_nb.estimators`): the linear velocity comes out
represented in the reference frame, the angular velocity in the moving
frame, and both are then represented in ``represent_in``.
"""

from __future__ import annotations

import numpy as np

from . import _matching
from ._kernels import quaternion as kq
from ._kernels import resample as kr
from ._validation import check_mode
from .frames import _resolve

__all__ = [
    "lookup_transform",
    "lookup_pose",
    "lookup_twist",
    "lookup_linear_velocity",
    "lookup_angular_velocity",
]


# ---------------------------------------------------------------------------
# frame-level implementation (ReferenceFrame.lookup_* forward here)
# ---------------------------------------------------------------------------


def _lookup(frame, to_frame):
    """Translation (n|1, 3), rotation (n|1, 4) and Target from frame to to_frame."""
    to_frame = _resolve(to_frame, "to_frame")
    steps = _matching.chain(frame, to_frame)
    target = _matching.match([f for f, _ in steps])
    t, r = _matching.compose(steps, target)
    n = len(target)
    if target.track is not None and t.shape[0] != n:
        t = np.repeat(t, n, axis=0)
        r = np.repeat(r, n, axis=0)
    return t, r, target


def _frame_lookup_transform(frame, to_frame):
    t, r, target = _lookup(frame, to_frame)
    if target.track is None:
        return t[0], r[0], None
    return t, r, target.timestamps


def _defaults(frame, reference, represent_in):
    if reference is None or represent_in is None:
        if frame.parent is None:
            raise ValueError(
                f"frame {frame.name!r} has no parent; pass the reference frame explicitly"
            )
    reference = _resolve(
        reference if reference is not None else frame.parent, "reference"
    )
    represent_in = _resolve(
        represent_in if represent_in is not None else frame.parent, "represent_in"
    )
    return reference, represent_in


def _moving_lookup(frame, reference, allow_static):
    t, r, target = _lookup(frame, reference)
    if target.track is None:
        if allow_static:
            return None
        raise ValueError(
            f"the transform between {frame.name!r} and {reference.name!r} is static; "
            f"a velocity needs timestamps (pass allow_static=True for zeros)"
        )
    return t, r, target


def _represent(vectors, track, outof, into, looked_up=None):
    """Vectors (n, 3) at ``track`` re-represented from ``outof`` in ``into``.

    ``looked_up`` is (frame, reference, r): the rotation r from frame to
    reference at ``track``, already known; re-representing between those two
    frames then needs no second lookup (the result is the same).
    """
    if outof is into:
        return vectors, track
    if looked_up is not None:
        frame, reference, r = looked_up
        if outof is frame and into is reference:
            return _rotate(r, vectors), track
        if outof is reference and into is frame:
            return _rotate(kq.qconj(r), vectors), track
    from .transforms import _frame_transform

    out, ts = _frame_transform(outof, "vectors", vectors, into, timestamps=track)
    return out, _matching_track(track, ts)


def _rotate(r, vectors):
    return kr.transform_blocks(
        r, r[:1, :3], np.ascontiguousarray(vectors)[:, None, :], False
    )[:, 0]


def _matching_track(track, values):
    from .transforms import _track_of

    return _track_of(track, values)


def _result(values, track, as_track):
    return values, (track if as_track else (None if track is None else track.values))


def _linear_part(frame, reference, represent_in, looked_up, outlier_thresh, cutoff):
    """Linear velocity of ``frame`` wrt ``reference``, represented in ``represent_in``."""
    from .estimators import _linear_velocity

    t, r, target = looked_up
    linear = _linear_velocity(t, target.track.seconds(), outlier_thresh, cutoff)
    return _represent(
        linear, target.track, reference, represent_in, (frame, reference, r)
    )


def _angular_part(
    frame, reference, represent_in, looked_up, mode, outlier_thresh, cutoff
):
    """Angular velocity of ``frame`` wrt ``reference``, represented in ``represent_in``."""
    from .estimators import _angular_velocity

    _, r, target = looked_up
    angular = _angular_velocity(r, target.track.seconds(), mode, outlier_thresh, cutoff)
    # the estimate is in the moving frame's axes (2 q^-1 dq/dt)
    return _represent(angular, target.track, frame, represent_in, (frame, reference, r))


def _frame_lookup_linear_velocity(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    allow_static=False,
    as_track=False,
):
    reference, represent_in = _defaults(frame, reference, represent_in)
    looked_up = _moving_lookup(frame, reference, allow_static)
    if looked_up is None:
        return np.zeros(3), None
    linear, track = _linear_part(
        frame, reference, represent_in, looked_up, outlier_thresh, cutoff
    )
    return _result(linear, track, as_track)


def _frame_lookup_angular_velocity(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    mode="quaternion",
    allow_static=False,
    as_track=False,
):
    check_mode(mode)
    reference, represent_in = _defaults(frame, reference, represent_in)
    looked_up = _moving_lookup(frame, reference, allow_static)
    if looked_up is None:
        return np.zeros(3), None
    angular, track = _angular_part(
        frame, reference, represent_in, looked_up, mode, outlier_thresh, cutoff
    )
    return _result(angular, track, as_track)


def _frame_lookup_twist(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    mode="quaternion",
    allow_static=False,
    as_track=False,
):
    check_mode(mode)
    reference, represent_in = _defaults(frame, reference, represent_in)
    looked_up = _moving_lookup(frame, reference, allow_static)
    if looked_up is None:
        return np.zeros(3), np.zeros(3), None
    linear, lin_track = _linear_part(
        frame, reference, represent_in, looked_up, outlier_thresh, cutoff
    )
    # outlier_thresh refers to the position, so the rotation is not filtered
    angular, ang_track = _angular_part(
        frame, reference, represent_in, looked_up, mode, None, cutoff
    )
    final = _matching.match([], [ang_track, lin_track])
    angular = _matching.resample_array(angular[:, None, :], ang_track, final, False)[
        :, 0
    ]
    linear = _matching.resample_array(linear[:, None, :], lin_track, final, False)[:, 0]
    if as_track:
        return linear, angular, final.track
    return linear, angular, final.timestamps


# ---------------------------------------------------------------------------
# public functions
# ---------------------------------------------------------------------------


def lookup_transform(
    outof,
    into,
    as_dataset=False,
    return_timestamps=False,
    *,
    time=None,
    as_matrix=False,
    as_transform=False,
):
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
        extrapolated. See :mod:`rbm_nb._at_time`.
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
    if time is not None or as_matrix or as_transform:
        from ._at_time import lookup_at

        return lookup_at(
            outof, into, time, as_matrix=as_matrix, as_transform=as_transform,
            as_dataset=as_dataset, return_timestamps=return_timestamps,
        )  # fmt: skip
    into = _resolve(into, "into")
    outof = _resolve(outof, "outof")
    translation, rotation, timestamps = _frame_lookup_transform(outof, into)
    if as_dataset:
        from ._xarray import transform_dataset

        return transform_dataset(translation, rotation, outof.name, timestamps)
    if return_timestamps:
        return translation, rotation, timestamps
    return translation, rotation


def lookup_pose(frame, reference, as_dataset=False, return_timestamps=False):
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
    reference = _resolve(reference, "reference")
    frame = _resolve(frame, "frame")
    position, orientation, timestamps = _frame_lookup_transform(frame, reference)
    if as_dataset:
        from ._xarray import transform_dataset

        return transform_dataset(
            position, orientation, reference.name, timestamps, pose=True
        )
    if return_timestamps:
        return position, orientation, timestamps
    return position, orientation


def _public_frames(frame, reference, represent_in):
    frame = _resolve(frame, "frame")
    if reference is None:
        if frame.parent is None:
            raise ValueError(
                f"frame {frame.name!r} has no parent; pass the reference frame explicitly"
            )
        reference = frame.parent
    reference = _resolve(reference, "reference")
    represent_in = _resolve(
        represent_in if represent_in is not None else reference, "represent_in"
    )
    return frame, reference, represent_in


def lookup_twist(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    mode="quaternion",
    as_dataset=False,
    return_timestamps=False,
):
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
        How the angular velocity is differentiated.
    as_dataset : bool, default False
    return_timestamps : bool, default False

    Returns
    -------
    linear, angular : ndarray, shape (n, 3)
    timestamps : ndarray, shape (n,), if ``return_timestamps``
    ds : xarray.Dataset, if ``as_dataset``
    """
    frame, reference, represent_in = _public_frames(frame, reference, represent_in)
    linear, angular, timestamps = _frame_lookup_twist(
        frame, reference, represent_in, outlier_thresh, cutoff, mode
    )
    if as_dataset:
        from ._xarray import twist_dataset

        return twist_dataset(
            linear, angular, frame.name, reference.name, represent_in.name, timestamps
        )
    if return_timestamps:
        return linear, angular, timestamps
    return linear, angular


def lookup_linear_velocity(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    as_dataarray=False,
    return_timestamps=False,
):
    """Estimate the linear velocity of ``frame`` wrt ``reference``.

    Parameters are those of :func:`lookup_twist` (``as_dataarray`` returns
    an xarray DataArray with dims time and cartesian_axis).

    Returns
    -------
    linear : ndarray, shape (n, 3), or DataArray
    timestamps : ndarray, shape (n,), if ``return_timestamps``
    """
    frame, reference, represent_in = _public_frames(frame, reference, represent_in)
    linear, timestamps = _frame_lookup_linear_velocity(
        frame, reference, represent_in, outlier_thresh, cutoff
    )
    if as_dataarray:
        from ._xarray import velocity_dataarray

        return velocity_dataarray(
            linear, "linear", frame.name, reference.name, represent_in.name, timestamps
        )
    if return_timestamps:
        return linear, timestamps
    return linear


def lookup_angular_velocity(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    mode="quaternion",
    as_dataarray=False,
    return_timestamps=False,
):
    """Estimate the angular velocity of ``frame`` wrt ``reference``.

    Parameters are those of :func:`lookup_twist`; ``outlier_thresh`` here
    applies to the second differences of the rotation.

    Returns
    -------
    angular : ndarray, shape (n, 3), or DataArray
    timestamps : ndarray, shape (n,), if ``return_timestamps``
    """
    frame, reference, represent_in = _public_frames(frame, reference, represent_in)
    angular, timestamps = _frame_lookup_angular_velocity(
        frame, reference, represent_in, outlier_thresh, cutoff, mode
    )
    if as_dataarray:
        from ._xarray import velocity_dataarray

        return velocity_dataarray(
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
