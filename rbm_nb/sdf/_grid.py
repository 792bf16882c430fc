"""``GridSDF``: signed distances on a grid fixed in a frame, and their queries."""

from __future__ import annotations

import os
from typing import NamedTuple

import numpy as np

from .._door.unpack import float_array, kernel_array
from .._door.validation import check_finite, check_last_axis
from .._kernels import sdf
from ..core.frames import ReferenceFrame, resolve_frame
from ..core.rigid_transform import Transform
from ..core.transforms import transform_points, transform_quaternions
from . import _mesh

_IDENTITY_Q = np.array([[1.0, 0.0, 0.0, 0.0]])


def _kernels():
    return sdf


def _read_only(arr: np.ndarray) -> np.ndarray:
    view = arr.view()
    view.flags.writeable = False
    return view


def _points(value, name: str) -> np.ndarray:
    arr = float_array(value, name)
    check_last_axis(arr, 3, name)
    check_finite(arr, name)
    return arr


class RayHits(NamedTuple):
    """Result of :meth:`GridSDF.ray_hits`; rays that miss hold nan.

    Attributes
    ----------
    points : ndarray, shape (..., 3)
        Hit points, in the frame the rays were given in.
    distances : ndarray, shape (...)
        Distance from each ray's origin to its hit, along the ray.
    hit : ndarray of bool, shape (...)
        Which rays hit the zero level set within ``max_distance``.
    normals : ndarray, shape (..., 3)
        Unit outward normals (normalised gradients) at the hits, in the
        frame the rays were given in.
    """

    points: np.ndarray
    distances: np.ndarray
    hit: np.ndarray
    normals: np.ndarray


