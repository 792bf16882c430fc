"""dask-backed inputs stay lazy through the array functions and equal the eager results."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

dask = pytest.importorskip("dask")
import dask.array as dsa  # noqa: E402
from dask.callbacks import Callback  # noqa: E402
from recordings import REAL_DIR, real_recording  # noqa: E402

import rbm_nb as rbm  # noqa: E402
from rbm_nb.data import synthetic_head_eye  # noqa: E402

CHUNK = 700


class ComputeCounter(Callback):
    """Counts the graphs dask executes (each compute/persist/.values is one)."""

    def __init__(self):
        super().__init__()
        self.count = 0

    def _start(self, dsk):
        self.count += 1


def assert_lazy_until_computed(func, data, name, rtol=1e-11):
    """func on ``data`` chunked along time builds a graph and computes nothing;
    computing it once gives the eager result's metadata, chunks and values."""
    eager = func(data)
    lazy_in = data.chunk(time=CHUNK)
    counter = ComputeCounter()
    with counter:
        lazy = func(lazy_in)
    assert counter.count == 0, (
        f"{name} computed {counter.count} graph(s) before being asked"
    )
    assert isinstance(lazy.data, dsa.Array), f"{name} returned {type(lazy.data)}"
    assert lazy.dims == eager.dims
    assert list(lazy.coords) == list(eager.coords)
    assert lazy.attrs == eager.attrs
    assert not np.isnan(sum(lazy.chunks[0]))
    if lazy.sizes["time"] == lazy_in.sizes["time"]:
        assert (
            lazy.chunks[lazy.dims.index("time")]
            == lazy_in.chunks[lazy_in.dims.index("time")]
        )
    with counter:
        result = lazy.compute()
    assert counter.count == 1
    np.testing.assert_array_equal(result["time"].values, eager["time"].values)
    np.testing.assert_allclose(result.values, eager.values, rtol=rtol, atol=1e-12)


@pytest.fixture(scope="module", params=["synthetic", "real"])
def recording(request):
    """20 s of the synthetic recording, or the first 60 s of the real one
    (its irregular eye clock, NaN rows and gaps included)."""
    if request.param == "synthetic":
        return synthetic_head_eye(duration=20.0, seed=3)
    real = real_recording()
    if real is None:
        pytest.fail(f"{REAL_DIR} is missing: CI has ../shared beside the clone")
    head, left_eye, right_eye = real
    start = head.time.values[0]
    first = slice(start, start + np.timedelta64(60, "s"))
    return SimpleNamespace(
        head=head.sel(time=first),
        left_eye=left_eye.sel(time=first),
        right_eye=right_eye.sel(time=first),
    )


@pytest.fixture
def tree(recording):
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_dataset(
        recording.head, "position", "orientation", "time", parent="world", name="head"
    ).register()


def _eye(recording, var):
    return recording.left_eye[var].dropna("time")


def _cases(recording):
    pos = _eye(recording, "position")
    q = _eye(recording, "orientation")
    head_times = recording.head.time.values[50:2000]
    return {
        "transform_points": (
            pos,
            lambda a: rbm.transform_points(
                a, outof="head", into="world", dim="cartesian_axis", timestamps="time"
            ),
        ),
        "transform_vectors": (
            pos,
            lambda a: rbm.transform_vectors(
                a, outof="head", into="world", dim="cartesian_axis"
            ),
        ),
        "transform_quaternions": (
            q,
            lambda a: rbm.transform_quaternions(
                a, outof="head", into="world", dim="quaternion_axis"
            ),
        ),
        "estimate_linear_velocity": (
            pos,
            lambda a: rbm.estimate_linear_velocity(a, dim="cartesian_axis"),
        ),
        "estimate_linear_velocity_cutoff": (
            pos,
            lambda a: rbm.estimate_linear_velocity(a, dim="cartesian_axis", cutoff=0.1),
        ),
        "estimate_angular_velocity": (
            q,
            lambda a: rbm.estimate_angular_velocity(a, dim="quaternion_axis"),
        ),
        "estimate_angular_velocity_rotvec": (
            q,
            lambda a: rbm.estimate_angular_velocity(
                a, dim="quaternion_axis", mode="rotation_vector"
            ),
        ),
        "qinterp_accessor": (q, lambda a: a.rbm.qinterp(time=head_times)),
        "qinv": (q, lambda a: rbm.qinv(a, qaxis=1)),
        "qmul": (q, lambda a: rbm.qmul(a, rbm.qinv(a, qaxis=1), qaxis=1)),
        "rotate_vectors_single_q": (
            pos,
            lambda a: rbm.rotate_vectors(np.array([0.5, 0.5, 0.5, 0.5]), a),
        ),
        "transform_coordinates": (
            pos,
            lambda a: rbm.transform_coordinates(
                a, "spherical", outof="cartesian", dim="cartesian_axis"
            ),
        ),
    }


