"""What a scene contains, as plain data: no widget, no transport.

:class:`SceneState` holds the meshcat commands that build the scene (objects,
fixed transforms, properties) by path, the pose tracks of everything that
moves, and the time base they share. The :class:`~rbm_nb.scene.Scene` facade
changes it and forwards each change to whatever shows it (the notebook
widget, an HTML export); tests check it directly.

Paths follow meshcat's tree (``/rbm/root/<name>/pose/geom``); a track's pose
is the transform of its node relative to its parent node.

Times are exact keys (:mod:`rbm_nb.scene.timekeys`): the timeline, second 0
(:attr:`SceneState.base`), pins, chunk boundaries and every search. Float
seconds are made only where tracks are packed for the browser, counted
from second 0 by int64 subtraction.
"""

from __future__ import annotations

import math

import numpy as np
import umsgpack

from .._engine.time import TimeBase, check_compatible
from . import commands
from .commands import Message, TransformPacker
from .looked_up import even_rows
from .timekeys import base_of, key_after, seconds_from
from .tracks import SceneTrack, duration, moving_span

ROOT = "/rbm"


def _under(path: str, prefix: str) -> bool:
    return path == prefix or path.startswith(prefix + "/")


class SceneState:
    """The content of a scene and its poses over time.

    Attributes
    ----------
    objects : dict of str to Message
        ``set_object`` commands by path.
    statics : dict of str to Message
        ``set_transform`` commands of nodes that do not move, by path.
    properties : dict of (str, str) to Message
        ``set_property`` commands by (path, property).
    tracks : dict of str to PoseTrack or LookedUpTrack
        Poses over time of the nodes that move, by path.
    pins : dict of str to int or float
        Nodes shown at their own time (a key) instead of the scene's (what
        the publishers do).
    kind : {"datetime64", "timedelta64", "numeric"} or None
        How the tracks' timestamps were given (None while nothing moves).
    """

    def __init__(self):
        self.objects: dict[str, Message] = {}
        self.statics: dict[str, Message] = {}
        self.properties: dict[tuple[str, str], Message] = {}
        self.tracks: dict[str, SceneTrack] = {}
        self.pins: dict[str, int | float] = {}
        self.kind: str | None = None

    # -- changes --------------------------------------------------------------------
    def set_object(self, path: str, obj) -> Message:
        message = commands.set_object(path, obj)
        self.objects[path] = message
        return message

    def set_static(self, path: str, matrix: np.ndarray) -> Message:
        message = TransformPacker(path).message(matrix)
        self.statics[path] = message
        return message

    def set_property(self, path: str, key: str, value) -> Message:
        message = commands.set_property(path, key, value)
        self.properties[(path, key)] = message
        return message

    def add_track(self, path: str, track: SceneTrack, what: str = "scene") -> None:
        """Make the node at ``path`` follow ``track`` (a moving one)."""
        if track.static:
            raise ValueError(f"{what}: the track of {path!r} does not move")
        check_compatible([self.kind, track.kind], what)
        self.kind = track.kind
        self.tracks[path] = track

    def delete(self, path: str) -> Message:
        """Forget everything at or below ``path``."""
        for table in (self.objects, self.statics, self.tracks, self.pins):
            for key in [k for k in table if _under(k, path)]:
                del table[key]
        for prop in [k for k in self.properties if _under(k[0], path)]:
            del self.properties[prop]
        if not self.tracks:
            self.kind = None
        return commands.delete(path)

    # -- what a viewer needs ------------------------------------------------------------
    def snapshot(self) -> list[Message]:
        """Commands that build the scene from nothing (its moving poses aside)."""
        messages = [commands.delete(ROOT)]
        messages += self.objects.values()
        messages += self.statics.values()
        messages += self.properties.values()
        return messages

    def timeline(self) -> tuple[np.ndarray, np.ndarray | None] | None:
        """The scene's time axis as exact keys, and as given when shared.

        When every track has the same timestamps these are the axis; else a
        regular grid from the earliest to the latest sample at the finest
        mean sampling interval (ns keys: rounded to the ns). None when
        nothing moves.
        """
        tracks = list(self.tracks.values())
        if not tracks:
            return None
        # the axis is the player's (kept by it): made on request, not kept
        # here (an hour of the explorer's recording: 10 MB)
        # tracks of different lengths cannot share their timestamps: their
        # keys (a whole-recording array each) are made only when they might
        if all(len(t) == len(tracks[0]) for t in tracks):
            times = [t.sample_keys() for t in tracks]  # moving tracks only
            first = times[0]
            if all(s is first or np.array_equal(s, first) for s in times):
                return first, tracks[0].original_timestamps
        spans = [moving_span(t) for t in tracks]
        start = min(first for first, _ in spans)
        end = max(last for _, last in spans)
        steps = [
            (last - first) / (len(t) - 1)
            for t, (first, last) in zip(tracks, spans, strict=True)
            if len(t) > 1 and last > first
        ]
        if not steps or end <= start:
            return np.unique(np.concatenate([t.sample_keys() for t in tracks])), None
        n = int(np.ceil((end - start) / min(steps) - 1e-9)) + 1
        if self.kind == "numeric":
            return np.linspace(start, end, n), None
        # ns keys: the grid's steps counted from the first key (a span of
        # up to 104 days is exact in float64 ns), each rounded to the ns
        offsets = np.round(np.linspace(0.0, float(end - start), n)).astype(np.int64)
        return start + offsets, None

    def span(self) -> tuple[int | float, int | float] | None:
        """Keys of the earliest and the latest sample (None while nothing
        moves): the ends of :meth:`timeline`, without making it."""
        if not self.tracks:
            return None
        spans = [moving_span(t) for t in self.tracks.values()]
        return min(s for s, _ in spans), max(e for _, e in spans)

    @property
    def base(self) -> TimeBase:
        """The scene's second 0: its earliest sample (0.0 while nothing moves)."""
        # the earliest sample (the timeline's first time), without the timeline
        span = self.span()
        return base_of(None if span is None else span[0], self.kind)

    @property
    def origin(self) -> float:
        """Second 0 as float data seconds (epoch seconds for datetime data).

        For the browser only (the widget's ``_origin``, which the player
        link falls back on without ``_player_shift``) and callers that
        asked for a float; ~0.24 µs
        coarse at today's epochs. Everything in the kernel counts from
        :attr:`base`.
        """
        return self.base.origin

    def pose_at(self, path: str, key: int | float) -> np.ndarray | None:
        """The (4, 4) transform of the node at ``path`` at time ``key``.

        Pinned nodes use their own time. None when the node is hidden because
        its track has not started yet or its sample there is missing. A node neither static nor moving is at
        the identity.
        """
        track = self.tracks.get(path)
        if track is None:
            return self.static_pose(path)
        index = track.index_at(self.pins.get(path, key))
        if index < 0 or track.missing(index):
            return None
        return track.matrix(index)

    def static_pose(self, path: str) -> np.ndarray:
        """The (4, 4) transform of the node at ``path``, which does not move.

        A node without a fixed transform is at the identity.
        """
        message = self.statics.get(path)
        if message is None:
            return np.eye(4)
        matrix = umsgpack.unpackb(message.data)["matrix"]
        return np.asarray(matrix, dtype=float).reshape(4, 4).T

    def world_pose(self, path: str, key: int | float) -> np.ndarray | None:
        """Transform of ``path`` into the scene's base at time ``key`` (product along the tree)."""
        parts = path.strip("/").split("/")
        matrix = np.eye(4)
        for i in range(1, len(parts) + 1):
            node = "/" + "/".join(parts[:i])
            pose = self.pose_at(node, key)
            if pose is None:
                return None
            matrix = matrix @ pose
        return matrix

    def track_payload(
        self, max_samples: int | None = None, base: TimeBase | None = None
    ) -> tuple[list[dict], list[bytes]]:
        """The tracks as binary buffers for a viewer.

        Times are float64 seconds from ``base`` (the scene's second 0 by
        default), counted from the exact keys;
        translations, rotations ``(x, y, z, w)`` (three.js order) and scales
        are float32 (a float32 coordinate 1 km from the origin is within
        0.06 mm: invisible on screen). Tracks with equal timestamps share one
        time buffer.

        Parameters
        ----------
        max_samples : int, optional
            Keep at most this many samples per track (evenly spaced, the last
            one kept). All samples by default.

        Returns
        -------
        meta : list of dict
            ``{"path", "times", "translation", "rotation", "scale"}`` with
            buffer indices (``scale`` may be None).
        buffers : list of bytes
        """
        base = self.base if base is None else base
        # a looked-up track without max_samples looks every sample up now (a
        # short recording: a long one streams, see scene/stream.py)
        picks = [
            (path, track, _decimate(len(track), max_samples))
            for path, track in self.tracks.items()
        ]
        return _pack(picks, base)

    def bytes_per_second(self) -> float:
        """Bytes of the packed tracks per second of recording (all tracks)."""
        total = 0.0
        for track in self.tracks.values():
            span = duration(track)
            if span > 0:
                total += _sample_bytes(track) * (len(track) - 1) / span
        return total

    def payload_bytes(self) -> int:
        """Bytes of every sample of every track, as :meth:`track_payload` packs them."""
        return sum(_sample_bytes(t) * len(t) for t in self.tracks.values())

    def chunk_count(self, chunk_seconds: float) -> int:
        """How many chunks of ``chunk_seconds`` cover the tracks from second 0."""
        span = self.span()
        if span is None:
            return 1
        end = float(seconds_from(self.base, np.array([span[1]]))[0])
        return int(math.floor(max(end, 0.0) / chunk_seconds)) + 1

    def track_chunk(
        self, index: int, chunk_seconds: float
    ) -> tuple[list[dict], list[bytes]]:
        """Every sample of every track for browser times in one chunk.

        Chunk ``index`` serves the times ``[index, index + 1) * chunk_seconds``
        (seconds from second 0): it holds the samples inside that span and
        the last one at or before its start, so the latest sample at or
        before any time in the span is in the chunk, and the pose shown at a
        chunk's boundary is the recording's own. Slices of the tracks (views)
        are converted as :meth:`track_payload` does; tracks looked up from
        frames look the chunk's samples up now (they keep none).
        """
        base = self.base
        # the span's ends as keys: searched exactly, whatever the epoch
        start = key_after(base, index * chunk_seconds)
        end = key_after(base, (index + 1) * chunk_seconds + CHUNK_SLACK)
        picks = []
        for path, track in self.tracks.items():
            lo = max(track.search(start, side="right") - 1, 0)
            # the browser looks up t + 1e-6 (scene.js): a sample that close
            # after the span's end is shown inside it
            hi = track.search(end, side="right")
            picks.append((path, track, slice(lo, max(hi, lo))))
        return _pack(picks, base)


