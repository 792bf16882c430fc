"""What every part of a :class:`~rbm_nb.scene.Scene` shares: one small object.

The facade's parts (anchors, camera, grid, selection, player link, view
link) each own their own state; what they all need is the scene's identity
(base frame, name, sample budget), its content (:class:`SceneState`), the
lock that makes one change atomic and whether the scene is closed. They get
this object as an argument instead of reaching into the facade.
"""

from __future__ import annotations

import itertools
import re
import threading
import uuid
from dataclasses import dataclass, field

import numpy as np

from ..core import frames
from .state import SceneState

_counter = itertools.count(1)


@dataclass
class SceneContext:
    """The scene's identity, content and lock, shared by its parts.

    Attributes
    ----------
    base : ReferenceFrame
        The fixed frame everything is drawn in.
    name : str
        The scene's name (in messages).
    max_samples : int or None
        Samples per moving object sent at once to a live view (None: all).
    state : SceneState
        What the scene contains (plain data).
    """

    base: object
    name: str
    max_samples: int | None
    state: SceneState = field(default_factory=SceneState)
    lock: threading.RLock = field(default_factory=threading.RLock)
    closed: bool = False

    @classmethod
    def checked(cls, base, name: str | None, max_samples) -> SceneContext:
        """The context of ``Scene(base, name=name, max_samples=max_samples)``,
        its arguments checked (a name is made up when None)."""
        base = frames.resolve_frame(base, "Scene: base")
        if name is None:
            name = f"scene-{next(_counter)}-{uuid.uuid4().hex[:6]}"
        if not re.fullmatch(r"[A-Za-z0-9_\-]+", name):
            raise ValueError(
                f"Scene: name must be letters, digits, '-' or '_', got {name!r}"
            )
        if max_samples is not None and (
            isinstance(max_samples, bool)
            or not isinstance(max_samples, (int, np.integer))
            or max_samples < 2
        ):
            raise ValueError(
                f"Scene: max_samples must be an integer >= 2 or None, got {max_samples!r}"
            )
        return cls(base, name, None if max_samples is None else int(max_samples))

    def check_open(self) -> None:
        if self.closed:
            raise RuntimeError(f"scene {self.name!r} is closed; create a new Scene")
