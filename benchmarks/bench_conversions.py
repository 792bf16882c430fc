"""Rotation conversions: rbm_nb against scipy and the memory-bandwidth floor.

Run from the repository root::

    .venv/bin/python benchmarks/bench_conversions.py [--n 1000000] [--repeat 9]

For each conversion of ``n`` rotations the table gives the best of
``--repeat`` wall-clock times (ms) of

* ``rbm_nb``: the public function in ``rbm_nb.conversions`` (validation
  included);
* ``floor``: a numba loop that reads the same input bytes and writes an
  output array of the same size, allocation included - no conversion can
  beat it in one pass;
* ``scipy``: ``scipy.spatial.transform`` doing the same conversion (with
  ``scalar_first=True`` so that no reordering is timed for rbm_nb alone).

A second table times the ``Transform`` value type against scipy's
``RigidTransform`` on ``n`` transforms.

``x floor`` is rbm_nb / floor, ``x faster`` is scipy / rbm_nb. All numbers
come from the same run, on the same data.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from functools import partial

import numba
import numpy as np
import scipy
from numba import njit
from scipy.spatial.transform import RigidTransform, Rotation

import rbm_nb.core.conversions as conv


@njit(cache=True)
def _floor_copy(src, n_out):
    """Read every element of ``src`` once and write ``n_out`` new elements."""
    n_in = src.size
    out = np.empty(n_out)
    common = min(n_in, n_out)
    for i in range(common):
        out[i] = src[i]
    for i in range(common, n_out):
        out[i] = src[i - common]
    rest = 0.0
    for i in range(common, n_in):
        rest += src[i]
    if n_out > 0:
        out[0] += 0.0 * rest
    return out


def _best(func, repeat):
    func()  # compile / warm up
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return best * 1e3


def _cases(n):
    rng = np.random.default_rng(0)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    matrices = conv.matrix_from_quaternion(q)
    rotvec = conv.rotation_vector_from_quaternion(q)
    axis, angle = conv.axis_angle_from_quaternion(q)
    euler_xyz = conv.euler_from_quaternion(q, "xyz")
    euler_zxz = conv.euler_from_quaternion(q, "zxz", extrinsic=True)
    translation = rng.normal(size=(n, 3))
    homogeneous = conv.homogeneous_from_transform(translation, q)
    aa_in = np.concatenate([axis.ravel(), angle])
    th_in = np.concatenate([translation.ravel(), q.ravel()])

    def rot(quat):
        return Rotation.from_quat(quat, scalar_first=True)

    # name, rbm_nb call, floor input, floor output size, scipy call
    return [
        (
            "matrix_from_quaternion",
            lambda: conv.matrix_from_quaternion(q),
            q, 9 * n,
            lambda: rot(q).as_matrix(),
        ),
        (
            "quaternion_from_matrix",
            lambda: conv.quaternion_from_matrix(matrices),
            matrices, 4 * n,
            lambda: Rotation.from_matrix(matrices).as_quat(scalar_first=True),
        ),
        (
            "rotation_vector_from_quaternion",
            lambda: conv.rotation_vector_from_quaternion(q),
            q, 3 * n,
            lambda: rot(q).as_rotvec(),
        ),
        (
            "quaternion_from_rotation_vector",
            lambda: conv.quaternion_from_rotation_vector(rotvec),
            rotvec, 4 * n,
            lambda: Rotation.from_rotvec(rotvec).as_quat(scalar_first=True),
        ),
        (
            "axis_angle_from_quaternion",
            lambda: conv.axis_angle_from_quaternion(q),
            q, 4 * n,
            lambda: _scipy_axis_angle(rot(q).as_rotvec()),
        ),
        (
            "quaternion_from_axis_angle",
            lambda: conv.quaternion_from_axis_angle(axis, angle),
            aa_in, 4 * n,
            lambda: Rotation.from_rotvec(axis * angle[:, None]).as_quat(scalar_first=True),
        ),
        (
            "euler_from_quaternion xyz intr.",
            lambda: conv.euler_from_quaternion(q, "xyz"),
            q, 3 * n,
            lambda: rot(q).as_euler("XYZ"),
        ),
        (
            "quaternion_from_euler xyz intr.",
            lambda: conv.quaternion_from_euler(euler_xyz, "xyz"),
            euler_xyz, 4 * n,
            lambda: Rotation.from_euler("XYZ", euler_xyz).as_quat(scalar_first=True),
        ),
        (
            "euler_from_quaternion zxz extr.",
            lambda: conv.euler_from_quaternion(q, "zxz", extrinsic=True),
            q, 3 * n,
            lambda: rot(q).as_euler("zxz"),
        ),
        (
            "quaternion_from_euler zxz extr.",
            lambda: conv.quaternion_from_euler(euler_zxz, "zxz", extrinsic=True),
            euler_zxz, 4 * n,
            lambda: Rotation.from_euler("zxz", euler_zxz).as_quat(scalar_first=True),
        ),
        (
            "homogeneous_from_transform",
            lambda: conv.homogeneous_from_transform(translation, q),
            th_in, 16 * n,
            lambda: RigidTransform.from_components(translation, rot(q)).as_matrix(),
        ),
        (
            "transform_from_homogeneous",
            lambda: conv.transform_from_homogeneous(homogeneous),
            homogeneous, 7 * n,
            lambda: _scipy_components(RigidTransform.from_matrix(homogeneous)),
        ),
    ]  # fmt: skip


def _scipy_axis_angle(rotvec):
    angle = np.linalg.norm(rotvec, axis=1)
    return rotvec / angle[:, None], angle


def _scipy_components(transform):
    translation, rotation = transform.as_components()
    return translation, rotation.as_quat(scalar_first=True)


def _transform_cases(n):
    """The Transform value type against scipy's RigidTransform."""
    from rbm_nb.core.rigid_transform import Transform

    rng = np.random.default_rng(1)
    q = rng.normal(size=(2, n, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    t = rng.normal(size=(2, n, 3))
    points = rng.normal(size=(n, 3))
    a, b = Transform(t[0], q[0]), Transform(t[1], q[1])
    sa = RigidTransform.from_components(
        t[0], Rotation.from_quat(q[0], scalar_first=True)
    )
    sb = RigidTransform.from_components(
        t[1], Rotation.from_quat(q[1], scalar_first=True)
    )
    return [
        ("a @ b", lambda: a @ b, lambda: sa * sb),
        ("a.inv()", a.inv, sa.inv),
        ("a.apply(points)", lambda: a.apply(points), lambda: sa.apply(points)),
        ("a.as_matrix()", a.as_matrix, sa.as_matrix),
        ("Transform(t, q) (validated)", lambda: Transform(t[0], q[0]),
         lambda: RigidTransform.from_components(t[0], Rotation.from_quat(q[0], scalar_first=True))),
    ]  # fmt: skip


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000, help="rotations per call")
    parser.add_argument("--repeat", type=int, default=9, help="timed calls per entry")
    args = parser.parse_args(argv)

    print(
        f"n = {args.n:,} rotations, best of {args.repeat}; numpy {np.__version__}, "
        f"scipy {scipy.__version__}, numba {numba.__version__}, "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs"
    )
    header = f"{'conversion':34s} {'rbm_nb':>9s} {'floor':>8s} {'x floor':>8s} {'scipy':>9s} {'x faster':>9s}"
    print(header)
    print("-" * len(header))
    for name, ours, floor_in, n_out, theirs in _cases(args.n):
        flat = np.ascontiguousarray(floor_in).reshape(-1)
        t_ours = _best(ours, args.repeat)
        t_floor = _best(partial(_floor_copy, flat, n_out), args.repeat)
        t_scipy = _best(theirs, max(3, args.repeat // 3))
        print(
            f"{name:34s} {t_ours:9.2f} {t_floor:8.2f} {t_ours / t_floor:8.2f} "
            f"{t_scipy:9.2f} {t_scipy / t_ours:9.1f}"
        )
    print("times in ms")
    print()
    header = f"{'Transform (n transforms)':34s} {'rbm_nb':>9s} {'scipy':>9s} {'x faster':>9s}"
    print(header)
    print("-" * len(header))
    for name, ours, theirs in _transform_cases(args.n):
        t_ours = _best(ours, args.repeat)
        t_scipy = _best(theirs, max(3, args.repeat // 3))
        print(f"{name:34s} {t_ours:9.2f} {t_scipy:9.2f} {t_scipy / t_ours:9.1f}")
    print("times in ms; scipy: RigidTransform")


if __name__ == "__main__":
    main()
