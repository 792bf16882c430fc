"""The Scene facade and its parts (issue 32, item 6).

``Scene`` holds parts with one job each (objects, placements, anchors,
assembly, grid, camera, selection, player link, view, traits) and no state
of its own; each module of ``rbm_nb.scene`` stays short. The grid and the
camera are refitted after every change from per-track summaries
(``PoseTrack.bounds``), never from copies of the tracks: a naive twin of the
old point-cloud extent checks the box, tracemalloc checks the copies.
"""

from __future__ import annotations

import ast
import tracemalloc

import numpy as np
import pytest
from conftest import REPO

import rbm_nb as rbm
from rbm_nb.scene import Scene
from rbm_nb.scene.handles import PathHandle, PointsHandle
from rbm_nb.scene.tracks import PoseTrack

pytestmark = pytest.mark.usefixtures("recording_comm")

SCENE = REPO / "rbm_nb" / "scene"
#: lines of a module of rbm_nb.scene (the facade's docstrings, which document
#: the public API, not counted)
MAX_LINES = 400


def _docstring_lines(tree: ast.Module) -> int:
    count = 0
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef)):
            first = node.body[0] if node.body else None
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                count += first.end_lineno - first.lineno + 1
    return count


def test_every_scene_module_is_short():
    sizes = {}
    for path in sorted(SCENE.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        lines = len(text.splitlines())
        if path.name == "scene.py":
            lines -= _docstring_lines(ast.parse(text))
        sizes[path.name] = lines
    too_long = {name: n for name, n in sizes.items() if n > MAX_LINES}
    assert not too_long, f"over {MAX_LINES} lines: {too_long} (all: {sizes})"


@pytest.fixture
def walk():
    """world -> body (moving, 2001 samples at 10 ms) -> eye (static)."""
    rbm.clear_registry()
    rbm.register_frame("world")
    ts = np.arange(2001) * 0.01
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=ts,
        translation=np.c_[np.sin(ts) * 3, ts, 0.1 * ts],
    )
    rbm.register_frame("eye", parent="body", translation=(0.1, 0.0, 0.2))
    yield ts
    rbm.clear_registry()


def _part_modules(scene: Scene) -> dict[str, str]:
    return {name: type(value).__module__ for name, value in vars(scene).items()}


