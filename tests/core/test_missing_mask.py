"""Rows treated as missing by a mask instead of NaN-masked copies (issue 35, kernel memory).

``ReferenceFrame(..., missing=mask)`` must give every result a frame of
NaN-masked copies gives, bit for bit (NaN payloads and signs included),
while keeping the caller's frozen arrays instead of the copies.
"""

from __future__ import annotations

import numpy as np
import pytest
from recordings import recording

from rbm_nb._infra.frozen import freeze_dataset, is_frozen
from rbm_nb.app import explorer
from rbm_nb.core import frames
from rbm_nb.core.frames import ReferenceFrame
from rbm_nb.core.lookups import lookup_transform, lookup_twist
from rbm_nb.core.transforms import transform_points, transform_quaternions


def frozen(arr):
    out = np.array(arr, order="C")  # owns its memory
    out.setflags(write=False)
    return out


def walk(n=800):
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.normal(size=(n, 3)), axis=0) * 0.01
    q = rng.normal(size=(n, 4)) * 0.05 + [1, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[::5] *= -1.0001  # sign flips and not exactly unit, as recordings have
    q[40:43] = np.nan  # missing samples of the recording itself
    t[40:43] = np.nan
    ts = np.arange(n) * 0.01
    ts[300:] += 0.5  # a long gap (max_gap)
    mask = rng.random(n) < 0.2
    mask[100:130] = True  # a long masked run
    return t, q, ts, mask


def nan_copy(arr, mask):
    out = np.array(arr)
    out[mask] = np.nan
    return out


def bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


def same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    np.testing.assert_array_equal(bits(a), bits(b))


def results(name):
    """Everything the engine gives for frame ``name`` (wrt 'world')."""
    frame = frames.registry[name]
    ts = frame.timestamps
    other = (ts[:-1] + np.diff(ts) * 0.37)[::3]  # between the samples
    out = [frame.translation, frame.rotation]
    out += list(lookup_transform(name, "world", return_timestamps=True))
    out += list(lookup_transform("world", name, return_timestamps=True))
    points = np.ones((len(other), 3))
    out += list(
        transform_points(
            points, "world", name, timestamps=other, return_timestamps=True
        )
    )
    quats = np.tile([0.5, 0.5, 0.5, 0.5], (len(other), 1))
    out.append(transform_quaternions(quats, "world", name, timestamps=other))
    out += list(lookup_twist(name, "world", return_timestamps=True))
    out.append(frame.transform_points(np.ones(3), "world"))
    return out


@pytest.mark.parametrize("freeze", [True, False])
@pytest.mark.parametrize("options", [{}, {"max_gap": 0.1}, {"discrete": True}])
def test_mask_gives_the_bits_of_nan_masked_copies(freeze, options):
    t, q, ts, mask = walk()
    prep = frozen if freeze else np.array
    frames.register_frame("world")
    ReferenceFrame(
        "copies",
        parent="world",
        translation=prep(nan_copy(t, mask)),
        rotation=prep(nan_copy(q, mask)),
        timestamps=prep(ts),
        **options,
    ).register(update=True)
    ReferenceFrame(
        "masked",
        parent="world",
        translation=prep(t),
        rotation=prep(q),
        timestamps=prep(ts),
        missing=mask,
        **options,
    ).register(update=True)
    expected, got = results("copies"), results("masked")
    for a, b in zip(expected, got, strict=True):
        same_bits(a, b)
    a, b = frames.registry["copies"].data, frames.registry["masked"].data
    same_bits(a.r, b.r)
    assert a.missing_rotations == b.missing_rotations


def test_mask_frame_keeps_the_callers_frozen_arrays():
    t, q, ts, mask = walk()
    ft, fq = frozen(t), frozen(q)
    frames.register_frame("world")
    user_mask = mask.copy()
    frame = ReferenceFrame(
        "masked",
        parent="world",
        translation=ft,
        rotation=fq,
        timestamps=frozen(ts),
        missing=user_mask,
    )
    samples = frame.data.samples
    assert np.shares_memory(samples.stored_t, ft)
    assert np.shares_memory(samples.stored_rotation, fq)
    assert samples.missing_rows is not None and is_frozen(samples.missing_rows)
    # the user's mask was copied: changing it later changes nothing
    before = frame.translation.copy()
    user_mask[:] = False
    same_bits(before, frame.translation)
    assert np.isnan(frame.translation[mask]).all()
    assert np.isnan(frame.rotation[mask]).all()


def test_mask_with_writeable_arrays_copies_them():
    """A user writing into their arrays later changes no frame."""
    t, q, ts, mask = walk()
    frames.register_frame("world")
    frame = ReferenceFrame(
        "masked", parent="world", translation=t, rotation=q, timestamps=ts,
        missing=mask,
    )  # fmt: skip
    before = [a.copy() for a in lookup_transform(frame, "world")]
    t[:] = 5.0
    q[:] = [0.0, 1.0, 0.0, 0.0]
    assert not np.shares_memory(frame.data.samples.stored_t, t)
    for a, b in zip(before, lookup_transform(frame, "world"), strict=True):
        same_bits(a, b)


def test_mask_errors_name_the_argument():
    t, q, ts, mask = walk()
    frames.register_frame("world")
    with pytest.raises(ValueError, match=r"frame 'm': missing must be a bool array"):
        ReferenceFrame(
            "m", parent="world", translation=t, rotation=q, timestamps=ts,
            missing=mask[:-1],
        )  # fmt: skip
    with pytest.raises(ValueError, match="missing must be a bool array"):
        ReferenceFrame(
            "m", parent="world", translation=t, rotation=q, timestamps=ts,
            missing=mask.astype(float),
        )  # fmt: skip
    with pytest.raises(ValueError, match="missing given without timestamps"):
        ReferenceFrame("m", parent="world", translation=t[0], missing=mask[:1])


def test_explorer_eye_frames_keep_the_frozen_recording():
    """The explorer's low-confidence eye samples are a mask beside the
    recording's own (read-only) arrays, not masked copies; results unchanged."""
    head, left, right, _ = recording()
    data = [freeze_dataset(ds.copy(deep=True)) for ds in (head, left, right)]
    explorer.register_head_eye_frames(*data)
    eye = frames.registry["pupil/left_eye"].data.samples
    assert np.shares_memory(eye.stored_t, data[1].position.values)
    assert np.shares_memory(eye.stored_rotation, data[1].orientation.values)
    low = (data[1].confidence < explorer.MIN_CONFIDENCE).values
    assert low.any()
    np.testing.assert_array_equal(eye.missing_rows, low)
    got = list(lookup_transform("pupil/left_eye", "world", return_timestamps=True))
    # the same frames from NaN-masked copies, as the explorer made them before
    masked = data[1].copy(deep=True)
    for var in ("position", "orientation"):
        masked[var].values[low] = np.nan
    explorer.register_head_eye_frames(data[0], masked, data[2])
    assert frames.registry["pupil/left_eye"].data.samples.missing_rows is None
    want = lookup_transform("pupil/left_eye", "world", return_timestamps=True)
    for a, b in zip(want, got, strict=True):
        if a.dtype.kind == "f":
            same_bits(a, b)
        else:
            np.testing.assert_array_equal(a, b)


def test_explorer_frames_keep_only_unit_rotations_seconds_and_mask():
    """What registering the explorer's frames keeps, beside a frozen recording:
    per sample the unit rotations (4 floats), the float seconds (1) and, for
    the eyes, a mask byte -- no copy of the poses or the times."""
    import gc
    import tracemalloc

    head, left, right, _ = recording()
    data = [freeze_dataset(ds.copy(deep=True)) for ds in (head, left, right)]
    explorer.register_head_eye_frames(data[0], data[1], data[2])  # warm
    frames.clear_registry()
    gc.collect()
    tracemalloc.start()
    explorer.register_head_eye_frames(*data)
    gc.collect()
    kept, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    n_head, n_eyes = (
        data[0].sizes["time"],
        data[1].sizes["time"] + data[2].sizes["time"],
    )
    allowed = n_head * 5 * 8 + n_eyes * (5 * 8 + 1) + 256 * 1024  # + small objects
    assert kept <= allowed, (kept, allowed)
