"""Kernel memory and build time of the explorer's dashboard, no browser (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_dashboard_memory.py [--hours 0 1 3] [--compare OTHER_TREE]
        [--repeat N] [--no-trace] [--read-only]

For each length, a fresh Python process loads the example recording tiled in
time (``tiled_recording.py``: head 200 Hz, eyes ~340 Hz, NaN rows kept; 0 =
the real 5.5 min) and builds what ``bench_dashboard_lab.py``'s kernel builds:
``explorer.dashboard(head, left_eye, right_eye)`` (frames registered, the
plots' series, Scene, Player, FrameTree, TimeSeries), with rbm_nb, the scene,
the widgets and ipywidgets imported first (imports are not the data's memory)
and numba's kernels compiled once on the real 5.5 min recording before the
data is loaded (they are a fixed cost, not the data's; the first row shows it
separately as ``warm``).

* ``loaded MB``: the bytes of every array of the three datasets the user
  loaded (``Dataset.nbytes``: every variable -- also those the dashboard never
  reads, such as the head's velocities and the eyes' confidence -- and every
  coordinate). That is what the user holds; the target compares against it.
* ``RSS``: the process's resident memory after the build minus before the
  data was loaded, so ``RSS`` counts the data itself plus everything the build
  keeps (``ratio`` = that / loaded; the issue's target at 3 h: <= 1.5). Also
  the peak (VmHWM minus the same baseline) during the build.
* ``build s``: seconds of the ``dashboard()`` call.
* ``floor MB``: RSS of the process with everything imported and warmed, before
  the data (not part of the ratio; printed so a reader can see it).

Without ``--no-trace`` a second fresh process per length builds the same
dashboard under ``tracemalloc`` and splits what the build keeps (allocated,
not necessarily resident) by the innermost rbm_nb module that allocated it:
``tables`` (the engine's squad tables: allocated whole per moving frame,
resident only where rows were computed -- untouched pages cost no RSS),
``frames`` (``core/frames.py``, ``_door``, the frames' time copies and,
in trees that mask by copying, the explorer's confidence-masked eye arrays), ``engine`` (the
rest of ``rbm_nb/_engine``, ``rbm_nb/_kernels``: lookup results, chains),
``scene`` (``rbm_nb/scene``: tracks), ``plots`` (``rbm_nb/widgets``,
``core/gaze``, the explorer's series), ``other`` (the rest, and allocations
outside rbm_nb).

The recording is tiled as the tree's loader gives it: read-only where
``rbm_nb.data.load_example`` returns frozen datasets (then frames keep the
arrays and, for the eyes' low-confidence samples, a mask beside them),
writeable where it returns them as ``xarray`` loads them (trees before
issue 35's loaders; frames copy what they keep).
``--read-only``: the recording's arrays are handed over read-only (owned
by nobody who can write them, as :mod:`rbm_nb._infra.frozen` defines it)
whatever the loader gives.

``--compare TREE`` runs the same lengths in another checkout (e.g.
``/work/main``) in the same run and prints its table and the ratios;
``--repeat N`` builds N times per tree, the trees taking turns, and keeps
each tree's fastest build (the build times of a shared machine vary by 2x
from run to run).
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
import gc, json, os, sys, time
sys.path.insert(0, {bench!r})
import numpy as np
import psutil
from rbm_nb import explorer
import rbm_nb.scene, rbm_nb.widgets, ipywidgets  # imports are not the data's memory
from tiled_recording import tiled_head_eye, loaded_bytes

proc = psutil.Process()

def peak():
    with open("/proc/self/status") as f:
        return [int(l.split()[1]) * 1024 for l in f if l.startswith("VmHWM")][0]

def reset_peak():
    # writing 5 to clear_refs resets VmHWM to the current RSS
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass

# compile and load numba's kernels once on the real recording: a fixed cost
t0 = time.perf_counter()
board = explorer.dashboard(*tiled_head_eye(0))
explorer.close_dashboard(board)
del board
gc.collect()
warm = time.perf_counter() - t0
trace = {trace}
rss_before = proc.memory_info().rss
data = tiled_head_eye({hours})
if {read_only}:
    data = tuple(ds.copy(deep=True) for ds in data)
    for ds in data:
        for var in ds.variables.values():
            var.values.setflags(write=False)
loaded = loaded_bytes(data)
gc.collect()
reset_peak()
if trace:
    import tracemalloc
    tracemalloc.start(40)
t0 = time.perf_counter()
board = explorer.dashboard(*data)
build = time.perf_counter() - t0
gc.collect()
out = {{"loaded": loaded, "floor": rss_before, "warm_s": warm, "build_s": build,
       "rss": proc.memory_info().rss - rss_before, "peak": peak() - rss_before}}
if trace:
    snap = tracemalloc.take_snapshot()
    tracemalloc.stop()
    import inspect
    # (trees before the mask made NaN copies in _confident)
    masker = getattr(explorer, "_unconfident", None) or explorer._confident
    lines, first = inspect.getsourcelines(masker)
    masking = range(first, first + len(lines))
    groups = {{"tables": 0, "frames": 0, "engine": 0, "scene": 0, "plots": 0, "other": 0}}
    def group(tb):
        parts = []
        for frame in reversed(tb):  # innermost first
            name = frame.filename.replace(os.sep, "/")
            if "/rbm_nb/" in name:
                parts.append((name.split("/rbm_nb/", 1)[1], frame.lineno))
        if any(p.startswith("_engine/fused") for p, _ in parts) and any(
            p.startswith("_infra/memory") for p, _ in parts[:1]
        ) and not any(p.startswith("core/frames") for p, _ in parts):
            return "tables"
        kept = [(p, line) for p, line in parts if not p.startswith("_infra/")]
        if not kept:
            return "other"
        inner = kept[0]
        parts = [p for p, _ in kept]
        if not parts:
            return "other"
        if any(p.startswith("core/frames") for p in parts[:3]):
            return "frames"  # the frames' samples and times (door, time copies)
        part = parts[0]
        if part.startswith("app/explorer") and inner[1] in masking:
            return "frames"  # the eyes' confidence-masked copies the frames hold
        if part.startswith(("_engine/", "_kernels/")):
            return "engine"
        if part.startswith(("core/frames", "_door/")):
            return "frames"
        if part.startswith("scene/"):
            return "scene"
        if part.startswith(("widgets/", "core/gaze", "app/explorer")):
            return "plots"
        return "other"
    for stat in snap.statistics("traceback"):
        groups[group(stat.traceback)] += stat.size
    out["groups"] = groups
    out["traced"] = sum(groups.values())
print("RESULT " + json.dumps(out))
"""


