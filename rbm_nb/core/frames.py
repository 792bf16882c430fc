"""Reference frames, the trees they form, and the registry of named frames.

A :class:`ReferenceFrame` is a node in a tree: its translation and rotation
map points given in the frame into its parent (``p_parent = rot(r, p) + t``),
either once (static) or per timestamp (moving; ``discrete`` frames hold each
value until the next event). Arrays are validated once, here, and kept in
one immutable value (:attr:`ReferenceFrame.data`, a
:class:`~rbm_nb._engine.frame_data.FrameData`), so lookups never re-check
them; a frame that changes (parent, name, ``discrete``, ``max_gap``) makes a
new value for itself and the frames below it.

This module is the one place where frame names are resolved
(:func:`resolve_frame`); the methods resolve their frame arguments and
forward to the engine (:mod:`rbm_nb._engine`), which reads the frames'
values, keys its caches by them, and never imports this module.
``ReferenceFrame``'s methods come from its base classes too, one job each:
:class:`~rbm_nb.core.frame_node.FrameNode` (walking the tree),
:class:`~rbm_nb.core.frame_constructors.FrameConstructors` (``from_dataset``
and the other classmethods) and
:class:`~rbm_nb.core.frame_transforms.FrameTransforms` (lookups and
transforms, resolving names through ``ReferenceFrame._resolve``).
"""

from __future__ import annotations

import difflib
import unicodedata
from collections.abc import Callable, Iterator, MutableMapping
from typing import Any, TypeAlias

import numpy as np

from .._door import frame_paths as _frame_paths
from .._door.unpack import ArrayInput
from .._engine import chain as _chain
from .._engine.frame_data import FrameData, Samples
from .frame_constructors import FrameConstructors
from .frame_node import FrameNode
from .frame_samples import _check_discrete, _checked_max_gap, _samples
from .frame_transforms import FrameTransforms

__all__ = [
    "ReferenceFrame",
    "registry",
    "register_frame",
    "deregister_frame",
    "clear_registry",
    "render_tree",
    "find_frame",
    "frames_between",
    "FrameLike",
    "resolve_frame",
    "on_registry_change",
    "remove_registry_callback",
]


# A frame argument: the frame itself or the name it is registered under.
FrameLike: TypeAlias = "ReferenceFrame | str"

# ---------------------------------------------------------------------------
# registry
# ---------------------------------------------------------------------------


class FrameRegistry(MutableMapping):
    """Mapping of names to registered frames.

    Change it with :func:`register_frame`, :meth:`ReferenceFrame.register`,
    :func:`deregister_frame` and :func:`clear_registry`, or as a dict
    (``registry[name] = frame``, ``del registry[name]``, as in
    rigid-body-motion); observers added with :func:`on_registry_change` are
    told about every change.
    """

    def __init__(self) -> None:
        self._frames: dict[str, ReferenceFrame] = {}
        self._callbacks: list[Callable[[str, str | None], None]] = []

    def __getitem__(self, name: str) -> ReferenceFrame:
        return self._frames[name]

    def __setitem__(self, name: str, frame: ReferenceFrame) -> None:
        if not isinstance(frame, ReferenceFrame):
            raise TypeError(
                f"registry[{name!r}] must be a ReferenceFrame, got "
                f"{type(frame).__name__}"
            )
        if not isinstance(name, str):
            raise TypeError(f"registry keys are frame names (str), got {name!r}")
        check_frame_name(name)
        self._frames[name] = frame
        self._notify("register", name)

    def __delitem__(self, name: str) -> None:
        if name not in self._frames:
            raise KeyError(_not_found_message(name))
        del self._frames[name]
        self._notify("deregister", name)

    def __iter__(self) -> Iterator[str]:
        return iter(self._frames)

    def __len__(self) -> int:
        return len(self._frames)

    def __contains__(self, name) -> bool:
        return name in self._frames

    def __repr__(self) -> str:
        return repr(self._frames)

    def _notify(self, event: str, name: str | None) -> None:
        for callback in list(self._callbacks):
            callback(event, name)


