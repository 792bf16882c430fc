"""Scene.to_html: one self-contained file, bounded size, atomic writes.

The file is checked here by content (the embedded data decodes back to the
scene's tracks); tests/notebook/test_browser.py opens it in chromium.
"""

from __future__ import annotations

import base64
import json
import os
import re

import numpy as np
import pytest
import umsgpack

import rbm_nb as rbm
from rbm_nb.scene import Scene, export
from rbm_nb.scene.commands import meshcat_js_path


@pytest.fixture
def scene():
    rbm.register_frame("world")
    ts = np.arange(101) * 0.01
    angle = np.linspace(0, 2 * np.pi, 101)
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=ts,
        translation=np.c_[np.cos(angle), np.sin(angle), np.zeros(101)],
        rotation=np.c_[
            np.cos(angle / 2), np.zeros(101), np.zeros(101), np.sin(angle / 2)
        ],
    )
    rbm.register_frame("eye", parent="body", translation=(0.1, 0, 0.2))
    late = 0.5 + np.arange(10) * 0.05
    rbm.register_frame(
        "late", parent="world", timestamps=late, translation=np.c_[late, late, late]
    )
    s = Scene("world")
    s.add_frame("body")
    s.add_path("body", color="#ff00ff")
    s.add_vectors("eye", (1, 0, 0), length=2)
    s.add_frame("late")
    yield s
    s.close()


def document_of(path) -> dict:
    text = path.read_text(encoding="utf-8")
    match = re.search(
        r'<script id="rbm-export-data" type="application/json">(.*?)</script>',
        text,
        re.S,
    )
    return json.loads(match.group(1))


def snapshot_of(document) -> tuple[list, dict, dict]:
    """(commands, tracks by path as arrays, scene model state) of the export's 3D view."""
    scene_model = document["models"][0]
    [message] = scene_model["messages"]
    content = message["content"]
    buffers = [base64.b64decode(b) for b in message["buffers"]]
    commands = [umsgpack.unpackb(b) for b in buffers[: content["commands"]]]
    tracks = {}
    for t in content["tracks"]:
        tracks[t["path"]] = {
            "times": np.frombuffer(buffers[t["times"]], "<f8"),
            "translation": np.frombuffer(buffers[t["translation"]], "<f4").reshape(
                -1, 3
            ),
            "rotation": np.frombuffer(buffers[t["rotation"]], "<f4").reshape(-1, 4),
        }
    return commands, tracks, scene_model["state"]


def test_export_is_one_self_contained_file(scene, tmp_path):
    out = scene.to_html(tmp_path / "scene.html")
    text = out.read_text(encoding="utf-8")
    document = document_of(out)
    meshcat = meshcat_js_path().read_text(encoding="utf-8")
    assert meshcat[:5000] in document["esm"][0]  # meshcat's viewer is inlined
    assert not re.search(r"<script[^>]+src=", text)  # nothing fetched from elsewhere
    assert not re.search(r"<link[^>]+href=", text)
    assert "</script" not in json.dumps(document)  # the JSON cannot end its element
    assert out.stat().st_size < 2_000_000
    # the dashboard: the 3D view and the player, wired by the player's model id
    models = {m["id"]: m for m in document["models"]}
    scene_state = document_of(out)["models"][0]["state"]
    player_id = scene_state["player"].removeprefix("IPY_MODEL_")
    assert document["layout"] == [scene.widget.model_id, player_id]
    assert models[player_id]["state"]["duration"] == pytest.approx(1.0)


def test_export_data_decodes_to_the_scene(scene, tmp_path):
    out = scene.to_html(tmp_path / "scene.html", max_frames=1000)
    commands, tracks, state = snapshot_of(document_of(out))
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert objects == {h.geom_path for h in scene.handles.values()} | {"/rbm/grid"}
    assert set(tracks) == set(scene.state.tracks)
    body = scene.state.tracks[scene["frame_body"].pose_path]
    track = tracks[scene["frame_body"].pose_path]
    seconds, translation, rotation, _ = body.take(None)
    np.testing.assert_allclose(track["times"], seconds, atol=1e-12)
    np.testing.assert_allclose(track["translation"], translation, atol=1e-6)
    np.testing.assert_allclose(track["rotation"], rotation[:, [1, 2, 3, 0]], atol=1e-6)
    late = tracks[scene["frame_late"].pose_path]
    assert late["times"][0] == pytest.approx(0.5)  # hidden in the page until then
    assert state["_frames"] == {
        "body": scene["frame_body"].pose_path,
        "late": scene["frame_late"].pose_path,
    }
    assert [row["text"] for row in state["_legend"]][-1] == "grid 50 cm"