def test_the_facade_holds_parts_and_no_state_of_its_own(walk):
    scene = Scene("world")
    parts = _part_modules(scene)
    # every attribute is a part: an instance of a class of another module of
    # rbm_nb.scene (no dict, list, number or flag kept by the facade itself)
    for name, module in parts.items():
        assert module.startswith("rbm_nb.scene."), (name, module)
        assert module != "rbm_nb.scene.scene", (name, module)
    # using the whole API adds nothing to the facade
    body = scene.add_frame("body", scale=0.2)
    scene.add_frame("eye", base="body", scale=0.1)
    scene.add_path("body")
    scene.add_points([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    scene.add_vectors("eye", (0.0, 0.0, 1.0), base="body")
    scene.add_mesh("body", "sphere", base="body", size=0.05)
    scene.widget  # noqa: B018 - creates the view
    scene.set_time(0.5)
    scene.highlight("eye")
    scene.selected = "body"
    scene.follow("body")
    scene.focus("body")
    scene.set_camera((5.0, 5.0, 5.0), (0.0, 0.0, 0.0))
    scene.fit_camera()
    player = scene.player()
    player.seek_time(1.0)
    body.update(scale=0.3)
    body.visible = False
    body.remove()
    assert scene.legend()
    scene.close()
    assert _part_modules(scene) == parts


def _naive_extent(scene: Scene) -> np.ndarray:
    """The points the grid and camera used to fit (every sample, copied):
    each object's geometry at the mean of its pose, its pose's samples, and
    its anchor's samples moved by the mean of those."""
    chunks = []
    for handle in scene.handles.values():
        track = scene.state.tracks.get(handle.pose_path)
        if track is None:
            origins = scene.state.static_pose(handle.pose_path)[:3, 3].reshape(1, 3)
        else:
            origins = track.positions()
        local = np.asarray(handle._extent(), dtype=float).reshape(-1, 3)
        if isinstance(handle, PathHandle) or (
            isinstance(handle, PointsHandle) and not handle.moving
        ):
            points = local + origins.mean(axis=0)
        else:
            points = np.vstack([origins, local + origins.mean(axis=0)])
        anchor = scene.state.tracks.get(scene._anchors.path(handle.base))
        if anchor is not None:
            points = anchor.positions() + points.mean(axis=0)
        chunks.append(points)
    return np.vstack(chunks)


def test_the_box_is_the_one_of_every_sample(walk):
    scene = Scene("world")
    scene.add_frame("world", scale=1.0)
    scene.add_mesh("body", "box", base="body", size=(0.2, 0.3, 0.4), offset=(1, 0, 0))
    scene.add_frame("eye", base="body", scale=0.1)
    scene.add_path("body")
    scene.add_points([[10.0, -4.0, 0.0], [11.0, -5.0, 2.0]])
    scene.add_vectors("eye", [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]], length=2.0)
    scene.add_points(
        [[0.0, 0.0, 0.0], [-7.0, 1.0, 0.0]], frame="body", timestamps=[0.0, 1.0]
    )
    points = _naive_extent(scene)
    bounds = scene._assembly.bounds()
    np.testing.assert_allclose(bounds.low, points.min(axis=0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(bounds.high, points.max(axis=0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(bounds.mean, points.mean(axis=0), rtol=0, atol=1e-9)
    assert bounds.count == len(points)
    scene.close()


def test_track_bounds_skip_missing_samples():
    ts = np.arange(6.0)
    translation = np.arange(18.0).reshape(6, 3)
    translation[[1, 4]] = np.nan
    rotation = np.tile([1.0, 0.0, 0.0, 0.0], (6, 1))
    rotation[2] = np.nan  # a missing rotation hides the sample too
    track = PoseTrack(translation, rotation, ts)
    kept = track.positions()
    low, high, mean, count = track.bounds
    np.testing.assert_array_equal(low, kept.min(axis=0))
    np.testing.assert_array_equal(high, kept.max(axis=0))
    np.testing.assert_allclose(mean, kept.mean(axis=0), rtol=1e-15)
    assert count == len(kept) == 3
    assert (
        PoseTrack(np.full((2, 3), np.nan), np.ones((2, 4)), [0.0, 1.0]).bounds is None
    )
    static = PoseTrack((1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0))
    assert [v.tolist() for v in static.bounds[:3]] == [[1.0, 2.0, 3.0]] * 3


@pytest.fixture
def long_walk():
    """world -> head, moving for 200,000 samples (4.8 MB of translations)."""
    rbm.clear_registry()
    rbm.register_frame("world")
    ts = np.arange(200_000) * 0.005
    rbm.register_frame(
        "head",
        parent="world",
        timestamps=ts,
        translation=np.c_[np.cos(ts / 60), np.sin(ts / 60), np.full_like(ts, 1.7)],
    )
    yield
    rbm.clear_registry()


def test_adding_objects_to_a_moving_frame_copies_no_track(long_walk):
    """Each ``add_*`` refits the grid and the camera to the whole content.

    Seven objects hang from the moving head (as in the explorer): the box
    they sweep is the head's track's, summarised once. Before the split the
    refit copied every track for every object (``PoseTrack.positions()``) and
    the reach check looked the head up again: tens of MB for one more mesh.
    """
    scene = Scene("world")
    scene.add_frame("head", base="head", scale=0.1)
    anchor = scene.state.tracks[scene._anchors.path(rbm.registry["head"])]
    size = len(anchor) * 3 * 8  # the translations, were they held
    tracemalloc.start()
    try:
        for _ in range(3):
            scene.add_mesh("head", "sphere", base="head", size=0.05)
        scene.add_vectors("head", (0.0, 0.0, 1.0), base="head")
        scene.add_frame("world")
        scene._assembly.refresh()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < size / 4, (
        f"peak {peak / 1e6:.2f} MB for a track of {size / 1e6:.2f} MB"
    )
    scene.close()


def test_summarising_a_track_copies_none_of_it(long_walk):
    """A looked-up track holds no poses: its summary is one pass in blocks,
    whose peak is a block's, not the track's."""
    track = PoseTrack.lookup(rbm.registry["head"], rbm.registry["world"])
    size = len(track) * 3 * 8  # the translations, were they held
    track.take(slice(0, 2))  # the engine's plan and tables for this chain, made
    tracemalloc.start()
    try:
        track.bounds  # noqa: B018 - computed here, once
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < size / 4, (
        f"peak {peak / 1e6:.2f} MB for a track of {size / 1e6:.2f} MB"
    )
