"""The time a scene shows: its own, or a linked player's.

Without a player the kernel keeps the time shown (``Scene.set_time``) and
tells the view. With one, the player owns the time: its clock runs in the
browser, the view follows it there, and ``set_time`` moves the player.
Publishers pin single objects to their own time until a time is set for the
whole scene again.
"""

from __future__ import annotations

import math

from .._engine.time import check_compatible, epoch_seconds, from_epoch_seconds
from .context import SceneContext
from .view import ViewLink


class PlayerLink:
    """The time shown by one scene (``time``) and its player (``player``)."""

    def __init__(self, context: SceneContext, view: ViewLink):
        self._context = context
        self._view = view
        self.player = None
        self.own_time: float | None = None  # what set_time kept, without a player

    @property
    def time(self) -> float | None:
        """The time shown (float seconds): the player's as the kernel last
        learned it, else the scene's own; None before any was set."""
        if self.player is not None:
            return self.player.data_time
        return self.own_time

    def timestamps(self):
        """Time axis for playback (see :attr:`Scene.timestamps`)."""
        state = self._context.state
        timeline = state.timeline()
        if timeline is None:
            return None
        seconds, original = timeline
        if original is not None:
            return original
        if state.kind is not None:
            return from_epoch_seconds(seconds, state.kind)
        return seconds

    def set_time(self, t) -> None:
        """Show ``t`` (see :meth:`Scene.set_time`)."""
        context = self._context
        context.check_open()
        state = context.state
        seconds = epoch_seconds(t, state.kind, "Scene.set_time: t")
        if not math.isfinite(seconds):
            raise ValueError(f"Scene.set_time: t must be finite, got {t!r}")
        span = state.span()
        if span is not None and self.player is None:
            # after the last sample every object stays as it was then, and
            # before the first all moving ones are hidden: times beyond show
            # nothing new, so 1e300 s is kept to the span (and one span before)
            start, end = span
            seconds = min(max(seconds, start - max(end - start, 1.0)), end)
        with context.lock:
            self.own_time = seconds
            self._unpin()
            if self.player is not None:
                self.player.seek_time(seconds)
            else:
                self._view.sync("time", seconds - state.origin)

    def publish(self, idx: int | None) -> None:
        """Show sample ``idx`` of the time axis (the first by default)."""
        self._context.check_open()
        timeline = self._context.state.timeline()
        if timeline is None:
            return
        seconds = timeline[0]
        idx = 0 if idx is None else int(idx)
        if not -len(seconds) <= idx < len(seconds):
            raise IndexError(
                f"Scene.publish: idx {idx} outside [0, {len(seconds) - 1}]"
            )
        self.set_time(float(seconds[idx]))

    def new_player(self, scene, step, speed, skip, loop: bool):
        """A Player over ``scene``'s time axis, linked to it."""
        context = self._context
        context.check_open()
        if not context.state.tracks:
            raise ValueError(
                f"Scene {context.name!r} has no moving objects, there is nothing to play; "
                "add a moving frame first"
            )
        # lazy (optional dependency): the Player needs anywidget
        from ..widgets.player import Player

        player = Player(scene, step=step, speed=speed, skip=skip, loop=loop)
        if self.own_time is not None:
            player.seek_time(self.own_time)
        player.link(scene)
        return player

    def attach(self, player) -> None:
        """Follow ``player`` (``Player.link`` calls ``Scene._attach_player``)."""
        context = self._context
        context.check_open()
        check_compatible(
            [context.state.kind, player.timestamps_kind],
            f"link(Scene {context.name!r})",
        )
        self.player = player
        self._unpin()  # the player drives everything from now on
        self._view.sync("player", player)

    def detach(self, player) -> None:
        if self.player is player:
            self.player = None
            self._view.sync("player", None)

    def show_in(self, widget) -> None:
        """Give a new view the player, or the time shown."""
        if self.player is not None:
            widget.player = self.player
        elif self.own_time is not None:
            widget.time = self.own_time - self._context.state.origin

    def pins(self) -> dict[str, float]:
        """The widget's ``_pins``: pinned nodes' times from the scene's origin."""
        state = self._context.state
        return {path: t - state.origin for path, t in state.pins.items()}

    def pin(self, path: str, seconds: float) -> None:
        """Show the node at ``path`` at its own time ``seconds`` (publishers)."""
        with self._context.lock:
            self._context.state.pins[path] = float(seconds)
            self._view.sync("_pins", self.pins())

    def pin_sample(self, path: str, index: int) -> float | None:
        """Show the node at ``path`` at sample ``index`` of its own track; its
        time, or None when it does not move."""
        self._context.check_open()
        track = self._context.state.tracks.get(path)
        if track is None:
            return None
        seconds = float(track.seconds_of([index])[0])
        self.pin(path, seconds)
        return seconds

    def _unpin(self) -> None:
        if self._context.state.pins:
            self._context.state.pins.clear()
            self._view.sync("_pins", self.pins())
