"""Timings of the quaternion utilities and estimators against a plain numba loop
and rigid-body-motion 0.9.3.

Run: ``.venv/bin/python benchmarks/bench_quaternion_utils.py [n]`` (default
n = 1_000_000). Prints the best of several runs per row, in milliseconds.
"""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np
from numba import njit


@njit(cache=True)
def plain_rotate(q, v):
    """The simplest loop one would write: v + 2 r x (s v + r x v) / |q|²."""
    out = np.empty_like(v)
    for i in range(q.shape[0]):
        w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        vx, vy, vz = v[i, 0], v[i, 1], v[i, 2]
        n2 = w * w + x * x + y * y + z * z
        tx = w * vx + (y * vz - z * vy)
        ty = w * vy + (z * vx - x * vz)
        tz = w * vz + (x * vy - y * vx)
        out[i, 0] = vx + 2.0 * (y * tz - z * ty) / n2
        out[i, 1] = vy + 2.0 * (z * tx - x * tz) / n2
        out[i, 2] = vz + 2.0 * (x * ty - y * tx) / n2
    return out


def best_ms(func, repeat):
    func()  # compile / warm caches
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return 1e3 * min(times)


def main(n: int) -> None:
    import rbm_nb as rbm

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import rigid_body_motion as ref

    rng = np.random.default_rng(0)
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    v = rng.standard_normal((n, 3))
    t = np.cumsum(rng.uniform(0.009, 0.011, n))
    smooth = rbm.from_euler_angles(np.cumsum(rng.normal(0, 0.01, (n, 3)), axis=0))
    x = np.cumsum(rng.normal(0, 1e-3, (n, 3)), axis=0)
    t_out = np.linspace(t[0], t[-1], n)

    rows = [
        ("rotate_vectors", lambda: plain_rotate(q, v), lambda: rbm.rotate_vectors(q, v),
         lambda: ref.rotate_vectors(q, v)),
        ("qmul", None, lambda: rbm.qmul(q, smooth), lambda: ref.qmul(q, smooth)),
        ("qinv", None, lambda: rbm.qinv(q), lambda: ref.qinv(q)),
        ("qinterp (squad)", None, lambda: rbm.qinterp(smooth, t, t_out),
         lambda: ref.qinterp(smooth, t, t_out)),
        ("estimate_linear_velocity", None, lambda: rbm.estimate_linear_velocity(x, timestamps=t),
         lambda: ref.estimate_linear_velocity(x, timestamps=t)),
        ("  + outlier_thresh, cutoff", None,
         lambda: rbm.estimate_linear_velocity(x, timestamps=t, outlier_thresh=1e-2, cutoff=0.3),
         lambda: ref.estimate_linear_velocity(x, timestamps=t, outlier_thresh=1e-2, cutoff=0.3)),
        ("estimate_angular_velocity", None,
         lambda: rbm.estimate_angular_velocity(smooth, timestamps=t),
         lambda: ref.estimate_angular_velocity(smooth, timestamps=t)),
    ]  # fmt: skip
    print(f"n = {n:,} samples; best of several runs, ms")
    print(
        f"{'function':30s} {'plain numba':>12s} {'rbm_nb':>10s} {'reference':>10s} {'speed-up':>9s}"
    )
    for name, plain, ours, theirs in rows:
        p = best_ms(plain, 7) if plain else float("nan")
        o = best_ms(ours, 7)
        r = best_ms(theirs, 2)
        print(f"{name:30s} {p:12.2f} {o:10.2f} {r:10.1f} {r / o:8.1f}x")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)
