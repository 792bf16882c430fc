"""The registered reference frames as a collapsible ipywidgets tree.

Each row shows a frame's name, whether it is static, moving or discrete, its
sample count, time span and mean rate. Selecting one frame shows its parent,
children, path to the root and its pose wrt the parent at the current time;
selecting two shows the chain between them and the transform from the first
into the second. The panel follows the registry (through
``rbm_nb.frames.on_registry_change``) and, linked to a
:class:`~rbm_nb.widgets.Player`, the player's time. ``rbm.render_tree`` remains
the plain-text view.
"""

from __future__ import annotations

import html
import sys
import threading
import weakref
from typing import Any

import ipywidgets as widgets
import numpy as np
import traitlets

from .._engine.time import TimeBase, as_track, epoch_seconds
from ..core import frames, lookups
from ._timebase import format_time
from .frame_details import (
    Details,
    FrameDetails,
    PairDetails,
    details_html,
    details_text,
    pose_at,
)

ROW_CSS = (
    "<style>.rbm-frame-tree .rbm-frame-row-text {height: auto}"
    ".rbm-frame-tree .rbm-frame-row-text .widget-html-content "
    "{height: auto; min-height: var(--jp-widgets-inline-height, 28px); "
    "line-height: 16px; white-space: normal; padding: 6px 0; overflow-wrap: anywhere}"
    "</style>"
)


def frame_kind(frame) -> str:
    """``root``, ``static``, ``moving`` or ``discrete``."""
    if frame.parent is None:
        return "root"
    if frame.timestamps is None:
        return "static"
    return "discrete" if getattr(frame, "discrete", False) else "moving"


def frame_info(frame) -> dict:
    """Kind, sample count, time span and mean rate of a frame.

    Returns
    -------
    dict
        ``kind``, ``samples`` (1 for static frames), ``start`` / ``end`` (float
        seconds, None if static), ``span`` (seconds), ``rate`` (Hz, None
        unless moving with at least two samples) and ``time_kind``.
    """
    kind = frame_kind(frame)
    info: dict[str, Any] = {
        "kind": kind,
        "samples": 1,
        "start": None,
        "end": None,
        "span": 0.0,
        "rate": None,
        "time_kind": None,
    }
    if frame.timestamps is not None:
        track = as_track(frame.timestamps, f"timestamps of {frame.name!r}", copy=False)
        seconds, time_kind = track.epoch_seconds(), track.kind
        info.update(
            samples=len(seconds),
            start=float(seconds[0]),
            end=float(seconds[-1]),
            time_kind=time_kind,
        )
        info["span"] = float(seconds[-1] - seconds[0])
        if len(seconds) > 1 and info["span"] > 0:
            info["rate"] = (len(seconds) - 1) / info["span"]
    return info


def _describe(info: dict) -> str:
    if info["kind"] in ("root", "static"):
        return info["kind"]
    unit = "events" if info["kind"] == "discrete" else "samples"
    text = f"{info['kind']} \u00b7 {info['samples']} {unit} \u00b7 {info['span']:.3g} s"
    if info["rate"] is not None:
        text += f" \u00b7 {info['rate']:.4g} Hz"
    return text


def _registry_listener(tree_ref):
    """A registry callback that keeps only a weak reference to the tree."""

    def callback(event, name):
        tree = tree_ref()
        if tree is None:
            try:
                frames.remove_registry_callback(callback)
            except ValueError:
                pass
            return
        tree._registry_changed()

    return callback