registry = FrameRegistry()


def on_registry_change(callback: Callable[[str, str | None], None]) -> Any:
    """Call ``callback(event, name)`` after every change of the registry.

    ``event`` is ``"register"``, ``"deregister"`` or ``"clear"`` (with
    ``name`` None). Returns the callback, so this works as a decorator.
    """
    registry._callbacks.append(callback)
    return callback


def remove_registry_callback(callback: Any) -> None:
    """Stop calling a callback added with :func:`on_registry_change`."""
    try:
        registry._callbacks.remove(callback)
    except ValueError:
        raise ValueError(f"{callback!r} is not a registry callback") from None


def _register(frame: ReferenceFrame, update: bool = False) -> None:
    name = frame.name
    if name is None:
        raise ValueError("cannot register a frame without a name; pass name=...")
    old = registry._frames.get(name)
    if old is not None and not update:
        # also for the same object again (as rigid-body-motion)
        raise ValueError(
            f"a frame named {name!r} is already registered; pass update=True "
            f"to replace it"
        )
    if old is not None and old is not frame:
        # check first, change after: a failed update leaves the tree as it was
        above = set(map(id, frame._path_to_root()))
        for child in old.children:
            if id(child) in above:
                raise ValueError(
                    f"cannot replace {name!r}: the new frame is {child.name!r} or "
                    f"below it, and {child.name!r} would become its own ancestor "
                    f"(a cycle)"
                )
        # the new frame takes over the old one's children, so that frames
        # below it see the new data instead of a detached copy
        for child in old.children:
            child.parent = frame
        old.parent = None
    registry._frames[name] = frame
    registry._notify("register", name)


def _deregister(name: str) -> None:
    if name not in registry._frames:
        raise ValueError(_not_found_message(name))
    del registry._frames[name]
    registry._notify("deregister", name)


def _not_found_message(name: str) -> str:
    names = list(registry._frames)
    close = difflib.get_close_matches(str(name), names, n=3)
    msg = f"frame {name!r} not found in registry"
    if close:
        msg += "; did you mean " + " or ".join(repr(c) for c in close) + "?"
    elif names:
        msg += f" (registered: {', '.join(repr(n) for n in names)})"
    else:
        msg += " (the registry is empty)"
    return msg


def resolve_frame(frame: Any, argument: str = "frame") -> ReferenceFrame:
    """A ReferenceFrame from a frame or the name of a registered one.

    Parameters
    ----------
    frame : ReferenceFrame or str
    argument : str
        How the argument is called in error messages.

    Raises
    ------
    ValueError
        If no frame of that name is registered (the message suggests close
        names).
    TypeError
        If ``frame`` is neither a frame nor a string.
    """
    if isinstance(frame, ReferenceFrame):
        return frame
    if isinstance(frame, str):
        try:
            return registry._frames[frame]
        except KeyError:
            raise ValueError(f"{argument}: {_not_found_message(frame)}") from None
    raise TypeError(
        f"{argument} must be a ReferenceFrame or the name of a registered frame, "
        f"got {type(frame).__name__}"
    )


def register_frame(
    name: str | None,
    parent: FrameLike | None = None,
    translation: ArrayInput | None = None,
    rotation: ArrayInput | None = None,
    timestamps: Any = None,
    inverse: bool = False,
    discrete: bool = False,
    update: bool = False,
    max_gap: float | None = None,
) -> None:
    """Create a reference frame and register it under ``name``.

    Parameters are those of :class:`ReferenceFrame` (including ``max_gap``,
    the longest gap in seconds interpolated across), plus

    update : bool, default False
        Replace a frame already registered under this name (its children
        move to the new frame). Otherwise that is an error.
    """
    frame = ReferenceFrame(
        name,
        parent=parent,
        translation=translation,
        rotation=rotation,
        timestamps=timestamps,
        inverse=inverse,
        discrete=discrete,
        max_gap=max_gap,
    )
    try:
        _register(frame, update=update)
    except ValueError:
        frame.parent = None  # not registered: not in the tree either
        raise


