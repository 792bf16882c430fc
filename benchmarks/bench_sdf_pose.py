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

``x faster`` is scikit-robot time / rbm_nb time; ``max |diff|`` is the
largest absolute difference between the two results on the rows timed (for
poses: between the 4x4 matrices), with the same out-of-grid entries on both
sides (checked, not counted).
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb.core.rigid_transform import Transform
from rbm_nb.sdf import GridSDF


def best(func, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def max_diff(ours, theirs):
    """Largest |ours - theirs| over finite entries; both must be non-finite alike."""
    ours = np.asarray(ours, dtype=float)
    theirs = np.asarray(theirs, dtype=float)
    finite = np.isfinite(ours)
    if not np.array_equal(finite, np.isfinite(theirs)):
        raise AssertionError("rbm_nb and scikit-robot disagree on out-of-grid entries")
    return float(np.max(np.abs(ours[finite] - theirs[finite]), initial=0.0))


def row(name, ours, theirs, diff, note=""):
    print(
        f"{name:<38} {ours * 1e3:>10.2f} {theirs * 1e3:>12.2f} "
        f"{theirs / ours:>9.1f} {diff:>11.1e}  {note}"
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
        max_diff(ours.sdf(pts), theirs(pts)),
    )
    eye = np.eye(3) * 1e-6

    def central_differences():
        with np.errstate(invalid="ignore"):  # inf - inf outside the grid
            return [theirs(pts + e) - theirs(pts - e) for e in eye]

    inside = ~ours.is_out_of_bounds(pts)
    fd = np.stack(central_differences(), axis=1) / 2e-6
    row(
        "gradient (skrobot: central diff.)",
        best(lambda: ours.gradient(pts), repeat),
        best(central_differences, repeat),
        # a difference straddling a cell face mixes two cells: skip those few
        np.quantile(np.abs(ours.gradient(pts)[inside] - fd[inside]).max(axis=1), 0.99),
        "99th percentile (cell faces excluded)",
    )

    starts = rng.uniform(-0.55, 0.55, (4 * n, 3))
    starts = starts[np.linalg.norm(starts, axis=1) > 0.4][:n]
    dirs = rng.normal(size=starts.shape) * 0.05 - starts
    ours.ray_hits(starts[:10], dirs[:10])
    tips, _ = ray_marching(starts.copy(), dirs.copy(), theirs, 1e-9)
    row(
        "ray_hits (skrobot: ray_marching)",
        best(lambda: ours.ray_hits(starts, dirs, tolerance=1e-6), repeat),
        best(lambda: ray_marching(starts.copy(), dirs.copy(), theirs, 1e-6), repeat),
        max_diff(ours.ray_hits(starts, dirs, tolerance=1e-10).points, tips),
        f"{len(starts)} rays; diff at tolerance 1e-10 vs 1e-9",
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
        max_diff(
            moving.sdf(pts, frame="world", timestamps=ts[which]), skrobot_moving()
        ),
    )
    rbm.clear_registry()


def pose_rows(n, loop_n, repeat):
    from skrobot.coordinates import Coordinates

    rng = np.random.default_rng(1)
    q = Rotation.random(n, rng=rng).as_quat(scalar_first=True)
    tfs = Transform(rng.normal(size=(n, 3)), q)
    q_other = Rotation.random(n, rng=rng).as_quat(scalar_first=True)
    others = Transform(rng.normal(size=(n, 3)), q_other)
    vecs = rng.normal(size=(n, 3))
    angles = rng.uniform(-np.pi, np.pi, n)
    mats = Rotation.from_quat(q, scalar_first=True).as_matrix()
    other_mats = Rotation.from_quat(q_other, scalar_first=True).as_matrix()
    tr = np.asarray(tfs.translation)
    other_tr = np.asarray(others.translation)
    scale = n / loop_n
    note = f"skrobot: loop over {loop_n} Coordinates x {scale:g}"

    def coords(i):
        return Coordinates(pos=tr[i], rot=mats[i])

    def other(i):
        return Coordinates(pos=other_tr[i], rot=other_mats[i])

    def looped(method, build):
        """Time ``method(obj, i)`` over ``loop_n`` objects built beforehand, scaled to n."""

        def once():
            objects = [build(i) for i in range(loop_n)]  # not timed
            start = time.perf_counter()
            for i in range(loop_n):
                method(objects[i], i)
            return time.perf_counter() - start

        return min(once() for _ in range(repeat)) * scale

    def pose_row(name, ours_call, method, setup, as_result):
        ours_call(slice(0, 2))  # warm the kernels
        ours = ours_call(slice(None))
        theirs = np.array([as_result(method(setup(i), i)) for i in range(loop_n)])
        mine = ours.as_matrix() if isinstance(ours, Transform) else ours
        row(
            name,
            best(lambda: ours_call(slice(None)), repeat),
            looped(method, setup),
            max_diff(mine[:loop_n], theirs),
            note,
        )

    def matrix(c):
        return c.T()

    def same(v):
        return v

    # skrobot's translate returns None in place: time it, then read the object
    tfs[:2].translate(vecs[:2])
    mine = tfs.translate(vecs).as_matrix()[:loop_n]
    theirs = []
    for i in range(loop_n):
        c = coords(i)
        c.translate(vecs[i])
        theirs.append(c.T())
    row(
        "translate (local)",
        best(lambda: tfs.translate(vecs), repeat),
        looped(lambda c, i: c.translate(vecs[i]), coords),
        max_diff(mine, theirs),
        note,
    )
    pose_row(
        "rotate (vector axis, local)",
        lambda s: tfs[s].rotate(angles[s], vecs[s]),
        lambda c, i: c.rotate(angles[i], vecs[i]),
        coords,
        matrix,
    )
    pose_row(
        "rotate ('z', world)",
        lambda s: tfs[s].rotate(angles[s], "z", wrt="world"),
        lambda c, i: c.rotate(angles[i], "z", wrt="world"),
        coords,
        matrix,
    )

    def pair(i):
        return coords(i), other(i)

    pose_row(
        "difference_position",
        lambda s: tfs[s].difference_position(others[s]),
        lambda co, i: co[0].difference_position(co[1]),
        pair,
        same,
    )
    pose_row(
        "difference_rotation",
        lambda s: tfs[s].difference_rotation(others[s]),
        lambda co, i: co[0].difference_rotation(co[1]),
        pair,
        same,
    )
    pose_row(
        "difference_rotation (mirror 'x', 'yz')",
        lambda s: tfs[s].difference_rotation(
            others[s], rotation_mask="yz", rotation_mirror="x"
        ),
        lambda co, i: co[0].difference_rotation(
            co[1], rotation_mask="yz", rotation_mirror="x"
        ),
        pair,
        same,
    )
    pose_row(
        "align_axis_to_direction",
        lambda s: tfs[s].align_axis_to_direction(vecs[s]),
        lambda c, i: c.align_axis_to_direction(vecs[i]),
        coords,
        matrix,
    )
    single = tfs[0]
    c0 = coords(0)
    many = max(repeat, 15)  # sub-millisecond rows: more tries for a stable best
    single.transform_vector(vecs[:2])
    row(
        "transform_vector (1 pose, n points)",
        best(lambda: single.transform_vector(vecs), many),
        best(lambda: c0.transform_vector(vecs), many),
        max_diff(single.transform_vector(vecs), c0.transform_vector(vecs)),
        "skrobot: its batched (n, 3) form",
    )
    row(
        "inverse_transform_vector (1 pose, n pts)",
        best(lambda: single.inverse_transform_vector(vecs), many),
        best(lambda: c0.inverse_transform_vector(vecs), many),
        max_diff(
            single.inverse_transform_vector(vecs), c0.inverse_transform_vector(vecs)
        ),
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
    print(
        f"{'operation':<38} {'rbm_nb ms':>10} {'skrobot ms':>12} {'x faster':>9} "
        f"{'max |diff|':>11}"
    )
    sdf_rows(args.n, args.repeat)
    pose_rows(args.n, args.loop_n, args.repeat)


if __name__ == "__main__":
    main()
