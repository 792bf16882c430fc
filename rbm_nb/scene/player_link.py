"""The time a scene shows: its own, or a linked player's.

Without a player the kernel keeps the time shown (``Scene.set_time``) and
tells the view. With one, the player owns the time: its clock runs in the
browser, the view follows it there, and ``set_time`` moves the player.
Publishers pin single objects to their own time until a time is set for the
whole scene again.

Times are kept as exact keys (:mod:`rbm_nb.scene.timekeys`); a float epoch
second given by the user becomes a key once, in :meth:`PlayerLink.set_time`,
and :attr:`PlayerLink.time` hands one back.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._engine.time import check_compatible, key_seconds, time_key
from .context import SceneContext
from .timekeys import KEYS_PER_SECOND, seconds_from
from .view import ViewLink


class PlayerLink:
    """The time shown by one scene (``time``) and its player (``player``)."""

    def __init__(self, context: SceneContext, view: ViewLink):
        self._context = context
        self._view = view
        self.player = None
        # the key set_time kept (int ns or float s), shown without a player
        self.own_key: int | float | None = None

    @property
    def own_time(self) -> float | None:
        """What set_time kept, as float data seconds (epoch seconds for datetime data)."""
        if self.own_key is None:
            return None
        return key_seconds(self.own_key, self._context.state.kind)

    @property
    def time(self) -> float | None:
        """The time shown (float seconds): the player's as the kernel last
        learned it, else the scene's own; None before any was set."""
        if self.player is not None:
            return self.player.data_time
        return self.own_time

    def time_key(self) -> int | float | None:
        """The time shown as an exact key: the player's (from its second 0
        and its time), else the scene's own; None before any was set."""
        if self.player is not None:
            return time_key(self.player.time_value, self._context.state.kind)
        return self.own_key

    def timestamps(self):
        """Time axis for playback (see :attr:`Scene.timestamps`)."""
        state = self._context.state
        timeline = state.timeline()
        if timeline is None:
            return None
        keys, original = timeline
        if original is not None:
            return original
        if state.kind in ("datetime64", "timedelta64"):
            return np.asarray(keys, dtype=np.int64).view(f"{state.kind}[ns]")
        return keys

    def set_time(self, t) -> None:
        """Show ``t`` (see :meth:`Scene.set_time`)."""
        context = self._context
        context.check_open()
        state = context.state
        # where a time enters: a datetime64 exactly, a float epoch second
        # rounded to the ns once (NaN, inf and NaT refused, naming t)
        key = time_key(t, state.kind, "Scene.set_time: t")
        span = state.span()
        if span is not None and self.player is None:
            # after the last sample every object stays as it was then, and
            # before the first all moving ones are hidden: times beyond show
            # nothing new, so 1e300 s is kept to the span (and one span before)
            start, end = span
            one_second = KEYS_PER_SECOND[state.kind or "numeric"]
            key = min(max(key, start - max(end - start, one_second)), end)
        with context.lock:
            self.own_key = key
            self._unpin()
            if self.player is not None:
                self.player.seek_time(self._value(key))
            else:
                self._view.sync("time", self._seconds(key))

    def _value(self, key: int | float):
        """``key`` in the data's kind (a datetime64[ns] exact to the ns)."""
        kind = self._context.state.kind
        if kind in ("datetime64", "timedelta64"):
            return np.array(key, dtype=np.int64).view(f"{kind}[ns]")[()]
        return key

    def _seconds(self, key: int | float) -> float:
        """``key`` as seconds from the scene's second 0 (for the browser)."""
        return float(seconds_from(self._context.state.base, np.array([key]))[0])

    def publish(self, idx: int | None) -> None:
        """Show sample ``idx`` of the time axis (the first by default)."""
        self._context.check_open()
        timeline = self._context.state.timeline()
        if timeline is None:
            return
        keys = timeline[0]
        idx = 0 if idx is None else int(idx)
        if not -len(keys) <= idx < len(keys):
            raise IndexError(f"Scene.publish: idx {idx} outside [0, {len(keys) - 1}]")
        self.set_time(self._value(keys[idx].item()))

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
        if self.own_key is not None:
            player.seek_time(self._value(self.own_key))
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
        self._view.sync("_player_shift", self.player_shift())
        self._view.sync("player", player)

    def detach(self, player) -> None:
        if self.player is player:
            self.player = None
            self._view.sync("player", None)
            self._view.sync("_player_shift", None)

    def player_shift(self) -> float | None:
        """:meth:`shift_to` the linked player (None: no player)."""
        return self.shift_to(self.player)

    def shift_to(self, player: Any) -> float | None:
        """Seconds from the scene's second 0 to ``player``'s.

        The JS boundary of the player link: the view shows this plus the
        player's ``time``. Counted from the two int64 ns keys (exact), not
        from the two float epoch seconds the browser has (``_origin`` and the
        player's ``origin``, ~0.24 µs coarse each). None without a player
        (or one with no time base).
        """
        timebase = getattr(player, "timebase", None)
        if player is None or timebase is None:
            return None
        state = self._context.state
        if not state.tracks:
            return float(player.origin) - state.origin
        return timebase.shift_to(state.base)

    def show_in(self, widget) -> None:
        """Give a new view the player, or the time shown."""
        if self.player is not None:
            widget._player_shift = self.player_shift()
            widget.player = self.player
        elif self.own_key is not None:
            widget.time = self._seconds(self.own_key)

    def pins(self) -> dict[str, float]:
        """The widget's ``_pins``: pinned nodes' times as seconds from second 0."""
        state = self._context.state
        if not state.pins:
            return {}
        paths = list(state.pins)
        seconds = seconds_from(state.base, np.array([state.pins[p] for p in paths]))
        return dict(zip(paths, seconds.tolist(), strict=True))

    def pin(self, path: str, key: int | float) -> None:
        """Show the node at ``path`` at its own time ``key`` (publishers)."""
        with self._context.lock:
            self._context.state.pins[path] = key
            self._view.sync("_pins", self.pins())

    def pin_sample(self, path: str, index: int) -> int | float | None:
        """Show the node at ``path`` at sample ``index`` of its own track; its
        time (a key), or None when it does not move."""
        self._context.check_open()
        track = self._context.state.tracks.get(path)
        if track is None:
            return None
        key = track.keys_of([index])[0].item()
        self.pin(path, key)
        return key

    def _unpin(self) -> None:
        if self._context.state.pins:
            self._context.state.pins.clear()
            self._view.sync("_pins", self.pins())