def deregister_frame(name: str) -> None:
    """Remove the frame registered under ``name`` from the registry."""
    _deregister(name)


def clear_registry() -> None:
    """Remove every frame from the registry."""
    registry._frames.clear()
    registry._notify("clear", None)


def check_frame_name(name: str) -> None:
    """Refuse a frame name with control characters (ESC, BEL, NUL, ...).

    Frame ids come from files (rosbags); printed by :func:`render_tree` or in
    an error, an ESC could rewrite the user's terminal.
    """
    for index, char in enumerate(name):
        if unicodedata.category(char) == "Cc":
            raise ValueError(
                f"frame name {name!r} has the control character U+{ord(char):04X} "
                f"at index {index}; frame names must be printable"
            )


def render_tree(root: FrameLike) -> None:
    """Print the tree below ``root`` (a frame or a registered name).

    Examples
    --------
    >>> world = ReferenceFrame("world")
    >>> _ = ReferenceFrame("observer", parent=world)
    >>> _ = ReferenceFrame("body", parent=world)
    >>> render_tree(world)
    world
    ├── observer
    └── body
    """
    for line in _tree_lines(resolve_frame(root, "root")):
        print(line)


def _registry_frames() -> list[ReferenceFrame]:
    """Every frame in the trees that registered frames belong to, roots first."""
    seen: set[int] = set()
    out: list[ReferenceFrame] = []
    for frame in registry._frames.values():
        root = frame.root
        if id(root) in seen:
            continue
        seen.add(id(root))
        out.append(root)
        out.extend(root.descendants)
    return out


def find_frame(path: str) -> ReferenceFrame:
    """The one frame of the registry's trees matching ``path``, e.g. ``"world/.../eye"``.

    See :mod:`rbm_nb._door.frame_paths` for the path syntax.

    Raises
    ------
    ValueError
        If no frame matches (the message suggests close names) or several do
        (the message lists their full paths).

    Examples
    --------
    >>> world = ReferenceFrame("world"); world.register()
    >>> head = ReferenceFrame("head", parent=world)
    >>> eye = ReferenceFrame("left_eye", parent=head)
    >>> find_frame("world/.../left_eye") is eye
    True
    >>> clear_registry()
    """
    return _frame_paths.find_frame(path, _registry_frames())


def frames_between(
    frame: ReferenceFrame | str,
    to_frame: ReferenceFrame | str,
    *,
    include_self: bool = True,
    include_to_frame: bool = True,
) -> tuple[ReferenceFrame, ...]:
    """The frames on the way from ``frame`` to ``to_frame`` (names resolved).

    See :func:`rbm_nb._door.frame_paths.frames_between`.
    """
    return _frame_paths.frames_between(
        resolve_frame(frame, "frame"),
        resolve_frame(to_frame, "to_frame"),
        include_self=include_self,
        include_to_frame=include_to_frame,
    )


def _tree_lines(frame: ReferenceFrame, prefix: str = "", branch: str = ""):
    yield f"{prefix}{branch}{frame.name}"
    if branch:
        prefix += "    " if branch.startswith("└") else "│   "
    children = frame.children
    for i, child in enumerate(children):
        yield from _tree_lines(
            child, prefix, "└── " if i == len(children) - 1 else "├── "
        )


# ---------------------------------------------------------------------------
# the frame
# ---------------------------------------------------------------------------


