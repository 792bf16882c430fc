"""meshcat scenes in the notebook: a widget over the kernel comm, handles, publishers, HTML export.

Names are resolved on first use, so ``import rbm_nb.scene`` stays cheap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._infra.lazy import lazy_attributes

_EXPORTS = {
    "Scene": "scene",
    "FramePublisher": "publishers",
    "PathPublisher": "publishers",
    "SceneState": "state",
    "SceneWidget": "widget",
    "default_scene": "scene",
}

__all__ = sorted(_EXPORTS)


__getattr__, __dir__ = lazy_attributes(__name__, _EXPORTS)

if TYPE_CHECKING:  # pragma: no cover - static analysers see the real names
    from .publishers import FramePublisher, PathPublisher  # noqa: F401
    from .scene import Scene, default_scene  # noqa: F401
    from .state import SceneState  # noqa: F401
    from .widget import SceneWidget  # noqa: F401
