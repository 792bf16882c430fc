"""Frame-core speed: rbm_nb against rigid-body-motion 0.9.3, in one run.

The workload has the shape of the example head/eye recording:

    world -> t265/world (static rotation) -> head (66,629 samples, 200 Hz)
          -> scene_cam (static) -> left_eye (113,373 samples, offset times)

Each operation is timed as the best of 5 after a warm-up call, the
contenders called in turns (a reference call that takes more than 60 s is
timed once), rbm_nb twice in the same run:
on one thread and on two (``RBM_NB_NUM_THREADS=1`` and ``=2``; its parallel
kernels run only for calls of at least ``rbm_nb._infra.parallel.MIN_ROWS`` rows). Also reported: the first call
in a fresh process with an empty and with a warm numba cache, and the time
``import rbm_nb`` takes.

Run:  .venv/bin/python benchmarks/bench_core.py  [--quick]
(--quick skips the reference's slowest cases.)
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore")

SLOW_LIMIT = 60.0
REPEATS = 5
#: calls shorter than this are timed in loops lasting about this long
LOOP_SECONDS = 1e-3


def best_time(fn, repeats=REPEATS):
    """Warm up once, then the best of ``repeats`` (once if the warm-up is slow)."""
    t0 = time.perf_counter()
    fn()
    first = time.perf_counter() - t0
    if first > SLOW_LIMIT:
        return first, True
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), False


def best_in_turns(fns, repeats=REPEATS):
    """Best time of each function, called in turns after one warm-up call each.

    On a shared machine the load changes during a run; calling the
    contenders in turns exposes them to it alike, so their ratios hold. The
    order rotates from one turn to the next: a call right after another
    contender's (whose freed memory glibc may have returned to the system)
    pays page faults that a call after itself does not.
    """
    # a call of a few µs is timed as a loop of calls (about 1 ms of them, the
    # same count for every contender): one call alone measures the timer and
    # a cold cache as much as the call
    first = []
    for fn in fns:
        t0 = time.perf_counter()
        fn()
        first.append(time.perf_counter() - t0)
    loops = min(1000, max(1, int(LOOP_SECONDS / max(min(first), 1e-7))))
    times: list[list[float]] = [[] for _ in fns]
    for turn in range(repeats):
        for k in range(len(fns)):
            i = (k + turn) % len(fns)
            # an on_threads call sets its threads once around the loop (setting
            # the variable twice per call costs ~3 µs, half a small call)
            fn = getattr(fns[i], "bare", fns[i])
            with threads(getattr(fns[i], "threads", None)):
                t0 = time.perf_counter()
                for _ in range(loops):
                    fn()
                times[i].append((time.perf_counter() - t0) / loops)
    return [min(t) for t in times]


def on_threads(n, fn):
    """fn, called with rbm_nb's kernels on at most n threads."""

    def call():
        with threads(n):
            return fn()

    call.bare, call.threads = fn, n  # type: ignore[attr-defined]
    return call


@contextlib.contextmanager
def threads(n):
    """rbm_nb's kernels on at most n threads inside the block (RBM_NB_NUM_THREADS).

    rbm_nb reads the variable at each call; its parallel kernels run only for
    calls of at least ``rbm_nb._infra.parallel.MIN_ROWS`` rows, and only on cores
    that no other runnable thread wants at the time (``_parallel.free_cores``):
    on a busy machine the 2-thread columns measure the serial kernels.
    """
    if n is None:  # not an on_threads call: nothing to set
        yield
        return
    name = "RBM_NB_NUM_THREADS"
    before = os.environ.get(name)
    os.environ[name] = str(n)
    try:
        yield
    finally:
        if before is None:
            del os.environ[name]
        else:
            os.environ[name] = before


def continuous_rotations(rng, n, step):
    q = np.cumsum(rng.normal(scale=step, size=(n, 4)), axis=0) + [1.0, 0, 0, 0]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q


def datetimes(start_ns, n, rate):
    return (start_ns + np.round(np.arange(n) * 1e9 / rate).astype(np.int64)).astype(
        "datetime64[ns]"
    )


