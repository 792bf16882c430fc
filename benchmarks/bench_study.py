"""A study of many synthetic recordings: sequential loop vs dask threads vs LocalCluster.

The study of issue 14: N synthetic head/eye recordings of M minutes (default
16 of 60 minutes, 4 GB of netCDF), written once into a cache folder
(``$RBM_NB_CACHE_DIR/study_<N>x<M>min``, else under the temporary
directory) and reused. Each recording gets the analysis of
``notebooks/07_many_recordings.ipynb`` plus fixation statistics: head speed,
the left eye's line of sight in the world (its elevation over confident
samples), and the eye-in-world angular speed (spline through the eye's
quaternions composed with the head's) with the fixations it implies
(< 30 deg/s for >= 100 ms). It returns a few numbers, reduced where it runs.

Every run is a fresh process (or fresh worker processes), warmed up first
on a short recording (imports, numba's cache), so that peak memory is that
run's own:

- ``loop``: a plain sequential loop over the recordings;
- ``threads``: ``Study.map`` on dask's default threaded scheduler;
- ``cluster``: ``Study.map`` on ``LocalCluster(n_workers=2,
  threads_per_worker=1, processes=True)``, started before the clock runs;
- ``tuned``: ``rbm_nb.study.local_cluster(2)``, the same cluster with the study's
  worker settings for big arrays (``rbm_nb.study.WORKER_SETTINGS``:
  glibc's malloc keeps arrays up to 32 MB on its heap instead of mapping and
  page-faulting each afresh, as distributed's default MALLOC_TRIM_THRESHOLD_
  makes it do; no statistical profiler), whole recordings and 60 s windows.

Printed per run: wall time, speed-up over the loop, and peak memory per
process -- the high-water resident set (``ru_maxrss``) and, above what the
process held after its warm-up, what it allocated at most (tracemalloc, read
inside each worker). Then the peak per worker for several window lengths
on the cluster, and the machine's load (``os.getloadavg``): the machine has
2 cores and other jobs may share them; run when it is quiet, and read ratios.

The cluster's rows end with where its time went: the task stream (busy
seconds per worker), CPU seconds per recording, and the speed-up as the
product of the CPU ratio and the ratio of cores the runs got.

    python benchmarks/bench_study.py                       # 16 x 60 min
    python benchmarks/bench_study.py --recordings 8 --minutes 10
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
import xarray as xr

import rbm_nb as rbm
from rbm_nb.app.explorer import SCENE_CAM_ROTATION, SCENE_CAM_TRANSLATION
from rbm_nb.data import synthetic_head_eye
from rbm_nb.study import open_study

FIXATION_SPEED = 30.0  # deg/s
FIXATION_MIN = 0.1  # s


def frames(rec):
    world = rbm.ReferenceFrame("world")
    head = rbm.ReferenceFrame.from_dataset(
        rec["head"], "position", "orientation", "time", parent=world, name="head"
    )
    camera = rbm.ReferenceFrame(
        "scene_cam", head, translation=SCENE_CAM_TRANSLATION,
        rotation=SCENE_CAM_ROTATION,
    )  # fmt: skip
    eye = rbm.ReferenceFrame.from_dataset(
        rec["left_eye"].dropna("time"), "position", "orientation", "time",
        parent=camera, name="left_eye",
    )  # fmt: skip
    return {"world": world, "head": head, "scene_cam": camera, "left_eye": eye}


def _fixations(times: np.ndarray, fixating: np.ndarray) -> tuple[int, float]:
    """Number and mean duration (s) of runs of fixating samples >= FIXATION_MIN."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], fixating.view(np.int8), [0]))))
    starts, stops = edges[::2], edges[1::2] - 1
    seconds = (times[stops] - times[starts]) / np.timedelta64(1, "s")
    long = seconds >= FIXATION_MIN
    return int(long.sum()), float(seconds[long].mean()) if long.any() else 0.0


def analysis(rec, fr):
    """Head speed, gaze elevation and fixation statistics of one recording (or window)."""
    speed = np.linalg.norm(
        rbm.lookup_linear_velocity(fr["head"], fr["world"], as_dataarray=True), axis=1
    )
    eye = rec["left_eye"].dropna("time")
    sight = xr.DataArray(
        np.tile([0.0, 0.0, 1.0], (eye.sizes["time"], 1)),
        {"time": eye.time, "cartesian_axis": ["x", "y", "z"]},
        ("time", "cartesian_axis"),
    )
    in_world = rbm.transform_vectors(
        sight, outof=fr["left_eye"], into=fr["world"], dim="cartesian_axis"
    )
    confident = eye.confidence.sel(time=in_world.time).values >= 0.6
    elevation = np.degrees(np.arcsin(in_world.values[confident, 1]))
    w = rbm.lookup_angular_velocity(fr["left_eye"], fr["world"], as_dataarray=True)
    gaze_speed = np.degrees(np.linalg.norm(w.values, axis=1))
    count, mean_s = _fixations(w.time.values, gaze_speed < FIXATION_SPEED)
    return xr.Dataset(
        {
            "walking_speed": float(np.median(speed)),
            "mean_gaze_elevation": float(elevation.mean()),
            "confident_fraction": float(confident.mean()),
            "fixation_fraction": float(np.mean(gaze_speed < FIXATION_SPEED)),
            "fixations": count,
            "mean_fixation_s": mean_s,
        }
    )


