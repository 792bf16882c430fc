"""Scaling on worker processes: 1 vs 2 workers of ``rbm_nb.study.local_cluster``.

Two workloads, each run on a fresh cluster of 1 and then of 2 worker
processes (1 thread each; the machine has 2 cores, so run when it is quiet
and read the ratios):

- **study**: ``Study.map`` of notebook 07's analysis (head speed, gaze
  elevation of confident samples) over ``--recordings`` copies of the real
  head/eye recording (``$RBM_NB_DATA_DIR`` or ``../shared/data/rbm-data``;
  the copies are symbolic links in a temporary folder, so the files are read
  by the workers, never copied);
- **lazy transform**: ``transform_points`` of a dask-backed recording of
  ``--samples`` samples (default 10^7) out of a moving head frame of as many
  samples (the real head recording tiled in time), in chunks of
  ``--chunk`` samples, into the world. The input is generated on the
  workers (a few bytes of graph per chunk), so what travels is the frames:
  each chunk's task carries the frame's samples its time window needs. The
  result is gathered and compared with the eager transform.

Printed per workload and worker count: wall time (the median of
``--repeats`` runs, after a warm-up run), the 1-worker / 2-worker ratio,
bytes shipped per task (the pickled graph each task needs, read from the
graph as the client sends it, and the largest), and each worker's peak
resident memory (``VmHWM``, warm-up included).

    python benchmarks/bench_distributed.py
    python benchmarks/bench_distributed.py --recordings 16 --samples 1e6 --repeats 1
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time
from pathlib import Path

import cloudpickle
import numpy as np
import xarray as xr

import rbm_nb as rbm
from rbm_nb.app.explorer import SCENE_CAM_ROTATION, SCENE_CAM_TRANSLATION
from rbm_nb.study import local_cluster, open_study

REPO = Path(__file__).resolve().parents[1]
DATA = Path(
    os.environ.get("RBM_NB_DATA_DIR", REPO.parent / "shared" / "data" / "rbm-data")
)
STREAMS = ("head", "left_eye", "right_eye")


# ---------------------------------------------------------------------------
# the study (notebook 07's analysis)
# ---------------------------------------------------------------------------


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


def gaze_summary(rec, fr):
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
    return xr.Dataset(
        {
            "median_walking_speed": float(np.median(speed)),
            "mean_gaze_elevation": float(elevation.mean()),
            "confident_fraction": float(confident.mean()),
        }
    )


def tiled_study_folder(count: int) -> Path:
    """``count`` recordings, each the real one (symbolic links to its files)."""
    folder = Path(tempfile.mkdtemp(prefix="rbm_nb_bench_distributed_"))
    for k in range(count):
        rec = folder / f"rec{k:02d}"
        rec.mkdir()
        for stream in STREAMS:
            (rec / f"{stream}.nc").symlink_to(DATA / f"{stream}.nc")
    return folder


def study_graph_bytes(study) -> tuple[float, int]:
    """Mean and largest pickled graph per task of the study."""
    results = study.delayed(gaze_summary, frames=frames)
    graph: dict = {}
    for result in results.values():
        graph.update(dict(result.__dask_graph__()))
    sizes = [len(cloudpickle.dumps(task)) for task in graph.values()]
    return float(np.mean(sizes)), max(sizes)


def run_study(client, study) -> float:
    start = time.perf_counter()
    result = study.map(gaze_summary, frames=frames, progress=False)
    elapsed = time.perf_counter() - start
    assert result.sizes["recording"] == len(study)
    return elapsed


# ---------------------------------------------------------------------------
# the lazy transform of a long recording
# ---------------------------------------------------------------------------


def long_head_frame(samples: int) -> tuple[rbm.ReferenceFrame, rbm.ReferenceFrame]:
    """The real head recording tiled in time to ``samples`` samples."""
    with xr.open_dataset(DATA / "head.nc") as ds:
        head = ds[["position", "orientation"]].load()
    times = head.time.values
    step = np.diff(times)
    reps = -(-samples // len(times))
    gaps = np.concatenate([np.tile(step, reps), step[: reps - 1]])
    # every tile continues from the last time of the one before
    t = times[0] + np.concatenate([[np.timedelta64(0, "ns")], np.cumsum(gaps)])
    position = np.tile(head.position.values, (reps, 1))[:samples]
    orientation = np.tile(head.orientation.values, (reps, 1))[:samples]
    world = rbm.ReferenceFrame("world")
    frame = rbm.ReferenceFrame(
        "head", world, translation=position, rotation=orientation,
        timestamps=t[:samples],
    )  # fmt: skip
    return world, frame


def _positions(block, block_info=None):
    """Points in the head frame for rows ``lo:hi`` (made where the task runs)."""
    lo, hi = block_info[None]["array-location"][0]
    k = np.arange(lo, hi, dtype=np.float64)
    return np.c_[0.1 * np.sin(k / 500), 0.1 * np.cos(k / 700), 0.05 + 0 * k]


def lazy_points(times: np.ndarray, chunk: int):
    import dask.array as dsa

    n = len(times)
    data = dsa.map_blocks(
        _positions, dsa.zeros((n, 3), chunks=(chunk, 3)), dtype=np.float64
    )
    return xr.DataArray(
        data,
        {"time": times, "cartesian_axis": ["x", "y", "z"]},
        ("time", "cartesian_axis"),
    )


def transform_graph_bytes(lazy) -> tuple[float, int]:
    """Mean and largest pickled task of the transform's own graph layers."""
    graph = dict(lazy.data.__dask_graph__())
    sizes = [
        len(cloudpickle.dumps(v)) for k, v in graph.items() if "_run_block" in str(k)
    ]
    return float(np.mean(sizes)), max(sizes)


