"""Meshes in and out of signed distance grids: sampling a mesh, the level set.

Optional dependencies of the extra ``rbm_nb[sdf]`` (trimesh, scikit-image)
are imported here, on first use, with an error that names the extra.
"""

from __future__ import annotations

import os
import tempfile

import numpy as np

from .._door.unpack import float_array, kernel_array
from .._door.validation import check_finite, check_last_axis
from .._kernels import sdf

# more nodes than this is almost certainly a resolution given in the wrong unit
MAX_GRID_NODES = 50_000_000


def _kernels():
    return sdf


def _require(module: str):
    """Import an optional dependency of the ``sdf`` extra, or say how to get it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise ImportError(
            f"this part of rbm_nb.sdf needs {module.split('.')[0]!r}; install the "
            "optional extra: pip install 'rbm_nb[sdf]'"
        ) from err


def sample_mesh(mesh, resolution, padding, use_abs: bool):
    """Signed (or unsigned) distances to a mesh on a grid around it.

    Returns
    -------
    data : ndarray, shape (nx, ny, nz)
    lower : ndarray, shape (3,)
        Position of node (0, 0, 0).
    resolution : float
    """
    tm = _load_mesh(mesh)
    try:
        resolution = float(resolution)
    except (TypeError, ValueError):
        resolution = np.nan
    if not (np.isfinite(resolution) and resolution > 0.0):
        raise ValueError(f"resolution must be a positive number, got {resolution!r}")
    if padding is None:
        padding = 5.0 * resolution
    if not (np.isfinite(padding) and padding >= 0.0):
        raise ValueError(f"padding must be a non-negative number, got {padding!r}")
    if not use_abs and not tm.is_watertight:
        raise ValueError(
            "mesh is not watertight, so inside and outside are undefined; "
            "repair it or pass use_abs=True for unsigned distances"
        )
    lower = tm.bounds[0] - padding
    # the 1e-9 keeps rounding noise in the span from adding a whole layer
    cells = (tm.bounds[1] + padding - lower) / resolution
    counts = np.ceil(cells - 1e-9).astype(int) + 1
    counts = np.maximum(counts, 2)
    if np.prod(counts) > MAX_GRID_NODES:
        raise ValueError(
            f"resolution {resolution:g} makes a grid of {counts.tolist()} nodes "
            f"(> {MAX_GRID_NODES}); use a coarser resolution"
        )
    axes = [lower[a] + np.arange(counts[a]) * resolution for a in range(3)]
    nodes = kernel_array(
        np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    )
    # trimesh hands out its cached arrays read-only: the door copies them
    triangles = kernel_array(tm.triangles)
    distance = _kernels().mesh_distances(nodes, triangles)
    # nodes on the surface come out at ~1e-17 with a sign that is pure
    # rounding (and the level set would zigzag through them): make them 0
    distance[distance < 1e-9 * resolution] = 0.0
    if not use_abs:
        inside = _inside(nodes, distance, tuple(counts), resolution, triangles)
        distance = np.where(inside, -distance, distance)
    return distance.reshape(tuple(counts)), lower, resolution


def level_set(data, origin, resolution, level):
    """Vertices (m, 3) and faces (k, 3) of ``data == level`` by marching cubes."""
    measure = _require("skimage.measure")
    level = float(level)
    if not (data.min() < level < data.max()):
        raise ValueError(
            f"level {level:g} is not crossed by the grid, whose values range "
            f"over [{data.min():g}, {data.max():g}]"
        )
    vertices, faces, _, _ = measure.marching_cubes(
        np.asarray(data),
        level=level,
        spacing=(resolution,) * 3,
        gradient_direction="descent",
    )
    return vertices + origin, faces.astype(np.int64)


def write_obj(vertices, faces) -> str:
    """Write a Wavefront .obj into the session's level-set folder; its path."""
    fd, path = tempfile.mkstemp(suffix=".obj", dir=_level_set_dir())
    with os.fdopen(fd, "w") as f:
        f.write(_obj_text(vertices, faces))
    return path


_LEVEL_SETS: tempfile.TemporaryDirectory | None = None


def _level_set_dir() -> str:
    """A folder for level-set files, removed when the interpreter exits.

    The scene may read a mesh file when it is added or later (an export, a
    browser reconnecting), so the files live as long as the session.
    """
    global _LEVEL_SETS
    if _LEVEL_SETS is None:
        _LEVEL_SETS = tempfile.TemporaryDirectory(prefix="rbm_nb_sdf_")
    return _LEVEL_SETS.name


def _inside(nodes, distance, shape, resolution, triangles) -> np.ndarray:
    """Which grid nodes lie inside a watertight mesh, flat boolean (n,).

    A surface crossing the segment between two neighbouring nodes passes
    within half a cell of one of them, so the nodes farther than that
    (``far``) form 6-connected regions that lie wholly inside or wholly
    outside; one winding number per region decides it. Only the thin shell
    of nodes near the surface needs a winding number each, which keeps the
    cost far below one per node.
    """
    from scipy import ndimage

    # half a cell is the bound; 10 % more absorbs rounding in the distances
    far = (distance > 0.55 * resolution).reshape(shape)
    labels, count = ndimage.label(far)
    labels = labels.reshape(-1)
    regions, first = np.unique(labels, return_index=True)  # 0: the near shell
    first = first[regions > 0]
    near = np.flatnonzero(labels == 0)
    queries = np.concatenate([near, first])
    winding = _kernels().winding_numbers(kernel_array(nodes[queries]), triangles)
    # |w| copes with meshes whose faces all point inwards
    inside_query = np.abs(winding) > 0.5
    region_inside = np.zeros(count + 1, dtype=bool)
    region_inside[regions[regions > 0]] = inside_query[len(near) :]
    inside = region_inside[labels]
    inside[near] = inside_query[: len(near)]
    return inside


def _obj_text(vertices: np.ndarray, faces: np.ndarray) -> str:
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


def _load_mesh(mesh):
    """A trimesh.Trimesh from a path, a Trimesh or (vertices, faces)."""
    trimesh = _require("trimesh")
    if isinstance(mesh, trimesh.Trimesh):
        tm = mesh
    elif isinstance(mesh, (str, os.PathLike)):
        if not os.path.isfile(mesh):
            raise ValueError(f"mesh file {os.fspath(mesh)!r} does not exist")
        tm = trimesh.load(mesh, force="mesh")
    elif isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        vertices = _finite_rows(mesh[0], "vertices")
        faces = np.asarray(mesh[1])
        if (
            faces.ndim != 2
            or faces.shape[1] != 3
            or not np.issubdtype(faces.dtype, np.integer)
        ):
            raise ValueError(
                f"faces must be integers of shape (k, 3), got {faces.dtype} {faces.shape}"
            )
        if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise ValueError(
                f"faces index vertices 0..{len(vertices) - 1}, got indices "
                f"{faces.min()}..{faces.max()}"
            )
        tm = trimesh.Trimesh(vertices.reshape(-1, 3), faces, process=False)
    else:
        raise TypeError(
            "mesh must be a file path, a trimesh.Trimesh or a (vertices, faces) "
            f"pair, got {type(mesh).__name__}"
        )
    if len(tm.faces) == 0:
        raise ValueError("mesh has no faces")
    return tm


def _finite_rows(value, name: str) -> np.ndarray:
    arr = float_array(value, name)
    check_last_axis(arr, 3, name)
    check_finite(arr, name)
    return arr
