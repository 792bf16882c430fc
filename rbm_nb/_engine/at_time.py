"""Point-in-time lookups: a transform between two resolved frames at chosen times.

A lookup without a time returns the transform at the timestamps the frames
were recorded at (matched by the rules in :mod:`rbm_nb._engine.chain`). Here
the caller names the times instead, tf2 style: every moving frame of the
chain is interpolated at exactly those times (translation linearly, rotation
by squad, as the core resamples; discrete frames hold their last event) and
the chain is composed.

Nothing is extrapolated: a time before the first or after the last sample
of a continuous moving frame on the chain raises
:class:`~rbm_nb.errors.ExtrapolationError` naming the frame, its time range
and the offending time.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import ExtrapolationError
from . import chain as _chain
from . import time as _time

__all__ = ["Requested", "transform_at_times", "latest_common_time"]


class Requested(NamedTuple):
    """Times a caller asks for, checked at the door (:func:`_time.requested_times`)."""

    track: _time.Track  # the sorted unique times
    inverse: np.ndarray  # the position of each requested time in track
    scalar: bool  # a single time (0-d) was requested
    values: np.ndarray  # the requested times as given


def _moving(steps):
    continuous = [f for f, _ in steps if f.track is not None and not f.discrete]
    discrete = [f for f, _ in steps if f.track is not None and f.discrete]
    return continuous, discrete


def _check_range(frames, track) -> None:
    """Raise ExtrapolationError if ``track`` leaves any frame's time range."""
    for frame in frames:
        own = frame.track
        if track.key[0] < own.key[0]:
            raise ExtrapolationError(
                f"frame {frame.name!r} {_span(own)}; the requested time "
                f"{track.values[0]} is before its first sample (lookups do not "
                "extrapolate into the past)"
            )
        if track.key[-1] > own.key[-1]:
            raise ExtrapolationError(
                f"frame {frame.name!r} {_span(own)}; the requested time "
                f"{track.values[-1]} is after its last sample (lookups do not "
                "extrapolate into the future)"
            )


def _span(own) -> str:
    # worded only when raising: formatting two numpy times costs ~2 µs, a
    # tenth of a one-time lookup
    return f"has data from {own.values[0]} to {own.values[-1]} ({len(own)} samples)"


def transform_at_times(outof, into, requested: Requested):
    """Transform from ``outof`` to ``into`` at the requested times.

    Parameters
    ----------
    outof, into : ReferenceFrame
        Resolved frames of the same tree.
    requested : Requested
        Numeric or datetime64 times, like the moving frames' timestamps, in
        any order, repeats allowed: the door's
        ``Requested(*_time.requested_times(times))``.

    Returns
    -------
    translation : ndarray, shape (3,) or (n, 3)
    rotation : ndarray, shape (4,) or (n, 4)
        Such that ``p_into = rot(rotation, p_outof) + translation`` at each
        requested time, in the order requested.
    timestamps : ndarray, shape (n,), or None
        The requested times as given (None for a scalar time).

    Raises
    ------
    ExtrapolationError
        If a requested time lies outside the range of a continuous moving
        frame on the chain.
    ValueError
        If the frames are in different trees, or datetime64 and numeric
        times meet (what only the frames' data can tell).
    """
    track, inverse, scalar, values = requested
    steps = _chain.chain(outof, into)
    continuous, discrete = _moving(steps)
    _time.check_compatible([f.track for f in continuous + discrete] + [track])
    _check_range(continuous, track)
    t, r = _chain.evaluate(steps, _chain.Target(track, None))
    # (1, 3) and (1, 4) where the chain does not move; copies either way (a
    # static chain's rows are the cached ones)
    t, r = t.reshape(-1, 3), r.reshape(-1, 4)
    if scalar:
        return t[0].copy(), r[0].copy(), None
    if t.shape[0] == 1:
        t, r = np.repeat(t, len(track), axis=0), np.repeat(r, len(track), axis=0)
    return t[inverse], r[inverse], values


def latest_common_time(outof, into):
    """The latest time at which the whole chain from ``outof`` to ``into`` has data.

    That is the earliest last sample among the continuous moving frames on
    the chain (discrete frames hold their value and do not limit it), or the
    latest event of the discrete frames if there is no continuous one.

    Returns
    -------
    scalar or None
        A timestamp in the frames' dtype, or None if the chain is static.

    Raises
    ------
    ExtrapolationError
        If the continuous frames' time ranges do not overlap.
    """
    continuous, discrete = _moving(_chain.chain(outof, into))
    if continuous:
        _time.check_compatible([f.track for f in continuous])
        ends = [f.track.key[-1] for f in continuous]
        starts = [f.track.key[0] for f in continuous]
        latest = continuous[int(np.argmin(ends))]
        earliest = continuous[int(np.argmax(starts))]
        if max(starts) > min(ends):
            raise ExtrapolationError(
                f"no common time: frame {earliest.name!r} starts at "
                f"{earliest.track.values[0]}, after frame {latest.name!r} ends at "
                f"{latest.track.values[-1]}"
            )
        return latest.track.values[-1]
    if discrete:
        _time.check_compatible([f.track for f in discrete])
        return discrete[
            int(np.argmax([f.track.key[-1] for f in discrete]))
        ].track.values[-1]
    return None
