"""Kernel time of a TimeSeries' zoom answers on a long recording (issue 35).

    PYTHONPATH=. python benchmarks/timeseries_zoom_latency.py [--hours 3] [--repeat 5]

The explorer's three panels at the example's rates (head 200 Hz, both eyes
~340 Hz, datetime64 stamps, a missing-sample run every ~40 ms in the eyes, as
in the real recording): builds the TimeSeries, then times the kernel's
answer to a window request (what ``_on_message`` computes on its worker
thread, without the comm) for windows of several lengths in the middle of
the recording, and the cursor's exact readout. Prints the best of
``--repeat`` runs in milliseconds and the rows answered; no thresholds.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np
import xarray as xr

from rbm_nb.widgets import TimeSeries

T0 = np.datetime64("2020-02-02T00:27:14.300365210", "ns")


def _series(hours: float, rate: float, columns: list[str], seed: int):
    n = int(hours * 3600 * rate)
    rng = np.random.default_rng(seed)
    step = int(round(1e9 / rate))
    stamps = T0 + (np.arange(n, dtype=np.int64) * step).astype("timedelta64[ns]")
    values = np.cumsum(rng.normal(size=(n, len(columns))), axis=0)
    values[rng.random(n) < 0.07] = np.nan
    return xr.DataArray(
        values,
        dims=("time", "c"),
        coords={"time": stamps, "c": columns},
        attrs={"units": "deg"},
    )


def _best(fn, repeat: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best * 1e3, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, default=3.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--width", type=int, default=1000)
    args = parser.parse_args()
    series = {
        "head yaw rate": _series(args.hours, 200.0, ["head"], 1),
        "gaze yaw": _series(args.hours, 340.0, ["left eye", "right eye"], 2),
        "gaze yaw rate": _series(args.hours, 340.0, ["left eye", "right eye"], 3),
    }
    rows = sum(s.sizes["time"] for s in series.values())
    # the first TimeSeries loads its bundle and widget machinery: not the data's
    TimeSeries({"warm-up": _series(0.001, 200.0, ["x"], 0)}).close()
    tracemalloc.start(30)
    start = time.perf_counter()
    plot = TimeSeries(series)
    built = time.perf_counter() - start
    kept = tracemalloc.get_traced_memory()[0]
    top = tracemalloc.take_snapshot().statistics("traceback")[:3]
    tracemalloc.stop()
    times = sum(s["time"].values.nbytes for s in series.values())
    print(
        f"{args.hours:g} h, {rows:,} rows in 3 panels: built in {built * 1e3:.0f} ms, "
        f"keeps {kept / 1e6:.2f} MB (one float64 copy of the times: {times / 1e6:.0f} MB)"
    )
    for stat in top:
        where = " < ".join(
            f"{f.filename.split('/')[-1]}:{f.lineno}" for f in stat.traceback[-4:]
        )
        print(f"  kept {stat.size / 1e6:.2f} MB at {where}")
    middle = args.hours * 1800.0
    print(f"{'window':>10}  {'best ms':>8}  {'rows sent':>10}  every sample")
    for span in (1.0, 10.0, 60.0, 600.0, 3600.0, args.hours * 3600.0):
        lo, hi = middle - span / 2, middle + span / 2
        if span >= args.hours * 3600.0:
            lo, hi = 0.0, args.hours * 3600.0
        ms, (answer, full) = _best(
            lambda lo=lo, hi=hi: plot._window_rows(lo, hi, args.width), args.repeat
        )
        sent = sum(x.size for x, _ in answer)
        print(f"{span:>9g}s  {ms:8.1f}  {sent:>10,}  {all(full)}")
    ms, _ = _best(lambda: plot.nearest_samples(middle + 0.0012345), args.repeat)
    print(f"{'readout':>10}  {ms:8.2f}")
    plot.close()


if __name__ == "__main__":
    main()