def build_workload():
    rng = np.random.default_rng(0)
    start = np.datetime64("2020-02-02T00:27:14.300365210").astype(np.int64)
    head_ts = datetimes(start, 66_629, 200.0)
    eye_ts = datetimes(start + 1_234_567, 113_373, 340.3)
    t = np.arange(66_629) / 200.0
    head_pos = np.column_stack([np.sin(t / 30) * 20, 0.02 * np.sin(t * 11), -1.4 * t])
    head_rot = continuous_rotations(rng, 66_629, 0.003)
    eye_rot = continuous_rotations(rng, 113_373, 0.004)
    frames = [
        ("world", {}),
        (
            "t265/world",
            {"parent": "world", "rotation": (np.sqrt(0.5), np.sqrt(0.5), 0, 0)},
        ),
        (
            "head",
            {
                "parent": "t265/world",
                "translation": head_pos,
                "rotation": head_rot,
                "timestamps": head_ts,
            },
        ),
        (
            "scene_cam",
            {
                "parent": "head",
                "translation": (0.0, -0.05, 0.02),
                "rotation": (0.99, 0.1, 0.0, 0.0)
                / np.linalg.norm((0.99, 0.1, 0.0, 0.0)),
            },
        ),
        (
            "left_eye",
            {
                "parent": "scene_cam",
                "translation": np.tile([0.03, 0.0, 0.0], (113_373, 1)),
                "rotation": eye_rot,
                "timestamps": eye_ts,
            },
        ),
    ]
    gaze = rng.normal(size=(113_373, 3))
    return frames, head_ts, eye_ts, head_rot, gaze


def build_big(rng):
    """1M points against a moving frame of 100k samples and a discrete one of 2k events."""
    t_frame = np.arange(100_000) * 0.001
    moving = {
        "parent": "world",
        "translation": rng.normal(size=(100_000, 3)),
        "rotation": continuous_rotations(rng, 100_000, 0.002),
        "timestamps": t_frame,
    }
    events = np.sort(rng.choice(100_000, 2_000, replace=False)) * 0.001
    discrete = {
        "parent": "world",
        "translation": rng.normal(size=(2_000, 3)),
        "rotation": continuous_rotations(rng, 2_000, 0.1),
        "timestamps": events,
        "discrete": True,
    }
    t_points = np.linspace(0.0, 99.999, 1_000_000)
    points = rng.normal(size=(1_000_000, 3))
    return moving, discrete, t_points, points


def plain_numba_rotate():
    from numba import njit

    @njit(cache=False)
    def rotate(q, v):
        out = np.empty_like(v)
        for i in range(v.shape[0]):
            w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
            vx, vy, vz = v[i, 0], v[i, 1], v[i, 2]
            # v + 2w (u x v) + 2 u x (u x v)
            cx = y * vz - z * vy
            cy = z * vx - x * vz
            cz = x * vy - y * vx
            out[i, 0] = vx + 2 * (w * cx + y * cz - z * cy)
            out[i, 1] = vy + 2 * (w * cy + z * cx - x * cz)
            out[i, 2] = vz + 2 * (w * cz + x * cy - y * cx)
        return out

    return rotate


def fresh_process_first_call(cache_dir):
    code = textwrap.dedent(
        """
        import time
        t0 = time.perf_counter()
        import numpy as np
        import rbm_nb as rbm
        rbm.register_frame("world")
        ts = np.arange(100) * 0.01
        q = np.tile([1.0, 0, 0, 0], (100, 1))
        rbm.register_frame("head", parent="world", translation=np.zeros((100, 3)), rotation=q, timestamps=ts)
        rbm.register_frame("cam", parent="head", translation=(0, 0, 1.0))
        t1 = time.perf_counter()
        rbm.lookup_transform("cam", "world")
        rbm.transform_points(np.zeros((50, 3)), "world", "cam", timestamps=ts[::2] + 0.001)
        t2 = time.perf_counter()
        print(t2 - t1, t2 - t0)
        """
    )
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    first, total = (float(x) for x in out.stdout.split())
    return first, total


