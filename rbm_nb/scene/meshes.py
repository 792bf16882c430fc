"""The geometry of ``Scene.add_mesh``: a primitive, a meshcat geometry or a mesh file.

A primitive (``box``, ``sphere``, ``cylinder``, ``ellipsoid``) is sized by
``size``; a ``.obj``, ``.stl`` or ``.dae`` file is read by meshcat and
parsed by the browser, so its framing is checked here first.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .commands import meshcat_geometry as _geometry

PRIMITIVES = ("box", "sphere", "cylinder", "ellipsoid")
MESH_FORMATS = {".obj": "obj", ".stl": "stl", ".dae": "dae"}


def _check_mesh_file(path: Path, fmt: str) -> None:
    """Refuse a file whose content is not the format its name says.

    The browser parses meshes; a wrong file would fail there, silently. Only
    the framing is checked here: a binary STL's size matches its triangle
    count, an ASCII STL starts with ``solid`` and has facets, an OBJ has
    vertices, a DAE is COLLADA XML.
    """
    with open(path, "rb") as f:
        head = f.read(4096)
    size = path.stat().st_size
    if fmt == "stl":
        binary = size >= 84 and size == 84 + 50 * int.from_bytes(head[80:84], "little")
        ascii_ = head.lstrip().startswith(b"solid") and b"facet" in head
        ok = binary or ascii_
        what = "a binary STL (84 + 50 bytes per triangle) nor an ASCII STL"
    elif fmt == "obj":
        ok = any(line.split()[:1] == [b"v"] for line in head.splitlines()) or (
            size > len(head) and b"\0" not in head
        )
        what = "an OBJ file (no vertex lines 'v x y z')"
    else:
        ok = b"COLLADA" in head
        what = "a COLLADA (.dae) file"
    if not ok:
        raise ValueError(f"add_mesh: {str(path)!r} is not {what}; check the file")


def mesh_geometry(mesh, size):
    """The meshcat geometry ``add_mesh(mesh=..., size=...)`` draws (checked)."""
    g = _geometry()
    if isinstance(mesh, g.Geometry):
        return mesh
    if isinstance(mesh, (str, os.PathLike)) and str(mesh) in PRIMITIVES:
        kind = str(mesh)
        s = np.atleast_1d(np.asarray(size, dtype=float))
        if not (np.isfinite(s).all() and (s > 0).all()):
            raise ValueError(f"add_mesh: size must be positive, got {size!r}")
        if kind == "box":
            if s.size not in (1, 3):
                raise ValueError(
                    f"add_mesh: a box needs size=(x, y, z) or one number, got {size!r}"
                )
            return g.Box([float(v) for v in np.broadcast_to(s, (3,))])
        if kind == "sphere":
            if s.size != 1:
                raise ValueError(f"add_mesh: a sphere needs size=radius, got {size!r}")
            return g.Sphere(float(s[0]))
        if kind == "cylinder":
            if s.size != 2:
                raise ValueError(
                    f"add_mesh: a cylinder needs size=(height, radius), got {size!r}"
                )
            return g.Cylinder(float(s[0]), float(s[1]))
        if s.size != 3:
            raise ValueError(
                f"add_mesh: an ellipsoid needs size=(rx, ry, rz), got {size!r}"
            )
        return g.Ellipsoid([float(v) for v in s])
    if isinstance(mesh, (str, os.PathLike)):
        path = Path(mesh)
        fmt = MESH_FORMATS.get(path.suffix.lower())
        if fmt is None:
            raise ValueError(
                f"add_mesh: mesh must be one of {PRIMITIVES}, a meshcat Geometry or a "
                f".obj/.stl/.dae file, got {str(mesh)!r}"
            )
        if not path.is_file():
            raise ValueError(f"add_mesh: mesh file {str(path)!r} does not exist")
        _check_mesh_file(path, fmt)
        if fmt == "stl":
            return g.StlMeshGeometry.from_file(str(path))
        if fmt == "obj":
            return g.ObjMeshGeometry.from_file(str(path))
        return g.DaeMeshGeometry.from_file(str(path))
    raise ValueError(
        f"add_mesh: mesh must be one of {PRIMITIVES}, a meshcat Geometry or a mesh file path, "
        f"got {type(mesh).__name__}"
    )
