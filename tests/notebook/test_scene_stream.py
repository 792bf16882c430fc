"""Poses of a long recording go to the browser in chunks around the playhead.

Without a browser: the content message of a long scene has the same size at
any length (a coarse copy of each track and the chunking), every chunk holds
the recording's own samples for its span (and the one before it, so the pose
at a boundary is the recording's), and the widget answers a page's requests
for chunks and nothing else. The browser side is ``test_browser_scene_stream.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.scene import Scene, stream

pytestmark = pytest.mark.usefixtures("recording_comm")

RATE = 200.0  # Hz, as the head of the example recording


def register_walk(minutes: float) -> np.ndarray:
    """world -> body sampled at RATE for ``minutes``, with a run of missing samples."""
    rbm.register_frame("world")
    n = int(minutes * 60 * RATE)
    ts = np.arange(n) / RATE
    xyz = np.c_[np.cos(ts / 30), np.sin(ts / 30), 0.01 * ts]
    xyz[1000:1100] = np.nan
    angle = ts / 10
    quat = np.c_[np.cos(angle / 2), np.zeros(n), np.zeros(n), np.sin(angle / 2)]
    rbm.register_frame(
        "body", parent="world", timestamps=ts, translation=xyz, rotation=quat
    )
    return ts


def custom(widget):
    return [
        (data["content"], buffers)
        for data, buffers in widget.comm.sent
        if data and data.get("method") == "custom"
    ]


def content_bytes(minutes: float) -> tuple[int, dict]:
    """Bytes a page gets before its first frame: the content and the first chunks."""
    rbm.clear_registry()
    register_walk(minutes)
    scene = Scene("world")
    scene.add_frame("body")
    scene.add_path("body")
    scene.widget.comm.receive({"type": "ready"})
    sent = custom(scene.widget)
    total = sum(sum(len(b) for b in buffers) for _, buffers in sent)
    content = sent[0][0]
    scene.close()
    return total, content


def test_bytes_before_the_first_frame_do_not_grow_with_the_recording():
    short, short_content = content_bytes(10)
    long, long_content = content_bytes(120)
    # 12 times the samples, the same bytes (the coarse copy and two chunks)
    assert long_content["stream"]["count"] > 10 * short_content["stream"]["count"] / 2
    assert long == pytest.approx(short, rel=0.05)
    assert long < 2_000_000
    every_sample = 120 * 60 * RATE * (8 + 12 + 16)
    assert long < every_sample / 10


def test_a_short_recording_still_goes_whole_in_one_message():
    register_walk(1)
    scene = Scene("world")
    scene.add_frame("body")
    scene.widget.comm.receive({"type": "ready"})
    [(content, _)] = custom(scene.widget)
    assert "stream" not in content and content["tracks"][0]["n"] == 12000
    scene.close()


@pytest.fixture
def long_scene():
    ts = register_walk(30)
    scene = Scene("world")
    frame = scene.add_frame("body")
    scene.widget.comm.receive({"type": "ready"})
    yield scene, frame, ts
    scene.close()


def chunk_samples(head, buffers, path):
    [m] = [t for t in head["tracks"] if t["path"] == path]
    times = np.frombuffer(buffers[m["times"]], "<f8")
    xyz = np.frombuffer(buffers[m["translation"]], "<f4").reshape(-1, 3)
    xyzw = np.frombuffer(buffers[m["rotation"]], "<f4").reshape(-1, 4)
    return times, xyz, xyzw


def test_chunks_hold_the_recordings_samples_across_each_boundary(long_scene):
    scene, frame, ts = long_scene
    widget = scene.widget
    content = custom(widget)[0][0]
    plan = content["stream"]
    assert plan["first"] == [0, 1]
    # the coarse copy, and the first two chunks right after the content
    assert content["tracks"][0]["n"] == stream.COARSE_SAMPLES
    assert [c["index"] for c, _ in custom(widget)[1:]] == [0, 1]
    seconds = plan["chunk"]
    t, r = rbm.lookup_transform(outof="body", into="world")
    for index in (1, 2, plan["count"] - 1):
        widget.comm.receive(
            {"type": "chunks", "indices": [index], "generation": plan["generation"]}
        )
        head, buffers = custom(widget)[-1]
        assert head["type"] == "chunk" and head["index"] == index
        times, xyz, xyzw = chunk_samples(head, buffers, frame.pose_path)
        # the span's samples and the one before it, each the recording's own
        start, end = index * seconds, (index + 1) * seconds
        lo = np.searchsorted(ts, start, side="right") - 1
        hi = np.searchsorted(ts, end + stream_slack(), side="right")
        np.testing.assert_array_equal(times, ts[lo:hi])
        np.testing.assert_allclose(xyz, t[lo:hi], rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(xyzw, r[lo:hi][:, [1, 2, 3, 0]], atol=1e-6)
        # at any time in the span, the latest sample at or before it is there
        for when in np.linspace(start, min(end, ts[-1]), 7):
            i = np.searchsorted(times, when + 1e-6, side="right") - 1
            j = np.searchsorted(ts, when + 1e-6, side="right") - 1
            assert times[i] == ts[j]
    # the run of missing samples (5-5.5 s) goes as NaN: the view hides the frame there
    head, buffers = custom(widget)[1]
    times, xyz, _ = chunk_samples(head, buffers, frame.pose_path)
    assert np.isnan(xyz[(times >= 5.0) & (times < 5.5)]).all()


def stream_slack() -> float:
    from rbm_nb.scene.state import CHUNK_SLACK

    return CHUNK_SLACK


def test_the_page_can_only_ask_for_chunks_that_exist(long_scene):
    scene, _, _ = long_scene
    widget = scene.widget
    plan = custom(widget)[0][0]["stream"]
    before = len(custom(widget))
    for bad in (
        {"type": "chunks", "indices": [-1, plan["count"], 1.5, True, "2"]},
        {"type": "chunks", "indices": "0"},
        {"type": "chunks"},
    ):
        widget.comm.receive(bad)
    assert len(custom(widget)) == before
    widget.comm.receive({"type": "chunks", "indices": list(range(40))})
    assert len(custom(widget)) == before + stream.MAX_REQUEST
    # chunks are not content: the saved snapshot is not rebuilt for them
    saved = widget._saved
    widget.comm.receive({"type": "chunks", "indices": [3]})
    assert widget._saved is saved


def test_a_change_resends_the_content_with_a_new_generation(long_scene):
    scene, _, _ = long_scene
    widget = scene.widget
    first = custom(widget)[0][0]["stream"]["generation"]
    scene.add_frame("body", label="second")
    contents = [c for c, _ in custom(widget) if c["type"] == "snapshot"]
    assert len(contents) == 2
    assert contents[-1]["stream"]["generation"] == first + 1
    assert len(contents[-1]["tracks"]) == 2
    # the kernel's playhead decides the first chunks
    scene.set_time(20 * 60.0)
    widget.send_content()
    plan = [c for c, _ in custom(widget) if c["type"] == "snapshot"][-1]["stream"]
    k = int(20 * 60.0 // plan["chunk"])
    assert plan["first"] == [k, k + 1]


def test_max_samples_keeps_the_poses_in_one_message(long_scene):
    coarse = Scene("world", max_samples=500)
    coarse.add_frame("body")
    coarse.widget.comm.receive({"type": "ready"})
    [(content, _)] = custom(coarse.widget)
    assert "stream" not in content and content["tracks"][0]["n"] == 500
    coarse.close()