def import_times(n=9):
    code = "import time; t=time.perf_counter(); import rbm_nb; print(time.perf_counter()-t)"
    times = []
    for _ in range(n):
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True
        )
        times.append(float(out.stdout))
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument(
        "--quick", action="store_true", help="skip the reference's slow cases"
    )
    args = parser.parse_args()

    import rigid_body_motion as ref

    import rbm_nb as rbm

    frames, head_ts, eye_ts, head_rot, gaze = build_workload()
    for module in (rbm, ref):
        module.clear_registry()
        for name, kwargs in frames:
            module.register_frame(name, **kwargs)

    rows = []

    def compare(label, fn_nb, fn_ref, check=None):
        contenders = [on_threads(1, fn_nb), on_threads(2, fn_nb)]
        if fn_ref is None:
            rows.append((label, *best_in_turns(contenders), None, False))
            return
        t_ref, once = best_time(fn_ref)
        if once:  # the reference is too slow for turns
            t_nb, t_nb2 = best_in_turns(contenders)
        else:
            t_nb, t_nb2, t_ref = best_in_turns([*contenders, fn_ref])
        if check is not None:
            check(fn_nb(), fn_ref())
        rows.append((label, t_nb, t_nb2, t_ref, once))

    def same(a, b):
        a = a if isinstance(a, tuple) else (a,)
        b = b if isinstance(b, tuple) else (b,)
        for x, y in zip(a, b, strict=False):
            if x is not None and np.asarray(x).dtype.kind == "f":
                x, y = np.asarray(x), np.asarray(y)
                if x.shape[-1:] == (4,):  # quaternions: up to sign
                    x = x * np.sign(np.sum(x * y, axis=-1, keepdims=True))
                # loose: the reference rounds epoch nanoseconds to float
                # (256 ns steps), which shows in finite differences
                assert x.shape == y.shape, (x.shape, y.shape)
                assert np.nanmax(np.abs(x - y)) <= 1e-3 * np.nanmax(np.abs(y)) + 1e-9

    compare(
        "lookup_transform left_eye->world",
        lambda: rbm.lookup_transform("left_eye", "world"),
        lambda: ref.lookup_transform("left_eye", "world"),
        same,
    )
    compare(
        "lookup_pose left_eye wrt world",
        lambda: rbm.lookup_pose("left_eye", "world"),
        lambda: ref.lookup_pose("left_eye", "world"),
        same,
    )
    compare(
        "transform_points 113k (eye ts) left_eye->world",
        lambda: rbm.transform_points(gaze, "world", "left_eye", timestamps=eye_ts),
        lambda: ref.transform_points(gaze, "world", "left_eye", timestamps=eye_ts),
        same,
    )
    compare(
        "transform_vectors 113k (head ts) left_eye->world",
        lambda: rbm.transform_vectors(
            gaze[:66_629], "world", "left_eye", timestamps=head_ts
        ),
        lambda: ref.transform_vectors(
            gaze[:66_629], "world", "left_eye", timestamps=head_ts
        ),
        same,
    )
    compare(
        "lookup_twist head wrt world",
        lambda: rbm.lookup_twist("head", "world"),
        lambda: ref.lookup_twist("head", "world"),
        same,
    )
    compare(
        "lookup_angular_velocity left_eye wrt world",
        lambda: rbm.lookup_angular_velocity("left_eye", "world"),
        lambda: ref.lookup_angular_velocity("left_eye", "world"),
        same,
    )
    compare(
        "lookup_transform t265/world->world (static: overhead)",
        lambda: rbm.lookup_transform("t265/world", "world"),
        lambda: ref.lookup_transform("t265/world", "world"),
        same,
    )
    one_point = np.array([0.1, 0.2, 0.3])
    compare(
        "transform_points 1 point t265/world->world (static)",
        lambda: rbm.transform_points(one_point, "world", "t265/world"),
        lambda: ref.transform_points(one_point, "world", "t265/world"),
        same,
    )
    compare(
        "qinterp 66k head -> 113k eye timestamps",
        lambda: rbm.qinterp(head_rot, head_ts, eye_ts[eye_ts <= head_ts[-1]]),
        lambda: ref.qinterp(head_rot, head_ts, eye_ts[eye_ts <= head_ts[-1]]),
        same,
    )

    rng = np.random.default_rng(1)
    q1m = continuous_rotations(rng, 1_000_000, 0.001)
    v1m = rng.normal(size=(1_000_000, 3))
    compare(
        "rotate_vectors 1M",
        lambda: rbm.rotate_vectors(q1m, v1m),
        lambda: ref.rotate_vectors(q1m, v1m),
        same,
    )
    plain = plain_numba_rotate()
    plain(q1m[:10], v1m[:10])
    t_plain, _ = best_time(lambda: plain(q1m, v1m))
    np.testing.assert_allclose(plain(q1m, v1m), rbm.rotate_vectors(q1m, v1m), atol=1e-9)
    rows.append(("rotate_vectors 1M: plain numba loop", t_plain, t_plain, None, False))

    moving, discrete, t_points, points = build_big(rng)
    for module in (rbm, ref):
        module.register_frame("moving100k", **moving)
        module.register_frame("discrete2k", **discrete)
    compare(
        "transform_points 1M via moving frame (100k)",
        lambda: rbm.transform_points(
            points, "world", "moving100k", timestamps=t_points
        ),
        None
        if args.quick
        else (
            lambda: ref.transform_points(
                points, "world", "moving100k", timestamps=t_points
            )
        ),
        same,
    )
    compare(
        "transform_points 1M via discrete frame (2k events)",
        lambda: rbm.transform_points(
            points, "world", "discrete2k", timestamps=t_points
        ),
        None
        if args.quick
        else (
            lambda: ref.transform_points(
                points, "world", "discrete2k", timestamps=t_points
            )
        ),
        same,
    )

    print()
    print(
        f"load average {os.getloadavg()}; best of {REPEATS}; 1T/2T: RBM_NB_NUM_THREADS"
    )
    print(
        f"{'operation':<52} {'rbm_nb 1T':>11} {'rbm_nb 2T':>11} {'rbm 0.9.3':>11}"
        f" {'x ref 1T':>9} {'x ref 2T':>9}"
    )
    print("-" * 108)

    def cell(t, digits=2):
        # calls of a few µs (one point, static chain) in µs: 0.01 ms says nothing
        return f"{t * 1e6:>9.1f}µs" if t < 1e-3 else f"{t * 1e3:>9.{digits}f}ms"

    for label, t_nb, t_nb2, t_ref, once in rows:
        cells = f"{label:<52} {cell(t_nb)} {cell(t_nb2)}"
        if t_ref is None:
            print(cells)
        else:
            mark = "*" if once else " "
            print(
                f"{cells} {cell(t_ref, 1)}{mark}{t_ref / t_nb:>8.0f}x"
                f"{t_ref / t_nb2:>9.0f}x"
            )
    ratio = rows[[r[0] for r in rows].index("rotate_vectors 1M")][1] / t_plain
    print(f"{'rotate_vectors 1M: rbm_nb / plain numba loop':<52} {ratio:>10.2f}x")
    print("(* reference timed once: it took more than 60 s)")

    with tempfile.TemporaryDirectory() as cache:
        cold_first, cold_total = fresh_process_first_call(cache)
        warm_first, warm_total = fresh_process_first_call(cache)
    print()
    print("first lookup_transform + transform_points in a fresh process:")
    print(
        f"  empty numba cache: {cold_first:6.2f} s (process total from import {cold_total:6.2f} s)"
    )
    print(
        f"  warm numba cache:  {warm_first:6.2f} s (process total from import {warm_total:6.2f} s)"
    )
    print(f"import rbm_nb (median of 9 fresh processes): {import_times():.3f} s")


if __name__ == "__main__":
    main()
