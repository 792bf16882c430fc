"""The ``ros`` namespace of the reference API, with no ROS installation needed.

Rosbags are read and written through the pure-Python ``rosbags`` package; the
tf2 buffer, the publishers and the playback widget run on rbm_nb's own frame
core and meshcat scene. Names are resolved on first use.
"""

from __future__ import annotations

from .._lazy import lazy_attributes

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
