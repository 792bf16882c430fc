"""The FrameTree explains a missing sample instead of raising (issue 28, item 5)."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.widgets import FrameTree

REASON = "no pupil seen (blink, lost pupil) or confidence below 0.6"


@pytest.fixture
def tree():
    rbm.clear_registry()
    rbm.register_frame("world")
    t = np.arange(6) * 0.5
    rotation = np.tile([1.0, 0.0, 0.0, 0.0], (6, 1))
    rotation[3] = np.nan  # one missing sample at 1.5 s
    rbm.register_frame(
        "eye",
        parent="world",
        translation=np.zeros((6, 3)),
        rotation=rotation,
        timestamps=t,
    )
    tree = FrameTree("world", missing_reasons={"eye": REASON})
    yield tree
    tree.close()
    rbm.clear_registry()


def test_one_frame_at_a_missing_sample_says_so(tree):
    tree.select("eye")
    tree.time = 1.6
    text = tree.details_text()
    assert "no sample of eye at 1.5" in text and f"(missing: {REASON})" in text, text
    assert tree.details.pose.attitude is None
    tree.time = 1.0
    assert "rotation yaw 0.00" in tree.details_text()


def test_two_frames_at_a_missing_sample_say_which_frame(tree):
    tree.select("eye", "world")
    tree.time = 1.5
    text = tree.details_text()
    assert "Error" not in text and "no sample of eye at 1.5" in text, text
    assert REASON in text


def test_the_details_panel_has_a_fixed_height(tree):
    height = tree._details.layout.height
    tree.select("eye")
    tree.select("eye", "world")
    assert tree._details.layout.height == height and height.endswith("em")
    assert tree._details.layout.overflow == "auto"
