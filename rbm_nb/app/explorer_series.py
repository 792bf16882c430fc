"""The explorer's time series: gaze angles and yaw, head yaw rate, VOR.

Part of :mod:`rbm_nb.app.explorer` (which re-exports every name here): the
series notebook 06 plots and asks its questions of, computed from the frames
:func:`~rbm_nb.app.explorer_frames.register_head_eye_frames` registers.
"""

from __future__ import annotations

import numpy as np

from .._engine.time import epoch_seconds
from .._infra.time_index import dataarray_on
from ..core import frames as registry
from ..core import gaze
from ..core.lookups import lookup_angular_velocity
from ..core.quaternions import rotate_vectors
from . import explorer_yaw
from .explorer_frames import (
    EXAMPLE_FRAMES,
    EYES,
    GAZE_COLORS,
    MAX_EYE_GAP,
    MIN_CONFIDENCE,
    HeadEyeFrames,
)


def gaze_angles(
    eye,
    name: str | None = None,
    *,
    min_confidence: float = MIN_CONFIDENCE,
    max_angle: float | None = None,
    frames: HeadEyeFrames = EXAMPLE_FRAMES,
):
    """Azimuth (right) and elevation (up) of an eye's line of sight, in degrees.

    With ``name`` (``"left_eye"`` or ``"right_eye"``) and the explorer's
    frames registered, the angles are measured in the head's axes (x
    forward, y left, z up) by :mod:`rbm_nb.gaze`: samples below
    ``min_confidence``, beyond ``max_angle`` degrees from the scene camera's
    straight-ahead (see :data:`rbm_nb.gaze.OCULOMOTOR_RANGE`) and missing
    ones are NaN, so plots show them as gaps. The result is on the eye's
    own times (its time index is the dataset's, not a copy); pauses of the
    eye tracker longer than :data:`MAX_EYE_GAP` are named in
    ``attrs["max_gap"]``, which :class:`~rbm_nb.widgets.TimeSeries` draws
    as gaps. Without ``name`` they are computed from the dataset's
    orientations alone, in the eye tracker's image axes (x right, y down, z
    forward in the image; no masking).

    Returns
    -------
    xarray.DataArray, dims (time, angle)
    """
    import xarray as xr

    if name is not None and frames.eye(name) in registry.registry:
        confident = eye is not None and "confidence" in eye
        sight = gaze.directions(
            frames.eye(name),
            frames.head,
            confidence=eye.confidence if confident else None,
            min_confidence=min_confidence,
            max_angle=max_angle,
        )
        out = gaze.angles(sight, frames.head, forward="x", up="z")
        out.attrs = {"long_name": "Gaze angles", "units": "deg", "max_gap": MAX_EYE_GAP}
        return out

    eye = eye.dropna("time")
    sight = rotate_vectors(
        eye.orientation.values, np.array([0.0, 0.0, 1.0]), one_to_one=False
    )
    azimuth = np.degrees(np.arctan2(sight[:, 0], sight[:, 2]))
    elevation = np.degrees(np.arctan2(-sight[:, 1], np.hypot(sight[:, 0], sight[:, 2])))
    return xr.DataArray(
        np.column_stack([azimuth, elevation]),
        dims=("time", "angle"),
        coords={"time": eye.time, "angle": ["azimuth", "elevation"]},
        attrs={"long_name": "Gaze angles", "units": "deg"},
    )


def head_speed(head):
    """Norm of the head tracker's linear velocity, in m/s."""
    speed = np.sqrt((head.linear_velocity**2).sum("cartesian_axis"))
    speed.attrs = {"long_name": "Head speed", "units": "m/s"}
    return speed


def head_yaw_rate(*, world: str | None = None, frames: HeadEyeFrames = EXAMPLE_FRAMES):
    """Head angular velocity about its own vertical axis, deg/s, positive left.

    The z component of the angular velocity of ``head`` relative to
    ``world`` represented in the head's axes (x forward, y left, z up), so
    a turn to the left is positive, as the gaze yaw of
    :func:`gaze_yaw`. Register the frames first.
    """
    omega, times = lookup_angular_velocity(
        frames.head,
        world or frames.world,
        represent_in=frames.head,
        return_timestamps=True,
    )
    # one new array, the plotted one; on the frame's own times (the head
    # dataset's, which nobody can change): no copy of the time index
    return dataarray_on(
        np.degrees(omega[:, 2]),
        times,
        ("time",),
        attrs={"long_name": "Head yaw rate (+ left)", "units": "deg/s"},
        name="angular_velocity",
    )


