"""The view's synced traits, each computed from the part that owns it.

The widget shows the time base (``_origin``, and ``_player_shift`` to a
linked player's), the camera (``_camera``), where
each frame's triad is (``_frames``, ``_labels``), the legend (``_legend``)
and the objects pinned to their own time (``_pins``). :class:`ViewTraits`
sets them from the scene's parts whenever one changes; without a widget it
does nothing.
"""

from __future__ import annotations

from .camera import Camera
from .context import SceneContext
from .grid import Grid
from .legend import legend_rows
from .objects import SceneObjects
from .player_link import PlayerLink
from .view import ViewLink

#: the traits that follow the content (refreshed after each change of it)
CONTENT_TRAITS = ("_origin", "_player_shift", "_frames", "_labels", "_legend")
ALL_TRAITS = ("_camera", *CONTENT_TRAITS, "_pins")


class ViewTraits:
    """Pushes one scene's traits to its view."""

    def __init__(
        self,
        context: SceneContext,
        view: ViewLink,
        objects: SceneObjects,
        grid: Grid,
        camera: Camera,
        link: PlayerLink,
    ):
        self._context = context
        self._view = view
        self._objects = objects
        self._grid = grid
        self._camera = camera
        self._link = link

    def legend(self) -> list[dict]:
        return legend_rows(self._objects, self._grid.legend_row())

    def value(self, name: str):
        """The value of trait ``name`` now."""
        if name == "_origin":
            return self._context.state.origin
        if name == "_player_shift":
            return self._link.player_shift()
        if name == "_camera":
            return dict(self._camera.value or {})
        if name == "_frames":
            return self._objects.frame_paths()
        if name == "_labels":
            return {path: frame for frame, path in self._objects.frame_paths().items()}
        if name == "_legend":
            return self.legend()
        if name == "_pins":
            return self._link.pins()
        raise KeyError(name)

    def push(self, *names: str) -> None:
        """Set the traits ``names`` of the widget (if there is one)."""
        if self._view.widget is not None:
            for name in names:
                self._view.sync(name, self.value(name))
