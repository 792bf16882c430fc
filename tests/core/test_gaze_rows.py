"""The gaze kernels against the numpy code they replace (issue 35, build time).

``rbm_nb._kernels.gaze_rows`` does the per-sample work of
``gaze.directions``, ``gaze.angles`` and ``gaze.rates`` in one pass each;
the numpy twins below are the code they replace, and every value must be
theirs bit for bit (NaN where they give NaN).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from rbm_nb._kernels import gaze_rows
from rbm_nb._kernels import quaternion as qk
from rbm_nb.core import frames, gaze

AXIS = np.array([0.0, 0.0, 1.0])


def bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def same_bits(a, b):
    assert a.shape == b.shape
    np.testing.assert_array_equal(bits(a), bits(b))


def quaternions(n=5000, seed=4):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4)) * [1.0, 0.3, 0.3, 0.3]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q *= 1 + 1e-4 * rng.normal(size=(n, 1))  # recorded: not exactly unit
    valid = rng.random(n) > 0.1
    q[~valid] = np.nan
    return q, valid


def naive_sight(q, valid, max_angle):
    u = q[valid] / np.linalg.norm(q[valid], axis=1, keepdims=True)
    sight = qk.rotate_vectors_outer(u, AXIS[None]).reshape(len(u), 3)
    if max_angle is not None:
        sight[~(sight[:, 2] >= np.cos(np.radians(max_angle)))] = np.nan
    return sight


@pytest.mark.parametrize("max_angle", [None, 50.0, 10.0])
def test_sight_rows_is_the_numpy_sight(max_angle):
    q, valid = quaternions()
    out = np.empty((int(valid.sum()), 3))
    check = max_angle is not None
    min_z = float(np.cos(np.radians(max_angle))) if check else 0.0
    gaze_rows.sight_rows(q, valid, AXIS, min_z, check, out)
    same_bits(out, naive_sight(q, valid, max_angle))
    if check:
        assert np.isnan(out).any() and not np.isnan(out).all()


@pytest.mark.parametrize("forward, up", [("x", "z"), ("z", "-y"), ("-y", "x")])
def test_axis_components_are_the_matrix_products(forward, up):
    q, valid = quaternions()
    v = np.full((len(q), 3), np.nan)
    v[valid] = naive_sight(q, valid, None)
    axes = {"x": 0, "y": 1, "z": 2}
    fwd, upv = np.zeros(3), np.zeros(3)
    fwd[axes[forward[-1]]] = -1.0 if forward[0] == "-" else 1.0
    upv[axes[up[-1]]] = -1.0 if up[0] == "-" else 1.0
    right = np.cross(fwd, upv)
    out = np.empty((3, len(v)))
    gaze_rows.axis_components(v, valid, right, fwd, upv, out)
    for row, axis in zip(out, (right, fwd, upv), strict=True):
        want = v @ axis
        np.testing.assert_array_equal(np.isnan(row), ~valid)
        # bit for bit, but for the sign of an exact zero (matmul's order)
        np.testing.assert_array_equal(row[valid], want[valid])


def naive_slope(t, y, window):
    """``gaze._windowed_slope`` before the kernel."""
    valid = np.flatnonzero(np.isfinite(y))
    out = np.full(t.shape, np.nan)
    if valid.size < 2:
        return out
    tv, yv = t[valid], y[valid]
    first = np.searchsorted(tv, t - window / 2, side="left")
    last = np.searchsorted(tv, t + window / 2, side="right") - 1
    first = np.clip(first, 0, tv.size - 1)
    last = np.clip(last, 0, tv.size - 1)
    span = tv[last] - tv[first]
    ok = np.isfinite(y) & (last > first) & (span >= window / 2 * (1 - 1e-9))
    out[ok] = (yv[last[ok]] - yv[first[ok]]) / span[ok]
    return out


@pytest.mark.parametrize("window", [0.02, 0.0031, 1.0])
def test_windowed_slopes_are_the_searchsorted_ones(window):
    rng = np.random.default_rng(5)
    n = 4000
    t = np.cumsum(rng.exponential(1 / 340, n))
    t[1000:1003] = t[999]  # repeated times
    t[2000:] += 0.5  # a pause
    y = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    y[rng.random((n, 2)) < 0.3] = np.nan
    y[3000:3300, 1] = np.nan
    y[5, 0] = np.inf
    out = np.empty_like(y)
    gaze_rows.windowed_slopes(t, y, window / 2, window / 2 * (1 - 1e-9), out)
    for k in range(2):
        same_bits(out[:, k], naive_slope(t, y[:, k], window))
    lonely = np.full((3, 1), np.nan)
    lonely[1] = 1.0
    got = np.empty_like(lonely)
    gaze_rows.windowed_slopes(np.arange(3.0), lonely, 1.0, 1.0, got)
    assert np.isnan(got).all()


def test_public_gaze_calls_give_the_numpy_values():
    """directions -> angles -> rates through the kernels, against the twins."""
    q, valid = quaternions(n=3000, seed=6)
    q[~valid] = np.nan
    ts = np.arange(len(q)) / 340.0
    conf = np.where(np.random.default_rng(7).random(len(q)) < 0.2, 0.3, 0.9)
    frames.clear_registry()
    frames.register_frame("cam")
    frames.register_frame("eye", parent="cam", rotation=q, timestamps=ts)
    sight = gaze.directions("eye", "cam", confidence=conf, max_angle=50.0)
    keep = valid & (conf >= 0.6)
    want = np.full((len(q), 3), np.nan)
    want[keep] = naive_sight(q, keep, 50.0)
    same_bits(sight.values, want)
    angles = gaze.angles(sight, "cam", forward="z", up="-y")
    x, y, z = want @ [1.0, 0.0, 0.0], want @ [0.0, 0.0, 1.0], want @ [0.0, -1.0, 0.0]
    same_bits(angles.values[:, 0], np.degrees(np.arctan2(x, y)))
    same_bits(angles.values[:, 1], np.degrees(np.arctan2(z, np.hypot(x, y))))
    da = xr.DataArray(angles.values, dims=("time", "angle"), coords={"time": ts})
    rates = gaze.rates(da, window=0.02)
    for k in range(2):
        same_bits(rates.values[:, k], naive_slope(ts, angles.values[:, k], 0.02))
    frames.clear_registry()
