"""Playback of timestamped data: a widget whose clock runs in the browser.

The :class:`Player` is an anywidget (``js/src/player.js``). Pressing play
starts a ``requestAnimationFrame`` clock in the browser: the time moves, and
every view linked to the player (the 3D :class:`~rbm_nb.scene.Scene`, the
time-series plot) follows it there, with no message through the kernel. So
play, pause, skip, scrub, speed and loop keep working while the kernel is busy.
The kernel has no playback thread; it learns the time at a throttled rate
(``THROTTLE_MS`` in ``js/src/timeline.js``, 200 ms) and then calls the Python
callbacks and objects linked with :meth:`Player.link`.

Contract for other views (also in ``js/src/timeline.js``)
---------------------------------------------------------
Synced traits of the Player:

``time`` (float)
    Seconds from the start of the recording, in ``[0, duration]``. Set by the
    browser clock every animation frame, pushed to the kernel throttled (and
    at once on pause and seek); setting it in Python moves every view and the
    clock continues from there. It is not echoed back to the browser.
``playing`` (bool), ``speed`` (float), ``loop`` (bool)
``duration`` (float)
    Seconds from the first to the last sample.
``t0_ns`` (int or None)
    Absolute time of second 0 in ns since the Unix epoch, or None when the
    timestamps are plain seconds.
``origin`` (float)
    Second 0 on the data's own float-seconds axis (epoch seconds for
    datetime data): ``data seconds = origin + time``.

A linked view declares ``player = Instance(Player, allow_none=True).tag(sync=True,
**widget_serialization)``; in JS it gets the player's model with
``await model.widget_manager.get_model(id)`` and listens to ``change:time``
(``followPlayer`` in ``js/src/timeline.js`` does this). To seek from a view,
``seek(player, t)`` from timeline.js. :meth:`Player.link` sets such a view's
``player`` trait.

The time arithmetic (seek, skips in seconds, loop) is
:class:`rbm_nb.widgets.playback.Playback`, tested without a browser.
"""

from __future__ import annotations

import sys
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol, cast

import anywidget
import numpy as np
import traitlets

from .._engine.time import TimeBase, as_track, check_compatible, latest_index
from .._infra.frozen import is_frozen
from ..core import frames
from ._frontend import FrontendGuard
from ._timebase import format_time
from .playback import Playback, SampleTimes, check_speed

STATIC = Path(__file__).resolve().parent / "static"


def bundle(name: str) -> str:
    """Text of the built JS bundle ``rbm_nb/widgets/static/<name>.js``."""
    path = STATIC / f"{name}.js"
    if not path.is_file():
        raise FileNotFoundError(
            f"the widget bundle {path} is missing; rebuild it with "
            "npm --prefix js ci && npm --prefix js run build"
        )
    return path.read_text(encoding="utf-8")


class _Link:
    """A Python object the kernel drives when it learns the player's time."""

    def __init__(self, obj: Any, base: TimeBase):
        self.obj = obj
        set_time = getattr(obj, "set_time", None)
        publish = getattr(obj, "publish", None)
        self.set_time = set_time if callable(set_time) else None
        self.publish = publish if callable(publish) else None
        if self.set_time is None and self.publish is None:
            raise TypeError(
                f"cannot link {type(obj).__name__}: it needs a set_time(t) or a publish(idx) "
                "method, or a 'player' trait"
            )
        self.base = base
        self.track = None
        kind = getattr(obj, "timestamps_kind", None)
        if self.set_time is None:
            timestamps = getattr(obj, "timestamps", None)
            if timestamps is not None:
                self.track = as_track(
                    timestamps,
                    f"timestamps of the linked {type(obj).__name__}",
                    copy=False,
                    repeats=True,
                )
                kind = self.track.kind
        check_compatible([base.kind, kind], f"link({type(obj).__name__})")
        self.last: int | None = None

    def show(self, index: int, time: float) -> None:
        """Show the player's ``time`` (seconds from its second 0)."""
        if self.set_time is not None:
            # the time in the data's own kind: a datetime64 exact to the ns
            self.set_time(self.base.value(time))
            return
        assert self.publish is not None  # __init__ refuses an object with neither
        if self.track is None:
            idx = index
        else:
            idx = latest_index(self.track, self.base, time)
            if idx < 0:  # nothing recorded yet at this time
                return
        if idx != self.last:
            self.publish(idx)
            self.last = idx


