"""What a smaller squad table would cost per row (issue 16's memory item).

The fused kernels read, per segment of a frame, a 15-column table
(120 bytes): the control point a, and both inner great circles of squad as
an angle and a unit direction (r[i] -> r[i+1] and a -> b), so that a row's
inner slerps are one ``sincos`` each. Issue 16 asks for cached
coefficients no larger than the frame's own data (64 bytes per sample:
time, translation, rotation). The smallest table that still spares every
row the exp/log of the control points holds a and b only (8 columns, 64
bytes); a row must then form all three slerps of squad from their end
points, by the small-arc series (no sqrt, no atan2).

This script times the fast path of both layouts on the real recording,
with the same structure as the fused kernels (a scalar pass gathers each
row's segment into structure-of-arrays scratch, a vector pass evaluates a
block of 96 rows, a last loop stores them):

* the head interpolated at the eye's times (smooth motion, as
  ``lookup_transform("left_eye", "world")`` does) and
* the eye at the head's times (saccades, as ``lookup_transform("world",
  "left_eye")`` and ``transform_vectors`` at the head's times do),

warm (the same call repeated) and cold (64 MB streamed through the caches
before each call), and counts the rows the 8-column form would send off
the series (in the kernels, to a slower vector pass or the scalar route:
arcs whose tangent is over ``SERIES_RATIO``). Neither kernel here handles
those rows, gaps or missing samples: both are fast paths only, measured
side by side.

Run:  RBM_NB_DATA_DIR=../shared/data/rbm-data .venv/bin/python benchmarks/bench_table_layout.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).parent))

import bench_fused  # noqa: E402  (the head/eye workload)

BLOCK = 96
REPEATS = 40


def _kernels():
    """The two evaluation kernels (compiled on first call)."""
    from rbm_nb._kernels.scalar import (
        SERIES_RATIO,
        atan_over_x,
        cos_series,
        sinc_series,
        sincos,
    )

    off_series = SERIES_RATIO * SERIES_RATIO

    @njit(inline="always")
    def seek(times, t, i):
        if i >= 0 and t < times[i]:
            i = -1
        while i + 1 < times.shape[0] and times[i + 1] <= t:
            i += 1
        return i

    @njit(inline="always")
    def segment(times, t, i):
        """The segment of t (walking on from segment i) and squad's fraction τ."""
        i = seek(times, t, i)
        return i, (t - times[i]) / (times[i + 1] - times[i])

    @njit(inline="always")
    def series_slerp(aw, ax, ay, az, bw, bx, by, bz, h):
        d = aw * bw + ax * bx + ay * by + az * bz
        ow, ox, oy, oz = bw - d * aw, bx - d * ax, by - d * ay, bz - d * az
        inv = 1.0 / d
        x2 = (ow * ow + ox * ox + oy * oy + oz * oz) * inv * inv
        p = atan_over_x(x2)
        y2 = h * h * x2 * p * p
        c = cos_series(y2)
        k = sinc_series(y2) * h * p * inv
        return c * aw + k * ow, c * ax + k * ox, c * ay + k * oy, c * az + k * oz, x2

    @njit(error_model="numpy")
    def fifteen(times, r, c, target, out):
        """Rows from the 15-column table (rbm_nb's layout)."""
        m = target.shape[0]
        w = np.empty(23 * BLOCK)
        i = 0
        for j0 in range(0, m, BLOCK):
            nb = min(BLOCK, m - j0)
            for b in range(nb):
                i, w[b] = segment(times, target[j0 + b], i)
                w[BLOCK + b] = c[i, 4]
                w[2 * BLOCK + b] = c[i, 9]
                for e in range(4):
                    w[(3 + e) * BLOCK + b] = r[i, e]
                    w[(7 + e) * BLOCK + b] = c[i, 5 + e]
                    w[(11 + e) * BLOCK + b] = c[i, e]
                    w[(15 + e) * BLOCK + b] = c[i, 10 + e]
            for b in range(BLOCK):
                tau = w[b]
                s1, c1 = sincos(tau * w[BLOCK + b])
                s2, c2 = sincos(tau * w[2 * BLOCK + b])
                q = series_slerp(
                    c1 * w[3 * BLOCK + b] + s1 * w[7 * BLOCK + b],
                    c1 * w[4 * BLOCK + b] + s1 * w[8 * BLOCK + b],
                    c1 * w[5 * BLOCK + b] + s1 * w[9 * BLOCK + b],
                    c1 * w[6 * BLOCK + b] + s1 * w[10 * BLOCK + b],
                    c2 * w[11 * BLOCK + b] + s2 * w[15 * BLOCK + b],
                    c2 * w[12 * BLOCK + b] + s2 * w[16 * BLOCK + b],
                    c2 * w[13 * BLOCK + b] + s2 * w[17 * BLOCK + b],
                    c2 * w[14 * BLOCK + b] + s2 * w[18 * BLOCK + b],
                    2.0 * tau * (1.0 - tau),
                )
                for e in range(4):
                    w[(19 + e) * BLOCK + b] = q[e]
            for b in range(nb):
                for e in range(4):
                    out[j0 + b, e] = w[(19 + e) * BLOCK + b]

    @njit(error_model="numpy")
    def eight(times, r, ab, target, out):
        """Rows from an 8-column table (a, b); returns the rows off the series."""
        m = target.shape[0]
        w = np.empty(22 * BLOCK)
        i = 0
        off = 0
        for j0 in range(0, m, BLOCK):
            nb = min(BLOCK, m - j0)
            for b in range(nb):
                i, w[b] = segment(times, target[j0 + b], i)
                for e in range(4):
                    w[(1 + e) * BLOCK + b] = r[i, e]
                    w[(5 + e) * BLOCK + b] = r[i + 1, e]
                    w[(9 + e) * BLOCK + b] = ab[i, e]
                    w[(13 + e) * BLOCK + b] = ab[i, 4 + e]
            for b in range(BLOCK):
                tau = w[b]
                s = series_slerp(
                    w[BLOCK + b], w[2 * BLOCK + b], w[3 * BLOCK + b], w[4 * BLOCK + b],
                    w[5 * BLOCK + b], w[6 * BLOCK + b], w[7 * BLOCK + b], w[8 * BLOCK + b],
                    tau,
                )  # fmt: skip
                g = series_slerp(
                    w[9 * BLOCK + b], w[10 * BLOCK + b], w[11 * BLOCK + b],
                    w[12 * BLOCK + b], w[13 * BLOCK + b], w[14 * BLOCK + b],
                    w[15 * BLOCK + b], w[16 * BLOCK + b], tau,
                )  # fmt: skip
                q = series_slerp(
                    s[0], s[1], s[2], s[3], g[0], g[1], g[2], g[3],
                    2.0 * tau * (1.0 - tau),
                )  # fmt: skip
                wide = (
                    (s[4] >= off_series) | (g[4] >= off_series) | (q[4] >= off_series)
                )
                w[21 * BLOCK + b] = 1.0 if wide else 0.0
                for e in range(4):
                    w[(17 + e) * BLOCK + b] = q[e]
            for b in range(nb):
                off += w[21 * BLOCK + b] != 0.0
                for e in range(4):
                    out[j0 + b, e] = w[(17 + e) * BLOCK + b]
        return off

    return fifteen, eight


