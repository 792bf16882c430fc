"""Path simplification: the numba split against the former numpy loop (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_path_simplify.py [--hours 1] [--repeat 3]

The head's positions of the example recording tiled in time to ``--hours``
(``tiled_recording.py``; NaN rows kept) are simplified as the scene does
(:func:`rbm_nb.scene.decimate.simplify_path`, default tolerance, 1000 and
2000 points), and refined as a zoomed camera asks (``refine_region``: a box
a tenth of the path's extent wide around a sample mid-recording, 1/2000 and
1/20000 of that box's diagonal, 10,000 points). Each is timed (best of
``--repeat``) with the kernel and with the former numpy/heapq loop, kept as
the reference in ``tests/notebook/test_path_simplify_kernel.py``, and the
answers are checked to be the same bit for bit. Printed: seconds before,
after, and the ratio.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests" / "notebook"))

import test_path_simplify_kernel as reference  # noqa: E402
from tiled_recording import tiled_head_eye  # noqa: E402

from rbm_nb.scene import decimate  # noqa: E402


def _best(func, repeat: int):
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        out = func()
        best = min(best, time.perf_counter() - start)
    return best, out


def _same(a, b) -> bool:
    (sa, ea), (sb, eb) = a, b
    return (
        ea == eb
        and len(sa) == len(sb)
        and all(np.array_equal(x, y) for x, y in zip(sa, sb, strict=True))
    )


def _refine_before(samples, low, high, tolerance, max_points):
    # refine_region's own selection, then the former loop
    original = decimate.simplify_path
    decimate.simplify_path = reference._reference_simplify_path
    try:
        return decimate.refine_region(samples, low, high, tolerance, max_points)
    finally:
        decimate.simplify_path = original


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--hours", type=float, default=1.0)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    head, _, _ = tiled_head_eye(args.hours)
    samples = np.ascontiguousarray(head.position.values, dtype=np.float64)
    decimate.simplify_path(samples[:1000])  # the kernel compiled (or loaded) first
    lo, hi = np.nanmin(samples, axis=0), np.nanmax(samples, axis=0)
    # the box around a sample mid-recording, a tenth of the path's extent wide
    middle = samples[np.flatnonzero(~np.isnan(samples).any(axis=1))[len(samples) // 2]]
    extent = hi - lo
    low, high = middle - extent / 20, middle + extent / 20
    print(f"head path: {len(samples)} samples ({args.hours:g} h tiled)")
    diagonal = float(np.linalg.norm(high - low))
    cases = {
        "simplify_path, 1000 points (add_path's default)": (
            lambda: reference._reference_simplify_path(samples),
            lambda: decimate.simplify_path(samples),
        ),
        "simplify_path, 2000 points (the explorer's)": (
            lambda: reference._reference_simplify_path(samples, None, 2000),
            lambda: decimate.simplify_path(samples, None, 2000),
        ),
    }
    for share in (2000, 20000):
        tolerance = diagonal / share
        cases[f"refine_region, box diagonal / {share}"] = (
            lambda t=tolerance: _refine_before(samples, low, high, t, 10_000),
            lambda t=tolerance: decimate.refine_region(samples, low, high, t, 10_000),
        )
    for name, (before, after) in cases.items():
        t_before, out_before = _best(before, args.repeat)
        t_after, out_after = _best(after, args.repeat)
        kept = sum(len(s) for s in out_after[0])
        print(
            f"{name}: {kept} points kept, before {t_before:.3f} s, after "
            f"{t_after:.3f} s, ratio {t_before / t_after:.1f}x, same bits: "
            f"{_same(out_before, out_after)}"
        )


if __name__ == "__main__":
    main()
