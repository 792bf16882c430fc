"""Dask workers compute with the frames' values; they build no ReferenceFrame.

A frame is checked and prepared once, when the user builds it
(``ReferenceFrame.__init__``: shapes, finite rows, unit quaternions, sign
continuity, increasing timestamps). A lazy result's tasks carry the frames'
immutable values (``ReferenceFrame.data``, cut to each chunk's window) and
the worker hands those to the engine as they are (issue 32, item 3).

The proof runs on real worker processes (a ``LocalCluster`` with
``processes=True``): a worker plugin wraps the worker's
``ReferenceFrame.__init__`` and the frame module's sample checks with
counters, and the counts are read back from the worker after computing.
"""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")
xr = pytest.importorskip("xarray")
import cloudpickle  # noqa: E402

import rbm_nb as rbm  # noqa: E402

pytestmark = pytest.mark.slow

# the plugin and the counter reader travel to the worker by value (the
# worker cannot import this test module by name)
cloudpickle.register_pickle_by_value(sys.modules[__name__])

N = 3000
CHUNK = 700


class CountFrameChecks(distributed.WorkerPlugin):
    """Counts, in the worker process, frames built and frame samples checked."""

    name = "count-frame-checks"

    def setup(self, worker):
        from rbm_nb.core import frames

        counts = {"__init__": 0, "_samples": 0}
        init, samples = frames.ReferenceFrame.__init__, frames._samples

        def counted_init(self, *args, **kwargs):
            counts["__init__"] += 1
            init(self, *args, **kwargs)

        def counted_samples(*args, **kwargs):
            counts["_samples"] += 1
            return samples(*args, **kwargs)

        frames.ReferenceFrame.__init__ = counted_init
        frames._samples = counted_samples
        frames._worker_counts = counts  # read by _counts


def _counts():
    from rbm_nb.core import frames

    return dict(frames._worker_counts)


def _rotations(rng, n):
    """A smooth random rotation, stored to ~5 digits (|q| - 1 up to ~1e-5)."""
    angles = np.cumsum(rng.normal(0.0, 0.02, (n, 3)), axis=0)
    half = np.linalg.norm(angles, axis=1, keepdims=True) / 2
    axis = angles / np.maximum(2 * half, 1e-12)
    q = np.hstack([np.cos(half), np.sin(half) * axis])
    q[rng.random(n) < 0.5] *= -1  # sign flips, as recorders write them
    return np.round(q, 5)


@pytest.fixture(scope="module")
def tree():
    rng = np.random.default_rng(32)
    start = np.datetime64("2024-01-01T00:00:00", "ns")
    head_t = start + np.cumsum(rng.integers(8, 12, N)).astype("timedelta64[ms]")
    eye_t = start + np.cumsum(rng.integers(3, 6, N)).astype("timedelta64[ms]")
    world = rbm.ReferenceFrame("world")
    head = rbm.ReferenceFrame(
        "head", parent=world, translation=rng.normal(size=(N, 3)),
        rotation=_rotations(rng, N), timestamps=head_t,
    )  # fmt: skip
    eye = rbm.ReferenceFrame(
        "eye", parent=head, translation=rng.normal(size=(N, 3)) * 0.01,
        rotation=_rotations(rng, N), timestamps=eye_t,
    )  # fmt: skip
    points = xr.DataArray(
        rng.normal(size=(N, 3)), dims=("time", "cartesian_axis"),
        coords={"time": eye_t[:N]},
    )  # fmt: skip
    return world, head, eye, points


@pytest.mark.timeout(300)
def test_workers_compute_with_values_not_constructors(tree):
    world, head, eye, points = tree
    calls = {
        "transform_points": lambda a: rbm.transform_points(
            a, outof=eye, into=world, dim="cartesian_axis"
        ),
        "transform_angular_velocity": lambda a: rbm.transform_angular_velocity(
            a, outof=eye, into=world, what="reference_frame", dim="cartesian_axis"
        ),
    }
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
            dashboard_address=None, silence_logs=50,
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
        ) as cluster,
        distributed.Client(cluster) as client,
    ):  # fmt: skip
        client.register_plugin(CountFrameChecks())
        (worker_pid,) = client.run(os.getpid).values()
        assert worker_pid != os.getpid()
        for name, call in calls.items():
            eager = call(points)
            (lazy,) = dask.compute(call(points.chunk(time=CHUNK)), scheduler=client)
            # the window's rows are the frames' prepared rows: the same bits
            np.testing.assert_array_equal(lazy.values, eager.values, err_msg=name)
        (counts,) = client.run(_counts).values()
    assert counts == {"__init__": 0, "_samples": 0}
