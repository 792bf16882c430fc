"""The plots' M4 rows by one kernel pass, against the numpy code it replaces."""

from __future__ import annotations

import numpy as np
import pytest

from rbm_nb.widgets import _decimate


def panel(n, k, seed):
    rng = np.random.default_rng(seed)
    y = np.cumsum(rng.normal(size=(n, k)), axis=0)
    y[rng.random((n, k)) < 0.2] = np.nan
    y[100:400, 0] = np.nan  # a whole column missing in one component
    y[np.arange(0, n, 97), -1] = np.round(y[np.arange(0, n, 97), -1])  # ties
    y[7, 0], y[9, 0], y[11, -1] = np.inf, -np.inf, -np.inf
    return y


@pytest.mark.parametrize("k", [1, 2, 3])
@pytest.mark.parametrize("columns", [1, 17, 500])
def test_kernel_keeps_the_numpy_rows(k, columns):
    y = panel(5000, k, seed=k + columns)
    starts = np.unique(
        np.r_[0, np.sort(np.random.default_rng(0).integers(0, 5000, columns - 1))]
    )
    got = np.unique(np.concatenate(_decimate._extremes(y, starts)))
    want = np.unique(np.concatenate(_decimate._extremes_by_numpy(y, starts)))
    np.testing.assert_array_equal(got, want)


def test_kernel_reads_read_only_and_strided_panels():
    y = panel(3000, 2, seed=9)
    starts = np.arange(0, 3000, 64)
    frozen = y.copy()
    frozen.setflags(write=False)
    wide = np.repeat(y, 2, axis=1)[:, ::2]  # not contiguous
    want = np.unique(np.concatenate(_decimate._extremes_by_numpy(y, starts)))
    for arr in (frozen, wide):
        got = np.unique(np.concatenate(_decimate._extremes(arr, starts)))
        np.testing.assert_array_equal(got, want)


def test_m4_rows_unchanged_on_a_long_panel(monkeypatch):
    y = panel(1_500_000, 2, seed=3)  # more than one step of CHUNK_ROWS
    x = np.arange(len(y)) / 340.0
    got = _decimate.m4_rows(x, y, x[0], x[-1], 800)
    monkeypatch.setattr(_decimate, "_extremes", _decimate._extremes_by_numpy)
    want = _decimate.m4_rows(x, y, x[0], x[-1], 800)
    np.testing.assert_array_equal(got, want)
    assert got.size < 800 * 10 and got[0] == 0 and got[-1] == len(y) - 1
