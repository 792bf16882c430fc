"""A frame as the engine sees it: one immutable value.

A :class:`~rbm_nb.ReferenceFrame` validates its arguments once and hands the
engine a :class:`FrameData` (its public ``data`` property): the prepared
:class:`Samples` (translation, rotations as given, the unit and
sign-continuous rotations interpolation needs, the :class:`~rbm_nb._engine.time.Track`
of the times, whether a rotation sample is missing), the options
``discrete`` and ``max_gap``, the name, and the parent's FrameData.

Nothing in a value changes. A frame that changes (a new parent, a new name
or option) makes a new value, and so does every frame below it, since a
value holds its parent's: the chain between two values is fixed for as long
as they exist. The engine keys its caches by these values -- chains by the
pair of end values, squad tables and spline coefficients by the Samples,
which a frame keeps through every change -- so an entry made before a
change can never be found after it; nothing has to be told to forget it
for the results to be right.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._kernels import signed_rows as _signed
from .._kernels._arrays import kernel_array
from . import time as _time

__all__ = ["Samples", "FrameData"]

_SAME: Any = object()  # replace(): keep this field


class _Frozen:
    """Attributes set once, in ``__init__``; assigning later is an error."""

    __slots__ = ()

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable (set {name!r})")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable (del {name!r})")


class Samples(_Frozen):
    """A frame's transform samples, prepared for the kernels.

    Attributes
    ----------
    track : Track or None
        The times of a moving frame (None: static, one row).
    t : ndarray, shape (n|1, 3)
        Translations (NaN rows: missing samples).
    r : ndarray, shape (n|1, 4)
        Unit rotations, sign-continuous for a moving frame (interpolation):
        kept for a static frame; made at each read for a moving frame from
        ``rotation`` and ``signs`` (the fused kernels make each row as they
        read it, ``_kernels.signed_rows``).
    signs : ndarray of int8, shape (n,), or None
        A moving frame's sign code per sample (``_kernels.signed_rows``):
        all it keeps of ``r``, 1 byte per sample instead of 32. None: static.
    rotation : ndarray, shape (n|1, 4)
        The rotations as given (returned at the frame's own times).
    missing_rotations : bool
        A rotation sample is missing (a NaN row).
    missing_rows : ndarray of bool, shape (n,), or None
        Rows to treat as missing although ``stored_t`` and
        ``stored_rotation`` hold numbers there (the explorer's
        low-confidence eye samples): ``t`` and ``rotation`` read NaN in
        them, ``r`` holds NaN in them. None: no such rows.
    stored_t, stored_rotation : ndarray
        The arrays kept, without ``missing_rows`` applied: the caller's own
        memory where nobody can write it, else the frame's copies.

    The arrays are the frame's private copies, or the caller's own arrays
    where nobody can write them any more (``rbm_nb._infra.frozen``: ``t``,
    ``rotation`` and the track's values; the kernels get a writeable-flagged
    alias of the same memory). Nobody writes them.

    With ``missing_rows``, ``t`` and ``rotation`` are made at each read: a
    copy of the kept array with those rows NaN, exactly the arrays a frame
    of NaN-masked copies kept, so every kernel sees the same numbers; the
    copy lives as long as the call that reads it, not as long as the frame
    (a frame over the caller's frozen arrays keeps one byte per row instead
    of 7 floats). :meth:`rows` reads a few rows without copying
    the rest.
    """

    __slots__ = (
        "track",
        "stored_t",
        "unit",
        "signs",
        "stored_rotation",
        "missing_rotations",
        "missing_rows",
        "__weakref__",
    )

    track: _time.Track | None
    stored_t: np.ndarray
    unit: np.ndarray | None
    signs: np.ndarray | None
    stored_rotation: np.ndarray
    missing_rotations: bool
    missing_rows: np.ndarray | None

    def __init__(
        self,
        track,
        t,
        r,
        rotation,
        missing_rotations=False,
        missing_rows=None,
        signs=None,
    ) -> None:
        setter = object.__setattr__
        setter(self, "track", track)
        setter(self, "stored_t", t)
        setter(self, "stored_rotation", rotation)
        setter(self, "missing_rotations", bool(missing_rotations))
        setter(self, "missing_rows", missing_rows)
        if track is not None and signs is None:
            # a moving frame that made its unit rows itself: kept as codes
            signs = _sign_codes(self.rotation, r)
        setter(self, "unit", None if signs is not None else r)
        setter(self, "signs", signs)

    @property
    def r(self) -> np.ndarray:
        """The unit, sign-continuous rotations (a moving frame's: a new array)."""
        if self.unit is not None:
            return self.unit
        assert self.signs is not None  # (set for every moving frame)
        return _signed.signed_unit_rows(kernel_array(self.rotation), self.signs)

    @property
    def t(self) -> np.ndarray:
        """Translations, NaN in ``missing_rows`` (a fresh copy if there are any)."""
        return _masked(self.stored_t, self.missing_rows)

    @property
    def rotation(self) -> np.ndarray:
        """Rotations as given, NaN in ``missing_rows`` (a fresh copy if there are any)."""
        return _masked(self.stored_rotation, self.missing_rows)

    def rows(self, index) -> tuple[np.ndarray, np.ndarray]:
        """``(t[index], rotation[index])`` reading only those rows.

        Views of the kept arrays for a slice with no row in
        ``missing_rows``; otherwise new arrays.
        """
        t = self.stored_t[index]
        rotation = self.stored_rotation[index]
        mask = self.missing_rows
        if mask is None:
            return t, rotation
        mask = mask[index]
        if not mask.any():  # a window with no missing row: views, as unmasked
            return t, rotation
        return _masked(t, mask), _masked(rotation, mask)

    def __reduce__(self):
        # (pickle and copy would set the slots one by one, which is refused)
        return Samples, (
            self.track,
            self.stored_t,
            self.unit,
            self.stored_rotation,
            self.missing_rotations,
            self.missing_rows,
            self.signs,
        )


def _sign_codes(rotation: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The sign codes that make ``r`` from ``rotation`` (every row, bit for bit)."""
    codes = np.empty(len(r), dtype=np.int8)
    bad = _signed.sign_codes(kernel_array(rotation), kernel_array(r), codes)
    if bad >= 0:  # not a user's mistake: r was made from rotation
        raise RuntimeError(
            f"unit rotation row {bad} is not the stored row {bad} normalised "
            f"and signed: {r[bad]} from {rotation[bad]}"
        )
    return codes


def _masked(values: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
    """``values`` with the rows in ``mask`` NaN: a new C-contiguous float64
    array (the kernels' layout) when ``mask`` is given, else ``values``."""
    if mask is None:
        return values
    # one pass, reading both (5x faster than a copy and a masked assignment
    # at 3.7M rows; the same bits: NaN is np.nan's in both)
    out = np.where(mask[:, None], np.nan, values)
    return np.ascontiguousarray(out, dtype=np.float64)


class FrameData(_Frozen):
    """One frame's data, options and place in its tree, as a value.

    The sample attributes (``track``, ``t``, ``r``, ``rotation``,
    ``missing_rotations``) are those of ``samples``, repeated here because
    the engine reads them in its loops over chains.
    """

    __slots__ = (
        "name",
        "parent",
        "samples",
        "discrete",
        "max_gap",
        "track",
        "signs",
        "missing_rotations",
        "__weakref__",
    )

    name: str | None
    parent: FrameData | None
    samples: Samples
    discrete: bool
    max_gap: float | None
    track: _time.Track | None
    signs: np.ndarray | None
    missing_rotations: bool

    def __init__(
        self,
        name: str | None,
        parent: FrameData | None,
        samples: Samples,
        discrete: bool = False,
        max_gap: float | None = None,
    ) -> None:
        setter = object.__setattr__
        setter(self, "name", name)
        setter(self, "parent", parent)
        setter(self, "samples", samples)
        setter(self, "discrete", bool(discrete))
        setter(self, "max_gap", max_gap)
        setter(self, "track", samples.track)
        setter(self, "signs", samples.signs)
        setter(self, "missing_rotations", samples.missing_rotations)

    @property
    def t(self) -> np.ndarray:
        """The samples' translations (:attr:`Samples.t`)."""
        return self.samples.t

    @property
    def rotation(self) -> np.ndarray:
        """The samples' rotations as given (:attr:`Samples.rotation`)."""
        return self.samples.rotation

    @property
    def r(self) -> np.ndarray:
        """The unit, sign-continuous rotations (:attr:`Samples.r`)."""
        return self.samples.r

    def __reduce__(self):
        return FrameData, (
            self.name,
            self.parent,
            self.samples,
            self.discrete,
            self.max_gap,
        )

    def replace(
        self,
        *,
        name: Any = _SAME,
        parent: Any = _SAME,
        discrete: Any = _SAME,
        max_gap: Any = _SAME,
    ) -> FrameData:
        """A new value with some of ``name``, ``parent``, ``discrete``, ``max_gap`` changed."""
        return FrameData(
            self.name if name is _SAME else name,
            self.parent if parent is _SAME else parent,
            self.samples,
            self.discrete if discrete is _SAME else discrete,
            self.max_gap if max_gap is _SAME else max_gap,
        )

    @property
    def data(self) -> FrameData:
        """The value itself: engine functions take a frame or its value."""
        return self

    @property
    def timestamps(self) -> np.ndarray | None:
        """The times of a moving frame as given (None if static)."""
        return None if self.track is None else self.track.values

    def path_to_root(self) -> list[FrameData]:
        """This value, its parent's, ..., the root's."""
        path = []
        node: FrameData | None = self
        while node is not None:
            path.append(node)
            node = node.parent
        return path

    def __repr__(self) -> str:
        kind = "static" if self.track is None else f"{len(self.track)} samples"
        return f"<FrameData {self.name!r} ({kind})>"
