"""The gaze calls' one door call each: an eye's samples, directions, rates.

:func:`sight` is what :func:`rbm_nb.gaze.directions` calls,
:func:`angle_arguments` what :func:`rbm_nb.gaze.angles` calls and
:func:`rate_arguments` what :func:`rbm_nb.gaze.rates` calls. Each checks its
call once (frames resolved by the caller's ``resolve``, options, the
confidence against the eye's samples, the directions' layout, the times'
order) with the messages the gaze functions have always given, and hands
back a frozen value holding what the facade computes on: nothing is checked
again on the way to the engine.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from .._engine import time as _time
from .coverage import chain_samples
from .unpack import is_dataarray
from .xarray import check_directions

__all__ = [
    "Sight",
    "sight",
    "AngleArguments",
    "angle_arguments",
    "RateArguments",
    "rate_arguments",
]

_AXES = {"x": 0, "y": 1, "z": 2}


class Sight(NamedTuple):
    """A checked ``gaze.directions`` call.

    ``rotation`` (n, 4) is the eye's orientation at ``times`` (NaN where it
    has no sample; read, never written: it may be the frame's own array),
    ``valid`` the samples to compute (a sample of the eye, confident enough).
    ``track`` holds the valid samples' times when the eye's parent is not
    ``into`` (the lines of sight are carried there at those times), else
    None. ``like`` is the confidence DataArray whose time index the result
    may share.
    """

    eye: Any
    into: Any
    times: np.ndarray
    rotation: np.ndarray
    valid: np.ndarray
    track: Any
    max_gap: float | None
    max_angle: float | None
    like: Any


def sight(
    resolve: Callable,
    eye_frame: Any,
    into: Any,
    confidence: Any,
    min_confidence: Any,
    max_gap: Any,
    max_angle: Any,
) -> Sight:
    """Everything ``gaze.directions`` checks, once."""
    eye = resolve(eye_frame, "eye_frame")
    target = resolve(into, "into")
    if eye.parent is None:
        raise ValueError(
            f"eye_frame {eye.name!r} is a root frame; it has no orientation to look along"
        )
    min_confidence = finite_number(min_confidence, "min_confidence")
    if max_gap is not None and finite_number(max_gap, "max_gap") <= 0:
        raise ValueError(f"max_gap must be positive (seconds), got {max_gap!r}")
    if max_angle is not None and not 0 < finite_number(max_angle, "max_angle") <= 180:
        raise ValueError(f"max_angle must be in (0, 180] degrees, got {max_angle!r}")
    times, rotation = _eye_samples(eye, confidence)
    valid = np.isfinite(rotation).all(axis=1)
    if confidence is not None:
        valid &= _confidence_values(confidence, times, eye) >= min_confidence
    track = None
    if eye.parent is not target and valid.any():
        track = _valid_track(times, valid)
        # the eye's samples and the frames to ``into`` must share time
        chain_samples(eye.parent, target, [track])
    like = confidence if is_dataarray(confidence) else None
    return Sight(
        eye,
        target,
        times,
        rotation,
        valid,
        track,
        None if max_gap is None else float(max_gap),
        None if max_angle is None else float(max_angle),
        like,
    )


class AngleArguments(NamedTuple):
    """A checked ``gaze.angles`` call: the directions as (n, 3) ``values``
    along ``times``, the frames, and the reference's signed axes. ``track``
    holds the valid rows' times when the directions must first be carried
    into ``reference`` (else None)."""

    directions: Any
    source: Any
    reference: Any
    times: np.ndarray
    values: np.ndarray
    valid: np.ndarray
    track: Any
    forward: tuple[int, float]
    up: tuple[int, float]


def angle_arguments(
    resolve: Callable, directions: Any, reference: Any, forward: Any, up: Any
) -> AngleArguments:
    """Everything ``gaze.angles`` checks, once."""
    check_directions(directions)
    f_axis, f_sign = _signed_axis(forward, "forward")
    u_axis, u_sign = _signed_axis(up, "up")
    if f_axis == u_axis:
        raise ValueError(
            f"forward ({forward!r}) and up ({up!r}) must be different axes"
        )
    ref = resolve(reference, "reference")
    source = resolve(directions.attrs["representation_frame"], "directions' frame")
    times = directions["time"].values
    values = np.asarray(directions.transpose("time", "cartesian_axis").values, float)
    valid = np.isfinite(values).all(axis=1)
    track = _valid_track(times, valid) if source is not ref and valid.any() else None
    if track is not None:
        chain_samples(source, ref, [track])
    return AngleArguments(
        directions, source, ref, times, values, valid, track,
        (f_axis, f_sign), (u_axis, u_sign),
    )  # fmt: skip


class RateArguments(NamedTuple):
    """A checked ``gaze.rates`` call: the angles with ``time`` first
    (``arr``), their ``values`` as (n, k) floats, ``t`` the seconds from the
    first time, and the ``window`` in seconds."""

    arr: Any
    values: np.ndarray
    t: np.ndarray
    window: float


def rate_arguments(angles: Any, window: Any) -> RateArguments:
    """Everything ``gaze.rates`` checks, once.

    Times out of order are refused naming the first such index: the
    windowed slopes would be wrong without a word.
    """
    if not is_dataarray(angles) or "time" not in angles.dims:
        raise ValueError("angles must be a DataArray with a 'time' dimension")
    if finite_number(window, "window") <= 0:
        raise ValueError(f"window must be positive (seconds), got {window!r}")
    arr = angles.transpose("time", ...)
    stamps = arr["time"].values
    keys = _time.sort_keys(stamps, "angles time")
    back = np.flatnonzero(np.diff(keys) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise ValueError(
            f"angles time must be non-decreasing: angles time[{i}] = {stamps[i]} "
            f"is earlier than angles time[{i - 1}] = {stamps[i - 1]}"
        )
    scale = 1e9 if np.issubdtype(arr["time"].dtype, np.datetime64) else 1.0
    # from the first time: epoch seconds as floats would round to 0.2 us
    t = (keys - keys[0]) / scale if len(keys) else keys / scale
    values = np.asarray(arr.values, dtype=float).reshape(len(t), -1)
    return RateArguments(arr, values, t, float(window))


# -- helpers ----------------------------------------------------------------


def finite_number(value: Any, name: str) -> float:
    """``value`` as a float, refused by ``name`` unless a finite number."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return float(value)


