"""The objects of a scene by name: unique names, and which frames have a triad.

The facade's ``handles``, ``scene[name]`` and ``len(scene)`` read this
registry; the camera (``focus``, ``follow``), the selection and the labels
of the view ask it where each frame's triad is.
"""

from __future__ import annotations

import itertools
from typing import cast

from ..core import frames
from .anchors import slug
from .handles import FrameHandle, SceneHandle


class SceneObjects:
    """The handles of one scene, in the order they were added."""

    def __init__(self):
        self.by_name: dict[str, SceneHandle] = {}

    def __len__(self) -> int:
        return len(self.by_name)

    def __iter__(self):
        return iter(list(self.by_name.values()))

    def __getitem__(self, name: str) -> SceneHandle:
        try:
            return self.by_name[name]
        except KeyError:
            raise KeyError(
                f"no object {name!r} in this scene; objects: {sorted(self.by_name)}"
            ) from None

    def new_name(self, label: str) -> str:
        """``label`` as a name no object has yet (``name_2``, ``name_3``... after)."""
        name = slug(label)
        if name in self.by_name:
            for i in itertools.count(2):
                if f"{name}_{i}" not in self.by_name:
                    return f"{name}_{i}"
        return name

    def add(self, handle: SceneHandle) -> None:
        self.by_name[handle.name] = handle

    def discard(self, handle: SceneHandle) -> None:
        self.by_name.pop(handle.name, None)
        handle.removed = True

    def clear(self) -> None:
        for handle in self.by_name.values():
            handle.removed = True
        self.by_name.clear()

    def triads(self) -> list[FrameHandle]:
        return [h for h in self.by_name.values() if isinstance(h, FrameHandle)]

    def frame_paths(self) -> dict[str, str]:
        """Frame name -> pose path of its (first) triad."""
        out: dict[str, str] = {}
        for handle in self.triads():
            out.setdefault(handle.frame.name, handle.pose_path)
        return out

    def triad_at(self, pose_path: str) -> FrameHandle:
        """The (first) triad whose pose is at ``pose_path``."""
        return next(h for h in self.triads() if h.pose_path == pose_path)

    def drawn(self, name: str, owner: str) -> str:
        """``name`` when a triad of that frame is drawn, else a ValueError."""
        paths = self.frame_paths()
        if name not in paths:
            raise ValueError(
                f"{owner}: frame {name!r} is not drawn in this scene; "
                f"add_frame({name!r}) first (drawn: {sorted(paths)})"
            )
        return name

    def checked_frame_name(self, name, trait: str) -> str:
        """What the view's ``selected`` (a registered frame) and ``follow``
        (a drawn one) accept, from Python and from the browser."""
        if not isinstance(name, str):
            raise ValueError(f"Scene.{trait} must be a frame name, got {name!r}")
        # a registered frame always has a name
        resolved = cast(str, frames.resolve_frame(name, f"Scene.{trait}").name)
        if trait == "follow":
            self.drawn(resolved, "Scene.follow")
        return resolved
