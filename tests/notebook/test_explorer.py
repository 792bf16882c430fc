"""The explorer's dashboard without a browser: parts, colours, exports (issue 29)."""

from __future__ import annotations

import re
import threading

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.app import explorer
from tests.recordings import real_recording

MAX_EXPORT_BYTES = 5_000_000


def _sources():
    marks = [] if real_recording() is not None else [pytest.mark.skip("no real data")]
    return [pytest.param("real", marks=marks), "synthetic"]


@pytest.fixture
def data_dir(monkeypatch, tmp_path):
    def choose(source):
        if source == "real":
            from tests.recordings import REAL_DIR

            monkeypatch.setenv("RBM_NB_DATA_DIR", str(REAL_DIR))
        else:
            (tmp_path / "no-data").mkdir(exist_ok=True)
            monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "no-data"))

    yield choose
    rbm.clear_registry()


def _content(html: str) -> str:
    # widget model ids and the scene's random uids (also inside the base64 of
    # meshcat's commands) differ between two builds; the rest must not
    html = re.sub(r"[A-Za-z0-9+/=]{200,}", "BLOB", html)
    return re.sub(r"[0-9a-f]{32}", "ID", html)


@pytest.mark.parametrize("source", _sources())
def test_notebook_and_cli_exports_are_the_same_and_under_5_mb(
    source, data_dir, tmp_path
):
    data_dir(source)
    board = explorer.dashboard()
    try:
        notebook = explorer.export_html(board, tmp_path / "notebook.html")
    finally:
        explorer.close_dashboard(board)
    cli = explorer.write_explorer_html(tmp_path / "cli.html", progress=False)
    sizes = {p.name: p.stat().st_size for p in (notebook, cli)}
    print(f"{source} export sizes (bytes):", sizes)
    assert all(size <= MAX_EXPORT_BYTES for size in sizes.values()), sizes
    a, b = notebook.read_text(), cli.read_text()
    assert len(a) == len(b)  # the blobs hold the same amount of data
    assert _content(a) == _content(b)
    assert (
        "head/eye recording" in a
        and source in a.split("<title>")[1].split("</title>")[0]
    )


def test_the_plot_colours_each_eye_as_the_scene_does(data_dir):
    data_dir("synthetic")
    board = explorer.dashboard()
    try:
        panels = {p["label"]: p for p in board.plot.panels}
        for name in ("gaze yaw", "gaze yaw rate"):
            assert panels[name]["components"] == ["left eye", "right eye"]
            assert panels[name]["colors"] == [
                explorer.GAZE_COLORS["left_eye"],
                explorer.GAZE_COLORS["right_eye"],
            ]
        rays = {h.name: h.style.get("color") for h in board.scene.handles.values()}
        assert rays["left_eye_gaze"] == explorer.GAZE_COLORS["left_eye"]
        assert rays["right_eye_gaze"] == explorer.GAZE_COLORS["right_eye"]
        # the Player starts where head and both eyes have samples
        sight = explorer.gaze_yaw(*explorer.load_head_eye("synthetic")[1:3])
        at = sight.sel(time=board.player.timestamp, method="nearest")
        assert np.isfinite(at.values).all()
    finally:
        explorer.close_dashboard(board)


def test_a_users_own_files_open_in_the_explorer(tmp_path, monkeypatch):
    """Files in RBM_NB_DATA_DIR that are not the example's, same schema: opened, said."""
    from rbm_nb.data.synthetic import synthetic_head_eye

    recording = synthetic_head_eye(duration=20.0, seed=3)
    for name in ("head", "left_eye", "right_eye"):
        getattr(recording, name).to_netcdf(tmp_path / f"{name}.nc")
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path))
    head, left, right, note = explorer.load_head_eye()
    assert note.startswith("your own head/eye recording") and str(tmp_path) in note
    assert head.sizes["time"] == recording.head.sizes["time"]
    from rbm_nb.data import last_choice

    assert last_choice("left_eye").kind == "own"
    # a file without the schema: synthetic data, and the note says which file and why
    import xarray as xr

    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(tmp_path / "head.nc")
    *_, note = explorer.load_head_eye()
    assert note.startswith("synthetic head/eye recording")
    assert str(tmp_path / "head.nc") in note and "'position'" in note
    rbm.clear_registry()


# the example tree under other names, as a user's own registration would be
_RENAMED = {
    "world": "map",
    "t265/world": "odom",
    "t265/tracker": "tracker",
    "head": "base_head",
    "pupil/scene_cam": "cam",
    "pupil/left_eye": "eye_l",
    "pupil/right_eye": "eye_r",
}


def _register_renamed():
    """Copy the registered example tree under _RENAMED's names (public API only)."""
    from rbm_nb.core import frames

    for old, new in _RENAMED.items():
        frame = frames.registry[old]
        parent = None if frame.parent is None else _RENAMED[frame.parent.name]
        if parent is None:
            rbm.register_frame(new)
            continue
        rbm.register_frame(
            new,
            parent=parent,
            translation=frame.translation,
            rotation=frame.rotation,
            timestamps=frame.timestamps,
            max_gap=frame.max_gap,
        )


