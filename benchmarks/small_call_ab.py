"""Small calls (issue 32, item 8) in this tree against another checkout, in turns.

Each round starts one fresh process per tree (alternating, so that both see
the machine's load alike) that times, best of 7 ``timeit`` repeats after a
warm-up call:

* ``transform_points`` of one point (shape (3,)) through a static chain of
  three frames (``bench_small_call.py``'s), and of one point wrt
  ``t265/world`` -> ``world`` on ``bench_core.py``'s workload;
* a one-time ``lookup_transform`` left_eye -> world through the real
  head/eye recording (``bench_fused.py``'s frames; needs RBM_NB_DATA_DIR),
  at a time between two eye samples.

Prints, per call, the min and median over rounds of each tree's best time
(µs) and the median of the per-round ratios (this tree / other).

Run: ``RBM_NB_DATA_DIR=... .venv/bin/python benchmarks/small_call_ab.py OTHER_TREE [--rounds 5]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, os, sys, timeit, warnings
warnings.filterwarnings("ignore")
sys.path.insert(0, {benchmarks!r})
import numpy as np
import rbm_nb as rbm

def best(fn, number):
    fn()
    return min(timeit.repeat(fn, number=number, repeat=7)) / number * 1e6

out = {{}}
rbm.clear_registry()
rbm.register_frame("world")
rbm.register_frame("head", parent="world", translation=(0.1, 0.2, 1.7),
                   rotation=(np.cos(0.2), 0.0, 0.0, np.sin(0.2)))
rbm.register_frame("eye", parent="head", translation=(0.03, 0.0, 0.05),
                   rotation=(np.cos(0.1), np.sin(0.1), 0.0, 0.0))
point = np.array([0.0, 0.0, 1.0])
out["transform_points 1 point, static eye -> world"] = best(
    lambda: rbm.transform_points(point, "world", "eye"), 5000)

import bench_core
frames = bench_core.build_workload()[0]
rbm.clear_registry()
for name, kwargs in frames:
    rbm.register_frame(name, **kwargs)
out["transform_points 1 point, static t265/world -> world (bench_core)"] = best(
    lambda: rbm.transform_points(point, "world", "t265/world"), 5000)

from bench_fused import real_workload, register
real = real_workload()
if real is not None:
    frames, _, eye_ts = real[:3]
    register(rbm, frames)
    step = eye_ts[1] - eye_ts[0]
    when = eye_ts[len(eye_ts) // 2] + step / 3
    out["lookup_transform left_eye -> world at one time (real recording)"] = best(
        lambda: rbm.lookup_transform("left_eye", "world", time=when), 500)
print(json.dumps(out))
"""


def _run(tree: Path) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=str(tree), RBM_NB_NUM_THREADS="1")
    code = CHILD.format(benchmarks=str(tree / "benchmarks"))
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True,
        check=True, cwd=tree,
    )  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("other", type=Path, help="another checkout of the repository")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    mine: list[dict[str, float]] = []
    theirs: list[dict[str, float]] = []
    for _ in range(args.rounds):
        mine.append(_run(REPO))
        theirs.append(_run(args.other.resolve()))
    print(f"this tree: {REPO}; other: {args.other.resolve()}; {args.rounds} rounds")
    print(f"{'call':<68} {'this min/med':>14} {'other min/med':>14} {'ratio':>6}")
    for name in mine[0]:
        a = [m[name] for m in mine]
        b = [t[name] for t in theirs]
        ratio = statistics.median(x / y for x, y in zip(a, b, strict=True))
        print(
            f"{name:<68} {min(a):6.1f}/{statistics.median(a):<6.1f} "
            f"{min(b):6.1f}/{statistics.median(b):<6.1f} {ratio:6.2f}"
        )


if __name__ == "__main__":
    main()
