"""How close the frame core is to the floor (issue 16), in one script.

Prints, for the head/eye workload (the real recording when
``RBM_NB_DATA_DIR`` points at it, else the synthetic one of
``bench_core.py``):

1. every frame-tree operation, rbm_nb on 1 and on 2 threads
   (``RBM_NB_NUM_THREADS``; the parallel kernels run only for calls of at
   least ``_parallel.MIN_ROWS`` rows) against rigid-body-motion 0.9.3 in
   the same process (best of 5 after a warm-up call, the contenders called
   in turns), and for lookups and
   transforms also the fused kernels called directly on the engine
   (``_engine.fused``, 1 thread);
2. that table in three malloc regimes, each in its own process:
   ``MALLOC_MMAP_THRESHOLD_=131072`` (big arrays are fresh mmap pages on
   every call: first-touch page faults), a large threshold (freed memory is
   reused: no page faults) and glibc's default (adaptive);
3. the scaling of a lookup from 1e3 to 1e6 samples (1e7 with ``--big``) in
   ns/sample on 1 and 2 threads, beside a fused *floor* kernel and its
   ``prange`` twin (below: exactly the arithmetic of the lookup, for this
   one chain, with precomputed coefficients and nothing else);
4. peak temporary memory of a lookup, a transform and an angular-velocity
   lookup against their output size (tracemalloc traces numpy's
   allocations);
5. registration time of the head/eye frames, the first lookup after
   registration against the steady state, and a one-point static
   ``transform_points``.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_fused.py [--big] [--no-reference] [--regime NAME]
(default: all three regimes for the table, then the rest once; a few
minutes on the 2-core machine.)
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
import timeit
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

warnings.filterwarnings("ignore")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_core import (  # noqa: E402
    best_in_turns,
    build_workload,
    continuous_rotations,
    datetimes,
    on_threads,
    threads,
)

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


def best(fn, repeats=REPEATS):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


# ---------------------------------------------------------------------------
# the workload
# ---------------------------------------------------------------------------


def real_workload():
    """The head/eye recording as frames, if RBM_NB_DATA_DIR has it (else None)."""
    folder = os.environ.get("RBM_NB_DATA_DIR")
    if not folder or not (Path(folder) / "head.nc").exists():
        return None
    from rbm_nb.data import load_example

    head = load_example("head", source="remote")
    eye = load_example("left_eye", source="remote")
    # the eye tracker's missing samples (NaN rows) are dropped, so that both
    # packages time the same interpolation work
    keep = ~np.isnan(eye.orientation.values).any(axis=1)
    head_ts = head.time.values
    eye_ts = eye.time.values[keep]
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
                "translation": head.position.values,
                "rotation": head.orientation.values,
                "timestamps": head_ts,
            },
        ),
        (
            "scene_cam",
            {
                "parent": "head",
                "translation": (0.0, -0.05, 0.02),
                "rotation": np.array((0.99, 0.1, 0.0, 0.0))
                / np.linalg.norm((0.99, 0.1, 0.0, 0.0)),
            },
        ),
        (
            "left_eye",
            {
                "parent": "scene_cam",
                "translation": np.tile([0.03, 0.0, 0.0], (len(eye_ts), 1)),
                "rotation": eye.orientation.values[keep],
                "timestamps": eye_ts,
            },
        ),
    ]
    gaze = np.random.default_rng(0).normal(size=(len(eye_ts), 3))
    return frames, head_ts, eye_ts, head.orientation.values, gaze


def workload():
    real = real_workload()
    if real is not None:
        return "real head/eye recording", real
    return "synthetic head/eye workload (bench_core.py)", build_workload()


def register(module, frames):
    module.clear_registry()
    for name, kwargs in frames:
        module.register_frame(name, **kwargs)


# ---------------------------------------------------------------------------
# 1-2: the table
# ---------------------------------------------------------------------------


def fused_direct(outof, into, kind=None, data=None, timestamps=None):
    """A lookup or transform through ``_engine.fused`` (no public plumbing)."""
    from rbm_nb._engine import chain as C
    from rbm_nb._engine import fused as FU
    from rbm_nb._engine.transform import SIZES, Blocks
    from rbm_nb.core import frames as F

    a, b = F.resolve_frame(outof), F.resolve_frame(into)
    steps = C.chain(a, b)
    if kind is None:
        target = C.match([f for f, _ in steps])
        plan, own = C.fused_plan(steps, target)
        return FU.lookup(plan, target, own)
    blocks = Blocks(data, SIZES[kind], -1, 0, timestamps, kind)
    target = C.match([f for f, _ in steps], [blocks.track])
    matched = C.resample_array(blocks.data, blocks.track, target, kind == "quaternions")
    plan, own = C.fused_plan(steps, target)
    return FU.transform(plan, target, own, matched, kind)


def table(reference: bool) -> None:
    import rbm_nb as rbm

    name, (frames, head_ts, eye_ts, head_rot, gaze) = workload()
    register(rbm, frames)
    ref = None
    if reference:
        import rigid_body_motion as ref

        register(ref, frames)
    n_eye, n_head = len(eye_ts), len(head_ts)
    quats = continuous_rotations(np.random.default_rng(2), n_eye, 0.01)
    inside = eye_ts[(eye_ts >= head_ts[0]) & (eye_ts <= head_ts[-1])]
    rng = np.random.default_rng(1)
    q1m = continuous_rotations(rng, 1_000_000, 0.001)
    v1m = rng.normal(size=(1_000_000, 3))

    ops = [
        ("lookup_transform left_eye->world", lambda m: m.lookup_transform("left_eye", "world"),
         lambda: fused_direct("left_eye", "world")),
        ("lookup_transform world->left_eye", lambda m: m.lookup_transform("world", "left_eye"),
         lambda: fused_direct("world", "left_eye")),
        ("lookup_pose left_eye wrt world", lambda m: m.lookup_pose("left_eye", "world"), None),
        (f"transform_points {n_eye} (eye ts)",
         lambda m: m.transform_points(gaze, "world", "left_eye", timestamps=eye_ts),
         lambda: fused_direct("left_eye", "world", "points", gaze, eye_ts)),
        (f"transform_vectors {n_head} (head ts)",
         lambda m: m.transform_vectors(gaze[:n_head], "world", "left_eye", timestamps=head_ts),
         lambda: fused_direct("left_eye", "world", "vectors", gaze[:n_head], head_ts)),
        (f"transform_quaternions {n_eye} (eye ts)",
         lambda m: m.transform_quaternions(quats, "world", "left_eye", timestamps=eye_ts),
         lambda: fused_direct("left_eye", "world", "quaternions", quats, eye_ts)),
        ("lookup_twist head wrt world", lambda m: m.lookup_twist("head", "world"), None),
        ("lookup_linear_velocity left_eye wrt world",
         lambda m: m.lookup_linear_velocity("left_eye", "world"), None),
        ("lookup_angular_velocity left_eye wrt world",
         lambda m: m.lookup_angular_velocity("left_eye", "world"), None),
        # a static lookup takes about a microsecond: timed 1,000 at a time, so
        # that neither the clock nor the threads() wrapper is what is measured
        ("lookup_transform t265/world->world (static) x1000",
         lambda m: [m.lookup_transform("t265/world", "world") for _ in range(1000)], None),
        (f"qinterp head -> {len(inside)} eye times",
         lambda m: m.qinterp(head_rot, head_ts, inside), None),
        ("rotate_vectors 1M", lambda m: m.rotate_vectors(q1m, v1m), None),
    ]  # fmt: skip
    print(f"{name}; best of {REPEATS}; rbm_nb on 1 and 2 threads (RBM_NB_NUM_THREADS)")
    print(
        f"{'operation':<46} {'rbm 1T':>9} {'rbm 2T':>9} {'fused':>9} {'rbm 0.9.3':>10}"
        f" {'x ref 1T':>8} {'x ref 2T':>8} {'x ref fused':>11}"
    )
    for label, call, fused in ops:
        # in turns, so that the machine's load changes hit every contender alike
        fns = [on_threads(1, lambda call=call: call(rbm))]
        fns += [on_threads(2, lambda call=call: call(rbm))]
        fns += [on_threads(1, fused)] if fused is not None else []
        fns += [lambda call=call: call(ref)] if ref is not None else []
        got = best_in_turns(fns)
        t_1, t_2 = got[0], got[1]
        t_fu = got[2] if fused is not None else None
        t_ref = got[-1] if ref is not None else None
        cells = [f"{t_1 * 1e3:7.2f}ms", f"{t_2 * 1e3:7.2f}ms"]
        cells += [f"{t_fu * 1e3:7.2f}ms" if t_fu else " " * 9]
        if t_ref is not None:
            cells += [
                f"{t_ref * 1e3:8.1f}ms",
                f"{t_ref / t_1:7.1f}x",
                f"{t_ref / t_2:7.1f}x",
            ]
            cells += [f"{t_ref / t_fu:10.1f}x" if t_fu else ""]
        print(f"{label:<46} " + " ".join(cells), flush=True)


def regimes(args) -> None:
    for regime, env in REGIMES.items():
        print(f"\n== malloc regime: {regime} {env or '(glibc default)'}", flush=True)
        cmd = [sys.executable, __file__, "--regime", regime]
        if args.no_reference:
            cmd.append("--no-reference")
        subprocess.run(cmd, env=dict(os.environ, **env), check=True)


# ---------------------------------------------------------------------------
# 3: scaling, beside the floor kernel
# ---------------------------------------------------------------------------


def floor_kernels():
    """Fused kernels with exactly a lookup's arithmetic, for one chain shape.

    world <- S0 <- head (moving, squad) <- S1 <- eye (moving, evaluated at
    its own sample times): per output row, one merge-walk step in the head's
    times, one squad evaluation with precomputed coefficients, the eye's
    sample and two static transforms, composed like ``chain_step``. In
    blocks of rows with the passes of rbm_nb's chain kernels (a scalar walk
    that gathers each row's segment, then rbm_nb's vector passes for the
    great circles, the outer slerp and the compositions), as the lookup
    computes, with its prefetch hints; nothing else (no plan, no missing
    samples, gaps or signs).

    Returns the serial kernel and its two-thread twin (``prange`` over
    contiguous chunks of rows, each starting its walk by a binary search):
    the floors of rbm_nb's serial and parallel lookups.
    """
    from numba import njit, prange

    from rbm_nb._kernels import chain_rows as kr
    from rbm_nb._kernels._prefetch import prefetch
    from rbm_nb._kernels.quaternion import _qslerp1, _qslerp_unit1

    block = kr.BLOCK
    ahead = kr.AHEAD
    acc, step = kr._ACC, kr._STEP

    @njit(cache=False, nogil=True)
    def static(work, s):
        kr._compose_static_rows(work, s.reshape(1, 7), 0, False, False, False)

    @njit(cache=False, nogil=True)
    def rows(s1, s0, h_times, h_t, h_r, a, b, seg, e_t, e_r, target, off, j0, j1,
             t_out, r_out, work):  # fmt: skip
        n = h_times.shape[0]
        i = max(np.searchsorted(h_times, target[j0] + off, side="right") - 1, 0)
        m = target.shape[0]
        for k0 in range(j0, j1, block):
            nb = min(block, j1 - k0)
            # the next block's eye samples and times asked for, a cache line
            # (8 values) at a time (as rbm_nb)
            k1, k2 = k0 + block, min(k0 + 2 * block, m)
            for q in range(k1, k2, 8):
                prefetch(target, q)
            for q in range(3 * k1, 3 * k2, 8):
                prefetch(e_t, q)
            for q in range(4 * k1, 4 * k2, 8):
                prefetch(e_r, q)
            # eye sample j, then the static scene_cam -> head
            for q in range(nb):
                for e in range(3):
                    work[acc + e * block + q] = e_t[k0 + q, e]
                for e in range(4):
                    work[acc + (3 + e) * block + q] = e_r[k0 + q, e]
            static(work, s1)
            # the head at the eye's time: walk and gather, then the passes
            for q in range(block):
                work[kr._PATH + q] = 0.0
            for q in range(nb):
                t = target[k0 + q] + off
                while i < n - 2 and h_times[i + 1] <= t:
                    i += 1
                if i + ahead < n:  # the segment further on (as rbm_nb)
                    g = i + ahead
                    prefetch(seg, 11 * g)
                    prefetch(seg, 11 * g + 8)
                    prefetch(a, 4 * g)
                    prefetch(h_r, 4 * g)
                    prefetch(h_t, 3 * g)
                u = (t - h_times[i]) / (h_times[i + 1] - h_times[i])
                work[step + q] = h_t[i, 0] + u * (h_t[i + 1, 0] - h_t[i, 0])
                work[step + block + q] = h_t[i, 1] + u * (h_t[i + 1, 1] - h_t[i, 1])
                work[step + 2 * block + q] = h_t[i, 2] + u * (h_t[i + 1, 2] - h_t[i, 2])
                if seg[i, 10] == 0.0:
                    work[kr._PATH + q] = kr._GATHERED
                    work[kr._NEG + q] = 0.0
                    work[kr._TAU + q] = u
                    work[kr._TH1 + q] = seg[i, 0]
                    work[kr._TH2 + q] = seg[i, 5]
                    for e in range(4):
                        work[kr._P + e * block + q] = h_r[i, e]
                        work[kr._U1 + e * block + q] = seg[i, 1 + e]
                        work[kr._Q + e * block + q] = a[i, e]
                        work[kr._U2 + e * block + q] = seg[i, 6 + e]
                else:
                    p0, p1, p2, p3 = _qslerp1(
                        h_r[i, 0], h_r[i, 1], h_r[i, 2], h_r[i, 3],
                        h_r[i + 1, 0], h_r[i + 1, 1], h_r[i + 1, 2], h_r[i + 1, 3], u,
                    )  # fmt: skip
                    q0, q1, q2, q3 = _qslerp1(
                        a[i, 0], a[i, 1], a[i, 2], a[i, 3], b[i, 0], b[i, 1], b[i, 2], b[i, 3], u
                    )  # fmt: skip
                    hq = _qslerp_unit1(
                        p0, p1, p2, p3, q0, q1, q2, q3, 2.0 * u * (1.0 - u)
                    )
                    for e in range(4):
                        work[step + (3 + e) * block + q] = hq[e]
            wide = kr._squad_rows(work)
            if wide >= kr._WIDE_ROWS:
                wide = kr._wide_rows(work)
            if wide > 0:
                for q in range(nb):
                    if work[kr._PATH + q] != kr._GENERAL:
                        continue
                    u = work[kr._TAU + q]
                    hq = _qslerp_unit1(
                        work[kr._P + q], work[kr._P + block + q],
                        work[kr._P + 2 * block + q], work[kr._P + 3 * block + q],
                        work[kr._Q + q], work[kr._Q + block + q],
                        work[kr._Q + 2 * block + q], work[kr._Q + 3 * block + q],
                        2.0 * u * (1.0 - u),
                    )  # fmt: skip
                    for e in range(4):
                        work[step + (3 + e) * block + q] = hq[e]
            kr._compose_rows(work, False, False)
            static(work, s0)
            kr._store_lookup(work, t_out, r_out, k0, k0 + nb, False)

    @njit(cache=False, nogil=True)
    def lookup(s1, s0, h_times, h_t, h_r, a, b, seg, e_t, e_r, target, off):
        m = target.shape[0]
        t_out = np.empty((m, 3))
        r_out = np.empty((m, 4))
        work = np.zeros(kr.WORK * block)
        rows(s1, s0, h_times, h_t, h_r, a, b, seg, e_t, e_r, target, off, 0, m,
             t_out, r_out, work)  # fmt: skip
        return t_out, r_out

    @njit(cache=False, nogil=True, parallel=True)
    def lookup_parallel(s1, s0, h_times, h_t, h_r, a, b, seg, e_t, e_r, target, off):
        m = target.shape[0]
        t_out = np.empty((m, 3))
        r_out = np.empty((m, 4))
        chunks = 64
        per = ((m + chunks - 1) // chunks + block - 1) // block * block
        for c in prange(chunks):
            work = np.zeros(kr.WORK * block)
            j0 = min(c * per, m)
            j1 = min(j0 + per, m)
            if j1 > j0:
                rows(s1, s0, h_times, h_t, h_r, a, b, seg, e_t, e_r, target, off,
                     j0, j1, t_out, r_out, work)  # fmt: skip
        return t_out, r_out

    return lookup, lookup_parallel


def floor_kernel():
    """The serial floor kernel (:func:`floor_kernels`)."""
    return floor_kernels()[0]


def floor_args(n):
    """Register the scaling chain with n eye samples; the floor kernels' arguments.

    Also checks that the floor computes rbm_nb's lookup (to 1e-9).
    """
    import rbm_nb as rbm
    from rbm_nb._engine import chain as C
    from rbm_nb.core import frames as F

    register(rbm, scaling_frames(n))
    head, eye = F.resolve_frame("head"), F.resolve_frame("left_eye")
    s0 = C.static_transform(F.resolve_frame("t265/world"), F.resolve_frame("world"))
    s1 = C.static_transform(F.resolve_frame("scene_cam"), head)
    s0 = np.concatenate([s0[0][0], s0[1][0]])
    s1 = np.concatenate([s1[0][0], s1[1][0]])
    a, b, seg = head._squad_coefficients()
    target = C.match([eye, head])
    lo = int(np.searchsorted(eye.data.track.key, target.track.key[0]))
    e_t = eye.data.t[lo : lo + len(target)]
    e_r = eye.data.rotation[lo : lo + len(target)]
    off = (target.track.origin - head.data.track.origin) / 1e9
    return (s1, s0, head.data.track.base, head.data.t, head.data.r, a, b, seg, e_t, e_r,
            target.track.base, off)  # fmt: skip


def scaling_frames(n):
    """The head/eye chain with n eye samples (head at 200/340 of the rate)."""
    rng = np.random.default_rng(n)
    start = np.datetime64("2020-02-02T00:27:14.300365210").astype(np.int64)
    n_head = max(int(n * 200 / 340.3), 4)
    head_ts = datetimes(start, n_head + 2, 200.0)
    eye_ts = datetimes(start + 1_234_567, n, 340.3)
    s = np.sqrt(0.5)
    cam = np.array((0.99, 0.1, 0.0, 0.0)) / np.linalg.norm((0.99, 0.1, 0.0, 0.0))
    return [
        ("world", {}),
        ("t265/world", {"parent": "world", "rotation": (s, s, 0, 0)}),
        ("head", {"parent": "t265/world", "translation": rng.normal(size=(n_head + 2, 3)),
                  "rotation": continuous_rotations(rng, n_head + 2, 0.003),
                  "timestamps": head_ts}),
        ("scene_cam", {"parent": "head", "translation": (0.0, -0.05, 0.02), "rotation": cam}),
        ("left_eye", {"parent": "scene_cam", "translation": np.tile([0.03, 0.0, 0.0], (n, 1)),
                      "rotation": continuous_rotations(rng, n, 0.004), "timestamps": eye_ts}),
    ]  # fmt: skip


def scaling(sizes) -> None:
    import numba

    import rbm_nb as rbm

    floor, floor_2 = floor_kernels()
    print(
        "\n== scaling: lookup_transform left_eye->world, ns per output row, "
        "1 and 2 threads (rbm_nb: RBM_NB_NUM_THREADS; its parallel twins run "
        "from _parallel.MIN_ROWS rows)"
    )
    print(
        f"{'samples':>9} {'rbm 1T':>8} {'rbm 2T':>8} {'floor 1T':>9} {'floor 2T':>9}"
        f" {'rbm/floor 1T':>13} {'rbm/floor 2T':>13}"
    )
    for n in sizes:
        args = floor_args(n)
        t_f, r_f = floor(*args)
        t_p, r_p = rbm.lookup_transform("left_eye", "world")[:2]
        assert np.abs(t_f - t_p).max() < 1e-9 and np.abs(r_f - r_p).max() < 1e-9
        m = len(args[-2])
        reps = 5 if n <= 1_000_000 else 3
        with threads(1):
            t_1 = best(lambda: rbm.lookup_transform("left_eye", "world"), reps)
        with threads(2):
            t_2 = best(lambda: rbm.lookup_transform("left_eye", "world"), reps)
        f_1 = best(lambda args=args: floor(*args), reps)
        numba.set_num_threads(2)
        f_2 = best(lambda args=args: floor_2(*args), reps)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        ns = [x / m * 1e9 for x in (t_1, t_2, f_1, f_2)]
        print(
            f"{n:>9.0e} {ns[0]:>8.1f} {ns[1]:>8.1f} {ns[2]:>9.1f} {ns[3]:>9.1f}"
            f" {t_1 / f_1:>12.2f}x {t_2 / f_2:>12.2f}x",
            flush=True,
        )


# ---------------------------------------------------------------------------
# 4: memory
# ---------------------------------------------------------------------------


def peak_memory(fn):
    """(peak traced bytes during fn, bytes of its result arrays)."""
    fn()
    tracemalloc.start()
    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    result = fn()
    peak = tracemalloc.get_traced_memory()[1] - before
    tracemalloc.stop()
    arrays = result if isinstance(result, tuple) else (result,)
    out = sum(a.nbytes for a in arrays if isinstance(a, np.ndarray))
    return peak, out


def memory() -> None:
    import rbm_nb as rbm

    _, (frames, head_ts, eye_ts, head_rot, gaze) = workload()
    register(rbm, frames)
    print("\n== peak temporary memory (tracemalloc) against the output")
    cases = [
        ("lookup_transform left_eye->world", lambda: rbm.lookup_transform("left_eye", "world")),
        ("  fused engine path", lambda: fused_direct("left_eye", "world")),
        ("transform_points (eye ts)",
         lambda: rbm.transform_points(gaze, "world", "left_eye", timestamps=eye_ts)),
        ("  fused engine path", lambda: fused_direct("left_eye", "world", "points", gaze, eye_ts)),
        ("lookup_angular_velocity left_eye wrt world",
         lambda: rbm.lookup_angular_velocity("left_eye", "world")),
    ]  # fmt: skip
    for label, fn in cases:
        peak, out = peak_memory(fn)
        print(
            f"{label:<46} peak {peak / 1e6:7.1f} MB  output {out / 1e6:6.1f} MB  {peak / out:5.2f}x"
        )
    angular_velocity_routes(rbm)


def angular_velocity_routes(rbm) -> None:
    """The chain kernel of lookup_angular_velocity against the route it replaces
    (the chain's rotations looked up, then estimated): memory and time."""
    from rbm_nb._engine import twist

    chain_rates = twist._chain_rates
    call = lambda: rbm.lookup_angular_velocity("left_eye", "world")  # noqa: E731
    print(
        "lookup_angular_velocity left_eye wrt world: chain kernel vs lookup + estimate"
    )
    try:
        for route, kernel in (
            ("chain kernel", chain_rates),
            ("lookup + estimate", None),
        ):
            twist._chain_rates = kernel or (lambda *args: None)
            peak, out = peak_memory(call)
            times = []
            for n_threads in (1, 2):
                with threads(n_threads):
                    call()
                    times.append(f"{n_threads}T {best(call) * 1e3:6.2f} ms")
            print(
                f"  {route:<20} peak {peak / out:5.2f}x output   " + "   ".join(times)
            )
    finally:
        twist._chain_rates = chain_rates


# ---------------------------------------------------------------------------
# 5: registration, first use, small calls
# ---------------------------------------------------------------------------


def registration() -> None:
    import rbm_nb as rbm

    _, (frames, *_rest) = workload()
    print("\n== registration and first use")
    t_reg = best(lambda: register(rbm, frames))
    print(f"register the 5 head/eye frames: {t_reg * 1e3:.2f} ms (best of {REPEATS})")
    for n_threads in (1, 2):
        firsts, steadies = [], []
        with threads(n_threads):
            for _ in range(5):
                register(rbm, frames)
                t0 = time.perf_counter()
                rbm.lookup_transform("left_eye", "world")
                firsts.append(time.perf_counter() - t0)
                steadies.append(best(lambda: rbm.lookup_transform("left_eye", "world")))
        first, steady = min(firsts), min(steadies)
        print(
            f"lookup_transform left_eye->world, {n_threads}T: first after registration "
            f"{first * 1e3:.2f} ms, steady {steady * 1e3:.2f} ms, ratio {first / steady:.2f}x "
            "(best of 5 each)"
        )
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "head",
        parent="world",
        translation=(0.1, 0.2, 1.7),
        rotation=(np.cos(0.2), 0.0, 0.0, np.sin(0.2)),
    )
    rbm.register_frame("eye", parent="head", translation=(0.03, 0.0, 0.05),
                       rotation=(np.cos(0.1), np.sin(0.1), 0.0, 0.0))  # fmt: skip
    point = np.array([0.0, 0.0, 1.0])
    call = lambda: rbm.transform_points(point, "world", "eye")  # noqa: E731
    call()
    one = min(timeit.repeat(call, number=2000, repeat=7)) / 2000
    print(f"transform_points, 1 point, static chain: {one * 1e6:.1f} µs")
    try:
        import rigid_body_motion as ref
    except ImportError:
        return
    register(ref, [("world", {}),
                   ("head", {"parent": "world", "translation": (0.1, 0.2, 1.7),
                             "rotation": (np.cos(0.2), 0.0, 0.0, np.sin(0.2))}),
                   ("eye", {"parent": "head", "translation": (0.03, 0.0, 0.05),
                            "rotation": (np.cos(0.1), np.sin(0.1), 0.0, 0.0)})])  # fmt: skip
    call_ref = lambda: ref.transform_points(point, "world", "eye")  # noqa: E731
    call_ref()
    one_ref = min(timeit.repeat(call_ref, number=200, repeat=5)) / 200
    print(f"  rigid-body-motion: {one_ref * 1e6:.1f} µs ({one_ref / one:.1f}x)")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--big", action="store_true", help="scaling up to 1e7 samples")
    parser.add_argument(
        "--no-reference", action="store_true", help="skip rigid-body-motion"
    )
    parser.add_argument(
        "--regime", choices=REGIMES, help="(internal) one table, this process"
    )
    parser.add_argument(
        "--only", choices=["table", "scaling", "memory", "registration"]
    )
    args = parser.parse_args()
    from rbm_nb._infra import parallel as _parallel

    print(
        f"load average {os.getloadavg()[0]:.2f}, free cores now {_parallel.free_cores()} "
        "(rbm_nb's parallel kernels use only free cores)",
        flush=True,
    )
    if args.regime:
        table(not args.no_reference)
        return
    if args.only in (None, "table"):
        regimes(args)
    sizes = [1_000, 10_000, 100_000, 1_000_000] + ([10_000_000] if args.big else [])
    if args.only in (None, "scaling"):
        scaling(sizes)
    if args.only in (None, "memory"):
        memory()
    if args.only in (None, "registration"):
        registration()


if __name__ == "__main__":
    main()