def _valid_track(times: np.ndarray, valid: np.ndarray) -> Any:
    # the rows carried to another frame: checked as the transforms check
    # their timestamps (the same message)
    rows = times[valid]
    return _time.as_track(rows, "timestamps", length=len(rows), copy=False)


def _eye_samples(eye: Any, confidence: Any) -> tuple[np.ndarray, np.ndarray]:
    """Times of the result and the eye's rotation (n, 4) at them (NaN if missing).

    The rotation is read only: on the eye's own times it is the frame's
    array, not a copy.
    """
    own = eye.timestamps
    if is_dataarray(confidence):
        if "time" not in confidence.dims or confidence.ndim != 1:
            raise ValueError(
                f"confidence must be a 1-d DataArray along 'time', got dims {confidence.dims}"
            )
        if "time" not in confidence.coords:
            raise ValueError(
                "confidence has a 'time' dimension but no 'time' coordinate"
            )
        times = np.asarray(confidence["time"].values)
    elif own is not None:
        times = np.asarray(own)
    else:
        raise ValueError(
            f"eye_frame {eye.name!r} is static; pass confidence as a DataArray with "
            f"a 'time' coordinate to give the sample times"
        )
    if own is None:
        return times, np.broadcast_to(eye.rotation, (len(times), 4))
    rotation = np.asarray(eye.rotation, dtype=float)
    if times is own or (len(times) == len(own) and np.array_equal(times, own)):
        return times, rotation
    index = _match(np.asarray(own), times, eye.name)
    out = np.full((len(times), 4), np.nan)
    found = index >= 0
    out[found] = rotation[index[found]]
    return times, out


def _match(own: Any, times: Any, name: str) -> np.ndarray:
    """Index into ``own`` of each of ``times`` (exact sample), -1 where none."""
    own, times = np.asarray(own), np.asarray(times)
    is_datetime = np.issubdtype(own.dtype, np.datetime64)
    if is_datetime != np.issubdtype(times.dtype, np.datetime64):
        raise ValueError(
            f"confidence times ({times.dtype}) and the timestamps of eye_frame "
            f"{name!r} ({own.dtype}) must both be datetime64 or both numeric"
        )
    a = _time.sort_keys(own, f"timestamps of eye_frame {name!r}")
    b = _time.sort_keys(times, "confidence times")
    if len(a) == 0:
        return np.full(len(b), -1)
    # datetime64 keys are exact ns; numeric ones may have been through float
    tol = 0 if is_datetime else 1e-9 * max(1.0, float(np.max(np.abs(a))))
    j = np.clip(np.searchsorted(a, b), 0, len(a) - 1)
    left = np.maximum(j - 1, 0)
    best = np.where(np.abs(a[left] - b) <= np.abs(a[j] - b), left, j)
    return np.where(np.abs(a[best] - b) <= tol, best, -1)


def _confidence_values(confidence: Any, times: np.ndarray, eye: Any) -> np.ndarray:
    if is_dataarray(confidence):
        values = np.asarray(confidence.values, dtype=float)
    else:
        try:
            values = np.asarray(confidence, dtype=float)
        except (TypeError, ValueError):
            raise ValueError("confidence must be an array of numbers") from None
        if values.shape != (len(times),):
            raise ValueError(
                f"confidence must have shape ({len(times)},) like the timestamps of "
                f"eye_frame {eye.name!r}, got {values.shape}"
            )
    # NaN confidence compares False: such samples are dropped
    return np.where(np.isnan(values), -np.inf, values)


def _signed_axis(spec: Any, name: str) -> tuple[int, float]:
    if not isinstance(spec, str):
        raise ValueError(f"{name} must be an axis like 'z' or '-y', got {spec!r}")
    sign = -1.0 if spec.startswith("-") else 1.0
    letter = spec.lstrip("+-")
    if letter not in _AXES or len(spec) - len(letter) > 1:
        raise ValueError(
            f"{name} must be one of x, y, z with an optional sign, got {spec!r}"
        )
    return _AXES[letter], sign