def per_window(rec, fr):
    """The analysis of one window, as one row over time (windows are joined)."""
    return analysis(rec, fr).expand_dims(time=[rec["head"].time.values[0]])


# ---------------------------------------------------------------------------
# data
# ---------------------------------------------------------------------------


def cache_folder(count: int, minutes: float) -> Path:
    root = os.environ.get("RBM_NB_CACHE_DIR") or tempfile.gettempdir()
    return Path(root) / f"rbm_nb_study_{count}x{minutes:g}min"


def write_recordings(folder: Path, count: int, minutes: float) -> None:
    for k in range(count):
        target = folder / f"rec{k:02d}"
        if (target / "right_eye.nc").exists():
            continue
        target.mkdir(parents=True, exist_ok=True)
        streams = synthetic_head_eye(duration=minutes * 60, seed=k)._asdict()
        for name, ds in streams.items():
            ds.to_netcdf(target / f".{name}.nc")
            (target / f".{name}.nc").rename(target / f"{name}.nc")
        print(f"  wrote {target.name}", flush=True)


def warm_folder() -> Path:
    """A 30 s recording for warming up processes (imports, numba's cache, netCDF)."""
    folder = cache_folder(1, 0.5)
    write_recordings(folder, 1, 0.5)
    return folder


# ---------------------------------------------------------------------------
# one run, in its own process
# ---------------------------------------------------------------------------


def max_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def cpu_seconds() -> float:
    """User + system CPU time of this process so far (all its threads)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


START: dict[str, int] = {}


def start_tracing() -> None:
    tracemalloc.start()
    START["traced"] = tracemalloc.get_traced_memory()[0]


def traced_peak_mb() -> float:
    """Peak allocated above the start of tracing (MB); 0 if not tracing."""
    if not tracemalloc.is_tracing():
        return 0.0
    current, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return (peak - START.get("traced", 0)) / 1e6


def warm_up() -> None:
    """Imports, numba's cache and netCDF reading, on a 30 s recording."""
    from rbm_nb.study._sources import _read_rows

    study = open_study(warm_folder())
    rec = study.open(study.names[0])
    analysis(rec, frames(rec))
    for path in (warm_folder() / study.names[0]).glob("*.nc"):
        _read_rows(path, (0, 100))


def run_loop(folder: Path, trace: bool) -> dict:
    study = open_study(folder)
    names = study.names
    warm_up()
    if trace:
        start_tracing()
    cpu = cpu_seconds()
    start = time.perf_counter()
    out = {}
    for name in names:
        rec = study.open(name)
        out[name] = analysis(rec, frames(rec))
        del rec
    seconds = time.perf_counter() - start
    cpu = cpu_seconds() - cpu
    result = xr.concat(list(out.values()), dim="recording")
    return {
        "seconds": seconds,
        "cpu": cpu,
        "rss_mb": [max_rss_mb()],
        "traced_mb": [traced_peak_mb()],
        "result": result.walking_speed.values.tolist(),
    }


def run_threads(folder: Path, trace: bool) -> dict:
    import dask

    study = open_study(folder)
    warm_up()
    if trace:
        start_tracing()
    cpu = cpu_seconds()
    start = time.perf_counter()
    result = study.map(analysis, frames=frames, progress=False)
    seconds = time.perf_counter() - start
    return {
        "seconds": seconds,
        "cpu": cpu_seconds() - cpu,
        "workers": dask.config.get("num_workers", None) or os.cpu_count(),
        "rss_mb": [max_rss_mb()],
        "traced_mb": [traced_peak_mb()],
        "result": result.walking_speed.values.tolist(),
    }


def _tuned_settings() -> dict:
    """rbm_nb.study.WORKER_SETTINGS (what ``rbm_nb.study.local_cluster`` sets)."""
    from rbm_nb.study import WORKER_SETTINGS

    return dict(WORKER_SETTINGS)


