"""The synthetic recording misses eye samples the way the real one does (issue 28, item 6).

Measured with one function on both: the rows where only this eye has no
orientation (the other eye's monocular rows of the gaze mapper, a lost
pupil), the rows where both have none (blinks, both pupils lost), and the
lengths of those runs of rows. On the real file: left 32.5 % missing, 27.1 %
for the left eye alone, 5.4 % for both, runs of median length 1.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.recordings import real_recording


def missing_pattern(left, right) -> dict:
    """Fractions of rows and run lengths of missing samples, per eye and for both."""
    np.testing.assert_array_equal(left.time.values, right.time.values)
    gone = {
        "left": left.orientation.isnull().any("quaternion_axis").values,
        "right": right.orientation.isnull().any("quaternion_axis").values,
    }
    both = gone["left"] & gone["right"]
    out = {"both": both.mean(), "both_runs": _runs(both)}
    for eye, other in (("left", "right"), ("right", "left")):
        alone = gone[eye] & ~gone[other]
        out[eye] = gone[eye].mean()
        out[f"{eye}_alone"] = alone.mean()
        out[f"{eye}_alone_runs"] = _runs(alone)
    return out


def _runs(mask) -> np.ndarray:
    edges = np.diff(np.r_[0, mask.astype(int), 0])
    return np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)


@pytest.fixture(scope="module")
def synthetic():
    from rbm_nb.data.synthetic import synthetic_head_eye

    return synthetic_head_eye(seed=0)


def test_synthetic_misses_samples_like_the_real_recording(synthetic):
    real = real_recording()
    if real is None:
        pytest.skip("no real data")
    ours = missing_pattern(synthetic.left_eye, synthetic.right_eye)
    theirs = missing_pattern(real[1], real[2])
    print({k: round(float(v), 4) for k, v in theirs.items() if not k.endswith("runs")})
    print({k: round(float(v), 4) for k, v in ours.items() if not k.endswith("runs")})
    for key in ("left", "right", "left_alone", "right_alone"):
        assert abs(ours[key] - theirs[key]) < 0.015, key
    assert abs(ours["both"] - theirs["both"]) < 0.005
    for key in ("both_runs", "left_alone_runs", "right_alone_runs"):
        assert np.median(ours[key]) == np.median(theirs[key]) == 1, key
        assert (
            abs(np.percentile(ours[key], 95) - np.percentile(theirs[key], 95)) <= 1
        ), key
        # blinks: a few runs of tens of rows with neither eye
        if key == "both_runs":
            assert ours[key].max() > 20 and theirs[key].max() > 20