CASES = list(_cases(synthetic_head_eye(duration=16.0, seed=0)))


@pytest.mark.parametrize("name", CASES)
def test_dataarray_results_are_lazy_and_equal(name, recording, tree):
    data, func = _cases(recording)[name]
    assert_lazy_until_computed(func, data, name)


def test_plain_dask_arrays(recording, tree):
    pos = _eye(recording, "position")
    ts = pos.time.values
    eager, eager_ts = rbm.transform_points(
        pos.values, outof="head", into="world", timestamps=ts, return_timestamps=True
    )
    lazy, lazy_ts = rbm.transform_points(
        dsa.from_array(pos.values, chunks=(CHUNK, 3)),
        outof="head",
        into="world",
        timestamps=ts,
        return_timestamps=True,
    )
    assert isinstance(lazy, dsa.Array)
    np.testing.assert_array_equal(lazy_ts, eager_ts)
    np.testing.assert_allclose(lazy.compute(), eager, rtol=1e-12, atol=1e-14)

    q_da = _eye(recording, "orientation")
    q, ts = q_da.values, q_da.time.values
    lq = dsa.from_array(q, chunks=(CHUNK, 4))
    np.testing.assert_array_equal(rbm.qinv(lq).compute(), rbm.qinv(q))
    np.testing.assert_allclose(
        rbm.estimate_angular_velocity(lq, timestamps=ts).compute(),
        rbm.estimate_angular_velocity(q, timestamps=ts),
        rtol=1e-11,
        atol=1e-12,
    )
    np.testing.assert_array_equal(
        rbm.cartesian_to_spherical(
            dsa.from_array(pos.values, chunks=(CHUNK, 3))
        ).compute(),
        rbm.cartesian_to_spherical(pos.values),
    )
    t_out = ts[10:-10:3]
    np.testing.assert_allclose(
        rbm.qinterp(lq, ts, t_out).compute(),
        rbm.qinterp(q, ts, t_out),
        rtol=1e-12,
        atol=1e-14,
    )


def test_transform_crops_to_the_frames_range(recording, tree):
    """Samples outside a frame's time range are dropped, as eagerly; chunk sizes stay known."""
    part = recording.head.isel(time=slice(500, 2500))
    rbm.ReferenceFrame.from_dataset(
        part, "position", "orientation", "time", parent="world", name="head_part"
    ).register()
    pos = _eye(recording, "position")
    eager = rbm.transform_points(
        pos, outof="head_part", into="world", dim="cartesian_axis"
    )
    lazy = rbm.transform_points(
        pos.chunk(time=CHUNK), outof="head_part", into="world", dim="cartesian_axis"
    )
    assert 0 < eager.sizes["time"] < pos.sizes["time"]
    assert lazy.sizes["time"] == eager.sizes["time"]
    assert not np.isnan(sum(lazy.chunks[0]))
    np.testing.assert_allclose(lazy.values, eager.values, rtol=1e-12, atol=1e-14)


