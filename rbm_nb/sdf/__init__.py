"""Signed distance fields on a grid, attached to a (static or moving) reference frame.

A :class:`GridSDF` stores signed distances (negative inside) at the nodes of a
regular grid that is fixed in a reference frame of the registry, e.g. an
object that the recording tracks. Queries take points in any frame of the
same tree, with one timestamp per point when the frames move relative to each
other, and are answered by numba kernels: trilinear distances, their
gradients (surface normals), and sphere-traced ray hits ("where on this object
did the gaze ray land").

Building a field from a mesh (:meth:`GridSDF.from_mesh`) and extracting its
zero level set (:meth:`GridSDF.surface_mesh`, :meth:`GridSDF.add_to_scene`)
need the optional extra ``rbm_nb[sdf]`` (trimesh and scikit-image).
"""

from __future__ import annotations

from ._grid import GridSDF, RayHits
from ._mesh import MAX_GRID_NODES

__all__ = ["GridSDF", "RayHits", "MAX_GRID_NODES"]
