"""Studies of many recordings: threads, a real dask.distributed LocalCluster, windows."""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest
import xarray as xr
from head_start import in_background

dask = pytest.importorskip("dask")

import rbm_nb as rbm  # noqa: E402
from rbm_nb.app.explorer import SCENE_CAM_ROTATION, SCENE_CAM_TRANSLATION  # noqa: E402
from rbm_nb.data import synthetic_head_eye  # noqa: E402
from rbm_nb.study import WORKER_SETTINGS, local_cluster, open_study  # noqa: E402

N_RECORDINGS = 8


def build_frames(rec):
    """Head and scene-camera-fixed eye frames, as objects (tasks share the registry)."""
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
        rec["left_eye"].dropna("time"),
        "position",
        "orientation",
        "time",
        parent=camera,
        name="left_eye",
    )
    return {"world": world, "head": head, "left_eye": eye}


def head_and_gaze(rec, frames):
    """Head speed and the left eye's line of sight in the world, over time."""
    v = rbm.lookup_linear_velocity(frames["head"], frames["world"], as_dataarray=True)
    sight = xr.DataArray(
        np.tile([0.0, 0.0, 1.0], (frames["left_eye"].timestamps.size, 1)),
        {"time": frames["left_eye"].timestamps, "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
    )
    gaze = rbm.transform_vectors(
        sight, outof=frames["left_eye"], into=frames["world"], dim="cartesian_axis"
    )
    speed = np.sqrt((v**2).sum("cartesian_axis"))
    return xr.Dataset({"head_speed": speed, "gaze": gaze.rename(time="eye_time")})


def summary(rec, frames):
    """Whole-recording numbers: mean head speed and mean gaze elevation."""
    series = head_and_gaze(rec, frames)
    elevation = np.degrees(np.arcsin(series.gaze.sel(cartesian_axis="y")))
    return xr.Dataset(
        {
            "mean_speed": series.head_speed.mean(),
            "mean_elevation": elevation.mean(),
        }
    )


def sequential(recordings, analysis):
    """The loop a user would write without rbm_nb.study."""
    out = {}
    for name, streams in recordings.items():
        rec = rbm.study.Recording(name, streams)
        out[name] = analysis(rec, build_frames(rec))
    return out


@pytest.fixture(scope="module")
def recordings():
    return {
        f"subject{k:02d}": synthetic_head_eye(duration=18.0, seed=k)._asdict()
        for k in range(N_RECORDINGS)
    }


@pytest.fixture(scope="module")
def study_folder(recordings, tmp_path_factory):
    folder = tmp_path_factory.mktemp("study")
    for name, streams in recordings.items():
        (folder / name).mkdir()
        for stream, ds in streams.items():
            ds.to_netcdf(folder / name / f"{stream}.nc")
    return folder


@pytest.fixture(scope="module")
def expected(recordings):
    return sequential(recordings, summary)


def assert_summaries_equal(result, expected):
    assert list(result.recording.values) == sorted(expected)
    for name, want in expected.items():
        got = result.sel(recording=name)
        for var in want.data_vars:
            np.testing.assert_allclose(got[var].values, want[var].values, rtol=1e-12)


def test_threads_give_the_sequential_numbers(study_folder, expected):
    study = open_study(study_folder)
    assert study.names == sorted(expected)
    result = study.map(summary, frames=build_frames, progress=False)
    assert result.sizes["recording"] == N_RECORDINGS
    assert_summaries_equal(result, expected)


def test_in_memory_recordings_and_stream_selection(recordings, expected):
    study = open_study(recordings, streams=["head", "left_eye"])
    assert set(study.open("subject00").streams) == {"head", "left_eye"}
    result = study.map(summary, frames=build_frames, progress=False)
    assert_summaries_equal(result, expected)


def test_windows_equal_the_whole_recording(recordings):
    first = {k: recordings[k] for k in list(recordings)[:2]}
    study = open_study(first)
    whole = study.map(head_and_gaze, frames=build_frames, combine=False, progress=False)
    windowed = study.map(
        lambda rec, fr: head_and_gaze(rec, fr)[["head_speed"]],
        frames=build_frames,
        window=4.0,
        margin=0.5,
        combine=False,
        progress=False,
    )
    for name in first:
        a, b = whole[name].head_speed, windowed[name].head_speed
        np.testing.assert_array_equal(a.time.values, b.time.values)
        # each window counts time from its own first sample: rounding only
        np.testing.assert_allclose(b.values, a.values, rtol=1e-9, atol=1e-12)


def test_to_netcdf_writes_one_file_per_recording(study_folder, expected, tmp_path):
    study = open_study(study_folder)
    paths = study.to_netcdf(
        summary, tmp_path / "out", frames=build_frames, progress=False
    )
    assert [p.name for p in paths] == [f"{n}.nc" for n in sorted(expected)]
    for path in paths:
        with xr.open_dataset(path) as ds:
            want = expected[path.stem]
            np.testing.assert_allclose(
                ds.mean_speed.values, want.mean_speed.values, rtol=1e-12
            )
    assert not [p for p in (tmp_path / "out").iterdir() if p.name.startswith(".")]


def test_bad_input_is_named(study_folder, tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        open_study(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="lacks stream"):
        open_study(study_folder, streams=["head", "nose"])
    with pytest.raises(TypeError, match="analysis must be callable"):
        open_study(study_folder).map("mean", progress=False)
    with pytest.raises(KeyError, match="no recording named"):
        open_study(study_folder).open("subject99")
    with pytest.raises(ValueError, match="window must be a positive"):
        open_study(study_folder).map(summary, frames=build_frames, window=0.0)
    with pytest.raises(ValueError, match="no 'time' dimension"):
        open_study(study_folder).map(
            summary, frames=build_frames, window=5.0, progress=False
        )
    (tmp_path / "mixed" / "rec").mkdir(parents=True)
    (tmp_path / "mixed" / "a.nc").write_bytes(b"")
    with pytest.raises(ValueError, match="mixes recording files"):
        open_study(tmp_path / "mixed")


# ---------------------------------------------------------------------------
# a real dask.distributed cluster
# ---------------------------------------------------------------------------


@pytest.fixture
def cluster():
    distributed = pytest.importorskip("distributed")
    with (
        local_cluster(2, silence_logs=50) as cl,
        distributed.Client(cl, security=cl.security) as client,
    ):
        yield client


@pytest.mark.slow
def test_local_cluster_gives_the_sequential_numbers(cluster, study_folder, expected):
    study = open_study(study_folder)
    result = study.map(summary, frames=build_frames, progress=False)
    assert_summaries_equal(result, expected)
    # both workers took part
    assert len(cluster.run(os.getpid)) == 2


@pytest.mark.slow
def test_a_stock_cluster_started_before_does_not_change_the_settings(monkeypatch):
    """A stock LocalCluster's nanny writes MALLOC_TRIM_THRESHOLD_=65536 into
    this process's environment, and a nanny lets that environment override
    its pre-spawn settings: local_cluster's workers still get the study's
    values, and the environment is left as the stock cluster left it."""
    distributed = pytest.importorskip("distributed")
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
    ):
        pass
    left = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    assert (
        left is not None
        and left
        != WORKER_SETTINGS["distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"]
    )
    with (
        local_cluster(n_workers=1, secure=False) as study_cluster,
        distributed.Client(study_cluster) as client,
    ):
        env = next(iter(client.run(lambda: dict(os.environ)).values()))
    prefix = "distributed.nanny.pre-spawn-environ."
    for key, value in WORKER_SETTINGS.items():
        if key.startswith(prefix):
            assert env.get(key[len(prefix) :]) == value, key
    assert os.environ.get("MALLOC_TRIM_THRESHOLD_") == left


@pytest.mark.slow
def test_the_study_cluster_is_private_and_tuned(cluster):
    distributed = pytest.importorskip("distributed")
    address = cluster.scheduler.address
    assert address.startswith("tls://127.0.0.1:")
    # every worker runs with the study's settings
    prefix = "distributed.nanny.pre-spawn-environ."
    wanted = {
        k[len(prefix) :]: v for k, v in WORKER_SETTINGS.items() if k.startswith(prefix)
    }
    # and its share of the cores for rbm_nb's parallel kernels (2 workers)
    wanted["RBM_NB_NUM_THREADS"] = str(max(1, (os.cpu_count() or 1) // 2))
    for env in cluster.run(lambda: dict(os.environ)).values():
        assert {k: env.get(k) for k in wanted} == wanted
    profiling = cluster.run(
        lambda: __import__("dask").config.get("distributed.worker.profile.enabled")
    )
    assert set(profiling.values()) == {False}
    # a client holding another certificate is refused by the scheduler
    from distributed.security import Security

    with pytest.raises(OSError, match="certificate"):
        distributed.Client(address, security=Security.temporary(), timeout=5)


def _listening() -> set[tuple[int, str, int]]:
    """(pid, address, port) of every socket this process and its children listen on."""
    psutil = pytest.importorskip("psutil")
    me = psutil.Process()
    found = set()
    for process in [me, *me.children(recursive=True)]:
        if in_background(process):  # the session's slow checks (head_start.py)
            continue
        for conn in process.net_connections(kind="inet"):
            if conn.status == psutil.CONN_LISTEN:
                found.add((process.pid, conn.laddr.ip, conn.laddr.port))
    return found


# what distributed serves over plain HTTP when it is allowed to
HTTP_ROUTES = (
    "/json/identity.json",
    "/metrics",
    "/health",
    "/status",
    "/info/main/workers.html",
)


def _answered(port: int) -> list[str]:
    """The routes a plain-HTTP request to 127.0.0.1:port gets an answer (2xx) to."""
    import urllib.error
    import urllib.request

    answered = []
    for route in HTTP_ROUTES:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}{route}", timeout=5):
                answered.append(route)
        except (urllib.error.URLError, ConnectionError, OSError):
            pass  # 404, or a TLS port hanging up on plain HTTP
    return answered


@pytest.mark.slow
@pytest.mark.parametrize("dashboard", [False, True])
def test_nothing_listens_beyond_loopback_and_no_http_unless_asked(dashboard):
    """Scheduler, nannies and workers listen on 127.0.0.1 only; without the
    dashboard no port answers an HTTP request, with it the dashboard does."""
    pytest.importorskip("distributed")
    before = _listening()
    cluster = local_cluster(2, dashboard=dashboard, silence_logs=50)
    try:
        started = _listening() - before
        # scheduler (comm + HTTP), 2 nannies, 2 workers (comm + HTTP)
        assert len(started) >= 7, started
        assert {address for _, address, _ in started} == {"127.0.0.1"}, started
        answers = {port: _answered(port) for _, _, port in started}
        if dashboard:
            link = cluster.dashboard_link
            assert link.startswith("http://127.0.0.1:"), link
            port = int(link.split(":")[2].split("/")[0])
            assert answers[port] == list(HTTP_ROUTES)
        else:
            assert not any(answers.values()), answers
    finally:
        cluster.close()


def test_local_cluster_names_a_bad_argument():
    pytest.importorskip("distributed")
    with pytest.raises(ValueError, match="n_workers must be a positive integer"):
        local_cluster(0)
    with pytest.raises(
        ValueError, match="threads_per_worker must be a positive integer"
    ):
        local_cluster(1, threads_per_worker=1.5)


@pytest.mark.slow
def test_a_killed_worker_is_recovered(cluster, study_folder, expected):
    study = open_study(study_folder)
    outcome = {}

    def run():
        outcome["result"] = study.map(
            lambda rec, fr: (time.sleep(0.5), summary(rec, fr))[1],
            frames=build_frames,
            progress=False,
        )

    runner = threading.Thread(target=run)
    runner.start()
    deadline = time.monotonic() + 60
    while not any(cluster.processing().values()):
        assert time.monotonic() < deadline, "no task started within 60 s"
        time.sleep(0.05)
    victim = next(
        pid
        for address, pid in cluster.run(os.getpid).items()
        if cluster.processing()[address]
    )
    os.kill(victim, signal.SIGKILL)
    runner.join(timeout=240)
    assert not runner.is_alive(), "the study did not finish after a worker was killed"
    assert victim not in cluster.run(os.getpid).values()
    assert_summaries_equal(outcome["result"], expected)


def per_window_summary(rec, frames):
    """One row per window: its mean head speed and mean gaze elevation."""
    series = head_and_gaze(rec, frames)
    elevation = np.degrees(np.arcsin(series.gaze.sel(cartesian_axis="y")))
    return xr.Dataset(
        {
            "mean_speed": series.head_speed.mean(),
            "mean_elevation": elevation.mean(),
        }
    ).expand_dims(time=[rec["head"].time.values[0]])


def _write_recording(folder, duration, seed):
    rec = synthetic_head_eye(duration=duration, seed=seed)._asdict()
    (folder / "rec").mkdir(parents=True)
    for stream, ds in rec.items():
        ds.to_netcdf(folder / "rec" / f"{stream}.nc")
    return sum(ds.nbytes for ds in rec.values()) / 1e6


@pytest.fixture
def one_worker():
    distributed = pytest.importorskip("distributed")
    with (
        # the statistical profiler caches source lines as it meets them
        dask.config.set({"distributed.worker.profile.enabled": False}),
        distributed.LocalCluster(
            n_workers=1,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
            silence_logs=50,
        ) as cl,
        distributed.Client(cl) as client,
    ):
        yield client


def _traced(client, folder):
    """Start tracemalloc in the worker after a warm-up on a short recording's files.

    Imports, compiled kernels, the first opening of netCDF files and the
    source lines distributed's profiler caches are not what is measured.
    tracemalloc counts what Python and NumPy allocate (data read, frames,
    intermediates, results), which, unlike the process RSS, does not depend
    on what the allocator keeps from earlier.
    """
    import tracemalloc

    _write_recording(folder, 30.0, seed=1)
    warm = open_study(folder)
    for options in ({}, {"window": 10.0}):
        warm.map(
            per_window_summary if options else head_and_gaze,
            frames=build_frames,
            combine=False,
            progress=False,
            **options,
        )
    client.run(tracemalloc.start)


def _peak_mb(client, study, analysis, **options) -> float:
    """Peak memory (MB) a worker allocated above what it held before the run."""
    import tracemalloc

    client.run(tracemalloc.reset_peak)
    before = client.run(lambda: tracemalloc.get_traced_memory()[0])
    study.map(analysis, frames=build_frames, combine=False, progress=False, **options)
    peaks = client.run(lambda: tracemalloc.get_traced_memory()[1])
    return max(peaks[w] - before[w] for w in peaks) / 1e6


@pytest.mark.slow
def test_windowed_memory_follows_the_window_not_the_recording(one_worker, tmp_path):
    """A 10-minute recording: with 20 s windows a worker holds a window, not the recording."""
    data_mb = _write_recording(tmp_path / "long", 600.0, seed=11)
    study = open_study(tmp_path / "long")
    _traced(one_worker, tmp_path / "warm")
    peaks = {
        label: _peak_mb(
            one_worker,
            study,
            lambda rec, fr: head_and_gaze(rec, fr)[["head_speed"]],
            **options,
        )
        for label, options in (("whole", {}), ("windowed", {"window": 20.0}))
    }
    print(f"data {data_mb:.0f} MB, peak allocated per worker (MB) {peaks}")
    # the whole recording is in memory at once; a 20 s window is 1/30 of it.
    # Measured: whole 138 MB, windowed 7-9 MB (frames, the lookups' tables
    # and the joined head-speed series, 2 MB, of which a window holds 1/30)
    assert peaks["whole"] > data_mb
    assert peaks["windowed"] < peaks["whole"] / 4


@pytest.mark.slow
def test_windowed_memory_is_flat_in_recording_length(one_worker, tmp_path):
    """60 s windows of a 10- and a 40-minute recording: the same peak per worker.

    Each window reads only its rows (the time coordinate included), and the
    frame tree a window's task builds is freed after it, so nothing a worker
    holds grows with the number of windows it has run. The analysis gives
    one row per window, so the joined result is small too.
    """
    peaks, data = {}, {}
    _traced(one_worker, tmp_path / "warm")
    for minutes in (10, 40):
        folder = tmp_path / f"{minutes}min"
        data[minutes] = _write_recording(folder, minutes * 60.0, seed=minutes)
        peaks[minutes] = _peak_mb(
            one_worker, open_study(folder), per_window_summary, window=60.0
        )
    print(f"data (MB) {data}, peak allocated per worker (MB) {peaks}")
    # Measured: 14.6 and 14.7 MB for 43 and 173 MB of data (before windows
    # read only their rows and their cycles were collected: 57 and 101 MB).
    # A share of even 5 % of the extra 130 MB the longer recording has would
    # break this bound; 4 MB allow for the worker's own bookkeeping.
    assert peaks[40] <= 1.3 * peaks[10] + 4.0
    # and a window's peak is far below the recording's data (whole: 138 MB)
    assert peaks[10] < data[10] / 2
