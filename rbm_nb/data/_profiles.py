"""Smooth building blocks of the synthetic recording, each with its exact rate.

Every signal here comes with its time derivative in closed form, so that the
velocities stored in the synthetic datasets are the true derivatives of the
stored positions and orientations, not finite-difference estimates of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def smootherstep(x: np.ndarray) -> np.ndarray:
    """Quintic 0 → 1 step, flat to second order at both ends, shape of ``x``."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (x * (6.0 * x - 15.0) + 10.0)


def smootherstep_slope(x: np.ndarray) -> np.ndarray:
    """d/dx of :func:`smootherstep`, zero outside [0, 1], shape of ``x``."""
    inside = (x > 0.0) & (x < 1.0)
    xc = np.where(inside, x, 0.0)
    return np.where(inside, 30.0 * xc * xc * (1.0 - xc) ** 2, 0.0)


def bump(t: np.ndarray, start: float, duration: float, hold: float) -> tuple:
    """Go 0 → 1 in ``duration``, stay for ``hold``, come back in ``duration``.

    Minimum-jerk shape (the quintic step), the profile of voluntary head
    movements. Returns the value and its time derivative, shapes of ``t``.
    """
    up = (t - start) / duration
    down = (t - start - duration - hold) / duration
    value = smootherstep(up) - smootherstep(down)
    rate = (smootherstep_slope(up) - smootherstep_slope(down)) / duration
    return value, rate


@dataclass(frozen=True)
class RandomSines:
    """A sum of sinusoids with random phases: a smooth, band-limited wobble."""

    amplitudes: np.ndarray
    frequencies: np.ndarray
    phases: np.ndarray

    @classmethod
    def draw(
        cls, rng: np.random.Generator, amplitude: float, band: tuple, n: int = 3
    ) -> RandomSines:
        """``n`` components with frequencies in ``band`` (Hz), total RMS ~ amplitude."""
        frequencies = rng.uniform(band[0], band[1], n)
        amplitudes = amplitude * np.sqrt(2.0 / n) * rng.uniform(0.7, 1.3, n)
        phases = rng.uniform(0.0, 2.0 * np.pi, n)
        return cls(amplitudes, frequencies, phases)

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value and time derivative at ``t``, shapes of ``t``."""
        arg = 2.0 * np.pi * np.multiply.outer(t, self.frequencies) + self.phases
        rates = 2.0 * np.pi * self.frequencies * self.amplitudes
        return np.sin(arg) @ self.amplitudes, np.cos(arg) @ rates
