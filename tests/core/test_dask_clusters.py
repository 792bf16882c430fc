"""Lazy results on clusters of worker processes equal the eager ones.

Two clusters: a ``LocalCluster`` of processes, and a scheduler and two
workers started as separate programs (``dask scheduler``, ``dask worker``),
each in its own working directory, as on a real cluster. Their registries
are empty: frames named in the notebook must reach the tasks as values.
Everything listens on 127.0.0.1, and everything started here is stopped in
a ``finally``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")
import dask.array as dsa  # noqa: E402
from recordings import REAL_DIR, REPO, real_recording  # noqa: E402

import rbm_nb as rbm  # noqa: E402
from rbm_nb.core import gaze  # noqa: E402

pytestmark = pytest.mark.slow

CHUNK = 700
# seconds the separate programs may take to start
START_TIMEOUT = 90.0


@pytest.fixture(scope="module")
def recording():
    """The first 60 s of the real recording (irregular eye clock, NaN rows, gaps)."""
    real = real_recording()
    if real is None:
        pytest.fail(f"{REAL_DIR} is missing: CI has ../shared beside the clone")
    head, left_eye, _ = real
    start = head.time.values[0]
    first = slice(start, start + np.timedelta64(60, "s"))
    return SimpleNamespace(
        head=head.sel(time=first), left_eye=left_eye.sel(time=first).dropna("time")
    )


def _tree(recording, register: bool) -> dict:
    world = rbm.ReferenceFrame("world")
    head = rbm.ReferenceFrame.from_dataset(
        recording.head, "position", "orientation", "time", parent=world, name="head"
    )
    eye = rbm.ReferenceFrame.from_dataset(
        recording.left_eye, "position", "orientation", "time", parent=head, name="eye"
    )
    frames = {"world": world, "head": head, "eye": eye}
    if register:
        for frame in frames.values():
            frame.register(update=True)
        return {name: name for name in frames}
    return frames


def _operations(recording, f) -> dict:
    """name -> (eager input, lazy input, function); ``f`` maps frame names to
    what the calls get (the names themselves, or ReferenceFrame objects)."""
    pos = recording.left_eye.position
    q = recording.left_eye.orientation
    ts = pos.time.values
    head_times = recording.head.time.values[50:2000]
    chunked = {"pos": pos.chunk(time=CHUNK), "q": q.chunk(time=CHUNK)}
    plain = dsa.from_array(pos.values, chunks=(CHUNK, 3))
    plain_q = dsa.from_array(q.values, chunks=(CHUNK, 4))
    sight = gaze.directions(f["eye"], f["head"])
    return {
        "transform_points": (
            pos, chunked["pos"],
            lambda a: rbm.transform_points(
                a, outof=f["head"], into=f["world"], dim="cartesian_axis"
            ),
        ),
        "transform_points_plain": (
            pos.values, plain,
            lambda a: rbm.transform_points(
                a, outof=f["head"], into=f["world"], timestamps=ts
            ),
        ),
        "transform_vectors": (
            pos, chunked["pos"],
            lambda a: rbm.transform_vectors(
                a, outof=f["eye"], into=f["world"], dim="cartesian_axis"
            ),
        ),
        "transform_quaternions": (
            q, chunked["q"],
            lambda a: rbm.transform_quaternions(
                a, outof=f["head"], into=f["world"], dim="quaternion_axis"
            ),
        ),
        "gaze_directions_into_world": (
            sight, sight.chunk(time=CHUNK),
            lambda a: rbm.transform_vectors(a, outof=f["head"], into=f["world"]),
        ),
        "angular_velocity_reference_frame": (
            pos, chunked["pos"],
            lambda a: rbm.transform_angular_velocity(
                a, outof=f["head"], into=f["world"], what="reference_frame",
                dim="cartesian_axis",
            ),
        ),
        "angular_velocity_moving_frame": (
            pos, chunked["pos"],
            lambda a: rbm.transform_angular_velocity(
                a, outof=f["head"], into=f["eye"], what="moving_frame",
                dim="cartesian_axis",
            ),
        ),
        "linear_velocity_reference_frame": (
            pos, chunked["pos"],
            lambda a: rbm.transform_linear_velocity(
                a, outof=f["head"], into=f["world"], what="reference_frame",
                moving_frame=f["eye"], dim="cartesian_axis", cutoff=0.2,
            ),
        ),
        "linear_velocity_moving_frame": (
            pos, chunked["pos"],
            lambda a: rbm.transform_linear_velocity(
                a, outof=f["head"], into=f["eye"], what="moving_frame",
                reference_frame=f["world"], dim="cartesian_axis",
            ),
        ),
        "linear_velocity_representation_frame": (
            pos, chunked["pos"],
            lambda a: rbm.transform_linear_velocity(
                a, outof=f["head"], into=f["world"], what="representation_frame",
                dim="cartesian_axis",
            ),
        ),
        "estimate_angular_velocity": (
            q, chunked["q"],
            lambda a: rbm.estimate_angular_velocity(a, dim="quaternion_axis"),
        ),
        "estimate_linear_velocity_cutoff": (
            pos, chunked["pos"],
            lambda a: rbm.estimate_linear_velocity(
                a, dim="cartesian_axis", cutoff=0.1
            ),
        ),
        "accessor_qinterp": (q, chunked["q"], lambda a: a.rbm.qinterp(time=head_times)),
        "accessor_qinv": (q, chunked["q"], lambda a: a.rbm.qinv()),
        "qinterp_plain": (
            q.values, plain_q, lambda a: rbm.qinterp(a, ts, ts[10:-10:3])
        ),
    }  # fmt: skip


# ---------------------------------------------------------------------------
# the clusters
# ---------------------------------------------------------------------------


def _dask_command() -> list[str]:
    script = Path(sys.executable).with_name("dask")
    return [str(script)] if script.exists() else [sys.executable, "-m", "dask"]


def _wait_for(path: Path, process: subprocess.Popen, what: str) -> None:
    deadline = time.monotonic() + START_TIMEOUT
    while not path.exists():
        if process.poll() is not None:
            raise RuntimeError(f"{what} exited with {process.returncode}")
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what} did not start within {START_TIMEOUT} s")
        time.sleep(0.2)


def _stop(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=20)


@contextmanager
def separate_programs(folder: Path):
    """``dask scheduler`` and two ``dask worker`` programs, each in its own folder.

    Loopback only, no dashboard (the HTTP servers bind to a free port of
    127.0.0.1); the workers give up on their own if the scheduler goes away
    (``--death-timeout``), so nothing outlives the test even if it is killed.
    The workers import rbm_nb from this checkout, as a cluster's workers
    import the installed package.
    """
    env = dict(os.environ, PYTHONPATH=str(REPO), RBM_NB_NUM_THREADS="1")
    http = ["--no-dashboard", "--dashboard-address", "127.0.0.1:0"]
    started: list[subprocess.Popen] = []
    logs = []
    try:
        home = folder / "scheduler"
        home.mkdir()
        scheduler_file = home / "scheduler.json"
        log = open(home / "log.txt", "w")  # noqa: SIM115 - closed in finally
        logs.append(log)
        started.append(
            subprocess.Popen(
                [*_dask_command(), "scheduler", "--host", "127.0.0.1", "--port", "0",
                 "--scheduler-file", str(scheduler_file), *http],
                cwd=home, env=env, stdout=log, stderr=subprocess.STDOUT,
            )
        )  # fmt: skip
        _wait_for(scheduler_file, started[0], "dask scheduler")
        address = json.loads(scheduler_file.read_text())["address"]
        for k in range(2):
            home = folder / f"worker{k}"
            home.mkdir()
            log = open(home / "log.txt", "w")  # noqa: SIM115 - closed in finally
            logs.append(log)
            started.append(
                subprocess.Popen(
                    [*_dask_command(), "worker", address, "--host", "127.0.0.1",
                     "--nthreads", "1", "--memory-limit", "2GiB", "--death-timeout",
                     "30", "--local-directory", str(home), *http],
                    cwd=home, env=env, stdout=log, stderr=subprocess.STDOUT,
                )
            )  # fmt: skip
        with distributed.Client(address, timeout=START_TIMEOUT) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT)
            yield client
    finally:
        for process in reversed(started):
            _stop(process)
        for log in logs:
            log.close()


@contextmanager
def local_processes():
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
            dashboard_address=None, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            silence_logs=50,
        ) as cluster,
        distributed.Client(cluster) as client,
    ):  # fmt: skip
        yield client


@pytest.fixture(scope="module", params=["local_processes", "separate_programs"])
def client(request, tmp_path_factory):
    if request.param == "local_processes":
        context = local_processes()
    else:
        context = separate_programs(tmp_path_factory.mktemp("cluster"))
    with context as client:
        yield client


# ---------------------------------------------------------------------------
# the tests
# ---------------------------------------------------------------------------


NAMES = [
    "transform_points", "transform_points_plain", "transform_vectors",
    "transform_quaternions", "gaze_directions_into_world",
    "angular_velocity_reference_frame", "angular_velocity_moving_frame",
    "linear_velocity_reference_frame", "linear_velocity_moving_frame",
    "linear_velocity_representation_frame", "estimate_angular_velocity",
    "estimate_linear_velocity_cutoff", "accessor_qinterp", "accessor_qinv",
    "qinterp_plain",
]  # fmt: skip


@pytest.mark.timeout(600)
@pytest.mark.parametrize("frames_as", ["names", "objects"])
def test_every_lazy_operation_equals_eager(client, recording, frames_as):
    """On worker processes whose registry is empty, for frames by name and as objects."""
    f = _tree(recording, register=frames_as == "names")
    operations = _operations(recording, f)
    assert sorted(operations) == sorted(NAMES)
    workers = set(client.run(os.getpid).values())
    assert len(workers) == 2 and os.getpid() not in workers
    for name in NAMES:
        eager_in, lazy_in, func = operations[name]
        eager = func(eager_in)
        lazy = func(lazy_in)
        (result,) = dask.compute(lazy, scheduler=client)
        got = getattr(result, "values", result)
        want = getattr(eager, "values", eager)
        assert got.shape == want.shape, name
        np.testing.assert_allclose(
            got, want, rtol=1e-12, atol=1e-12, err_msg=name, equal_nan=True
        )
        if hasattr(eager, "dims"):
            np.testing.assert_array_equal(result.time.values, eager.time.values)
            assert result.attrs == eager.attrs, name
