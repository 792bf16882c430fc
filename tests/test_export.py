"""Scene.to_html: one self-contained file, bounded size, atomic writes.

The file is checked here by content (the embedded data decodes back to the
scene's tracks); tests/test_browser.py opens it in chromium.
"""

from __future__ import annotations

import base64
import json
import os
import re

import numpy as np
import pytest
import umsgpack
from hypothesis import given, settings
from hypothesis import strategies as st

import rbm_nb as rbm
from rbm_nb.scene import Scene, export
from rbm_nb.scene.server import meshcat_js_path


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


def payload_of(path) -> dict:
    text = path.read_text(encoding="utf-8")
    match = re.search(
        r'<script id="rbm-data" type="application/json">(.*?)</script>', text, re.S
    )
    return json.loads(match.group(1))


def floats(b64: str, width: int) -> np.ndarray:
    return np.frombuffer(base64.b64decode(b64), dtype="<f4").reshape(-1, width)


def test_export_is_one_self_contained_file(scene, tmp_path):
    out = scene.to_html(tmp_path / "scene.html")
    text = out.read_text(encoding="utf-8")
    assert (
        meshcat_js_path().read_text(encoding="utf-8") in text
    )  # the viewer is inlined
    assert not re.search(r"<script[^>]+src=", text)  # nothing fetched from elsewhere
    assert not re.search(r"<link[^>]+href=", text)
    assert "rbmViewer.loadExport" in text
    assert out.stat().st_size < 2_000_000


def test_export_data_decodes_to_the_scene(scene, tmp_path):
    out = scene.to_html(tmp_path / "scene.html", max_frames=1000)
    data = payload_of(out)
    commands = [umsgpack.unpackb(base64.b64decode(c)) for c in data["commands"]]
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    assert objects == {h.geom_path for h in scene.handles.values()}
    tracks = {t["path"]: t for t in data["tracks"]}
    assert set(tracks) == {node.path for node in scene._dynamic}
    body = scene._nodes[scene["frame_body"].pose_path].track
    track = tracks[scene["frame_body"].pose_path]
    np.testing.assert_allclose(floats(track["times"], 1)[:, 0], body.seconds, atol=1e-6)
    np.testing.assert_allclose(
        floats(track["position"], 3), body.translation, atol=1e-6
    )
    np.testing.assert_allclose(
        floats(track["quaternion"], 4), body.rotation[:, [1, 2, 3, 0]], atol=1e-6
    )
    assert data["t0"] == 0.0 and data["duration"] == pytest.approx(1.0)
    assert data["datetime"] is False and data["camera"]["type"] == "rbm_camera"
    late = tracks[scene["frame_late"].pose_path]
    assert late["visible"] == {
        "times": [0.0, 0.5],
        "values": [False, True],
    }  # hidden until it starts


def test_max_frames_bounds_every_track(scene, tmp_path):
    out = scene.to_html(tmp_path / "small.html", max_frames=7)
    for track in payload_of(out)["tracks"]:
        times = floats(track["times"], 1)[:, 0]
        assert 2 <= len(times) <= 7
    body = payload_of(out)["tracks"][0]
    assert floats(body["times"], 1)[-1, 0] == pytest.approx(
        1.0
    )  # the last sample is kept


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 5000), st.integers(2, 600))
def test_subsample_indices(n, max_frames):
    idx = export.subsample_indices(n, max_frames)
    assert idx[0] == 0 and idx[-1] == n - 1
    assert len(idx) <= max(max_frames, 1)
    assert (np.diff(idx) > 0).all()
    if n <= max_frames:
        assert len(idx) == n


def test_datetime_export(tmp_path):
    rbm.register_frame("world")
    ts = np.datetime64("2020-02-02T00:27:14") + np.arange(5) * np.timedelta64(100, "ms")
    rbm.register_frame(
        "head", parent="world", timestamps=ts, translation=np.zeros((5, 3))
    )
    with Scene("world") as s:
        s.add_frame("head")
        data = payload_of(s.to_html(tmp_path / "dt.html"))
    assert data["datetime"] is True
    assert data["t0"] == pytest.approx(
        ts[0].astype("datetime64[ns]").astype(np.int64) / 1e9
    )


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
    from rbm_nb.explorer import register_head_eye_frames

    register_head_eye_frames(
        recording.head, recording.left_eye, recording.right_eye, ros_eyes=True
    )


@pytest.mark.slow
def test_full_head_eye_recording_exports_under_20_mb(tmp_path):
    from rbm_nb.data import synthetic_head_eye

    register_head_eye(synthetic_head_eye())  # 5.5 minutes, 200 Hz head, ~343 Hz eyes
    with Scene("world") as s:
        for name in (
            "t265/world",
            "t265/tracker",
            "head",
            "pupil/scene_cam",
            "pupil/left_eye",
            "left_eye",
            "pupil/right_eye",
            "right_eye",
        ):
            s.add_frame(name, scale=0.3)
        s.add_path("head", color="#ff00ff")
        s.add_vectors("left_eye", (1, 0, 0), length=3)
        s.add_vectors("right_eye", (1, 0, 0), length=3)
        out = s.to_html(tmp_path / "head_eye.html")
    size = out.stat().st_size
    assert size <= 20 * 1024 * 1024
    data = payload_of(out)
    assert data["datetime"] is True and data["duration"] == pytest.approx(330, abs=5)
    assert max(len(base64.b64decode(t["times"])) // 4 for t in data["tracks"]) <= 5000
