"""Array operations of issue 16 against rigid-body-motion 0.9.3, in one script.

Prints, on the head/eye workload (the real recording when ``RBM_NB_DATA_DIR``
points at it, else the synthetic one of ``bench_core.py``):

1. a table of rbm_nb against rigid-body-motion measured in the same process
   (best of 5 after a warm-up call, interleaved), for ``qinterp`` (head
   orientations at the eye's timestamps), ``rotate_vectors``, ``qmul`` and
   ``qinv`` on 1M rows, and the velocity lookups (with the plain
   ``lookup_transform`` they are computed from, for the floor). Operations
   with a parallel twin (``rbm_nb._infra.parallel``) are timed with 1 and with 2
   threads (``RBM_NB_NUM_THREADS``);
2. that table in three malloc regimes, each in its own process:
   ``MALLOC_MMAP_THRESHOLD_=131072`` (big arrays are fresh pages on every
   call: first-touch page faults), large thresholds (freed memory is reused)
   and glibc's default;
3. peak temporary memory (tracemalloc: numpy's allocations) of the array
   operations and the velocity lookups against the size of their output.

The machine's load (``os.getloadavg``) is printed with each table: on a
shared machine only ratios measured in the same run mean anything.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_array_ops.py [--regime NAME] [--only table|memory]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

warnings.filterwarnings("ignore")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_core import build_workload, continuous_rotations  # noqa: E402

REPEATS = 5
REGIMES = {
    "first-touch": {"MALLOC_MMAP_THRESHOLD_": "131072"},
    "reuse": {
        "MALLOC_MMAP_THRESHOLD_": str(2**30),
        "MALLOC_TRIM_THRESHOLD_": str(2**31),
        "MALLOC_TOP_PAD_": str(2**28),
    },
    "default": {},
}
THREADS = "RBM_NB_NUM_THREADS"


def workload():
    """(label, frames, head_ts, eye_ts, head orientations, gaze vectors)."""
    folder = os.environ.get("RBM_NB_DATA_DIR")
    if folder and (Path(folder) / "head.nc").exists():
        from rbm_nb.data import load_example

        head = load_example("head", source="remote")
        eye = load_example("left_eye", source="remote")
        keep = ~np.isnan(eye.orientation.values).any(axis=1)
        head_ts, eye_ts = head.time.values, eye.time.values[keep]
        cam = np.array((0.99, 0.1, 0.0, 0.0)) / np.linalg.norm((0.99, 0.1, 0.0, 0.0))
        frames = [
            ("world", {}),
            ("t265/world", {"parent": "world", "rotation": (np.sqrt(0.5), np.sqrt(0.5), 0, 0)}),
            ("head", {"parent": "t265/world", "translation": head.position.values,
                      "rotation": head.orientation.values, "timestamps": head_ts}),
            ("scene_cam", {"parent": "head", "translation": (0.0, -0.05, 0.02), "rotation": cam}),
            ("left_eye", {"parent": "scene_cam", "translation": np.tile([0.03, 0.0, 0.0], (len(eye_ts), 1)),
                          "rotation": eye.orientation.values[keep], "timestamps": eye_ts}),
        ]  # fmt: skip
        gaze = np.random.default_rng(0).normal(size=(len(eye_ts), 3))
        label = "real head/eye recording"
        return label, frames, head_ts, eye_ts, head.orientation.values, gaze
    frames, head_ts, eye_ts, head_rot, gaze = build_workload()
    return (
        "synthetic head/eye workload (bench_core.py)",
        frames,
        head_ts,
        eye_ts,
        head_rot,
        gaze,
    )


def register(module, frames) -> None:
    module.clear_registry()
    for name, kwargs in frames:
        module.register_frame(name, **kwargs)


def best_pair(fn_a, fn_b, repeats=REPEATS):
    """Best times of two calls, interleaved (a warm-up call each first)."""
    fn_a()
    if fn_b is not None:
        fn_b()
    ta, tb = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn_a()
        ta.append(time.perf_counter() - t0)
        if fn_b is not None:
            t0 = time.perf_counter()
            fn_b()
            tb.append(time.perf_counter() - t0)
    return min(ta), (min(tb) if tb else None)


def operations(work):
    """(label, rbm_nb call, reference call, has a parallel twin)."""

    _, _, head_ts, eye_ts, head_rot, _ = work
    inside = eye_ts[(eye_ts >= head_ts[0]) & (eye_ts <= head_ts[-1])]
    rng = np.random.default_rng(1)
    q1m = np.ascontiguousarray(continuous_rotations(rng, 1_000_000, 0.001))
    p1m = np.ascontiguousarray(continuous_rotations(rng, 1_000_000, 0.002))
    v1m = rng.normal(size=(1_000_000, 3))
    import importlib

    import xarray as xr

    da = xr.DataArray(head_rot, {"time": head_ts}, ("time", "quaternion_axis"))

    def accessor(m):
        # both packages register ".rbm": call each one's accessor class
        return importlib.import_module(f"{m.__name__}.accessors").DataArrayAccessor(da)

    return [
        (f"qinterp {len(head_ts)} head -> {len(inside)} eye times",
         lambda m: m.qinterp(head_rot, head_ts, inside), True),
        ("  the same with .rbm.qinterp(time=...)",
         lambda m: accessor(m).qinterp(time=inside), True),
        ("rotate_vectors 1M", lambda m: m.rotate_vectors(q1m, v1m), True),
        ("qmul 1M", lambda m: m.qmul(q1m, p1m), True),
        ("qinv 1M", lambda m: m.qinv(q1m), True),
        ("lookup_transform left_eye->world (floor)",
         lambda m: m.lookup_transform("left_eye", "world"), False),
        ("lookup_twist head wrt world", lambda m: m.lookup_twist("head", "world"), False),
        ("lookup_linear_velocity left_eye wrt world",
         lambda m: m.lookup_linear_velocity("left_eye", "world"), False),
        ("lookup_angular_velocity left_eye wrt world",
         lambda m: m.lookup_angular_velocity("left_eye", "world"), False),
    ]  # fmt: skip


def table() -> None:
    import rigid_body_motion as ref

    import rbm_nb as rbm

    work = workload()
    register(rbm, work[1])
    register(ref, work[1])
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"{work[0]}; best of {REPEATS}; load average {load}")
    print(
        f"{'operation':<48} {'threads':>7} {'rbm_nb':>10} {'rbm 0.9.3':>10} {'x ref':>7}"
    )
    for label, call, parallel in operations(work):
        for threads in ("1", "2") if parallel else (None,):
            if threads is not None:
                os.environ[THREADS] = threads
            t_nb, t_ref = best_pair(
                lambda call=call: call(rbm), lambda call=call: call(ref)
            )
            os.environ.pop(THREADS, None)
            assert t_ref is not None
            print(
                f"{label:<48} {threads or '':>7} {t_nb * 1e3:8.2f}ms {t_ref * 1e3:8.1f}ms "
                f"{t_ref / t_nb:6.1f}x",
                flush=True,
            )


def regimes() -> None:
    for regime, env in REGIMES.items():
        print(f"\n== malloc regime: {regime} {env or '(glibc default)'}", flush=True)
        cmd = [sys.executable, __file__, "--regime", regime]
        subprocess.run(cmd, env=dict(os.environ, **env), check=True)


def peak_memory(fn):
    """(peak traced bytes during one call, bytes of its result arrays)."""
    fn()
    tracemalloc.start()
    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    result = fn()
    peak = tracemalloc.get_traced_memory()[1] - before
    tracemalloc.stop()
    arrays = result if isinstance(result, tuple) else (result,)
    # DataArrays count their data
    arrays = tuple(
        a if isinstance(a, np.ndarray) else getattr(a, "data", a) for a in arrays
    )
    return peak, sum(a.nbytes for a in arrays if isinstance(a, np.ndarray))


def memory() -> None:
    import rbm_nb as rbm

    work = workload()
    _, frames, head_ts, eye_ts, _, gaze = work
    register(rbm, frames)
    quats = continuous_rotations(np.random.default_rng(2), len(eye_ts), 0.01)
    n_head = len(head_ts)
    print("\n== peak temporary memory (tracemalloc) against the output")
    cases = [
        ("transform_points (eye ts)",
         lambda: rbm.transform_points(gaze, "world", "left_eye", timestamps=eye_ts)),
        ("transform_vectors (head ts)",
         lambda: rbm.transform_vectors(gaze[:n_head], "world", "left_eye", timestamps=head_ts)),
        ("transform_quaternions (eye ts)",
         lambda: rbm.transform_quaternions(quats, "world", "left_eye", timestamps=eye_ts)),
    ] + [(label, lambda call=call: call(rbm)) for label, call, _ in operations(work)]  # fmt: skip
    for label, fn in cases:
        peak, out = peak_memory(fn)
        print(
            f"{label:<48} peak {peak / 1e6:7.1f} MB  output {out / 1e6:6.1f} MB  {peak / out:5.2f}x",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument(
        "--regime", choices=REGIMES, help="(internal) one table, this process"
    )
    parser.add_argument("--only", choices=["table", "memory"])
    args = parser.parse_args()
    if args.regime:
        table()
        return
    if args.only in (None, "table"):
        regimes()
    if args.only in (None, "memory"):
        memory()


if __name__ == "__main__":
    main()
