"""Point-in-time lookups: a transform between two resolved frames at chosen times.

A lookup without a time returns the transform at the timestamps the frames
were recorded at (matched by the rules in :mod:`rbm_nb._engine.chain`). Here
the caller names the times instead, tf2 style: every moving frame of the
chain is interpolated at exactly those times (translation linearly, rotation
by squad, as the core resamples; discrete frames hold their last event) and
the chain is composed.

Nothing is extrapolated: the door (:mod:`rbm_nb._door.at_times`) refuses a
time before the first or after the last sample of a continuous moving frame
on the chain, and times of another kind than the frames', before this runs.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import chain as _chain
from . import time as _time

__all__ = ["Requested", "moving_frames", "transform_at_times"]


class Requested(NamedTuple):
    """Times a caller asks for, checked at the door (:func:`_time.requested_times`)."""

    track: _time.Track  # the sorted unique times
    inverse: np.ndarray  # the position of each requested time in track
    scalar: bool  # a single time (0-d) was requested
    values: np.ndarray  # the requested times as given


def transform_at_times(outof, into, requested: Requested):
    """Transform from ``outof`` to ``into`` at the requested times.

    Parameters
    ----------
    outof, into : ReferenceFrame
        Resolved frames of the same tree.
    requested : Requested
        Numeric or datetime64 times, like the moving frames' timestamps, in
        any order, repeats allowed: the door's
        ``_door.at_times.requested_at``.

    Returns
    -------
    translation : ndarray, shape (3,) or (n, 3)
    rotation : ndarray, shape (4,) or (n, 4)
        Such that ``p_into = rot(rotation, p_outof) + translation`` at each
        requested time, in the order requested.
    timestamps : ndarray, shape (n,), or None
        The requested times as given (None for a scalar time).

    The door has checked the times against the chain (``_door.at_times``):
    nothing here refuses anything.
    """
    track, inverse, scalar, values = requested
    steps = _chain.chain(outof, into)
    t, r = _chain.evaluate(steps, _chain.Target(track, None))
    # (1, 3) and (1, 4) where the chain does not move; copies either way (a
    # static chain's rows are the cached ones)
    t, r = t.reshape(-1, 3), r.reshape(-1, 4)
    if scalar:
        return t[0].copy(), r[0].copy(), None
    if t.shape[0] == 1:
        t, r = np.repeat(t, len(track), axis=0), np.repeat(r, len(track), axis=0)
    return t[inverse], r[inverse], values


def moving_frames(outof, into) -> tuple[list, list]:
    """The chain's continuous and discrete moving frames (values), in chain order."""
    steps = _chain.chain(outof, into)
    continuous = [f for f, _ in steps if f.track is not None and not f.discrete]
    discrete = [f for f, _ in steps if f.track is not None and f.discrete]
    return continuous, discrete
