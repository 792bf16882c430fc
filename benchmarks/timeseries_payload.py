"""Bytes the explorer's TimeSeries sends to the browser, and the time to build it.

    RBM_NB_DATA_DIR=../shared/data/rbm-data python benchmarks/timeseries_payload.py

Prints, for every sample and for a few ``max_points``, the samples per panel,
the binary buffers (sent once over the comm; base64 in an HTML export adds a
third) and the JSON state beside them.
"""

from __future__ import annotations

import json
import time

from rbm_nb.app import explorer
from rbm_nb.widgets import TimeSeries


def main() -> None:
    head, left_eye, right_eye, note = explorer.load_head_eye()
    explorer.register_head_eye_frames(head, left_eye, right_eye)
    series = explorer.explorer_series(head, left_eye, right_eye)
    print(f"data: {note}")
    print(
        f"{'max_points':>10}  {'samples per panel':>26}  {'buffers':>9}  {'json':>7}  {'build':>7}"
    )
    for max_points in (None, 20000, 5000):
        start = time.perf_counter()
        plot = TimeSeries(series, max_points=max_points)
        built = time.perf_counter() - start
        samples = [len(d["x"]) // 8 for d in plot.data]
        buffers = sum(len(d["x"]) + sum(len(y) for y in d["y"]) for d in plot.data)
        state = {k: v for k, v in plot.get_state().items() if k not in ("data", "_esm")}
        print(
            f"{str(max_points):>10}  {str(samples):>26}  {buffers / 1e6:7.2f}MB"
            f"  {len(json.dumps(state)) / 1e3:5.1f}kB  {built * 1e3:5.0f}ms"
        )
        plot.close()


if __name__ == "__main__":
    main()
