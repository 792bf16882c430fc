"""Per-call overhead of small frame-core calls (issue 13 item 4, issue 16 item 4).

Times a one-point ``transform_points`` through a static chain of three frames
(and a few other small calls) with ``timeit``, best of 7 repeats, after a
warm-up call so that numba compilation is not counted.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/bench_small_call.py
"""

from __future__ import annotations

import timeit

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


if __name__ == "__main__":
    main()
