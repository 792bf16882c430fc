"""Physical checks of the synthetic head/eye recording, printed as a table.

    .venv/bin/python benchmarks/synthetic_checks.py [--duration 330] [--seed 0]

Every number is measured from the generated datasets the way one would
analyse a real recording (rbm_nb.data._measures); the right-hand column says
what a person walking around a building produces. The eye tracker's flaws
(NaN rows, low confidence, dropouts) are compared with the real recording,
measured live when ``RBM_NB_DATA_DIR`` holds it (else the numbers measured on
it once are shown).
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
            "blink fraction (no data, confidence < 0.1)",
            f"{measures.blink_fraction(left):.3f}, {measures.blink_fraction(right):.3f}",
            "0.02-0.05",
        ),
        *_tracker_rows(left, right),
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


def _real_eyes():
    from rbm_nb.data import example_data
    from rbm_nb.io import load_netcdf

    if not all(example_data.is_available(n) for n in ("left_eye", "right_eye")):
        return None
    return load_netcdf(example_data.path("left_eye")), load_netcdf(
        example_data.path("right_eye")
    )


# measured on the real left_eye.nc / right_eye.nc (left, right)
_REAL_TEXT = {
    "rows": "113373, 113373",
    "median_interval": "2.503, 2.503",
    "nan_rows": "36844, 35236",
    "low_confidence": "0.305, 0.332",
    "gaps_over_0.1s": "3, 3",
}


def _tracker_rows(left, right):
    real = _real_eyes()
    rows = []
    for key, label, fmt in (
        ("rows", "eye rows", "{:d}"),
        ("median_interval", "eye clock median interval (ms)", "{:.3f}"),
        ("nan_rows", "NaN orientation rows", "{:d}"),
        ("low_confidence", "confidence < 0.6 (rows with data)", "{:.3f}"),
        ("gaps_over_0.1s", "dropouts > 0.1 s", "{:d}"),
    ):
        scale = 1e3 if key == "median_interval" else 1

        def value(eye, key=key, fmt=fmt, scale=scale):
            v = measures.tracker_quality(eye)[key]
            return fmt.format(v * scale if scale != 1 else v)

        ours = f"{value(left)}, {value(right)}"
        theirs = (
            f"{value(real[0])}, {value(real[1])} (real, measured now)"
            if real is not None
            else f"{_REAL_TEXT[key]} (real)"
        )
        rows.append((label, ours, theirs))
    return rows


if __name__ == "__main__":
    main()
