"""A synthetic head/eye recording with the schema of the real example data.

It stands in for ``head.nc``, ``left_eye.nc`` and ``right_eye.nc`` when those
cannot be downloaded: same dimensions, variables and attributes, physically
plausible content (see :func:`synthetic_head_eye`), generated in about a
second and identical for identical arguments.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..io._schema import motion_dataset
from ._eye_tracker import (
    both_lost_rows,
    draw_dropouts,
    eye_clock,
    eyeball_centres,
    mapper_confidence,
    missing_rows,
    remove_dropouts,
    tracking_error,
)
from ._gaze import (
    EYE_CENTERS,
    SCENE_CAMERA_ROTATION,
    SCENE_CAMERA_TRANSLATION,
    draw_blinks,
    eye_orientation,
    lid_closure,
    plan_fixations,
)
from ._walking import WalkParams, simulate_head

SOURCE = "synthetic (rbm_nb)"
DEFAULT_START = "2020-02-02T00:27:14.300365210"
# the eye clock starts and stops within a few ms of the head tracker's
_EYE_LEAD_IN = (0.5e-3, 2e-3)
_EYE_LEAD_OUT = 2e-3
_EYE_NOISE = np.deg2rad(0.03)


class HeadEyeRecording(NamedTuple):
    """The three datasets of a head/eye recording."""

    head: object  # xarray.Dataset
    left_eye: object
    right_eye: object


def synthetic_head_eye(
    duration: float = 330.0,
    seed: int = 0,
    *,
    head_rate: float = 200.0,
    eye_rate: float = 200.0,
    speed: float = 1.45,
    laps: int = 2,
    start: str | np.datetime64 = DEFAULT_START,
) -> HeadEyeRecording:
    """Simulate a walk of ``laps`` laps around a building with head and eye tracking.

    The default is a 5.5-minute recording like the real example data, with its
    schema (variables, order, dtypes, coordinates, attributes) and its flaws:
    a head tracker (RealSense T265 conventions) at 200 Hz, and a binocular
    eye tracker (Pupil Core conventions) whose two eyes share one irregular
    clock near 400 Hz, with NaN rows (blinks, lost pupils, monocular rows),
    ~30 % of rows below confidence 0.6 and a few dropouts longer than 0.1 s.

    Parameters
    ----------
    duration : float, default 330.0
        Length of the head recording in seconds (at least 15).
    seed : int, default 0
        Seed of every random choice; equal arguments give equal datasets.
    head_rate : float, default 200.0
        Sampling rate of the head tracker in Hz.
    eye_rate : float, default 200.0
        Frame rate of each eye camera in Hz. Both cameras' frames make up the
        eyes' shared clock (frames close in time become one row): about
        1.7 * eye_rate rows per second, median interval 1 / (2 * eye_rate).
    speed : float, default 1.45
        Walking speed in m/s; the walk starts and ends with 2 s of standing.
    laps : int, default 2
        Laps around the building, which is sized to fit the walk (aspect 3:2).
    start : str or numpy.datetime64
        Time of the first head sample.

    Returns
    -------
    HeadEyeRecording
        Named tuple of ``head``, ``left_eye`` and ``right_eye``
        :class:`xarray.Dataset`, each with dims ``time`` (datetime64[ns]),
        ``cartesian_axis`` (x, y, z) and ``quaternion_axis`` (w, x, y, z).

        ``head``: ``position`` (m) and ``orientation`` of the head tracker wrt
        a world frame at its starting pose (x right, y up, z backwards, so
        walking forward is -z in the head frame); ``linear_velocity`` (m/s)
        and ``angular_velocity`` (rad/s) of the head wrt world, represented in
        world like the T265 reports them and equal to the derivatives of
        position and orientation; ``confidence``, the T265 tracker confidence
        level (0 failed, 1 low, 2 medium, 3 high).

        ``left_eye`` / ``right_eye`` (one shared time axis): ``confidence``,
        the binocular gaze mapper confidence in [0, 1] (the same for both
        eyes; low during blinks and often below 0.6); ``position`` (m), the
        eyeball centre, drifting by millimetres; ``orientation``, the eye wrt
        the scene camera (camera convention x right, y down, z forward; gaze
        is the eye frame's z axis, torsion by Listing's law), noisier the lower
        the confidence. Rows without data are NaN: both variables during
        blinks and in monocular rows of the other eye, only ``orientation``
        where the pupil was lost. The scene camera's pose in the head frame is
        in the attrs ``scene_camera_translation`` and ``scene_camera_rotation``
        (w, x, y, z); the real files have no dataset attributes.

    Raises
    ------
    ValueError
        If a duration, rate, speed or lap count is not a positive finite
        number (duration at least 15 s).

    Examples
    --------
    >>> rec = synthetic_head_eye(duration=20.0)
    >>> rec.head.sizes["time"], rec.head.attrs["source"]
    (4000, 'synthetic (rbm_nb)')
    """
    _check_positive(
        duration=duration, head_rate=head_rate, eye_rate=eye_rate, speed=speed
    )
    if duration < 15.0:
        raise ValueError(
            f"duration must be at least 15 s (standing, walking, standing), got {duration}"
        )
    if int(laps) != laps or laps < 1:
        raise ValueError(f"laps must be a positive integer, got {laps!r}")
    # np.array, unlike np.datetime64, types a str-or-datetime64 argument
    origin = np.array(start, dtype="datetime64[ns]")[()]
    rng = np.random.default_rng(seed)

    head_ns = _grid_ns(0.0, duration, head_rate, rng, jitter=0.0)
    clock = eye_clock(
        rng, rng.uniform(*_EYE_LEAD_IN), duration - _EYE_LEAD_OUT, float(eye_rate)
    )
    dropouts = draw_dropouts(rng, clock.t[0], clock.t[-1])
    clock = remove_dropouts(clock, dropouts)
    eye_ns = np.round(clock.t * 1e9).astype(np.int64)
    unique = np.r_[True, np.diff(eye_ns) > 0]
    clock = clock._replace(
        t=clock.t[unique], left=clock.left[unique], right=clock.right[unique]
    )
    eye_ns = eye_ns[unique]
    grid_ns = np.union1d(head_ns, eye_ns)
    params = WalkParams(speed=float(speed), laps=int(laps))
    head = simulate_head(grid_ns * 1e-9, float(duration), rng, params)

    eye_start = eye_ns[0] * 1e-9
    fixations = plan_fixations(rng, head, eye_start, duration)
    blinks = draw_blinks(rng, eye_start, duration)

    attrs = {
        "source": SOURCE,
        "seed": int(seed),
        "duration": float(duration),
        "walking_speed": float(speed),
        "laps": int(laps),
        "lap_length": float(head.lap_length),
    }
    i_head = np.searchsorted(grid_ns, head_ns)
    head_ds = _head_dataset(
        origin + head_ns.astype("timedelta64[ns]"), head, i_head, rng, attrs
    )
    index = np.searchsorted(grid_ns, eye_ns)
    t_eye = grid_ns[index] * 1e-9
    closed = lid_closure(t_eye, blinks)
    confidence = mapper_confidence(rng, t_eye, closed)
    eye_time = origin + eye_ns.astype("timedelta64[ns]")
    both_lost = both_lost_rows(rng, t_eye.size)
    missing = {
        eye: missing_rows(rng, clock, eye, closed, both_lost) for eye in EYE_CENTERS
    }
    # the binocular mapper reports 0 when it lost either pupil
    for no_orientation, no_position in missing.values():
        confidence[no_orientation & ~no_position] = 0.0
    eyes = {}
    for eye in EYE_CENTERS:
        error = tracking_error(rng, confidence, _EYE_NOISE)
        orientation = eye_orientation(rng, head, index, eye, fixations, error)
        position = eyeball_centres(rng, t_eye, EYE_CENTERS[eye])
        no_orientation, no_position = missing[eye]
        orientation[no_orientation] = np.nan
        position[no_position] = np.nan
        eyes[eye] = _eye_dataset(
            eye_time, eye, orientation, position, confidence.copy(), attrs
        )
    return HeadEyeRecording(head_ds, eyes["left_eye"], eyes["right_eye"])


def _check_positive(**values) -> None:
    for name, value in values.items():
        if not (
            isinstance(value, (int, float, np.number))
            and np.isfinite(value)
            and value > 0
        ):
            raise ValueError(f"{name} must be a positive finite number, got {value!r}")


def _grid_ns(first: float, last: float, rate: float, rng, jitter: float) -> np.ndarray:
    """Sample times in ns from ``first`` to before ``last`` (s); jitter in periods."""
    n = int(np.floor((last - first) * rate))
    k = np.arange(n, dtype=float)
    if jitter:
        k += rng.uniform(-jitter, jitter, n)
    return np.round((first + k / rate) * 1e9).astype(np.int64)


def _tracker_confidence(rng, t: np.ndarray) -> np.ndarray:
    """T265 confidence levels 0-3: low while starting up, a few medium stretches."""
    level = np.full(t.shape, 3.0)
    level[t < 1.0] = 2.0
    level[t < 0.25] = 1.0
    for onset in rng.uniform(0.1 * t[-1], 0.9 * t[-1], 3):
        level[(t >= onset) & (t < onset + rng.uniform(0.5, 1.5))] = 2.0
    return level


def _head_dataset(time, head, index, rng, attrs):
    variables = {
        "position": head.position[index],
        "linear_velocity": head.linear_velocity[index],
        "angular_velocity": head.angular_velocity[index],
        "confidence": _tracker_confidence(rng, head.t[index]),
        "orientation": head.orientation[index],
    }
    description = (
        "Synthetic head tracker (RealSense T265 conventions): pose of the head wrt "
        "a world frame at its starting pose (x right, y up, z backwards); "
        "velocities are wrt world and represented in world."
    )
    # the real head.nc: no attributes on confidence
    return motion_dataset(
        time, variables, {**attrs, "description": description}, {"confidence": {}}
    )


def _eye_dataset(time, eye, orientation, position, confidence, attrs):
    # variable order and attributes of the real left_eye.nc / right_eye.nc
    variables = {
        "confidence": confidence,
        "position": position,
        "orientation": orientation,
    }
    description = (
        f"Synthetic {eye.replace('_', ' ')} tracker (Pupil Core conventions): pose of "
        "the eye wrt the scene camera (x right, y down, z forward; gaze along the "
        "eye's z axis)."
    )
    attrs = {
        **attrs,
        "description": description,
        "scene_camera_translation": SCENE_CAMERA_TRANSLATION.copy(),
        "scene_camera_rotation": SCENE_CAMERA_ROTATION.copy(),
    }
    variable_attrs = {
        "confidence": {"long_name": "3d gaze mapper confidence"},
        "position": {},
        "orientation": {},
    }
    ds = motion_dataset(time, variables, attrs, variable_attrs)
    ds["quaternion_axis"].attrs = {}
    return ds