class FrameTree(widgets.VBox):
    """Collapsible tree of the registered frames below ``root``.

    Parameters
    ----------
    root : str, default "world"
        Name of the registered frame at the top of the tree.
    scene : rbm_nb.scene.Scene, optional
        Selection goes both ways: selecting a frame here selects (highlights)
        it in the scene, clicking a frame in the 3D view selects it here.
    player : rbm_nb.widgets.Player, optional
        Link to this player: poses are shown at its current time, and times
        are printed from its start (``12.345 s · 2020-02-02 00:27:26.345``).
    missing_reasons : dict, optional
        Frame name -> why its recording has samples with no value (NaN rows),
        said in the details where such a sample is the one shown: "no sample
        of pupil/left_eye at 72.969 s (missing: <reason>)".

    Examples
    --------
    >>> import rbm_nb as rbm
    >>> rbm.clear_registry()
    >>> rbm.register_frame("world")
    >>> rbm.register_frame("observer", parent="world", translation=(5, 0, 0))
    >>> tree = FrameTree("world")
    >>> tree.nodes
    ['world', 'observer']
    >>> tree.select("observer")
    >>> "parent: world" in tree.details_text()
    True
    """

    root = traitlets.Unicode("world", help="Name of the frame at the top of the tree.")
    selected = traitlets.Tuple(help="Names of the selected frames (at most two).")
    chain = traitlets.Tuple(
        help="Frames a lookup between the two selected frames goes through, in order."
    )
    time = traitlets.Float(
        None,
        allow_none=True,
        help="Time shown, in data seconds (epoch seconds for datetime frames); None: first sample.",
    )

    def __init__(
        self,
        root: str = "world",
        *,
        scene=None,
        player=None,
        missing_reasons: dict[str, str] | None = None,
    ):
        if not isinstance(root, str):
            root = getattr(root, "name", None)
            if root is None:
                raise ValueError(
                    "FrameTree: root must be the name of a registered frame"
                )
        self._rows: dict[str, dict] = {}
        self._order: list[str] = []
        self._collapsed: set[str] = set()
        self._updating = False
        self._lock = threading.RLock()
        self._lookup_cache: dict = {}
        self._current: Details = None
        self._player: Any = None  # the linked Player
        # the time set_time was given, exact (a datetime64 to the ns), while
        # ``time`` (float data seconds) still says the same
        self._exact: tuple[Any, float] | None = None
        self._scene_widget: Any = None  # the linked Scene's widget
        self._message = widgets.HTML(value="")
        self._rows_box = widgets.VBox(
            [], layout=widgets.Layout(overflow="auto", max_height="400px")
        )
        self._missing_reasons = {
            str(k): str(v) for k, v in (missing_reasons or {}).items()
        }
        # a fixed height with its own scroll bar: selecting frames never moves
        # what is below the tree (the Player, the plots)
        self._details = widgets.HTML(
            value="",
            layout=widgets.Layout(
                padding="4px 8px", height="10.5em", overflow="auto", flex="0 0 auto"
            ),
        )
        self._details.add_class("rbm-frame-details")
        self._refresh_button = widgets.Button(
            icon="refresh", tooltip="Refresh", layout=widgets.Layout(width="40px")
        )
        self._refresh_button.on_click(lambda _: self.refresh())
        self._title = widgets.HTML(value="")
        # ipywidgets gives HTML text one line of fixed height; the rows'
        # descriptions wrap instead (a style element, as no widget sets CSS)
        self._style = widgets.HTML(value=ROW_CSS, layout=widgets.Layout(display="none"))
        header = widgets.HBox([self._refresh_button, self._title, self._style])
        super().__init__(
            children=[header, self._message, self._rows_box, self._details]
        )
        self.add_class("rbm-frame-tree")
        self.scene = scene
        if scene is not None:
            # the 3D view's `selected` (a click on a frame) selects here too
            self._scene_widget = scene.widget
            self._scene_widget.observe(self._on_scene_selected, "selected")
        self.root = root

        self._listener = None
        if hasattr(frames, "on_registry_change"):
            self._listener = frames.on_registry_change(
                _registry_listener(weakref.ref(self))
            )
        self.refresh()
        if player is not None:
            player.link(self)

    # -- public API -------------------------------------------------------------
    @property
    def nodes(self) -> list[str]:
        """Frame names in display order (depth first)."""
        return list(self._order)

    @property
    def visible_nodes(self) -> list[str]:
        """Names of the rows not hidden by a collapsed ancestor."""
        return [n for n in self._order if self._rows[n]["box"].layout.display != "none"]

    def row_text(self, name: str) -> str:
        """The description shown in the row of ``name``."""
        return html.unescape(self._rows[name]["label"].value)

    @property
    def details(self) -> Details:
        """What the details panel shows: FrameDetails, PairDetails or None."""
        return self._current

    def details_text(self) -> str:
        """The details panel as plain text (rendered from :attr:`details`)."""
        return details_text(self._current)

    def refresh(self) -> None:
        """Rebuild the tree from the registry."""
        with self._lock:
            self._lookup_cache.clear()
            self._build()
            keep = tuple(n for n in self.selected if n in self._rows)
            if keep != tuple(self.selected):
                self.selected = keep
            else:
                self._update_details()

    def select(self, *names: str) -> None:
        """Select one or two frames by name (no names clears the selection)."""
        self.selected = tuple(names)

    def show_lookup(self, outof: str, into: str) -> tuple:
        """Highlight the chain of frames that ``lookup_transform(outof, into)`` uses.

        Selects both frames; the frames in between are highlighted too and the
        details show the transform. Returns the chain's frame names.
        """
        self.select(outof, into)
        return self.chain

    def collapse(self, name: str) -> None:
        """Hide the frames below ``name``."""
        self._check_node(name)
        self._collapsed.add(name)
        self._apply_collapse()

    def expand(self, name: str) -> None:
        """Show the frames below ``name``."""
        self._check_node(name)
        self._collapsed.discard(name)
        self._apply_collapse()

    def set_time(self, t) -> None:
        """Show poses at time ``t`` (float seconds or datetime64); for Player links."""
        seconds = epoch_seconds(t, name="FrameTree.set_time: t")
        same = self.time == seconds
        self._exact = (t, seconds)  # before ``time`` redraws the details
        self.time = seconds
        if same:  # times under ~0.25 us apart share their epoch float
            self._update_details()
        if self._listener is None:  # no registry hook: notice changes on steps
            self._poll_registry()

    def _attach_player(self, player) -> None:
        """Follow ``player`` (called by ``Player.link``): its time and its start."""
        if self._player is not None and self._player is not player:
            self._detach_player(self._player)
        self._player = player
        player.observe(self._on_player_time, "time")
        self._on_player_time()

    def _detach_player(self, player) -> None:
        if self._player is player:
            player.unobserve(self._on_player_time, "time")
            self._player = None
            self._update_details()

    def _on_player_time(self, change=None) -> None:
        self.set_time(self._player.time_value)

    def close(self) -> None:
        if self._player is not None:
            self._detach_player(self._player)
        if self._scene_widget is not None:
            self._scene_widget.unobserve(self._on_scene_selected, "selected")
            self._scene_widget = None
        frames = sys.modules.get("rbm_nb.core.frames")
        if self._listener is not None and frames is not None:
            try:
                frames.remove_registry_callback(self._listener)
            except ValueError:
                pass
            self._listener = None
        for row in self._rows.values():
            for w in row["widgets"]:
                w.close()
        super().close()

    # -- validation and observers -----------------------------------------------
    @traitlets.validate("selected")
    def _valid_selected(self, proposal):
        names = tuple(proposal["value"])
        if len(names) > 2:
            raise traitlets.TraitError(f"select at most two frames, got {len(names)}")
        for name in names:
            if name not in self._rows:
                raise traitlets.TraitError(
                    f"frame {name!r} is not in the tree below {self.root!r}; frames: {self._order}"
                )
        if len(names) == 2 and names[0] == names[1]:
            names = names[:1]
        return names

    @traitlets.observe("selected")
    def _on_selected(self, change):
        self.chain = self._chain_names()
        self._updating = True
        try:
            for name, row in self._rows.items():
                row["button"].value = name in self.selected
                if name in self.selected:
                    style = "info"
                elif name in self.chain:
                    style = "warning"  # a frame the lookup passes through
                else:
                    style = ""
                row["button"].button_style = style
        finally:
            self._updating = False
        self._update_details()
        if self._scene_widget is not None:
            chosen = self.selected[-1] if self.selected else None
            if self._scene_widget.selected != chosen:
                try:
                    self.scene.selected = chosen  # the scene highlights it
                except (ValueError, RuntimeError) as err:
                    self._message.value = (
                        f"<i>selecting in the scene failed: {html.escape(str(err))}</i>"
                    )

    def _on_scene_selected(self, change) -> None:
        name = change["new"]
        current = self.selected[-1] if self.selected else None
        if name == current:
            return
        if name is None:
            self.selected = ()
        elif name in self._rows:
            self.selected = (name,)

    def _chain_names(self) -> tuple:
        if len(self.selected) != 2:
            return ()
        a, b = (self._rows[name]["frame"] for name in self.selected)
        return tuple(f.name for f in a.frames_between(b))

    @traitlets.observe("time")
    def _on_time(self, change):
        self._update_details()

    @traitlets.observe("root")
    def _on_root(self, change):
        if self._rows is not None and change["old"] != change["new"]:
            self.refresh()

    # -- building -----------------------------------------------------------------
    def _registry_changed(self) -> None:
        # called from inside register_frame & co: never let a display
        # problem of the panel break a registration
        try:
            self.refresh()
        except Exception as err:
            self._message.value = f"<span style='color:#b00'>refresh failed: {html.escape(str(err))}</span>"

    def _poll_registry(self) -> None:
        signature = tuple((n, id(f)) for n, f in frames.registry.items())
        if signature != getattr(self, "_signature", None):
            self._signature = signature
            self.refresh()

    def _check_node(self, name: str) -> None:
        if name not in self._rows:
            raise ValueError(
                f"frame {name!r} is not in the tree below {self.root!r}; frames: {self._order}"
            )

    def _walk(self, frame, depth: int, out: list) -> None:
        out.append((frame, depth))
        registered = self._registered()
        for child in frame.children:
            if child.name in registered and registered[child.name] is child:
                self._walk(child, depth + 1, out)

    def _registered(self) -> dict:
        return dict(frames.registry.items())

    def _build(self) -> None:
        for row in self._rows.values():
            for w in row["widgets"]:
                w.close()
        self._rows = {}
        self._order = []
        registered = self._registered()
        root = registered.get(self.root)
        if root is None:
            names = ", ".join(repr(n) for n in registered) or "none"
            self._message.value = (
                f"<i>no frame named {html.escape(repr(self.root), quote=False)} is registered "
                f"(registered: {html.escape(names, quote=False)})</i>"
            )
            self._title.value = ""
            self._rows_box.children = []
            return
        self._message.value = ""
        walked: list = []
        self._walk(root, 0, walked)
        self._title.value = (
            f"<b>{len(walked)}</b> frames below <b>{html.escape(self.root)}</b>"
        )
        boxes = []
        for frame, depth in walked:
            row = self._make_row(frame, depth)
            self._rows[frame.name] = row
            self._order.append(frame.name)
            boxes.append(row["box"])
        self._rows_box.children = boxes
        self._collapsed &= set(self._rows)
        self._apply_collapse()

    def _make_row(self, frame, depth: int) -> dict:
        info = frame_info(frame)
        has_children = any(c.name in self._registered() for c in frame.children)
        toggle = widgets.Button(
            icon="caret-down" if has_children else "",
            tooltip="Collapse / expand" if has_children else "",
            disabled=not has_children,
            layout=widgets.Layout(
                width="34px",
                padding="0",
                visibility="visible" if has_children else "hidden",
            ),
        )
        button = widgets.ToggleButton(
            value=frame.name in self.selected,
            description=frame.name,
            tooltip=f"Select {frame.name}",
            # never shrink the name (long frame names like "pupil/left_eye"),
            # let the description beside it take what room is left
            layout=widgets.Layout(width="auto", min_width="90px", flex="0 0 auto"),
        )
        button.add_class("rbm-frame-node")
        # a Label never wraps: in a narrow tree its end was hidden under the
        # 3D view. This text wraps in the room beside the name (ROW_CSS lets
        # it grow in height).
        label = widgets.HTML(
            value=html.escape(_describe(info)),
            layout=widgets.Layout(flex="1 1 0", min_width="0"),
        )
        label.add_class("rbm-frame-row-text")
        box = widgets.HBox(
            [toggle, button, label],
            layout=widgets.Layout(margin=f"0 0 0 {18 * depth}px", width="auto"),
        )
        name = frame.name
        toggle.on_click(lambda _: self._toggle_collapse(name))
        button.observe(lambda change: self._on_click(name, change), "value")
        return {
            "frame": frame,
            "depth": depth,
            "info": info,
            "box": box,
            "button": button,
            "toggle": toggle,
            "label": label,
            "widgets": (toggle, button, label, box),
        }

    def _toggle_collapse(self, name: str) -> None:
        if name in self._collapsed:
            self.expand(name)
        else:
            self.collapse(name)

    def _apply_collapse(self) -> None:
        hidden_below: list[int] = []
        for name in self._order:
            row = self._rows[name]
            depth = row["depth"]
            while hidden_below and depth <= hidden_below[-1]:
                hidden_below.pop()
            row["box"].layout.display = "none" if hidden_below else None
            if name in self._collapsed:
                hidden_below.append(depth)
            if row["toggle"].icon:
                row["toggle"].icon = (
                    "caret-right" if name in self._collapsed else "caret-down"
                )

    def _on_click(self, name: str, change) -> None:
        if self._updating:
            return
        current = list(self.selected)
        if change["new"] and name not in current:
            current = (current + [name])[-2:]
        elif not change["new"] and name in current:
            current.remove(name)
        self.selected = tuple(current)

    # -- details ------------------------------------------------------------------
    def _frame(self, name: str):
        return self._rows[name]["frame"]

    def _update_details(self) -> None:
        try:
            self._current = self._build_details()
            text = details_html(self._current)
        except Exception as err:  # shown, not raised: the panel must stay usable
            self._current = None
            text = f"<span style='color:#b00'>{html.escape(type(err).__name__)}: {html.escape(str(err))}</span>"
        self._details.value = text

    def _build_details(self) -> Details:
        names = [n for n in self.selected if n in self._rows]
        if not names:
            return None
        if len(names) == 1:
            return self._single_details(self._frame(names[0]))
        return self._pair_details(self._frame(names[0]), self._frame(names[1]))

    # -- one time base: seconds from the start, plus the date if any ---------------
    def _time_base(self) -> TimeBase:
        """Second 0: the linked player's, else the earliest frame's first sample."""
        player = self._player
        if player is not None:
            return player.timebase
        first = None
        for row in self._rows.values():
            frame = row["frame"]
            if frame.timestamps is None:
                continue
            stamps = np.asarray(getattr(frame.timestamps, "values", frame.timestamps))
            seconds = row["info"]["start"]
            if first is None or seconds < first[0]:
                first = (seconds, stamps[:1])
        if first is None:
            return TimeBase(t0_s=0.0)
        return TimeBase.of(first[1])

    def format_time(self, seconds: float) -> str:
        """Data seconds (epoch seconds for datetime frames) as the shared readout."""
        base = self._time_base()
        return _readout(base)(base.at(seconds))

    def _shown(self, base: TimeBase) -> float | None:
        """The time shown as seconds of ``base``; exact when set_time had a datetime."""
        if self.time is None:
            return None
        try:
            if self._exact is not None and self._exact[1] == self.time:
                return base.at(self._exact[0])
            return base.at(self.time)
        except ValueError:  # a time of another kind than the tree's frames
            return self.time - base.origin

    def _single_details(self, frame) -> FrameDetails:
        info = self._rows[frame.name]["info"]
        pose = None
        if frame.parent is not None:
            base = self._time_base()
            seconds = None
            if frame.timestamps is not None:
                seconds = _seconds_on(
                    base, frame.timestamps, f"timestamps of {frame.name!r}"
                )
            pose = pose_at(
                f"wrt {frame.parent.name}",
                np.asarray(frame.translation, dtype=float),
                np.asarray(frame.rotation, dtype=float),
                seconds,
                self._shown(base),
                _readout(base),
                lambda at: self._missing_text([frame], at, base),
            )
        return FrameDetails(
            name=frame.name,
            summary=_describe(info),
            parent=None if frame.parent is None else frame.parent.name,
            children=tuple(c.name for c in frame.children if c.name in self._rows),
            path=tuple(f.name for f in _path_to_root(frame)),
            pose=pose,
        )

    def _pair_details(self, a, b) -> PairDetails:
        chain = tuple(f.name for f in a.frames_between(b))
        key = (a.name, b.name, id(a), id(b))
        if key not in self._lookup_cache:
            t, r, ts = lookups.lookup_transform(outof=a, into=b, return_timestamps=True)
            track = (
                None
                if ts is None
                else as_track(ts, "transform timestamps", copy=False, repeats=True)
            )
            self._lookup_cache[key] = (np.asarray(t), np.asarray(r), track)
        t, r, track = self._lookup_cache[key]
        base = self._time_base()
        seconds = (
            None if track is None else _seconds_on(base, track, "transform timestamps")
        )
        frames = [f for f in a.frames_between(b) if f.timestamps is not None]
        pose = pose_at(
            f"of {a.name} in {b.name}",
            t,
            r,
            seconds,
            self._shown(base),
            _readout(base),
            lambda at: self._missing_text(frames, at, base),
        )
        return PairDetails(outof=a.name, into=b.name, chain=chain, pose=pose)

    def _missing_text(self, frames, at: float, base: TimeBase) -> str:
        """ "no sample of <frame> at <time> (missing: <why>)" for a NaN result at ``at``.

        Names the moving frames of ``frames`` whose own sample at or next to
        ``at`` has no value (the samples an interpolation there needs).
        """
        culprits = [f for f in frames if _missing_near(f, at, base)]
        readout = _readout(base)
        if not culprits:
            return f"no sample at {readout(at)} (missing)"
        names = ", ".join(f.name for f in culprits)
        reasons = [
            self._missing_reasons[f.name]
            for f in culprits
            if f.name in self._missing_reasons
        ]
        why = "; ".join(dict.fromkeys(reasons)) or "the recording has no value there"
        return f"no sample of {names} at {readout(at)} (missing: {why})"

    def __repr__(self) -> str:
        return f"<FrameTree root={self.root!r} frames={len(self._order)} selected={self.selected}>"


