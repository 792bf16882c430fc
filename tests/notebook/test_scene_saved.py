"""The scene's snapshot saved with the widget state, for pages without a kernel."""

from __future__ import annotations

import json
import struct

import numpy as np

import rbm_nb as rbm
from rbm_nb.scene.widget import SceneWidget, pack_snapshot


def _unpack(blob: bytes):
    n = struct.unpack_from("<I", blob)[0]
    content = json.loads(blob[4 : 4 + n])
    buffers, at = [], 4 + n
    while at < len(blob):
        size = struct.unpack_from("<I", blob, at)[0]
        buffers.append(blob[at + 4 : at + 4 + size])
        at += 4 + size
    return content, buffers


def test_pack_round_trip():
    content = {"type": "snapshot", "commands": 1, "tracks": []}
    assert _unpack(pack_snapshot(content, [b"abc", b""])) == (content, [b"abc", b""])


def _moving_scene(n=20000):
    rbm.clear_registry()
    rbm.register_frame("world")
    ts = np.linspace(0.0, 100.0, n)
    rbm.register_frame(
        "body", parent="world", translation=np.c_[ts, 0 * ts, 0 * ts], timestamps=ts
    )
    return rbm.scene.Scene("world")


def test_saved_state_follows_the_content_without_a_browser():
    scene = _moving_scene()
    widget = scene.widget
    assert isinstance(widget, SceneWidget) and not widget.ready
    empty = _unpack(widget._saved)[0]
    assert empty["type"] == "snapshot" and empty["tracks"] == []
    scene.add_frame("body")
    content, buffers = _unpack(widget._saved)
    (track,) = content["tracks"]
    # the moving frame is in it, capped to SAVED_SAMPLES samples
    times = np.frombuffer(buffers[track["times"]], dtype=np.float64)
    assert len(times) == SceneWidget.SAVED_SAMPLES
    assert content["commands"] >= 1
    scene.close()


def test_saved_state_is_the_message_the_kernel_sends():
    scene = _moving_scene(100)
    scene.add_frame("body")
    content, buffers = _unpack(scene.widget._saved)
    sent_content, sent_buffers = scene._snapshot_message()
    assert content == json.loads(json.dumps(sent_content))
    assert buffers == [bytes(b) for b in sent_buffers]
    scene.close()