#: seconds past a chunk's end still served with it (scene.js looks up t + 1e-6)
CHUNK_SLACK = 1e-5


def _sample_bytes(track: SceneTrack) -> int:
    """Bytes per packed sample: time, xyz and xyzw (and scale)."""
    return 8 + 12 + 16 + (4 if track.scale is not None else 0)


def _pack(picks, base: TimeBase) -> tuple[list[dict], list[bytes]]:
    """Pack ``(path, track, index or slice or None)`` as buffers (see ``track_payload``)."""
    meta: list[dict] = []
    buffers: list[bytes] = []
    shared: list[tuple[np.ndarray, int]] = []
    for path, track, index in picks:
        keys, translation, rotation, scale = track.take(index)
        times = None
        for known, at in shared:
            if known is keys or (
                known.shape == keys.shape and np.array_equal(known, keys)
            ):
                times = at
                break
        if times is None:
            times = len(buffers)
            # the JS boundary: float seconds from second 0, counted exactly
            buffers.append(
                np.ascontiguousarray(seconds_from(base, keys), dtype="<f8").tobytes()
            )
            shared.append((keys, times))
        entry = {"path": path, "times": times, "n": int(len(keys))}
        entry["translation"] = len(buffers)
        buffers.append(translation.astype("<f4").tobytes())
        xyzw = rotation[:, [1, 2, 3, 0]]
        entry["rotation"] = len(buffers)
        buffers.append(np.ascontiguousarray(xyzw, dtype="<f4").tobytes())
        entry["scale"] = None
        if scale is not None:
            entry["scale"] = len(buffers)
            buffers.append(scale.astype("<f4").tobytes())
        meta.append(entry)
    return meta, buffers


def _decimate(n: int, max_samples: int | None) -> np.ndarray | None:
    if max_samples is None or n <= max_samples:
        return None
    if max_samples < 2:
        raise ValueError(f"max_samples must be at least 2, got {max_samples}")
    return even_rows(n, max_samples)
