"""A frame's masked rows checked without masked copies (issue 35, build time).

``ReferenceFrame(..., missing=mask)`` over frozen arrays checks the rows and
makes the sign codes in one kernel pass over the caller's arrays
(``_kernels.masked_rows.masked_signs``) instead of from NaN-masked copies;
the results must be those of the copies (``tests/core/test_missing_mask.py``)
and a bad row must be refused with the copies' message.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from rbm_nb._infra.config import UNIT_QUATERNION_TOLERANCE
from rbm_nb._kernels import masked_rows, rows
from rbm_nb.core import frames
from rbm_nb.core.frames import ReferenceFrame


def frozen(arr):
    out = np.array(arr, order="C")
    out.setflags(write=False)
    return out


def walk(n=600, seed=2):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.normal(size=(n, 3)), axis=0) * 0.01
    q = rng.normal(size=(n, 4)) * 0.05 + [1, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[::7] *= -1.00005  # sign flips, not exactly unit
    q[50:53] = np.nan  # the recording's own missing rows
    t[50:53] = np.nan
    mask = rng.random(n) < 0.25
    mask[200:240] = True
    return t, q, np.arange(n) * 0.01, mask


def nan_copy(arr, mask):
    out = np.array(arr)
    out[mask] = np.nan
    return out


def garbage_in_masked_rows(t, q, mask):
    """What a masked row may hold: it is not read (as NaN in a copy)."""
    t, q = t.copy(), q.copy()
    rows_ = np.flatnonzero(mask)
    t[rows_[0]] = np.inf
    q[rows_[1]] = [3.0, 0.0, 0.0, 0.0]
    q[rows_[2], 1] = np.nan
    return t, q


@pytest.mark.parametrize("bad", [None, "norm", "inf", "half_nan"])
def test_masked_signs_is_moving_signs_of_the_masked_copies(bad):
    t, q, _, mask = walk()
    t, q = garbage_in_masked_rows(t, q, mask)
    row = int(np.flatnonzero(~mask)[100])
    if bad == "norm":
        q[row] *= 1.5
    elif bad == "inf":
        t[row, 2] = -np.inf
    elif bad == "half_nan":
        q[row, 3] = np.nan
    codes = np.empty(len(q), dtype=np.int8)
    want_codes = np.empty(len(q), dtype=np.int8)
    got = masked_rows.masked_signs(t, q, mask, UNIT_QUATERNION_TOLERANCE, codes)
    want = rows.moving_signs(
        nan_copy(t, mask), nan_copy(q, mask), UNIT_QUATERNION_TOLERANCE, want_codes
    )
    assert got == want
    assert (got[0] > 0) == (bad is not None)
    np.testing.assert_array_equal(codes, want_codes)


@pytest.mark.parametrize(
    "variable, value, words",
    [
        ("rotation", [2.0, 0.0, 0.0, 0.0], "rotation"),
        ("translation", [0.0, np.inf, 0.0], "translation"),
    ],
)
def test_bad_unmasked_row_refused_with_the_copies_message(variable, value, words):
    t, q, ts, mask = walk()
    row = int(np.flatnonzero(~mask)[7])
    arrays = {"translation": t.copy(), "rotation": q.copy()}
    arrays[variable][row] = value
    frames.register_frame("world")
    with pytest.raises(ValueError) as via_copies:
        ReferenceFrame(
            "m", parent="world", timestamps=ts,
            translation=nan_copy(arrays["translation"], mask),
            rotation=nan_copy(arrays["rotation"], mask),
        )  # fmt: skip
    with pytest.raises(ValueError) as via_mask:
        ReferenceFrame(
            "m", parent="world", timestamps=frozen(ts),
            translation=frozen(arrays["translation"]),
            rotation=frozen(arrays["rotation"]), missing=mask,
        )  # fmt: skip
    assert str(via_mask.value) == str(via_copies.value)
    assert words in str(via_mask.value) and str(row) in str(via_mask.value)


def test_bad_value_in_a_masked_row_is_not_read():
    t, q, ts, mask = walk()
    t, q = garbage_in_masked_rows(t, q, mask)
    frames.register_frame("world")
    frame = ReferenceFrame(
        "m", parent="world", timestamps=frozen(ts), translation=frozen(t),
        rotation=frozen(q), missing=mask,
    )  # fmt: skip
    assert np.isnan(frame.rotation[mask]).all()
    assert np.isfinite(frame.rotation[~mask & np.isfinite(q).all(axis=1)]).all()


def test_masked_frozen_frame_makes_no_masked_copies():
    """Registering over frozen arrays allocates no array of the rows' size
    (it made two NaN-masked copies, 7 floats per sample, before)."""
    t, q, ts, mask = walk(n=200_000, seed=3)
    t, q, ts = frozen(t), frozen(q), frozen(ts)
    frames.register_frame("world")
    ReferenceFrame(
        "warm", parent="world", timestamps=ts, translation=t, rotation=q,
        missing=mask,
    )  # fmt: skip
    tracemalloc.start()
    try:
        ReferenceFrame(
            "m", parent="world", timestamps=ts, translation=t, rotation=q,
            missing=mask,
        )  # fmt: skip
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the sign codes (1 byte) and the mask's private copy (1 byte) per sample
    assert peak < len(ts) * 3 * 8
