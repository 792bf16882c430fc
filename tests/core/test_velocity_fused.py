"""body_rates (one kernel) against unflip + spline_derivative +
angular_velocity_from_derivative (three), and the velocity path that uses it."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._kernels import differences as dk
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import velocity_fused as vf
from tests.recordings import recording


def three_kernels(q, t):
    qb = kq.unflip(q)
    return dk.angular_velocity_from_derivative(qb, dk.spline_derivative(qb, t))


@pytest.mark.parametrize("n", [4, 5, 6, 9, 200])
@pytest.mark.parametrize("seed", range(3))
def test_same_arithmetic_as_the_three_kernels(n, seed):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q *= np.where(rng.random(n) < 0.3, -1.0, 1.0)[:, None]  # sign flips
    t = np.cumsum(rng.uniform(0.1, 2.0, n))
    out, bad = vf.body_rates(q, t)
    assert bad == 0
    np.testing.assert_array_equal(out, three_kernels(q, t))


@pytest.mark.parametrize("row", [0, 3, 9])
@pytest.mark.parametrize("value", [np.nan, 0.0])
def test_missing_or_zero_rows_are_left_to_the_caller(row, value):
    q = np.tile([1.0, 0.0, 0.0, 0.0], (10, 1))
    q[row] = value
    assert vf.body_rates(q, np.arange(10.0))[1] == 1


def test_the_recording_and_the_public_estimate():
    """The head's orientations: the kernel, and estimate_angular_velocity
    (which now takes it) against the three kernels."""
    head = recording()[0]
    q = np.ascontiguousarray(head.orientation.values)
    t = (head.time.values - head.time.values[0]) / np.timedelta64(1, "s")
    out, bad = vf.body_rates(q, t)
    assert bad == 0
    np.testing.assert_array_equal(out, three_kernels(q, t))
    public = rbm.estimate_angular_velocity(q, timestamps=t, mode="quaternion")
    np.testing.assert_allclose(public, three_kernels(q, t), rtol=0, atol=1e-12)