def run_cluster(
    folder: Path,
    windows: list[float | None],
    trace: bool,
    limit: int | None = None,
    tuned: bool = False,
) -> dict:
    from distributed import Client, LocalCluster

    from rbm_nb.study import Study, find_sources, local_cluster

    study = Study(find_sources(folder)[:limit])
    runs = []
    for window in windows:
        # fresh workers per run: their high-water marks are this run's
        with (
            (
                # the study's own cluster: WORKER_SETTINGS, TLS
                local_cluster(2, silence_logs=50)
                if tuned
                else LocalCluster(
                    n_workers=2, threads_per_worker=1, processes=True,
                    host="127.0.0.1", dashboard_address=None, silence_logs=50,
                )
            ) as cluster,
            Client(cluster, security=cluster.security) as client,
        ):  # fmt: skip
            client.run(warm_up)
            if trace:
                client.run(start_tracing)
            cpu = client.run(cpu_seconds)
            client.get_task_stream()  # start recording the task stream
            start = time.perf_counter()
            if window is None:
                result = study.map(analysis, frames=frames, progress=False)
                speeds = result.walking_speed.values.tolist()
            else:
                result = study.map(
                    per_window, frames=frames, window=window, progress=False
                )
                speeds = []
            seconds = time.perf_counter() - start
            cpu_after = client.run(cpu_seconds)
            stream = client.get_task_stream()
            runs.append(
                {
                    "window": window,
                    "seconds": seconds,
                    "cpu": sum(cpu_after[w] - cpu[w] for w in cpu),
                    "tasks": _task_times(stream, start),
                    "rss_mb": list(client.run(max_rss_mb).values()),
                    "traced_mb": list(client.run(traced_peak_mb).values()),
                    "result": speeds,
                }
            )
    return {"runs": runs}


def _task_times(stream: list, start: float) -> dict:
    """From distributed's task stream: busy time per worker, first start, last end.

    Times are wall-clock seconds on the workers (same machine as this process).
    """
    busy: dict[str, float] = {}
    first, last = float("inf"), 0.0
    epoch = time.time() - (time.perf_counter() - start)  # the run's start
    for task in stream:
        for span in task.get("startstops", ()):
            if span.get("action") != "compute":
                continue
            busy[task["worker"]] = busy.get(task["worker"], 0.0) + (
                span["stop"] - span["start"]
            )
            first = min(first, span["start"] - epoch)
            last = max(last, span["stop"] - epoch)
    return {"busy": sorted(busy.values()), "first": first, "last": last}


def child(
    mode: str, folder: Path, windows: list[float | None], trace: bool, limit: int
) -> None:
    if mode == "loop":
        out = run_loop(folder, trace)
    elif mode == "threads":
        out = run_threads(folder, trace)
    else:
        out = run_cluster(folder, windows, trace, limit or None, mode == "tuned")
    print("RESULT " + json.dumps(out), flush=True)


def in_subprocess(
    mode: str, folder: Path, windows=(), trace=False, limit=0, env=None
) -> dict:
    command = [sys.executable, __file__, "--child", mode, "--folder", str(folder)]
    command += ["--limit", str(limit)]
    if trace:
        command.append("--trace")
    for w in windows:
        command += ["--window", "whole" if w is None else str(w)]
    done = subprocess.run(
        command, capture_output=True, text=True, check=False,
        env=None if env is None else {**os.environ, **env},
    )  # fmt: skip
    for line in done.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT ") :])
    raise RuntimeError(f"{mode} run failed:\n{done.stdout}\n{done.stderr}")


# ---------------------------------------------------------------------------
# the report
# ---------------------------------------------------------------------------


def _row(label: str, run: dict, loop: float) -> str:
    seconds = run["seconds"]
    return (
        f"{label:40s} {seconds:8.1f} {loop / seconds:7.2f} {run['cpu']:8.1f} "
        f"{run['cpu'] / seconds:6.2f} {max(run['rss_mb']):9.0f}"
    )


