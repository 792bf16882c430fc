"""How much of a recording with missing samples survives each operation.

For each eye of the head/eye recording: the fraction of rows that are
missing in the recording itself (NaN rows of the eye's orientation), and
the fraction of NaN rows in the result of each frame-core operation, for
rbm_nb and for rigid-body-motion 0.9.3 (the reference) in the same run, on
the same frame tree:

    world -> head (the T265's pose, 200 Hz)
          -> scene_cam (static mount)
          -> left_eye / right_eye (the eye's orientation, ~340 Hz, NaN rows)

A result row counts as missing when any of its numbers is NaN. The rows
that *must* be missing are those whose own samples are: at an eye's own
timestamps that is the raw fraction; on the head's clock it is the
head-clock instants that do not lie between (or on) two valid eye samples.

Run with the real files (``RBM_NB_DATA_DIR`` pointing at a folder with
head.nc, left_eye.nc and right_eye.nc)::

    RBM_NB_DATA_DIR=../shared/data/rbm-data .venv/bin/python benchmarks/bench_missing.py

Without them the synthetic recording is used, and the script says so.
``--markdown`` prints the table as markdown (the README's).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

warnings.filterwarnings("ignore")

EYES = ("left_eye", "right_eye")
SIGHT = np.array([0.0, 0.0, 1.0])  # the eye frame's line of sight (z)


def load_recording():
    """(head, left_eye, right_eye, label): the real files when they can be had."""
    folder = os.environ.get("RBM_NB_DATA_DIR")
    if folder and all((Path(folder) / f"{n}.nc").is_file() for n in ("head", *EYES)):
        datasets = [xr.load_dataset(Path(folder) / f"{n}.nc") for n in ("head", *EYES)]
        return (*datasets, f"the real recording ({folder})")
    from rbm_nb.data.synthetic import synthetic_head_eye

    head, left, right = synthetic_head_eye(seed=0)
    return (
        head,
        left,
        right,
        "the synthetic recording (RBM_NB_DATA_DIR has no real files)",
    )


def register(m, head, eyes):
    """The frame tree above, in module ``m`` (rbm_nb or rigid_body_motion)."""
    m.clear_registry()
    m.register_frame("world")
    m.ReferenceFrame.from_dataset(
        head, "position", "orientation", "time", parent="world", name="head"
    ).register()
    m.register_frame(
        "scene_cam",
        parent="head",
        translation=(0.0, 0.05, 0.08),
        rotation=(0.5, -0.5, 0.5, -0.5),
    )
    for name, eye in eyes.items():
        m.ReferenceFrame.from_dataset(
            eye, "position", "orientation", "time", parent="scene_cam", name=name
        ).register()


def nan_rows(*arrays) -> np.ndarray:
    out = None
    for a in arrays:
        a = np.asarray(a, dtype=float)
        rows = np.isnan(a.reshape(len(a), -1)).any(axis=1)
        out = rows if out is None else out | rows
    return out


def operations(eye_name, eye, head):
    """(label, function of the module -> boolean NaN rows) for one eye."""
    eye_times = eye.time.values
    head_times = head.time.values
    inside = (head_times >= eye_times[0]) & (head_times <= eye_times[-1])
    head_clock = head_times[inside]

    def own_parent(m):
        t, r = m.lookup_transform(eye_name, "scene_cam")
        return nan_rows(t, r)

    def own_world(m):
        t, r = m.lookup_transform(eye_name, "world")
        return nan_rows(t, r)

    def sight_world(m):
        v = np.broadcast_to(SIGHT, (len(eye_times), 3))
        return nan_rows(
            m.transform_vectors(v, outof=eye_name, into="world", timestamps=eye_times)
        )

    def head_clock_world(m):
        v = np.broadcast_to(SIGHT, (len(head_clock), 3))
        return nan_rows(
            m.transform_vectors(v, outof=eye_name, into="world", timestamps=head_clock)
        )

    def angular_velocity(m):
        return nan_rows(m.lookup_angular_velocity(eye_name, "scene_cam"))

    def dropped_rows(m):
        # the recipe of docs/missing_data.md: the eye on its own samples only
        # (NaN rows dropped), never interpolated across more than 0.1 s
        if m.__name__ != "rbm_nb":
            return None  # (the reference has no max_gap)
        m.ReferenceFrame.from_dataset(
            eye.dropna("time"),
            "position",
            "orientation",
            "time",
            parent="scene_cam",
            name="eye_dropna",
            max_gap=0.1,
        ).register()
        v = np.broadcast_to(SIGHT, (len(head_clock), 3))
        return nan_rows(
            m.transform_vectors(
                v, outof="eye_dropna", into="world", timestamps=head_clock
            )
        )

    return [
        (f"{eye_name} → scene_cam at its own times", own_parent),
        (f"{eye_name} → world at its own times", own_world),
        ("line of sight in world, own times", sight_world),
        ("line of sight in world, head clock", head_clock_world),
        (f"angular velocity of {eye_name} in scene_cam", angular_velocity),
        ("line of sight, head clock, NaN rows dropped, max_gap 0.1 s", dropped_rows),
    ], head_clock


def needed(eye, head_clock) -> tuple[float, float, float]:
    """Missing fractions that the samples themselves force: at the eye's own
    times; on the head clock (instants not on or between two valid
    consecutive samples); and for a velocity at the eye's own times (a
    missing sample, or a present one with no present neighbour: a
    derivative needs two samples)."""
    missing = nan_rows(eye.orientation.values)
    t = eye.time.values
    i = np.searchsorted(t, head_clock, side="right") - 1
    i = np.clip(i, 0, len(t) - 1)
    on_sample = t[i] == head_clock
    j = np.clip(i + 1, 0, len(t) - 1)
    ok = ~missing[i] & (on_sample | ~missing[j])
    present = ~missing
    paired = np.zeros_like(present)
    paired[1:] |= present[:-1]
    paired[:-1] |= present[1:]
    alone = present & ~paired
    return missing.mean(), 1.0 - ok.mean(), (missing | alone).mean()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--markdown", action="store_true", help="print a markdown table"
    )
    parser.add_argument(
        "--no-reference", action="store_true", help="rbm_nb only (no rigid-body-motion)"
    )
    args = parser.parse_args()

    import rbm_nb

    modules = {"rbm_nb": rbm_nb}
    if not args.no_reference:
        try:
            import rigid_body_motion
        except ImportError:
            print("rigid-body-motion is not installed: rbm_nb only", file=sys.stderr)
        else:
            modules["rigid-body-motion 0.9.3"] = rigid_body_motion

    head, left, right, label = load_recording()
    eyes = {"left_eye": left, "right_eye": right}
    print(f"data: {label}\n")
    rows = []
    for name, eye in eyes.items():
        ops, head_clock = operations(name, eye, head)
        raw, clock_floor, velocity_floor = needed(eye, head_clock)
        rows.append((f"{name}: missing in the recording", [raw] * len(modules), None))
        floor = {0: raw, 1: raw, 2: raw, 3: clock_floor, 4: velocity_floor}
        for k, (what, op) in enumerate(ops):
            values = []
            for m in modules.values():
                register(m, head, eyes)
                rows_nan = op(m)
                values.append(math.nan if rows_nan is None else float(rows_nan.mean()))
            rows.append((what, values, floor.get(k)))
    names = list(modules)
    if args.markdown:
        print("| operation | " + " | ".join(names) + " | forced by the samples |")
        print("|---|" + "---:|" * (len(names) + 1))
        for what, values, floor in rows:
            cells = " | ".join(
                "–" if math.isnan(v) else f"{100 * v:.1f} %" for v in values
            )
            f = "" if floor is None else f"{100 * floor:.1f} %"
            print(f"| {what} | {cells} | {f} |")
    else:
        width = max(len(w) for w, _, _ in rows)
        print(f"{'':{width}}  " + "  ".join(f"{n:>24}" for n in names) + "  forced")
        for what, values, floor in rows:
            cells = "  ".join(
                f"{'–':>24}" if math.isnan(v) else f"{100 * v:23.1f}%" for v in values
            )
            f = "" if floor is None else f"{100 * floor:5.1f}%"
            print(f"{what:{width}}  {cells}  {f}")


if __name__ == "__main__":
    main()
