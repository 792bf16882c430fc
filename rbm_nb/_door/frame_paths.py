"""Frame-path queries: the chain between two frames, and frames found by path.

``frames_between(a, b)`` lists the frames a transform from ``a`` to ``b``
passes through: up from ``a`` to the closest common ancestor, then down to
``b``.

``find_frame(path)`` looks a frame up in the trees of the registry with a
path of frame names from an ancestor down to the frame, separated by ``/``:

* ``"world/head/left_eye"``: each frame is a direct child of the one before;
* ``"world/.../left_eye"``: ``...`` stands for any chain of frames, so
  ``left_eye`` is anywhere below ``world``;
* ``"*"``, ``"?"`` and ``"[...]"`` inside a name work as in shell globs
  (``"world/*/left_eye"``: exactly one frame in between, any name);
* a leading ``/`` anchors the path at a root (``"/world/head"``); without it
  the first name may be any frame, so ``"left_eye"`` finds the one frame of
  that name.

Exactly one frame must match: no match is an error that suggests close
names, several matches an error that lists them.

Everything here works on resolved frames; :mod:`rbm_nb.frames` resolves
names and supplies the registry's frames (this module never imports it).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from fnmatch import fnmatchcase
from typing import Any

from .._engine.chain import chain

__all__ = ["find_frame", "frames_between", "frame_path"]

_ANY_CHAIN = "..."


def frame_path(frame: Any) -> str:
    """The names from the root down to ``frame``, joined by ``/``.

    Examples
    --------
    >>> from rbm_nb.frames import ReferenceFrame
    >>> world = ReferenceFrame("world")
    >>> eye = ReferenceFrame("eye", parent=ReferenceFrame("head", parent=world))
    >>> frame_path(eye)
    'world/head/eye'
    >>> [f.name for f in frames_between(eye, world, include_self=False)]
    ['head', 'world']
    """
    return "/".join(str(f.name) for f in frame.path)


def frames_between(
    start: Any, end: Any, *, include_self: bool = True, include_to_frame: bool = True
) -> tuple:
    """The frames on the way from ``start`` to ``end``, in order.

    Parameters
    ----------
    start, end : ReferenceFrame
        Frames of the same tree.
    include_self, include_to_frame : bool, default True
        Whether the two end frames are part of the result.

    Returns
    -------
    tuple of ReferenceFrame
        Up from ``start`` to the closest common ancestor (included once),
        then down to ``end``: the frames the transform chain of
        :func:`rbm_nb._engine.chain.chain` steps through, plus the common
        ancestor. ``frames_between(a, a)`` is ``(a,)``.

    Raises
    ------
    ValueError
        If the frames are in different trees.
    """
    chain(start, end)  # the engine's check (and message) for different trees
    up = list(reversed(start.path))  # start .. root
    down = list(reversed(end.path))
    i, j = len(up), len(down)
    while i > 1 and j > 1 and up[i - 2] is down[j - 2]:
        i -= 1
        j -= 1
    # up[i - 1] is the common ancestor
    path = up[:i] + list(reversed(down[: j - 1]))
    if not include_self:
        path = path[1:]
    if not include_to_frame and path and path[-1] is end:
        path = path[:-1]
    return tuple(path)


def _parse(path):
    if not isinstance(path, str):
        raise ValueError(f"path must be a string such as 'world/.../eye', got {path!r}")
    anchored = path.startswith("/")
    parts = path[1:].split("/") if anchored else path.split("/")
    patterns: list[str] = []
    gaps: list[bool] = []
    gap = False
    for k, part in enumerate(parts):
        if part == _ANY_CHAIN:
            gap = True
            continue
        if not part:
            raise ValueError(
                f"path {path!r} has an empty element (at position {k}); use names "
                f"or '...' between the slashes"
            )
        patterns.append(part)
        gaps.append(gap)
        gap = False
    if not patterns:
        raise ValueError(f"path {path!r} names no frame")
    if gap:
        raise ValueError(f"path {path!r} must end with a frame name, not with '...'")
    # a leading '...' only matters for anchored paths: it releases the anchor
    if gaps[0]:
        anchored = False
    return patterns, gaps, anchored


def _matches(node, k, patterns, gaps, anchored) -> bool:
    """Whether ``node`` can be the frame of pattern ``k``, with 0..k-1 above it."""
    if node.name is None or not fnmatchcase(node.name, patterns[k]):
        return False
    if k == 0:
        return not anchored or node.parent is None
    if gaps[k]:
        above = node.parent
        while above is not None:
            if _matches(above, k - 1, patterns, gaps, anchored):
                return True
            above = above.parent
        return False
    return node.parent is not None and _matches(
        node.parent, k - 1, patterns, gaps, anchored
    )


def find_frame(path: str, frames: Iterable[Any]) -> Any:
    """The single frame of ``frames`` that matches ``path``.

    Parameters
    ----------
    path : str
        Frame names from an ancestor down to the wanted frame, separated by
        ``/``; ``...`` stands for any chain of frames, ``*``/``?``/``[...]``
        are name wildcards, a leading ``/`` anchors at a root.
    frames : iterable of ReferenceFrame
        The frames to search (the registry's trees, roots first).

    Returns
    -------
    ReferenceFrame

    Raises
    ------
    ValueError
        If no frame matches (the message suggests close names) or several do
        (the message lists their full paths).

    """
    patterns, gaps, anchored = _parse(path)
    frames = list(frames)
    found = [
        f for f in frames if _matches(f, len(patterns) - 1, patterns, gaps, anchored)
    ]
    if len(found) == 1:
        return found[0]
    if found:
        listing = ", ".join(repr(frame_path(f)) for f in found)
        raise ValueError(
            f"{len(found)} frames match the path {path!r}: {listing}; give more of "
            f"the path to pick one"
        )
    named = [f for f in frames if f.name is not None]
    if not named:
        raise ValueError(f"no frame matches the path {path!r}: the registry is empty")
    close = difflib.get_close_matches(
        patterns[-1], sorted({f.name for f in named}), n=3
    )
    if close:
        # closest names first
        hint = ", ".join(
            repr(frame_path(f)) for c in close for f in named if f.name == c
        )
        raise ValueError(f"no frame matches the path {path!r}; close names: {hint}")
    known = ", ".join(repr(frame_path(f)) for f in named[:12])
    more = " ..." if len(named) > 12 else ""
    raise ValueError(f"no frame matches the path {path!r} (frames: {known}{more})")