def run(tree: Path, hours: float, trace: bool, read_only: bool) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    script = CHILD.format(
        bench=str(HERE), hours=hours, trace=trace, read_only=read_only
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
        check=False,
    )
    for line in done.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT ") :])
    raise RuntimeError(f"{tree} at {hours} h failed:\n{done.stderr[-3000:]}")


def measure(trees, hours_list, trace: bool, read_only: bool, repeat: int):
    """Rows per tree; with ``repeat`` > 1 the trees take turns, fresh processes
    each time, and each keeps its fastest build (a loaded machine slows a run
    now and then; the least disturbed one is the comparable one)."""
    rows: list[list[dict]] = [[] for _ in trees]
    for hours in hours_list:
        runs: list[list[dict]] = [[] for _ in trees]
        for _ in range(repeat):
            for k, tree in enumerate(trees):
                runs[k].append(run(tree, hours, False, read_only))
        for k, tree in enumerate(trees):
            best = min(runs[k], key=lambda r: r["build_s"])
            row = {"hours": hours, **best, "builds": [r["build_s"] for r in runs[k]]}
            if trace:
                row["trace"] = run(tree, hours, True, read_only)
            rows[k].append(row)
            print(f"  {tree} {hours} h: {json.dumps(row)}", file=sys.stderr)
    return rows


def _label(hours: float) -> str:
    return "5.5 min (real)" if hours == 0 else f"{hours:g} h"


def table(rows) -> str:
    mb = 1e6
    lines = [
        "| recording | loaded MB | RSS MB (ratio) | peak MB (ratio) | build s "
        "| floor MB | tables | frames | engine | scene | plots | other (MB, tracemalloc) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        groups = r.get("trace", {}).get("groups")
        split = (
            " | ".join(f"{groups[k] / mb:.0f}" for k in groups)
            if groups
            else " | ".join("-" * 6)
        )
        lines.append(
            f"| {_label(r['hours'])} | {r['loaded'] / mb:.0f} "
            f"| {r['rss'] / mb:.0f} ({r['rss'] / r['loaded']:.2f}x) "
            f"| {r['peak'] / mb:.0f} ({r['peak'] / r['loaded']:.2f}x) "
            f"| {r['build_s']:.2f} | {r['floor'] / mb:.0f} | {split} |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[0, 1, 3])
    parser.add_argument("--compare", type=Path, help="another checkout to run too")
    parser.add_argument("--no-trace", action="store_true", help="skip tracemalloc")
    parser.add_argument(
        "--repeat", type=int, default=1, help="builds per tree, taking turns (best)"
    )
    parser.add_argument(
        "--read-only", action="store_true", help="the recording's arrays read-only"
    )
    args = parser.parse_args()
    here = HERE.parent
    trees = [here] + ([args.compare.resolve()] if args.compare else [])
    results = measure(trees, args.hours, not args.no_trace, args.read_only, args.repeat)
    for tree, rows in zip(trees, results, strict=True):
        print(f"\n{tree}\n")
        print(table(rows))
    if args.compare:
        print("\n| recording | RSS this / other | build s this / other (best) |")
        print("|---|---|---|")
        for a, b in zip(*results, strict=True):
            print(
                f"| {_label(a['hours'])} | {a['rss'] / b['rss']:.2f} "
                f"| {a['build_s'] / b['build_s']:.2f} |"
            )


if __name__ == "__main__":
    main()
