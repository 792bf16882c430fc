"""Putting objects into a scene and taking them out, and what follows each change.

An object goes in as a :class:`~rbm_nb.scene.placements.Placement`: it hangs
below its base's anchor (``/rbm/<anchor>/<name>``), its ``pose`` node follows
its frame, an optional ``data`` node its own samples, and its ``geom`` node
holds the geometry. Every change is refused whole or made whole under the
scene's lock, sent to the view, and followed by a refresh of what depends
on the whole content: the grid, the camera when it is fitted, the legend
and the labels.
"""

from __future__ import annotations

from .._engine.time import check_compatible
from .anchors import Anchors
from .bounds import Bounds, check_reach, scene_bounds
from .camera import Camera
from .commands import Message
from .context import SceneContext
from .grid import Grid
from .handles import SceneHandle
from .objects import SceneObjects
from .placements import H, Placement
from .selection import Selection
from .traits import CONTENT_TRAITS, ViewTraits
from .view import ViewLink


class Assembly:
    """Installs, redraws and removes the objects of one scene."""

    def __init__(
        self,
        context: SceneContext,
        objects: SceneObjects,
        anchors: Anchors,
        view: ViewLink,
        traits: ViewTraits,
        grid: Grid,
        camera: Camera,
        selection: Selection,
    ):
        self._context = context
        self._objects = objects
        self._anchors = anchors
        self._view = view
        self._traits = traits
        self._grid = grid
        self._camera = camera
        self._selection = selection

    def install(self, placement: Placement[H]) -> H:
        """Put ``placement``'s object into the scene: anchor, nodes, geometry."""
        handle, inner = placement.handle, placement.inner
        context, anchors, state = self._context, self._anchors, self._context.state
        anchor = anchors.pose(handle.base, context.base)
        # before anything changes: an object the view cannot draw is refused whole
        check_reach(handle, placement.carrier, inner, anchor)
        with context.lock:
            for track in (placement.carrier, inner):
                if track is not None and not track.static:
                    check_compatible(
                        [state.kind, track.kind], f"scene {context.name!r}"
                    )
            moving_before = set(state.tracks)
            path, messages = anchors.acquire(handle.base, anchor)
            handle.root_path = f"{path}/{handle.name}"
            handle.pose_path = leaf = f"{handle.root_path}/pose"
            messages += anchors.place(handle.pose_path, placement.carrier)
            if inner is not None:
                leaf = f"{handle.pose_path}/data"
                messages += anchors.place(leaf, inner)
            handle.geom_path = f"{leaf}/geom"
            if placement.offset is not None:
                messages.append(state.set_static(handle.geom_path, placement.offset))
            messages += self._geometry(handle)
            self._objects.add(handle)
            self._view.emit(messages)
            added = [p for p in state.tracks if p not in moving_before]
            if added:
                self._view.emit_tracks(added)
            self.refresh()
        return handle

    def redraw(self, handle: SceneHandle) -> None:
        """Draw ``handle``'s geometry again (its style changed)."""
        with self._context.lock:
            self._view.emit(self._geometry(handle))
            self.refresh()

    def set_visible(self, handle: SceneHandle, visible: bool) -> None:
        with self._context.lock:
            state = self._context.state
            self._view.emit([state.set_property(handle.root_path, "visible", visible)])

    def remove(self, handle: SceneHandle) -> None:
        """Take ``handle``'s object out (and its anchor, when it was the last on it)."""
        self._context.check_open()
        state = self._context.state
        with self._context.lock:
            self._selection.forget(handle)
            self._objects.discard(handle)
            before = set(state.tracks)
            messages = [state.delete(handle.root_path)]
            messages += self._anchors.release(handle.base)
            self._view.emit(messages)
            gone = [p for p in before if p not in state.tracks]
            if gone:
                self._view.emit_tracks([], removed=gone)
            self.refresh()

    def refresh(self) -> None:
        """Refit what depends on the whole content: grid, legend, labels, camera."""
        bounds = self.bounds()
        self._view.emit(self._grid.refit(bounds, self._context.state))
        self._traits.push(*CONTENT_TRAITS)
        if self._camera.value is not None and self._camera.auto:
            self._camera.fit(bounds)
            self._traits.push("_camera")

    def bounds(self) -> Bounds | None:
        """The box of everything in the scene (None when it is empty)."""
        state, anchors = self._context.state, self._anchors
        return scene_bounds(
            self._objects,
            state,
            lambda handle: state.tracks.get(anchors.path(handle.base)),
        )

    def _geometry(self, handle: SceneHandle) -> list[Message]:
        state = self._context.state
        return [
            state.set_object(handle.geom_path + (f"/{rel}" if rel else ""), obj)
            for rel, obj in handle._objects()
        ]
