"""Signed distance grids and pose algebra: rbm_nb against scikit-robot.

Run from the repository root::

    .venv/bin/python benchmarks/bench_sdf_pose.py [--n 100000] [--loop-n 10000] [--repeat 3]

Every row times the same work on the same data in the same run and prints
the best of ``--repeat`` wall-clock times:

* SDF rows (``--n`` points or rays): ``rbm_nb.sdf.GridSDF`` against
  ``skrobot.sdf.GridSDF`` on the same 81³ grid of a ball. scikit-robot has no
  gradient, so its row is the central difference (6 queries) a user would
  write; its ray marcher is ``skrobot.sdf.signed_distance_function.ray_marching``
  (vectorised, stops when every ray has arrived), given rays that all hit.
  The moving-frame row looks each point's pose up at one of 100 timestamps;
  scikit-robot moves its SDF to each of the 100 poses in turn.
* Pose-algebra rows: one call on a batch of ``--n`` Transforms against a
  Python loop over scikit-robot ``Coordinates`` (one object per pose, as
  its API requires). The loop is timed on ``--loop-n`` poses and scaled to
  ``--n`` (it is linear in the number of poses); the column says so.

``x faster`` is scikit-robot time / rbm_nb time.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb.rigid_transform import Transform
from rbm_nb.sdf import GridSDF


def best(func, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def row(name, ours, theirs, note=""):
    print(
        f"{name:<38} {ours * 1e3:>10.2f} {theirs * 1e3:>12.2f} "
        f"{theirs / ours:>9.1f}  {note}"
    )


def ball(n_nodes=81, radius=0.3):
    axis = np.linspace(-0.6, 0.6, n_nodes)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    return np.sqrt(x**2 + y**2 + z**2) - radius, np.full(3, -0.6), axis[1] - axis[0]


def sdf_rows(n, repeat):
    from skrobot.coordinates import Coordinates
    from skrobot.sdf import GridSDF as SkGridSDF
    from skrobot.sdf.signed_distance_function import ray_marching

    data, origin, res = ball()
    ours = GridSDF(data, origin, res)
    theirs = SkGridSDF(data, origin, res)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-0.7, 0.7, (n, 3))
    ours.sdf(pts[:10])  # compile / load the kernels outside the timing
    ours.gradient(pts[:10])
    row(
        "sdf query",
        best(lambda: ours.sdf(pts), repeat),
        best(lambda: theirs(pts), repeat),
    )
    eye = np.eye(3) * 1e-6

    def central_differences():
        with np.errstate(invalid="ignore"):  # inf - inf outside the grid
            return [theirs(pts + e) - theirs(pts - e) for e in eye]

    row(
        "gradient (skrobot: central diff.)",
        best(lambda: ours.gradient(pts), repeat),
        best(central_differences, repeat),
    )

    starts = rng.uniform(-0.55, 0.55, (4 * n, 3))
    starts = starts[np.linalg.norm(starts, axis=1) > 0.4][:n]
    dirs = rng.normal(size=starts.shape) * 0.05 - starts
    ours.ray_hits(starts[:10], dirs[:10])
    row(
        "ray_hits (skrobot: ray_marching)",
        best(lambda: ours.ray_hits(starts, dirs, tolerance=1e-6), repeat),
        best(lambda: ray_marching(starts.copy(), dirs.copy(), theirs, 1e-6), repeat),
        f"{len(starts)} rays",
    )

    rbm.clear_registry()
    ts = np.linspace(0.0, 10.0, 100)
    t = np.c_[0.1 * ts, np.zeros((100, 2))]
    q = Rotation.from_euler("z", 0.3 * ts[:, None]).as_quat(scalar_first=True)
    rbm.register_frame("world")
    rbm.register_frame(
        "object", parent="world", translation=t, rotation=q, timestamps=ts
    )
    moving = GridSDF(data, origin, res, frame="object")
    which = np.sort(rng.integers(0, 100, n))
    rot = Rotation.from_quat(q, scalar_first=True).as_matrix()

    def skrobot_moving():
        out = np.empty(n)
        for i in range(100):
            sel = which == i
            theirs.newcoords(Coordinates(pos=t[i], rot=rot[i]))
            out[sel] = theirs(pts[sel])
        return out

    moving.sdf(pts[:10], frame="world", timestamps=ts[which[:10]])
    row(
        "sdf query, moving frame (100 times)",
        best(lambda: moving.sdf(pts, frame="world", timestamps=ts[which]), repeat),
        best(skrobot_moving, repeat),
    )
    rbm.clear_registry()


def pose_rows(n, loop_n, repeat):
    from skrobot.coordinates import Coordinates

    rng = np.random.default_rng(1)
    q = Rotation.random(n, rng=rng).as_quat(scalar_first=True)
    tfs = Transform(rng.normal(size=(n, 3)), q)
    others = Transform(
        rng.normal(size=(n, 3)), Rotation.random(n, rng=rng).as_quat(scalar_first=True)
    )
    vecs = rng.normal(size=(n, 3))
    angles = rng.uniform(-np.pi, np.pi, n)
    mats = Rotation.from_quat(q, scalar_first=True).as_matrix()
    other_mats = Rotation.from_quat(
        np.asarray(others.rotation), scalar_first=True
    ).as_matrix()
    tr = np.asarray(tfs.translation)
    other_tr = np.asarray(others.translation)
    scale = n / loop_n
    note = f"skrobot: loop over {loop_n} Coordinates x {scale:g}"

    def looped(method):
        def run():
            for i in range(loop_n):
                method(i)

        return best(run, repeat) * scale

    def coords(i):
        return Coordinates(pos=tr[i], rot=mats[i])

    def other(i):
        return Coordinates(pos=other_tr[i], rot=other_mats[i])

    construct = looped(coords)  # subtracted below: only the method is timed
    tfs[:2].translate(vecs[:2])  # warm the kernels
    row(
        "translate (local)",
        best(lambda: tfs.translate(vecs), repeat),
        looped(lambda i: coords(i).translate(vecs[i])) - construct,
        note,
    )
    tfs[:2].rotate(angles[:2], vecs[:2])
    row(
        "rotate (vector axis, local)",
        best(lambda: tfs.rotate(angles, vecs), repeat),
        looped(lambda i: coords(i).rotate(angles[i], vecs[i])) - construct,
        note,
    )
    row(
        "rotate ('z', world)",
        best(lambda: tfs.rotate(angles, "z", wrt="world"), repeat),
        looped(lambda i: coords(i).rotate(angles[i], "z", wrt="world")) - construct,
        note,
    )
    both = looped(lambda i: (coords(i), other(i)))
    tfs.difference_position(others)  # warm the kernels
    row(
        "difference_position",
        best(lambda: tfs.difference_position(others), repeat),
        looped(lambda i: coords(i).difference_position(other(i))) - both,
        note,
    )
    row(
        "difference_rotation",
        best(lambda: tfs.difference_rotation(others), repeat),
        looped(lambda i: coords(i).difference_rotation(other(i))) - both,
        note,
    )
    row(
        "difference_rotation (mirror 'x')",
        best(lambda: tfs.difference_rotation(others, rotation_mirror="x"), repeat),
        looped(lambda i: coords(i).difference_rotation(other(i), rotation_mirror="x"))
        - both,
        note,
    )
    row(
        "align_axis_to_direction",
        best(lambda: tfs.align_axis_to_direction(vecs), repeat),
        looped(lambda i: coords(i).align_axis_to_direction(vecs[i])) - construct,
        note,
    )
    single = tfs[0]
    c0 = coords(0)
    row(
        "transform_vector (1 pose, n points)",
        best(lambda: single.transform_vector(vecs), repeat),
        best(lambda: c0.transform_vector(vecs), repeat),
        "skrobot: its batched (n, 3) form",
    )
    row(
        "inverse_transform_vector (1 pose, n pts)",
        best(lambda: single.inverse_transform_vector(vecs), repeat),
        best(lambda: c0.inverse_transform_vector(vecs), repeat),
        "skrobot: its batched (n, 3) form",
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000)
    parser.add_argument("--loop-n", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    import skrobot

    print(
        f"n = {args.n}, best of {args.repeat}; python {platform.python_version()}, "
        f"numpy {np.__version__}, scikit-robot {skrobot.__version__}"
    )
    print(f"{'operation':<38} {'rbm_nb ms':>10} {'skrobot ms':>12} {'x faster':>9}")
    sdf_rows(args.n, args.repeat)
    pose_rows(args.n, args.loop_n, args.repeat)


if __name__ == "__main__":
    main()
