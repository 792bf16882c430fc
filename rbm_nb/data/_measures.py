"""Physical measurements on a head/eye recording (synthetic or real).

Used by the tests and ``benchmarks/synthetic_checks.py`` to show that the
synthetic recording behaves like a person walking: walking speed, head bob,
saccades on the main sequence, a VOR that keeps gaze still in the world,
blinks. Everything is measured from the datasets alone, the way one would
analyse a real recording, never from the generator's internals.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._engine.time import epoch_seconds
from .._kernels.quaternion import qconj, qmul, rotate_vectors
from ..core.estimators import estimate_angular_velocity, estimate_linear_velocity
from ..core.frames import ReferenceFrame
from ..core.transforms import transform_linear_velocity

if TYPE_CHECKING:
    import xarray as xr

SACCADE_THRESHOLD = np.deg2rad(100.0)  # gaze-in-world speed above this is a saccade
FIXATION_THRESHOLD = np.deg2rad(20.0)  # ... and below this, gaze is holding still
HEAD_TURN_THRESHOLD = np.deg2rad(30.0)  # head speed that counts as a head turn


def _seconds(time, origin) -> np.ndarray:
    """datetime64 values as float seconds since ``origin``."""
    return epoch_seconds(np.asarray(time) - origin, name="time")


def walking_mask(head: xr.Dataset, threshold: float = 0.5) -> np.ndarray:
    """Samples where the head moves faster than ``threshold`` m/s horizontally."""
    v = head.linear_velocity.values
    return np.hypot(v[:, 0], v[:, 2]) > threshold


def mean_walking_speed(head: xr.Dataset) -> float:
    """Mean horizontal speed (m/s) while walking."""
    v = head.linear_velocity.values[walking_mask(head)]
    return float(np.hypot(v[:, 0], v[:, 2]).mean())


def head_frame_velocity(head: xr.Dataset) -> np.ndarray:
    """Mean head velocity (m/s) represented in the head frame, through rbm's frames."""
    world = ReferenceFrame("world")
    head_frame = ReferenceFrame.from_dataset(
        head, "position", "orientation", "time", parent=world, name="head"
    )
    v = transform_linear_velocity(
        head.linear_velocity, outof=world, into=head_frame, what="representation_frame"
    )
    return np.asarray(v).mean(axis=0)


def bob(head: xr.Dataset) -> tuple[float, float]:
    """Dominant frequency (Hz) and RMS amplitude (m) of vertical head motion while walking."""
    walking = walking_mask(head)
    idx = np.flatnonzero(walking)
    segment = slice(idx[0], idx[-1] + 1)
    t = _seconds(head.time.values, head.time.values[0])[segment]
    y = head.position.values[segment, 1]
    y = y - np.polyval(np.polyfit(t, y, 3), t)
    dt = np.median(np.diff(t))
    spectrum = np.abs(np.fft.rfft(y * np.hanning(y.size)))
    freq = np.fft.rfftfreq(y.size, dt)
    band = (freq > 0.5) & (freq < 5.0)
    return float(freq[band][np.argmax(spectrum[band])]), float(y.std())


def _interp_rows(t: np.ndarray, t_in: np.ndarray, values: np.ndarray) -> np.ndarray:
    return np.stack(
        [np.interp(t, t_in, values[:, k]) for k in range(values.shape[1])], axis=1
    )


def usable_eye_rows(eye: xr.Dataset, min_confidence: float = 0.6) -> np.ndarray:
    """Rows with an orientation and a confidence of at least ``min_confidence``."""
    finite = np.isfinite(eye.orientation.values).all(axis=1)
    return finite & (eye.confidence.values >= min_confidence)


def _gaze(eye: xr.Dataset, head: xr.Dataset):
    """Eye times (s), gaze in the head frame and in world, head orientation there.

    Only usable rows (:func:`usable_eye_rows`) are kept: missing and
    low-confidence samples would be read as eye movements.
    """
    eye = eye.isel(time=usable_eye_rows(eye))
    origin = head.time.values[0]
    t = _seconds(eye.time.values, origin)
    t_head = _seconds(head.time.values, origin)
    q = head.orientation.values.copy()
    # same hemisphere for neighbours, so that componentwise interpolation is a blend
    flip = np.cumsum(np.r_[0, np.einsum("ij,ij->i", q[1:], q[:-1]) < 0]) % 2 == 1
    q[flip] *= -1
    q_head = _interp_rows(t, t_head, q)
    q_head /= np.linalg.norm(q_head, axis=1, keepdims=True)
    q_cam = np.asarray(eye.attrs["scene_camera_rotation"], dtype=float)[None, :]
    z = np.array([[0.0, 0.0, 1.0]])
    in_head = rotate_vectors(
        qmul(q_cam, np.ascontiguousarray(eye.orientation.values)), z
    )
    in_world = rotate_vectors(q_head, in_head)
    return t, in_head, in_world, q_head


