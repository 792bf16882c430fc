"""rbm_nb.se3 against spatialmath-python and rbm_nb.evaluation against evo.

Run from the repository root::

    .venv/bin/python benchmarks/bench_se3_evaluation.py [--n 100000] [--repeat 5]

First table: each ``rbm_nb.se3`` function on a stack of ``n`` values (best of
``--repeat`` wall-clock times, validation included) against spatialmath's
function of the same name called once per value (spatialmath works on one
matrix at a time; timed once, the loop is the only way to use it on a stack).

Second table: ``rbm_nb.evaluation.ape``/``rpe`` on two trajectories of ``n``
poses with the same timestamps, against evo doing the same: building its
``PoseTrajectory3D`` objects, ``sync.associate_trajectories``, alignment and
``process_data``. rbm_nb's time includes its own timestamp matching (the
estimate looked up at the reference times). Every row also checks that the
two results agree and prints the largest difference.

``x faster`` is oracle time / rbm_nb time. All numbers come from the same
run, on the same data.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import spatialmath.base as sb
from evo.core import metrics, sync, trajectory
from spatialmath.quaternion import Quaternion

from rbm_nb.core import evaluation as ev
from rbm_nb.core import se3
from rbm_nb.core.conversions import (
    matrix_from_quaternion,
    quaternion_from_rotation_vector,
)
from rbm_nb.core.quaternions import qmul


def _best(func, repeat):
    func()  # compile / warm up
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return best


def _once(func):
    start = time.perf_counter()
    out = func()
    return time.perf_counter() - start, out


def _poses(rng, n):
    q = rng.normal(size=(n, 4))
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = matrix_from_quaternion(q / np.linalg.norm(q, axis=1, keepdims=True))
    T[:, :3, 3] = rng.normal(size=(n, 3))
    T[:, 3, 3] = 1.0
    return T


def se3_rows(n, repeat):
    rng = np.random.default_rng(0)
    T0, T1 = _poses(rng, n), _poses(rng, n)
    ang = rng.uniform(-1.2, 1.2, size=(n, 3))
    d = rng.normal(scale=1e-2, size=(n, 6))
    s = rng.uniform(0, 1, n)
    noisy = T0.copy()
    noisy[:, :3, :3] += rng.normal(scale=1e-6, size=(n, 3, 3))
    S = se3.skew(ang)
    q = rng.normal(size=(n, 4))

    def loop(func, *arrays):
        return lambda: np.stack([func(*row) for row in zip(*arrays, strict=True)])

    cases = [
        ("tr2delta", lambda: se3.tr2delta(T0, T1), loop(sb.tr2delta, T0, T1)),
        ("delta2tr", lambda: se3.delta2tr(d), loop(sb.delta2tr, d)),
        ("tr2adjoint", lambda: se3.tr2adjoint(T0), loop(sb.tr2adjoint, T0)),
        ("rpy2jac", lambda: se3.rpy2jac(ang), loop(sb.rpy2jac, ang)),
        ("eul2jac", lambda: se3.eul2jac(ang), loop(sb.eul2jac, ang)),
        ("exp2jac", lambda: se3.exp2jac(ang), loop(sb.exp2jac, ang)),
        (
            "rotvelxform inverse",
            lambda: se3.rotvelxform(ang, inverse=True),
            loop(lambda a: sb.rotvelxform(a, inverse=True), ang),
        ),
        ("trinterp", lambda: se3.trinterp(T0, T1, s), loop(sb.trinterp, T0, T1, s)),
        ("trnorm", lambda: se3.trnorm(noisy), loop(sb.trnorm, noisy)),
        ("skew", lambda: se3.skew(ang), loop(sb.skew, ang)),
        ("vex", lambda: se3.vex(S), loop(sb.vex, S)),
        ("qexp", lambda: se3.qexp(q), loop(lambda r: Quaternion(r).exp().vec, q)),
        ("qlog", lambda: se3.qlog(q), loop(lambda r: Quaternion(r).log().vec, q)),
    ]
    print(f"\nrbm_nb.se3 vs spatialmath.base, n = {n:,}")
    print(
        f"{'function':<22}{'rbm_nb ms':>11}{'spatialmath ms':>16}{'x faster':>10}{'max |diff|':>12}"
    )
    for name, ours, theirs in cases:
        t_ours = _best(ours, repeat)
        t_theirs, want = _once(theirs)
        diff = float(np.abs(ours() - want).max())
        print(
            f"{name:<22}{t_ours * 1e3:>11.2f}{t_theirs * 1e3:>16.0f}"
            f"{t_theirs / t_ours:>10.0f}{diff:>12.1e}"
        )


def _trajectories(n):
    rng = np.random.default_rng(1)
    t = 0.005 * np.arange(n)
    p = np.cumsum(rng.normal(scale=0.01, size=(n, 3)), axis=0)
    q = np.asarray(
        quaternion_from_rotation_vector(
            np.cumsum(rng.normal(scale=0.01, size=(n, 3)), axis=0)
        )
    )
    pe = p + np.cumsum(rng.normal(scale=1e-3, size=(n, 3)), axis=0) + [1.0, 2.0, 0.5]
    noise = quaternion_from_rotation_vector(
        np.cumsum(rng.normal(scale=1e-3, size=(n, 3)), axis=0)
    )
    qe = np.asarray(qmul(noise, q))
    return (t, p, q), (t, pe, qe)


def _evo(ref, est, relation, align=False, scale=False, rpe=None):
    a = trajectory.PoseTrajectory3D(
        positions_xyz=ref[1], orientations_quat_wxyz=ref[2], timestamps=ref[0]
    )
    b = trajectory.PoseTrajectory3D(
        positions_xyz=est[1], orientations_quat_wxyz=est[2], timestamps=est[0]
    )
    a, b = sync.associate_trajectories(a, b)
    if align:
        b.align(a, correct_scale=scale)
    if rpe is None:
        metric = metrics.APE(relation)
    else:
        delta, unit, all_pairs = rpe
        metric = metrics.RPE(
            relation, delta=delta, delta_unit=metrics.Unit[unit], all_pairs=all_pairs
        )
    metric.process_data((a, b))
    return metric.error


def evaluation_rows(n, repeat):
    ref, est = _trajectories(n)
    PR = metrics.PoseRelation
    cases = [
        ("ape translation", {}, (PR.translation_part,)),
        ("ape translation sim3", {"align": True, "correct_scale": True},
         (PR.translation_part, True, True)),
        ("ape angle_deg", {"pose_relation": "angle_deg"}, (PR.rotation_angle_deg,)),
        ("ape full se3", {"pose_relation": "full", "align": True},
         (PR.full_transformation, True)),
        ("rpe translation 10 frames", {"rpe": (10, "frames", False)},
         (PR.translation_part, False, False, (10, "frames", False))),
        ("rpe angle_deg all 10 frames", {"rpe": (10, "frames", True),
                                          "pose_relation": "angle_deg"},
         (PR.rotation_angle_deg, False, False, (10, "frames", True))),
        ("rpe translation 0.5 m", {"rpe": (0.5, "meters", False)},
         (PR.translation_part, False, False, (0.5, "meters", False))),
    ]  # fmt: skip

    def ours(kwargs):
        kwargs = dict(kwargs)
        spec = kwargs.pop("rpe", None)
        if spec is None:
            return lambda: ev.ape(ref, est, **kwargs).error.values
        delta, unit, all_pairs = spec
        return lambda: (
            ev.rpe(
                ref, est, delta=delta, delta_unit=unit, all_pairs=all_pairs, **kwargs
            ).error.values
        )

    print(f"\nrbm_nb.evaluation vs evo, two trajectories of n = {n:,} poses")
    print(
        f"{'metric':<30}{'rbm_nb ms':>11}{'evo ms':>10}{'x faster':>10}{'max |diff|':>12}"
    )
    for name, kwargs, evo_args in cases:
        func = ours(kwargs)
        t_ours = _best(func, repeat)
        t_evo, want = _once(lambda a=evo_args: _evo(ref, est, *a))
        diff = float(np.abs(func() - want).max())
        print(
            f"{name:<30}{t_ours * 1e3:>11.1f}{t_evo * 1e3:>10.0f}{t_evo / t_ours:>10.1f}{diff:>12.1e}"
        )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, "
        f"{os.cpu_count()} CPUs, {platform.processor() or platform.machine()}"
    )
    se3_rows(args.n, args.repeat)
    evaluation_rows(args.n, args.repeat)


if __name__ == "__main__":
    main()