def _explain(whole: dict, loop: dict, label: str) -> None:
    """Where a cluster run's time went, and its speed-up decomposed."""
    tasks = whole["tasks"]
    t_loop = loop["seconds"]
    print()
    print(f"where the cluster's time goes ({label}, whole recordings):")
    print(
        f"  first task started {tasks['first']:.2f} s after the call, last ended "
        f"{tasks['last']:.2f} s, call returned {whole['seconds']:.2f} s"
    )
    print(
        "  busy (task) seconds per worker: "
        + ", ".join(f"{b:.1f}" for b in tasks["busy"])
        + f"; CPU per recording: loop {loop['cpu'] / len(loop['result']):.2f} s,"
        f" cluster {whole['cpu'] / len(loop['result']):.2f} s"
    )
    share = loop["cpu"] / t_loop
    print(
        f"  speed-up = (CPU loop / CPU cluster) x (cores cluster / cores loop) = "
        f"{loop['cpu'] / whole['cpu']:.2f} x {whole['cpu'] / whole['seconds']:.2f}"
        f" / {share:.2f} = {t_loop / whole['seconds']:.2f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", type=int, default=16)
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--folder", type=Path, default=None)
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--window", action="append", default=[], help=argparse.SUPPRESS)
    parser.add_argument("--trace", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--limit", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument(
        "--memory-recordings", type=int, default=4,
        help="recordings in the memory-vs-window runs (the first ones)",
    )  # fmt: skip
    parser.add_argument(
        "--memory-windows", default="30,60,300,whole",
        help="window lengths (s) for the memory table, 'whole' for none",
    )  # fmt: skip
    args = parser.parse_args()
    if args.child:
        windows = [None if w == "whole" else float(w) for w in args.window]
        child(args.child, args.folder, windows, args.trace, args.limit)
        return

    folder = args.folder or cache_folder(args.recordings, args.minutes)
    print(f"{args.recordings} recordings of {args.minutes:g} min in {folder}")
    write_recordings(folder, args.recordings, args.minutes)
    size_mb = sum(p.stat().st_size for p in folder.rglob("*.nc")) / 1e6
    print(f"  {size_mb:.0f} MB of netCDF; load average {os.getloadavg()}")
    warm_folder()

    loop = in_subprocess("loop", folder)
    # the loop with the workers' tuned malloc settings, for a fair comparison
    malloc = {
        key.rsplit(".", 1)[1]: value
        for key, value in _tuned_settings().items()
        if key.startswith("distributed.nanny.pre-spawn-environ.")
    }
    loop_tuned = in_subprocess("loop", folder, env=malloc)
    threads = in_subprocess("threads", folder)
    cluster = in_subprocess("cluster", folder, [None])["runs"]
    tuned = in_subprocess("tuned", folder, [None, 60.0])["runs"]
    for run in (loop_tuned, threads, cluster[0], tuned[0]):
        np.testing.assert_allclose(run["result"], loop["result"], rtol=1e-12)

    t_loop = loop["seconds"]
    print()
    print(
        f"{'run':40s} {'seconds':>8s} {'x loop':>7s} {'CPU s':>8s} {'cores':>6s} "
        f"{'RSS MB':>9s}"
    )
    print(_row("sequential loop", loop, t_loop))
    print(_row("sequential loop, tuned malloc", loop_tuned, t_loop))
    print(
        _row(f"Study.map, threads ({threads['workers']})", threads, t_loop)
    )  # fmt: skip
    print(_row("Study.map, LocalCluster(2)", cluster[0], t_loop))
    for run in tuned:
        label = "Study.map, rbm_nb.study.local_cluster(2)"
        if run["window"]:
            label += f", {run['window']:g} s win"
        print(_row(label, run, t_loop))
    print(
        "(CPU s: user + system time of the processes doing the work -- the loop's,"
        " the threads', both workers';\n cores: CPU s / seconds, the cores they got"
        " on average; RSS MB: the high-water resident set of\n that process -- for"
        " the cluster, of the larger worker; every run in fresh processes;\n load"
        f" average now {os.getloadavg()})"
    )
    print(
        " tuned: workers' malloc keeps arrays up to 32 MB and 256 MB of freed heap, no"
    )
    print(" profiler (rbm_nb.study.WORKER_SETTINGS, set by rbm_nb.study.local_cluster)")
    _explain(cluster[0], loop, "default, vs the loop")
    _explain(tuned[0], loop, "tuned, vs the loop")
    _explain(tuned[0], loop_tuned, "tuned, vs the loop with the same malloc")

    windows = [
        None if w == "whole" else float(w) for w in args.memory_windows.split(",")
    ]
    print()
    count = min(args.memory_recordings, args.recordings)
    print(f"peak per worker vs window, LocalCluster(2), {count} recordings")
    print("(alloc MB: the most a worker allocated above what it held after its")
    print(" warm-up, tracemalloc in the worker; this table's runs are traced)")
    print(f"{'window':>10s} {'seconds':>8s} {'RSS MB':>9s} {'alloc MB':>10s}")
    for run in in_subprocess("cluster", folder, windows, True, count)["runs"]:
        label = "whole" if run["window"] is None else f"{run['window']:g} s"
        print(
            f"{label:>10s} {run['seconds']:8.1f} {max(run['rss_mb']):9.0f} "
            f"{max(run['traced_mb']):10.0f}"
        )


if __name__ == "__main__":
    main()
