"""Playback of timestamped data as an ipywidgets control.

A :class:`Player` owns a time axis (the timestamps it was built from) and a
set of linked objects. While playing, a background thread computes from the
wall clock which sample is due and publishes only that one: when a linked
object is slower than the play interval, intermediate samples are skipped
instead of piling up, so pausing stops at once.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import ipywidgets as widgets
import numpy as np
import traitlets

from ._time import check_kinds, format_time, time_as_seconds, timestamps_as_seconds

SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0)

# Widgets in the browser are updated at most this often while playing; linked
# objects still get every step. The frontend cannot show more and every update
# is a message through the kernel.
UI_INTERVAL = 0.05


class _Link:
    """A linked object and how to drive it."""

    def __init__(self, obj: Any, player_kind: str):
        self.obj = obj
        self.set_time = getattr(obj, "set_time", None)
        publish = getattr(obj, "publish", None)
        if not callable(self.set_time):
            self.set_time = None
        if self.set_time is None and not callable(publish):
            raise TypeError(
                f"cannot link {type(obj).__name__}: it needs a set_time(t) or a publish(idx) method"
            )
        self.publish = publish
        self.seconds = None
        kind = getattr(obj, "timestamps_kind", None)
        if self.set_time is None:
            timestamps = getattr(obj, "timestamps", None)
            if timestamps is not None:
                self.seconds, kind = timestamps_as_seconds(
                    timestamps, f"timestamps of the linked {type(obj).__name__}"
                )
        check_kinds(player_kind, kind, f"link({type(obj).__name__})")
        self.last = None

    def show(self, index: int, t: float) -> None:
        if self.set_time is not None:
            self.set_time(t)
            return
        if self.seconds is None:
            idx = index
        else:
            idx = int(np.searchsorted(self.seconds, t, side="right")) - 1
            if idx < 0:  # nothing recorded yet at this time
                return
        if idx != self.last:
            self.publish(idx)
            self.last = idx


def _check_positive_int(value, name: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"Player: {name} must be a positive integer, got {value!r}")


def _resolve_timestamps(source) -> tuple[Any, str]:
    """Timestamps from an array, a frame (or its name) or an object having them."""
    if isinstance(source, str):
        from .. import frames

        if source not in frames.registry:
            raise ValueError(f"Player: no frame named {source!r} is registered")
        source = frames.registry[source]
    frames_mod = sys.modules.get("rbm_nb.frames")
    is_frame = frames_mod is not None and isinstance(source, frames_mod.ReferenceFrame)
    if is_frame or (
        hasattr(source, "timestamps") and not isinstance(source, np.ndarray)
    ):
        name = getattr(source, "name", type(source).__name__)
        timestamps = source.timestamps
        if timestamps is None:
            what = "frame" if is_frame else type(source).__name__
            raise ValueError(
                f"Player: {what} {name!r} is static, it has no timestamps to play"
            )
        return timestamps, f"timestamps of {name!r}"
    if source is None:
        raise ValueError("Player: timestamps must be given, got None")
    return source, "timestamps"


class Player(widgets.VBox):
    """Play/pause, slider, stepping and speed control over a time axis.

    Parameters
    ----------
    timestamps : array_like, shape (n,), or ReferenceFrame, str or object
        The time axis: float seconds or datetime64 values, a moving frame (or
        the name of a registered one) or any object with a ``timestamps``
        attribute (a publisher, a :class:`~rbm_nb.scene.Scene`).
    step : int, default 1
        Index difference between consecutive samples shown while playing.
    speed : float, default 1.0
        Playback speed relative to the recording.
    skip : int, optional
        Samples jumped by the skip buttons; ``10 * step`` by default.
    loop : bool, default False
        Start over at the end instead of stopping.
    max_rate : float, default 100.0
        Upper bound on steps per wall-clock second. Playback time still follows
        the wall clock, faster recordings just show fewer of their samples.
    clock : callable, optional
        Returns the wall-clock time in seconds (``time.monotonic`` by default);
        tests inject their own to be deterministic.
    threaded : bool, default True
        Run playback in a background thread. With False nothing happens on its
        own after :meth:`play`: call :meth:`tick` to advance (tests, custom
        event loops).

    Examples
    --------
    >>> import numpy as np
    >>> player = Player(np.arange(10) * 0.1, step=2)
    >>> round(player.interval, 3)
    0.2
    >>> player.step_forward(); player.index
    2
    """

    index = traitlets.Int(0, help="Index of the sample being shown.")
    playing = traitlets.Bool(False, help="Whether the playback thread is running.")
    speed = traitlets.Float(1.0, help="Playback speed relative to the recording.")
    step = traitlets.Int(1, help="Index difference between consecutive steps.")
    skip = traitlets.Int(10, help="Samples jumped by the skip buttons.")
    loop = traitlets.Bool(False, help="Start over at the end instead of stopping.")

    def __init__(
        self,
        timestamps,
        step: int = 1,
        speed: float = 1.0,
        skip: int | None = None,
        *,
        loop: bool = False,
        max_rate: float = 100.0,
        clock: Callable[[], float] | None = None,
        threaded: bool = True,
    ):
        _check_positive_int(step, "step")
        if skip is not None:
            _check_positive_int(skip, "skip")
        if not (
            isinstance(speed, (int, float, np.number))
            and np.isfinite(speed)
            and speed > 0
        ):
            raise ValueError(f"Player: speed must be a positive number, got {speed!r}")
        raw, what = _resolve_timestamps(timestamps)
        self._seconds, self.timestamps_kind = timestamps_as_seconds(raw, what)
        self._raw = np.asarray(getattr(raw, "values", raw))
        if not (np.isfinite(max_rate) and max_rate > 0):
            raise ValueError(
                f"Player: max_rate must be a positive number, got {max_rate}"
            )
        self.max_rate = float(max_rate)
        self._clock = clock or time.monotonic
        self._threaded = bool(threaded)
        self._links: list[_Link] = []
        self._lock = threading.RLock()
        self._thread: threading.Thread | None = None
        self._stop_event = threading.Event()
        self._anchor_index = 0
        self._anchor_time = float(self._seconds[0])
        self._anchor_wall = 0.0
        self._last_ui = -np.inf
        self._updating_ui = False
        self.error: BaseException | None = None
        self._build_ui()
        super().__init__(children=[self._controls, self._slider, self._error])
        self.step = step
        self.speed = speed
        self.skip = skip if skip is not None else 10 * self.step
        self.loop = loop
        self._sync_ui()

    # -- validation -----------------------------------------------------------
    @traitlets.validate("step")
    def _valid_step(self, proposal):
        value = proposal["value"]
        if value < 1:
            raise traitlets.TraitError(f"step must be a positive integer, got {value}")
        return value

    @traitlets.validate("skip")
    def _valid_skip(self, proposal):
        value = proposal["value"]
        if value < 1:
            raise traitlets.TraitError(f"skip must be a positive integer, got {value}")
        return value

    @traitlets.validate("speed")
    def _valid_speed(self, proposal):
        value = proposal["value"]
        if not (np.isfinite(value) and value > 0):
            raise traitlets.TraitError(f"speed must be a positive number, got {value}")
        return value

    @traitlets.validate("index")
    def _valid_index(self, proposal):
        value = proposal["value"]
        if not 0 <= value < len(self._seconds):
            raise traitlets.TraitError(
                f"index must be in [0, {len(self._seconds) - 1}], got {value}"
            )
        return value

    # -- the time axis --------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples on the time axis."""
        return len(self._seconds)

    @property
    def timestamps(self) -> np.ndarray:
        """The time axis as given (float seconds or datetime64)."""
        return self._raw

    @property
    def seconds(self) -> np.ndarray:
        """The time axis as float seconds."""
        return self._seconds

    @property
    def time(self) -> float:
        """Time of the current sample in float seconds."""
        return float(self._seconds[self.index])

    @property
    def timestamp(self):
        """Time of the current sample as given (float or datetime64)."""
        return self._raw[self.index]

    @property
    def _mean_dt(self) -> float:
        if self.n < 2:
            return 0.0
        return float(self._seconds[-1] - self._seconds[0]) / (self.n - 1)

    @property
    def interval(self) -> float:
        """Wall-clock seconds between steps: mean timestamp difference x step / speed."""
        if self.n < 2:
            return float("inf")
        return max(self._mean_dt * self.step / self.speed, 1.0 / self.max_rate)

    def index_at(self, t) -> int:
        """Index of the latest sample at or before ``t`` (0 before the start)."""
        seconds = time_as_seconds(t, self.timestamps_kind)
        return max(int(np.searchsorted(self._seconds, seconds, side="right")) - 1, 0)

    # -- linked objects -------------------------------------------------------
    def link(self, obj):
        """Drive ``obj`` from this player and show it the current time.

        ``obj`` needs ``set_time(t)`` (called with float seconds) or
        ``publish(idx)``. With ``publish`` and a ``timestamps`` attribute, the
        index is that of its latest sample at or before the player's time, so
        objects recorded at different rates stay in sync; without timestamps it
        gets the player's own index.

        Returns
        -------
        obj
            The linked object.
        """
        link = _Link(obj, self.timestamps_kind)
        with self._lock:
            self._links.append(link)
            link.show(self.index, self.time)
        return obj

    def unlink(self, obj) -> None:
        """Stop driving ``obj``."""
        with self._lock:
            self._links = [link for link in self._links if link.obj is not obj]

    @property
    def linked(self) -> list:
        """The linked objects."""
        return [link.obj for link in self._links]

    # -- navigation -----------------------------------------------------------
    def seek(self, index: int) -> None:
        """Show sample ``index`` (clipped to the time axis)."""
        index = int(np.clip(index, 0, self.n - 1))
        self._go_to(index, source="api")
        if self.playing:
            self._anchor(self._clock())

    def seek_time(self, t) -> None:
        """Show the latest sample at or before ``t`` (float seconds or datetime64)."""
        self.seek(self.index_at(t))

    def step_forward(self) -> None:
        self.seek(self.index + self.step)

    def step_back(self) -> None:
        self.seek(self.index - self.step)

    def skip_forward(self) -> None:
        self.seek(self.index + self.skip)

    def skip_back(self) -> None:
        self.seek(self.index - self.skip)

    # -- playback -------------------------------------------------------------
    def play(self) -> None:
        """Start playing from the current sample (from the start when at the end)."""
        if self.playing or self.n < 2:
            return
        if self.index >= self._last_reachable(self.index):
            self._go_to(0, source="api")
        self.error = None
        self._anchor(self._clock())
        self.playing = True

    def pause(self) -> None:
        """Stop playing; returns once no further sample will be published."""
        self.playing = False

    def toggle(self) -> None:
        """Play when paused, pause when playing."""
        if self.playing:
            self.pause()
        else:
            self.play()

    def tick(self, now: float | None = None) -> bool:
        """Publish the sample that is due at wall-clock time ``now``.

        Only the latest due sample is published; the ones in between are
        dropped. Called by the playback thread; tests call it directly with
        their own clock values.

        Returns
        -------
        bool
            Whether playback goes on (False once stopped or at the end).
        """
        if not self.playing:
            return False
        now = self._clock() if now is None else now
        target = self._anchor_time + (now - self._anchor_wall) * self.speed
        # a sample due within a thousandth of the sampling interval counts as
        # due: wall-clock arithmetic is not exact
        target += 1e-3 * self._mean_dt
        due = max(int(np.searchsorted(self._seconds, target, side="right")) - 1, 0)
        start = self._anchor_index
        index = start + max(due - start, 0) // self.step * self.step
        last = self._last_reachable(start)
        if index >= last and self.loop:
            self._go_to(0, source="loop")
            self._anchor(now)
            return self.playing
        if index >= last:
            self._go_to(last, source="loop")
            self._finish()
            return False
        if index != self.index:
            self._go_to(index, source="loop")
        return self.playing

    def _last_reachable(self, start: int) -> int:
        return start + (self.n - 1 - start) // self.step * self.step

    def _anchor(self, now: float) -> None:
        self._anchor_index = self.index
        self._anchor_time = self.time
        self._anchor_wall = now

    def _finish(self) -> None:
        self._stop_event.set()
        self.playing = False

    @traitlets.observe("playing")
    def _on_playing(self, change) -> None:
        if change["new"]:
            self._start_thread()
        else:
            self._stop_thread()
            self._sync_ui()
        self._sync_button()

    @traitlets.observe("speed", "step")
    def _on_rate(self, change) -> None:
        if self.playing:
            self._anchor(self._clock())
        self._sync_ui()

    def _start_thread(self) -> None:
        self._stop_event = threading.Event()
        if not self._threaded:
            return
        self._thread = threading.Thread(
            target=self._run,
            args=(self._stop_event,),
            name="rbm_nb-player",
            daemon=True,
        )
        self._thread.start()

    def _stop_thread(self) -> None:
        self._stop_event.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=10.0)
        self._thread = None

    def _run(self, stop: threading.Event) -> None:
        deadline = self._clock()
        while not stop.is_set():
            if not self.tick():
                break
            deadline += self.interval
            now = self._clock()
            if deadline < now:  # late: drop what was missed instead of catching up
                deadline = now
            stop.wait(deadline - now)

    def _go_to(self, index: int, source: str) -> None:
        with self._lock:
            if source == "loop" and self._stop_event.is_set():
                return
            try:
                self.index = index
                t = self.time
                for link in self._links:
                    link.show(index, t)
            except Exception as err:
                self.error = err
                self._show_error(err)
                if source == "loop":
                    self._finish()
                elif source == "api":
                    raise
                return
        now = time.monotonic()
        if source != "loop" or now - self._last_ui >= UI_INTERVAL:
            self._last_ui = now
            self._sync_ui()

    # -- widgets --------------------------------------------------------------
    def _build_ui(self) -> None:
        button = widgets.Layout(width="40px")
        self._play_button = widgets.ToggleButton(
            value=False, icon="play", tooltip="Play / pause", layout=button
        )
        self._step_back_button = widgets.Button(
            icon="step-backward", tooltip="Step back", layout=button
        )
        self._step_forward_button = widgets.Button(
            icon="step-forward", tooltip="Step forward", layout=button
        )
        self._skip_back_button = widgets.Button(
            icon="backward", tooltip="Skip back", layout=button
        )
        self._skip_forward_button = widgets.Button(
            icon="forward", tooltip="Skip forward", layout=button
        )
        self._speed_box = widgets.Dropdown(
            options=[(f"{s:g}\u00d7", s) for s in SPEEDS],
            value=1.0,
            tooltip="Playback speed",
            layout=widgets.Layout(width="80px"),
        )
        self._readout = widgets.Label(value="")
        self._readout.add_class("rbm-player-readout")
        self._slider = widgets.IntSlider(
            value=0,
            min=0,
            max=max(self.n - 1, 0),
            readout=False,
            continuous_update=True,
            layout=widgets.Layout(width="100%"),
        )
        self._error = widgets.HTML(value="", layout=widgets.Layout(display="none"))
        self._controls = widgets.HBox(
            [
                self._play_button,
                self._skip_back_button,
                self._step_back_button,
                self._step_forward_button,
                self._skip_forward_button,
                self._speed_box,
                self._readout,
            ]
        )
        self._play_button.observe(self._on_play_button, "value")
        self._slider.observe(self._on_slider, "value")
        self._speed_box.observe(self._on_speed_box, "value")
        self._step_back_button.on_click(lambda _: self._ui_call(self.step_back))
        self._step_forward_button.on_click(lambda _: self._ui_call(self.step_forward))
        self._skip_back_button.on_click(lambda _: self._ui_call(self.skip_back))
        self._skip_forward_button.on_click(lambda _: self._ui_call(self.skip_forward))

    def _ui_call(self, action) -> None:
        try:
            action()
        except Exception:  # already shown in the error box
            pass

    def _on_play_button(self, change) -> None:
        if self._updating_ui:
            return
        if change["new"]:
            self.play()
        else:
            self.pause()
        self._sync_button()

    def _on_slider(self, change) -> None:
        if self._updating_ui or change["new"] == self.index:
            return
        self._go_to(int(change["new"]), source="ui")
        if self.playing:
            self._anchor(self._clock())

    def _on_speed_box(self, change) -> None:
        if not self._updating_ui:
            self.speed = float(change["new"])

    @traitlets.observe("speed")
    def _on_speed(self, change) -> None:
        value = change["new"]
        options = list(self._speed_box.options)
        if value not in [v for _, v in options]:
            options = sorted(
                options + [(f"{value:g}\u00d7", value)], key=lambda o: o[1]
            )
        self._updating_ui = True
        try:
            self._speed_box.options = options
            self._speed_box.value = value
        finally:
            self._updating_ui = False

    def _sync_button(self) -> None:
        self._updating_ui = True
        try:
            self._play_button.value = self.playing
            self._play_button.icon = "pause" if self.playing else "play"
        finally:
            self._updating_ui = False

    def _sync_ui(self) -> None:
        self._updating_ui = True
        try:
            self._slider.value = self.index
            self._readout.value = self.readout()
        finally:
            self._updating_ui = False

    def readout(self) -> str:
        """The text of the index/time display."""
        return f"{self.index} / {self.n - 1}  {format_time(self.time, self.timestamps_kind)}"

    def _show_error(self, err: BaseException) -> None:
        import html

        self._error.value = (
            f"<span style='color:#b00'>{html.escape(type(err).__name__)}: "
            f"{html.escape(str(err))}</span>"
        )
        self._error.layout.display = None

    def close(self) -> None:
        """Stop playing and close the widgets."""
        if not hasattr(self, "_controls"):  # construction failed half-way
            super().close()
            return
        self.pause()
        for child in (
            self._play_button,
            self._step_back_button,
            self._step_forward_button,
            self._skip_back_button,
            self._skip_forward_button,
            self._speed_box,
            self._readout,
            self._slider,
            self._error,
            self._controls,
        ):
            child.close()
        super().close()

    def __repr__(self) -> str:
        state = "playing" if self.playing else "paused"
        return f"<Player {self.readout().strip()} ({state}, {len(self._links)} linked)>"
