"""Speed of the notebook layer on the synthetic 5.5-minute head/eye recording.

Prints a table:

* the time to add 10 frames, 1 path and 2 gaze vectors (one lookup each);
* the content message a browser gets when the view opens (built once, sent
  once): time to build and bytes, all samples and decimated;
* what the kernel does per seek from Python now that the browser plays
  (a trait update: no pose data);
* size and time of ``Scene.to_html`` for the recording.

Run: ``.venv/bin/python benchmarks/bench_scene.py``
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

import rbm_nb as rbm
from rbm_nb.app.explorer import register_head_eye_frames
from rbm_nb.data import synthetic_head_eye
from rbm_nb.scene import Scene
from rbm_nb.widgets import Player

FRAMES = (
    "world",
    "t265/world",
    "t265/tracker",
    "head",
    "nose",
    "pupil/scene_cam",
    "pupil/left_eye",
    "left_eye",
    "pupil/right_eye",
    "right_eye",
)


def register_head_eye(recording) -> None:
    """The frame tree of the ROS guide (1.6) plus a static 'nose' on the head."""
    register_head_eye_frames(
        recording.head, recording.left_eye, recording.right_eye, ros_eyes=True
    )
    rbm.register_frame("nose", parent="head", translation=(0.1, 0.0, -0.05))


def build_scene() -> Scene:
    scene = Scene("world")
    for name in FRAMES:
        scene.add_frame(name, scale=0.3)
    scene.add_path("head", color="#ff00ff")
    scene.add_vectors("left_eye", (1, 0, 0), length=3.0, color="#ffff00")
    scene.add_vectors("right_eye", (1, 0, 0), length=3.0, color="#00ffff")
    return scene


def row(name: str, value: str) -> None:
    print(f"| {name:<58} | {value:>22} |")


def main() -> None:
    import comm

    class CountingComm:
        """A comm that counts what the kernel would send (no browser needed)."""

        kernel = "Truthy"

        def __init__(self, *args, **kwargs):
            import uuid

            self.comm_id = uuid.uuid4().hex
            self.bytes = 0

        def open(self, *args, **kwargs):
            pass

        def on_msg(self, *args, **kwargs):
            pass

        def close(self, *args, **kwargs):
            pass

        def send(self, data=None, metadata=None, buffers=None):
            self.bytes += len(str(data)) + sum(len(b) for b in buffers or [])

    comm.create_comm = lambda **kwargs: CountingComm()
    t0 = time.perf_counter()
    recording = synthetic_head_eye()
    t_data = time.perf_counter() - t0
    register_head_eye(recording)
    t0 = time.perf_counter()
    scene = build_scene()
    t_add = time.perf_counter() - t0
    print(
        f"\nscene: {len(FRAMES)} frames, 1 path, 2 gaze vectors; "
        f"{len(scene.state.tracks)} moving nodes; player axis {len(scene.timestamps)} samples"
    )
    print(f"| {'measurement':<58} | {'value':>22} |")
    print(f"|{'-' * 60}|{'-' * 24}|")
    row("synthetic_head_eye() (330 s, not rbm_nb.scene)", f"{t_data:.2f} s")
    row("add 10 frames + path + 2 vectors (lookups included)", f"{t_add * 1e3:.0f} ms")
    for max_samples in (None, 10000):
        t0 = time.perf_counter()
        content, buffers = scene._snapshot_message(max_samples=max_samples)
        dt = time.perf_counter() - t0
        size = sum(len(b) for b in buffers)
        label = "all samples" if max_samples is None else f"<= {max_samples} per track"
        row(
            f"content message ({label}): build / size",
            f"{dt * 1e3:.0f} ms / {size / 1e6:.2f} MB",
        )
    row(
        "scene widget module (meshcat viewer + scene.js)",
        f"{len(scene.widget._esm) / 1e6:.2f} MB",
    )

    player = Player(scene)
    player.link(scene)
    before = player.comm.bytes + scene.widget.comm.bytes
    n = 2000
    t0 = time.perf_counter()
    for i in np.random.default_rng(0).integers(0, player.n, n):
        player.seek(int(i))
    dt = (time.perf_counter() - t0) / n
    sent = (player.comm.bytes + scene.widget.comm.bytes - before) / n
    row(
        "Player.seek from Python: time / bytes sent",
        f"{dt * 1e6:.0f} us / {sent:.0f} B",
    )

    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            out = scene.to_html(Path(tmp) / "head_eye.html", max_frames=10000)
            times.append(time.perf_counter() - t0)
        size = out.stat().st_size
    row(
        "to_html (max_frames=10000): first / best of 3",
        f"{times[0]:.2f} / {min(times):.2f} s",
    )
    row("to_html size", f"{size / 1e6:.2f} MB")
    player.close()
    scene.close()
    import ipywidgets

    ipywidgets.Widget.close_all()  # before the interpreter tears down their comms


if __name__ == "__main__":
    main()
