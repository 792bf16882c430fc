"""Which frame the scene emphasises: the selected one, drawn larger.

A frame is selected by a click in 3D, by ``Scene.selected`` or by a linked
FrameTree. A frame drawn with ``add_frame`` is emphasised by doubling its
triad; a frame not drawn gets a triad of its own while it is highlighted
(removed with the emphasis).
"""

from __future__ import annotations

from collections.abc import Callable

from .commands import Message
from .handles import FrameHandle, SceneHandle
from .state import SceneState


class Selection:
    """The emphasis of one scene: ``current`` is ``("scaled", handle)`` (a
    drawn triad enlarged), ``("added", handle)`` (a triad added for it) or None."""

    def __init__(self):
        self.current: tuple[str, SceneHandle] | None = None

    def clear(self, state: SceneState) -> list[Message]:
        """Undo the emphasis: the commands that shrink an enlarged triad
        (an added one is removed here, through its handle)."""
        if self.current is None:
            return []
        kind, handle = self.current
        self.current = None
        if kind == "scaled" and not handle.removed:
            return [state.set_property(handle.geom_path, "scale", [1.0, 1.0, 1.0])]
        if kind == "added":
            handle.remove()
        return []

    def emphasise(
        self,
        frame,
        handles,
        state: SceneState,
        add_triad: Callable[[object], SceneHandle],
    ) -> list[Message]:
        """Emphasise ``frame``: the commands that enlarge its first triad in
        ``handles``, else ``add_triad(frame)`` draws one (its own commands)."""
        for handle in handles:
            if isinstance(handle, FrameHandle) and handle.frame is frame:
                self.current = ("scaled", handle)
                return [state.set_property(handle.geom_path, "scale", [2.0, 2.0, 2.0])]
        self.current = ("added", add_triad(frame))
        return []

    def forget(self, handle: SceneHandle) -> None:
        """``handle`` is being removed: it is no longer emphasised."""
        if self.current is not None and self.current[1] is handle:
            self.current = None
