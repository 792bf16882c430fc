"""Velocities between resolved frames: lookups and the three-term transforms.

Velocities are estimated from the looked-up transform by finite differences
(:mod:`rbm_nb._engine.velocity`): the linear velocity comes out represented
in the reference frame, the angular velocity in the moving frame, and both
are then represented in ``represent_in``.

Changing the frames of a velocity uses the three-term formulas:

* angular, new reference R -> R': w_M/R' = w_M/R + w_R/R';
* angular, new moving frame M -> M': w_M'/R = w_M/R + w_M'/M;
* linear, new reference: v_M/R' = v_M/R + v_R/R' + w_R/R' x t_M/R;
* linear, new moving frame: v_M'/R = v_M/R + v_M'/M + w_M/R x t_M'/M.

Every frame argument is a resolved ``ReferenceFrame`` (or None where a
default applies); the facades resolve names.
"""

from __future__ import annotations

import numpy as np

from .._kernels import quaternion as kq
from .._kernels import resample as kr
from .._kernels._arrays import kernel_array
from . import chain as _chain
from . import fused as _fused
from . import velocity as _velocity
from .transform import Blocks, track_of, transform

__all__ = [
    "lookup_linear_velocity",
    "lookup_angular_velocity",
    "lookup_twist",
    "transform_angular_velocity",
    "transform_linear_velocity",
    "velocity_terms",
    "velocity_parts",
    "interpolated_terms",
    "combine",
]


def _moving_lookup(frame, reference, allow_static, rotation_only=False):
    t, r, target = _chain.lookup(frame, reference, rotation_only)
    if target.track is None:
        # (the door refuses a static chain unless allow_static: zeros)
        assert allow_static, "the door refuses a static chain's velocity"
        return None
    return t, r, target, _breaks(frame, reference, target)


def _breaks(frame, reference, target):
    """Where consecutive samples straddle a gap longer than a frame's max_gap.

    Returns a boolean array (n - 1,) or None: velocities take no difference
    across such a pair (the motion may have jumped while nothing was recorded).
    """
    track = target.track
    out = None
    for f, _ in _chain.chain(frame, reference):
        if f.track is None or f.discrete or f.max_gap is None or len(track) < 2:
            continue
        base = track.base_in(f.track.origin)
        middle = 0.5 * (base[1:] + base[:-1])
        gap = _chain.in_long_gap(f.track.base, middle, f.max_gap)
        out = gap if out is None else out | gap
    return out


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
            return _rotate(kq.qconj(kernel_array(r)), vectors), track
    out, ts = transform(outof, "vectors", Blocks.of_rows(vectors, track), into)
    return out, track_of(track, ts)


def _rotate(r, vectors):
    r = kernel_array(r)
    return kr.transform_blocks(
        r, kernel_array(r[:1, :3]), kernel_array(vectors)[:, None, :], False
    )[:, 0]


def _result(values, track, as_track):
    return values, (track if as_track else (None if track is None else track.values))


def _linear_part(frame, reference, represent_in, looked_up, outlier_thresh, cutoff):
    """Linear velocity of ``frame`` wrt ``reference``, represented in ``represent_in``."""
    t, r, target, breaks = looked_up
    linear = _velocity.linear_velocity(
        t,
        target.track.seconds(),
        outlier_thresh,
        cutoff,
        breaks,
    )
    return _represent(
        linear, target.track, reference, represent_in, (frame, reference, r)
    )


def _angular_part(
    frame, reference, represent_in, looked_up, mode, outlier_thresh, cutoff
):
    """Angular velocity of ``frame`` wrt ``reference``, represented in ``represent_in``."""
    _, r, target, breaks = looked_up
    angular = _velocity.angular_velocity(
        r,
        target.track.seconds(),
        mode,
        outlier_thresh,
        cutoff,
        breaks,
    )
    # the estimate is in the moving frame's axes (2 q^-1 dq/dt)
    return _represent(angular, target.track, frame, represent_in, (frame, reference, r))


def lookup_linear_velocity(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    allow_static=False,
    as_track=False,
):
    """Linear velocity (n, 3) of ``frame`` wrt ``reference`` and its timestamps."""
    looked_up = _moving_lookup(frame, reference, allow_static)
    if looked_up is None:
        return np.zeros(3), None
    linear, track = _linear_part(
        frame, reference, represent_in, looked_up, outlier_thresh, cutoff
    )
    return _result(linear, track, as_track)