def gaze_yaw(
    left_eye,
    right_eye,
    *,
    max_angle: float | None = None,
    frames: HeadEyeFrames = EXAMPLE_FRAMES,
):
    """Horizontal gaze angle of both eyes in the head's axes, deg, positive left.

    Dims (time, eye) with eyes ``"left eye"`` and ``"right eye"``; NaN where
    an eye has no trusted sample (see :func:`gaze_angles`). The two eyes
    share one clock in the example data; otherwise each keeps its own times
    and the other's column is NaN there.
    """
    labels = [name.replace("_", " ") for name in EYES]
    attrs = {
        "long_name": "Gaze yaw in head (+ left)",
        "units": "deg",
        "colors": [GAZE_COLORS[eye] for eye in EYES],
        "max_gap": MAX_EYE_GAP,
    }
    fast = explorer_yaw.yaw_columns(
        [left_eye, right_eye],
        [frames.eye(name) for name in EYES],
        frames.head,
        MIN_CONFIDENCE,
        max_angle,
    )
    if fast is not None:
        values, confidence = fast
        # on the confidence's time index, as gaze_angles' result (a shallow
        # copy shares it)
        template = confidence.drop_vars([c for c in confidence.coords if c != "time"])
        yaw = template.expand_dims(eye=len(EYES), axis=1).copy(deep=False, data=values)
        yaw = yaw.assign_coords(eye=labels)
        yaw.name, yaw.attrs = None, attrs
        return yaw
    return _yaw_by_angles(left_eye, right_eye, labels, attrs, max_angle, frames)


def _yaw_by_angles(left_eye, right_eye, labels, attrs, max_angle, frames):
    """:func:`gaze_yaw` through :func:`gaze_angles`, one eye after the other."""
    first = gaze_angles(left_eye, EYES[0], max_angle=max_angle, frames=frames)
    # the one (n, 2) array kept, on the first eye's time index (a shallow
    # copy shares it); each eye's column is written in place
    yaw = first.copy(deep=False, data=np.empty(first.shape)).rename(angle="eye")
    yaw = yaw.assign_coords(eye=labels)
    yaw.name, yaw.attrs = None, attrs
    np.negative(first.sel(angle="azimuth").values, out=yaw.values[:, 0])
    del first  # its angles: not kept
    second = gaze_angles(right_eye, EYES[1], max_angle=max_angle, frames=frames)
    if not second.indexes["time"].equals(yaw.indexes["time"]):
        return _outer_yaw(yaw, second, attrs)
    np.negative(second.sel(angle="azimuth").values, out=yaw.values[:, 1])
    return yaw


def _outer_yaw(yaw, right, attrs):
    """The eyes on two clocks: each keeps its times, NaN in the other's column."""
    import xarray as xr

    label = str(yaw["eye"].values[1])
    right = -right.sel(angle="azimuth", drop=True).expand_dims(eye=[label], axis=1)
    out = xr.concat([yaw.isel(eye=[0]), right], dim="eye", join="outer")
    out.attrs = attrs
    return out


def explorer_series(
    head,
    left_eye,
    right_eye,
    *,
    max_angle: float | None = None,
    frames: HeadEyeFrames = EXAMPLE_FRAMES,
) -> dict:
    """The explorer's time series, for the questions notebook 06 asks.

    ``"head yaw rate"`` (deg/s, in the head's axes), ``"gaze yaw"`` (deg,
    both eyes, in the head's axes) and ``"gaze yaw rate"`` (deg/s, both
    eyes, see :func:`rbm_nb.gaze.rates`); all positive to the left. The
    vestibulo-ocular reflex shows as the eyes' rate opposite in sign to the
    head's; saccades as spikes of several hundred deg/s in the eyes' rate.
    Register the frames first (:func:`register_head_eye_frames`).
    ``max_angle`` (degrees) flags impossible gaze, default
    :data:`rbm_nb.gaze.OCULOMOTOR_RANGE`. The eye datasets give the
    confidence of each sample (None: the frames' samples are all trusted);
    ``frames`` names the registered frames.
    """
    if max_angle is None:
        max_angle = gaze.OCULOMOTOR_RANGE
    yaw = gaze_yaw(left_eye, right_eye, max_angle=max_angle, frames=frames)
    rate = gaze.rates(yaw)
    rate.attrs["colors"] = yaw.attrs["colors"]
    rate.attrs["max_gap"] = yaw.attrs["max_gap"]
    return {
        "head yaw rate": head_yaw_rate(frames=frames),
        "gaze yaw": yaw,
        "gaze yaw rate": rate,
    }


