"""What the notebooks say in words holds on the data they print from.

The notebooks print their numbers from the data; their sentences make claims
that must be true whichever recording they get (real, or synthetic when the
real one cannot be had). Each claim is checked here on both, and the claims
of notebook 03 (synthetic point clouds) on the clouds it builds.
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
    # "a little below the median speed ... part of the walking velocity lies
    # along +y ... the sideways sway along x averages out"
    speed = np.linalg.norm(head.linear_velocity.values, axis=1)
    assert 0.8 * np.median(speed) < abs(mean[2]) < np.median(speed)
    assert mean[1] > 0.05 and abs(mean[0]) < mean[1]


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


def test_missing_eye_rows_are_mostly_one_eye_single_samples(source):
    """'only the rows missing in both eyes can be blinks ... how few they are.
    Most of the left eye's missing rows are missing for that eye only, one
    sample at a time'."""
    left, right = source[1], source[2]
    assert np.array_equal(left.time.values, right.time.values)
    missing = left.orientation.isnull().any("quaternion_axis").values
    both = missing & right.orientation.isnull().any("quaternion_axis").values
    assert both.mean() < 0.1 and (missing & ~both).mean() > 3 * both.mean()
    steps = np.diff(np.r_[0, missing.astype(int), 0])
    runs = np.flatnonzero(steps == -1) - np.flatnonzero(steps == 1)
    assert np.median(runs) == 1


def _icp_turn_error(stretch, start_from_centroids=True):
    """Notebook 03's ICP run: the blob of 100 points, turned 45 deg about z."""
    rng = np.random.default_rng(0)
    p1 = 0.1 * rng.standard_normal((100, 3)) * np.asarray(stretch, dtype=float)
    t = np.array((1.0, 1.0, 0.0))
    r = rbm.from_euler_angles(yaw=np.pi / 4)
    p2 = rng.permutation(rbm.rotate_vectors(r, p1, one_to_one=False) + t)
    start = (p2.mean(axis=0) - p1.mean(axis=0), np.array((1.0, 0.0, 0.0, 0.0)))
    _, r_icp = rbm.iterative_closest_point(
        p1, p2, init_transform=start if start_from_centroids else None
    )
    w = abs(float(np.asarray(rbm.qmul(rbm.qinv(r), r_icp))[0]))
    return np.degrees(2 * np.arccos(min(w, 1.0)))


@pytest.mark.parametrize(
    "stretch, recovered",
    [
        ((3, 1, 0.2), True),
        ((3, 1, 1), True),
        ((1, 2, 3), True),
        ((5, 2, 1), True),
        ((1, 1, 1), False),
        ((1, 1, 3), False),
        ((2, 2, 0.5), False),
        ((2, 1, 0.5), False),
    ],
)
def test_icp_verdicts_of_notebook_03(stretch, recovered):
    """The solution of exercise 4: which stretched blobs ICP recovers within 1 deg."""
    assert (_icp_turn_error(stretch) < 1.0) == recovered


def test_icp_fails_on_the_blob_without_a_start():
    """'The first run failed' (default tolerance, no initial guess)."""
    assert _icp_turn_error((1, 1, 1), start_from_centroids=False) > 5.0
