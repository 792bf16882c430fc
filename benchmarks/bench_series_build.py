"""The series' and the frames' share of the explorer dashboard's build (issue 35).

    RBM_NB_DATA_DIR=... python benchmarks/bench_series_build.py --hours 0 1 3 [--compare /work/main]

Times, on the real head/eye recording tiled in time (``tiled_recording``),
the three parts of :func:`rbm_nb.explorer.dashboard` outside the scene that
walk every sample: registering the frames (``register_head_eye_frames``:
the eyes' missing-row masks), the plotted series (``explorer_series``: gaze
directions, angles and rates) and the head model's eye centres
(``eye_centres``). Best of ``--repeat`` runs, each in a fresh process per
tree (``--compare`` runs the same parts with another checkout's rbm_nb,
first, and prints the ratios: this tree / other). It also checks that both
trees give the same series, bit for bit (or prints the largest difference).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
PARTS = ("register", "series", "eye_centres")

_CHILD = r"""
import json, sys, time, hashlib
import numpy as np
sys.path.insert(0, {bench!r})
from tiled_recording import tiled_head_eye
from rbm_nb import explorer
hours, repeat = {hours!r}, {repeat!r}
head, left, right = tiled_head_eye(0)
explorer.register_head_eye_frames(head, left, right)  # warm: compile, caches
explorer.explorer_series(head, left, right); explorer.eye_centres()
head, left, right = tiled_head_eye(hours)
best = dict.fromkeys({parts!r}, float("inf"))
for _ in range(repeat):
    t0 = time.perf_counter(); explorer.register_head_eye_frames(head, left, right)
    t1 = time.perf_counter(); series = explorer.explorer_series(head, left, right)
    t2 = time.perf_counter(); centres = explorer.eye_centres()
    t3 = time.perf_counter()
    for key, dt in zip(best, (t1 - t0, t2 - t1, t3 - t2)):
        best[key] = min(best[key], dt)
    if _ + 1 < repeat:
        del series
digests = {{}}
arrays = {{**{{k: v.values for k, v in series.items()}},
          **{{"centre " + k: v for k, v in centres.items()}}}}
for key, values in arrays.items():
    values = np.ascontiguousarray(values)
    digests[key] = [values.shape, hashlib.sha256(values.tobytes()).hexdigest()]
np.savez({dump!r}, **arrays)
print(json.dumps({{"times": best, "digests": digests, "samples": int(left.sizes["time"])}}))
"""


def run(tree: Path, hours: float, repeat: int, dump: str) -> dict:
    code = _CHILD.format(
        bench=str(HERE), hours=hours, repeat=repeat, parts=PARTS, dump=dump
    )
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, check=True, capture_output=True,
        text=True, cwd=tree,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def largest_difference(a: str, b: str) -> dict:
    import numpy as np

    with np.load(a) as fa, np.load(b) as fb:
        out = {}
        for key in fa.files:
            x, y = fa[key], fb[key]
            if x.shape != y.shape:
                out[key] = f"shapes {x.shape} vs {y.shape}"
                continue
            same_nan = np.array_equal(np.isnan(x), np.isnan(y))
            diff = np.nanmax(np.abs(x - y)) if np.isfinite(x).any() else 0.0
            out[key] = f"max |diff| {diff:.3g}, NaN rows same: {same_nan}"
        return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[0.0, 1.0, 3.0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--compare", type=Path, default=None)
    args = parser.parse_args()
    this = HERE.parent
    for hours in args.hours:
        mine = run(this, hours, args.repeat, "/tmp/series_this.npz")
        line = f"{hours:g} h ({mine['samples']} eye samples): " + ", ".join(
            f"{k} {v:.3f} s" for k, v in mine["times"].items()
        )
        total = sum(mine["times"].values())
        line += f"; total {total:.3f} s"
        if args.compare is not None:
            other = run(args.compare, hours, args.repeat, "/tmp/series_other.npz")
            base = sum(other["times"].values())
            line += f" | other tree: total {base:.3f} s (" + ", ".join(
                f"{k} {v:.3f}" for k, v in other["times"].items()
            )
            line += f"); ratio this/other {total / base:.2f}"
            same = mine["digests"] == other["digests"]
            line += f"\n   series and eye centres bit for bit: {same}"
            if not same:
                diffs = largest_difference(
                    "/tmp/series_this.npz", "/tmp/series_other.npz"
                )
                line += "".join(f"\n   {k}: {v}" for k, v in diffs.items())
        print(line, flush=True)


if __name__ == "__main__":
    main()
