"""The times a point-in-time lookup is asked at, checked against its chain.

``lookup_transform(..., time=)``, the tf2-style ``Transformer`` and
``ape``/``rpe``'s matching ask for a transform at times of their own. Before
the engine interpolates (:mod:`rbm_nb._engine.at_time`), the times pass the
one time rule (a scalar or one dimension, not empty, numeric or datetime64,
no NaN or NaT; any order, repeats allowed), must be of the moving frames'
kind of time, and must lie inside every continuous moving frame's samples:
nothing is extrapolated, and the error names the frame, its time range and
the time (:class:`~rbm_nb.errors.ExtrapolationError`, as tf2's buffer
raises it). Discrete frames hold their events and limit nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._engine import at_time as _at_time
from .._engine import time as _time
from ..errors import ExtrapolationError
from .coverage import connected

__all__ = ["requested_at", "latest_common_time"]


def requested_at(
    outof: Any, into: Any, time: Any, name: str = "time"
) -> _at_time.Requested:
    """``time`` checked for a lookup from ``outof`` to ``into`` (resolved frames)."""
    requested = _at_time.Requested(*_time.requested_times(time, name))
    connected(outof, into)
    continuous, discrete = _at_time.moving_frames(outof, into)
    _time.check_compatible([f.track for f in continuous + discrete] + [requested.track])
    _check_range(continuous, requested.track)
    return requested


def latest_common_time(outof: Any, into: Any) -> Any:
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
    continuous, discrete = _at_time.moving_frames(outof, into)
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


def _span(own: Any) -> str:
    # worded only when raising: formatting two numpy times costs ~2 µs, a
    # tenth of a one-time lookup
    return f"has data from {own.values[0]} to {own.values[-1]} ({len(own)} samples)"


def _check_range(frames: list, track: Any) -> None:
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