class _Follower(Protocol):
    """A widget with a ``player`` trait: it follows the player in the browser."""

    player: Player | None


def _follower(obj: object) -> _Follower | None:
    """``obj`` if it has a ``player`` trait, else None."""
    if isinstance(obj, traitlets.HasTraits) and obj.has_trait("player"):
        return cast(_Follower, obj)
    return None


def _positive(value, name: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(
            f"Player: {name} must be a positive number, got {value!r}"
        ) from None
    if isinstance(value, bool) or not (np.isfinite(number) and number > 0):
        raise ValueError(f"Player: {name} must be a positive number, got {value!r}")
    return number


def _resolve_timestamps(source) -> tuple[Any, str]:
    """Timestamps from an array, a frame (or its name) or an object having them."""
    if isinstance(source, str):
        if source not in frames.registry:
            raise ValueError(f"Player: no frame named {source!r} is registered")
        source = frames.registry[source]
    frames_mod = sys.modules.get("rbm_nb.core.frames")
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


class Player(FrontendGuard, anywidget.AnyWidget):
    """Play/pause, skips, slider, speed and loop over a time axis.

    Parameters
    ----------
    timestamps : array_like, shape (n,), or ReferenceFrame, str or object
        The time axis: float seconds or datetime64 values, a moving frame (or
        the name of a registered one) or any object with a ``timestamps``
        attribute (a publisher, a :class:`~rbm_nb.scene.Scene`).
    step : int, default 1
        Samples moved by :meth:`step_forward` / :meth:`step_back`.
    speed : float, default 1.0
        Playback speed relative to the recording.
    skip : float, optional
        Seconds jumped by the arrow keys and the small skip buttons (1 s by
        default); shift+arrows and the big buttons jump ``10 * skip``.
    loop : bool, default False
        Start over at the end instead of stopping.

    Examples
    --------
    >>> import numpy as np
    >>> player = Player(np.arange(10) * 0.1, step=2)
    >>> player.duration
    0.9
    >>> player.step_forward(); player.index
    2
    >>> player.skip_forward(); player.time  # 1 s later is past the end
    0.9
    """

    # the browser's controls; duration, origin, t0_ns, error... are the kernel's
    _frontend_settable = frozenset({"time", "playing", "speed", "loop"})

    _esm = traitlets.Unicode("").tag(sync=True)
    _uid = traitlets.Unicode("").tag(sync=True)
    time = traitlets.Float(0.0, help="Seconds from the first sample.").tag(
        sync=True, echo_update=False
    )
    playing = traitlets.Bool(False, help="Whether the browser clock runs.").tag(
        sync=True
    )
    speed = traitlets.Float(1.0, help="Playback speed relative to the recording.").tag(
        sync=True
    )
    loop = traitlets.Bool(False, help="Start over at the end instead of stopping.").tag(
        sync=True
    )
    duration = traitlets.Float(
        0.0, help="Seconds from the first to the last sample."
    ).tag(sync=True)
    t0_ns = traitlets.Int(
        None, allow_none=True, help="Absolute time of second 0 (ns since the epoch)."
    ).tag(sync=True)
    origin = traitlets.Float(
        0.0, help="Second 0 on the data's float-seconds axis."
    ).tag(sync=True)
    skip = traitlets.Float(1.0, help="Seconds of a small skip (arrow keys).").tag(
        sync=True
    )
    big_skip = traitlets.Float(10.0, help="Seconds of a big skip (shift+arrows).").tag(
        sync=True
    )
    error = traitlets.Unicode("", help="Last error of a linked object.").tag(sync=True)

    def __init__(
        self,
        timestamps,
        step: int = 1,
        speed: float = 1.0,
        skip: float | None = None,
        *,
        loop: bool = False,
        **kwargs,
    ):
        if (
            isinstance(step, bool)
            or not isinstance(step, (int, np.integer))
            or step < 1
        ):
            raise ValueError(f"Player: step must be a positive integer, got {step!r}")
        speed = check_speed(speed, "Player")
        skip = 1.0 if skip is None else _positive(skip, "skip")
        raw, what = _resolve_timestamps(timestamps)
        # exact keys (int64 ns for datetime64) and second 0: the samples'
        # seconds from the start come from int64 differences, so stamps 1 ns
        # apart stay two samples at any epoch. Kept are the keys alone (a view
        # of timestamps nobody can change any more, else a copy); seconds are
        # counted from them when asked (playback.SampleTimes)
        given = np.asarray(getattr(raw, "values", raw))
        track = as_track(raw, what, copy=not is_frozen(given), repeats=True)
        self._base = TimeBase.of(track)
        self.timestamps_kind = track.kind
        self._raw = track.values
        samples = SampleTimes(track.key, 1.0 if track.kind == "numeric" else 1e9)
        del track  # its float seconds: not kept
        if not np.isfinite(samples.at(len(samples) - 1)):
            # e.g. -1e308 to 1e308: the span overflows
            first, last = self._raw[0], self._raw[-1]
            raise ValueError(
                f"Player: the timestamps run from {first:.6g} to {last:.6g} s, a span "
                "too long to play (not finite)"
            )
        self.playback = Playback(samples, speed=speed, loop=loop)
        self.step = int(step)
        self._links: list[_Link] = []
        self._callbacks: list[Callable[[float], Any]] = []
        # the JS boundary: second 0 as absolute ns (display) and as float
        # data seconds (``origin``, epoch seconds for datetime data)
        t0_ns = self._base.t0_ns if self._base.absolute else None
        super().__init__(
            _esm=bundle("player"),
            _uid=uuid.uuid4().hex,
            duration=self.playback.duration,
            origin=self._base.origin,
            t0_ns=t0_ns,
            speed=speed,
            loop=bool(loop),
            skip=skip,
            big_skip=10.0 * skip,
            **kwargs,
        )
        self.error_object: BaseException | None = None

    # -- validation -------------------------------------------------------------
    @traitlets.validate("time")
    def _valid_time(self, proposal):
        value = float(proposal["value"])
        if not np.isfinite(value):
            raise traitlets.TraitError(f"time must be finite, got {value}")
        return min(max(value, 0.0), self.duration)

    @traitlets.validate("speed", "skip", "big_skip")
    def _valid_positive(self, proposal):
        value = float(proposal["value"])
        if not (np.isfinite(value) and value > 0):
            name = proposal["trait"].name
            raise traitlets.TraitError(f"{name} must be a positive number, got {value}")
        return value

    # -- the time axis ------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples on the time axis."""
        return len(self._raw)

    @property
    def timestamps(self) -> np.ndarray:
        """The time axis as given (float seconds or datetime64)."""
        return self._raw

    @property
    def seconds(self) -> np.ndarray:
        """The time axis as float data seconds (epoch seconds for datetime64).

        ~0.25 µs coarse at today's epochs; :attr:`timebase` and
        :attr:`timestamps` are exact.
        """
        return self._base.origin + self.playback.relative

    @property
    def timebase(self) -> TimeBase:
        """Second 0 of the player (its first sample), exact."""
        return self._base

    @property
    def time_value(self):
        """The current time in the data's kind: datetime64[ns] (exact to the ns) or float."""
        return self._base.value(self.time)

    @property
    def index(self) -> int:
        """Index of the latest sample at or before the current time."""
        return self.playback.index_at(self.time)

    @property
    def t0_s(self) -> float:
        """Second 0 on the data's float-seconds axis (the same as ``origin``)."""
        return self.origin

    @property
    def data_time(self) -> float:
        """The current time on the data's float-seconds axis (``origin + time``)."""
        return self.origin + self.time

    @property
    def timestamp(self):
        """The current sample's timestamp as given (float or datetime64)."""
        return self._raw[self.index]

    def index_at(self, t) -> int:
        """Index of the latest sample at or before ``t`` (data seconds or datetime64)."""
        return self.playback.index_at(self._base.at(t, "Player.index_at: t"))

    # -- navigation (kernel side; the browser does the same without the kernel) ----
    def seek(self, index: int) -> None:
        """Go to sample ``index`` (clipped to the axis)."""
        self.time = self.playback.time_of(int(index))

    def seek_time(self, t) -> None:
        """Go to ``t``: data seconds (epoch seconds for datetime data) or datetime64."""
        self.time = self.playback.clamp(self._base.at(t, "Player.seek_time: t"))

    def step_forward(self) -> None:
        """Go ``step`` samples forward."""
        self.seek(self.index + self.step)

    def step_back(self) -> None:
        """Go ``step`` samples back."""
        self.seek(self.index - self.step)

    def skip_forward(self, seconds: float | None = None) -> None:
        """Jump ``seconds`` (``skip`` by default) forward; wraps with ``loop``."""
        self._skip(self.skip if seconds is None else float(seconds))

    def skip_back(self, seconds: float | None = None) -> None:
        """Jump ``seconds`` (``skip`` by default) back; wraps with ``loop``."""
        self._skip(-(self.skip if seconds is None else float(seconds)))

    def _skip(self, seconds: float) -> None:
        model = self.playback
        model.loop = self.loop
        model.playing = False
        model.time = self.time
        self.time = model.skip(seconds, now=0.0)

    # -- playback: the browser's clock runs it --------------------------------------
    def play(self) -> None:
        """Start the browser clock (from the start when at the end)."""
        if self.duration <= 0:
            return
        with self.hold_sync():
            if self.time >= self.duration:
                self.time = 0.0
            self.playing = True

    def pause(self) -> None:
        """Stop the browser clock."""
        self.playing = False

    def toggle(self) -> None:
        """Play when paused, pause when playing."""
        if self.playing:
            self.pause()
        else:
            self.play()

    # -- linked objects -----------------------------------------------------------
    def link(self, obj):
        """Drive ``obj`` from this player and show it the current time.

        A widget with a ``player`` trait (the 3D scene, the time-series plot)
        follows the player in the browser: its ``player`` is set to this one.
        Any other object needs ``set_time(t)`` (called with the time in the
        data's kind: a datetime64[ns] exact to the ns for datetime data, float
        seconds otherwise) or ``publish(idx)``; the kernel calls
        it when it learns a new time. With ``publish`` and a ``timestamps``
        attribute, the index is that of its latest sample at or before the
        player's time.

        Returns
        -------
        obj
            The linked object.
        """
        attach = getattr(obj, "_attach_player", None)
        if callable(attach):
            attach(self)
            return obj
        follower = _follower(obj)
        if follower is not None:
            follower.player = self
            return obj
        link = _Link(obj, self._base)
        self._links.append(link)
        self._show(link)
        return obj

    def unlink(self, obj) -> None:
        """Stop driving ``obj``."""
        self._links = [link for link in self._links if link.obj is not obj]
        follower = _follower(obj)
        if follower is not None and follower.player is self:
            follower.player = None
        detach = getattr(obj, "_detach_player", None)
        if callable(detach):
            detach(self)

    @property
    def linked(self) -> list:
        """The Python objects driven by the kernel."""
        return [link.obj for link in self._links]

    def on_time(self, callback: Callable[[float], Any]) -> Callable[[float], Any]:
        """Call ``callback(data_seconds)`` whenever the kernel learns a new time.

        A callback that raises does not stop the others: its error is shown
        in the widget (``error``, and the exception in ``error_object``).

        Returns the callback (usable as a decorator).
        """
        self._callbacks.append(callback)
        return callback

    def _show(self, link: _Link) -> None:
        try:
            link.show(self.index, self.time)
        except Exception as err:
            self.error_object = err
            self.error = f"{type(err).__name__}: {err}"
            raise

    @traitlets.observe("time")
    def _on_time(self, change) -> None:
        seconds = self.data_time
        index = self.index
        for link in list(self._links):
            try:
                link.show(index, self.time)
            except Exception as err:  # shown in the widget; playback goes on
                self.error_object = err
                self.error = f"{type(err).__name__}: {err}"
        for callback in list(self._callbacks):
            try:
                callback(seconds)
            except Exception as err:  # shown in the widget; the others still run
                self.error_object = err
                name = getattr(callback, "__qualname__", repr(callback))
                self.error = f"on_time callback {name}: {type(err).__name__}: {err}"

    # -- display --------------------------------------------------------------------
    def readout(self) -> str:
        """The text of the time display: seconds from the start, and the date if any."""
        return format_time(self.time, self.t0_ns)

    def __repr__(self) -> str:
        state = "playing" if self.playing else "paused"
        return f"<Player {self.readout()} of {self.duration:.3f} s ({state}, {len(self._links)} linked)>"
