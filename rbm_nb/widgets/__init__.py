"""ipywidgets panels for the notebook: the frame tree and the playback player.

``rbm_nb.widgets`` itself imports nothing heavy; ipywidgets is loaded when a
widget class is first used.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._infra.lazy import lazy_attributes

_EXPORTS = {
    "Player": "player",
    "FrameTree": "frame_tree",
    "TimeSeries": "timeseries",
    "FrameSliders": "teaching",
    "check_answer": "teaching",
}

__all__ = sorted(_EXPORTS)


__getattr__, __dir__ = lazy_attributes(__name__, _EXPORTS)

if TYPE_CHECKING:  # pragma: no cover - static analysers see the real names
    from .frame_tree import FrameTree  # noqa: F401
    from .player import Player  # noqa: F401
    from .teaching import FrameSliders, check_answer  # noqa: F401
    from .timeseries import TimeSeries  # noqa: F401
