"""The explorer's scene build on a long recording, this tree against another.

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_scene_build.py --compare /work/main [--hours 0 1 3] [--repeat 2]

The example recording (the real one with ``RBM_NB_DATA_DIR``) is tiled to
``--hours`` (:mod:`tiled_recording`), its frames registered as the explorer
does, and ``explorer.explorer_scene()`` timed (world axes, head model, head
path, gaze rays: nine objects, seven of them hanging from the moving head),
then the opening of its view (``scene.widget``: the snapshot the dashboard
sends, the coarse copy of every track and the copy saved with the
notebook). The scene's share of the dashboard's build is their sum less
``explorer.eye_centres`` (the eyes' median centres for the head model, a
lookup of the explorer's own, timed and printed apart). Each process first
builds and closes the scene of the real recording (numba's kernels loaded,
modules imported), as ``/work/s6/prof_build.py`` does; ``--cold`` skips
that. Loading and tiling are not timed; ``--hours 0`` is the real
recording. Each run is a fresh process, the trees
take turns, the best of ``--repeat`` runs per tree is kept and the ratio
printed (before / after: above 1 means this tree builds faster). Without
``--compare`` only this tree runs.

No tracemalloc here (``bench_scene_scale.py`` traces memory during the
build, which slows it): this is the build's own time.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def measure(hours: float, cold: bool = False) -> dict:
    sys.path.insert(0, str(HERE))
    from tiled_recording import tiled_head_eye

    from rbm_nb.app import explorer

    if not cold:
        explorer.register_head_eye_frames(*tiled_head_eye(0))
        warm = explorer.explorer_scene()
        warm.widget  # noqa: B018
        warm.close()
    spent = [0.0]
    centres = explorer.eye_centres

    def timed_centres(*args, **kwargs):
        start = time.perf_counter()
        try:
            return centres(*args, **kwargs)
        finally:
            spent[0] += time.perf_counter() - start

    explorer.eye_centres = timed_centres
    head, left, right = tiled_head_eye(hours)
    explorer.register_head_eye_frames(head, left, right)
    start = time.perf_counter()
    scene = explorer.explorer_scene()
    build = time.perf_counter() - start
    start = time.perf_counter()
    scene.widget  # noqa: B018 - opening the view is what is timed
    view = time.perf_counter() - start
    samples = len(head.time)
    scene.close()
    return {
        "build_s": build - spent[0] + view,
        "scene_s": build - spent[0],
        "centres_s": spent[0],
        "view_s": view,
        "head_samples": samples,
    }


def run(tree: Path, hours: float, cold: bool) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    extra = ["--cold"] if cold else []
    out = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--one", str(hours), *extra],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[1.0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--compare", help="another checkout (before the change)")
    parser.add_argument("--cold", action="store_true", help="no warm-up build")
    parser.add_argument("--one", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one is not None:
        print(json.dumps(measure(args.one, args.cold)))
        return
    trees = {"after": HERE.parent}
    if args.compare:
        trees = {"before": Path(args.compare).resolve(), "after": HERE.parent}
    for hours in args.hours:
        best: dict[str, dict] = {}
        for turn in range(args.repeat):
            for name, tree in trees.items():
                row = run(tree, hours, args.cold)
                if row["build_s"] < best.get(name, {}).get("build_s", float("inf")):
                    best[name] = row
                print(
                    f"turn {turn + 1} {name}: {row['build_s']:.2f} s "
                    f"({row['head_samples']:,} head samples)",
                    file=sys.stderr,
                )
        for name, row in best.items():
            print(
                f"{name}: {hours:g} h: explorer_scene() {row['scene_s']:.2f} s + "
                f"view {row['view_s']:.2f} s = {row['build_s']:.2f} s (best; "
                f"eye_centres apart: {row['centres_s']:.2f} s)"
            )
        if "before" in best:
            ratio = best["before"]["build_s"] / best["after"]["build_s"]
            print(f"{hours:g} h: ratio before/after: {ratio:.2f}x")


if __name__ == "__main__":
    main()
