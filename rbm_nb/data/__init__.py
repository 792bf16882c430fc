"""Example data: the real head/eye recordings via pooch, and a synthetic stand-in.

``example_data["head"]`` is the local path of the real ``head.nc`` (downloaded
on first use); :func:`load_example` returns datasets and falls back to
:func:`synthetic_head_eye`, a recording with the same schema generated
offline. The generator and loaders are imported on first use, so that
``rbm.example_data`` stays cheap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._infra.lazy import lazy_attributes
from .fetch import ExampleDataStore, ExampleDataUnavailable, example_data

_LAZY = {
    "load_example": "load",
    "last_choice": "load",
    "DataChoice": "load",
    "write_synthetic_rosbag": "load",
    "synthetic_head_eye": "synthetic",
    "HeadEyeRecording": "synthetic",
}

__all__ = ["ExampleDataStore", "ExampleDataUnavailable", "example_data", *_LAZY]


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY)

if TYPE_CHECKING:  # pragma: no cover - static analysers see the real names
    from .load import DataChoice, last_choice, load_example, write_synthetic_rosbag  # noqa: F401
    from .synthetic import HeadEyeRecording, synthetic_head_eye  # noqa: F401
