"""Bytes the explorer's plots send to the browser as the recording grows (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_scale.py [--compare OTHER_TREE] [--hours 0 1 3]

The explorer's series (head yaw rate, gaze yaw and gaze yaw rate of both
eyes) of the example recording (5.5 min when real) are tiled in time to 1 h
and 3 h, NaN rows kept. For each length a TimeSeries is built and linked to a
Player on the head's timestamps, as ``explorer.dashboard()`` does (the eye
clock starts 0.7 ms before the head's, so linking changes the time base), in
two ways: the player given at construction ("player=") and linked afterwards
("linked later"). Printed: the bytes of the comm's open message and of every
message after it (JSON and binary buffers), at full resolution and at the
explorer's ``max_points``, and, with ``max_points``, the answer to a zoom into
100-110 s (the samples there at full resolution; not in the total). Only the widget's own comm is counted (not the
Player's, nor the 3D scene's).

``--compare TREE`` runs the same measurement on another checkout (e.g. the
main branch, before this change) in a subprocess and prints both side by side.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np


class CountingComm:
    """Stands in for the kernel's comm; counts what would go to the browser."""

    kernel = "Truthy"  # ipywidgets only checks that there is one
    live: list[CountingComm] = []

    def __init__(self, *args, data=None, buffers=None, **kwargs):
        self.comm_id = os.urandom(16).hex()
        self.opened = len(json.dumps(data, default=str)) + sum(
            memoryview(b).nbytes for b in buffers or []
        )
        self.after = 0
        CountingComm.live.append(self)

    def open(self, *args, **kwargs):
        pass

    def on_msg(self, callback):
        pass

    def send(self, data=None, metadata=None, buffers=None):
        self.after += len(json.dumps(data, default=str)) + sum(
            memoryview(b).nbytes for b in buffers or []
        )

    def close(self, *args, **kwargs):
        pass


def tiled(series: dict, hours: float) -> dict:
    """Every series repeated in time to at least ``hours`` (0: as recorded)."""
    import xarray as xr

    if hours <= 0:
        return series
    first = min(da.time.values[0] for da in series.values())
    last = max(da.time.values[-1] for da in series.values())
    period = (last - first) + np.timedelta64(5, "ms")
    tiles = int(
        np.ceil(hours * 3600e9 / period.astype("timedelta64[ns]").astype(np.int64))
    )
    out = {}
    for name, da in series.items():
        shifts = (np.arange(tiles) * period).astype("timedelta64[ns]")
        time = (da.time.values[None, :] + shifts[:, None]).ravel()
        values = np.concatenate([da.values] * tiles, axis=0)
        out[name] = xr.DataArray(
            values,
            dims=da.dims,
            coords={**{d: da[d] for d in da.dims if d != "time"}, "time": time},
            attrs=da.attrs,
        )
    return out


def measure(hours_list) -> list[dict]:
    import comm

    from rbm_nb.app import explorer
    from rbm_nb.widgets import Player, TimeSeries

    comm.create_comm = CountingComm
    head, left_eye, right_eye, note = explorer.load_head_eye()
    explorer.register_head_eye_frames(head, left_eye, right_eye)
    base = explorer.explorer_series(head, left_eye, right_eye)
    rows = []
    for hours in hours_list:
        series = tiled(base, hours)
        span = max(
            float((da.time.values[-1] - da.time.values[0]) / np.timedelta64(1, "s"))
            for da in series.values()
        )
        head_time = tiled({"h": base["head yaw rate"]}, hours)["h"].time.values
        player = Player(head_time)
        for max_points in (None, explorer.PLOT_MAX_POINTS):
            for how in ("player=", "linked later"):
                CountingComm.live.clear()
                if how == "player=":
                    plot = TimeSeries(series, player=player, max_points=max_points)
                else:
                    plot = TimeSeries(series, max_points=max_points)
                    plot.player = player
                own = plot.comm
                zoom = None
                if max_points is not None and hasattr(plot, "window"):
                    # what a zoom into 10 s costs: the answer to the page's request
                    before = own.after
                    plot._on_message(
                        plot,
                        {"type": "window", "id": 1, "start": 100.0, "end": 110.0},
                        [],
                    )
                    if hasattr(plot, "_last_request"):  # answered on a worker thread
                        plot._last_request.result(timeout=600)
                    zoom = (own.after - before) / 1e6
                    own.after = before
                rows.append(
                    {
                        "length": f"{span / 60:.1f} min"
                        if span < 3600
                        else f"{span / 3600:.1f} h",
                        "max_points": str(max_points),
                        "how": how,
                        "open_MB": own.opened / 1e6,
                        "after_MB": own.after / 1e6,
                        "zoom_MB": zoom,
                    }
                )
                plot.close()
                del plot
        player.close()
    import ipywidgets

    ipywidgets.Widget.close_all()  # while the interpreter can still close them
    print(f"data: {note}", file=sys.stderr)
    return rows


def table(columns: dict[str, list[dict]]) -> None:
    names = list(columns)
    first = columns[names[0]]
    head = f"{'recording':>10} {'max_points':>10} {'player':>13}"
    for n in names:
        head += f" | {n + ': open + after = total MB, 10 s zoom':>46}"
    print(head)
    for i, row in enumerate(first):
        line = f"{row['length']:>10} {row['max_points']:>10} {row['how']:>13}"
        for n in names:
            r = columns[n][i]
            total = r["open_MB"] + r["after_MB"]
            zoom = "-" if r.get("zoom_MB") is None else f"{r['zoom_MB']:.3f}"
            line += f" | {r['open_MB']:12.2f} + {r['after_MB']:8.2f} = {total:8.2f} {zoom:>6}"
        print(line)
    if len(names) == 2:
        a, b = (sum(r["open_MB"] + r["after_MB"] for r in columns[n]) for n in names)
        print(f"all rows: {names[1]} sends {b / a:.2f}x the bytes of {names[0]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[0, 1, 3])
    parser.add_argument("--compare", help="another checkout to measure the same way")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.json:
        print(json.dumps(measure(args.hours)))
        return
    columns = {}
    if args.compare:
        env = {**os.environ, "PYTHONPATH": os.path.abspath(args.compare)}
        out = subprocess.run(
            [sys.executable, __file__, "--json", "--hours", *map(str, args.hours)],
            env=env,
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        columns[os.path.basename(os.path.abspath(args.compare))] = json.loads(out)
    columns["this tree"] = measure(args.hours)
    table(columns)


if __name__ == "__main__":
    main()
