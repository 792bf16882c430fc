"""Moving frames keep one sign code per sample, not their unit rotations.

The unit, sign-continuous rotations interpolation needs are made from the
rotations as kept and an int8 code per sample (``_kernels.signed_rows``):
these tests hold the rows to the bits of the route that made and kept them
(``unit_rows`` then ``unflip``) and bound what a frame keeps.
"""

from __future__ import annotations

import numpy as np
import pytest

from rbm_nb import ReferenceFrame, frames
from rbm_nb._infra.frozen import freeze_dataset
from rbm_nb._kernels import quaternion as kq
from rbm_nb._kernels import rows as _rows
from rbm_nb._kernels import signed_rows as ks
from tests.memory_support import kept_by


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def _walk(n=2000, seed=3):
    """Rotations as recorded: ~4 digits (norms off 1), sign flips, NaN rows,
    rows of norm exactly 1."""
    rng = np.random.default_rng(seed)
    q = np.cumsum(rng.normal(scale=0.05, size=(n, 4)), axis=0) + [1.0, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1)[:, None]
    q = np.round(q, 4)
    q[rng.random(n) < 0.3] *= -1.0  # the sign flips unflip removes
    q[5] = [1.0, 0.0, 0.0, 0.0]
    q[6] = [0.0, -1.0, 0.0, 0.0]
    q[100:103] = np.nan  # missing samples
    q[500] = np.nan
    t = rng.normal(size=(n, 3))
    t[100:103] = np.nan
    t[500] = np.nan
    ts = np.arange(n) / 200.0
    return t, q, ts


def _frozen(a):
    a = np.array(a)
    a.setflags(write=False)
    return a


def _old_route(q):
    """The unit rows as frames kept them: ``unit_rows`` then ``unflip``."""
    unit, bad = _rows.unit_rows(np.ascontiguousarray(q), 1e-2, True)
    assert bad < 0
    return kq.unflip(unit)


@pytest.fixture(autouse=True)
def _world():
    frames.clear_registry()
    frames.register_frame("world")
    yield
    frames.clear_registry()


@pytest.mark.parametrize("freeze", [False, True], ids=["copied", "frozen"])
def test_rows_made_from_the_codes_are_the_kept_rows_bit_for_bit(freeze):
    t, q, ts = _walk()
    args = map(_frozen, (t, q, ts)) if freeze else (t, q, ts)
    tt, qq, tss = args
    frame = ReferenceFrame(
        "m", parent="world", translation=tt, rotation=qq, timestamps=tss
    )
    samples = frame.data.samples
    assert samples.unit is None and samples.signs.dtype == np.int8
    assert set(np.unique(samples.signs)) <= {-1, 1}
    np.testing.assert_array_equal(_bits(samples.r), _bits(_old_route(q)))
    # the fused kernels' row, one at a time, is the same
    rows = ks.signed_unit_rows(np.ascontiguousarray(q), samples.signs)
    np.testing.assert_array_equal(_bits(rows), _bits(samples.r))


def test_masked_rows_read_nan_as_in_a_frame_of_masked_copies():
    t, q, ts = _walk()
    mask = np.zeros(len(ts), dtype=bool)
    mask[[7, 8, 900, 1500]] = True
    masked_q = np.where(mask[:, None], np.nan, q)
    frame = ReferenceFrame(
        "m", parent="world", translation=_frozen(t), rotation=_frozen(q),
        timestamps=_frozen(ts), missing=mask,
    )  # fmt: skip
    samples = frame.data.samples
    assert samples.unit is None
    np.testing.assert_array_equal(_bits(samples.r), _bits(_old_route(masked_q)))


def test_an_inverted_frame_keeps_codes_of_its_conjugates():
    t, q, ts = _walk()
    frame = ReferenceFrame(
        "m", parent="world", translation=t, rotation=q, timestamps=ts, inverse=True
    )
    samples = frame.data.samples
    assert samples.unit is None
    unit, _ = _rows.unit_rows(np.ascontiguousarray(q), 1e-2, True)
    expected = kq.unflip(kq.qconj(unit))
    np.testing.assert_array_equal(_bits(samples.r), _bits(expected))


def test_sign_codes_refuse_rows_no_code_makes():
    p = np.array([[1.0, 0.0, 0.0, 0.0], [0.6, 0.8, 0.0, 0.0]])
    r = p.copy()
    r[1, 0] = 0.7  # not p's row normalised or as it is, with either sign
    codes = np.empty(2, dtype=np.int8)
    assert ks.sign_codes(p, r, codes) == 1


def test_a_frame_over_frozen_arrays_keeps_a_byte_per_sample():
    """Beside the caller's frozen arrays a moving frame keeps its float
    seconds (8 bytes per sample) and one sign code (1), not 32 bytes of unit
    rotations."""
    n = 200_000
    t, q, ts = _walk(n)
    t, q, ts = map(_frozen, (t, q, ts))
    ReferenceFrame("warm", parent="world", translation=t, rotation=q, timestamps=ts)
    frame, kept = kept_by(
        lambda: ReferenceFrame(
            "m", parent="world", translation=t, rotation=q, timestamps=ts
        )
    )
    assert frame.data.samples.unit is None
    assert kept <= n * (8 + 1) + 64 * 1024, kept / n


def test_a_frozen_recording_registered_by_the_explorer_keeps_no_unit_rows():
    import xarray as xr

    t, q, ts = _walk(50_000)
    ds = xr.Dataset(
        {
            "position": (("time", "cartesian_axis"), t),
            "orientation": (("time", "quaternion_axis"), q),
        },
        coords={"time": ts},
    )
    ds = freeze_dataset(ds)
    frame = ReferenceFrame.from_dataset(
        ds, "position", "orientation", "time", "world", name="ds"
    )
    assert frame.data.samples.unit is None
    assert np.shares_memory(frame.data.samples.stored_rotation, ds.orientation.data)