class GridSDF:
    """Signed distances sampled on a regular grid that is fixed in a frame.

    Parameters
    ----------
    sdf_data : array_like, shape (nx, ny, nz)
        Signed distances at the nodes, negative inside; every dimension at
        least 2. Node ``(i, j, k)`` lies at ``origin + (i, j, k) * resolution``.
    origin : array_like, shape (3,)
        Position of node ``(0, 0, 0)`` in the grid's frame.
    resolution : float
        Node spacing (the same along all three axes), > 0.
    frame : str or ReferenceFrame, optional
        The frame the grid is fixed in (a registered name or a frame). Static
        or moving; queries in other frames are transformed into it. Without
        a frame, query points are taken as grid-frame coordinates.
    fill_value : float, default inf
        Returned for points outside the grid.
    use_abs : bool, default False
        Use absolute values (unsigned distances), e.g. for open meshes.

    Raises
    ------
    ValueError
        If a shape is wrong, a value is not finite or ``resolution`` is not
        positive.

    Notes
    -----
    Values between nodes are trilinear in each cell, as scipy's
    ``RegularGridInterpolator`` (and so scikit-robot's ``GridSDF``) computes
    them; a point is inside the grid when every coordinate lies in
    ``[origin, origin + (n - 1) * resolution]``.

    Examples
    --------
    A sphere of radius 0.5 sampled on a 21³ grid:

    >>> import numpy as np
    >>> from rbm_nb.sdf import GridSDF
    >>> axis = np.linspace(-1.0, 1.0, 21)
    >>> x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    >>> ball = GridSDF(np.sqrt(x**2 + y**2 + z**2) - 0.5, [-1.0, -1.0, -1.0], 0.1)
    >>> ball.sdf([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0], [2.0, 0.0, 0.0]]).round(6)
    array([-0.5,  0.3,  inf])

    Gradients are those of the trilinear interpolant, so only roughly radial
    on a coarse grid:

    >>> ball.gradient([[0.75, 0.0, 0.0]], normalize=True).round(2)
    array([[1.  , 0.07, 0.07]])
    """

    def __init__(
        self,
        sdf_data,
        origin,
        resolution,
        *,
        frame=None,
        fill_value=np.inf,
        use_abs: bool = False,
    ):
        data = float_array(sdf_data, "sdf_data")
        if data.ndim != 3 or min(data.shape) < 2:
            raise ValueError(
                "sdf_data must have shape (nx, ny, nz) with every dimension at "
                f"least 2, got shape {data.shape}"
            )
        check_finite(data, "sdf_data")
        origin = float_array(origin, "origin")
        if origin.shape != (3,):
            raise ValueError(f"origin must have shape (3,), got shape {origin.shape}")
        check_finite(origin, "origin")
        try:
            resolution = float(resolution)
        except (TypeError, ValueError):
            raise ValueError(
                f"resolution must be a positive number, got {resolution!r}"
            ) from None
        if not (np.isfinite(resolution) and resolution > 0.0):
            raise ValueError(
                f"resolution must be a positive number, got {resolution!r}"
            )
        try:
            fill_value = float(fill_value)
        except (TypeError, ValueError):
            raise ValueError(
                f"fill_value must be a number, got {fill_value!r}"
            ) from None
        if np.isnan(fill_value):
            raise ValueError("fill_value must not be nan (use inf or a number)")
        if frame is not None:
            if not isinstance(frame, (str, ReferenceFrame)):
                raise TypeError(
                    "frame must be a ReferenceFrame, the name of a registered frame "
                    f"or None, got {type(frame).__name__}"
                )
        # private copies the kernels read (they take writeable arrays); the
        # properties hand out read-only views, so the grid cannot change
        # behind its back, through the caller's array or through them
        self._data = kernel_array(np.abs(data)) if use_abs else data.copy(order="C")
        self._origin = origin.copy()
        self._resolution = resolution
        self._frame = frame
        self._fill_value = fill_value
        self._use_abs = bool(use_abs)

    # -- description ---------------------------------------------------------

    @property
    def data(self) -> np.ndarray:
        """The node values, shape (nx, ny, nz), read-only."""
        return _read_only(self._data)

    @property
    def origin(self) -> np.ndarray:
        """Position of node (0, 0, 0) in the grid's frame, shape (3,), read-only."""
        return _read_only(self._origin)

    @property
    def resolution(self) -> float:
        """Node spacing."""
        return self._resolution

    @property
    def shape(self) -> tuple:
        """Number of nodes along x, y and z."""
        return self._data.shape

    @property
    def frame(self):
        """The frame the grid is fixed in (as given), or None."""
        return self._frame

    @property
    def fill_value(self) -> float:
        """The value returned outside the grid."""
        return self._fill_value

    @property
    def use_abs(self) -> bool:
        """Whether distances are unsigned."""
        return self._use_abs

    @property
    def bounds(self) -> np.ndarray:
        """Lower and upper corner of the grid in its frame, shape (2, 3)."""
        upper = self._origin + (np.array(self.shape) - 1) * self._resolution
        return np.stack([self._origin, upper])

    def __repr__(self) -> str:
        frame = getattr(self._frame, "name", self._frame)
        return (
            f"GridSDF(shape={self.shape}, resolution={self._resolution:g}, "
            f"frame={frame!r}, bounds={self.bounds.round(6).tolist()})"
        )

    # -- frames ----------------------------------------------------------------

    def _pose(self, frame, timestamps, lead: tuple, what: str) -> Transform | None:
        """The transformation from ``frame`` into the grid's frame, per point.

        Returns None when the points are already in the grid's frame, a
        single Transform for a static relation, and otherwise a batch that
        broadcasts against the points' leading shape ``lead`` (one pose per
        entry along its first axis, looked up at that entry's timestamp).
        """
        if frame is None:
            if timestamps is not None:
                raise ValueError(
                    f"{what}: timestamps are only used together with frame= (the "
                    "points are in the grid's own frame, which needs no lookup)"
                )
            return None

        query = resolve_frame(frame, f"{what}: frame")
        if self._frame is None:
            raise ValueError(
                f"{what}: this GridSDF is not attached to a frame, so points in "
                f"frame {query.name!r} cannot be placed in it; give frame= when "
                "building the GridSDF or query with frame=None"
            )
        grid = resolve_frame(self._frame, "the GridSDF's frame")
        if query is grid:
            return None

        if timestamps is None:
            t, ts = transform_points(
                np.zeros((1, 3)), into=grid, outof=query, return_timestamps=True
            )
            if ts is not None:
                raise ValueError(
                    f"{what}: frames {query.name!r} and {grid.name!r} move relative "
                    "to each other; pass timestamps (one per point along the first "
                    "axis of the points)"
                )
            q = transform_quaternions(_IDENTITY_Q, into=grid, outof=query)
            return Transform(t[0], q[0])
        ts = np.asarray(timestamps)
        if ts.ndim != 1 or not lead or ts.shape[0] != lead[0]:
            raise ValueError(
                f"{what}: timestamps must have shape ({lead[0] if lead else 'n'},), "
                f"one per entry along the first axis of the points, got shape "
                f"{ts.shape}"
            )
        # the core matches strictly increasing timestamps: look each distinct
        # time up once and hand the result back to every point sharing it
        times, back = np.unique(ts, return_inverse=True)
        t, ts_out = transform_points(
            np.zeros((len(times), 3)),
            into=grid,
            outof=query,
            timestamps=times,
            return_timestamps=True,
        )
        if ts_out is not None and len(ts_out) != len(times):
            missing = np.setdiff1d(times, ts_out)
            raise ValueError(
                f"{what}: timestamps {missing[:3].tolist()}"
                f"{' ...' if len(missing) > 3 else ''} lie outside the time range "
                f"over which {query.name!r} can be placed in {grid.name!r}"
            )
        q = transform_quaternions(
            np.repeat(_IDENTITY_Q, len(times), axis=0),
            into=grid,
            outof=query,
            timestamps=times,
        )
        expand = (slice(None),) + (None,) * (len(lead) - 1)
        return Transform(t[back][expand], q[back][expand])

    def _in_grid(self, points, frame, timestamps, what):
        p = _points(points, "points")
        pose = self._pose(frame, timestamps, p.shape[:-1], what)
        if pose is not None:
            p = pose.apply(p)
        return kernel_array(p.reshape(-1, 3)), p.shape[:-1], pose

    # -- queries -----------------------------------------------------------------

    def sdf(self, points, *, frame=None, timestamps=None) -> np.ndarray:
        """Signed distances at points, ``fill_value`` outside the grid.

        Parameters
        ----------
        points : array_like, shape (..., 3)
            Points expressed in ``frame``.
        frame : str or ReferenceFrame, optional
            The frame of ``points``; default: the grid's own frame.
        timestamps : array_like, shape (n,), optional
            One timestamp per entry along the first axis of ``points``,
            needed when ``frame`` and the grid's frame move relative to each
            other. Need not be sorted or distinct.

        Returns
        -------
        ndarray, shape (...)

        Raises
        ------
        ValueError
            For bad shapes or non-finite points, a frame outside the grid's
            tree, missing timestamps for moving frames, or timestamps outside
            the frames' time range.
        """
        rows, lead, _ = self._in_grid(points, frame, timestamps, "sdf")
        out = _kernels().grid_values(
            self._data, self._origin, self._resolution, self._fill_value, rows
        )
        if self._use_abs:
            out = np.abs(out)
        return out.reshape(lead)

    __call__ = sdf

    def is_out_of_bounds(self, points, *, frame=None, timestamps=None) -> np.ndarray:
        """Whether points lie outside the grid (where ``sdf`` gives ``fill_value``).

        Parameters are those of :meth:`sdf`. (scikit-robot's method of this
        name lets points up to one cell beyond the last node count as inside,
        although its interpolator fills them; here the two always agree.)

        Returns
        -------
        ndarray of bool, shape (...)
        """
        rows, lead, _ = self._in_grid(points, frame, timestamps, "is_out_of_bounds")
        # the kernel's test, on offsets from the origin, so both always agree
        offset = rows - self._origin
        last = (np.array(self.shape) - 1) * self._resolution
        out = np.any((offset < 0.0) | (offset > last), axis=1)
        return out.reshape(lead)

    def gradient(
        self, points, *, frame=None, timestamps=None, normalize: bool = False
    ) -> np.ndarray:
        """Gradients of the interpolated distance (outward surface normals).

        The gradient of the trilinear interpolant of the cell each point
        falls in; on a face shared by two cells the cell above is used.

        Parameters
        ----------
        points, frame, timestamps
            As for :meth:`sdf`.
        normalize : bool, default False
            Return unit vectors (the surface normal direction).

        Returns
        -------
        ndarray, shape (..., 3)
            Represented in ``frame``. Rows of nan for points outside the grid
            (see :meth:`is_out_of_bounds`) and, with ``normalize``, where the
            gradient vanishes.
        """
        rows, lead, pose = self._in_grid(points, frame, timestamps, "gradient")
        g = _kernels().grid_gradients(self._data, self._origin, self._resolution, rows)
        if normalize:
            norm = np.linalg.norm(g, axis=1, keepdims=True)
            with np.errstate(invalid="ignore", divide="ignore"):
                g = np.where(norm > 0.0, g / norm, np.nan)
        g = g.reshape(lead + (3,))
        if pose is not None:
            g = pose.inv().apply_vectors(g)
        return g

    def ray_hits(
        self,
        origins,
        directions,
        max_distance=np.inf,
        *,
        frame=None,
        timestamps=None,
        tolerance: float | None = None,
        max_steps: int = 512,
    ) -> RayHits:
        """Where rays first meet the zero level set, by sphere tracing.

        Each ray advances by the distance sampled at its tip until that
        distance falls below ``tolerance``; a step that lands inside the
        object is refined onto the crossing (Illinois method). Only the part
        of a ray inside the grid is traced.

        Parameters
        ----------
        origins : array_like, shape (..., 3)
            Ray origins in ``frame`` (e.g. eye positions).
        directions : array_like, shape (..., 3)
            Ray directions in ``frame``, any non-zero length; broadcast
            against ``origins``.
        max_distance : float or array_like, shape (...), default inf
            Longest distance to trace along each ray, > 0.
        frame, timestamps
            As for :meth:`sdf` (timestamps along the first axis of the
            broadcast rays).
        tolerance : float, optional
            Distance at which a ray counts as arrived; default
            ``1e-4 * resolution``.
        max_steps : int, default 512
            Rays still marching after this many steps count as misses
            (grazing rays converge slowly).

        Returns
        -------
        RayHits
            ``points``, ``distances``, ``hit`` and ``normals``; nan for misses.
            A ray that starts inside the object hits at distance 0.

        Examples
        --------
        >>> import numpy as np
        >>> from rbm_nb.sdf import GridSDF
        >>> axis = np.linspace(-1.0, 1.0, 41)
        >>> x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
        >>> ball = GridSDF(np.sqrt(x**2 + y**2 + z**2) - 0.5, [-1.0, -1.0, -1.0], 0.05)
        >>> hits = ball.ray_hits([[-3.0, 0.0, 0.0], [-3.0, 0.9, 0.0]], [1.0, 0.0, 0.0])
        >>> hits.hit
        array([ True, False])
        >>> hits.distances.round(6)
        array([2.5, nan])
        """
        o = _points(origins, "origins")
        u = _points(directions, "directions")
        try:
            lead = np.broadcast_shapes(o.shape[:-1], u.shape[:-1])
        except ValueError:
            raise ValueError(
                f"origins of shape {o.shape} and directions of shape {u.shape} do "
                "not broadcast"
            ) from None
        norm = np.linalg.norm(u, axis=-1)
        if not np.all(norm > 0.0):
            raise ValueError("directions must not contain zero-length vectors")
        u = u / norm[..., None]
        o = np.broadcast_to(o, lead + (3,))
        u = np.broadcast_to(u, lead + (3,))
        reach = float_array(max_distance, "max_distance")
        if np.isnan(reach).any() or not np.all(reach > 0.0):
            raise ValueError(
                f"max_distance must be positive (inf allowed), got {max_distance!r}"
            )
        try:
            reach = np.broadcast_to(reach, lead)
        except ValueError:
            raise ValueError(
                f"max_distance of shape {reach.shape} does not broadcast against "
                f"the rays' shape {lead}"
            ) from None
        if tolerance is None:
            tolerance = 1e-4 * self._resolution
        if not (np.isfinite(tolerance) and tolerance > 0.0):
            raise ValueError(f"tolerance must be a positive number, got {tolerance!r}")
        if int(max_steps) != max_steps or max_steps < 1:
            raise ValueError(f"max_steps must be a positive integer, got {max_steps!r}")
        pose = self._pose(frame, timestamps, lead, "ray_hits")
        if pose is not None:
            o_grid, u_grid = pose.apply(o), pose.apply_vectors(u)
        else:
            o_grid, u_grid = o, u
        k = _kernels()
        t, hit = k.sphere_trace(
            self._data,
            self._origin,
            self._resolution,
            kernel_array(o_grid.reshape(-1, 3)),
            kernel_array(u_grid.reshape(-1, 3)),
            kernel_array(reach.reshape(-1)),
            float(tolerance),
            int(max_steps),
        )
        t = t.reshape(lead)
        hit = hit.reshape(lead)
        points = o + t[..., None] * u
        normals = np.full(lead + (3,), np.nan)
        if hit.any():
            at = kernel_array((o_grid + t[..., None] * u_grid)[hit].reshape(-1, 3))
            g = k.grid_gradients(self._data, self._origin, self._resolution, at)
            with np.errstate(invalid="ignore", divide="ignore"):
                g = g / np.linalg.norm(g, axis=1, keepdims=True)
            if pose is not None:
                inverse = pose.inv()
                if inverse.shape:
                    inverse = Transform(
                        np.broadcast_to(inverse.translation, lead + (3,))[hit],
                        np.broadcast_to(inverse.rotation, lead + (4,))[hit],
                    )
                g = inverse.apply_vectors(g)
            normals[hit] = g
        return RayHits(points, t, hit, normals)

    # -- meshes ---------------------------------------------------------------------

    @classmethod
    def from_mesh(
        cls,
        mesh,
        resolution: float,
        *,
        padding: float | None = None,
        frame=None,
        fill_value=np.inf,
        use_abs: bool = False,
    ) -> GridSDF:
        """Sample the signed distance to a closed triangle mesh on a grid.

        Distances are exact point-to-triangle distances (numba). Their sign
        needs a watertight mesh (unless ``use_abs`` asks for unsigned
        distances): nodes farther than a cell from the surface fall into
        regions that the surface does not cross, each decided by the winding
        number of one of its nodes; the nodes near the surface get their own.

        Parameters
        ----------
        mesh : str, path, trimesh.Trimesh or (vertices, faces)
            A mesh file trimesh can read, a Trimesh, or ``vertices`` (m, 3)
            and integer ``faces`` (k, 3), in the grid's frame.
        resolution : float
            Node spacing, > 0.
        padding : float, optional
            Margin around the mesh's bounding box; default ``5 * resolution``.
        frame, fill_value, use_abs
            As for :class:`GridSDF`.

        Returns
        -------
        GridSDF

        Raises
        ------
        ImportError
            Without the ``sdf`` extra (trimesh).
        ValueError
            For an empty or non-watertight mesh (unless ``use_abs``), or a
            grid of more than ``rbm_nb.sdf.MAX_GRID_NODES`` nodes.

        Examples
        --------
        >>> import trimesh
        >>> from rbm_nb.sdf import GridSDF
        >>> box = trimesh.creation.box(extents=[0.2, 0.2, 0.2])
        >>> grid = GridSDF.from_mesh(box, 0.02)
        >>> grid.sdf([[0.0, 0.0, 0.0], [0.15, 0.0, 0.0]]).round(6)
        array([-0.1 ,  0.05])
        """
        data, lower, resolution = _mesh.sample_mesh(mesh, resolution, padding, use_abs)
        return cls(
            data,
            lower,
            resolution,
            frame=frame,
            fill_value=fill_value,
            use_abs=use_abs,
        )

    def surface_mesh(self, level: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Triangles of the level set ``sdf == level`` (marching cubes).

        Parameters
        ----------
        level : float, default 0.0
            Must lie strictly between the grid's smallest and largest value.

        Returns
        -------
        vertices : ndarray, shape (m, 3)
            In the grid's frame.
        faces : ndarray of int, shape (k, 3)
            Counter-clockwise seen from outside (normals point to larger
            values).

        Raises
        ------
        ImportError
            Without the ``sdf`` extra (scikit-image).
        ValueError
            If the grid does not cross ``level``.
        """
        return _mesh.level_set(self._data, self._origin, self._resolution, level)

    def add_to_scene(
        self,
        scene,
        *,
        level: float = 0.0,
        color="#c8a2c8",
        opacity: float = 0.6,
        label: str | None = None,
    ):
        """Draw the level set in a :class:`rbm_nb.scene.Scene`, fixed in the grid's frame.

        The triangles go through ``Scene.add_mesh`` as a Wavefront ``.obj``
        file in a temporary folder that is removed when Python exits.

        Parameters
        ----------
        scene : rbm_nb.scene.Scene
        level : float, default 0.0
        color : str or int, default "#c8a2c8"
        opacity : float, default 0.6
        label : str, optional
            Name of the object in the scene.

        Returns
        -------
        MeshHandle
            The scene's handle for the mesh (hide, restyle or remove it).

        Raises
        ------
        ValueError
            If the GridSDF has no frame to attach the mesh to.
        """
        if self._frame is None:
            raise ValueError(
                "add_to_scene: this GridSDF is not attached to a frame; build it "
                "with frame= so the scene knows where to draw it"
            )
        vertices, faces = self.surface_mesh(level)
        path = _mesh.write_obj(vertices, faces)
        try:
            handle = scene.add_mesh(
                self._frame,
                path,
                color=color,
                opacity=opacity,
                label=label or f"sdf {getattr(self._frame, 'name', self._frame)}",
            )
        except BaseException:
            os.remove(path)
            raise
        return handle
