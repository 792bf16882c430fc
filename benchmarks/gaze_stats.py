"""Gaze statistics of the head/eye recording before and after rbm_nb.gaze.

Before: every non-NaN eye sample drawn as gaze (what the explorer did, via
``explorer.gaze_angles`` on ``dropna`` data). After: ``gaze.directions`` with
the recording's confidence (threshold 0.6) and ``gaze.angles`` in the scene
camera. Prints, per eye, the largest azimuth/elevation and eccentricity (angle
from the camera's forward axis), the fraction of drawn samples beyond 60 deg,
and the fraction of samples dropped by confidence.

Run with the real files: ``RBM_NB_DATA_DIR=/path/to/rbm-data python benchmarks/gaze_stats.py``
(without them the synthetic recording is used and the script says so).
"""

from __future__ import annotations

import numpy as np

import rbm_nb as rbm
from rbm_nb.app import explorer
from rbm_nb.core import gaze


def _stats(label: str, ang: np.ndarray, eccentricity: np.ndarray) -> None:
    print(
        f"  {label:6s} drawn {len(ecc := eccentricity):6d}  "
        f"max |azimuth| {np.max(np.abs(ang[:, 0])):6.1f}  "
        f"max |elevation| {np.max(np.abs(ang[:, 1])):5.1f}  "
        f"max eccentricity {np.max(ecc):6.1f} deg  "
        f"> 60 deg: {100 * np.mean(ecc > 60):.3f} %"
    )


def main() -> None:
    head, left, right, note = explorer.load_head_eye("auto")
    print(f"recording: {note}")
    explorer.register_head_eye_frames(head, left, right)
    for name, eye in (("left_eye", left), ("right_eye", right)):
        n = eye.sizes["time"]
        missing = eye.orientation.isnull().any("quaternion_axis").values
        print(
            f"{name}: {n} samples, {missing.sum()} NaN rows ({100 * missing.mean():.1f} %)"
        )
        before = explorer.gaze_angles(eye).values
        # eccentricity from azimuth/elevation: cos = cos(az) cos(el)
        ecc_before = np.degrees(
            np.arccos(
                np.cos(np.radians(before[:, 0])) * np.cos(np.radians(before[:, 1]))
            )
        )
        _stats("before", before, ecc_before)
        sight = gaze.directions(
            f"pupil/{name}", "pupil/scene_cam", confidence=eye.confidence
        )
        after = gaze.angles(sight, "pupil/scene_cam").values
        drawn = np.isfinite(after).all(axis=1)
        ecc_after = np.degrees(np.arccos(np.clip(sight.values[drawn, 2], -1.0, 1.0)))
        _stats("after", after[drawn], ecc_after)
        low = (~missing) & ~(eye.confidence.values >= 0.6)
        print(
            f"  dropped by confidence < 0.6: {low.sum()} of {n} samples "
            f"({100 * low.mean():.1f} %; {100 * low.sum() / (~missing).sum():.1f} % of the non-NaN ones)"
        )
    rbm.clear_registry()


if __name__ == "__main__":
    main()
