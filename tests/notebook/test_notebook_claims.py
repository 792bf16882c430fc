"""What notebook 04 says about the head/eye recording holds on both sources.

The notebook prints its numbers from the data; its sentences make claims
that must be true whichever recording it gets (real, or synthetic when the
real one cannot be had). Each claim is checked here on both.
"""

from __future__ import annotations

import numpy as np
import pytest
from recordings import real_recording, synthetic_recording

import rbm_nb as rbm


@pytest.fixture(params=["real", "synthetic"])
def source(request):
    if request.param == "real":
        real = real_recording()
        if real is None:
            pytest.skip("the real recordings are not beside the repo")
        return real
    return synthetic_recording(330.0)


def test_walking_is_negative_z_in_the_head_frame(source):
    """'a steady negative velocity along z, the largest of the three means'."""
    head = source[0]
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_dataset(
        head, "position", "orientation", "time", parent="world", name="head"
    ).register()
    v_head = rbm.transform_linear_velocity(
        head.linear_velocity, outof="world", into="head", what="representation_frame"
    )
    mean = v_head.mean("time").values
    assert mean[2] < -0.5 and np.argmax(np.abs(mean)) == 2
    # "a little below the walking speed": standing at both ends lowers the mean
    speed = np.linalg.norm(head.linear_velocity.values, axis=1)
    assert abs(mean[2]) < np.median(speed[speed > 0.5])


def test_eyes_sample_at_another_rate_and_have_missing_samples(source):
    """'samples at a different rate'; NaN rows; confidence below 0.6; gaps."""
    head, left = source[0], source[1]

    def median_dt(ds):
        return np.median(np.diff(ds.time.values) / np.timedelta64(1, "s"))

    assert abs(median_dt(left) / median_dt(head) - 1) > 0.2
    missing = left.orientation.isnull().any("quaternion_axis")
    low = (left.confidence < 0.6) & ~missing
    assert 0.1 < float(missing.mean()) < 0.5 and 0.1 < float(low.mean()) < 0.5
    assert int((left.time.diff("time") > np.timedelta64(100, "ms")).sum()) >= 1
    # qinterp onto the eye's times works although the eye rows have NaN
    out = head.orientation.rbm.qinterp(time=left.time)
    assert out.sizes["time"] == left.sizes["time"]