def _angular_rate(t: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Angular velocity (n, 3) of unit directions d over t: d x dd/dt."""
    return np.cross(d, np.gradient(d, t, axis=0))


def saccades(eye: xr.Dataset, head: xr.Dataset) -> dict:
    """Saccades found as gaze-in-world speed above 100 deg/s: count, rate, peaks."""
    t, _, in_world, _ = _gaze(eye, head)
    speed = np.linalg.norm(_angular_rate(t, in_world), axis=1)
    fast = speed > SACCADE_THRESHOLD
    edges = np.flatnonzero(np.diff(fast.astype(np.int8)))
    starts, ends = edges[::2] + 1, edges[1::2] + 1
    if fast[0]:
        starts = np.r_[0, starts]
    n = min(starts.size, ends.size)
    starts, ends = starts[:n], ends[:n]
    peaks = np.array([speed[a:b].max() for a, b in zip(starts, ends, strict=True)])
    amplitudes = np.array(
        [
            np.arccos(
                np.clip(
                    np.dot(in_world[max(a - 3, 0)], in_world[min(b + 3, t.size - 1)]),
                    -1,
                    1,
                )
            )
            for a, b in zip(starts, ends, strict=True)
        ]
    )
    return {
        "count": int(n),
        "rate": n / (t[-1] - t[0]),
        "peak_median": float(np.rad2deg(np.median(peaks))),
        "peak_p95": float(np.rad2deg(np.percentile(peaks, 95))),
        "peak_max": float(np.rad2deg(peaks.max())),
        "amplitude_median": float(np.rad2deg(np.median(amplitudes))),
        # main sequence: bigger saccades are faster
        "peak_amplitude_correlation": float(np.corrcoef(amplitudes, peaks)[0, 1]),
    }


def vor_gain(eye: xr.Dataset, head: xr.Dataset) -> float:
    """Eye-in-head against head rotation during fixations while the head turns.

    Only the head rotation about axes perpendicular to the gaze can be
    compensated by turning the gaze, so that is what the gain compares:
    ``-<w_eye, w_head_perp> / <w_head_perp, w_head_perp>`` (1 = perfect).
    """
    t, in_head, in_world, q_head = _gaze(eye, head)
    w_eye = _angular_rate(t, in_head)
    # head angular velocity in the head frame, at the eye's timestamps
    t_head = _seconds(head.time.values, head.time.values[0])
    w_world = _interp_rows(t, t_head, head.angular_velocity.values)
    w_head = rotate_vectors(qconj(q_head), w_world)
    w_head_perp = w_head - np.einsum("ij,ij->i", w_head, in_head)[:, None] * in_head
    gaze_speed = np.linalg.norm(_angular_rate(t, in_world), axis=1)
    use = (gaze_speed < FIXATION_THRESHOLD) & (
        np.linalg.norm(w_head_perp, axis=1) > HEAD_TURN_THRESHOLD
    )
    a, b = w_eye[use], w_head_perp[use]
    return float(-np.sum(a * b) / np.sum(b * b))


def blink_fraction(eye: xr.Dataset, threshold: float = 0.1) -> float:
    """Fraction of samples with (nearly) closed lids: no data and confidence below ``threshold``."""
    missing = ~np.isfinite(eye.position.values).all(axis=1)
    return float(np.mean(missing & (eye.confidence.values < threshold)))


def tracker_quality(eye: xr.Dataset) -> dict:
    """Rates of the tracker's flaws: NaN rows, low confidence, dropouts."""
    missing = ~np.isfinite(eye.orientation.values).all(axis=1)
    confidence = eye.confidence.values
    dt = np.diff(_seconds(eye.time.values, eye.time.values[0]))
    return {
        "rows": int(missing.size),
        "rows_per_second": float(missing.size / (dt.sum() or np.nan)),
        "median_interval": float(np.median(dt)),
        "nan_rows": int(missing.sum()),
        "low_confidence": float(np.mean(confidence[~missing] < 0.6)),
        "gaps_over_0.1s": int(np.sum(dt > 0.1)),
        "largest_gap": float(dt.max()),
        "position_std": np.nanstd(eye.position.values, axis=0),
    }


def estimator_consistency(head: xr.Dataset) -> tuple[float, float]:
    """RMS difference between the stored velocities and rbm's estimates from the poses.

    The angular estimate (head frame) is rotated into world, where the
    dataset represents it. Returns (linear m/s, angular rad/s).
    """
    v = estimate_linear_velocity(head.position, dim="cartesian_axis", timestamps="time")
    w_body = estimate_angular_velocity(
        head.orientation, dim="quaternion_axis", timestamps="time"
    )
    w = rotate_vectors(
        np.ascontiguousarray(head.orientation.values),
        np.ascontiguousarray(np.asarray(w_body)),
    )
    dv = np.asarray(v) - head.linear_velocity.values
    dw = w - head.angular_velocity.values
    rms = lambda d: float(np.sqrt(np.mean(np.sum(d * d, axis=1))))  # noqa: E731
    return rms(dv), rms(dw)
