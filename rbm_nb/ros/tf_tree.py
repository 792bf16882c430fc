"""A bag's whole tf tree in one call: into a Transformer or the frame registry.

Most ROS bags keep their frames on ``/tf`` and ``/tf_static``
(``tf2_msgs/TFMessage``). :func:`register_frames_from_bag` registers every
parent/child pair as a reference frame (static pairs as static frames, the
others as moving frames with datetime64 timestamps);
:meth:`rbm_nb.ros.Transformer.from_bag` fills a tf2-style buffer from
:func:`load_tf_tree` (this module does not know the Transformer).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from ..core.frames import ReferenceFrame, check_frame_name, register_frame, registry
from .reader import RosbagReader

__all__ = ["load_tf_tree", "register_frames_from_bag"]


def load_tf_tree(
    bag_file: str | os.PathLike, topics: Sequence[str] | None = None
) -> dict:
    """The tf pairs of a bag, checked to form trees, parents before children.

    Parameters
    ----------
    bag_file : str or path-like
        A ROS1 ``.bag`` or a ROS2 bag folder.
    topics : sequence of str, optional
        tf topics (default: ``/tf`` and ``/tf_static`` where present).

    Returns
    -------
    dict
        ``{child_frame_id: TfPair}`` in an order where every parent comes
        before its children (see :meth:`RosbagReader.load_tf`).

    Raises
    ------
    ValueError
        If a frame has two parents or the transforms form a loop (both
        named), or the bag has no tf topic.
    """
    with RosbagReader(bag_file) as reader:
        pairs = reader.load_tf(topics)
    by_child: dict = {}
    for (parent, child), pair in pairs.items():
        if child in by_child:
            raise ValueError(
                f"{bag_file}: frame {child!r} has two parents in tf, "
                f"{by_child[child].frame_id!r} and {parent!r}; a tf tree allows one"
            )
        if parent == child:
            raise ValueError(f"{bag_file}: frame {child!r} is its own parent in tf")
        by_child[child] = pair
    ordered: dict = {}

    def visit(child, seen):
        if child in ordered or child not in by_child:
            return
        if child in seen:
            raise ValueError(
                f"{bag_file}: the tf transforms form a loop through {sorted(seen)}"
            )
        visit(by_child[child].frame_id, seen | {child})
        ordered[child] = by_child[child]

    for child in by_child:
        visit(child, frozenset())
    return ordered


def register_frames_from_bag(
    bag_file: str | os.PathLike,
    topics: Sequence[str] | None = None,
    *,
    update: bool = False,
) -> list[str]:
    """Register every frame of a bag's tf tree in the frame registry.

    Roots (frames that are only parents, e.g. ``map`` or ``odom``) are
    registered as root frames unless a frame of that name is registered
    already, which then becomes the parent. Moving pairs get datetime64[ns]
    timestamps, exact to the nanosecond of the header stamps.

    Parameters
    ----------
    bag_file : str or path-like
    topics : sequence of str, optional
        tf topics (default: ``/tf`` and ``/tf_static`` where present).
    update : bool, default False
        Replace frames of the same names that are registered already
        (otherwise that is an error, as in :func:`rbm_nb.register_frame`).

    Returns
    -------
    list of str
        The names registered, parents before children.

    Raises
    ------
    ValueError
        See :func:`load_tf_tree`; also if a frame exists and ``update`` is
        False.
    """
    tree = load_tf_tree(bag_file, topics)
    for child, pair in tree.items():
        for name in (pair.frame_id, child):
            try:
                check_frame_name(name)
            except ValueError as err:  # before any is registered
                raise ValueError(f"{bag_file}: {err}") from None
    taken = sorted(name for name in tree if name in registry)
    if taken and not update:
        # checked first, so that a refused call registers nothing
        raise ValueError(
            f"frames {taken} from the tf tree of {bag_file} are registered already; "
            "pass update=True to replace them"
        )
    names = []
    children = set(tree)
    for pair in tree.values():
        if pair.frame_id not in children and pair.frame_id not in registry:
            register_frame(pair.frame_id)
            names.append(pair.frame_id)
    for child, pair in tree.items():
        if pair.static:
            frame = ReferenceFrame(
                child, parent=pair.frame_id,
                translation=pair.position[-1], rotation=pair.orientation[-1],
            )  # fmt: skip
        else:
            frame = ReferenceFrame(
                child, parent=pair.frame_id,
                translation=pair.position, rotation=pair.orientation,
                timestamps=pair.stamps_ns.astype("datetime64[ns]"),
            )  # fmt: skip
        frame.register(update=update)
        names.append(child)
    return names


def time_span(tree: dict) -> float:
    """Seconds from the first to the last moving sample of a tree (0 if none)."""
    stamps = [p.stamps_ns for p in tree.values() if not p.static]
    if not stamps:
        return 0.0
    all_ns = np.concatenate(stamps)
    return float(all_ns.max() - all_ns.min()) / 1e9
