"""meshcat scenes in the notebook: a widget over the kernel comm, handles, publishers, HTML export.

Names are resolved on first use, so ``import rbm_nb.scene`` stays cheap.
"""

from __future__ import annotations

from .._lazy import lazy_attributes

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
