"""What a head-mounted eye tracker adds to eye movements: its clock and its failures.

Modelled on the real example recording (Pupil Core, binocular 3d gaze mapper),
whose rates the synthetic one reproduces (measured in ``tests/data/test_synthetic.py``):

* one clock for both eyes: the two eye cameras run at ~200 Hz each, about
  half a period apart, with jitter and dropped frames; frames of the two
  cameras very close in time become one binocular row, the others monocular
  rows. The result is an irregular clock with a median interval of half a
  camera period (~400 Hz) and ~340 rows per second;
* a few stretches with no rows at all (the tracker dropped data), some longer
  than 0.1 s;
* NaN rows: during blinks (both eyes), when a pupil is lost (orientation NaN,
  eyeball position still known, confidence 0), and in the monocular rows of
  the other eye (about a third of an eye's rows in all);
* one binocular mapper confidence shared by both eyes, below 0.6 for about
  30 % of the rows with data; low-confidence gaze is noisy and sometimes
  far off, as with a real tracker;
* the eyeball centre drifts by millimetres as the 3d eye model is refitted.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._profiles import RandomSines

# rows closer than this (s) are one binocular row
_MERGE = 0.5e-3
# the eye cameras drop this fraction of their frames (~340 rows/s from 400)
_DROPPED_FRAMES = 0.15
# probability that a monocular row of one eye has no data for the other eye
# (the real recording: 27 % / 26 % of the rows miss only the left / right eye,
# in runs of median length 1)
_MONOCULAR_MISSING = 0.53
# fraction of rows where a pupil is lost (orientation NaN, position kept)
_LOST_PUPIL = 0.033
# fraction of rows where both pupils are lost at once: single rows mostly (the
# real recording: 5.4 % of rows miss both eyes, median run 1, 95th percentile
# 3 rows; blinks add the longer runs)
_BOTH_LOST = 0.011
# confidence of rows with data: P(< 0.6) = _LOW_FRACTION
_LOW_FRACTION = 0.30
# mean time (s) between the tracker's dropouts
_DROPOUT_INTERVAL = 110.0


class EyeClock(NamedTuple):
    """The shared eye clock (s) and which camera(s) each row comes from."""

    t: np.ndarray  # (n,) s
    left: np.ndarray  # (n,) bool: the row has a left-camera frame
    right: np.ndarray  # (n,) bool


def _camera_times(
    rng, first: float, last: float, rate: float, phase: float
) -> np.ndarray:
    """Frame times of one camera; ``phase`` in periods, frames dropped at random."""
    n = int(np.floor((last - first) * rate)) - 1
    k = np.arange(n) + phase + rng.uniform(-0.08, 0.08, n)
    # the second camera's phase wanders slowly around half a period
    k += RandomSines.draw(rng, 0.03 if phase else 0.0, (1 / 60, 1 / 10)).evaluate(
        first + k / rate
    )[0]
    t = first + np.sort(k) / rate
    return t[(rng.random(n) >= _DROPPED_FRAMES) & (t >= first) & (t <= last)]


def eye_clock(
    rng: np.random.Generator, first: float, last: float, camera_rate: float
) -> EyeClock:
    """Rows of both eye cameras from ``first`` to ``last`` (s), merged when close."""
    left = _camera_times(rng, first, last, camera_rate, 0.0)
    right = _camera_times(rng, first, last, camera_rate, 0.5)
    t = np.concatenate([left, right])
    side = np.r_[np.zeros(left.size, bool), np.ones(right.size, bool)]
    order = np.argsort(t, kind="stable")
    t, side = t[order], side[order]
    # a frame merges with the next one if that is from the other camera and close
    close = (np.diff(t) < _MERGE) & (side[1:] != side[:-1])
    merged = np.zeros(t.size, bool)
    keep = np.ones(t.size, bool)
    i = np.flatnonzero(close)
    # no frame merges twice: drop pairs that overlap the previous pair
    i = i[np.r_[True, np.diff(i) > 1]] if i.size else i
    merged[i] = True
    keep[i + 1] = False
    t_rows = np.where(merged, 0.5 * (t + np.r_[t[1:], t[-1]]), t)[keep]
    has_left = np.where(merged, True, ~side)[keep]
    has_right = np.where(merged, True, side)[keep]
    return EyeClock(t_rows, has_left, has_right)


def draw_dropouts(rng: np.random.Generator, first: float, last: float) -> np.ndarray:
    """(start, duration) rows of stretches with no eye data; at least one."""
    n = max(1, int(round((last - first) / _DROPOUT_INTERVAL)))
    durations = np.clip(rng.lognormal(np.log(0.2), 0.8, n), 0.11, 1.2)
    starts = np.sort(rng.uniform(first + 1.0, last - 2.0, n))
    return np.column_stack([starts, durations])


def remove_dropouts(clock: EyeClock, dropouts: np.ndarray) -> EyeClock:
    keep = np.ones(clock.t.size, bool)
    for start, duration in dropouts:
        keep &= ~((clock.t >= start) & (clock.t < start + duration))
    return EyeClock(clock.t[keep], clock.left[keep], clock.right[keep])


def mapper_confidence(
    rng: np.random.Generator, t: np.ndarray, closed: np.ndarray
) -> np.ndarray:
    """Binocular mapper confidence per row, in [0, 1].

    ``closed`` (n,) in [0, 1] is how far the lids are closed (blinks).
    """
    n = t.size
    low = rng.random(n) < _LOW_FRACTION
    confidence = np.where(
        low,
        0.6 * rng.beta(1.6, 1.2, n),  # spread over [0, 0.6), most near 0.3-0.5
        0.6 + 0.4 * rng.beta(2.2, 1.0, n),  # most near 1
    )
    return np.clip(confidence * (1.0 - closed), 0.0, 1.0)


def both_lost_rows(rng: np.random.Generator, n: int) -> np.ndarray:
    """Rows (n,) where neither pupil is found, apart from blinks."""
    return rng.random(n) < _BOTH_LOST


def missing_rows(
    rng: np.random.Generator,
    clock: EyeClock,
    eye: str,
    closed: np.ndarray,
    both_lost: np.ndarray | None = None,
) -> tuple:
    """Rows with no orientation, and rows with no position either, for ``eye``."""
    own = clock.left if eye == "left_eye" else clock.right
    n = clock.t.size
    monocular_other = ~own & (rng.random(n) < _MONOCULAR_MISSING)
    blink = closed > 0.5
    lost = rng.random(n) < _LOST_PUPIL
    if both_lost is not None:
        lost |= both_lost
    no_position = monocular_other | blink
    return no_position | lost, no_position


def eyeball_centres(
    rng: np.random.Generator, t: np.ndarray, centre: np.ndarray
) -> np.ndarray:
    """Eyeball centre (n, 3) in m: slow drift of the eye model plus fitting noise."""
    drift = np.stack(
        [
            RandomSines.draw(rng, scale, (1 / 120, 1 / 15)).evaluate(t)[0]
            for scale in (0.5e-3, 3e-3, 8e-3)
        ],
        axis=1,
    )
    noise = rng.normal(0.0, 1.0, (t.size, 3)) * np.array([0.05e-3, 0.3e-3, 1.0e-3])
    return centre + drift + noise


def tracking_error(
    rng: np.random.Generator, confidence: np.ndarray, base: float
) -> np.ndarray:
    """Angular error (rad, shape (n,)) of each row's gaze given its confidence.

    High-confidence rows are off by ~``base`` (tracker noise); below 0.6 the
    error grows, and one low-confidence row in 50 is a wild mis-detection.
    """
    shortfall = np.clip(0.6 - confidence, 0.0, 0.6) / 0.6
    error = rng.rayleigh(base + np.deg2rad(6.0) * shortfall)
    wild = (confidence < 0.6) & (rng.random(confidence.size) < 0.02)
    return np.where(wild, np.deg2rad(rng.uniform(20.0, 80.0, confidence.size)), error)