def _path_to_root(frame) -> list:
    out = [frame]
    while out[-1].parent is not None:
        out.append(out[-1].parent)
    return out


def _readout(base: TimeBase):
    """Seconds of ``base`` -> the shared readout (with the date for datetime data)."""
    t0_ns = base.t0_ns if base.absolute else None
    return lambda seconds: format_time(seconds, t0_ns)


def _seconds_on(base: TimeBase, timestamps, name: str) -> np.ndarray:
    """Sample times as seconds of ``base``, from exact keys.

    A frame whose times are of another kind than the base's (a tree mixing
    datetime64 and numeric frames) keeps its data seconds less second 0's.
    """
    track = as_track(timestamps, name, copy=False, repeats=True)
    if track.kind == base.kind:
        return base.seconds(track)
    return track.epoch_seconds() - base.origin


def _missing_near(frame, at: float, base: TimeBase) -> bool:
    """Whether ``frame``'s sample at or before ``at``, or the next one, is NaN."""
    if frame.timestamps is None:
        return False
    seconds = _seconds_on(base, frame.timestamps, f"timestamps of {frame.name!r}")
    i = int(np.searchsorted(seconds, at, side="right")) - 1
    rows = [j for j in (i, i + 1) if 0 <= j < len(seconds)]
    for values in (frame.translation, frame.rotation):
        values = np.asarray(values, dtype=float)
        picked = values[rows] if values.ndim == 2 else values
        if not np.isfinite(picked).all():
            return True
    return False
