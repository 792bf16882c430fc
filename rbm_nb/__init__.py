"""rbm_nb: rigid body motion you can compute with, look at and play back in Jupyter.

The frame core keeps the API of the rigid-body-motion package, so that
``import rbm_nb as rbm`` is all a migration needs. Everything is imported on
first use: ``import rbm_nb`` loads neither numba, xarray nor the kernels, and
compiles nothing.
"""

from __future__ import annotations

import importlib
import sys
from typing import TYPE_CHECKING

from ._infra.import_hook import alias_modules, call_after_import
from ._infra.lazy import lazy_attributes
from ._version import __version__

# public name -> submodule that defines it. Submodules themselves are listed in
# _SUBMODULES. Keeping this table explicit (rather than star-imports) is what
# lets the top level stay lazy.
_EXPORTS: dict[str, str] = {
    # reference frames and the registry
    "ReferenceFrame": "core.frames",
    "registry": "core.frames",
    "register_frame": "core.frames",
    "deregister_frame": "core.frames",
    "clear_registry": "core.frames",
    "render_tree": "core.frames",
    "find_frame": "core.frames",
    # transformations
    "transform_vectors": "core.transforms",
    "transform_points": "core.transforms",
    "transform_quaternions": "core.transforms",
    "transform_angular_velocity": "core.transforms",
    "transform_linear_velocity": "core.transforms",
    "transform_coordinates": "core.coordinates",
    # lookups
    "lookup_transform": "core.lookups",
    "lookup_pose": "core.lookups",
    "lookup_twist": "core.lookups",
    "lookup_linear_velocity": "core.lookups",
    "lookup_angular_velocity": "core.lookups",
    # estimators
    "estimate_linear_velocity": "core.estimators",
    "estimate_angular_velocity": "core.estimators",
    "shortest_arc_rotation": "core.estimators",
    "best_fit_rotation": "core.estimators",
    "best_fit_transform": "core.estimators",
    "iterative_closest_point": "core.estimators",
    # quaternion utilities
    "from_euler_angles": "core.quaternions",
    "qinv": "core.quaternions",
    "qmul": "core.quaternions",
    "qmean": "core.quaternions",
    "qinterp": "core.quaternions",
    "rotate_vectors": "core.quaternions",
    # coordinate systems
    "cartesian_to_polar": "core.coordinates",
    "polar_to_cartesian": "core.coordinates",
    "cartesian_to_spherical": "core.coordinates",
    "spherical_to_cartesian": "core.coordinates",
    # example data
    "example_data": "data",
    # conversions and the transform value type (beyond the reference)
    "Transform": "core.rigid_transform",
    "quaternion_from_matrix": "core.conversions",
    "matrix_from_quaternion": "core.conversions",
    "quaternion_from_rotation_vector": "core.conversions",
    "rotation_vector_from_quaternion": "core.conversions",
    "quaternion_from_axis_angle": "core.conversions",
    "axis_angle_from_quaternion": "core.conversions",
    "quaternion_from_euler": "core.conversions",
    "euler_from_quaternion": "core.conversions",
    "homogeneous_from_transform": "core.conversions",
    "transform_from_homogeneous": "core.conversions",
}

# public submodule -> where it lives. The spec's facades are in ``core``, the
# explorer and the command line in ``app``; ``rbm_nb.frames`` & co. stay
# importable under their old names (see _MOVED below).
_SUBMODULES: dict[str, str] = {
    **{
        name: f"core.{name}"
        for name in (
            "accessors",
            "conversions",
            "coordinates",
            "estimators",
            "evaluation",
            "frames",
            "gaze",
            "lookups",
            "plot",
            "quaternions",
            "rigid_transform",
            "se3",
            "transforms",
        )
    },
    "explorer": "app.explorer",
    **{
        name: name
        for name in (
            "app",
            "core",
            "data",
            "io",
            "ros",
            "scene",
            "sdf",
            "study",
            "widgets",
        )
    },
}
# ``import rbm_nb.frames`` (the path rigid-body-motion users and our own
# notebooks of earlier releases write) gives the module now in ``core``
_MOVED: dict[str, str] = {
    **{name: path for name, path in _SUBMODULES.items() if path != name},
    "cli": "app.cli",
}

# the public names, and the sub-packages that hold the rest: the facades'
# modules are listed once, where they live (``core``), so that the API
# reference documents each of them under its own name
__all__ = (
    sorted(_EXPORTS)
    + sorted(name for name, path in _SUBMODULES.items() if path == name)
    + ["__version__"]
)


__getattr__, __dir__ = lazy_attributes(__name__, _EXPORTS, _SUBMODULES)
alias_modules(__name__, _MOVED)


if TYPE_CHECKING:  # pragma: no cover - static analysers see the real names
    from . import app, core, data, io, ros, scene, sdf, study, widgets  # noqa: F401
    from .app import explorer  # noqa: F401
    from .core import (  # noqa: F401
        accessors,
        conversions,
        coordinates,
        estimators,
        evaluation,
        frames,
        gaze,
        lookups,
        plot,
        quaternions,
        rigid_transform,
        se3,
        transforms,
    )
    from .core.conversions import (  # noqa: F401
        axis_angle_from_quaternion,
        euler_from_quaternion,
        homogeneous_from_transform,
        matrix_from_quaternion,
        quaternion_from_axis_angle,
        quaternion_from_euler,
        quaternion_from_matrix,
        quaternion_from_rotation_vector,
        rotation_vector_from_quaternion,
        transform_from_homogeneous,
    )
    from .core.coordinates import (  # noqa: F401
        cartesian_to_polar,
        cartesian_to_spherical,
        polar_to_cartesian,
        spherical_to_cartesian,
        transform_coordinates,
    )
    from .core.estimators import (  # noqa: F401
        best_fit_rotation,
        best_fit_transform,
        estimate_angular_velocity,
        estimate_linear_velocity,
        iterative_closest_point,
        shortest_arc_rotation,
    )
    from .core.frames import (  # noqa: F401
        ReferenceFrame,
        clear_registry,
        deregister_frame,
        find_frame,
        register_frame,
        registry,
        render_tree,
    )
    from .core.lookups import (  # noqa: F401
        lookup_angular_velocity,
        lookup_linear_velocity,
        lookup_pose,
        lookup_transform,
        lookup_twist,
    )
    from .core.quaternions import (  # noqa: F401
        from_euler_angles,
        qinterp,
        qinv,
        qmean,
        qmul,
        rotate_vectors,
    )
    from .core.rigid_transform import Transform  # noqa: F401
    from .core.transforms import (  # noqa: F401
        transform_angular_velocity,
        transform_linear_velocity,
        transform_points,
        transform_quaternions,
        transform_vectors,
    )
    from .data import example_data  # noqa: F401


# The ``DataArray.rbm`` accessor must exist as soon as xarray does, even when
# nothing else of rbm_nb has been touched yet. Importing xarray here would cost
# ~0.4 s, so register right away only if xarray is already loaded, and
# otherwise once it gets imported.
def _register_accessor() -> None:
    importlib.import_module(f"{__name__}.core.accessors")


if "xarray" in sys.modules:
    _register_accessor()
else:
    call_after_import("xarray", _register_accessor)
