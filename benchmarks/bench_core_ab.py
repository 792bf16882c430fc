"""rbm_nb against another checkout of itself on bench_core.py's workload.

Times the frame-core calls of ``bench_core.py`` (rbm_nb only, one thread) in
two source trees, in alternating fresh processes, and prints the best time of
each and their ratio: what a change to the kernels cost on NaN-free data.

Run:  .venv/bin/python benchmarks/bench_core_ab.py OTHER_TREE [--rounds 4]

``OTHER_TREE`` is another checkout of the repository (e.g. ``git worktree add
../before HEAD~5``); each tree's own numba cache is used, so warm both first.
"""

from __future__ import annotations

import argparse
import collections
import os
import statistics
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

CHILD = """
import os, sys, time
os.environ["RBM_NB_NUM_THREADS"] = "1"
sys.path.insert(0, {benchmarks!r})
import bench_core
import rbm_nb as rbm
frames, head_ts, eye_ts, head_rot, gaze = bench_core.build_workload()
rbm.clear_registry()
for name, kwargs in frames:
    rbm.register_frame(name, **kwargs)
ops = {{
    "lookup_transform left_eye->world": lambda: rbm.lookup_transform("left_eye", "world"),
    "lookup_pose left_eye wrt world": lambda: rbm.lookup_pose("left_eye", "world"),
    "transform_points (eye times)": lambda: rbm.transform_points(
        gaze, "world", "left_eye", timestamps=eye_ts),
    "transform_vectors (head times)": lambda: rbm.transform_vectors(
        gaze[:66_629], "world", "left_eye", timestamps=head_ts),
    "lookup_twist head wrt world": lambda: rbm.lookup_twist("head", "world"),
    "lookup_angular_velocity left_eye": lambda: rbm.lookup_angular_velocity(
        "left_eye", "world"),
}}
for label, call in ops.items():
    call()
    times = []
    for _ in range(15):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    print(f"{{label}}\\t{{min(times) * 1e3:.4f}}")
"""


def run(tree: Path, child: str = CHILD) -> dict[str, float]:
    """One fresh process in ``tree`` running ``child``: label -> best time."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    code = child.format(benchmarks=str(REPO / "benchmarks"))
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tree, env=env, capture_output=True,
        text=True, check=True,
    ).stdout  # fmt: skip
    return {k: float(v) for k, v in (line.split("\t") for line in out.splitlines())}


def compare(
    description: str, child: str = CHILD, header: str = "call", unit: str = " ms"
) -> None:
    """Parse OTHER_TREE/--rounds, run ``child`` in both trees in turns, print ratios.

    Per call: the best time of each tree over all rounds and their ratio
    (``min``), and the ratio of the trees' median round (``median``: each
    round's value is that process's best), which a machine shared with
    other jobs moves less than a single lucky round.
    """
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("other", type=Path, help="another checkout of the repository")
    parser.add_argument("--rounds", type=int, default=4)
    args = parser.parse_args()
    rounds: dict[str, dict[str, list[float]]] = collections.defaultdict(
        lambda: collections.defaultdict(list)
    )
    for _ in range(args.rounds):
        for name, tree in (("other", args.other.resolve()), ("this", REPO)):
            for label, value in run(tree, child).items():
                rounds[label][name].append(value)
    print(f"{header:40s} {'other':>11s} {'this':>11s}  this/other (min, median)")
    for label, d in rounds.items():
        other, this = min(d["other"]), min(d["this"])
        median = statistics.median(d["this"]) / statistics.median(d["other"])
        print(
            f"{label:40s} {other:8.3f}{unit} {this:8.3f}{unit}"
            f"  {this / other:.3f}  {median:.3f}"
        )


if __name__ == "__main__":
    compare(__doc__.split("\n\n")[0])