class ReferenceFrame(FrameNode, FrameConstructors, FrameTransforms):
    """A three-dimensional reference frame, static or moving.

    Parameters
    ----------
    name : str, optional
        The name of the frame (needed to register it).
    parent : str or ReferenceFrame, optional
        The parent frame, or the name of a registered frame. Without a
        parent the frame is the root of a new tree.
    translation : array_like, shape (3,) or (n, 3), optional
        Position of this frame's origin in the parent frame (zeros if
        omitted). Shape (n, 3) with ``timestamps``; NaN rows of a moving
        frame mean "no data at that sample" (blinks, lost tracking).
    rotation : array_like, shape (4,) or (n, 4), optional
        Orientation of this frame wrt the parent as unit quaternions w, x, y,
        z (identity if omitted). Norms within ``UNIT_QUATERNION_TOLERANCE``
        of 1 are accepted (and normalised inside the math); NaN rows of a
        moving frame are missing samples.
    timestamps : array_like, shape (n,), optional
        Strictly increasing numeric or datetime64 times of a moving frame.
    inverse : bool, default False
        The translation and rotation describe the parent wrt this frame.
    discrete : bool, default False
        The timestamps are events: each transform holds until the next one
        instead of being interpolated.
    max_gap : float, optional
        The longest gap between two samples (in seconds) that lookups
        interpolate across; times inside a longer gap get NaN. Default None:
        no limit.
    missing : array_like of bool, shape (n,), optional
        Rows of a moving frame to treat as missing samples, as if they were
        NaN (e.g. samples below a confidence threshold). The same results as
        NaN-masked copies, without making them: arrays nobody can write any
        more (read-only down to their memory, as :func:`rbm_nb.data.load_example`
        returns them) are kept as they are, with this mask beside them.

    Raises
    ------
    ValueError
        If arrays have the wrong shape or values, the timestamps are not
        strictly increasing, a root frame is given a transform, or
        ``discrete`` is set without timestamps.
    """

    def __init__(
        self,
        name: str | None = None,
        parent: FrameLike | None = None,
        translation: ArrayInput | None = None,
        rotation: ArrayInput | None = None,
        timestamps: Any = None,
        inverse: bool = False,
        discrete: bool = False,
        max_gap: float | None = None,
        missing: Any = None,
    ) -> None:
        _check_name(name)
        self._parent: ReferenceFrame | None = None
        self._children: list[ReferenceFrame] = []
        # frames created as roots have no transform of their own (None)
        self._has_transform = parent is not None
        if parent is None:
            for arg, value in (
                ("translation", translation),
                ("rotation", rotation),
                ("timestamps", timestamps),
                ("missing", missing),
            ):
                if value is not None:
                    raise ValueError(
                        f"frame {name!r}: {arg} given without a parent frame; a "
                        f"root frame has no transform"
                    )
            identity = np.array([[1.0, 0.0, 0.0, 0.0]])
            samples = Samples(None, np.zeros((1, 3)), identity, identity)
        else:
            parent = resolve_frame(parent, "parent")
            samples = _samples(
                name, translation, rotation, timestamps, inverse, missing
            )
        _check_discrete(name, samples, discrete)
        # everything the engine reads, as one immutable value (made again,
        # with the frames below, whenever the frame changes: _remake)
        self._data = FrameData(
            name, None, samples, bool(discrete), _checked_max_gap(name, max_gap)
        )
        if parent is not None:
            self.parent = parent

    # -- data -------------------------------------------------------------

    @property
    def data(self) -> FrameData:
        """This frame as one immutable value: what the engine computes with.

        Its samples (prepared once, when the frame was built), options, name
        and its parent's value. Changing the frame (a new parent, name,
        ``discrete`` or ``max_gap``) makes a new value for it and for every
        frame below it; values already handed out stay as they were.
        """
        return self._data

    @property
    def name(self) -> str | None:
        """The name of the frame (None if it has none). Settable."""
        return self._data.name

    @name.setter
    def name(self, name: str | None) -> None:
        _check_name(name)
        self._remake(name=name)

    @property
    def discrete(self) -> bool:
        """Whether the timestamps are events held until the next one. Settable."""
        return self._data.discrete

    @discrete.setter
    def discrete(self, discrete: bool) -> None:
        _check_discrete(self.name, self._data.samples, discrete)
        self._remake(discrete=bool(discrete))

    @property
    def max_gap(self) -> float | None:
        """The longest gap (seconds) lookups interpolate across (None: no limit). Settable."""
        return self._data.max_gap

    @max_gap.setter
    def max_gap(self, max_gap: float | None) -> None:
        self._remake(max_gap=_checked_max_gap(self.name, max_gap))

    def _remake(self, **changes: Any) -> None:
        """Give this frame a new value with ``changes``, and the frames below
        new values holding it (a value holds its parent's)."""
        parent = self._parent
        changes["parent"] = None if parent is None else parent._data
        self._data = self._data.replace(**changes)
        stack = list(self._children)
        while stack:
            node = stack.pop()
            assert node._parent is not None  # (a child)
            node._data = node._data.replace(parent=node._parent._data)
            stack.extend(node._children)
        # the one place the engine hears of a change: results are right
        # without it (its caches are keyed by values), but the old values
        # may belong to frames that are gone, and their samples with them
        _chain.forget()

    @property
    def translation(self) -> Any:
        """Translation wrt the parent, shape (3,) or (n, 3); None for a root."""
        if not self._has_transform:
            return None
        data = self._data
        return _read_only(data.t if data.track is not None else data.t[0])

    @property
    def rotation(self) -> Any:
        """Rotation wrt the parent, shape (4,) or (n, 4); None for a root."""
        if not self._has_transform:
            return None
        data = self._data
        r = data.rotation
        return _read_only(r if data.track is not None else r[0])

    @property
    def timestamps(self) -> Any:
        """Timestamps of a moving frame as given, shape (n,); None if static."""
        track = self._data.track
        return None if track is None else _read_only(track.values)

    def __repr__(self) -> str:
        return f"<ReferenceFrame {self.name!r}>"

    __str__ = __repr__

    # -- tree -------------------------------------------------------------

    @property
    def parent(self) -> ReferenceFrame | None:
        """The parent frame (None for a root). Settable; cycles are refused."""
        return self._parent

    @parent.setter
    def parent(self, parent: FrameLike | None) -> None:
        if parent is not None:
            parent = resolve_frame(parent, "parent")
            node: ReferenceFrame | None = parent
            while node is not None:
                if node is self:
                    raise ValueError(
                        f"cannot make {parent.name!r} the parent of {self.name!r}: "
                        f"{parent.name!r} is {self.name!r} or below it, which would "
                        f"make a cycle"
                    )
                node = node._parent
        if self._parent is not None:
            self._parent._children.remove(self)
        self._parent = parent
        if parent is not None:
            parent._children.append(self)
        self._remake()  # the chains through this frame changed

    def frames_between(
        self,
        to_frame: FrameLike,
        *,
        include_self: bool = True,
        include_to_frame: bool = True,
    ) -> Any:
        """The frames from this one up to the common ancestor and down to ``to_frame``.

        See :func:`rbm_nb._door.frame_paths.frames_between`.
        """
        return _frame_paths.frames_between(
            self,
            resolve_frame(to_frame, "to_frame"),
            include_self=include_self,
            include_to_frame=include_to_frame,
        )

    # -- registry ----------------------------------------------------------

    @staticmethod
    def _resolve(frame: Any, argument: str) -> ReferenceFrame:
        """:func:`resolve_frame`, for the methods of the base classes (which
        cannot import it: it is defined here, checking against this class)."""
        return resolve_frame(frame, argument)

    def register(self, update: bool = False) -> None:
        """Register this frame under its name (``update`` replaces another)."""
        _register(self, update=update)

    def deregister(self) -> None:
        """Remove this frame's name from the registry."""
        if self.name is None:
            raise ValueError("a frame without a name is not registered")
        _deregister(self.name)


def _check_name(name: Any) -> None:
    if name is not None and not isinstance(name, str):
        raise ValueError(f"name must be a string, got {type(name).__name__}")
    if name is not None:
        check_frame_name(name)


def _read_only(arr: np.ndarray) -> np.ndarray:
    """A view that cannot change the frame's data (kernels get the original)."""
    view = arr.view()
    view.setflags(write=False)
    return view
