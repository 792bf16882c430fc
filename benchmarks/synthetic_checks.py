"""Physical checks of the synthetic head/eye recording, printed as a table.

    .venv/bin/python benchmarks/synthetic_checks.py [--duration 330] [--seed 0]

Every number is measured from the generated datasets the way one would
analyse a real recording (rbm_nb.data._measures); the right-hand column says
what a person walking around a building produces.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rbm_nb.data import _measures as measures
from rbm_nb.data import synthetic_head_eye


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=330.0)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    synthetic_head_eye(duration=20.0, seed=args.seed)  # compile the kernels once
    t0 = time.perf_counter()
    rec = synthetic_head_eye(duration=args.duration, seed=args.seed)
    elapsed = time.perf_counter() - t0
    head, left, right = rec

    v_head = measures.head_frame_velocity(head)
    bob_freq, bob_rms = measures.bob(head)
    lin_rms, ang_rms = measures.estimator_consistency(head)
    lin_scale = np.sqrt(np.mean(np.sum(head.linear_velocity.values**2, axis=1)))
    ang_scale = np.sqrt(np.mean(np.sum(head.angular_velocity.values**2, axis=1)))
    s_left, s_right = measures.saccades(left, head), measures.saccades(right, head)
    closure = np.linalg.norm(head.position.values[-1] - head.position.values[0])

    rows = [
        ("head samples", f"{head.sizes['time']}", "66,629 in the real head.nc"),
        (
            "eye samples (left, right)",
            f"{left.sizes['time']}, {right.sizes['time']}",
            "~113,000",
        ),
        ("generation time (s, warm)", f"{elapsed:.2f}", "well under a few s"),
        (
            "lap length (m), closure (m)",
            f"{head.attrs['lap_length']:.1f}, {closure:.2f}",
            "two laps, back at the start",
        ),
        (
            "mean walking speed (m/s)",
            f"{measures.mean_walking_speed(head):.3f}",
            "~1.4",
        ),
        (
            "mean velocity in head frame x, y, z (m/s)",
            ", ".join(f"{x:+.3f}" for x in v_head),
            "z ~ -1.4 (guide 1.5)",
        ),
        ("head bob frequency (Hz)", f"{bob_freq:.3f}", "step frequency 1.8-2.0"),
        ("head bob RMS (cm)", f"{100 * bob_rms:.2f}", "a few cm"),
        ("saccade rate (1/s, left)", f"{s_left['rate']:.2f}", "2-4 while walking"),
        ("saccade amplitude median (deg)", f"{s_left['amplitude_median']:.1f}", "5-20"),
        (
            "saccade peak velocity median / p95 / max (deg/s)",
            f"{s_left['peak_median']:.0f} / {s_left['peak_p95']:.0f} / {s_left['peak_max']:.0f}",
            "several hundred",
        ),
        (
            "main sequence corr(amplitude, peak)",
            f"{s_left['peak_amplitude_correlation']:.2f}",
            "strongly positive",
        ),
        (
            "saccades left / right",
            f"{s_left['count']} / {s_right['count']}",
            "same plan for both eyes",
        ),
        (
            "VOR gain (left, right)",
            f"{measures.vor_gain(left, head):.3f}, {measures.vor_gain(right, head):.3f}",
            "~1 for distant targets",
        ),
        (
            "blink fraction (confidence < 0.5)",
            f"{measures.blink_fraction(left):.3f}, {measures.blink_fraction(right):.3f}",
            "0.02-0.05",
        ),
        (
            "RMS |v - estimate_linear_velocity| (m/s)",
            f"{lin_rms:.2e} ({lin_rms / lin_scale:.1e} rel.)",
            "finite-difference error only",
        ),
        (
            "RMS |w - estimate_angular_velocity| (rad/s)",
            f"{ang_rms:.2e} ({ang_rms / ang_scale:.1e} rel.)",
            "finite-difference error only",
        ),
    ]
    width = [max(len(r[i]) for r in rows) for i in range(3)]
    print(f"synthetic_head_eye(duration={args.duration}, seed={args.seed})")
    for name, value, expected in rows:
        print(f"{name:<{width[0]}}  {value:>{width[1]}}  {expected}")


if __name__ == "__main__":
    main()
