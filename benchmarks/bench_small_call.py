"""Per-call overhead of small frame-core calls (issue 13 item 4, issue 16 item 4).

Times a one-point ``transform_points`` through a static chain of three frames
(and a few other small calls) with ``timeit``, best of 7 repeats, after a
warm-up call so that numba compilation is not counted. Then the same kind of
calls through a moving chain (a head of 66,000 samples at 200 Hz, as the
example recording's): a lookup at one time, as the tf2-style Transformer and
the widgets make them, the first one after registration, and one point at
one time against rigid-body-motion when it is installed; and, when
RBM_NB_DATA_DIR holds the example recordings, one-time lookups through the
real head/eye frames of ``bench_fused.py``.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_small_call.py
"""

from __future__ import annotations

import timeit
import warnings

import numpy as np

import rbm_nb as rbm


def _setup() -> None:
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "head",
        parent="world",
        translation=(0.1, 0.2, 1.7),
        rotation=(np.cos(0.2), 0.0, 0.0, np.sin(0.2)),
    )
    rbm.register_frame(
        "eye",
        parent="head",
        translation=(0.03, 0.0, 0.05),
        rotation=(np.cos(0.1), np.sin(0.1), 0.0, 0.0),
    )


def _best(stmt, number: int = 2000) -> float:
    stmt()
    times = timeit.repeat(stmt, number=number, repeat=7)
    return min(times) / number


def main() -> None:
    _setup()
    point = np.array([0.0, 0.0, 1.0])
    points = np.random.default_rng(0).normal(size=(100, 3))
    cases = {
        "transform_points, 1 point, static chain (eye -> world)": lambda: (
            rbm.transform_points(point, "world", "eye")
        ),
        "transform_points, 100 points, static chain": lambda: rbm.transform_points(
            points, "world", "eye"
        ),
        "transform_vectors, 1 vector, static chain": lambda: rbm.transform_vectors(
            point, "world", "eye"
        ),
        "lookup_transform, static chain": lambda: rbm.lookup_transform("eye", "world"),
    }
    for name, fn in cases.items():
        print(f"{_best(fn) * 1e6:8.1f} µs  {name}")
    moving()
    recording()


def _register_moving(lib, n: int) -> np.ndarray:
    rng = np.random.default_rng(1)
    ts = np.arange(n) / 200.0
    half = np.cumsum(rng.normal(scale=0.002, size=(n, 3)), axis=0)
    angle = np.linalg.norm(half, axis=1, keepdims=True)
    rotation = np.hstack([np.cos(angle), np.sin(angle) * half / angle])
    lib.clear_registry()
    lib.register_frame("world")
    lib.register_frame(
        "head",
        parent="world",
        translation=np.cumsum(rng.normal(scale=1e-3, size=(n, 3)), axis=0),
        rotation=rotation,
        timestamps=ts,
    )
    lib.register_frame(
        "eye", parent="head", translation=(0.03, 0.0, 0.05), rotation=(1, 0, 0, 0)
    )
    return ts


def _one_time_lookups(register, outof: str, when, many, label: str) -> None:
    """Time lookups of ``outof`` -> world at one time (first after ``register()``,
    then best of 500) and at the sorted times ``many``."""
    register()
    rbm.lookup_transform(outof, "world", time=many)  # kernels loaded
    register()
    start = timeit.default_timer()
    rbm.lookup_transform(outof, "world", time=when)
    first = timeit.default_timer() - start
    print(f"{first * 1e6:8.1f} µs  {label}: lookup_transform {outof} -> world "
          "at one time, first call after registering")  # fmt: skip
    cases = {
        f"{label}: the same, then": lambda: rbm.lookup_transform(
            outof, "world", time=when
        ),
        f"{label}: at {len(many)} times": lambda: rbm.lookup_transform(
            outof, "world", time=many
        ),
    }
    for name, fn in cases.items():
        print(f"{_best(fn, 500) * 1e6:8.1f} µs  {name}")


def moving(n: int = 66_000) -> None:
    ts = _register_moving(rbm, n)
    when = ts[n // 2] + 0.0013
    many = np.sort(np.random.default_rng(2).uniform(ts[1], ts[-2], 60))
    _one_time_lookups(
        lambda: _register_moving(rbm, n),
        "eye",
        when,
        many,
        f"moving chain ({n} samples)",
    )
    point, stamp = np.array([[0.0, 0.0, 1.0]]), np.array([when])
    ours = _best(
        lambda: rbm.transform_points(point, "eye", "world", timestamps=stamp), 500
    )
    print(f"{ours * 1e6:8.1f} µs  transform_points, 1 point at one time, moving chain")
    try:
        with warnings.catch_warnings():  # its accessor replaces ours: fine here
            warnings.simplefilter("ignore")
            import rigid_body_motion as ref
    except ImportError:
        return
    _register_moving(ref, n)
    with warnings.catch_warnings():  # scipy's on its extrapolation: not timed
        warnings.simplefilter("ignore")
        theirs = _best(
            lambda: ref.transform_points(point, "eye", "world", timestamps=stamp), 20
        )
    print(
        f"{theirs * 1e6:8.1f} µs  the same in rigid-body-motion ({theirs / ours:.1f}x)"
    )


def recording() -> None:
    """One-time lookups left_eye -> world through the real recording's frames."""
    from bench_fused import real_workload, register  # this folder, run as a script

    real = real_workload()
    if real is None:
        return
    frames, _, eye_ts = real[:3]
    step = eye_ts[1] - eye_ts[0]
    when = eye_ts[len(eye_ts) // 2] + step / 3
    many = np.sort(eye_ts[100:-100][:: len(eye_ts) // 60][:60] + step / 3)
    _one_time_lookups(
        lambda: register(rbm, frames), "left_eye", when, many, "real recording"
    )


if __name__ == "__main__":
    main()
