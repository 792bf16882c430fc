"""Compatibility names for point-in-time lookups (the engine holds them now).

:mod:`rbm_nb._engine.at_time` works on resolved frames; the functions here
accept names too, for code written against the earlier private module
(``rbm_nb.ros.transformer``). New code uses ``lookup_transform(..., time=)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._engine import at_time as _engine
from .errors import ExtrapolationError
from .frames import resolve_frame
from .lookups import lookup_at

__all__ = [
    "ExtrapolationError",
    "transform_at_times",
    "latest_common_time",
    "lookup_at",
]


def transform_at_times(
    outof: Any, into: Any, times: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Translation and rotation from ``outof`` to ``into`` at ``times``.

    See :func:`rbm_nb._engine.at_time.transform_at_times`.
    """
    t, r, _ = _engine.transform_at_times(
        resolve_frame(outof, "outof"), resolve_frame(into, "into"), times
    )
    return t, r


def latest_common_time(outof: Any, into: Any) -> Any:
    """See :func:`rbm_nb._engine.at_time.latest_common_time`."""
    return _engine.latest_common_time(
        resolve_frame(outof, "outof"), resolve_frame(into, "into")
    )