# streamed through before each "cold" call: more than the caches hold, so
# the call starts with its table, samples and times in memory only (as after
# other work, e.g. the benchmark's contenders called in turns)
_EVICT = np.ones(64 * 2**20 // 8)


def _best_ns_per_row(kernel, args, rows: int, cold: bool) -> float:
    kernel(*args)
    times = []
    for _ in range(REPEATS):
        if cold:
            _EVICT[::8] += 1.0  # one write per cache line
        t0 = time.perf_counter()
        kernel(*args)
        times.append(time.perf_counter() - t0)
    return min(times) / rows * 1e9


def main() -> None:
    import rbm_nb as rbm
    from rbm_nb._engine import fused
    from rbm_nb.core import frames

    source, (registered, *_rest) = bench_fused.workload()
    bench_fused.register(rbm, registered)
    # fill both squad tables
    rbm.lookup_transform("left_eye", "world")
    rbm.lookup_transform("world", "left_eye")
    fifteen, eight = _kernels()
    print(f"{source}; one thread; best of {REPEATS}; fast paths only")
    for name, at in (("head", "left_eye"), ("left_eye", "head")):
        frame, other = frames.resolve_frame(name), frames.resolve_frame(at)
        times, r = frame.data.track.base, frame.data.r
        table = fused._table(frame).rows
        target = (
            other.data.track.base
            + (other.data.track.origin - frame.data.track.origin) / 1e9
        )
        target = target[(target > times[1]) & (target < times[-2])].copy()
        # b from the table's great circle a -> b (unit segments)
        a = table[:, 0:4]
        b = np.cos(table[:, 9:10]) * a + np.sin(table[:, 9:10]) * table[:, 10:14]
        ab = np.ascontiguousarray(np.hstack([a, b]))
        out15 = np.empty((len(target), 4))
        out8 = np.empty((len(target), 4))
        off = eight(times, r, ab, target, out8) / len(target)
        line = f"{name} at {at}'s times ({len(target)} rows), ns/row:"
        for cold in (False, True):
            t15 = _best_ns_per_row(
                fifteen, (times, r, table, target, out15), len(target), cold
            )
            t8 = _best_ns_per_row(
                eight, (times, r, ab, target, out8), len(target), cold
            )
            line += (
                f" {'cold' if cold else 'warm'} 120 B {t15:4.1f}, 64 B {t8:4.1f} "
                f"({t8 / t15:.2f}x);"
            )
        line += f" rows off the series with 64 B: {off:.1%}"
        if off == 0.0:  # (else those rows' values here are not squad's)
            line += f"; max |difference| {np.max(np.abs(out15 - out8)):.1e}"
        print(line)


if __name__ == "__main__":
    main()
