"""rbm_nb/_kernels/rows.py: the one-pass checks of registration, against numpy.

The kernels count bad rows in a vectorised pass and only then look for the
first one; every kind of bad row, at the start, in the middle and at the
end, must be found, and good input must come back normalised exactly as
plain division by the norm does.
"""

from __future__ import annotations

import numpy as np
import pytest

from rbm_nb._kernels import rows

RNG = np.random.default_rng(11)


def _first_bad_numpy(a):
    nan = np.isnan(a)
    bad = (nan.any(axis=1) & ~nan.all(axis=1)) | np.isinf(a).any(axis=1)
    return int(np.argmax(bad)) if bad.any() else -1


@pytest.mark.parametrize("k", [3, 4, 5])
@pytest.mark.parametrize("where", [0, 517, 999])
@pytest.mark.parametrize("kind", ["partly nan", "inf", "-inf"])
def test_first_bad_row_finds_every_kind_anywhere(k, where, kind):
    a = RNG.normal(size=(1000, k))
    a[[3, 400, 998]] = np.nan  # whole NaN rows are missing samples, not mistakes
    assert rows.first_bad_row(a) == _first_bad_numpy(a) == -1
    a[where, k - 1] = {"partly nan": np.nan, "inf": np.inf, "-inf": -np.inf}[kind]
    a[where + 1 if where < 999 else 0, 0] = np.inf  # a later (or earlier) one too
    assert rows.first_bad_row(a) == _first_bad_numpy(a)


def _unit_numpy(q, tol, allow_nan):
    # the kernel's summation order (einsum's differs in the last bit)
    w, x, y, z = q.T
    norms = np.sqrt(w * w + x * x + y * y + z * z)
    nan = np.isnan(norms)
    bad = np.isinf(q).any(axis=1) | (nan & (not allow_nan)) | (np.abs(norms - 1) > tol)
    first = int(np.argmax(bad)) if bad.any() else -1
    with np.errstate(invalid="ignore"):
        out = np.where((norms == 1.0)[:, None] | nan[:, None], q, q / norms[:, None])
    return out, first


@pytest.mark.parametrize("allow_nan", [True, False])
def test_unit_rows_normalise_like_division_and_name_the_first_bad_row(allow_nan):
    q = RNG.normal(size=(5000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q *= RNG.uniform(1 - 1e-4, 1 + 1e-4, (5000, 1))
    q[7] = [0.0, 0.0, 0.0, 1.0]  # norm exactly 1: as it is
    q[[100, 4000]] = np.nan
    out, bad = rows.unit_rows(q, 1e-2, allow_nan)
    want, want_bad = _unit_numpy(q, 1e-2, allow_nan)
    assert bad == want_bad == (-1 if allow_nan else 100)
    if allow_nan:
        np.testing.assert_array_equal(out.view(np.int64), want.view(np.int64))
    for row, value in ((4999, [0.0, 0.0, 0.0, 0.0]), (2500, [np.inf, 0, 0, 0]),
                       (1234, [1.5, 0.0, 0.0, 0.0]), (0, [0.5, 0.5, 0.5, -np.inf])):  # fmt: skip
        broken = q.copy()
        broken[row] = value
        assert (
            rows.unit_rows(broken, 1e-2, allow_nan)[1]
            == _unit_numpy(broken, 1e-2, allow_nan)[1]
        )


def _samples(n, rng):
    """Rotations as trackers record them: 4 digits, sign flips, blinks."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q = np.round(q, 4)
    q[rng.random(n) < 0.1] *= -1.0
    t = rng.normal(size=(n, 3))
    missing = rng.random(n) < 0.05
    missing[:3] = True  # the first valid row comes after missing ones
    q[missing] = np.nan
    q[-1] = [-1.0, 0.0, 0.0, 0.0]  # norm exactly 1: kept as it is
    t[rng.random(n) < 0.05] = np.nan
    return t, q


def _moving_samples(t, q, tol=1e-2):
    n = len(q)
    outs = np.full((n, 3), -1.0), np.full((n, 4), -1.0), np.full((n, 4), -1.0)
    bad, missing = rows.moving_samples(t, q, tol, *outs)
    return (bad, missing, *outs)


@pytest.mark.parametrize("n", [1, 2, 255, 256, 257, 1000])
def test_moving_samples_is_the_checks_copies_and_unflip_bit_for_bit(n):
    from rbm_nb._kernels import quaternion as kq

    t, q = _samples(n, np.random.default_rng(n))
    bad, missing, t_out, q_out, r_out = _moving_samples(t, q)
    unit, first = rows.unit_rows(q, 1e-2, True)
    assert bad == 0 and first == -1
    assert rows.first_bad_row(t) == rows.first_bad_row(q) == -1
    assert missing == np.isnan(q[:, 0]).sum()
    for got, want in ((t_out, t), (q_out, q), (r_out, kq.unflip(unit))):
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))


@pytest.mark.parametrize("where", [0, 255, 256, 999])
@pytest.mark.parametrize(
    "which, value",
    [
        ("t", [np.nan, 0.0, 0.0]),
        ("t", [0.0, np.inf, 0.0]),
        ("q", [np.nan, 0.0, 0.0, 1.0]),
        ("q", [0.0, 0.0, 0.0, -np.inf]),
        ("q", [0.0, 0.0, 0.0, 0.0]),
        ("q", [1.02, 0.0, 0.0, 0.0]),
    ],
)
def test_moving_samples_reports_every_bad_row(where, which, value):
    t, q = _samples(1000, np.random.default_rng(3))
    (t if which == "t" else q)[where] = value
    assert _moving_samples(t, q)[0] != 0
