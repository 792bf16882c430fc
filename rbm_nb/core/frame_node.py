"""The tree a reference frame is a node of: links and navigation.

:class:`FrameNode` is a base class of
:class:`~rbm_nb.core.frames.ReferenceFrame`: the walks up and down the tree
(``path``, ``root``, ``descendants``, ``leaves`` ...) that need no frame
names, no registry and no data. ``ReferenceFrame`` keeps the links
(``_parent``, ``_children``) right: it sets them in its ``parent`` setter,
the one place the tree changes (cycles refused there).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar, cast

__all__ = ["FrameNode"]

_N = TypeVar("_N", bound="FrameNode")


class FrameNode:
    """A node of a tree of frames: the navigation of ``ReferenceFrame``.

    Not used on its own: ``ReferenceFrame`` derives from it and sets the
    links declared below.
    """

    # set by ReferenceFrame (its constructor and parent setter); read here
    _parent: FrameNode | None
    _children: Sequence[FrameNode]

    @property
    def children(self) -> tuple:
        """The frames whose parent this is, in order of attachment."""
        return tuple(self._children)

    def _path_to_root(self: _N) -> list[_N]:
        path: list[FrameNode] = []
        node: FrameNode | None = self
        while node is not None:
            path.append(node)
            node = node._parent
        # a node's parent is a node of its own class (ReferenceFrame's setter)
        return cast("list[_N]", path)

    def iter_path_reverse(self) -> Any:
        """Iterate from this frame up to the root (inclusive)."""
        node: FrameNode | None = self
        while node is not None:
            yield node
            node = node._parent

    @property
    def path(self) -> tuple:
        """The frames from the root down to this one."""
        return tuple(reversed(self._path_to_root()))

    @property
    def ancestors(self) -> tuple:
        """The frames from the root down to the parent."""
        return self.path[:-1]

    @property
    def root(self: _N) -> _N:
        """The root of this frame's tree."""
        return self._path_to_root()[-1]

    @property
    def depth(self) -> int:
        """Number of edges between this frame and the root."""
        return len(self._path_to_root()) - 1

    @property
    def descendants(self) -> tuple:
        """Every frame below this one, depth first."""
        out = []
        stack = list(reversed(self._children))
        while stack:
            node = stack.pop()
            out.append(node)
            stack.extend(reversed(node._children))
        return tuple(out)

    @property
    def height(self) -> int:
        """Number of edges on the longest path down to a leaf."""
        if not self._children:
            return 0
        return 1 + max(child.height for child in self._children)

    @property
    def is_root(self) -> bool:
        return self._parent is None

    @property
    def is_leaf(self) -> bool:
        return not self._children

    @property
    def leaves(self) -> tuple:
        """The frames without children at or below this one."""
        if not self._children:
            return (self,)
        return tuple(node for node in self.descendants if not node._children)

    @property
    def siblings(self) -> tuple:
        """The other children of this frame's parent."""
        if self._parent is None:
            return ()
        return tuple(c for c in self._parent._children if c is not self)
