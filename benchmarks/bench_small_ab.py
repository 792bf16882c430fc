"""Small calls and bench_core's workload, this tree against another, in CPU time.

Like ``bench_core_ab.py`` (alternating fresh processes, one thread, best of
each), but timed with the thread's CPU clock (``time.thread_time``), which a
machine shared with other jobs disturbs far less than the wall clock, and
with the two small calls of issue 32 item 8 added: a one-point static
``transform_points`` and a one-time ``lookup_transform`` through the
head/eye chain (each timed over a batch of calls).

Run:  .venv/bin/python benchmarks/bench_small_ab.py OTHER_TREE [--rounds 4]
"""

from __future__ import annotations

from bench_core_ab import compare

CHILD = """
import os, sys, time
os.environ["RBM_NB_NUM_THREADS"] = "1"
sys.path.insert(0, {benchmarks!r})
import numpy as np
import bench_core
import rbm_nb as rbm
frames, head_ts, eye_ts, head_rot, gaze = bench_core.build_workload()
rbm.clear_registry()
for name, kwargs in frames:
    rbm.register_frame(name, **kwargs)
rbm.register_frame("s1", parent="world", translation=[1.0, 2, 3], rotation=[1.0, 0, 0, 0])
rbm.register_frame("s2", parent="s1", translation=[0.5, 0, 0])
point = np.array([0.1, 0.2, 0.3])
when = head_ts[1000]
ops = {{
    "static transform_points, 1 point (us)": (
        lambda: rbm.transform_points(point, "world", "s2"), 2000, 1e6),
    "lookup_transform left_eye, 1 time (us)": (
        lambda: rbm.lookup_transform("left_eye", "world", time=when), 300, 1e6),
    "lookup_transform left_eye->world (ms)": (
        lambda: rbm.lookup_transform("left_eye", "world"), 1, 1e3),
    "transform_points (eye times) (ms)": (
        lambda: rbm.transform_points(gaze, "world", "left_eye", timestamps=eye_ts),
        1, 1e3),
    "transform_vectors (head times) (ms)": (
        lambda: rbm.transform_vectors(
            gaze[:66_629], "world", "left_eye", timestamps=head_ts), 1, 1e3),
    "lookup_twist head wrt world (ms)": (
        lambda: rbm.lookup_twist("head", "world"), 1, 1e3),
    "lookup_angular_velocity left_eye (ms)": (
        lambda: rbm.lookup_angular_velocity("left_eye", "world"), 1, 1e3),
}}
for label, (call, batch, unit) in ops.items():
    call()
    times = []
    for _ in range(15):
        t0 = time.thread_time()
        for _ in range(batch):
            call()
        times.append((time.thread_time() - t0) / batch)
    print(f"{{label}}\\t{{min(times) * unit:.4f}}")
"""


if __name__ == "__main__":
    compare(__doc__.split("\n\n")[0], CHILD, "call (best CPU time)", unit="")
