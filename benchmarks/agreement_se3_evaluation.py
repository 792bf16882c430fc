"""How closely rbm_nb.se3 and rbm_nb.evaluation agree with their oracles.

Run from the repository root::

    .venv/bin/python benchmarks/agreement_se3_evaluation.py [--n 2000]

Prints the largest absolute difference, element by element, between rbm_nb
and spatialmath-python (``spatialmath.base``, one call per value) on random
batches of ``n`` values (a third of the angle triples exactly at the
representation's singularity for the forward Jacobians), and between rbm_nb
and evo on the real head track (``$RBM_NB_SHARED/data/rbm-data/head.nc``,
default ``../shared``) against a drifted, rotated, scaled copy.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import spatialmath.base as sb
import xarray as xr
from evo.core import metrics, sync, trajectory
from spatialmath.quaternion import Quaternion

from rbm_nb.core import evaluation as ev
from rbm_nb.core import se3
from rbm_nb.core.conversions import (
    matrix_from_quaternion,
    quaternion_from_rotation_vector,
)
from rbm_nb.core.quaternions import qmul, rotate_vectors

REPS = ["rpy/xyz", "rpy/zyx", "rpy/yxz", "eul", "exp"]


def _rows(func, *arrays):
    return np.stack([func(*row) for row in zip(*arrays, strict=True)])


def _poses(rng, n):
    q = rng.normal(size=(n, 4))
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = matrix_from_quaternion(q / np.linalg.norm(q, axis=1, keepdims=True))
    T[:, :3, 3] = rng.normal(scale=3, size=(n, 3))
    T[:, 3, 3] = 1.0
    return T


def _singular(rng, rep, n):
    ang = rng.uniform(-np.pi, np.pi, size=(n, 3))
    if rep == "exp":
        return 0.5 * ang
    at = [0.0, np.pi, -np.pi] if rep == "eul" else [np.pi / 2, -np.pi / 2]
    ang[::3, 1] = rng.choice(at, size=len(ang[::3]))
    return ang


def se3_agreement(n):
    rng = np.random.default_rng(0)
    T0, T1 = _poses(rng, n), _poses(rng, n)
    s = rng.uniform(0, 1, n)
    d = rng.normal(size=(n, 6))
    v = rng.normal(size=(n, 3))
    M = rng.normal(size=(n, 3, 3))
    q = rng.normal(size=(n, 4))
    noisy = T0.copy()
    noisy[:, :3, :3] += rng.normal(scale=1e-3, size=(n, 3, 3))
    rows = [
        ("tr2delta(T0, T1)", se3.tr2delta(T0, T1), _rows(sb.tr2delta, T0, T1)),
        ("tr2delta(T)", se3.tr2delta(T0), _rows(sb.tr2delta, T0)),
        ("delta2tr", se3.delta2tr(d), _rows(sb.delta2tr, d)),
        ("tr2adjoint", se3.tr2adjoint(T0), _rows(sb.tr2adjoint, T0)),
        ("trinterp", se3.trinterp(T0, T1, s), _rows(sb.trinterp, T0, T1, s)),
        (
            "trinterp shortest=False",
            se3.trinterp(T0, T1, s, shortest=False),
            _rows(lambda a, b, f: sb.trinterp(a, b, f, shortest=False), T0, T1, s),
        ),
        ("trnorm", se3.trnorm(noisy), _rows(sb.trnorm, noisy)),
        ("skew", se3.skew(v), _rows(sb.skew, v)),
        ("vex", se3.vex(M), _rows(sb.vex, M)),
        ("qexp", se3.qexp(q), _rows(lambda r: Quaternion(r).exp().vec, q)),
        ("qlog", se3.qlog(q), _rows(lambda r: Quaternion(r).log().vec, q)),
    ]
    for rep in REPS:
        ang = _singular(rng, rep, n)
        rows.append(
            (
                f"rotvelxform {rep} (singular rows incl.)",
                se3.rotvelxform(ang, representation=rep),
                _rows(lambda a, r=rep: sb.rotvelxform(a, representation=r), ang),
            )
        )
        safe = rng.uniform(-1.2, 1.2, size=(n, 3))
        if rep == "eul":
            safe[:, 1] = np.abs(safe[:, 1]) + 0.1
        rows.append(
            (
                f"rotvelxform {rep} inverse",
                se3.rotvelxform(safe, inverse=True, representation=rep),
                _rows(
                    lambda a, r=rep: sb.rotvelxform(a, inverse=True, representation=r),
                    safe,
                ),
            )
        )
    for order in ("zyx", "xyz", "yxz"):
        ang = _singular(rng, "rpy", n)
        rows.append(
            (
                f"rpy2jac {order}",
                se3.rpy2jac(ang, order),
                _rows(lambda a, o=order: sb.rpy2jac(a, o), ang),
            )
        )
    ang = _singular(rng, "eul", n)
    rows.append(("eul2jac", se3.eul2jac(ang), _rows(sb.eul2jac, ang)))
    rows.append(("exp2jac", se3.exp2jac(v), _rows(sb.exp2jac, v)))
    print(f"rbm_nb.se3 vs spatialmath.base, {n} random values per row")
    print(f"{'function':<40}{'max |diff|':>12}")
    for name, ours, theirs in rows:
        print(f"{name:<40}{np.abs(ours - theirs).max():>12.1e}")


def _evo_traj(t, p, q):
    return trajectory.PoseTrajectory3D(
        positions_xyz=p, orientations_quat_wxyz=q, timestamps=t
    )


def evaluation_agreement(head_path: Path):
    ds = xr.load_dataset(head_path)
    t = (ds.time.values - ds.time.values[0]) / np.timedelta64(1, "s")
    p = ds.position.values
    q = ds.orientation.values / np.linalg.norm(
        ds.orientation.values, axis=1, keepdims=True
    )
    rng = np.random.default_rng(11)
    offset = quaternion_from_rotation_vector([0.1, -0.2, 0.3])
    drift = np.cumsum(rng.normal(scale=2e-3, size=p.shape), axis=0) + 0.01 * t[:, None]
    pe = np.asarray(rotate_vectors(offset, 1.05 * (p + drift))) + [0.5, -1.0, 2.0]
    noise = quaternion_from_rotation_vector(
        np.cumsum(rng.normal(scale=1e-3, size=p.shape), axis=0)
    )
    qe = np.asarray(qmul(offset, qmul(noise, q)))
    drifted = ds[["position", "orientation"]].copy()
    drifted["position"] = (("time", "cartesian_axis"), pe)
    drifted["orientation"] = (("time", "quaternion_axis"), qe)
    PR = metrics.PoseRelation
    print(
        f"\nrbm_nb.evaluation vs evo, real head track ({len(t)} poses) vs drifted copy"
    )
    print(f"{'metric':<42}{'max |diff| errors':>18}{'max |diff| stats':>18}")
    cases = [
        ("APE translation", {}, PR.translation_part, None),
        ("APE translation, sim3", {"align": True, "correct_scale": True},
         PR.translation_part, "sim3"),
        ("APE angle_deg, se3", {"align": True, "pose_relation": "angle_deg"},
         PR.rotation_angle_deg, "se3"),
        ("APE full, se3", {"align": True, "pose_relation": "full"},
         PR.full_transformation, "se3"),
        ("RPE translation, 100 frames", {"delta": 100}, PR.translation_part, "rpe"),
        ("RPE angle_deg, 1 m all pairs", {"delta": 1.0, "delta_unit": "meters",
                                          "all_pairs": True, "pose_relation": "angle_deg"},
         PR.rotation_angle_deg, "rpe"),
    ]  # fmt: skip
    for name, kwargs, relation, mode in cases:
        ref_e, est_e = sync.associate_trajectories(
            _evo_traj(t, p, q), _evo_traj(t, pe, qe)
        )
        if mode == "rpe":
            ours = ev.rpe(ds, drifted, **kwargs)
            metric = metrics.RPE(
                relation,
                delta=kwargs["delta"],
                delta_unit=metrics.Unit[kwargs.get("delta_unit", "frames")],
                all_pairs=kwargs.get("all_pairs", False),
            )
        else:
            ours = ev.ape(ds, drifted, **kwargs)
            if mode is not None:
                est_e.align(ref_e, correct_scale=mode == "sim3")
            metric = metrics.APE(relation)
        metric.process_data((ref_e, est_e))
        stats = metric.get_all_statistics()
        d_err = np.abs(ours.error.values - metric.error).max()
        d_stats = max(
            abs(ours.stats[k] - v) / max(abs(v), 1.0) for k, v in stats.items()
        )
        print(f"{name:<42}{d_err:>18.1e}{d_stats:>18.1e}")
    print("(stats: relative to max(|value|, 1), since sse grows with n)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=2000)
    args = parser.parse_args()
    se3_agreement(args.n)
    shared = Path(
        os.environ.get("RBM_NB_SHARED", Path(__file__).resolve().parents[2] / "shared")
    )
    head = shared / "data" / "rbm-data" / "head.nc"
    if head.exists():
        evaluation_agreement(head)
    else:
        print(
            f"\n{head} not found: set RBM_NB_SHARED to compare on the real head track"
        )


if __name__ == "__main__":
    main()
