"""The ``ros`` namespace of the reference API, with no ROS installation needed.

Rosbags are read and written through the pure-Python ``rosbags`` package; the
tf2 buffer, the publishers and the playback widget run on rbm_nb's own frame
core and meshcat scene. Names are resolved on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._infra.lazy import lazy_attributes

_EXPORTS: dict[str, str] = {
    "RosbagReader": "reader",
    "RosbagWriter": "writer",
    "play_publisher": "playback",
    "Transformer": "transformer",
    "load_tf_tree": "tf_tree",
    "register_frames_from_bag": "tf_tree",
    "ReferenceFrameTransformBroadcaster": "publishers",
    "ReferenceFrameMarkerPublisher": "publishers",
    "init_node": "publishers",
    "ExtrapolationError": "transformer",
}

__all__ = sorted(_EXPORTS)


__getattr__, __dir__ = lazy_attributes(__name__, _EXPORTS)

if TYPE_CHECKING:  # pragma: no cover - static analysers see the real names
    from .playback import play_publisher  # noqa: F401
    from .publishers import (  # noqa: F401
        ReferenceFrameMarkerPublisher,
        ReferenceFrameTransformBroadcaster,
        init_node,
    )
    from .reader import RosbagReader  # noqa: F401
    from .tf_tree import load_tf_tree, register_frames_from_bag  # noqa: F401
    from .transformer import ExtrapolationError, Transformer  # noqa: F401
    from .writer import RosbagWriter  # noqa: F401
