"""How fast the kernel serves a streamed scene's chunks, and what playback that allows (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_scene_chunks.py [--hours 0 1 3] [--compare OTHER_TREE]

For each length a fresh process registers the example recording tiled in
time (``tiled_recording.py``) as the explorer does, builds
``explorer_scene()``, makes the content a page gets (the coarse copy and the
chunking) and then asks for every chunk of the recording in order, one
request per chunk, as a page playing from start to end does
(``ViewLink.chunk_messages``, what the widget calls on a ``chunks``
message; no browser). Printed per length: the chunk's length in recording
seconds, the scene's build (``explorer_scene()``, not traced) and the
content message (ms), the time to serve one chunk (median, 95th percentile, largest;
the first request is not counted: it warms the lookups), and the playback
rate one kernel core keeps up with (``chunk s / p95``, times real time): the
page asks for chunks ahead of the playhead, so 10x playback needs it above
10. With ``--compare`` the same runs in another checkout (e.g. ``/work/main``,
where chunks are slices of poses held since the build).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

CHILD = r"""
import json, sys, time
sys.path.insert(0, {bench!r})
import numpy as np
from rbm_nb import explorer
from tiled_recording import tiled_head_eye

head, left, right = tiled_head_eye({hours})
explorer.register_head_eye_frames(head, left, right)
start = time.perf_counter()
scene = explorer.explorer_scene()
build = time.perf_counter() - start
view = scene._view
start = time.perf_counter()
view.live_snapshot_message(None)
content = time.perf_counter() - start
plan = view.stream
times, sizes = [], []
for k in range(plan["count"]):
    start = time.perf_counter()
    answers = view.chunk_messages({{"indices": [k]}})
    times.append(time.perf_counter() - start)
    sizes.append(sum(len(b) for b in answers[0][1]))
served = np.array(times[1:]) * 1e3
print("RESULT " + json.dumps({{
    "chunk_s": plan["chunk"], "chunks": plan["count"], "chunk_MB": float(np.mean(sizes)) / 1e6,
    "median_ms": float(np.median(served)), "p95_ms": float(np.percentile(served, 95)),
    "max_ms": float(served.max()), "first_ms": times[0] * 1e3,
    "build_s": build, "content_ms": content * 1e3,
}}))
"""


def run(tree: Path, hours: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    code = CHILD.format(bench=str(HERE), hours=hours)
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    line = [row for row in out.splitlines() if row.startswith("RESULT ")][-1]
    return json.loads(line[len("RESULT ") :])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[0, 1, 3])
    parser.add_argument("--compare", type=Path, help="another checkout to run too")
    args = parser.parse_args()
    trees = [HERE.parent] + ([args.compare] if args.compare else [])
    print(
        "| tree | recording | build s | content ms | chunk s | chunks | chunk MB "
        "| median ms | p95 ms | max ms | first ms | playback kept up with (x real time) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for hours in args.hours:
        for tree in trees:
            row = run(tree, hours)
            label = "5.5 min (real)" if hours == 0 else f"{hours:g} h"
            rate = row["chunk_s"] / (row["p95_ms"] / 1e3)
            print(
                f"| {tree} | {label} | {row['build_s']:.2f} | {row['content_ms']:.0f} "
                f"| {row['chunk_s']:.1f} | {row['chunks']} "
                f"| {row['chunk_MB']:.2f} | {row['median_ms']:.2f} | {row['p95_ms']:.2f} "
                f"| {row['max_ms']:.2f} | {row['first_ms']:.1f} | {rate:,.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
