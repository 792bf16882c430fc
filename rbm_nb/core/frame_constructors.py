"""Frames made from xarray objects and rotation matrices (classmethods).

:class:`FrameConstructors` is a base class of
:class:`~rbm_nb.core.frames.ReferenceFrame`: ``from_dataset``,
``from_translation_dataarray``, ``from_rotation_dataarray`` and
``from_rotation_matrix`` take the arrays out of their arguments (each
error naming the argument) and call the class with them, which checks
them once like any other frame's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TypeAlias, TypeVar

from .._door.unpack import ArrayInput, float_array
from .._door.xarray import dataarray_coordinate, dataset_variable
from .conversions import quaternion_from_matrix
from .frame_node import FrameNode

__all__ = ["FrameConstructors"]

_F = TypeVar("_F", bound="FrameConstructors")

# A frame argument: a frame or the name of a registered one (FrameLike of
# rbm_nb.core.frames, which defines ReferenceFrame, the FrameNode meant here).
FrameLike: TypeAlias = "FrameNode | str"


class FrameConstructors:
    """The classmethods that make a ``ReferenceFrame`` from other objects.

    Not used on its own: ``ReferenceFrame`` derives from it and provides
    the constructor declared below.
    """

    if TYPE_CHECKING:  # provided by ReferenceFrame

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
        ) -> None: ...

    @classmethod
    def from_dataset(
        cls: type[_F],
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
    ) -> _F:
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
        cls: type[_F],
        da: Any,
        timestamps: Any,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
        discrete: bool = False,
        max_gap: float | None = None,
    ) -> _F:
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
        cls: type[_F],
        da: Any,
        timestamps: Any,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
        discrete: bool = False,
        max_gap: float | None = None,
    ) -> _F:
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
        cls: type[_F],
        mat: ArrayInput,
        parent: FrameLike,
        name: str | None = None,
        inverse: bool = False,
    ) -> _F:
        """A static frame rotated by a (3, 3) rotation matrix wrt its parent."""
        mat = float_array(mat, "mat")
        if mat.shape != (3, 3):
            raise ValueError(f"mat must have shape (3, 3), got {mat.shape}")
        try:  # orthonormal and det +1, to a tolerance the message names
            q = quaternion_from_matrix(mat)
        except ValueError as err:
            raise ValueError(f"mat: {err}") from None
        return cls(name, parent, rotation=q, inverse=inverse)
