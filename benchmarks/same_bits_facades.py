"""Same bits as another checkout: every facade call of the one-door-call test.

Runs the calls of ``tests/core/test_one_door_call.py`` (estimators,
conversions, se3, coordinates, quaternions, transforms, lookups, on plain
arrays and DataArrays) plus a few on other layouts, in this tree and in
another checkout (each in its own process, the tree on PYTHONPATH), and
prints per call whether every output array is identical bit for bit (NaN
where NaN). Exits 1 if any differs.

Run:  .venv/bin/python benchmarks/same_bits_facades.py OTHER_TREE
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def _arrays(value) -> list[np.ndarray]:
    if isinstance(value, tuple | list):
        return [a for v in value for a in _arrays(v)]
    if hasattr(value, "data_vars"):  # a Dataset
        return [np.asarray(value[k].values) for k in sorted(value.data_vars)]
    if hasattr(value, "values") and hasattr(value, "dims"):
        return [np.asarray(value.values)]
    if hasattr(value, "aligned_estimate"):  # an ape/rpe TrajectoryError
        trajectories = (value.reference, value.estimate, value.aligned_estimate)
        alignment = value.alignment or {}
        return [
            *_arrays(value.error),
            np.array(sorted(value.stats.items()), dtype=object)[:, 1].astype(float),
            *[
                a
                for t in trajectories
                for a in (t.timestamps, t.positions, t.orientations)
            ],
            *[np.asarray(alignment[k]) for k in sorted(alignment)],
            *([] if value.pairs is None else [value.pairs]),
        ]
    if hasattr(value, "as_matrix"):  # a Transform
        return [np.asarray(value.as_matrix())]
    return [np.asarray(value)]


def _extra_calls():
    import rbm_nb as rbm

    rng = np.random.default_rng(1)
    x = rng.normal(size=(4, 20, 3))
    q = rbm.quaternion_from_euler(rng.normal(size=(4, 20, 3)) * 0.3, "xyz")
    t = np.arange(20) * 0.1
    return [
        ("estimate_linear_velocity 3-D axis=0",
         lambda: rbm.estimate_linear_velocity(np.moveaxis(x, 2, 0), axis=0,
                                              timestamps=t, time_axis=2)),
        ("estimate_angular_velocity rotation_vector",
         lambda: rbm.estimate_angular_velocity(q[0], timestamps=t, mode="rotation_vector")),
        ("qmul broadcast", lambda: rbm.qmul(q, q[0], q[:, :1])),
        ("qmean axis", lambda: rbm.qmean(q, axis=1)),
        ("rotate_vectors outer", lambda: rbm.rotate_vectors(q[0, :3], x[0], one_to_one=False)),
        ("rotate_vectors broadcast", lambda: rbm.rotate_vectors(q, x[:1])),
        ("qinterp 3-D", lambda: rbm.qinterp(q, t, t[1:-1] + 0.01, axis=1)),
        ("qinv 3-D", lambda: rbm.qinv(q)),
        ("transform_coordinates polar", lambda: rbm.transform_coordinates(x[0, :, :2], "polar", "cartesian")),
        ("spherical_to_cartesian axis=0", lambda: rbm.spherical_to_cartesian(x[0].T, axis=0)),
        ("from_euler_angles roll/yaw", lambda: rbm.from_euler_angles(roll=t, yaw=t[:, None])),
        ("se3.trinterp steps", lambda: rbm.se3.trinterp(None, rbm.homogeneous_from_transform(x[0, 0], q[0, 0]), 5)),
        ("se3.tr2delta one", lambda: rbm.se3.tr2delta(rbm.homogeneous_from_transform(x[0, :3], q[0, :3]))),
        ("se3.rotvelxform matrices",
         lambda: rbm.se3.rotvelxform(rbm.matrix_from_quaternion(q[0, :3]), inverse=True)),
        ("iterative_closest_point init",
         lambda: rbm.iterative_closest_point(x[0], x[0] + 0.02, init_transform=([0.01, 0, 0], [1.0, 0, 0, 0]))),
    ]  # fmt: skip


def dump(out: str) -> None:
    sys.path.insert(0, str(REPO / "tests" / "core"))
    from test_one_door_call import FACADE_CALLS, _register_moving

    _register_moving()
    results = {}
    for label, call in [*FACADE_CALLS, *_extra_calls()]:
        results[label] = [a.copy() for a in _arrays(call())]
    with open(out, "wb") as f:
        pickle.dump(results, f)


def _run(tree: Path, out: str) -> None:
    env = dict(os.environ, PYTHONPATH=str(tree))
    subprocess.run(
        [sys.executable, __file__, "--dump", out], env=env, cwd=tree, check=True
    )


def main() -> int:
    if sys.argv[1:2] == ["--dump"]:
        dump(sys.argv[2])
        return 0
    other = Path(sys.argv[1]).resolve()
    with tempfile.TemporaryDirectory() as tmp:
        mine, theirs = f"{tmp}/mine.pkl", f"{tmp}/theirs.pkl"
        _run(REPO, mine)
        _run(other, theirs)
        with open(mine, "rb") as f:
            a = pickle.load(f)
        with open(theirs, "rb") as f:
            b = pickle.load(f)
    differ = 0
    for label in a:
        same = len(a[label]) == len(b[label]) and all(
            x.shape == y.shape and x.dtype == y.dtype
            and np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
            for x, y in zip(a[label], b[label], strict=True)
        )  # fmt: skip
        differ += not same
        print(f"{'same bits' if same else 'DIFFER   '}  {label}")
    print(f"{len(a)} calls; {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
