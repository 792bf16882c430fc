"""Head kinematics of the synthetic recording: laps around a building.

World frame as the RealSense T265 defines it: origin at the tracker's start
position, y up (gravity), x right and z backwards at the start, so walking
straight ahead at first is walking towards -z. Yaw is a rotation about +y,
positive to the left; the head orientation is yaw ∘ pitch ∘ roll (intrinsic
y-x-z), pitch about the head's x axis (positive = nose up), roll about its z.

Positions integrate the velocity, and the velocity, the orientation and the
angular velocity are all evaluated in closed form from the same smooth
profiles, so the stored velocities are the exact derivatives of the stored
poses (up to the trapezoidal integration of the horizontal path).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._kernels.quaternion import qmul
from ._profiles import RandomSines, bump, smootherstep, smootherstep_slope


@dataclass(frozen=True)
class WalkParams:
    """Knobs of the walk; lengths in m, times in s, angles in rad."""

    speed: float = 1.45
    laps: int = 2
    step_frequency: float = 1.9  # steps per second: the head bobs once per step
    bob_amplitude: float = 0.02  # vertical head excursion, ± m
    sway_amplitude: float = 0.012  # sideways, once per stride (two steps)
    stand: float = 2.0  # standing still at the start and at the end
    ramp: float = 1.5  # time to reach walking speed and to stop again
    aspect: float = 1.5  # long side / short side of the building
    corner_halfwidth: float = 4.0  # arc length over which half a corner is turned
    pitch: float = np.deg2rad(-6.0)  # looking slightly down while walking
    scan_interval: float = 6.0  # mean pause between head scans


@dataclass(frozen=True)
class HeadScan:
    """A look to the side: turn in ``duration``, hold, turn back in ``duration``."""

    onset: float
    duration: float
    hold: float
    yaw: float
    pitch: float

    @property
    def turned(self) -> float:
        """Time at which the head has reached the scan direction."""
        return self.onset + self.duration

    @property
    def back(self) -> float:
        """Time at which the head starts turning back."""
        return self.onset + self.duration + self.hold


@dataclass(frozen=True)
class HeadMotion:
    """Head pose and twist wrt world on a time grid (all represented in world)."""

    t: np.ndarray  # (n,) s
    position: np.ndarray  # (n, 3) m
    orientation: np.ndarray  # (n, 4) w, x, y, z
    linear_velocity: np.ndarray  # (n, 3) m/s
    angular_velocity: np.ndarray  # (n, 3) rad/s
    arc_length: np.ndarray  # (n,) m walked so far
    gait: np.ndarray  # (n,) 0 standing .. 1 walking
    scans: tuple[HeadScan, ...]
    lap_length: float


def gait_envelope(t: np.ndarray, duration: float, p: WalkParams) -> tuple:
    """0 while standing, 1 while walking, quintic ramps in between; and its rate."""
    up = (t - p.stand) / p.ramp
    down = (t - (duration - p.stand - p.ramp)) / p.ramp
    g = smootherstep(up) - smootherstep(down)
    rate = (smootherstep_slope(up) - smootherstep_slope(down)) / p.ramp
    return g, rate


def corner_positions(lap_length: float, p: WalkParams) -> np.ndarray:
    """Arc lengths of the corner centres; the walk starts mid-way along a long side."""
    long_side = 0.5 * lap_length * p.aspect / (1.0 + p.aspect)
    short_side = 0.5 * lap_length / (1.0 + p.aspect)
    sides = np.tile([short_side, long_side], 2 * p.laps)[: 4 * p.laps - 1]
    return 0.5 * long_side + np.concatenate(([0.0], np.cumsum(sides)))


def path_heading(s: np.ndarray, corners: np.ndarray, halfwidth: float) -> tuple:
    """Heading of the path (rad, +90° per left corner) and d(heading)/ds."""
    x = (s[:, None] - corners[None, :] + halfwidth) / (2.0 * halfwidth)
    heading = 0.5 * np.pi * smootherstep(x).sum(axis=1)
    slope = 0.5 * np.pi * smootherstep_slope(x).sum(axis=1) / (2.0 * halfwidth)
    return heading, slope


def draw_scans(rng: np.random.Generator, duration: float, p: WalkParams) -> tuple:
    """Head scans at random times while walking, never overlapping."""
    scans = []
    onset = p.stand + p.ramp + rng.exponential(p.scan_interval)
    last_start = duration - p.stand - p.ramp - 4.0
    while onset < last_start:
        yaw = rng.choice([-1.0, 1.0]) * np.deg2rad(rng.uniform(15.0, 45.0))
        pitch = np.deg2rad(np.clip(rng.normal(0.0, 6.0), -15.0, 15.0))
        # about 200 deg/s peak for the largest turns, slower for small ones
        move = 0.25 + abs(yaw) / np.deg2rad(250.0)
        hold = rng.uniform(0.4, 2.0)
        scans.append(HeadScan(onset, move, hold, yaw, pitch))
        onset += 2.0 * move + hold + 1.0 + rng.exponential(p.scan_interval)
    return tuple(scans)


def _scan_angles(t: np.ndarray, scans: tuple) -> tuple:
    yaw, yaw_rate = np.zeros_like(t), np.zeros_like(t)
    pitch, pitch_rate = np.zeros_like(t), np.zeros_like(t)
    for scan in scans:
        i0, i1 = np.searchsorted(t, [scan.onset, scan.back + scan.duration])
        value, rate = bump(t[i0:i1], scan.onset, scan.duration, scan.hold)
        yaw[i0:i1] += scan.yaw * value
        yaw_rate[i0:i1] += scan.yaw * rate
        pitch[i0:i1] += scan.pitch * value
        pitch_rate[i0:i1] += scan.pitch * rate
    return yaw, yaw_rate, pitch, pitch_rate


def _gait_oscillation(t, g, g_rate, amplitude, frequency, phase=0.0) -> tuple:
    """``amplitude * g * sin(2 pi frequency t + phase)``, fading with the gait; and its rate."""
    arg = 2.0 * np.pi * frequency * t + phase
    value = amplitude * g * np.sin(arg)
    rate = amplitude * (
        g_rate * np.sin(arg) + g * 2.0 * np.pi * frequency * np.cos(arg)
    )
    return value, rate


def _axis_quaternions(angle: np.ndarray, axis: int) -> np.ndarray:
    q = np.zeros((angle.size, 4))
    q[:, 0] = np.cos(0.5 * angle)
    q[:, 1 + axis] = np.sin(0.5 * angle)
    return q


def simulate_head(
    t: np.ndarray, duration: float, rng: np.random.Generator, p: WalkParams
) -> HeadMotion:
    """Head motion on the sorted time grid ``t`` (s from the start, t[0] == 0)."""
    from scipy.integrate import cumulative_trapezoid

    g, g_rate = gait_envelope(t, duration, p)
    speed_wobble = RandomSines.draw(rng, 0.03, (1 / 60, 1 / 8))
    speed = p.speed * g * (1.0 + speed_wobble.evaluate(t)[0])
    arc = cumulative_trapezoid(speed, t, initial=0.0)
    # the building is sized so that the walk is exactly `laps` laps long
    lap_length = arc[-1] / p.laps
    halfwidth = min(p.corner_halfwidth, 0.1 * lap_length)
    corners = corner_positions(lap_length, p)
    heading, heading_slope = path_heading(arc, corners, halfwidth)

    wander = RandomSines.draw(rng, np.deg2rad(2.0), (1 / 30, 1 / 5))
    wander_angle, wander_rate = wander.evaluate(t)
    walk_dir = heading + wander_angle - wander.evaluate(np.zeros(1))[0]
    forward = np.stack([-np.sin(walk_dir), np.zeros_like(t), -np.cos(walk_dir)], 1)
    left = np.stack([-np.cos(walk_dir), np.zeros_like(t), np.sin(walk_dir)], 1)

    stride = 0.5 * p.step_frequency  # a stride is two steps

    def oscillation(amplitude, frequency, phase=0.0):
        return _gait_oscillation(t, g, g_rate, amplitude, frequency, phase)

    _, sway_rate = oscillation(p.sway_amplitude, stride)
    bob, bob_rate = oscillation(p.bob_amplitude, p.step_frequency, -0.5 * np.pi)
    velocity = speed[:, None] * forward + sway_rate[:, None] * left
    velocity[:, 1] = bob_rate
    position = cumulative_trapezoid(velocity, t, axis=0, initial=0.0)
    position[:, 1] = bob

    scans = draw_scans(rng, duration, p)
    scan_yaw, scan_yaw_rate, scan_pitch, scan_pitch_rate = _scan_angles(t, scans)
    look_angle, look_rate = RandomSines.draw(
        rng, np.deg2rad(2.0), (0.05, 0.3)
    ).evaluate(t)
    tilt_angle, tilt_rate = RandomSines.draw(
        rng, np.deg2rad(1.0), (0.05, 0.3)
    ).evaluate(t)
    pitch_bob, pitch_bob_rate = oscillation(np.deg2rad(0.8), p.step_frequency, 0.6)
    roll_sway, roll_sway_rate = oscillation(np.deg2rad(1.5), stride)

    yaw = heading + 0.3 * (walk_dir - heading) + scan_yaw
    yaw_rate = heading_slope * speed + 0.3 * wander_rate + scan_yaw_rate
    pitch = p.pitch + pitch_bob + scan_pitch + look_angle
    pitch_rate = pitch_bob_rate + scan_pitch_rate + look_rate
    roll = roll_sway + tilt_angle
    roll_rate = roll_sway_rate + tilt_rate

    orientation = qmul(
        qmul(_axis_quaternions(yaw, 1), _axis_quaternions(pitch, 0)),
        _axis_quaternions(roll, 2),
    )
    # world-frame angular velocity of the intrinsic yaw-pitch-roll chain
    angular = np.empty_like(velocity)
    angular[:, 0] = pitch_rate * np.cos(yaw) + roll_rate * np.sin(yaw) * np.cos(pitch)
    angular[:, 1] = yaw_rate - roll_rate * np.sin(pitch)
    angular[:, 2] = -pitch_rate * np.sin(yaw) + roll_rate * np.cos(yaw) * np.cos(pitch)

    return HeadMotion(
        t=t,
        position=position,
        orientation=orientation,
        linear_velocity=velocity,
        angular_velocity=angular,
        arc_length=arc,
        gait=g,
        scans=scans,
        lap_length=lap_length,
    )
