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
(:func:`resolve_frame`); the methods here resolve their frame arguments and
forward to the engine (:mod:`rbm_nb._engine`), which reads the frames'
values, keys its caches by them, and never imports this module.
"""

from __future__ import annotations

import difflib
import unicodedata
import warnings
from collections.abc import Callable, Iterator, MutableMapping
from typing import Any, TypeAlias

import numpy as np

from .._door import coverage as _coverage
from .._door import frame_paths as _frame_paths
from .._door import inputs as _inputs
from .._door import lookups as _lookups
from .._door.series import velocity_options
from .._door.unpack import ArrayInput, float_array
from .._door.validation import (
    check_what,
)
from .._door.xarray import dataarray_coordinate, dataset_variable
from .._engine import chain as _chain
from .._engine import transform as _transform
from .._engine import twist as _twist
from .._engine.frame_data import FrameData, Samples
from .conversions import quaternion_from_matrix
from .frame_samples import _check_discrete, _checked_max_gap, _samples

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


class ReferenceFrame:
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

    @property
    def children(self) -> tuple:
        """The frames whose parent this is, in order of attachment."""
        return tuple(self._children)

    def _path_to_root(self) -> list[ReferenceFrame]:
        path = []
        node: ReferenceFrame | None = self
        while node is not None:
            path.append(node)
            node = node._parent
        return path

    def iter_path_reverse(self) -> Any:
        """Iterate from this frame up to the root (inclusive)."""
        node: ReferenceFrame | None = self
        while node is not None:
            yield node
            node = node._parent

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

    @property
    def path(self) -> tuple:
        """The frames from the root down to this one."""
        return tuple(reversed(self._path_to_root()))

    @property
    def ancestors(self) -> tuple:
        """The frames from the root down to the parent."""
        return self.path[:-1]

    @property
    def root(self) -> ReferenceFrame:
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

    # -- construction from xarray ------------------------------------------

    @classmethod
    def from_dataset(
        cls,
        ds: Any,
        translation: ArrayInput | None,
        rotation: ArrayInput | None,
        timestamps: Any,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
        discrete: bool = False,
        max_gap: float | None = None,
        missing: Any = None,
    ) -> ReferenceFrame:
        """A moving frame from variables of an xarray Dataset.

        Parameters
        ----------
        ds : xarray.Dataset
        translation, rotation : str
            Names of the variables with shape (n, 3) and (n, 4).
        timestamps : str
            Name of the variable or coordinate with the n timestamps.
        parent : str or ReferenceFrame
        name : str, optional
        inverse, discrete : bool, default False
            As for :class:`ReferenceFrame`.
        max_gap : float, optional
            The longest gap (seconds) interpolated across, as for
            :class:`ReferenceFrame`; NaN rows (missing samples) are accepted.
        missing : array_like of bool, shape (n,), optional
            Rows to treat as missing, as for :class:`ReferenceFrame` (the
            dataset's arrays are kept, not masked copies, when the dataset
            is read-only as the loaders return it).
        """
        return cls(
            name,
            parent,
            translation=dataset_variable(ds, translation, "translation"),
            rotation=dataset_variable(ds, rotation, "rotation"),
            timestamps=dataset_variable(ds, timestamps, "timestamps"),
            inverse=inverse,
            discrete=discrete,
            max_gap=max_gap,
            missing=missing,
        )

    @classmethod
    def from_translation_dataarray(
        cls,
        da: Any,
        timestamps: Any,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
        discrete: bool = False,
        max_gap: float | None = None,
    ) -> ReferenceFrame:
        """A moving frame (no rotation) from a translation DataArray, shape (n, 3).

        ``timestamps`` names the coordinate holding the n timestamps.
        """
        return cls(
            name,
            parent,
            translation=da.data,
            timestamps=dataarray_coordinate(da, timestamps),
            inverse=inverse,
            discrete=discrete,
            max_gap=max_gap,
        )

    @classmethod
    def from_rotation_dataarray(
        cls,
        da: Any,
        timestamps: Any,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
        discrete: bool = False,
        max_gap: float | None = None,
    ) -> ReferenceFrame:
        """A moving frame (no translation) from a rotation DataArray, shape (n, 4).

        ``timestamps`` names the coordinate holding the n timestamps.
        """
        return cls(
            name,
            parent,
            rotation=da.data,
            timestamps=dataarray_coordinate(da, timestamps),
            inverse=inverse,
            discrete=discrete,
            max_gap=max_gap,
        )

    @classmethod
    def from_rotation_matrix(
        cls,
        mat: ArrayInput,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
    ) -> ReferenceFrame:
        """A static frame rotated by a (3, 3) rotation matrix wrt its parent."""
        mat = float_array(mat, "mat")
        if mat.shape != (3, 3):
            raise ValueError(f"mat must have shape (3, 3), got {mat.shape}")
        try:  # orthonormal and det +1, to a tolerance the message names
            q = quaternion_from_matrix(mat)
        except ValueError as err:
            raise ValueError(f"mat: {err}") from None
        return cls(name, parent, rotation=q, inverse=inverse)

    # -- registry ----------------------------------------------------------

    def register(self, update: bool = False) -> None:
        """Register this frame under its name (``update`` replaces another)."""
        _register(self, update=update)

    def deregister(self) -> None:
        """Remove this frame's name from the registry."""
        if self.name is None:
            raise ValueError("a frame without a name is not registered")
        _deregister(self.name)

    # -- lookups and transforms (see rbm_nb.lookups / rbm_nb.transforms) ----

    def lookup_transform(self, to_frame: FrameLike) -> Any:
        """Transform from this frame to ``to_frame``.

        Returns
        -------
        t : ndarray, shape (3,) or (n, 3)
        r : ndarray, shape (4,) or (n, 4)
        ts : ndarray, shape (n,), or None if static
        """
        to = resolve_frame(to_frame, "to_frame")
        _coverage.chain_samples(self, to)  # frames that share no time: refused
        return _chain.lookup_transform(self, to)

    def get_transformation(self, to_frame: FrameLike) -> Any:
        """Deprecated alias of :meth:`lookup_transform`."""
        warnings.warn(
            "get_transformation is deprecated, use lookup_transform instead",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.lookup_transform(to_frame)

    def lookup_twist(
        self,
        reference: FrameLike | None = None,
        represent_in: FrameLike | None = None,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
        mode: str = "quaternion",
        allow_static: bool = False,
        return_timestamps: bool = False,
    ) -> Any:
        """Linear and angular velocity of this frame wrt ``reference``.

        Both default to the parent frame. Returns ``(linear, angular)``
        with shape (n, 3) each, plus the timestamps if ``return_timestamps``.
        """
        reference = _optional(reference, "reference")
        represent_in = _optional(represent_in, "represent_in")
        mode = velocity_options(outlier_thresh, cutoff, mode=mode)
        reference, represent_in = _lookups.method_velocity_frames(
            self, reference, represent_in, outlier_thresh, cutoff, allow_static
        )
        linear, angular, ts = _twist.lookup_twist(
            self, reference, represent_in, outlier_thresh, cutoff, mode, allow_static
        )
        return (linear, angular, ts) if return_timestamps else (linear, angular)

    def lookup_linear_velocity(
        self,
        reference: FrameLike | None = None,
        represent_in: FrameLike | None = None,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
        allow_static: bool = False,
        return_timestamps: bool = False,
    ) -> Any:
        """Linear velocity of this frame wrt ``reference``, shape (n, 3)."""
        velocity_options(outlier_thresh, cutoff)
        reference, represent_in = _lookups.method_velocity_frames(
            self,
            _optional(reference, "reference"),
            _optional(represent_in, "represent_in"),
            outlier_thresh,
            cutoff,
            allow_static,
        )
        linear, ts = _twist.lookup_linear_velocity(
            self, reference, represent_in, outlier_thresh, cutoff, allow_static
        )
        return (linear, ts) if return_timestamps else linear

    def lookup_angular_velocity(
        self,
        reference: FrameLike | None = None,
        represent_in: FrameLike | None = None,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
        mode: str = "quaternion",
        allow_static: bool = False,
        return_timestamps: bool = False,
    ) -> Any:
        """Angular velocity of this frame wrt ``reference``, shape (n, 3)."""
        reference = _optional(reference, "reference")
        represent_in = _optional(represent_in, "represent_in")
        mode = velocity_options(outlier_thresh, cutoff, mode=mode)
        reference, represent_in = _lookups.method_velocity_frames(
            self, reference, represent_in, outlier_thresh, cutoff, allow_static
        )
        angular, ts = _twist.lookup_angular_velocity(
            self, reference, represent_in, outlier_thresh, cutoff, mode, allow_static
        )
        return (angular, ts) if return_timestamps else angular

    def transform_points(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
    ) -> Any:
        """Points given in this frame, expressed in ``to_frame``."""
        return _transform_call(
            "points",
            self,
            arr,
            to_frame,
            axis,
            time_axis,
            timestamps,
            return_timestamps,
        )

    def transform_vectors(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
    ) -> Any:
        """Vectors represented in this frame, represented in ``to_frame``."""
        return _transform_call(
            "vectors",
            self,
            arr,
            to_frame,
            axis,
            time_axis,
            timestamps,
            return_timestamps,
        )

    def transform_quaternions(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
    ) -> Any:
        """Orientations wrt this frame, expressed wrt ``to_frame``."""
        return _transform_call(
            "quaternions",
            self,
            arr,
            to_frame,
            axis,
            time_axis,
            timestamps,
            return_timestamps,
        )

    def transform_angular_velocity(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        what: str = "reference_frame",
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
        cutoff: float | None = None,
    ) -> Any:
        """Change the reference, moving or representation frame of angular velocities."""
        to_frame = resolve_frame(to_frame, "to_frame")
        check_what(what)
        blocks = _inputs.blocks(arr, 3, axis, time_axis, timestamps, "vectors")
        _coverage.velocity_transform(
            self, to_frame, blocks.track, what, False, cutoff=cutoff
        )
        out, ts = _twist.transform_angular_velocity(
            self, blocks, to_frame, what, cutoff
        )
        return (out, ts) if return_timestamps else out

    def transform_linear_velocity(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        what: str = "reference_frame",
        moving_frame: FrameLike | None = None,
        reference_frame: FrameLike | None = None,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
    ) -> Any:
        """Change the reference, moving or representation frame of linear velocities."""
        to_frame = resolve_frame(to_frame, "to_frame")
        check_what(what)
        blocks = _inputs.blocks(arr, 3, axis, time_axis, timestamps, "vectors")
        moving = _optional(moving_frame, "moving_frame")
        reference = _optional(reference_frame, "reference_frame")
        _coverage.velocity_transform(
            self, to_frame, blocks.track, what, True, moving, reference,
            outlier_thresh, cutoff,
        )  # fmt: skip
        out, ts = _twist.transform_linear_velocity(
            self, blocks, to_frame, what, moving, reference, outlier_thresh, cutoff
        )
        return (out, ts) if return_timestamps else out


def _check_name(name: Any) -> None:
    if name is not None and not isinstance(name, str):
        raise ValueError(f"name must be a string, got {type(name).__name__}")
    if name is not None:
        check_frame_name(name)


def _transform_call(
    kind, frame, arr, to_frame, axis, time_axis, timestamps, return_timestamps
):  # fmt: skip
    """A transform method's call: through the door, then the engine."""
    args = _inputs.method_arguments(
        kind, frame, arr, resolve_frame(to_frame, "to_frame"), axis, time_axis,
        timestamps,
    )  # fmt: skip
    if args.rows is not None:  # a static chain, plain rows: the short way
        out = _transform.transform_static(kind, args.static, args.rows)
        return (
            (out.reshape(args.shape), None)
            if return_timestamps
            else out.reshape(args.shape)
        )
    out, ts = _transform.transform(frame, kind, args.blocks, args.into)
    return (out, ts) if return_timestamps else out


def _optional(frame: Any, argument: str) -> ReferenceFrame | None:
    """``resolve_frame`` for arguments that may be None (a default applies)."""
    return None if frame is None else resolve_frame(frame, argument)


def _read_only(arr: np.ndarray) -> np.ndarray:
    """A view that cannot change the frame's data (kernels get the original)."""
    view = arr.view()
    view.setflags(write=False)
    return view