def test_the_explorer_of_frames_registered_under_any_names(data_dir):
    """dashboard(frames=...) explores a tree the user registered, by name: the
    same series, rays and start as the example's registration of the same data."""
    data_dir("synthetic")
    example = explorer.dashboard()
    try:
        _register_renamed()
        names = explorer.HeadEyeFrames("map", "base_head", "eye_l", "eye_r")
        mine = explorer.dashboard(frames=names)
        try:
            assert "registered frames" in mine.note and "'eye_l'" in mine.note
            for key, values in example.series.items():
                np.testing.assert_allclose(
                    mine.series[key].values, values.values, atol=1e-9, err_msg=key
                )
            assert mine.tree.root == "map"
            assert mine.player.timestamp == example.player.timestamp
            rays = {h.name: h.frame.name for h in mine.scene.handles.values()}
            assert rays["left_eye_gaze"] == "eye_l"
            assert rays["right_eye_gaze"] == "eye_r"
        finally:
            explorer.close_dashboard(mine)
    finally:
        explorer.close_dashboard(example)


def test_the_explorer_of_frames_names_what_is_wrong():
    rbm.register_frame("map")
    with pytest.raises(ValueError, match=r"frames.head is 'nohead', which is not a"):
        explorer.dashboard(frames=explorer.HeadEyeFrames("map", "nohead", "a", "b"))
    rbm.register_frame(
        "h", parent="map", timestamps=[0.0, 1.0], translation=np.zeros((2, 3))
    )
    rbm.register_frame("a", parent="h")
    rbm.register_frame("b", parent="h")
    with pytest.raises(
        ValueError, match=r"frames.left_eye .a. does not move relative to .h."
    ):
        explorer.dashboard(frames=explorer.HeadEyeFrames("map", "h", "a", "b"))
    with pytest.raises(ValueError, match="datasets or frames=, not both"):
        explorer.dashboard(1, 2, 3, frames=explorer.EXAMPLE_FRAMES)


def test_the_series_are_built_beside_the_scene_and_their_errors_reach_the_caller(
    data_dir, monkeypatch
):
    """The dashboard builds the plots' series on a thread of its own while the
    scene is built; what the series raise is raised by ``dashboard``, and the
    series it shows are the ones that thread made."""
    data_dir("synthetic")
    threads = []
    made = explorer.explorer_series

    def recorded(*args, **kwargs):
        threads.append(threading.current_thread().name)
        return made(*args, **kwargs)

    monkeypatch.setattr(explorer, "explorer_series", recorded)
    board = explorer.dashboard()
    try:
        assert threads and threads[0].startswith("rbm-explorer-series")
        head, left, right, _ = explorer.load_head_eye("synthetic")
        alone = made(head, left, right)
        for name, series in alone.items():
            assert board.series[name].identical(series), name
    finally:
        explorer.close_dashboard(board)

    def fails(*args, **kwargs):
        raise ValueError("the series could not be made")

    monkeypatch.setattr(explorer, "explorer_series", fails)
    with pytest.raises(ValueError, match="could not be made"):
        explorer.dashboard()


def _first_full_instant_whole(head, left_eye, right_eye, min_confidence):
    # the definition in one pass over every row (what the search must find)
    ok = left_eye.time.values >= head.time.values[0]
    for eye in (left_eye, right_eye):
        ok &= np.isfinite(eye.orientation.values).all(axis=1)
        if "confidence" in eye:
            ok &= eye.confidence.values >= min_confidence
    return left_eye.time.values[int(np.argmax(ok))]


@pytest.mark.parametrize("source", _sources())
def test_the_first_full_instant_searched_block_by_block_is_the_definitions(
    data_dir, source
):
    data_dir(source)
    head, left, right, _ = explorer.load_head_eye("auto")
    conf = explorer.MIN_CONFIDENCE
    found = explorer.first_full_instant(head, left, right, min_confidence=conf)
    assert found == _first_full_instant_whole(head, left, right, conf)
    # an instant past the first blocks: the eyes missing for 3.5 blocks
    late = left.copy(deep=True)
    late.orientation.values[: int(3.5 * explorer.FIRST_INSTANT_BLOCK)] = np.nan
    found = explorer.first_full_instant(head, late, right, min_confidence=conf)
    assert found == _first_full_instant_whole(head, late, right, conf)
    assert found >= late.time.values[int(3.5 * explorer.FIRST_INSTANT_BLOCK)]
    # no such instant: the eyes' first timestamp, as the definition gives
    never = left.copy(deep=True)
    never.orientation.values[:] = np.nan
    found = explorer.first_full_instant(head, never, right, min_confidence=conf)
    assert found == never.time.values[0]
    assert found == _first_full_instant_whole(head, never, right, conf)