def vor_gain(series: dict, *, max_rate: float = 60.0) -> dict:
    """Least-squares gain of each eye's yaw rate against the head's.

    Slow phases only: samples whose eye rate is above ``max_rate`` deg/s
    (saccades) are left out. The vestibulo-ocular reflex gives a negative
    gain, about -1 for a far target; a positive one means the eyes turn
    with the head, which no healthy eye does while fixating.

    Returns
    -------
    dict
        Eye name -> gain.
    """
    head = series["head yaw rate"]
    eyes = series["gaze yaw rate"]
    t_head = _seconds(head["time"].values)
    t_eye = _seconds(eyes["time"].values)
    head_at_eye = np.interp(t_eye, t_head, np.nan_to_num(head.values))
    out = {}
    for eye in eyes["eye"].values:
        rate = eyes.sel(eye=eye).values
        ok = np.isfinite(rate) & (np.abs(rate) < max_rate)
        h = head_at_eye[ok]
        out[str(eye)] = float(np.dot(h, rate[ok]) / np.dot(h, h))
    return out


def guided_instants(series: dict, *, window: float = 2.0) -> dict:
    """Instants worth a look in the explorer's series, found in the data.

    ``"vor"``: the middle of the ``window``-second stretch where the head
    turns fastest (mean absolute yaw rate) while both eyes have samples and
    counter-rotate (a negative :func:`vor_gain` there). ``"saccade"``: the
    fastest gaze shift both eyes make together (over 200 deg/s, same sign
    within 20 ms: a real saccade is conjugate, a tracker glitch is in one
    eye). Times are the series' own (datetime64 for the example data).
    """
    head = series["head yaw rate"]
    eyes = series["gaze yaw rate"]
    t_head, t_eye = _seconds(head["time"].values), _seconds(eyes["time"].values)
    rates = eyes.transpose("time", "eye").values
    head_at_eye = np.interp(t_eye, t_head, np.nan_to_num(head.values))
    slow = np.isfinite(rates).all(axis=1) & (np.abs(rates) < 60.0).all(axis=1)
    best, best_score = None, -np.inf
    starts = np.arange(t_eye[0], t_eye[-1] - window, window / 4)
    lo = np.searchsorted(t_eye, starts)
    hi = np.searchsorted(t_eye, starts + window)
    for a, b in zip(lo, hi, strict=True):
        ok = slow[a:b]
        if ok.sum() < 20:
            continue
        h = head_at_eye[a:b][ok]
        gain = np.dot(h, rates[a:b][ok].mean(axis=1)) / max(np.dot(h, h), 1e-12)
        score = np.abs(h).mean()
        if gain < -0.3 and score > best_score:
            # the row nearest the middle where both eyes have a sample
            rows = a + np.flatnonzero(ok)
            best, best_score = rows[np.argmin(np.abs(rows - (a + b) // 2))], score
    both_fast = np.isfinite(rates).all(axis=1) & (np.abs(rates) > 200.0).all(axis=1)
    both_fast &= np.sign(rates[:, 0]) == np.sign(rates[:, 1])
    speed = np.where(both_fast, np.abs(rates).min(axis=1), -np.inf)
    times = eyes["time"].values
    out = {}
    if best is not None:
        out["vor"] = times[best]
    if np.isfinite(speed).any():
        out["saccade"] = times[int(np.argmax(speed))]
    return out


def _seconds(times) -> np.ndarray:
    # float data seconds by the one time rule (epoch seconds for datetime64)
    return np.asarray(epoch_seconds(np.asarray(times)), dtype=float)