def test_sign_flips_across_chunks(recording, tree):
    """Chunks that start on a negated quaternion give the eager result all the same."""
    q = _eye(recording, "orientation")
    # relative to the first sample: angles well below pi, where rotation
    # vectors are well conditioned
    relative = rbm.qmul(rbm.qinv(q.values[0]), q.values)
    signs = np.where(np.arange(q.sizes["time"]) % 3 == 0, -1.0, 1.0)[:, None]
    flipped = q.copy(data=relative * signs)
    lazy = rbm.estimate_angular_velocity(
        flipped.chunk(time=CHUNK), dim="quaternion_axis", mode="rotation_vector"
    )
    eager = rbm.estimate_angular_velocity(
        flipped, dim="quaternion_axis", mode="rotation_vector"
    )
    # a chunk's times count from its own first sample: differences of a few
    # ulps of the times, magnified by 1/dt, are all that may differ
    np.testing.assert_allclose(lazy.values, eager.values, rtol=1e-11, atol=1e-11)


def _scores(arr, quaternions):
    """The eager estimators' outlier score of each sample (kernel of the engine)."""
    from rbm_nb._kernels import differences as dk
    from rbm_nb._kernels import quaternion as qk
    from rbm_nb._kernels import rotations as rk

    x = np.ascontiguousarray(arr.values, dtype=np.float64)
    if quaternions:
        x = rk.rotation_vectors(qk.unflip(x))
    return dk.second_difference_score(np.ascontiguousarray(x[:, None, :]))[:, 0]


ESTIMATORS = {
    "linear": (
        "position",
        lambda a, **kw: rbm.estimate_linear_velocity(a, dim="cartesian_axis", **kw),
    ),
    "angular": (
        "orientation",
        lambda a, **kw: rbm.estimate_angular_velocity(a, dim="quaternion_axis", **kw),
    ),
    "angular_rotvec": (
        "orientation",
        lambda a, **kw: rbm.estimate_angular_velocity(
            a, dim="quaternion_axis", mode="rotation_vector", **kw
        ),
    ),
}


@pytest.mark.parametrize("kind", ESTIMATORS)
def test_outlier_rejection_is_lazy_and_equal(kind, recording):
    """A fifth of the samples rejected; the series trimmed to start and end on kept ones."""
    var, estimate = ESTIMATORS[kind]
    arr = _eye(recording, var)
    score = _scores(arr, var == "orientation")
    thresh = float(np.quantile(score[np.isfinite(score)], 0.8))
    kept = np.flatnonzero(score <= thresh)
    arr = arr.isel(time=slice(kept[0], kept[-1] + 1))
    assert (score[kept[0] : kept[-1] + 1] > thresh).sum() > 100
    eager = estimate(arr, outlier_thresh=thresh)
    counter = ComputeCounter()
    with counter:
        lazy = estimate(arr.chunk(time=CHUNK), outlier_thresh=thresh)
    assert counter.count == 0
    assert isinstance(lazy.data, dsa.Array)
    assert lazy.chunks[0] == arr.chunk(time=CHUNK).chunks[0]
    np.testing.assert_allclose(lazy.values, eager.values, rtol=1e-12, atol=1e-12)
    # rejection and then the low-pass, both lazily
    eager = estimate(arr, outlier_thresh=thresh, cutoff=0.2)
    lazy = estimate(arr.chunk(time=CHUNK), outlier_thresh=thresh, cutoff=0.2)
    np.testing.assert_allclose(lazy.values, eager.values, rtol=1e-11, atol=1e-12)


