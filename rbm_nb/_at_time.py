"""Point-in-time lookups: a transform between two frames at chosen times.

``lookup_transform`` without a time returns the transform at the timestamps
the frames were recorded at (matched by the rules in ``_matching``). Here the
caller names the times instead, tf2 style: every moving frame of the chain
is interpolated at exactly those times (translation linearly, rotation by
squad, as the core resamples; discrete frames hold their last event) and
the chain is composed.

Nothing is extrapolated: a time before the first or after the last sample
of a continuous moving frame on the chain raises :class:`ExtrapolationError`
naming the frame, its time range and the offending time.
"""

from __future__ import annotations

import numpy as np

from . import _matching, _timestamps
from .frames import _resolve

__all__ = [
    "ExtrapolationError",
    "transform_at_times",
    "latest_common_time",
    "lookup_at",
]


class ExtrapolationError(ValueError):
    """A transform was requested at a time a moving frame has no data for."""


def _requested(time):
    """Validate the requested time(s).

    Returns
    -------
    track : Track
        The sorted unique times.
    inverse : ndarray of int, shape (n,)
        Position of each requested time in ``track``.
    scalar : bool
        Whether a single time (0-d) was requested.
    values : ndarray, shape (n,)
        The requested times as given (for returning them).
    """
    values = np.asarray(getattr(time, "values", time))
    scalar = values.ndim == 0
    values = values.reshape(-1) if scalar else values
    if values.ndim != 1:
        raise ValueError(
            f"time must be a scalar or one-dimensional, got shape {values.shape}"
        )
    if values.size == 0:
        raise ValueError("time must not be empty")
    kind = values.dtype.kind
    if kind == "M":
        if np.isnat(values).any():
            raise ValueError(f"time[{int(np.flatnonzero(np.isnat(values))[0])}] is NaT")
        key = values.astype("datetime64[ns]").view(np.int64)
    elif kind in "iuf":
        key = values.astype(np.float64)
        if not np.isfinite(key).all():
            bad = int(np.flatnonzero(~np.isfinite(key))[0])
            raise ValueError(f"time[{bad}] is {values[bad]}; times must be finite")
    else:
        raise ValueError(
            f"time must be numeric or datetime64 (like the frames' timestamps), "
            f"got dtype {values.dtype}"
        )
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    track = _timestamps.as_track(values[first], "time")
    return track, inverse.reshape(-1), scalar, values


def _moving(steps):
    continuous = [f for f, _ in steps if f._track is not None and not f.discrete]
    discrete = [f for f, _ in steps if f._track is not None and f.discrete]
    return continuous, discrete


def _check_range(frames, track) -> None:
    """Raise ExtrapolationError if ``track`` leaves any frame's time range."""
    for frame in frames:
        own = frame._track
        first, last = own.values[0], own.values[-1]
        span = f"has data from {first} to {last} ({len(own)} samples)"
        if track.key[0] < own.key[0]:
            raise ExtrapolationError(
                f"frame {frame.name!r} {span}; the requested time {track.values[0]} "
                f"is before its first sample (lookups do not extrapolate into the past)"
            )
        if track.key[-1] > own.key[-1]:
            raise ExtrapolationError(
                f"frame {frame.name!r} {span}; the requested time {track.values[-1]} "
                f"is after its last sample (lookups do not extrapolate into the future)"
            )


def transform_at_times(outof, into, times):
    """Transform from ``outof`` to ``into`` at the given times.

    Parameters
    ----------
    outof, into : str or ReferenceFrame
        Frames (or names of registered frames) of the same tree.
    times : scalar or array_like, shape (n,)
        Numeric or datetime64 times, like the moving frames' timestamps. Any
        order, repeats allowed.

    Returns
    -------
    translation : ndarray, shape (3,) or (n, 3)
    rotation : ndarray, shape (4,) or (n, 4)
        Such that ``p_into = rot(rotation, p_outof) + translation`` at each
        requested time, in the order requested.

    Raises
    ------
    ExtrapolationError
        If a requested time lies outside the range of a continuous moving
        frame on the chain.
    ValueError
        If the frames are in different trees, the times are invalid, or
        datetime64 and numeric times meet.
    """
    t, r, _ = _at_times(outof, into, times)
    return t, r


