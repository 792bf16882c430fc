"""A track holding a whole lookup holds one copy of its poses (issue 35).

Measured with tracemalloc (allocations, not time): a track made of a whole
lookup (``PoseTrack.looked_up_whole``, the reference the scene's per-window
tracks are tested against) keeps the lookup's arrays, marking missing rows
in them, instead of copying them (which held two copies at the peak).
"""

from __future__ import annotations

import tracemalloc

import numpy as np

import rbm_nb as rbm
from rbm_nb.scene.tracks import PoseTrack


def register_walk(n: int) -> None:
    rng = np.random.default_rng(1)
    rbm.register_frame("world")
    # a fixed mount between them: the lookup composes (fresh arrays)
    rbm.register_frame("mount", parent="world", translation=(1.0, 0.0, 0.5))
    t = np.cumsum(rng.normal(scale=0.01, size=(n, 3)), axis=0)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    t[::50] = np.nan  # missing samples (blinks)
    q[::50] = np.nan
    ts = np.datetime64("2024-01-01") + np.arange(n) * np.timedelta64(5, "ms")
    rbm.ReferenceFrame(
        "walker", parent="mount", translation=t, rotation=q, timestamps=ts
    ).register()


def test_track_of_a_lookup_keeps_the_lookup_arrays():
    n = 400_000  # 2,000 s at 200 Hz: 22 MB of poses
    register_walk(n)
    frame, base = rbm.registry["walker"], rbm.registry["world"]
    PoseTrack.looked_up_whole(frame, base)  # kernels and caches warm
    tracemalloc.start()
    track = PoseTrack.looked_up_whole(frame, base)
    kept, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    poses = track.translation.nbytes + track.rotation.nbytes
    assert np.isnan(track.translation[::50]).all()
    assert np.isnan(track.rotation[::50]).all()
    # what the track holds: poses, the timestamps and their exact keys (int64
    # ns: a copy here, the stamps are datetime64[ms]; no float seconds beside)
    own = poses + track.original_timestamps.nbytes + track.sample_keys().nbytes
    assert kept <= own * 1.05 + 1e6
    # one copy of the poses at a time (the lookup's, marked in place), with
    # the masks and time conversions (~1/3 of the poses) as temporaries
    assert peak <= own + poses / 2, (peak / 1e6, own / 1e6)


def test_track_never_marks_arrays_it_does_not_own():
    t = np.zeros((4, 3))
    r = np.tile([1.0, 0.0, 0.0, 0.0], (4, 1))
    t[1, 0] = np.nan
    track = PoseTrack(t, r, timestamps=np.arange(4.0))
    assert np.isnan(track.rotation[1]).all()
    assert not np.isnan(r).any()  # the caller's array is as it was
