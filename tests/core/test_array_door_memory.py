"""Temporaries on the way from the public array functions to their kernels.

tracemalloc sees numpy's allocations, so these are counts of bytes, not
timings: the door must not copy or convert what the kernel can take as it is.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import rbm_nb as rbm


def peak_over_output(fn):
    """Peak traced bytes of one call over the bytes of its array result(s)."""
    fn()
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        before = tracemalloc.get_traced_memory()[0]
        result = fn()
        peak = tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()
    arrays = result if isinstance(result, tuple) else (result,)
    return peak / sum(a.nbytes for a in arrays if isinstance(a, np.ndarray))


@pytest.fixture
def moving_tree():
    rng = np.random.default_rng(0)
    n = 20_000
    start = np.datetime64("2021-01-01T00:00:00", "ns")
    ts = start + (np.arange(n) * 5_000_000).astype("timedelta64[ns]")
    q = rng.normal(size=(n, 4)) * 0.01 + [1.0, 0.0, 0.0, 0.0]
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "body",
        parent="world",
        translation=rng.normal(size=(n, 3)),
        rotation=q / np.linalg.norm(q, axis=1)[:, None],
        timestamps=ts,
    )
    rbm.register_frame("cam", parent="body", translation=(0.0, 0.1, 0.0))
    yield ts
    rbm.clear_registry()


@pytest.mark.parametrize("threads", [1, 2])
def test_transform_points_makes_no_timestamps_nobody_asked_for(
    moving_tree, threads, monkeypatch, ignore_load
):
    # on 2 threads the parallel twin runs (and its scratch must stay per thread)
    from rbm_nb._infra import parallel as _parallel

    if threads > 1 and _parallel.threads() < 2:
        pytest.skip("numba has a single thread here")
    monkeypatch.setenv(_parallel.ENV_THREADS, str(threads))
    monkeypatch.setattr(_parallel, "MIN_ROWS", 0)
    ts = moving_tree
    points = np.random.default_rng(1).normal(size=(len(ts) - 7, 3))
    at = ts[3:-4]
    ratio = peak_over_output(
        lambda: rbm.transform_points(points, "world", "cam", timestamps=at)
    )
    assert ratio <= 1.5
    out, ts_out = rbm.transform_points(
        points, "world", "cam", timestamps=at, return_timestamps=True
    )
    np.testing.assert_array_equal(ts_out, at)
    np.testing.assert_array_equal(
        out, rbm.transform_points(points, "world", "cam", timestamps=at)
    )


def test_rotate_vectors_allocates_its_output_only(ignore_load):
    rng = np.random.default_rng(2)
    q = rng.normal(size=(200_000, 4))
    v = rng.normal(size=(200_000, 3))
    assert peak_over_output(lambda: rbm.rotate_vectors(q, v)) <= 1.05


def test_qmul_and_qinv_allocate_their_output_only(ignore_load):
    rng = np.random.default_rng(3)
    p = rng.normal(size=(200_000, 4))
    q = rng.normal(size=(200_000, 4))
    assert peak_over_output(lambda: rbm.qmul(p, q)) <= 1.05
    assert peak_over_output(lambda: rbm.qinv(p)) <= 1.05


def test_one_pass_kernels_equal_the_row_helpers():
    """The branch-free qmul/qinv/rotate loops (fused multiply-add, one
    division per row) against the kernels they replace on the public path."""
    from rbm_nb._kernels import quaternion as kq
    from rbm_nb._kernels import rotations as rk

    rng = np.random.default_rng(4)
    p = rng.normal(size=(1000, 4))
    q = rng.normal(size=(1000, 4))
    v = rng.normal(size=(1000, 3))
    for single in (slice(None), slice(0, 1)):
        out = np.empty((1000, 4))
        assert rk.qmul_into(p[single].copy(), q, out) == 0
        np.testing.assert_allclose(
            out, kq.qmul(p[single].copy(), q), rtol=0, atol=1e-14
        )
        out = np.empty((1000, 3))
        assert rk.rotate_vectors_into(p[single].copy(), v, out) == (0, 0)
        want, _ = rk.rotate_vectors_checked(p[single].copy(), v)
        np.testing.assert_allclose(out, want, rtol=0, atol=1e-13)
    out = np.empty((1000, 4))
    assert rk.qinv_into(p, out) == (0, 0)
    np.testing.assert_allclose(out, rk.qinv_checked(p)[0], rtol=1e-15, atol=0)
    p[[3, 7]] = 0.0
    q[5, 2] = -np.inf
    assert rk.qinv_into(p, np.empty((1000, 4))) == (2, 0)
    assert rk.qmul_into(p, q, np.empty((1000, 4))) == 1
    assert rk.rotate_vectors_into(p, v, np.empty((1000, 3)))[0] == 2
    for serial, parallel, args, width in (
        (rk.qmul_into, rk.qmul_into_parallel, (p, q), 4),
        (rk.qinv_into, rk.qinv_into_parallel, (p,), 4),
        (rk.rotate_vectors_into, rk.rotate_vectors_into_parallel, (p, v), 3),
    ):
        a, b = np.empty((1000, width)), np.empty((1000, width))
        assert serial(*args, a) == parallel(*args, b)
        np.testing.assert_array_equal(a, b)
