"""What the browser gets from the explorer's scene, compared with another checkout.

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/compare_scene_chunks.py --compare /work/main [--hours 0]

In each tree a fresh process registers the example recording (tiled to
``--hours``; 0: the real 5.5 min) as the explorer does, builds
``explorer_scene()`` and dumps the live content message (the coarse copy and
the chunking), every chunk (``ViewLink.chunk_messages``) and the whole
payload (``snapshot_message()``). Printed: whether the JSON parts, the
meshcat commands (their uuids, new in every run, blanked) and the pose
buffers (float32 xyz, xyzw) are byte for byte equal, and for the time buffers (float64 seconds from the scene's
second 0) how many differ and by how much at most (in seconds): a tree that
counts seconds from exact int64 ns keys and one that subtracts float epoch
seconds differ by up to half an ulp of an epoch second (~0.12 µs today).
"""

from __future__ import annotations

import argparse
import os
import pickle
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

CHILD = r"""
import pickle, sys
sys.path.insert(0, {bench!r})
from rbm_nb import explorer
from tiled_recording import tiled_head_eye

head, left, right = tiled_head_eye({hours})
explorer.register_head_eye_frames(head, left, right)
scene = explorer.explorer_scene()
view = scene._view
content = view.live_snapshot_message(None)
plan = view.stream
chunks = [view.chunk_messages({{"indices": [k]}})[0] for k in range(plan["count"])]
whole = view.snapshot_message()
with open({out!r}, "wb") as f:
    pickle.dump({{"content": content, "chunks": chunks, "whole": whole}}, f)
"""


def dump(tree: Path, hours: float, out: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    code = CHILD.format(bench=str(HERE), hours=hours, out=str(out))
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    with open(out, "rb") as f:
        return pickle.load(f)


# meshcat's object commands carry fresh uuid1s (made from the clock) per run
_UUID = re.compile(rb"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def _no_uuids(data) -> bytes:
    """The bytes of a buffer with every uuid blanked (same length)."""
    return _UUID.sub(b"0" * 36, bytes(data))


def _time_indices(head: dict) -> set[int]:
    return {entry["times"] for entry in head.get("tracks", [])}


def compare_message(a, b, tally: dict) -> None:
    """Compare one (head, buffers) message of each tree into ``tally``."""
    (head_a, bufs_a), (head_b, bufs_b) = a, b
    tally["json_equal"] &= head_a == head_b
    tally["buffers"] += len(bufs_a)
    if len(bufs_a) != len(bufs_b):
        tally["json_equal"] = False
        return
    times = _time_indices(head_a)
    for i, (x, y) in enumerate(zip(bufs_a, bufs_b, strict=True)):
        if i in times:
            ta, tb = np.frombuffer(x, "<f8"), np.frombuffer(y, "<f8")
            tally["time_values"] += ta.size
            if ta.shape != tb.shape:
                tally["json_equal"] = False
                continue
            differ = ta != tb
            tally["time_values_differing"] += int(differ.sum())
            if differ.any():
                tally["time_max_s"] = max(
                    tally["time_max_s"], float(np.abs(ta - tb).max())
                )
        elif _no_uuids(x) != _no_uuids(y):
            tally["other_bytes_equal"] = False
            tally.setdefault("differing_buffers", []).append(i)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=0.0)
    parser.add_argument("--compare", type=Path, required=True)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        ours = dump(HERE.parent, args.hours, Path(tmp) / "ours.pkl")
        theirs = dump(args.compare, args.hours, Path(tmp) / "theirs.pkl")
    for part in ("content", "whole", "chunks"):
        tally = {
            "json_equal": True,
            "other_bytes_equal": True,
            "buffers": 0,
            "time_values": 0,
            "time_values_differing": 0,
            "time_max_s": 0.0,
        }
        pairs = (
            zip(ours[part], theirs[part], strict=True)
            if part == "chunks"
            else [(ours[part], theirs[part])]
        )
        count = 0
        if part == "chunks" and len(ours[part]) != len(theirs[part]):
            print(f"{part}: {len(ours[part])} here, {len(theirs[part])} there")
            continue
        for a, b in pairs:
            compare_message(a, b, tally)
            count += 1
        print(f"{part} ({count} messages): {tally}")


if __name__ == "__main__":
    main()
