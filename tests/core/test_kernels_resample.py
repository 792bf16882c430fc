"""The resampling and chaining kernels against their plain-numpy twins."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import naive
import numpy as np
import pytest
from conftest import REPO

from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import resample as kr

RNG = np.random.default_rng(7)


def unit(n):
    q = RNG.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def times(n, start=0.0):
    return start + np.cumsum(RNG.uniform(0.01, 1.0, n))


def _interp():
    t = times(30)
    return (
        t,
        RNG.normal(size=(30, 3)),
        np.sort(np.concatenate([RNG.uniform(t[0], t[-1], 50), t])),
    )


def _hold_float():
    t = times(12)
    return t, RNG.normal(size=(12, 4)), np.sort(RNG.uniform(t[0] - 2, t[-1] + 2, 200))


CASES = [
    ("interp_linear", "interp_linear", _interp),
    (
        "interp_linear-one-column",
        "interp_linear",
        lambda: (np.arange(5.0), RNG.normal(size=(5, 1)), np.array([0.5, 1.0, 3.9])),
    ),
    ("hold_last-float", "hold_last", _hold_float),
    (
        "chain_step",
        "chain_step",
        lambda: (
            RNG.normal(size=(6, 3)),
            unit(6),
            RNG.normal(size=(6, 3)),
            unit(6),
            False,
        ),
    ),
    (
        "chain_step-inverse",
        "chain_step",
        lambda: (
            RNG.normal(size=(6, 3)),
            unit(6),
            RNG.normal(size=(6, 3)),
            unit(6),
            True,
        ),
    ),
    (
        "chain_step-broadcast",
        "chain_step",
        lambda: (np.zeros((1, 3)), unit(1), RNG.normal(size=(6, 3)), unit(1), True),
    ),
    (
        "transform_blocks-points",
        "transform_blocks",
        lambda: (unit(5), RNG.normal(size=(5, 3)), RNG.normal(size=(5, 4, 3)), True),
    ),
    (
        "transform_blocks-vectors",
        "transform_blocks",
        lambda: (unit(5), RNG.normal(size=(1, 3)), RNG.normal(size=(5, 2, 3)), False),
    ),
    (
        "transform_blocks-static-data",
        "transform_blocks",
        lambda: (unit(5), RNG.normal(size=(5, 3)), RNG.normal(size=(1, 1, 3)), True),
    ),
    ("qmul_blocks", "qmul_blocks", lambda: (unit(5), RNG.normal(size=(5, 3, 4)))),
    (
        "qmul_blocks-broadcast",
        "qmul_blocks",
        lambda: (unit(1), RNG.normal(size=(5, 2, 4))),
    ),
    ("hold_index", "hold_index", lambda: _hold_float()[::2]),
    (
        "transform_blocks_held",
        "transform_blocks_held",
        lambda: (
            unit(4),
            RNG.normal(size=(4, 3)),
            RNG.integers(0, 4, 9),
            RNG.normal(size=(9, 2, 3)),
            True,
        ),
    ),
    (
        "transform_blocks_held-static-data",
        "transform_blocks_held",
        lambda: (
            unit(4),
            RNG.normal(size=(4, 3)),
            RNG.integers(0, 4, 9),
            RNG.normal(size=(1, 1, 3)),
            False,
        ),
    ),
    (
        "qmul_blocks_held",
        "qmul_blocks_held",
        lambda: (unit(3), RNG.integers(0, 3, 7), RNG.normal(size=(7, 2, 4))),
    ),
]


def _as_kernel_input(a):
    if isinstance(a, (bool, np.bool_)):
        return a
    a = np.asarray(a)
    return (
        np.ascontiguousarray(a)
        if a.dtype.kind == "i"
        else np.ascontiguousarray(a, dtype=float)
    )


@pytest.mark.parametrize(
    "name, make_args", [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_kernel_matches_naive_twin(name, make_args):
    args = [_as_kernel_input(a) for a in make_args()]
    got = getattr(kr, name)(*args)
    expected = getattr(naive, name)(*args)
    if np.isscalar(got):
        assert got == expected
    elif isinstance(got, tuple):
        for g, e in zip(got, expected, strict=True):
            np.testing.assert_allclose(g, e, rtol=1e-10, atol=1e-12)
    else:
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("sort", [True, False])
@pytest.mark.parametrize("dtype", [np.float64, np.int64])
def test_search_right_equals_searchsorted(sort, dtype):
    from rbm_nb._kernels.quaternion import search_right

    for _ in range(20):
        t_in = np.unique(RNG.integers(0, 1000, RNG.integers(1, 60))).astype(dtype)
        t_out = RNG.integers(-10, 1010, RNG.integers(0, 90)).astype(dtype)
        t_out = np.concatenate([np.sort(t_out) if sort else t_out, t_in[:3]])
        expected = np.searchsorted(t_in, t_out, side="right") - 1
        np.testing.assert_array_equal(search_right(t_in, t_out), expected)


def test_interp_linear_is_exact_at_samples():
    t = np.linspace(0.1, 0.7, 7) * 1e-3 + 1e4
    y = RNG.normal(size=(7, 3))
    np.testing.assert_array_equal(kr.interp_linear(t, y, t), y)


def test_hold_last_before_first_event_takes_first():
    out = kr.hold_last(
        np.array([1.0, 2.0]),
        np.array([[10.0], [20.0]]),
        np.array([0.0, 1.0, 1.5, 2.0, 9.0]),
    )
    np.testing.assert_array_equal(out[:, 0], [10, 10, 10, 20, 20])


def test_unflip_bridges_nan_rows():
    q = unit(6)
    q[3] = np.nan
    out = kq.unflip(q)
    np.testing.assert_allclose(out, naive.unflip(q), equal_nan=True)
    valid = [0, 1, 2, 4, 5]
    dots = np.sum(out[valid][1:] * out[valid][:-1], axis=1)
    assert (dots >= 0).all()


@pytest.mark.slow
def test_kernels_run_as_plain_python():
    """The kernels' Python path (NUMBA_DISABLE_JIT=1) for coverage and sanity."""
    tests = Path(__file__).parent
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    result = subprocess.run(
        [
            sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
            str(tests / "test_kernels_quaternion.py"), str(tests / "test_kernels_resample.py"),
            "-k", "naive_twin or squad or search_right",
        ],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
