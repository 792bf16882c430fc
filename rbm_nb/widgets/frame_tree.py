"""The registered reference frames as a collapsible ipywidgets tree.

Each row shows a frame's name, whether it is static, moving or discrete, its
sample count, time span and mean rate. Selecting one frame shows its parent,
children, path to the root and its pose wrt the parent at the current time;
selecting two shows the chain between them and the transform from the first
into the second. The panel follows the registry (through
``rbm_nb.frames.on_registry_change``) and, linked to a
:class:`~rbm_nb.widgets.Player`, the player's time. ``rbm.render_tree`` remains
the plain-text view.

The widget is a facade over its parts: ``frame_facts`` (what a row says of a
frame), ``frame_tree_rows`` (a row's widgets, collapsing) and
``frame_tree_details`` (the details of a selection at the time shown).
"""

from __future__ import annotations

import html
import sys
import threading
import weakref
from typing import Any

import ipywidgets as widgets
import traitlets

from .._engine.time import TimeBase, epoch_seconds
from ..core import frames
from .frame_details import (
    Details,
    FrameDetails,
    PairDetails,
    details_html,
    details_text,
)
from .frame_facts import frame_info as frame_info  # documented here before
from .frame_facts import frame_kind as frame_kind  # documented here before
from .frame_tree_details import (
    looked_up,
    pair_details,
    readout,
    shown_seconds,
    single_details,
    time_base,
)
from .frame_tree_rows import ROW_CSS, apply_collapse, make_row


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
        name = frame.name
        return make_row(
            frame,
            depth,
            selected=name in self.selected,
            has_children=any(c.name in self._registered() for c in frame.children),
            on_toggle=lambda: self._toggle_collapse(name),
            on_click=lambda change: self._on_click(name, change),
        )

    def _toggle_collapse(self, name: str) -> None:
        if name in self._collapsed:
            self.expand(name)
        else:
            self.collapse(name)

    def _apply_collapse(self) -> None:
        apply_collapse(self._order, self._rows, self._collapsed)

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
        return time_base(self._player, self._rows)

    def format_time(self, seconds: float) -> str:
        """Data seconds (epoch seconds for datetime frames) as the shared readout."""
        base = self._time_base()
        return readout(base)(base.at(seconds))

    def _shown(self, base: TimeBase) -> float | None:
        """The time shown as seconds of ``base``; exact when set_time had a datetime."""
        return shown_seconds(self.time, self._exact, base)

    def _single_details(self, frame) -> FrameDetails:
        base = None if frame.parent is None else self._time_base()
        return single_details(
            frame,
            self._rows[frame.name]["info"],
            self._rows,
            base,
            None if base is None else self._shown(base),
            self._missing_reasons,
        )

    def _pair_details(self, a, b) -> PairDetails:
        chain = tuple(f.name for f in a.frames_between(b))
        looked = looked_up(a, b, self._lookup_cache)
        base = self._time_base()
        return pair_details(
            a, b, chain, looked, base, self._shown(base), self._missing_reasons
        )

    def __repr__(self) -> str:
        return f"<FrameTree root={self.root!r} frames={len(self._order)} selected={self.selected}>"
