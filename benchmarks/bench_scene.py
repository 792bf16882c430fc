"""Speed of the notebook layer on the synthetic 5.5-minute head/eye recording.

Prints a table:

* one Player step on a scene with 10 frames, 1 path and 2 gaze vectors, with
  the scene shown on the viewer server and a websocket client reading (the
  whole path a step takes in the kernel), and without a viewer;
* the time to add those objects (one lookup per object);
* size and time of ``Scene.to_html`` for the recording.

Run: ``.venv/bin/python benchmarks/bench_scene.py``
"""

from __future__ import annotations

import statistics
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

import rbm_nb as rbm
from rbm_nb.data import synthetic_head_eye
from rbm_nb.explorer import register_head_eye_frames
from rbm_nb.scene import Scene, shutdown_server
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


def time_steps(step, indices) -> np.ndarray:
    out = np.empty(len(indices))
    for k, i in enumerate(indices):
        t0 = time.perf_counter()
        step(int(i))
        out[k] = time.perf_counter() - t0
    return out * 1e3


class Reader:
    """A websocket client draining the viewer channel, like a browser would."""

    def __init__(self, url: str):
        import websocket

        self.ws = websocket.create_connection(url, timeout=5)
        self.count = 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        import websocket

        self.ws.settimeout(0.2)
        while not self.stop.is_set():
            try:
                self.ws.recv()
                self.count += 1
            except websocket.WebSocketTimeoutException:
                continue
            except Exception:
                return

    def close(self):
        self.stop.set()
        self.thread.join(timeout=5)
        self.ws.close()


def row(name: str, value: str) -> None:
    print(f"| {name:<58} | {value:>22} |")


def main() -> None:
    t0 = time.perf_counter()
    recording = synthetic_head_eye()
    t_data = time.perf_counter() - t0
    register_head_eye(recording)
    t0 = time.perf_counter()
    scene = build_scene()
    t_add = time.perf_counter() - t0
    n = len(scene.timestamps)
    rng = np.random.default_rng(0)
    indices = rng.integers(0, n, 2000)

    print(
        f"\nscene: {len(FRAMES)} frames, 1 path, 2 gaze vectors; {len(scene._dynamic)} moving nodes; "
        f"player axis {n} samples"
    )
    print(f"| {'measurement':<58} | {'value':>22} |")
    print(f"|{'-' * 60}|{'-' * 24}|")
    row("synthetic_head_eye() (330 s, not rbm_nb.scene)", f"{t_data:.2f} s")
    row("add 10 frames + path + 2 vectors (lookups included)", f"{t_add * 1e3:.0f} ms")

    player = Player(scene, threaded=False)
    player.link(scene)
    time_steps(player.seek, indices[:50])  # warm-up
    offline = time_steps(player.seek, indices)
    row(
        "Player step, no viewer: median / p95",
        f"{np.median(offline):.3f} / {np.percentile(offline, 95):.3f} ms",
    )

    reader = Reader(scene.url.replace("http://", "ws://") + "ws")
    time.sleep(0.5)
    live = time_steps(player.seek, indices)
    time.sleep(0.5)
    reader.close()
    row(
        "Player step, live viewer + websocket client: median / p95",
        f"{np.median(live):.3f} / {np.percentile(live, 95):.3f} ms",
    )
    row("Player step, live viewer: max", f"{live.max():.3f} ms")
    set_time = time_steps(lambda i: scene.set_time(float(player.seconds[i])), indices)
    row("Scene.set_time alone (live): median", f"{np.median(set_time):.3f} ms")
    row("messages read by the websocket client", f"{reader.count}")

    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            out = scene.to_html(Path(tmp) / "head_eye.html")
            times.append(time.perf_counter() - t0)
        size = out.stat().st_size
    row(
        "to_html (max_frames=5000): first / best of 3",
        f"{times[0]:.3f} / {min(times):.3f} s",
    )
    row("to_html size", f"{size / 2**20:.2f} MiB")
    print(
        f"\nstep budget 10 ms: median live step uses {statistics.median(live) / 10 * 100:.1f}% of it"
    )
    player.close()
    scene.close()
    shutdown_server()


if __name__ == "__main__":
    main()
