"""The frame tree's rows: one line of widgets per frame, collapsible.

A row is a caret that collapses the frames below, a toggle button with the
frame's name (selecting it) and a text that wraps beside the name (its kind,
samples, span and rate). A row is a plain dict of its frame, depth, facts
and widgets; the tree (:class:`rbm_nb.widgets.frame_tree.FrameTree`) owns
what happens on a click.
"""

from __future__ import annotations

import html
from collections.abc import Callable

import ipywidgets as widgets

from .frame_facts import describe, frame_info

ROW_CSS = (
    "<style>.rbm-frame-tree .rbm-frame-row-text {height: auto}"
    ".rbm-frame-tree .rbm-frame-row-text .widget-html-content "
    "{height: auto; min-height: var(--jp-widgets-inline-height, 28px); "
    "line-height: 16px; white-space: normal; padding: 6px 0; overflow-wrap: anywhere}"
    "</style>"
)


def make_row(
    frame,
    depth: int,
    selected: bool,
    has_children: bool,
    on_toggle: Callable[[], None],
    on_click: Callable[[dict], None],
) -> dict:
    """The widgets of ``frame``'s row, indented by ``depth``; ``on_toggle()``
    when its caret is clicked, ``on_click(change)`` when it is (de)selected."""
    info = frame_info(frame)
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
        value=selected,
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
        value=html.escape(describe(info)),
        layout=widgets.Layout(flex="1 1 0", min_width="0"),
    )
    label.add_class("rbm-frame-row-text")
    box = widgets.HBox(
        [toggle, button, label],
        layout=widgets.Layout(margin=f"0 0 0 {18 * depth}px", width="auto"),
    )
    toggle.on_click(lambda _: on_toggle())
    button.observe(on_click, "value")
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


def apply_collapse(order: list[str], rows: dict, collapsed: set[str]) -> None:
    """Hide the rows below each collapsed one (in ``order``, depth first) and
    turn each caret to say whether its frames are shown."""
    hidden_below: list[int] = []
    for name in order:
        row = rows[name]
        depth = row["depth"]
        while hidden_below and depth <= hidden_below[-1]:
            hidden_below.pop()
        row["box"].layout.display = "none" if hidden_below else None
        if name in collapsed:
            hidden_below.append(depth)
        if row["toggle"].icon:
            row["toggle"].icon = "caret-right" if name in collapsed else "caret-down"
