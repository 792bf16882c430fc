"""The explorer's gaze yaw and eye centres by their one-pass routes (issue 35).

``explorer.gaze_yaw`` takes ``app.explorer_yaw.yaw_columns`` where the eyes'
parent reaches the head through static frames, and ``eye_centres`` carries
only the kept translations through those frames; both must give what the
gaze calls and the whole lookup give, bit for bit, and step aside otherwise.
"""

from __future__ import annotations

import numpy as np
import pytest
from recordings import recording

from rbm_nb._infra.frozen import freeze_dataset
from rbm_nb.app import explorer, explorer_yaw
from rbm_nb.core import frames
from rbm_nb.core.lookups import lookup_transform

ATTRS = {"long_name": "x", "units": "deg", "colors": ["a", "b"], "max_gap": 0.5}
LABELS = ["left eye", "right eye"]


@pytest.fixture(params=["frozen", "writeable"])
def registered(request):
    head, left, right, _ = recording()
    data = [ds.copy(deep=True) for ds in (head, left, right)]
    if request.param == "frozen":
        data = [freeze_dataset(ds) for ds in data]
    explorer.register_head_eye_frames(*data)
    yield data
    frames.clear_registry()


def bits(a):
    return np.ascontiguousarray(a).view(np.uint64)


@pytest.mark.parametrize("max_angle", [None, 50.0, 20.0])
def test_yaw_in_one_pass_is_the_gaze_calls_yaw(registered, max_angle):
    _, left, right = registered
    names = [explorer.EXAMPLE_FRAMES.eye(e) for e in explorer.EYES]
    fast = explorer_yaw.yaw_columns(
        [left, right], names, "head", explorer.MIN_CONFIDENCE, max_angle
    )
    assert fast is not None
    got = explorer.gaze_yaw(left, right, max_angle=max_angle)
    want = explorer._yaw_by_angles(left, right, LABELS, got.attrs, max_angle,
                                   explorer.EXAMPLE_FRAMES)  # fmt: skip
    assert got.identical(want)
    np.testing.assert_array_equal(bits(got.values), bits(want.values))
    assert np.isnan(got.values).any() and np.isfinite(got.values).any()
    # the time index is the recording's own, not a copy
    assert got.indexes["time"] is left.indexes["time"]


def test_yaw_steps_aside_where_the_route_does_not_apply(registered):
    _, left, right = registered
    names = [explorer.EXAMPLE_FRAMES.eye(e) for e in explorer.EYES]
    conf = explorer.MIN_CONFIDENCE
    # a moving frame between the eyes' parent and the reference
    assert explorer_yaw.yaw_columns([left, right], names, "world", conf, 50.0) is None
    # no confidence, a bad max_angle (the gaze calls word the error)
    no_conf = left.drop_vars("confidence")
    assert explorer_yaw.yaw_columns([no_conf, right], names, "head", conf, 50.0) is None
    assert explorer_yaw.yaw_columns([left, right], names, "head", conf, 200.0) is None
    with pytest.raises(ValueError, match="max_angle"):
        explorer.gaze_yaw(left, right, max_angle=200.0)
    # eyes on two clocks
    shifted = right.assign_coords(time=right.time + np.timedelta64(1, "ms"))
    assert explorer_yaw.yaw_columns([left, shifted], names, "head", conf, 50.0) is None


def test_eye_centres_are_the_lookups_medians(registered):
    got = explorer.eye_centres()
    for eye in explorer.EYES:
        translation, _ = lookup_transform(explorer.EXAMPLE_FRAMES.eye(eye), "head")
        want = np.nanmedian(translation, axis=0)
        np.testing.assert_array_equal(bits(got[eye]), bits(want))
    # through a moving frame: the lookup's route, the same answer
    moving = explorer.eye_centres(head="world")
    for eye in explorer.EYES:
        translation, _ = lookup_transform(explorer.EXAMPLE_FRAMES.eye(eye), "world")
        np.testing.assert_array_equal(moving[eye], np.nanmedian(translation, axis=0))


def test_kept_translations_are_the_lookups_kept_rows(registered):
    kept = explorer._kept_translations("pupil/left_eye", "head")
    translation, _ = lookup_transform("pupil/left_eye", "head")
    rows = ~np.isnan(translation).any(axis=1)
    assert kept is not None and kept.shape == (3, rows.sum())
    np.testing.assert_array_equal(bits(kept.T), bits(translation[rows]))
    assert explorer._kept_translations("pupil/left_eye", "world") is None
