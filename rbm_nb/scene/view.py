"""The link from a scene to its live view: the widget and what is sent to it.

:class:`ViewLink` owns the scene's :class:`~rbm_nb.scene.widget.SceneWidget`
(created on first use), forwards each change of the content to it
(meshcat commands, new or removed tracks, synced traits) and builds the
content messages a page asks for: the whole scene at once, or a coarse copy
and its chunks for a long recording (see :mod:`rbm_nb.scene.stream`). Nothing
is sent while no view exists.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .._engine.time import TimeBase
from . import stream
from .commands import Message
from .context import SceneContext
from .path_refine import PathRefiner
from .state import SceneState
from .timekeys import seconds_from

if TYPE_CHECKING:  # the widget module needs the notebook extras at import
    from .widget import SceneWidget


class ViewLink:
    """The widget of one scene, and the chunking last sent to it."""

    def __init__(self, context: SceneContext):
        self._context = context
        self.widget: SceneWidget | None = None
        # the chunking last sent to a live view (None: poses went whole)
        self.stream: dict | None = None
        self._generation = 0
        # second 0 of the times last sent (exact: a move by less than a float
        # epoch second's ~0.24 µs still re-bases the view)
        self._sent_base: TimeBase | None = None
        # answers the view's requests for finer paths where it zooms in
        self.path_refiner: PathRefiner | None = None

    def open(
        self,
        time_shown: Callable[[], int | float | None],
        check_frame: Callable,
        handles: Callable[[], dict],
    ) -> SceneWidget:
        """Create the widget (once). ``time_shown()`` is the scene's time as
        a key (where a stream starts); ``check_frame(name, trait)``
        what ``selected`` and ``follow`` accept; ``handles()`` the objects by
        name, whose paths the view may ask for finer."""
        if self.widget is None:
            # lazy (optional dependency): the widget needs anywidget
            from .widget import SceneWidget

            max_samples = self._context.max_samples
            self.widget = SceneWidget(
                lambda cap=None: (
                    self.live_snapshot_message(time_shown())
                    if cap is None
                    else self.snapshot_message(min(cap, max_samples or cap))
                ),
                chunk=self.chunk_messages,
                check_frame=check_frame,
            )
            self.path_refiner = PathRefiner(self.widget, handles)
        return self.widget

    def close(self) -> None:
        widget, self.widget = self.widget, None
        if widget is not None:
            widget.close()

    def sync(self, name: str, value) -> None:
        """Set the widget's trait ``name`` (when there is a widget)."""
        if self.widget is not None:
            setattr(self.widget, name, value)

    def emit(self, messages: list[Message]) -> None:
        """Send meshcat commands to the view."""
        if messages and self.widget is not None:
            self.widget.push({"type": "commands"}, [m.data for m in messages])

    def emit_tracks(self, paths: list[str], removed: Sequence[str] = ()) -> None:
        """Send the tracks at ``paths`` (new) and forget those at ``removed``."""
        widget, state = self.widget, self._context.state
        if widget is None or not widget.ready:
            return
        origin = state.origin  # the JS boundary: second 0 as a float epoch second
        if (
            widget._origin != origin  # the time base moved
            or self._sent_base != state.base
            or self.stream is not None  # chunks of the old content are stale
            or stream.streams(state, self._context.max_samples)
        ):
            widget._origin = origin
            widget.send_content()
            return
        sub = SceneState()
        sub.tracks = {p: state.tracks[p] for p in paths}
        meta, buffers = sub.track_payload(
            max_samples=self._context.max_samples, base=state.base
        )
        widget.push(
            {"type": "tracks", "tracks": meta, "remove": list(removed)}, buffers
        )

    def snapshot_message(self, max_samples: int | None = None) -> tuple[dict, list]:
        """The content message that builds the scene in a fresh view."""
        state = self._context.state
        with self._context.lock:
            commands_ = [m.data for m in state.snapshot()]
            self._sent_base = state.base
            meta, buffers = state.track_payload(
                max_samples=max_samples, base=self._sent_base
            )
            offset = len(commands_)
            for entry in meta:
                for key in ("times", "translation", "rotation", "scale"):
                    if entry[key] is not None:
                        entry[key] += offset
            content = {"type": "snapshot", "commands": offset, "tracks": meta}
            return content, commands_ + buffers

    def live_snapshot_message(self, key: int | float | None) -> tuple[dict, list]:
        """The content message for a live view showing time ``key``: poses
        whole, or a coarse copy and the chunking when they are long."""
        context = self._context
        with context.lock:
            if not stream.streams(context.state, context.max_samples):
                self.stream = None
                return self.snapshot_message(context.max_samples)
            content, buffers = self.snapshot_message(stream.COARSE_SAMPLES)
            at = None
            if key is not None:
                at = float(seconds_from(context.state.base, np.array([key]))[0])
            self._generation += 1
            self.stream = stream.plan(context.state, at, self._generation)
            content["stream"] = self.stream
            return content, buffers

    def chunk_messages(self, content: dict) -> list[tuple[dict, list]]:
        """Answers to a browser's request for chunks (one message per chunk).

        A request for content that changed since (an older generation) gets
        the chunks of the current content, which the page then keeps.
        """
        with self._context.lock:
            plan = self.stream
            if plan is None:
                return []
            answers = []
            for index in stream.requested_chunks(content, plan["count"]):
                meta, buffers = self._context.state.track_chunk(index, plan["chunk"])
                head = {
                    "type": "chunk",
                    "index": index,
                    "generation": plan["generation"],
                    "tracks": meta,
                }
                answers.append((head, buffers))
            return answers
