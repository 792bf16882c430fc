"""Eye movements of the synthetic recording: fixations, saccades, VOR, blinks.

The eyes look at points in the world. While a point is fixated, each eye's
gaze direction follows it as the head walks, bobs and turns, which is the
vestibulo-ocular reflex (eye-in-head counter-rotation) without a gain to
tune. Gaze shifts are saccades whose peak velocity follows the main sequence,
with a minimum-jerk time course. Before every head scan the eyes jump to the
place the head is about to turn to, as people do.

Eye frames follow the scene camera's convention (OpenCV: x right, y down,
z forward); an eye's orientation is the shortest-arc rotation taking the
camera's z axis onto its gaze direction, so torsion obeys Listing's law.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._kernels.quaternion import qconj, rotate_vectors
from ._profiles import bump, smootherstep
from ._walking import HeadMotion

# scene camera (x right, y down, z forward in its image) in the head tracker's
# frame (x right, y up, z back): the calibration of the real head/eye
# recording, whose quaternion is in (x, y, z, w) order (see
# rbm_nb.explorer.SCENE_CAM_ROTATION): turned 180 deg about the tracker's y
# axis, so the camera looks forward with its image upside down (image x to
# the wearer's left, image y up). One tree serves real and synthetic data.
SCENE_CAMERA_TRANSLATION = np.array([24.5e-3, -29e-3, 0.0])
SCENE_CAMERA_ROTATION = np.array([3.977e-06, -0.00125, -1.0, 6.3463e-05])
SCENE_CAMERA_ROTATION = SCENE_CAMERA_ROTATION / np.linalg.norm(SCENE_CAMERA_ROTATION)
# eyeball centres in the scene camera frame: the left eye on the wearer's
# left (image +x), both below the camera (image -y) and behind it
EYE_CENTERS = {
    "left_eye": np.array([0.031, -0.03, -0.02]),
    "right_eye": np.array([-0.031, -0.03, -0.02]),
}
GROUND = -1.65  # m below the head's starting height
MAX_ECCENTRICITY = np.deg2rad(35.0)  # beyond this people turn the head instead
_MIN_FIXATION = 0.08  # s of steady gaze between two saccades
# the eyes lead head turns by this much at most
_MAX_SCAN_ECCENTRICITY = np.deg2rad(55.0)


@dataclass(frozen=True)
class Fixation:
    """A fixated world point, reached by a saccade starting at ``onset``."""

    onset: float
    target: np.ndarray  # (3,) world, m
    saccade_duration: float
    amplitude: float  # rad, cyclopean gaze shift at onset


def main_sequence_peak_velocity(amplitude: float) -> float:
    """Peak angular speed (rad/s) of a saccade of ``amplitude`` rad."""
    return float(np.deg2rad(520.0) * (1.0 - np.exp(-amplitude / np.deg2rad(14.0))))


class _HeadLookup:
    """Head pose at arbitrary times (nearest grid sample) for planning."""

    def __init__(self, head: HeadMotion):
        self.head = head

    def index(self, t: float) -> int:
        return min(int(np.searchsorted(self.head.t, t)), self.head.t.size - 1)

    def cyclopean_gaze(self, i: int, target: np.ndarray) -> np.ndarray:
        """Unit gaze direction (camera frame) from between the eyes to ``target``."""
        eye = 0.5 * (EYE_CENTERS["left_eye"] + EYE_CENTERS["right_eye"])
        return _gaze_in_camera(
            self.head.position[i : i + 1],
            self.head.orientation[i : i + 1],
            eye,
            target[None, :],
        )[0]

    def forward_point(self, i: int, distance: float, yaw: float, elevation: float):
        """World point ``distance`` away from the head, ``yaw`` left of its facing."""
        q = self.head.orientation[i : i + 1]
        ahead = rotate_vectors(q, np.array([[0.0, 0.0, -1.0]]))[0]
        heading = np.arctan2(-ahead[0], -ahead[2]) + yaw
        direction = np.array(
            [
                -np.sin(heading) * np.cos(elevation),
                np.sin(elevation),
                -np.cos(heading) * np.cos(elevation),
            ]
        )
        return self.head.position[i] + distance * direction

    def path_point(self, i: int, ahead: float):
        """Point on the ground where the walker will be ``ahead`` m later."""
        s = self.head.arc_length
        j = int(min(np.searchsorted(s, s[i] + ahead), s.size - 1))
        point = self.head.position[j].copy()
        point[1] = GROUND
        return point


def _gaze_in_camera(head_pos, head_q, eye_center, target) -> np.ndarray:
    """Unit directions (n, 3) in the camera frame from an eye to world targets."""
    q_cam = SCENE_CAMERA_ROTATION[None, :]
    eye_in_head = (
        SCENE_CAMERA_TRANSLATION + rotate_vectors(q_cam, eye_center[None, :])[0]
    )
    eye_world = head_pos + rotate_vectors(head_q, eye_in_head[None, :])
    in_head = rotate_vectors(qconj(head_q), target - eye_world)
    in_camera = rotate_vectors(qconj(q_cam), in_head)
    return in_camera / np.linalg.norm(in_camera, axis=1, keepdims=True)


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0)))


def _draw_target(
    rng: np.random.Generator, look: _HeadLookup, checks: list
) -> np.ndarray:
    """A random point to look at: on the path ahead or around, ahead of the head.

    ``checks`` lists (head-grid index, largest eye eccentricity there); the
    first index is where the head is when the point is chosen.
    """
    i = checks[0][0]
    forward = np.array([0.0, 0.0, 1.0])
    for _ in range(20):
        if rng.random() < 0.5:
            target = look.path_point(i, rng.uniform(3.0, 15.0))
        else:
            target = look.forward_point(
                i,
                rng.uniform(4.0, 25.0),
                np.deg2rad(np.clip(rng.normal(0.0, 15.0), -30.0, 30.0)),
                np.deg2rad(rng.normal(-5.0, 6.0)),
            )
        if all(
            _angle(look.cyclopean_gaze(k, target), forward) < limit
            for k, limit in checks
        ):
            return target
    return look.forward_point(i, 20.0, 0.0, 0.0)


def _saccade(
    rng: np.random.Generator, look: _HeadLookup, onset: float, previous, target
) -> Fixation:
    i = look.index(onset)
    amplitude = _angle(look.cyclopean_gaze(i, previous), look.cyclopean_gaze(i, target))
    peak = main_sequence_peak_velocity(amplitude) * rng.uniform(0.9, 1.1)
    # a minimum-jerk shift of amplitude A in D seconds peaks at 1.875 A / D
    duration = max(1.875 * amplitude / max(peak, 1e-9), 0.015)
    return Fixation(onset, target, duration, amplitude)


def plan_fixations(
    rng: np.random.Generator, head: HeadMotion, start: float, end: float
) -> tuple:
    """Fixations from ``start`` to ``end`` (s), with gaze shifts leading head scans."""
    look = _HeadLookup(head)
    forced = []  # (time, kind, scan)
    for scan in head.scans:
        forced.append((scan.onset - 0.04, "scan", scan))
        forced.append((scan.back - 0.04, "return", scan))
    forced = [f for f in forced if start < f[0] < end]

    first = look.path_point(look.index(start), 8.0)
    fixations = [Fixation(start, first, 0.015, 0.0)]
    pending = iter(forced)  # scans are in time order and never overlap
    upcoming = next(pending, None)
    while True:
        previous = fixations[-1]
        # a new saccade never starts before the last one has landed
        earliest = previous.onset + previous.saccade_duration + _MIN_FIXATION
        dwell_end = max(previous.onset + rng.gamma(4.0, 0.075), earliest)
        if upcoming is not None and upcoming[0] < dwell_end + 0.1:
            t, kind, scan = upcoming
            t = max(t, earliest)
            upcoming = next(pending, None)
            if kind == "scan":
                # look where the head will point once it has turned
                target = look.forward_point(
                    look.index(scan.turned),
                    rng.uniform(6.0, 25.0),
                    np.deg2rad(rng.normal(0.0, 4.0)),
                    scan.pitch,
                )
            else:
                # back to the way ahead, seen from where the head turns back to
                ahead = look.index(scan.back + scan.duration)
                target = _draw_target(
                    rng,
                    look,
                    [
                        (ahead, MAX_ECCENTRICITY),
                        (look.index(t), _MAX_SCAN_ECCENTRICITY),
                    ],
                )
        else:
            t, target = dwell_end, None
        if t >= end:
            break
        if target is None:
            target = _draw_target(
                rng,
                look,
                [
                    (look.index(t), MAX_ECCENTRICITY),
                    (look.index(t + 0.4), MAX_ECCENTRICITY),
                ],
            )
        fixations.append(_saccade(rng, look, t, previous.target, target))
    return tuple(fixations)


def _slerp_directions(a: np.ndarray, b: np.ndarray, u: np.ndarray) -> np.ndarray:
    cos = np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)
    angle = np.arccos(cos)
    small = angle < 1e-9
    sin = np.where(small, 1.0, np.sin(angle))
    wa = np.where(small, 1.0 - u, np.sin((1.0 - u) * angle) / sin)
    wb = np.where(small, u, np.sin(u * angle) / sin)
    out = wa[:, None] * a + wb[:, None] * b
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def eye_orientation(
    rng: np.random.Generator,
    head: HeadMotion,
    index: np.ndarray,
    eye: str,
    fixations: tuple,
    error: np.ndarray,
) -> np.ndarray:
    """Eye-in-camera quaternions (n, 4) at the head-grid samples ``index``.

    ``error`` (n,) is each sample's angular tracking error in rad, applied
    in a random direction.
    """
    t = head.t[index]
    onsets = np.array([f.onset for f in fixations])
    targets = np.array([f.target for f in fixations])
    durations = np.array([f.saccade_duration for f in fixations])
    k = np.clip(np.searchsorted(onsets, t, side="right") - 1, 0, None)
    pos, q = head.position[index], head.orientation[index]
    current = _gaze_in_camera(pos, q, EYE_CENTERS[eye], targets[k])
    previous = _gaze_in_camera(pos, q, EYE_CENTERS[eye], targets[np.maximum(k - 1, 0)])
    progress = smootherstep((t - onsets[k]) / durations[k])
    gaze = _tilt(rng, _slerp_directions(previous, current, progress), error)
    # shortest arc from the camera's z axis to the gaze direction
    quat = np.stack(
        [1.0 + gaze[:, 2], -gaze[:, 1], gaze[:, 0], np.zeros_like(t)], axis=1
    )
    return quat / np.linalg.norm(quat, axis=1, keepdims=True)


def _tilt(
    rng: np.random.Generator, directions: np.ndarray, angle: np.ndarray
) -> np.ndarray:
    """Unit directions turned by ``angle`` (rad) towards random perpendiculars."""
    side = np.cross(directions, rng.normal(size=directions.shape))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    out = np.cos(angle)[:, None] * directions + np.sin(angle)[:, None] * side
    # never behind the camera: the pupil would not be seen
    out[:, 2] = np.maximum(out[:, 2], 0.05)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def draw_blinks(rng: np.random.Generator, start: float, end: float) -> np.ndarray:
    """(onset, duration) rows: ~15 blinks a minute of 80-400 ms."""
    blinks = []
    t = start + rng.exponential(4.0)
    while t < end - 0.5:
        duration = float(np.clip(rng.lognormal(np.log(0.15), 0.3), 0.08, 0.4))
        blinks.append((t, duration))
        t += duration + max(rng.exponential(4.0), 0.5)
    return np.array(blinks).reshape(-1, 2)


def lid_closure(t: np.ndarray, blinks: np.ndarray) -> np.ndarray:
    """How far the lids are closed at ``t`` (0 open, 1 shut), shape of ``t``."""
    closed = np.zeros_like(t)
    edge = 0.03  # lids take ~30 ms to close and to open
    for onset, duration in blinks:
        i0, i1 = np.searchsorted(t, [onset, onset + duration])
        value, _ = bump(t[i0:i1], onset, edge, duration - 2.0 * edge)
        closed[i0:i1] = np.maximum(closed[i0:i1], value)
    return closed
