"""Same bits as another checkout: the frame core's outputs on the real recording.

Registers the explorer's head/eye frame tree (guide 1.6,
``rbm_nb.app.explorer.register_head_eye_frames``) on the real recording
(``RBM_NB_DATA_DIR``, default ``/work/shared/data/rbm-data``) in this tree
and in another checkout, each in its own process with its own numba cache,
computes lookups, transforms, twists and velocities (sorted target times,
unsorted ones, one time, serial and parallel launches) and ``qinterp``, and
prints, per output, max |a - b| and whether the two are identical bit for
bit (NaN where NaN). Exits 1 if any output differs.

Run:  .venv/bin/python benchmarks/same_bits_real.py OTHER_TREE
(with ``SAME_BITS_FROZEN=1`` both trees get the recording read-only, as the
loaders return it)
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("RBM_NB_DATA_DIR", "/work/shared/data/rbm-data"))


def dump(out: str) -> None:
    """Compute every output in this process (the tree on PYTHONPATH)."""
    import xarray as xr

    import rbm_nb as rbm
    from rbm_nb.app.explorer import register_head_eye_frames
    from rbm_nb.core.lookups import lookup_at

    head, left, right = (
        xr.open_dataset(DATA / f"{name}.nc").load()
        for name in ("head", "left_eye", "right_eye")
    )
    if os.environ.get("SAME_BITS_FROZEN"):
        # read-only down to the memory, as load_example returns them: frames
        # keep these arrays (and the eyes' low-confidence mask) in trees
        # that can
        for ds in (head, left, right):
            for var in ds.variables.values():
                node = np.asarray(var.values)
                while isinstance(node, np.ndarray):
                    node.setflags(write=False)
                    node = node.base
    rbm.clear_registry()
    register_head_eye_frames(head, left, right, ros_eyes=True)
    rng = np.random.default_rng(0)
    # times where every frame has data (lookups do not extrapolate)
    lo = max(ds.time.values[0] for ds in (head, left, right))
    hi = min(ds.time.values[-1] for ds in (head, left, right))
    eye_t = left.time.values[(left.time.values >= lo) & (left.time.values <= hi)]
    head_t = head.time.values[(head.time.values >= lo) & (head.time.values <= hi)]
    unsorted = rng.permutation(eye_t)[:5000]
    few = eye_t[1000:1040]  # serial launches
    one = eye_t[5000:5001]
    points = rng.normal(size=(len(eye_t), 3))
    res: dict[str, np.ndarray] = {}

    def keep(name, value):
        if isinstance(value, tuple):
            for k, v in enumerate(value):
                keep(f"{name}[{k}]", v)
        elif value is not None:
            res[name] = np.asarray(getattr(value, "values", value))

    pairs = [
        ("left_eye", "world"),
        ("right_eye", "world"),
        ("head", "world"),
        ("left_eye", "head"),
        ("world", "left_eye"),
        ("pupil/left_eye", "t265/tracker"),
    ]
    for a, b in pairs:
        keep(f"lookup_transform {a}->{b}", rbm.lookup_transform(a, b))
        for label, ts in (("eye", eye_t), ("head", head_t), ("unsorted", unsorted),
                          ("few", few), ("one", one)):  # fmt: skip
            keep(f"lookup_at {a}->{b} {label}", lookup_at(a, b, ts))
        keep(f"lookup_pose {a} wrt {b}", rbm.lookup_pose(a, b))
    for label, ts, n in (("eye", eye_t, len(eye_t)), ("head", head_t, len(head_t)),
                         ("few", few, len(few))):  # fmt: skip
        p = points[:n]
        keep(
            f"transform_points {label}",
            rbm.transform_points(p, "left_eye", "world", timestamps=ts),
        )
        keep(
            f"transform_vectors {label}",
            rbm.transform_vectors(p, "left_eye", "world", timestamps=ts),
        )
        q = rng.normal(size=(n, 4))
        q /= np.linalg.norm(q, axis=1)[:, None]
        keep(
            f"transform_quaternions {label}",
            rbm.transform_quaternions(q, "left_eye", "head", timestamps=ts),
        )
    for a, b in (("head", "world"), ("left_eye", "world"), ("left_eye", "head")):
        keep(f"lookup_twist {a} wrt {b}", rbm.lookup_twist(a, b))
        keep(f"lookup_angular_velocity {a} wrt {b}", rbm.lookup_angular_velocity(a, b))
        keep(f"lookup_linear_velocity {a} wrt {b}", rbm.lookup_linear_velocity(a, b))
    hq = head.orientation.values
    hts = (head_t - head_t[0]).astype(np.float64) / 1e9
    for label, t_out in (("sorted", np.sort(rng.uniform(hts[0], hts[-1], 200_000))),
                         ("unsorted", rng.uniform(hts[0], hts[-1], 5000))):  # fmt: skip
        keep(f"qinterp head {label}", rbm.qinterp(hq, hts, t_out))
    np.savez(out, **res)


def compare(tree_a: Path, tree_b: Path) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        files = []
        for k, tree in enumerate((tree_a, tree_b)):
            out = str(Path(tmp) / f"{k}.npz")
            env = dict(os.environ, PYTHONPATH=str(tree))
            subprocess.run(
                [sys.executable, __file__, "--dump", out], cwd=tree, env=env, check=True
            )
            files.append(np.load(out))
        a, b = files
        bad = 0
        worst = 0.0
        for name in sorted(set(a.files) | set(b.files)):
            if name not in a.files or name not in b.files:
                print(f"{name}: only in one tree")
                bad += 1
                continue
            x, y = a[name], b[name]
            if x.shape != y.shape or x.dtype != y.dtype:
                print(f"{name}: {x.shape} {x.dtype} vs {y.shape} {y.dtype}")
                bad += 1
                continue
            same = x.tobytes() == y.tobytes()
            if x.dtype.kind == "f":
                both = ~(np.isnan(x) & np.isnan(y))
                d = float(np.nanmax(np.abs(x - y)[both], initial=0.0))
            else:
                d = float(
                    np.max(np.abs(x.astype(np.int64) - y.astype(np.int64)), initial=0)
                )
            worst = max(worst, d)
            bad += not same
            print(
                f"{'same bits' if same else 'DIFFERENT':10s} max|diff| = {d:.3g}  {name} {x.shape}"
            )
        print(
            f"{len(a.files)} outputs; {bad} differ; max |diff| over all = {worst:.3g}"
        )
        return 1 if bad else 0


if __name__ == "__main__":
    if sys.argv[1] == "--dump":
        dump(sys.argv[2])
    else:
        sys.exit(compare(REPO, Path(sys.argv[1]).resolve()))
