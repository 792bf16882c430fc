"""Example data: the real head/eye recordings via pooch, and a synthetic stand-in.

``example_data["head"]`` is the local path of the real ``head.nc`` (downloaded
on first use); :func:`load_example` returns datasets and falls back to
:func:`synthetic_head_eye`, a recording with the same schema generated
offline. The generator and loaders are imported on first use, so that
``rbm.example_data`` stays cheap.
"""

from __future__ import annotations

import importlib

from .fetch import ExampleDataStore, ExampleDataUnavailable, example_data

_LAZY = {
    "load_example": "load",
    "write_synthetic_rosbag": "load",
    "synthetic_head_eye": "synthetic",
    "HeadEyeRecording": "synthetic",
}

__all__ = ["ExampleDataStore", "ExampleDataUnavailable", "example_data", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
