"""How a long recording's poses go to the browser: in chunks around the playhead.

A scene whose poses would take more than :data:`STREAM_ABOVE` bytes does not
send them with its content. The content message carries a coarse copy of
every track instead (:data:`COARSE_SAMPLES` samples each, evenly spaced) and
the chunking: chunk ``k`` holds every sample of every track for the browser
times ``[k, k + 1) * chunk_seconds`` (:meth:`SceneState.track_chunk`). The
browser asks for the chunks at and ahead of the playhead, drops those behind
it, and where a chunk has not arrived yet (a busy kernel, a jump) shows the
coarse pose: its clock never waits for the kernel. What is sent before the
first frame is the same at any length; the rest follows the playhead.
"""

from __future__ import annotations

import math

import numpy as np

# samples per track in the coarse copy sent with a streamed scene's content
# (defined with the tracks, which gather it when they are summarised)
from .looked_up import COARSE_SAMPLES  # noqa: F401 (documented here)
from .state import SceneState

#: bytes of poses above which a scene streams them (below: one message, as before)
STREAM_ABOVE = 2_000_000
#: bytes per chunk aimed at (all tracks): the chunk's length in seconds follows
CHUNK_BYTES = 400_000
#: bounds of a chunk's length in seconds
CHUNK_SECONDS = (1.0, 60.0)
#: chunks one browser request may ask for
MAX_REQUEST = 16


def streams(state: SceneState, max_samples: int | None) -> bool:
    """Whether a live view gets this scene's poses in chunks.

    Not with ``max_samples`` (the user bounded the samples sent at once).
    """
    return max_samples is None and state.payload_bytes() > STREAM_ABOVE


def chunk_seconds(state: SceneState) -> float:
    """Length of a chunk: :data:`CHUNK_BYTES` of all tracks, within :data:`CHUNK_SECONDS`."""
    rate = state.bytes_per_second()
    low, high = CHUNK_SECONDS
    if rate <= 0:
        return high
    return float(min(max(CHUNK_BYTES / rate, low), high))


def plan(state: SceneState, at: float | None, generation: int) -> dict:
    """The ``stream`` entry of a content message (see scene.js).

    ``at`` is the time shown (seconds from the scene's origin), None for
    the start: the chunks there and after go right after the content.
    """
    seconds = chunk_seconds(state)
    count = state.chunk_count(seconds)
    first = 0 if at is None or not math.isfinite(at) else int(at // seconds)
    first = min(max(first, 0), count - 1)
    return {
        "chunk": seconds,
        "count": count,
        "generation": generation,
        "first": [k for k in (first, first + 1) if k < count],
    }


def requested_chunks(content: dict, count: int) -> list[int]:
    """The chunk indices of a browser's ``chunks`` request that exist.

    The browser owns nothing here: anything but whole indices in
    ``[0, count)`` is ignored, and at most :data:`MAX_REQUEST` are served.
    """
    indices = content.get("indices")
    if not isinstance(indices, list):
        return []
    out: list[int] = []
    for value in indices[:MAX_REQUEST]:
        if (
            isinstance(value, (int, np.integer))
            and not isinstance(value, bool)
            and 0 <= value < count
            and int(value) not in out
        ):
            out.append(int(value))
    return out
