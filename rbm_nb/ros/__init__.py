"""The ``ros`` namespace of the reference API, with no ROS installation needed.

Rosbags are read and written through the pure-Python ``rosbags`` package; the
tf2 buffer, the publishers and the playback widget run on rbm_nb's own frame
core and meshcat scene. Names are resolved on first use.
"""

from __future__ import annotations

import importlib

_EXPORTS: dict[str, str] = {
    "RosbagReader": "reader",
    "RosbagWriter": "writer",
    "play_publisher": "playback",
    "Transformer": "transformer",
    "ReferenceFrameTransformBroadcaster": "publishers",
    "ReferenceFrameMarkerPublisher": "publishers",
    "init_node": "publishers",
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
