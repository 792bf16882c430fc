"""A scene keeps no whole-recording copy of its poses (issue 35).

A moving object's track looks its samples up from the frames per window
(a chunk around the playhead, the coarse copy, one pose) and keeps none;
bounds and the path come from a blockwise pass. What the browser gets is
the same as from a track holding a whole lookup
(:meth:`PoseTrack.looked_up_whole`, how the scene kept them before).
"""

from __future__ import annotations

import gc
import tracemalloc

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.scene import Scene, stream
from rbm_nb.scene.decimate import (
    refine_region,
    refine_region_blocks,
    simplify_path,
    simplify_path_blocks,
)
from rbm_nb.scene.looked_up import BLOCK_ROWS
from rbm_nb.scene.state import SceneState
from rbm_nb.scene.tracks import PoseTrack

HEAD_HZ, EYE_HZ = 200, 340


def register_head_eye(seconds: float, seed: int = 3) -> None:
    """world -> head (200 Hz, datetime64) -> eye (340 Hz, ``max_gap``, gaps
    and NaN runs): the explorer's shape of chain, synthetic."""
    rng = np.random.default_rng(seed)
    rbm.clear_registry()
    rbm.register_frame("world")
    start = np.datetime64("2024-03-01T10:00:00", "ns")
    n = int(seconds * HEAD_HZ)
    th = start + (np.arange(n) * (1e9 / HEAD_HZ)).astype("timedelta64[ns]")
    walk = np.cumsum(rng.normal(scale=0.003, size=(n, 3)), axis=0)
    q = np.c_[np.ones(n), rng.normal(scale=0.05, size=(n, 3))]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    walk[n // 3 : n // 3 + 40] = np.nan  # a run of missing head samples
    q[n // 3 : n // 3 + 40] = np.nan
    rbm.register_frame(
        "head", parent="world", translation=walk, rotation=q, timestamps=th
    )
    m = int(seconds * EYE_HZ)
    # eye clock 0.7 ms before the head's, 2.94 ms steps with jitter, a few
    # dropped stretches longer than max_gap
    steps = np.full(m - 1, int(1e9 / EYE_HZ)) + rng.integers(-20_000, 20_000, m - 1)
    steps[m // 5 :: max(m // 4, 1)] += 300_000_000
    te = start + 5_000_000 + np.r_[0, np.cumsum(steps)].astype("timedelta64[ns]")
    gaze = np.c_[rng.normal(scale=0.1, size=(m, 2)), np.ones(m)]
    qe = np.c_[np.ones(m), rng.normal(scale=0.1, size=(m, 3))]
    qe /= np.linalg.norm(qe, axis=1, keepdims=True)
    qe[::97] = np.nan  # blinks
    rbm.register_frame(
        "eye",
        parent="head",
        translation=gaze * 0.01,
        rotation=qe,
        timestamps=te,
        max_gap=0.1,
    )


@pytest.fixture
def head_eye():
    register_head_eye(60.0)
    yield
    rbm.clear_registry()


PAIRS = [("head", "world"), ("eye", "head"), ("eye", "world")]


@pytest.mark.parametrize("outof, into", PAIRS)
def test_windows_and_picks_equal_a_whole_lookup(head_eye, outof, into):
    frame, base = rbm.registry[outof], rbm.registry[into]
    lazy = PoseTrack.lookup(frame, base)
    whole = PoseTrack.looked_up_whole(frame, base)
    assert len(lazy) == len(whole)
    assert lazy.kind == whole.kind
    assert (lazy.start, lazy.end) == (whole.start, whole.end)
    np.testing.assert_array_equal(lazy.sample_keys(), whole.sample_keys())
    np.testing.assert_array_equal(lazy.original_timestamps, whole.original_timestamps)
    n = len(whole)
    picks = np.unique(np.linspace(0, n - 1, 777).round().astype(np.int64))
    for index in (None, slice(0, 1), slice(5, 9000), slice(n - 3000, n), picks):
        for got, want in zip(lazy.take(index), whole.take(index), strict=True):
            if want is None:
                assert got is None
            else:
                np.testing.assert_array_equal(got, want)
    for x in whole.sample_keys()[:: max(n // 500, 1)].tolist():
        for side in ("left", "right"):
            assert lazy.search(x, side) == whole.search(x, side)
        assert lazy.index_at(x + 100_000) == whole.index_at(x + 100_000)  # 0.1 ms after
    for summary, reference in zip(lazy.bounds, whole.bounds, strict=True):
        np.testing.assert_array_equal(summary, reference)


def test_chunks_and_the_coarse_copy_are_those_of_held_tracks(head_eye):
    """What goes to the browser is byte for byte what it was."""
    scene = Scene("world", grid=False)
    scene.add_frame("head", base="head", scale=0.1)
    scene.add_path("head", max_points=500)
    scene.add_vectors("eye", (0.0, 0.0, 1.0), base="head")
    lazy_state = scene.state
    held = SceneState()
    for path, track in lazy_state.tracks.items():
        assert not isinstance(track, PoseTrack)  # the scene keeps no poses
        held.add_track(path, _whole(scene, path))
    assert held.origin == lazy_state.origin
    assert lazy_state.payload_bytes() == held.payload_bytes()
    seconds = stream.chunk_seconds(lazy_state)
    count = lazy_state.chunk_count(seconds)
    assert count == held.chunk_count(seconds)
    for k in sorted({0, 1, count // 3, count // 2, count - 2, count - 1}):
        assert lazy_state.track_chunk(k, seconds) == held.track_chunk(k, seconds)
    for cap in (stream.COARSE_SAMPLES, 20_000, None):
        assert lazy_state.track_payload(cap) == held.track_payload(cap)
    timeline, reference = lazy_state.timeline(), held.timeline()
    np.testing.assert_array_equal(timeline[0], reference[0])
    scene.close()


def _whole(scene, path):
    """The held track of a scene's node (looked up whole, as before)."""
    if path == "/rbm/anchor_head":
        return PoseTrack.looked_up_whole(rbm.registry["head"], rbm.registry["world"])
    return PoseTrack.looked_up_whole(rbm.registry["eye"], rbm.registry["head"])


def _kept_by_a_scene(seconds: float) -> tuple[int, int]:
    """Bytes a scene of the explorer's objects keeps after its build and a
    look at its time axis (the engine's own caches made first), and the bytes
    of its tracks' poses."""
    register_head_eye(seconds)
    head, eye, world = (rbm.registry[n] for n in ("head", "eye", "world"))
    for outof, into in ((head, world), (eye, head)):
        rbm.lookup_transform(outof, into)  # the engine's tables and plans
    gc.collect()
    tracemalloc.start()
    try:
        scene = Scene("world")
        scene.add_frame("world", scale=1.0)
        scene.add_mesh("head", "sphere", base="head", size=0.1)
        scene.add_frame("head", base="head", scale=0.12)
        scene.add_path("head", max_points=2000)
        scene.add_vectors("eye", (0.0, 0.0, 1.0), base="head")
        scene.fit_camera()
        # the player's axis is made for it, not kept by the scene
        assert len(scene.timestamps) > seconds * EYE_HZ
        scene.set_time(scene.state.origin + 1.0)
        gc.collect()
        kept, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    poses = sum(len(t) * (8 + 7 * 8) for t in scene.state.tracks.values())
    scene.close()
    rbm.clear_registry()
    return kept, poses


def test_a_scene_keeps_a_bounded_share_of_a_long_recording():
    """Four times the recording, the same memory kept: a few chunks' worth."""
    _kept_by_a_scene(60.0)  # what a first scene makes once (kernels, imports)
    short, short_poses = _kept_by_a_scene(15 * 60.0)
    long, long_poses = _kept_by_a_scene(60 * 60.0)
    assert long_poses > 3.9 * short_poses  # 1 h: ~180 MB of float64 poses
    chunk = stream.CHUNK_BYTES
    assert long <= 4 * chunk, (long / 1e6, long_poses / 1e6)
    # not proportional to the recording: within a block's worth of the short one
    assert long - short <= BLOCK_ROWS * 64, (short / 1e6, long / 1e6)


@pytest.mark.parametrize("seed", range(40))
def test_a_path_simplified_block_by_block_is_the_one_simplified_whole(seed):
    """The naive twin: :func:`simplify_path` of the whole array."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 3000))
    points = np.cumsum(rng.normal(scale=rng.choice([1e-3, 1e-2, 0.1]), size=(n, 3)), 0)
    for _ in range(int(rng.integers(0, 8))):  # runs of missing samples
        if n:
            first = int(rng.integers(0, n))
            points[first : first + int(rng.integers(1, 40))] = np.nan
    if n and seed % 5 == 0:
        points[: int(rng.integers(0, n))] = np.nan  # missing from the start
    if n and seed % 5 == 1:
        points[int(rng.integers(0, n)) :] = np.nan  # ... and to the end
    tolerance = [None, 0.0, 0.05, 1e-4][seed % 4]
    max_points = [2, 50, 1000][seed % 3]
    present = points[~np.isnan(points).any(axis=1)]
    low = present.min(axis=0) if len(present) else np.zeros(3)
    high = present.max(axis=0) if len(present) else np.zeros(3)
    size = [1, 2, 3, 7, 64, 4096][seed % 6]
    blocks = (points[i : i + size] for i in range(0, n, size))
    got = simplify_path_blocks(blocks, low, high, tolerance, max_points)
    want = simplify_path(points, tolerance, max_points)
    assert got[1] == want[1]
    assert len(got[0]) == len(want[0])
    for piece, reference in zip(got[0], want[0], strict=True):
        np.testing.assert_array_equal(piece, reference)


def test_a_long_path_is_simplified_without_its_positions_held_whole():
    """Drawing the path looks its samples up and simplifies them block by
    block: its peak is that of simplifying the whole array less at least
    the array itself (real head, 1 h: 54 MB instead of 83 MB)."""
    register_head_eye(3600.0)
    scene = Scene("world", grid=False)
    scene.add_frame("head", base="head")  # the anchor, summarised
    track = scene.state.tracks["/rbm/anchor_head"]
    whole = len(track) * 3 * 8
    tracemalloc.start()
    try:
        path = scene.add_path("head", max_points=500)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        reference = simplify_path(track.positions_with_gaps(), None, 500)
        _, peak_whole = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak <= peak_whole - whole, (peak / 1e6, peak_whole / 1e6, whole / 1e6)
    stretches, error = path.stretches()
    assert error == reference[1]
    for piece, want in zip(stretches, reference[0], strict=True):
        np.testing.assert_array_equal(piece, want)
    scene.close()
    rbm.clear_registry()


@pytest.mark.parametrize("seed", range(30))
def test_a_region_refined_block_by_block_is_the_one_refined_whole(seed):
    """The naive twin: :func:`refine_region` of the whole array."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(1, 3000))
    points = np.cumsum(rng.normal(scale=0.01, size=(n, 3)), axis=0)
    for _ in range(int(rng.integers(0, 8))):
        first = int(rng.integers(0, n))
        points[first : first + int(rng.integers(1, 40))] = np.nan
    present = points[~np.isnan(points).any(axis=1)]
    if not len(present):
        present = np.zeros((1, 3))
    centre = present[int(rng.integers(0, len(present)))]
    half = rng.uniform(0.01, 0.3)
    low, high = centre - half, centre + half
    tolerance = [0.0, 1e-3, 0.02][seed % 3]
    size = [1, 2, 5, 64, 4096][seed % 5]
    blocks = (points[i : i + size] for i in range(0, n, size))
    got = refine_region_blocks(blocks, low, high, tolerance, 300)
    want = refine_region(points, low, high, tolerance, 300)
    assert got[1] == want[1]
    assert len(got[0]) == len(want[0])
    for piece, reference in zip(got[0], want[0], strict=True):
        np.testing.assert_array_equal(piece, reference)


def test_frames_that_share_no_time_are_refused_by_name():
    # the engine's matching takes the door's refusal as given; a scene
    # looking poses up must refuse such frames as the lookups do
    rbm.clear_registry()
    rbm.register_frame("world")
    q = np.tile([1.0, 0.0, 0.0, 0.0], (10, 1))
    early, late = np.arange(10) * 0.1, 100 + np.arange(10) * 0.1
    rbm.register_frame(
        "a", translation=np.zeros((10, 3)), rotation=q, timestamps=early, parent="world"
    )
    rbm.register_frame(
        "b", translation=np.ones((10, 3)), rotation=q, timestamps=late, parent="a"
    )
    scene = Scene("world")
    with pytest.raises(ValueError, match=r"do not overlap.*frame 'b'.*frame 'a'"):
        scene.add_frame("b")
    rbm.clear_registry()