def test_max_frames_bounds_every_track(scene, tmp_path):
    out = scene.to_html(tmp_path / "small.html", max_frames=7)
    _, tracks, _ = snapshot_of(document_of(out))
    for track in tracks.values():
        assert 2 <= len(track["times"]) <= 7
    body = tracks[scene["frame_body"].pose_path]
    assert body["times"][-1] == pytest.approx(1.0)  # the last sample is kept
    assert body["times"][0] == 0.0


def test_datetime_export(tmp_path):
    rbm.register_frame("world")
    ts = np.datetime64("2020-02-02T00:27:14") + np.arange(5) * np.timedelta64(100, "ms")
    rbm.register_frame(
        "head", parent="world", timestamps=ts, translation=np.zeros((5, 3))
    )
    with Scene("world") as s:
        s.add_frame("head")
        document = document_of(s.to_html(tmp_path / "dt.html"))
    player = document["models"][-1]["state"]
    assert player["t0_ns"] == ts[0].astype("datetime64[ns]").astype(np.int64)
    assert player["duration"] == pytest.approx(0.4)


def test_series_views_are_included(scene, tmp_path):
    import anywidget
    import traitlets
    from ipywidgets import widget_serialization

    from rbm_nb.widgets import Player

    class Plot(anywidget.AnyWidget):
        _esm = "export default { render({ el }) { el.textContent = 'plot'; } }"
        player = traitlets.Instance(Player, allow_none=True).tag(
            sync=True, **widget_serialization
        )
        values = traitlets.Bytes(b"").tag(sync=True)

    plot = Plot(values=np.arange(3, dtype="<f8").tobytes())
    player = scene.player()
    document = document_of(
        scene.to_html(tmp_path / "d.html", series=plot, player=player)
    )
    assert document["layout"] == [scene.widget.model_id, plot.model_id, player.model_id]
    spec = document["models"][1]
    assert spec["state"]["player"] == f"IPY_MODEL_{player.model_id}"
    assert spec["buffers"] == [
        {"path": ["values"], "data": base64.b64encode(plot.values).decode()}
    ]
    with pytest.raises(ValueError, match="anywidgets"):
        scene.to_html(tmp_path / "e.html", series=[object()])


def test_failed_write_keeps_the_old_file(scene, tmp_path, monkeypatch):
    target = tmp_path / "scene.html"
    target.write_text("old content")

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(export.os, "replace", broken_replace)
    with pytest.raises(
        OSError, match="to_html: cannot write .*scene.html.*No space left"
    ):
        scene.to_html(target)
    assert target.read_text() == "old content"
    assert os.listdir(tmp_path) == ["scene.html"]  # no temporary left behind


def test_overwrite_is_complete(scene, tmp_path):
    target = tmp_path / "scene.html"
    target.write_text("old content")
    scene.to_html(target)
    assert target.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")


def test_unwritable_paths(scene, tmp_path):
    with pytest.raises(FileNotFoundError, match="folder .*missing.* does not exist"):
        scene.to_html(tmp_path / "missing" / "scene.html")
    with pytest.raises(IsADirectoryError, match="is a directory"):
        scene.to_html(tmp_path)
    with pytest.raises(ValueError, match="path"):
        scene.to_html(42)


@pytest.mark.parametrize("max_frames", [1, 0, 2.5, True])
def test_bad_max_frames(scene, tmp_path, max_frames):
    with pytest.raises(ValueError, match="max_frames"):
        scene.to_html(tmp_path / "x.html", max_frames=max_frames)


def register_head_eye(recording):
    """The guide's head/eye frame tree (section 1.6) on a recording."""
    from rbm_nb.app.explorer import register_head_eye_frames

    register_head_eye_frames(
        recording.head, recording.left_eye, recording.right_eye, ros_eyes=True
    )


@pytest.mark.slow
def test_full_head_eye_explorer_exports_under_5_mb(tmp_path):
    from rbm_nb.app.explorer import write_explorer_html

    out = write_explorer_html(
        tmp_path / "explorer.html", source="synthetic", progress=False
    )
    size = out.stat().st_size
    assert size <= 5 * 1024 * 1024
    document = document_of(out)
    player = document["models"][-1]["state"]
    assert (
        player["duration"] == pytest.approx(330, abs=5) and player["t0_ns"] is not None
    )
    _, tracks, _ = snapshot_of(document)
    assert max(len(t["times"]) for t in tracks.values()) <= 10000