def run_transform(client, points, world, head, eager) -> float:
    start = time.perf_counter()
    lazy = rbm.transform_points(points, outof=head, into=world)
    (result,) = client.compute([lazy], sync=True)
    elapsed = time.perf_counter() - start
    np.testing.assert_allclose(result.values, eager, rtol=1e-12, atol=1e-12)
    return elapsed


# ---------------------------------------------------------------------------
# clusters
# ---------------------------------------------------------------------------


def _high_water_mb() -> float:
    """This process's peak resident memory (MB), from ``/proc/self/status``.

    Not ``ru_maxrss``: Linux keeps it across ``fork`` + ``exec``, so a worker
    that the nanny forked from this (client) process would report this
    process's peak, not its own.
    """
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def peak_mb(client) -> list[float]:
    return list(client.run(_high_water_mb).values())


def timed(workers: int, repeats: int, run) -> tuple[float, list[float]]:
    cluster = local_cluster(workers, silence_logs=50)
    try:
        client = cluster.get_client()
        try:
            run(client)  # warm-up: imports and numba's cache in the workers
            times = [run(client) for _ in range(repeats)]
            return statistics.median(times), peak_mb(client)
        finally:
            client.close()
    finally:
        cluster.close()


def report(name: str, rows: dict, per_task: tuple[float, int]) -> None:
    print(f"\n{name}")
    for workers, (seconds, peaks) in rows.items():
        peak = ", ".join(f"{p:.0f}" for p in peaks)
        print(
            f"  {workers} worker(s): {seconds:7.2f} s   peak RSS per worker: {peak} MB"
        )
    one, two = rows[1][0], rows[2][0]
    print(f"  1 worker / 2 workers: {one / two:.2f}x")
    print(f"  bytes per task: mean {per_task[0]:,.0f}, largest {per_task[1]:,}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", type=int, default=16)
    parser.add_argument("--samples", type=float, default=1e7)
    parser.add_argument("--chunk", type=int, default=250_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()}")

    study = open_study(tiled_study_folder(args.recordings))
    rows = {
        n: timed(n, args.repeats, lambda client: run_study(client, study))
        for n in (1, 2)
    }
    report(
        f"study: {len(study)} copies of the real recording "
        f"({args.recordings} tasks, notebook 07's analysis)",
        rows,
        study_graph_bytes(study),
    )

    samples = int(args.samples)
    world, head = long_head_frame(samples)
    points = lazy_points(head.timestamps, args.chunk)
    eager = rbm.transform_points(points.compute(), outof=head, into=world).values
    rows = {
        n: timed(
            n, args.repeats,
            lambda client: run_transform(client, points, world, head, eager),
        )
        for n in (1, 2)
    }  # fmt: skip
    lazy = rbm.transform_points(points, outof=head, into=world)
    report(
        f"lazy transform_points: {samples:,} samples, a moving frame of as many, "
        f"{lazy.data.numblocks[0]} chunks of {args.chunk:,} "
        f"(frame data {head.translation.nbytes + head.rotation.nbytes + head.timestamps.nbytes:,} bytes)",
        rows,
        transform_graph_bytes(lazy),
    )
    print(f"\nload average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
