"""The loaders return frozen datasets, so frames keep views (issue 35, kernel memory)."""

from __future__ import annotations

import numpy as np
import pytest

from rbm_nb._infra.frozen import freeze_dataset, is_frozen
from rbm_nb.core import frames
from rbm_nb.core.frames import ReferenceFrame
from rbm_nb.data import load_example


@pytest.fixture
def eye():
    return load_example("left_eye", source="synthetic")


def test_load_example_arrays_are_frozen(eye):
    for name in ("position", "orientation", "confidence", "time"):
        assert is_frozen(eye[name].values), name


def test_frames_keep_the_loaded_arrays_and_the_time(eye):
    frames.register_frame("world")
    frame = ReferenceFrame.from_dataset(
        eye, "position", "orientation", "time", parent="world", name="eye"
    )
    samples = frame.data.samples
    assert np.shares_memory(samples.stored_t, eye.position.values)
    assert np.shares_memory(samples.stored_rotation, eye.orientation.values)
    assert np.shares_memory(samples.track.values, eye.time.values)


def test_a_deep_copy_is_writeable_and_copied_by_frames(eye):
    mine = eye.copy(deep=True)
    mine.position.values[0] = 1.0  # the user's to change
    frames.register_frame("world")
    frame = ReferenceFrame.from_dataset(
        mine, "position", "orientation", "time", parent="world", name="eye"
    )
    assert not np.shares_memory(frame.data.samples.stored_t, mine.position.values)


def test_freeze_dataset_reaches_the_owner():
    import xarray as xr

    owner = np.arange(12.0)
    ds = xr.Dataset(
        {"v": (("time", "axis"), owner.reshape(4, 3))}, coords={"time": np.arange(4)}
    )
    freeze_dataset(ds)
    assert is_frozen(ds.v.values)
    assert not owner.flags.writeable  # the owner too, not only the view
