"""The numba split of a path keeps exactly what the former numpy loop kept.

``_reference_simplify_path`` below is :func:`rbm_nb.scene.decimate.simplify_path`
as it was before its inner loop moved into
:func:`rbm_nb._kernels.simplify.split_worst_first` (issue 35): numpy for the
deviation, :mod:`heapq` for the worst segment first. Both must keep the same
points, in the same order, and report the same error, bit for bit.
"""

from __future__ import annotations

import heapq

import numpy as np
import pytest

from rbm_nb.scene import decimate
from rbm_nb.scene.decimate import CELL_SHARE, PATH_TOLERANCE, _runs, simplify_path


def _reference_deviation(points, a, b):
    if b - a < 2:
        return 0.0, -1
    start, end = points[a], points[b]
    inner = points[a + 1 : b]
    direction = end - start
    length2 = float(direction @ direction)
    offset = inner - start
    if length2 > 0:
        along = np.clip(offset @ direction / length2, 0.0, 1.0)
        offset = offset - along[:, None] * direction
    distance2 = np.einsum("ij,ij->i", offset, offset)
    at = int(np.argmax(distance2))
    return float(np.sqrt(distance2[at])), a + 1 + at


def _reference_simplify_path(samples, tolerance=None, max_points=1000):
    samples = np.asarray(samples, dtype=np.float64).reshape(-1, 3)
    rows = np.flatnonzero(~np.isnan(samples).any(axis=1))
    points = samples[rows]
    if len(points) == 0:
        return [], 0.0
    if tolerance is None:
        diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
        tolerance = PATH_TOLERANCE * diagonal
    gap_after = np.zeros(len(points), dtype=bool)
    gap_after[:-1] = np.diff(rows) > 1
    cell = CELL_SHARE * tolerance
    slack = 0.0
    if cell > 0 and len(points) > 2:
        cells = np.floor(points / cell)
        fresh = np.ones(len(points), dtype=bool)
        fresh[1:] = (cells[1:] != cells[:-1]).any(axis=1) | gap_after[:-1]
        fresh |= gap_after
        fresh[-1] = True
        if not fresh.all():
            points, gap_after = points[fresh], gap_after[fresh]
            slack = float(np.sqrt(3.0) * cell)
    runs = _runs(points, gap_after, tolerance, max_points)
    tolerance -= slack
    keep = np.zeros(len(points), dtype=bool)
    heap = []
    for first, last in runs:
        keep[first] = keep[last] = True
        error, at = _reference_deviation(points, first, last)
        if at >= 0:
            heap.append((-error, at, first, last))
    heapq.heapify(heap)
    count = int(keep.sum())
    while heap and count < max_points and -heap[0][0] > tolerance:
        _, at, first, last = heapq.heappop(heap)
        keep[at] = True
        count += 1
        for a, b in ((first, at), (at, last)):
            error, where = _reference_deviation(points, a, b)
            if where >= 0:
                heapq.heappush(heap, (-error, where, a, b))
    error = -heap[0][0] if heap else 0.0
    stretches = [
        points[first : last + 1][keep[first : last + 1]] for first, last in runs
    ]
    return stretches, max(error, 0.0) + slack


def _walk(rng, n, kind):
    """A random walk of n samples with NaN runs; flat stretches and repeats by kind."""
    steps = rng.normal(size=(n, 3)) * rng.choice([1e-3, 1.0, 1e3])
    if kind in ("flat", "mixed"):
        steps[rng.random(n) < 0.3] = 0.0  # repeated samples
        steps[:, 2] *= rng.random(n) < 0.5  # flat in z often
    if kind in ("grid", "mixed"):
        steps = np.round(steps * 4) / 4  # ties: many equal distances
    walk = np.cumsum(steps, axis=0) + rng.normal(size=3) * 100
    for _ in range(rng.integers(0, 6)):
        start = rng.integers(0, n)
        walk[start : start + rng.integers(1, 40)] = np.nan
    walk[rng.random(n) < 0.01] = np.nan
    return walk


def _same(samples, tolerance, max_points):
    got, got_error = simplify_path(samples, tolerance, max_points)
    want, want_error = _reference_simplify_path(samples, tolerance, max_points)
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
    assert got_error == want_error
    return sum(len(w) for w in want)


@pytest.mark.parametrize("kind", ["walk", "flat", "grid", "mixed"])
def test_the_kernel_keeps_what_the_numpy_loop_kept(kind):
    rng = np.random.default_rng(35)
    kept = 0
    for _ in range(40):
        n = int(rng.integers(2, 3000))
        samples = _walk(rng, n, kind)
        for max_points in (2, 7, 100, 100_000):
            for tolerance in (None, 0.0, 1e-2, 10.0):
                kept += _same(samples, tolerance, max_points)
    assert kept > 10_000  # the cases exercised the split, not only the runs' ends


def test_exact_ties_split_at_the_first_farthest_point():
    # a square wave of equal teeth: every tooth's corner is equally far
    teeth = np.zeros((41, 3))
    teeth[:, 0] = np.arange(41)
    teeth[1::4, 1] = 1.0
    teeth[2::4, 1] = 1.0
    for max_points in range(2, 30):
        _same(teeth, 0.0, max_points)
    # the same point again and again, and a line with every sample on it
    _same(np.ones((50, 3)), 0.0, 10)
    _same(np.outer(np.arange(100.0), [1.0, 2.0, 3.0]), 0.0, 10)


def test_the_kernel_is_what_simplify_path_runs(monkeypatch):
    """Without the kernel (a stand-in keeping only the runs' ends) the answer changes."""
    samples = _walk(np.random.default_rng(1), 500, "walk")
    monkeypatch.setattr(decimate, "split_worst_first", lambda *args: 0.0)
    with pytest.raises(AssertionError):
        _same(samples, None, 100)