def _spiky_line(n=3000, run=(600, 1650)):
    """Positions on a line at uneven times, with noise over one long run of samples."""
    import xarray as xr

    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(0.002, 0.004, n))
    pos = 0.01 * np.c_[np.sin(t), np.cos(t), t]
    pos[run[0] : run[1]] += rng.normal(0.0, 0.05, (run[1] - run[0], 3))
    return xr.DataArray(
        pos,
        {"time": t, "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
    )


def test_outliers_across_chunk_boundaries():
    """A run of 1000+ rejected samples spans two chunk boundaries (700, 1400):
    each is interpolated from kept samples in other chunks."""
    pos = _spiky_line()
    eager = rbm.estimate_linear_velocity(pos, dim="cartesian_axis", outlier_thresh=1e-3)
    score = _scores(pos, False)
    rejected = np.flatnonzero(score > 1e-3)
    assert rejected.min() < CHUNK and rejected.max() > 2 * CHUNK
    assert (np.diff(rejected) == 1).all()  # one run
    lazy = rbm.estimate_linear_velocity(
        pos.chunk(time=CHUNK), dim="cartesian_axis", outlier_thresh=1e-3
    )
    np.testing.assert_allclose(lazy.values, eager.values, rtol=1e-12, atol=1e-12)
    # the run is a straight line in time between its two kept neighbours
    before, after = rejected.min() - 1, rejected.max() + 1
    t = pos.time.values
    w = (t[rejected] - t[before]) / (t[after] - t[before])
    line = eager.values[before] + w[:, None] * (
        eager.values[after] - eager.values[before]
    )
    np.testing.assert_allclose(lazy.values[rejected], line, rtol=1e-12, atol=1e-12)
    # plain dask arrays too
    plain = rbm.estimate_linear_velocity(
        dsa.from_array(pos.values, chunks=(CHUNK, 3)),
        timestamps=pos.time.values,
        outlier_thresh=1e-3,
    )
    np.testing.assert_allclose(plain.compute(), eager.values, rtol=1e-12, atol=1e-12)


def test_outlier_errors_are_the_eager_ones():
    """Rejected first samples (nothing to interpolate from) fail on compute,
    with the eager message; a bad threshold fails at once."""
    pos = _spiky_line(run=(0, 900))
    with pytest.raises(ValueError) as eager:
        rbm.estimate_linear_velocity(pos, dim="cartesian_axis", outlier_thresh=1e-3)
    lazy = rbm.estimate_linear_velocity(
        pos.chunk(time=CHUNK), dim="cartesian_axis", outlier_thresh=1e-3
    )
    with pytest.raises(ValueError) as on_compute:
        lazy.compute()
    assert str(on_compute.value) == str(eager.value)
    assert "rejects the first" in str(eager.value)
    with pytest.raises(ValueError, match="keeps only"):
        rbm.estimate_linear_velocity(
            pos.chunk(time=CHUNK), dim="cartesian_axis", outlier_thresh=0.0
        ).compute()
    with pytest.raises(ValueError, match="outlier_thresh must be a non-negative"):
        rbm.estimate_linear_velocity(
            pos.chunk(time=CHUNK), dim="cartesian_axis", outlier_thresh=-1.0
        )


VELOCITY_CASES = {
    "angular_reference_frame": lambda a: rbm.transform_angular_velocity(
        a, outof="head", into="world", what="reference_frame", dim="cartesian_axis"
    ),
    "angular_moving_frame": lambda a: rbm.transform_angular_velocity(
        a, outof="head", into="eye", what="moving_frame", dim="cartesian_axis"
    ),
    "angular_representation_frame": lambda a: rbm.transform_angular_velocity(
        a, outof="head", into="world", what="representation_frame",
        dim="cartesian_axis",
    ),
    "linear_reference_frame": lambda a: rbm.transform_linear_velocity(
        a, outof="head", into="world", what="reference_frame", moving_frame="eye",
        dim="cartesian_axis",
    ),
    "linear_moving_frame": lambda a: rbm.transform_linear_velocity(
        a, outof="head", into="eye", what="moving_frame", reference_frame="world",
        dim="cartesian_axis",
    ),
    "linear_reference_frame_filtered": lambda a: rbm.transform_linear_velocity(
        a, outof="head", into="world", what="reference_frame", moving_frame="eye",
        dim="cartesian_axis", cutoff=0.2,
    ),
}  # fmt: skip


@pytest.mark.parametrize("name", VELOCITY_CASES)
def test_velocity_transforms_are_lazy_and_equal(name, recording, tree):
    """The frames' velocities are estimated once; chunks only match them to their times."""
    rbm.ReferenceFrame.from_dataset(
        recording.left_eye.dropna("time"), "position", "orientation", "time",
        parent="head", name="eye",
    ).register()  # fmt: skip
    func = VELOCITY_CASES[name]
    # the eye's samples, cut at both ends: the frames' ranges crop the result
    v = _eye(recording, "position").isel(time=slice(100, -100))
    assert_lazy_until_computed(func, v, name, rtol=1e-12)


def test_velocity_transform_of_a_plain_dask_array(recording, tree):
    v = _eye(recording, "position")
    ts = v.time.values
    eager, eager_ts = rbm.transform_angular_velocity(
        v.values, outof="head", into="world", timestamps=ts, return_timestamps=True
    )
    lazy, lazy_ts = rbm.transform_angular_velocity(
        dsa.from_array(v.values, chunks=(CHUNK, 3)),
        outof="head",
        into="world",
        timestamps=ts,
        return_timestamps=True,
    )
    assert isinstance(lazy, dsa.Array)
    np.testing.assert_array_equal(lazy_ts, eager_ts)
    np.testing.assert_allclose(lazy.compute(), eager, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="moving_frame must be given"):
        rbm.transform_linear_velocity(
            dsa.from_array(v.values, chunks=(CHUNK, 3)),
            outof="head",
            into="world",
            timestamps=ts,
        )


# ---------------------------------------------------------------------------
# what the graph carries: values of the frames, cut to each chunk's window
# ---------------------------------------------------------------------------


def _moving_tree(n: int, rate: float = 100.0):
    """world <- head (n samples at ``rate`` Hz, float seconds) <- eye (static)."""
    t = np.arange(n) / rate
    world = rbm.ReferenceFrame("world")
    head = rbm.ReferenceFrame(
        "head",
        world,
        translation=np.c_[np.sin(t), np.cos(t), 0.01 * t],
        rotation=rbm.from_euler_angles(yaw=0.3 * np.sin(t)),
        timestamps=t,
    )
    eye = rbm.ReferenceFrame("eye", head, translation=(0.03, 0.0, 0.1))
    return world, eye


def _one_chunk_graph_bytes(lazy) -> int:
    """Pickled size of what computing the first output chunk needs."""
    import cloudpickle
    from dask.core import flatten
    from dask.optimization import cull

    data = lazy.data
    first = next(flatten(data.__dask_keys__()))
    graph, _ = cull(dict(data.__dask_graph__()), [first])
    return len(cloudpickle.dumps(graph))


@pytest.mark.parametrize("kind", ["transform_points", "linear_velocity"])
def test_one_chunks_graph_does_not_grow_with_the_recording(kind):
    """The same 2000 samples transformed with a frame of 10^4 or 10^6 samples:
    the first chunk's share of the graph is the same size (its window of the
    frame), not the frame's 56 bytes per sample."""
    import xarray as xr

    sizes = {}
    for n in (10_000, 1_000_000):
        world, eye = _moving_tree(n)
        times = 10.0 + np.arange(2000) / 150.0  # inside the frame's first 10^4
        pos = xr.DataArray(
            dsa.ones((2000, 3), chunks=(500, 3)),  # a graph of a few bytes per chunk
            {"time": times, "cartesian_axis": list("xyz")},
            ("time", "cartesian_axis"),
        )
        if kind == "transform_points":
            lazy = rbm.transform_points(pos, outof=eye, into=world)
        else:
            lazy = rbm.transform_linear_velocity(
                pos, outof=eye.parent, into=world, moving_frame=eye
            )
        sizes[n] = _one_chunk_graph_bytes(lazy)
    # a few bytes may differ (indices); 10^6 samples of the frame are 56 MB
    assert abs(sizes[1_000_000] - sizes[10_000]) < 1_000, sizes
    assert sizes[1_000_000] < 100_000, sizes


def test_a_graph_is_a_snapshot_of_the_registry(recording, tree):
    """A frame registered again after the graph was built does not change it."""
    pos = _eye(recording, "position")
    eager = rbm.transform_points(pos, outof="head", into="world", dim="cartesian_axis")
    lazy = rbm.transform_points(
        pos.chunk(time=CHUNK), outof="head", into="world", dim="cartesian_axis"
    )
    moved = recording.head.assign(position=recording.head.position + 1.0)
    rbm.ReferenceFrame.from_dataset(
        moved, "position", "orientation", "time", parent="world", name="head"
    ).register(update=True)
    np.testing.assert_allclose(lazy.values, eager.values, rtol=1e-12, atol=1e-12)
    # a graph built now sees the new frame
    now = rbm.transform_points(
        pos.chunk(time=CHUNK), outof="head", into="world", dim="cartesian_axis"
    )
    np.testing.assert_allclose(now.values, eager.values + 1.0, rtol=1e-12, atol=1e-12)


def test_frames_in_different_trees_are_named_when_the_graph_is_built(recording, tree):
    other = rbm.ReferenceFrame("elsewhere")
    pos = _eye(recording, "position").chunk(time=CHUNK)
    with pytest.raises(ValueError, match="different trees"):
        rbm.transform_points(pos, outof="head", into=other, dim="cartesian_axis")


def test_long_recordings_count_times_from_the_first_sample():
    """400,000 samples (the real head recording tiled, ~33 min): chunks far from
    the first sample transform at the eager call's times, to the bit. Counted
    from their own first sample, the times round differently: 17 % of the
    values differed (by up to 1e-11 here, 2e-8 at 10^7 samples)."""
    import xarray as xr

    real = real_recording()
    if real is None:
        pytest.fail(f"{REAL_DIR} is missing: CI has ../shared beside the clone")
    head = real[0]
    reps = 6
    step = np.diff(head.time.values)
    gaps = np.concatenate([np.tile(step, reps), step[: reps - 1]])
    times = head.time.values[0] + np.concatenate(
        [[np.timedelta64(0, "ns")], np.cumsum(gaps)]
    )
    world = rbm.ReferenceFrame("world")
    frame = rbm.ReferenceFrame(
        "head", world, translation=np.tile(head.position.values, (reps, 1)),
        rotation=np.tile(head.orientation.values, (reps, 1)), timestamps=times,
    )  # fmt: skip
    k = np.arange(len(times), dtype=np.float64)
    points = xr.DataArray(
        np.c_[0.1 * np.sin(k / 500), 0.1 * np.cos(k / 700), 0.05 + 0 * k],
        {"time": times, "cartesian_axis": list("xyz")},
        ("time", "cartesian_axis"),
    )
    eager = rbm.transform_points(points, outof=frame, into=world)
    lazy = rbm.transform_points(points.chunk(time=150_000), outof=frame, into=world)
    np.testing.assert_array_equal(lazy.values, eager.values)


def test_a_tasks_frames_are_freed_when_it_ends(recording, tree, monkeypatch):
    """Without a pass of the cycle collector: the engine caches chains by the
    values they join, so a worker could otherwise keep every finished task's
    values (and the window's samples and tables that go with them). The
    samples themselves belong to the graph (its tasks' arguments)."""
    import gc
    import weakref

    from rbm_nb.core._frame_snapshot import FrameTree

    made = []
    values = FrameTree.values

    def recording_values(self):
        named = values(self)
        for value in named:
            made.extend(weakref.ref(data) for data in value.path_to_root())
        return named

    monkeypatch.setattr(FrameTree, "values", recording_values)
    pos = _eye(recording, "position").chunk(time=CHUNK)
    lazy = rbm.transform_points(pos, outof="head", into="world", dim="cartesian_axis")
    gc.disable()
    try:
        lazy.compute(scheduler="sync")
        assert made
        assert [r for r in made if r() is not None] == []
    finally:
        gc.enable()
