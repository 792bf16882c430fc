"""A study of many synthetic recordings: sequential loop vs dask threads vs LocalCluster.

Writes N synthetic head/eye recordings of M minutes to a scratch folder (or
reuses them), then runs the same analysis -- head speed and the left eye's
line of sight in the world, summarised per recording -- four ways:

- a plain sequential loop over the recordings (what a user writes today);
- ``Study.map`` on dask's default threaded scheduler;
- ``Study.map`` on a ``dask.distributed.LocalCluster`` with 2 worker processes;
- the same cluster with 60 s windows (memory per task set by the window).

It prints wall time, the speed-up over the loop, and peak memory (this
process for the loop and threads; the largest worker for the cluster), and
then the peak worker memory of a windowed run for several recording lengths.
The machines are shared and noisy: read ratios, and run it twice.

    python benchmarks/bench_study.py --recordings 16 --minutes 60

The default (8 recordings of 10 minutes) runs in a few minutes.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

import rbm_nb as rbm
from rbm_nb.data import synthetic_head_eye
from rbm_nb.explorer import SCENE_CAM_ROTATION, SCENE_CAM_TRANSLATION
from rbm_nb.study import Recording, open_study


def build_frames(rec):
    world = rbm.ReferenceFrame("world")
    head = rbm.ReferenceFrame.from_dataset(
        rec["head"], "position", "orientation", "time", parent=world, name="head"
    )
    camera = rbm.ReferenceFrame(
        "scene_cam",
        head,
        translation=SCENE_CAM_TRANSLATION,
        rotation=SCENE_CAM_ROTATION,
    )
    eye = rbm.ReferenceFrame.from_dataset(
        rec["left_eye"].dropna("time"), "position", "orientation", "time",
        parent=camera, name="left_eye",
    )  # fmt: skip
    return {"world": world, "head": head, "left_eye": eye}


def series(rec, frames):
    v = rbm.lookup_linear_velocity(frames["head"], frames["world"], as_dataarray=True)
    n = frames["left_eye"].timestamps.size
    sight = xr.DataArray(
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        {"time": frames["left_eye"].timestamps, "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
    )
    gaze = rbm.transform_vectors(
        sight, outof=frames["left_eye"], into=frames["world"], dim="cartesian_axis"
    )
    return xr.Dataset(
        {
            "head_speed": np.sqrt((v**2).sum("cartesian_axis")),
            "gaze": gaze.rename(time="eye_time"),
        }
    )


def summary(rec, frames):
    """Per recording: mean walking speed, gaze elevation and eye-in-world speed.

    The eye's angular velocity in the world (the spline through the eye's
    quaternions, composed with the head's) is the costly part, as in a real
    fixation/saccade analysis.
    """
    s = series(rec, frames)
    elevation = np.degrees(np.arcsin(s.gaze.sel(cartesian_axis="y")))
    eye_in_world = rbm.lookup_angular_velocity(
        frames["left_eye"], frames["world"], as_dataarray=True
    )
    eye_speed = np.degrees(np.sqrt((eye_in_world**2).sum("cartesian_axis")))
    return xr.Dataset(
        {
            "mean_speed": s.head_speed.mean(),
            "mean_elevation": elevation.mean(),
            "median_eye_speed": eye_speed.median(),
        }
    )


def windowed_speed(rec, frames):
    return (
        series(rec, frames)[["head_speed"]]
        .mean("time")
        .expand_dims(time=[rec["head"].time.values[0]])
    )


def write_recordings(folder: Path, count: int, minutes: float) -> None:
    for k in range(count):
        target = folder / f"rec{k:02d}"
        if (target / "right_eye.nc").exists():
            continue
        target.mkdir(parents=True, exist_ok=True)
        streams = synthetic_head_eye(duration=minutes * 60, seed=k)._asdict()
        for name, ds in streams.items():
            ds.to_netcdf(target / f"{name}.nc")
        print(f"  wrote {target.name}", flush=True)


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def loop(folder: Path):
    study = open_study(folder)
    out = {}
    for name in study.names:
        rec = study.open(name)
        out[name] = summary(rec, build_frames(rec)).compute()
    return out


def timed(label, func, rows, baseline=None):
    start = time.perf_counter()
    result = func()
    seconds = time.perf_counter() - start
    rows.append((label, seconds, baseline))
    return result, seconds


def cluster_run(folder: Path, **options):
    from distributed import Client, LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=None, silence_logs=50,
    ) as cluster, Client(cluster) as client:  # fmt: skip
        study = open_study(folder)
        # imports and numba's cache load on each worker are not the study
        client.run(lambda: __import__("rbm_nb").lookup_linear_velocity)
        start = time.perf_counter()
        if options.get("window"):
            result = study.map(
                windowed_speed, frames=build_frames, progress=False, combine=False,
                window=options["window"], margin=1.0,
            )  # fmt: skip
        else:
            result = study.map(summary, frames=build_frames, progress=False)
        seconds = time.perf_counter() - start
        worker_peak = max(client.run(peak_mb).values())
    return result, seconds, worker_peak


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", type=int, default=8)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument(
        "--folder", type=Path, default=None, help="reuse recordings here"
    )
    args = parser.parse_args()

    folder = args.folder or Path(tempfile.mkdtemp(prefix="rbm_nb_study_"))
    print(f"{args.recordings} recordings of {args.minutes:g} min in {folder}")
    write_recordings(folder, args.recordings, args.minutes)
    size_mb = sum(p.stat().st_size for p in folder.rglob("*.nc")) / 1e6
    print(f"  {size_mb:.0f} MB of netCDF")

    # warm numba's cache and imports in this process
    first = Recording("warm", synthetic_head_eye(duration=16.0, seed=99)._asdict())
    summary(first, build_frames(first))

    start = time.perf_counter()
    expected = loop(folder)
    t_loop = time.perf_counter() - start
    mem_loop = peak_mb()

    start = time.perf_counter()
    threaded = open_study(folder).map(summary, frames=build_frames, progress=False)
    t_threads = time.perf_counter() - start
    mem_threads = peak_mb()

    clustered, t_cluster, mem_cluster = cluster_run(folder)
    _, t_window, mem_window = cluster_run(folder, window=60.0)

    for name, want in expected.items():
        for result in (threaded, clustered):
            got = result.sel(recording=name)
            assert np.allclose(got.mean_speed, want.mean_speed, rtol=1e-12)

    print()
    print(f"{'run':34s} {'seconds':>8s} {'x loop':>7s} {'peak MB':>8s}")
    for label, seconds, mem in (
        ("sequential loop", t_loop, mem_loop),
        ("Study.map, threads (2 cores)", t_threads, mem_threads),
        ("Study.map, LocalCluster(2)", t_cluster, mem_cluster),
        ("Study.map, LocalCluster(2), 60 s win", t_window, mem_window),
    ):
        print(f"{label:34s} {seconds:8.1f} {t_loop / seconds:7.2f} {mem:8.0f}")
    print("(peak MB: this process for the loop and threads -- cumulative, so the")
    print(" threads row includes the loop's peak -- and the largest worker otherwise)")


if __name__ == "__main__":
    main()
