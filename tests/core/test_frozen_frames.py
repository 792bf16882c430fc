"""Frames keep the caller's frozen arrays instead of copies (issue 35, kernel memory).

Frozen (``rbm_nb._infra.frozen``): read-only down to the memory, so nobody can
change it after the frame is made. Anything else is copied, as before.
"""

from __future__ import annotations

import numpy as np
import pytest
from recordings import recording

from rbm_nb._infra.frozen import is_frozen, kernel_alias
from rbm_nb.app import explorer
from rbm_nb.core import frames
from rbm_nb.core.frames import ReferenceFrame
from rbm_nb.core.lookups import lookup_transform


def frozen(arr):
    out = np.array(arr, order="C")  # owns its memory
    out.setflags(write=False)
    return out


def walk(n=500):
    rng = np.random.default_rng(0)
    t = rng.normal(size=(n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[::7] *= 1.0001  # as recordings store them: not exactly unit
    q[10] = np.nan  # a missing sample
    t[10] = np.nan
    ts = np.arange(n) * 0.01
    return t, q, ts


def test_is_frozen_follows_the_base_chain():
    owner = frozen(np.zeros((4, 3)))
    assert is_frozen(owner) and is_frozen(owner[1:]) and is_frozen(owner.view())
    writeable = np.zeros((4, 3))
    view = writeable.view()
    view.setflags(write=False)
    # the owner can still write through its base: not frozen
    assert not is_frozen(view) and not is_frozen(writeable)
    assert is_frozen(np.frombuffer(b"\0" * 24))
    assert not is_frozen(np.frombuffer(bytearray(24)))
    assert not is_frozen([1.0, 2.0])


def test_kernel_alias_is_the_same_memory_and_keeps_it_alive():
    owner = frozen(np.arange(12.0).reshape(4, 3))
    alias = kernel_alias(owner)
    assert alias.flags.writeable and np.shares_memory(alias, owner)
    del owner
    assert alias[3, 2] == 11.0
    plain = np.zeros(3)
    assert kernel_alias(plain) is plain


def test_frozen_arrays_are_kept_writeable_ones_copied():
    t, q, ts = walk()
    ft, fq, fts = frozen(t), frozen(q), frozen(ts)
    frames.register_frame("world")
    shared = ReferenceFrame(
        "shared", parent="world", translation=ft, rotation=fq, timestamps=fts
    )
    samples = shared.data.samples
    assert np.shares_memory(samples.t, ft)
    assert np.shares_memory(samples.rotation, fq)
    assert np.shares_memory(shared.data.track.values, fts)
    copied = ReferenceFrame(
        "copied", parent="world", translation=t, rotation=q, timestamps=ts
    )
    assert not np.shares_memory(copied.data.samples.t, t)
    assert not np.shares_memory(copied.data.samples.rotation, q)
    # a read-only view of a writeable array can still change: copied
    view_t, view_q = t.view(), q.view()
    view_t.setflags(write=False)
    view_q.setflags(write=False)
    viewed = ReferenceFrame(
        "viewed", parent="world", translation=view_t, rotation=view_q, timestamps=ts
    )
    assert not np.shares_memory(viewed.data.samples.t, t)
    # every value the same, bit for bit
    for a, b in (
        (samples.t, copied.data.samples.t),
        (samples.r, copied.data.samples.r),
        (samples.rotation, copied.data.samples.rotation),
    ):
        np.testing.assert_array_equal(a, b)
    assert samples.missing_rotations == copied.data.samples.missing_rotations


def test_lookup_into_the_parent_hands_out_copies():
    """At its own times a frame's lookup into its parent is its samples: the
    caller gets copies, never the frame's (possibly the user's frozen) memory."""
    frames.register_frame("world")
    t, q, ts = walk()
    for name, args in (
        ("own_copy", (t, q, ts)),
        ("own_frozen", map(frozen, (t, q, ts))),
    ):
        tt, qq, tss = args
        frame = ReferenceFrame(
            name, parent="world", translation=tt, rotation=qq, timestamps=tss
        )
        frame.register(update=True)
        for result in (
            lookup_transform(name, "world"),
            lookup_transform(name, "world", return_timestamps=True),
        ):
            out_t, out_q = result[0], result[1]
            assert not np.shares_memory(out_t, frame.data.samples.t)
            assert not np.shares_memory(out_q, frame.data.samples.rotation)
            out_t[0] = 123.0  # the caller's to change
            assert frame.data.samples.t[0, 0] != 123.0


@pytest.mark.parametrize("freeze", [False, True])
def test_head_eye_lookups_bit_identical_with_frozen_recording(freeze):
    """Lookups through the head/eye chain are the same bits whether the
    frames copied the recording or keep it."""
    head, left, right, _ = recording()

    def arrays(data):
        out = []
        for a, b in (
            ("pupil/left_eye", "head"),
            ("pupil/right_eye", "world"),
            ("head", "world"),
            ("world", "pupil/left_eye"),
        ):
            out += list(lookup_transform(a, b, return_timestamps=True))
        out.append(explorer.head_yaw_rate().values)
        return out

    explorer.register_head_eye_frames(head, left, right)
    expected = arrays((head, left, right))
    if freeze:
        data = []
        for ds in (head, left, right):
            ds = ds.copy(deep=True)
            for var in ds.variables.values():
                var.values.setflags(write=False)
            data.append(ds)
        explorer.register_head_eye_frames(*data)
        tracker = frames.registry["t265/tracker"].data.samples
        assert np.shares_memory(tracker.t, data[0].position.values)
        assert np.shares_memory(tracker.rotation, data[0].orientation.values)
        got = arrays(data)
        for a, b in zip(expected, got, strict=True):
            np.testing.assert_array_equal(a, b)