def lookup_angular_velocity(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    mode="quaternion",
    allow_static=False,
    as_track=False,
):
    """Angular velocity (n, 3) of ``frame`` wrt ``reference`` and its timestamps
    (``mode`` checked by the caller)."""
    if (
        mode == "quaternion"
        and outlier_thresh is None
        and cutoff is None
        and (represent_in is frame or represent_in is reference)
    ):
        lean = _chain_rates(frame, reference, represent_in is reference)
        if lean is not None:
            return _result(lean[0], lean[1], as_track)
    # (the translations are not needed: not computed, not held in memory)
    looked_up = _moving_lookup(frame, reference, allow_static, rotation_only=True)
    if looked_up is None:
        return np.zeros(3), None
    angular, track = _angular_part(
        frame, reference, represent_in, looked_up, mode, outlier_thresh, cutoff
    )
    return _result(angular, track, as_track)


def _chain_rates(frame, reference, in_reference):
    """(angular velocity, Track) by the chain kernel, or None where it does not apply.

    The same rates as the lookup followed by the estimate, without the
    lookup's rotations in memory (:func:`rbm_nb._engine.fused.body_rates`).
    It does not apply across a long gap (the estimate splits the series
    there) nor where a rotation is missing: the caller's route handles both.
    """
    planned = _chain.rates_plan(frame, reference)
    if planned is None:
        return None
    plan, own, target = planned
    breaks = _breaks(frame, reference, target)
    if breaks is not None and breaks.any():
        return None
    rates = _fused.body_rates(plan, target, own, in_reference)
    return None if rates is None else (rates, target.track)


def lookup_twist(
    frame,
    reference=None,
    represent_in=None,
    outlier_thresh=None,
    cutoff=None,
    mode="quaternion",
    allow_static=False,
    as_track=False,
):
    """Linear and angular velocity (n, 3) each of ``frame`` and their timestamps
    (``mode`` checked by the caller)."""
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
    final = _chain.match([], [ang_track, lin_track])
    angular = _chain.resample_array(angular[:, None, :], ang_track, final, False)[:, 0]
    linear = _chain.resample_array(linear[:, None, :], lin_track, final, False)[:, 0]
    if as_track:
        return linear, angular, final.track
    return linear, angular, final.timestamps


# ---------------------------------------------------------------------------
# changing the frames of a velocity
# ---------------------------------------------------------------------------


def velocity_terms(
    linear: bool,
    frame,
    to_frame,
    what: str,
    moving_frame=None,
    reference_frame=None,
    outlier_thresh=None,
    cutoff=None,
):
    """The looked-up terms of a change of the reference or moving frame of velocities.

    Estimated once for a whole call (the eager transform, and the lazy one
    before its graph is cut into chunks). ``what`` is "reference_frame" or
    "moving_frame"; ``moving_frame`` (linear, reference frame changed) and
    ``reference_frame`` (linear, moving frame changed) are resolved frames
    or None.

    Returns
    -------
    extras : list of (ndarray (n|1, 3), Track or None)
        One term for angular velocities (added), three for linear ones
        (``rotated + ext[0] + ext[1] x ext[2]``, see :func:`combine`).
    """
    if not linear:
        # w_M/R' = w_M/R + w_R/R'  or  w_M'/R = w_M/R + w_M'/M
        moving, reference = (
            (frame, to_frame) if what == "reference_frame" else (to_frame, frame)
        )
        angular, ang_ts = lookup_angular_velocity(
            moving, reference, to_frame, None, cutoff, "quaternion", True, as_track=True
        )
        return [(angular, ang_ts)]
    if what == "reference_frame":
        # v_M/R' = v_M/R + v_R/R' + w_R/R' x t_M/R (moving_frame given: the door)
        linear_v, angular, twist_ts = lookup_twist(
            frame, to_frame, to_frame, outlier_thresh, cutoff, "quaternion", True,
            as_track=True,
        )  # fmt: skip
        lin_ts = ang_ts = twist_ts
        translation, _, trans_target = _chain.lookup(moving_frame, frame)
    else:
        # v_M'/R = v_M/R + v_M'/M + w_M/R x t_M'/M (reference_frame given: the door)
        linear_v, lin_ts = lookup_linear_velocity(
            to_frame, frame, to_frame, outlier_thresh, cutoff, True, as_track=True
        )
        angular, ang_ts = lookup_angular_velocity(
            frame, reference_frame, to_frame, None, cutoff, "quaternion", True,
            as_track=True,
        )  # fmt: skip
        translation, _, trans_target = _chain.lookup(to_frame, frame)
    # the lever arm, represented in to_frame like everything else
    lever, lever_ts = transform(
        frame, "vectors", Blocks.of_rows(translation, trans_target.track), to_frame
    )
    lever_track = None if lever_ts is None else track_of(trans_target.track, lever_ts)
    return [(linear_v, lin_ts), (angular, ang_ts), (lever, lever_track)]


