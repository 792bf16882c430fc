"""Where the fused kernels' parallel twins start to pay (``_parallel.MIN_ROWS``).

For the head/eye chain of ``bench_fused.py`` (world <- head (squad) <- eye,
with n eye samples, head at 200/340 of the eye's rate) and n from 1e3 to
1e7 rows, prints the time of

* ``lookup_transform("left_eye", "world")`` (n rows) and
* ``transform_points`` of n points at the eye's times (world -> left_eye)

on the serial kernels (``RBM_NB_NUM_THREADS=1``) and on the parallel twins
with 2 threads (``RBM_NB_NUM_THREADS=2`` and ``_parallel.MIN_ROWS`` set to 0,
so that every size runs them), their ratio, ns per row beside the fused
floor kernel of ``bench_fused.py`` and its 2-thread twin, and the crossover:
the smallest size from which the twins win at every larger size, for both
operations. Best of 7 (3 from 1e6 rows) in one process, serial and parallel calls
in turns, tables complete
(the steady state); the load average is printed, as the machine is shared.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_parallel.py [--quick] [--sizes 1e4 1e7]
(--quick stops at 1e6 rows; the whole run takes a few minutes.)
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

warnings.filterwarnings("ignore")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_fused import floor_args, floor_kernels, threads  # noqa: E402

SIZES = [1_000, 2_000, 5_000, 10_000, 20_000, 50_000, 100_000, 200_000]
SIZES += [500_000, 1_000_000, 10_000_000]


def alternating(fn_a, fn_b, repeats):
    """Best times of fn_a and fn_b, called in turns (load changes hit both alike)."""
    a: list[float] = []
    b: list[float] = []
    pairs = [(fn_a, a), (fn_b, b)]
    for turn in range(repeats):
        for fn, out in pairs[turn % 2 :] + pairs[: turn % 2]:  # the order alternates
            t0 = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t0)
    return min(a), min(b)


def serial(fn):
    """fn on the serial kernels (RBM_NB_NUM_THREADS=1)."""

    def call():
        with threads(1):
            return fn()

    return call


def parallel(fn):
    """fn on the parallel twins, 2 threads, whatever its size (MIN_ROWS = 0)."""
    from rbm_nb._infra import parallel as _parallel

    def call():
        saved = _parallel.MIN_ROWS
        _parallel.MIN_ROWS = 0
        try:
            with threads(2):
                return fn()
        finally:
            _parallel.MIN_ROWS = saved

    return call


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="stop at 1e6 rows")
    parser.add_argument("--sizes", nargs="+", type=float, help="these sizes only")
    args = parser.parse_args()
    sizes = [n for n in SIZES if not (args.quick and n > 1_000_000)]
    if args.sizes:
        sizes = [int(n) for n in args.sizes]

    import numba

    import rbm_nb as rbm
    from rbm_nb._infra import parallel as _parallel

    print(f"load average {os.getloadavg()}; numba threading layer: ", end="")
    floor, floor_2 = floor_kernels()
    numba.set_num_threads(2)
    floor_2(*floor_args(1000))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    print(numba.threading_layer(), flush=True)
    print(
        "ms per call (best of 7, in turns; 3 from 1e6 rows), serial (1T) against the "
        "parallel twins on 2 threads (2T); ns per row beside the floor kernels"
    )
    head = (
        f"{'rows':>9} | {'lookup 1T':>10} {'2T':>8} {'1T/2T':>6} |"
        f" {'points 1T':>10} {'2T':>8} {'1T/2T':>6} |"
        f" {'ns/row 1T':>9} {'2T':>6} {'floor 1T':>9} {'2T':>6}"
    )
    print(head)
    print("-" * len(head))
    wins = []
    for n in sizes:
        fargs = floor_args(n)  # registers the chain with n eye samples
        eye_ts = rbm.lookup_transform("left_eye", "world", return_timestamps=True)[2]
        points = np.random.default_rng(n).normal(size=(len(eye_ts), 3))
        m = len(eye_ts)
        reps = 7 if n < 1_000_000 else 3

        def lookup():
            return rbm.lookup_transform("left_eye", "world")

        def transform(points=points, eye_ts=eye_ts):
            return rbm.transform_points(points, "world", "left_eye", timestamps=eye_ts)

        times = {}
        for label, fn in (("lookup", lookup), ("points", transform)):
            one, two = serial(fn)(), parallel(fn)()  # warm-up; the twins: same bits
            if isinstance(one, np.ndarray):
                one, two = (one,), (two,)
            for x, y in zip(one, two, strict=True):
                assert x is None or np.array_equal(x, y, equal_nan=True)
            times[label, 1], times[label, 2] = alternating(
                serial(fn), parallel(fn), reps
            )

        def floor_twin(fargs=fargs):
            numba.set_num_threads(2)
            try:
                return floor_2(*fargs)
            finally:
                numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)

        f_1, f_2 = alternating(lambda fargs=fargs: floor(*fargs), floor_twin, reps)
        lk = times["lookup", 1] / times["lookup", 2]
        pt = times["points", 1] / times["points", 2]
        wins.append((n, lk > 1.0 and pt > 1.0))
        print(
            f"{m:>9} | {times['lookup', 1] * 1e3:>10.3f} {times['lookup', 2] * 1e3:>8.3f}"
            f" {lk:>6.2f} | {times['points', 1] * 1e3:>10.3f}"
            f" {times['points', 2] * 1e3:>8.3f} {pt:>6.2f} |"
            f" {times['lookup', 1] / m * 1e9:>9.1f} {times['lookup', 2] / m * 1e9:>6.1f}"
            f" {f_1 / m * 1e9:>9.1f} {f_2 / m * 1e9:>6.1f}",
            flush=True,
        )
    crossover = None
    for n, won in reversed(wins):
        if not won:
            break
        crossover = n
    print(f"load average {os.getloadavg()}")
    if crossover is None:
        print("crossover: the parallel twins never won at the largest size")
    else:
        print(
            f"crossover: the twins win for both operations from {crossover:,} rows "
            f"on (MIN_ROWS now {_parallel.MIN_ROWS:,})"
        )


if __name__ == "__main__":
    main()
