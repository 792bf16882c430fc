"""The explorer's 3D scene as the recording grows: bytes, time and memory (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_scene_scale.py [--compare OTHER_TREE] [--hours 0 1 3]

The example recording (head 200 Hz, eyes ~340 Hz; the real one with
``RBM_NB_DATA_DIR``) is tiled in time to 1 h and 3 h (0: as recorded,
5.5 min when real), its frames registered as the explorer does and
``explorer_scene()`` built (world axes, head model, head path, gaze rays). No
browser: a comm stand-in counts what the widget would send. Printed per
length:

* ``build s``: building the scene (the poses' lookups and the path);
* ``kernel MB``: memory the scene keeps after it is built (tracemalloc), and
  the peak while building;
* ``state MB``: the widget's state sent when it is displayed (meshcat's viewer
  and the saved snapshot included);
* ``first MB``: the content a page gets when it opens (in answer to its
  ``ready``): all of it before this change; the content and the first two
  chunks after; ``largest MB`` the largest single message;
* ``chunk``: bytes of one chunk and the time to serve it (after);
* ``path``: points drawn and the largest error (m);
* ``html MB``: ``Scene.to_html`` of the scene alone with the explorer's
  ``max_frames`` (10000 poses per moving object).

``--compare TREE`` runs the same in another checkout (e.g. ``/work/main``,
before this change) in a subprocess and prints both. Frames per second in
the browser: ``tests/notebook/test_browser_scene_stream.py`` prints them.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np


class CountingComm:
    """Stands in for the kernel's comm; counts what would go to the browser."""

    kernel = "Truthy"

    def __init__(self, *args, data=None, buffers=None, **kwargs):
        self.comm_id = os.urandom(16).hex()
        self.opened = len(json.dumps(data, default=str)) + sum(
            memoryview(b).nbytes for b in buffers or []
        )
        self.messages: list[int] = []

    def open(self, *args, **kwargs):
        pass

    def on_msg(self, callback):
        pass

    def send(self, data=None, metadata=None, buffers=None):
        self.messages.append(
            len(json.dumps(data, default=str))
            + sum(memoryview(b).nbytes for b in buffers or [])
        )

    def close(self, *args, **kwargs):
        pass


def tiled(ds, hours: float):
    """``ds`` repeated in time to at least ``hours`` (0: as recorded)."""
    import xarray as xr

    if hours <= 0:
        return ds
    time_ = ds.time.values
    period = (time_[-1] - time_[0]) + np.timedelta64(5, "ms")
    span = period.astype("timedelta64[ns]").astype(np.int64)
    tiles = int(np.ceil(hours * 3600e9 / span))
    return xr.concat(
        [ds.assign_coords(time=time_ + k * period) for k in range(tiles)], dim="time"
    )


def measure(hours: float) -> dict:
    import comm

    from rbm_nb.app import explorer

    comm.create_comm = CountingComm
    head, left, right, note = explorer.load_head_eye()
    head, left, right = (tiled(ds, hours) for ds in (head, left, right))
    explorer.register_head_eye_frames(head, left, right)
    span = float((head.time.values[-1] - head.time.values[0]) / np.timedelta64(1, "s"))
    tracemalloc.start()
    start = time.perf_counter()
    scene = explorer.explorer_scene()
    build = time.perf_counter() - start
    kept, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    widget = scene.widget
    state = widget.comm.opened
    before = len(widget.comm.messages)
    widget._on_message(widget, {"type": "ready"}, [])
    first = widget.comm.messages[before:]
    row = {
        "length": f"{span / 60:.1f} min" if span < 3600 else f"{span / 3600:.2f} h",
        "build_s": build,
        "kernel_MB": kept / 1e6,
        "peak_MB": peak / 1e6,
        "state_MB": state / 1e6,
        "first_MB": sum(first) / 1e6,
        "largest_MB": max(first) / 1e6,
        "messages": len(first),
    }
    plan = getattr(scene, "_stream", None)
    if plan:
        mid = plan["count"] // 2
        start = time.perf_counter()
        widget._on_message(widget, {"type": "chunks", "indices": [mid]}, [])
        row["chunk_ms"] = (time.perf_counter() - start) * 1e3
        row["chunk_MB"] = widget.comm.messages[-1] / 1e6
        row["chunk_s"] = plan["chunk"]
        row["chunks"] = plan["count"]
    [path] = [h for h in scene.handles.values() if h.kind == "path"]
    if hasattr(path, "stretches"):
        stretches, error = path.stretches()
        row["path"] = f"{sum(len(s) for s in stretches)} pts, {error * 100:.2g} cm"
    else:
        row["path"] = f"{len(path.shown_positions())} pts (stride)"
    with tempfile.TemporaryDirectory() as tmp:
        out = scene.to_html(
            Path(tmp) / "scene.html", max_frames=explorer.PLOT_MAX_POINTS
        )
        row["html_MB"] = out.stat().st_size / 1e6
    scene.close()
    print(f"data: {note}", file=sys.stderr)
    return row


COLUMNS = (
    ("build_s", "build s", "{:.1f}"),
    ("kernel_MB", "kernel MB", "{:.0f}"),
    ("peak_MB", "peak MB", "{:.0f}"),
    ("state_MB", "state MB", "{:.2f}"),
    ("first_MB", "first MB", "{:.2f}"),
    ("largest_MB", "largest MB", "{:.2f}"),
    ("chunk_MB", "chunk MB", "{:.2f}"),
    ("chunk_ms", "chunk ms", "{:.1f}"),
    ("chunk_s", "chunk s", "{:.0f}"),
    ("path", "path", "{}"),
    ("html_MB", "html MB", "{:.2f}"),
)


def table(runs: dict[str, list[dict]]) -> None:
    header = ["tree", "length"] + [title for _, title, _ in COLUMNS]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for tree, rows in runs.items():
        for row in rows:
            cells = [tree, row["length"]]
            for key, _, fmt in COLUMNS:
                cells.append(fmt.format(row[key]) if key in row else "")
            print("| " + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[0, 1, 3])
    parser.add_argument("--compare", help="another checkout (before the change)")
    parser.add_argument("--one", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one is not None:
        print(json.dumps(measure(args.one)))
        return
    here = Path(__file__).resolve().parents[1]
    trees = {"after": here}
    if args.compare:
        trees = {"before": Path(args.compare).resolve(), "after": here}
    runs: dict[str, list[dict]] = {name: [] for name in trees}
    for hours in args.hours:
        for name, tree in trees.items():
            # one process per run: each starts from an empty kernel
            env = dict(os.environ, PYTHONPATH=str(tree))
            out = subprocess.run(
                [sys.executable, str(Path(__file__).resolve()), "--one", str(hours)],
                env=env,
                cwd=tree,
                capture_output=True,
                text=True,
                check=True,
            )
            runs[name].append(json.loads(out.stdout.strip().splitlines()[-1]))
            print(f"{name} {hours} h done", file=sys.stderr)
    table(runs)


if __name__ == "__main__":
    main()
