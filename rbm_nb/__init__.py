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

from ._infra.lazy import lazy_attributes

__version__ = "0.1.0"

# public name -> submodule that defines it. Submodules themselves are listed in
# _SUBMODULES. Keeping this table explicit (rather than star-imports) is what
# lets the top level stay lazy.
_EXPORTS: dict[str, str] = {
    # reference frames and the registry
    "ReferenceFrame": "frames",
    "registry": "frames",
    "register_frame": "frames",
    "deregister_frame": "frames",
    "clear_registry": "frames",
    "render_tree": "frames",
    "find_frame": "frames",
    # transformations
    "transform_vectors": "transforms",
    "transform_points": "transforms",
    "transform_quaternions": "transforms",
    "transform_angular_velocity": "transforms",
    "transform_linear_velocity": "transforms",
    "transform_coordinates": "coordinates",
    # lookups
    "lookup_transform": "lookups",
    "lookup_pose": "lookups",
    "lookup_twist": "lookups",
    "lookup_linear_velocity": "lookups",
    "lookup_angular_velocity": "lookups",
    # estimators
    "estimate_linear_velocity": "estimators",
    "estimate_angular_velocity": "estimators",
    "shortest_arc_rotation": "estimators",
    "best_fit_rotation": "estimators",
    "best_fit_transform": "estimators",
    "iterative_closest_point": "estimators",
    # quaternion utilities
    "from_euler_angles": "quaternions",
    "qinv": "quaternions",
    "qmul": "quaternions",
    "qmean": "quaternions",
    "qinterp": "quaternions",
    "rotate_vectors": "quaternions",
    # coordinate systems
    "cartesian_to_polar": "coordinates",
    "polar_to_cartesian": "coordinates",
    "cartesian_to_spherical": "coordinates",
    "spherical_to_cartesian": "coordinates",
    # example data
    "example_data": "data",
    # conversions and the transform value type (beyond the reference)
    "Transform": "rigid_transform",
    "quaternion_from_matrix": "conversions",
    "matrix_from_quaternion": "conversions",
    "quaternion_from_rotation_vector": "conversions",
    "rotation_vector_from_quaternion": "conversions",
    "quaternion_from_axis_angle": "conversions",
    "axis_angle_from_quaternion": "conversions",
    "quaternion_from_euler": "conversions",
    "euler_from_quaternion": "conversions",
    "homogeneous_from_transform": "conversions",
    "transform_from_homogeneous": "conversions",
}

_SUBMODULES = {
    "accessors",
    "conversions",
    "coordinates",
    "data",
    "estimators",
    "explorer",
    "frames",
    "gaze",
    "io",
    "lookups",
    "plot",
    "quaternions",
    "rigid_transform",
    "ros",
    "scene",
    "study",
    "se3",
    "evaluation",
    "sdf",
    "transforms",
    "widgets",
}

__all__ = sorted(_EXPORTS) + sorted(_SUBMODULES) + ["__version__"]


__getattr__, __dir__ = lazy_attributes(__name__, _EXPORTS, _SUBMODULES)


if TYPE_CHECKING:  # pragma: no cover - static analysers see the real names
    from . import data, io, ros, scene, sdf, study, widgets  # noqa: F401
    from .app import explorer
    from .core import (
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
    importlib.import_module(f"{__name__}.accessors")


if "xarray" in sys.modules:
    _register_accessor()
else:
    from ._infra.import_hook import call_after_import

    call_after_import("xarray", _register_accessor)