def _at_times(outof, into, times):
    """``transform_at_times`` plus the requested times (None for a scalar)."""
    outof = _resolve(outof, "outof")
    into = _resolve(into, "into")
    track, inverse, scalar, values = _requested(times)
    steps = _matching.chain(outof, into)
    continuous, discrete = _moving(steps)
    _timestamps.check_compatible([f._track for f in continuous + discrete] + [track])
    _check_range(continuous, track)
    t, r = _matching.compose(steps, _matching.Target(track, None))
    t = np.broadcast_to(t, (len(track), 3))[inverse]
    r = np.broadcast_to(r, (len(track), 4))[inverse]
    return (t[0], r[0], None) if scalar else (t, r, values)


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
    outof = _resolve(outof, "outof")
    into = _resolve(into, "into")
    continuous, discrete = _moving(_matching.chain(outof, into))
    if continuous:
        _timestamps.check_compatible([f._track for f in continuous])
        ends = [f._track.key[-1] for f in continuous]
        starts = [f._track.key[0] for f in continuous]
        latest = continuous[int(np.argmin(ends))]
        earliest = continuous[int(np.argmax(starts))]
        if max(starts) > min(ends):
            raise ExtrapolationError(
                f"no common time: frame {earliest.name!r} starts at "
                f"{earliest._track.values[0]}, after frame {latest.name!r} ends at "
                f"{latest._track.values[-1]}"
            )
        return latest._track.values[-1]
    if discrete:
        _timestamps.check_compatible([f._track for f in discrete])
        return discrete[
            int(np.argmax([f._track.key[-1] for f in discrete]))
        ]._track.values[-1]
    return None


def lookup_at(
    outof,
    into,
    time=None,
    *,
    as_matrix: bool = False,
    as_transform: bool = False,
    as_dataset: bool = False,
    return_timestamps: bool = False,
):
    """``lookup_transform`` with a ``time`` and the matrix/Transform outputs.

    Parameters
    ----------
    outof, into : str or ReferenceFrame
    time : scalar or array_like, optional
        Times to look the transform up at (see :func:`transform_at_times`);
        without it, the frames' own matched timestamps are used.
    as_matrix : bool, default False
        Return homogeneous matrices, shape (4, 4) or (n, 4, 4).
    as_transform : bool, default False
        Return a :class:`rbm_nb.Transform` (scalar or of shape (n,)).
    as_dataset : bool, default False
        Return an xarray Dataset (as ``lookup_transform`` does).
    return_timestamps : bool, default False
        Also return the timestamps (the requested times, or the matched
        ones; None for a static transform or a scalar time).

    Returns
    -------
    (translation, rotation[, timestamps]), matrices[, timestamps],
    Transform[, timestamps], or Dataset
    """
    chosen = [k for k, v in (("as_matrix", as_matrix), ("as_transform", as_transform),
                             ("as_dataset", as_dataset)) if v]  # fmt: skip
    if len(chosen) > 1:
        raise ValueError(f"choose at most one of {', '.join(chosen)}")
    outof = _resolve(outof, "outof")
    into = _resolve(into, "into")
    if time is None:
        from .lookups import _frame_lookup_transform

        t, r, timestamps = _frame_lookup_transform(outof, into)
    else:
        t, r, timestamps = _at_times(outof, into, time)
    if as_dataset:
        from ._xarray import transform_dataset

        return transform_dataset(t, r, outof.name, timestamps)
    if as_matrix:
        from .conversions import homogeneous_from_transform

        out = homogeneous_from_transform(t, r)
    elif as_transform:
        from .rigid_transform import Transform

        out = Transform(t, r)
    else:
        return (t, r, timestamps) if return_timestamps else (t, r)
    return (out, timestamps) if return_timestamps else out
