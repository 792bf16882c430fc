"""meshcat scenes in the notebook: live viewer, handles, publishers, HTML export.

Names are resolved on first use, so ``import rbm_nb.scene`` stays cheap.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "Scene": "scene",
    "FramePublisher": "publishers",
    "PathPublisher": "publishers",
    "ViewerServer": "server",
    "get_server": "server",
    "shutdown_server": "server",
    "default_scene": "scene",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        module = importlib.import_module(f"{__name__}.{_EXPORTS[name]}")
        value = getattr(module, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return __all__
