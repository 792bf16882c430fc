"""ipywidgets panels for the notebook: the frame tree and the playback player.

``rbm_nb.widgets`` itself imports nothing heavy; ipywidgets is loaded when a
widget class is first used.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "Player": "player",
    "FrameTree": "frame_tree",
    "TimeSeries": "timeseries",
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
