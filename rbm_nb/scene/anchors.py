"""The frames a scene's objects hang from, and every pose lookup the scene makes.

An object added with ``base=B`` hangs below the node ``/rbm/anchor_B``,
which follows B in the scene's base; objects in the scene's base hang below
``/rbm/root``. An anchor is shared by its objects and deleted with the last
of them. Poses are looked up here and nowhere else in the scene (how they
are obtained, all at once or per time window, is this module's business),
and a pose already held by an anchor is not looked up again: a second
lookup of a long recording costs its time and a copy of its poses.
"""

from __future__ import annotations

import re

from .commands import Message
from .context import SceneContext
from .state import ROOT
from .tracks import PoseTrack, SceneTrack

#: the anchor of objects drawn in the scene's base
ROOT_ANCHOR = f"{ROOT}/root"


def slug(text: str) -> str:
    """``text`` as a meshcat path segment (letters, digits, ``_.-``)."""
    return re.sub(r"[^A-Za-z0-9_.\-]+", "_", str(text)).strip("_") or "object"


class Anchors:
    """The anchors of one scene: which exist, who uses them, their poses."""

    def __init__(self, context: SceneContext):
        self._context = context
        # path -> [users, base frame]
        self._users: dict[str, list] = {}

    def path(self, base) -> str:
        """The node that objects expressed in ``base`` hang below."""
        if base is self._context.base:
            return ROOT_ANCHOR
        return f"{ROOT}/anchor_{slug(base.name)}"

    def pose(self, frame, base) -> SceneTrack:
        """The pose of ``frame`` in ``base`` over time.

        The one an anchor holds already (objects drawn in ``frame``), else
        looked up.
        """
        if base is self._context.base and frame is not base:
            held = self._context.state.tracks.get(self.path(frame))
            if held is not None:
                return held
        return PoseTrack.lookup(frame, base)

    def acquire(self, base, track: SceneTrack) -> tuple[str, list[Message]]:
        """One more object hangs from ``base``'s anchor, whose pose is ``track``
        (from :meth:`pose`); returns the anchor's path and the commands that
        create it."""
        path = self.path(base)
        entry = self._users.get(path)
        messages: list[Message] = []
        if entry is None:
            if base is not self._context.base:
                messages = self.place(path, track)
            entry = [0, base]
            self._users[path] = entry
        entry[0] += 1
        return path, messages

    def release(self, base) -> list[Message]:
        """One object less hangs from ``base``'s anchor: the commands that
        delete it once none does."""
        path = self.path(base)
        entry = self._users.get(path)
        if entry is None:
            return []
        entry[0] -= 1
        if entry[0] > 0:
            return []
        del self._users[path]
        if path == ROOT_ANCHOR:
            return []
        return [self._context.state.delete(path)]

    def place(self, path: str, track: SceneTrack) -> list[Message]:
        """Put the node at ``path`` where ``track`` says: fixed, or following it."""
        state = self._context.state
        if track.static:
            return [state.set_static(path, track.matrix())]
        state.add_track(path, track, f"scene {self._context.name!r}")
        return []

    def moving_path(self, frame) -> str | None:
        """The path of ``frame``'s anchor when it exists and moves, else None."""
        path = self.path(frame)
        return path if path in self._context.state.tracks else None