def combine(rotated, matched):
    """The transformed velocities from the rotated input and the matched terms."""
    if len(matched) == 1:
        return rotated + matched[0]
    return rotated + matched[0] + np.cross(matched[1], matched[2])


def interpolated_terms(frame, to_frame, track, extras) -> list[bool]:
    """Which terms a transform of arrays at ``track`` interpolates.

    :func:`velocity_parts` takes a term's own values where the array's
    times are a run of the term's times, and interpolates it otherwise. A
    chunk of dask-backed data may be such a run where the whole array is
    not: it then follows the whole array's choice, found here.
    """
    target = _chain.match([f for f, _ in _chain.chain(frame, to_frame)], [track])
    final = _chain.match([], [target.track] + [t for _, t in extras])
    return [
        t is not None and _chain._same_times(t, final.track) is None for _, t in extras
    ]


def velocity_parts(blocks, frame, to_frame, extras, interpolated=None):
    """Represent the input in ``to_frame`` and match it with looked-up terms.

    ``extras`` is a list of (array of shape (3,) or (n, 3), Track or None);
    ``interpolated`` (one flag per term, :func:`interpolated_terms`) forces
    the interpolation of a term where the whole array's call interpolates
    it. Returns the matched (n, k, 3) input, the matched extras as
    (n|1, 1, 3) arrays, and the target.
    """
    steps = _chain.chain(frame, to_frame)
    target = _chain.match([f for f, _ in steps], [blocks.track])
    data = _chain.resample_array(blocks.data, blocks.track, target, False)
    rotated = _chain.apply("vectors", steps, target, data)
    final = _chain.match([], [target.track] + [t for _, t in extras])
    rotated = _chain.resample_array(rotated, target.track, final, False)
    if interpolated is None:
        interpolated = [False] * len(extras)
    matched = []
    for (values, track), interpolate in zip(extras, interpolated, strict=True):
        block = kernel_array(np.reshape(values, (-1, 1, 3)))
        if interpolate:
            t_out = final.track.base_in(track.origin)
            block = kr.interp_linear(track.base, kernel_array(block[:, 0, :]), t_out)
            matched.append(block[:, None, :])
        else:
            matched.append(_chain.resample_array(block, track, final, False))
    return rotated, matched, final


def transform_angular_velocity(frame, blocks, to_frame, what, cutoff=None):
    """Change the ``what`` frame of angular velocities from ``frame`` to ``to_frame``.

    ``blocks`` are the velocities as the door laid them out (vectors) and
    ``what`` one of the door's checked modes.
    """
    if what == "representation_frame":
        return transform(frame, "vectors", blocks, to_frame)
    extras = velocity_terms(False, frame, to_frame, what, cutoff=cutoff)
    rotated, matched, final = velocity_parts(blocks, frame, to_frame, extras)
    return blocks.restore(combine(rotated, matched), final), final.timestamps


def transform_linear_velocity(
    frame,
    blocks,
    to_frame,
    what,
    moving_frame=None,
    reference_frame=None,
    outlier_thresh=None,
    cutoff=None,
):
    """Change the ``what`` frame of linear velocities from ``frame`` to ``to_frame``.

    ``blocks`` and ``what`` as for :func:`transform_angular_velocity`;
    ``moving_frame`` (for ``what="reference_frame"``) and ``reference_frame``
    (for ``what="moving_frame"``) are resolved frames or None.
    """
    if what == "representation_frame":
        return transform(frame, "vectors", blocks, to_frame)
    extras = velocity_terms(
        True, frame, to_frame, what, moving_frame, reference_frame, outlier_thresh,
        cutoff,
    )  # fmt: skip
    rotated, matched, final = velocity_parts(blocks, frame, to_frame, extras)
    return blocks.restore(combine(rotated, matched), final), final.timestamps
