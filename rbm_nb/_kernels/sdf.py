"""Signed distance grids: trilinear sampling, gradients and sphere tracing.

Conventions shared by every function here:

* ``data`` is a C-contiguous float64 array of shape (nx, ny, nz), every
  dimension at least 2; node ``(i, j, k)`` lies at
  ``origin + (i, j, k) * resolution`` in the grid's frame;
* points, origins and directions are C-contiguous float64 arrays of shape
  (n, 3) in the grid's frame; directions are unit vectors;
* a point is inside the grid when every coordinate lies in
  ``[origin, origin + (n - 1) * resolution]`` (both ends included, as in
  scipy's ``RegularGridInterpolator``);
* nothing is validated: ``rbm_nb.sdf`` checks shapes and values first.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import F1, F2, F3, F, I, helper, kernel

# an upper bound on the Illinois steps that pin a bracketed zero down (it
# typically needs 3-6; bisection alone would need ~50 for the same accuracy)
_REFINEMENTS = 100


@helper
def _locate(x, n, resolution):
    """Cell index and fraction of offset ``x`` along an axis of ``n`` nodes; -1 outside."""
    if not (x >= 0.0 and x <= (n - 1) * resolution):
        return -1, 0.0
    i = int(math.floor(x / resolution))
    if i > n - 2:
        i = n - 2
    lo = i * resolution
    return i, (x - lo) / ((i + 1) * resolution - lo)


@helper
def _sample(data, origin, resolution, px, py, pz, fill_value):
    """Trilinear value and its gradient at one point; (fill, nan, nan, nan) outside."""
    nx, ny, nz = data.shape
    i, fx = _locate(px - origin[0], nx, resolution)
    j, fy = _locate(py - origin[1], ny, resolution)
    k, fz = _locate(pz - origin[2], nz, resolution)
    if i < 0 or j < 0 or k < 0:
        return fill_value, np.nan, np.nan, np.nan
    c000 = data[i, j, k]
    c100 = data[i + 1, j, k]
    c010 = data[i, j + 1, k]
    c110 = data[i + 1, j + 1, k]
    c001 = data[i, j, k + 1]
    c101 = data[i + 1, j, k + 1]
    c011 = data[i, j + 1, k + 1]
    c111 = data[i + 1, j + 1, k + 1]
    # interpolate along x first, then y, then z
    c00 = c000 + fx * (c100 - c000)
    c10 = c010 + fx * (c110 - c010)
    c01 = c001 + fx * (c101 - c001)
    c11 = c011 + fx * (c111 - c011)
    c0 = c00 + fy * (c10 - c00)
    c1 = c01 + fy * (c11 - c01)
    value = c0 + fz * (c1 - c0)
    # derivatives of the same trilinear polynomial inside this cell
    dx0 = (c100 - c000) + fy * ((c110 - c010) - (c100 - c000))
    dx1 = (c101 - c001) + fy * ((c111 - c011) - (c101 - c001))
    gx = (dx0 + fz * (dx1 - dx0)) / resolution
    dy0 = c10 - c00
    dy1 = c11 - c01
    gy = (dy0 + fz * (dy1 - dy0)) / resolution
    gz = (c1 - c0) / resolution
    return value, gx, gy, gz


@kernel(F3, F1, F, F, F2)
def grid_values(data, origin, resolution, fill_value, points):
    """Trilinear distances at (n, 3) points; ``fill_value`` outside the grid."""
    n = points.shape[0]
    out = np.empty(n)
    for p in range(n):
        out[p] = _sample(
            data, origin, resolution, points[p, 0], points[p, 1], points[p, 2],
            fill_value,
        )[0]  # fmt: skip
    return out


@kernel(F3, F1, F, F2)
def grid_gradients(data, origin, resolution, points):
    """Gradients (n, 3) of the trilinear interpolant; rows of nan outside the grid."""
    n = points.shape[0]
    out = np.empty((n, 3))
    for p in range(n):
        _, gx, gy, gz = _sample(
            data, origin, resolution, points[p, 0], points[p, 1], points[p, 2], 0.0
        )
        out[p, 0] = gx
        out[p, 1] = gy
        out[p, 2] = gz
    return out


@helper
def _box_segment(lo, hi, o, u, t_max):
    """Parameter range [t0, t1] of the ray o + t u inside the box, within [0, t_max]."""
    t0 = 0.0
    t1 = t_max
    for a in range(3):
        if u[a] == 0.0:
            if o[a] < lo[a] or o[a] > hi[a]:
                return 1.0, 0.0
            continue
        ta = (lo[a] - o[a]) / u[a]
        tb = (hi[a] - o[a]) / u[a]
        if ta > tb:
            ta, tb = tb, ta
        t0 = max(t0, ta)
        t1 = min(t1, tb)
    return t0, t1


@helper
def _along(data, origin, resolution, lo, hi, o, u, t):
    """Distance at o + t u, the point clamped into the box (t is inside up to rounding)."""
    px = min(max(o[0] + t * u[0], lo[0]), hi[0])
    py = min(max(o[1] + t * u[1], lo[1]), hi[1])
    pz = min(max(o[2] + t * u[2], lo[2]), hi[2])
    return _sample(data, origin, resolution, px, py, pz, np.inf)[0]


@helper
def _crossing(data, origin, resolution, lo, hi, o, u, a, fa, b, fb, tol):
    """The zero between a (value fa > 0) and b (fb < 0) by the Illinois method.

    Regula falsi that halves the value kept at an end which survives twice
    in a row, so it converges superlinearly instead of stalling; it stops
    once a sample is within ``tol`` of zero or the bracket is that short.
    """
    m = a
    side = 0
    for _ in range(_REFINEMENTS):
        m = (a * fb - b * fa) / (fb - fa)
        fm = _along(data, origin, resolution, lo, hi, o, u, m)
        if abs(fm) <= tol or b - a <= tol:
            break
        if fm < 0.0:
            b = m
            fb = fm
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a = m
            fa = fm
            if side == 1:
                fb *= 0.5
            side = 1
    return m


@kernel(F3, F1, F, F2, F2, F1, F, I)
def sphere_trace(
    data, origin, resolution, origins, directions, max_distance, tol, max_steps
):
    """March rays to the zero level set.

    Parameters
    ----------
    origins, directions : (n, 3)
        Directions of unit length.
    max_distance : (n,)
    tol : float
        A sample with distance <= tol ends the march as a hit.
    max_steps : int

    Returns
    -------
    t : (n,)
        Distance along the ray to the hit (nan for a miss).
    hit : (n,) bool

    A step of the current distance cannot pass the surface when the field
    is a true distance; an interpolated grid may overestimate a little, so a
    step that lands on a negative value is refined on the bracket it spans
    (Illinois method) to the crossing the step jumped over.
    """
    n = origins.shape[0]
    nx, ny, nz = data.shape
    lo = origin.copy()
    hi = np.empty(3)
    hi[0] = origin[0] + (nx - 1) * resolution
    hi[1] = origin[1] + (ny - 1) * resolution
    hi[2] = origin[2] + (nz - 1) * resolution
    t_out = np.full(n, np.nan)
    hit = np.zeros(n, dtype=np.bool_)
    for r in range(n):
        o = origins[r]
        u = directions[r]
        t0, t1 = _box_segment(lo, hi, o, u, max_distance[r])
        if t0 > t1:
            continue
        t = t0
        d = _along(data, origin, resolution, lo, hi, o, u, t)
        if d <= tol:
            t_out[r] = t
            hit[r] = True
            continue
        for _ in range(max_steps):
            t_next = min(t + d, t1)
            d_next = _along(data, origin, resolution, lo, hi, o, u, t_next)
            if d_next < 0.0:
                t_out[r] = _crossing(
                    data, origin, resolution, lo, hi, o, u, t, d, t_next, d_next, tol
                )
                hit[r] = True
                break
            if d_next <= tol:
                t_out[r] = t_next
                hit[r] = True
                break
            if t_next >= t1:
                break
            t = t_next
            d = d_next
    return t_out, hit


@helper
def _triangle_distance2(px, py, pz, tri):
    """Squared distance from a point to a (3, 3) triangle (Ericson's regions)."""
    ax, ay, az = tri[0, 0], tri[0, 1], tri[0, 2]
    abx, aby, abz = tri[1, 0] - ax, tri[1, 1] - ay, tri[1, 2] - az
    acx, acy, acz = tri[2, 0] - ax, tri[2, 1] - ay, tri[2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return apx * apx + apy * apy + apz * apz
    bpx, bpy, bpz = px - tri[1, 0], py - tri[1, 1], pz - tri[1, 2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bpx * bpx + bpy * bpy + bpz * bpz
    cpx, cpy, cpz = px - tri[2, 0], py - tri[2, 1], pz - tri[2, 2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cpx * cpx + cpy * cpy + cpz * cpz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        qx, qy, qz = apx - v * abx, apy - v * aby, apz - v * abz
        return qx * qx + qy * qy + qz * qz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        qx, qy, qz = apx - w * acx, apy - w * acy, apz - w * acz
        return qx * qx + qy * qy + qz * qz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        qx = bpx - w * (tri[2, 0] - tri[1, 0])
        qy = bpy - w * (tri[2, 1] - tri[1, 1])
        qz = bpz - w * (tri[2, 2] - tri[1, 2])
        return qx * qx + qy * qy + qz * qz
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    qx = apx - abx * v - acx * w
    qy = apy - aby * v - acy * w
    qz = apz - abz * v - acz * w
    return qx * qx + qy * qy + qz * qz


# triangles per leaf of the bounding-volume hierarchy
_LEAF_SIZE = 4


@helper
def _build_bvh(triangles):
    """A bounding-volume hierarchy over (m, 3, 3) triangles, median splits.

    Returns
    -------
    order : (m,) triangle indices, each leaf owning a contiguous run
    box_lo, box_hi : (k, 3) node bounding boxes
    first, count : (k,) a leaf's run in ``order`` (count 0 for inner nodes)
    left : (k,) first child of an inner node (the second is ``left + 1``)
    """
    m = triangles.shape[0]
    tri_lo = np.empty((m, 3))
    tri_hi = np.empty((m, 3))
    centre = np.empty((m, 3))
    for f in range(m):
        for a in range(3):
            lo = min(triangles[f, 0, a], triangles[f, 1, a], triangles[f, 2, a])
            hi = max(triangles[f, 0, a], triangles[f, 1, a], triangles[f, 2, a])
            tri_lo[f, a] = lo
            tri_hi[f, a] = hi
            centre[f, a] = 0.5 * (lo + hi)
    order = np.arange(m)
    size = 2 * m + 1
    box_lo = np.empty((size, 3))
    box_hi = np.empty((size, 3))
    first = np.zeros(size, dtype=np.int64)
    count = np.zeros(size, dtype=np.int64)
    left = np.full(size, -1, dtype=np.int64)
    stack_node = np.empty(size, dtype=np.int64)
    stack_start = np.empty(size, dtype=np.int64)
    stack_stop = np.empty(size, dtype=np.int64)
    stack_node[0], stack_start[0], stack_stop[0] = 0, 0, m
    depth = 1
    n_nodes = 1
    while depth > 0:
        depth -= 1
        node = stack_node[depth]
        start = stack_start[depth]
        stop = stack_stop[depth]
        for a in range(3):
            lo = np.inf
            hi = -np.inf
            for i in range(start, stop):
                lo = min(lo, tri_lo[order[i], a])
                hi = max(hi, tri_hi[order[i], a])
            box_lo[node, a] = lo
            box_hi[node, a] = hi
        if stop - start <= _LEAF_SIZE:
            first[node] = start
            count[node] = stop - start
            continue
        # split the widest spread of centres at the median
        axis = 0
        widest = -1.0
        for a in range(3):
            lo = np.inf
            hi = -np.inf
            for i in range(start, stop):
                lo = min(lo, centre[order[i], a])
                hi = max(hi, centre[order[i], a])
            if hi - lo > widest:
                widest = hi - lo
                axis = a
        run = order[start:stop].copy()
        keys = np.empty(stop - start)
        for i in range(stop - start):
            keys[i] = centre[run[i], axis]
        order[start:stop] = run[np.argsort(keys)]
        middle = (start + stop) // 2
        left[node] = n_nodes
        stack_node[depth], stack_start[depth], stack_stop[depth] = (
            n_nodes,
            start,
            middle,
        )
        stack_node[depth + 1] = n_nodes + 1
        stack_start[depth + 1] = middle
        stack_stop[depth + 1] = stop
        depth += 2
        n_nodes += 2
    return order, box_lo[:n_nodes], box_hi[:n_nodes], first, count, left


@helper
def _box_distance2(px, py, pz, box_lo, box_hi, node):
    d2 = 0.0
    for a, v in ((0, px), (1, py), (2, pz)):
        if v < box_lo[node, a]:
            d2 += (box_lo[node, a] - v) ** 2
        elif v > box_hi[node, a]:
            d2 += (v - box_hi[node, a]) ** 2
    return d2


@kernel(F2, F3)
def mesh_distances(points, triangles):
    """Unsigned distances (n,) from points (n, 3) to the nearest of (m, 3, 3) triangles.

    Exact, through a bounding-volume hierarchy: a subtree is skipped when
    its box is farther than the best distance so far, which starts from the
    triangle nearest to the previous point (grid points come in order, so
    that bound is tight from the start), and the nearer child is searched
    first.
    """
    order, box_lo, box_hi, first, count, left = _build_bvh(triangles)
    n = points.shape[0]
    out = np.empty(n)
    stack = np.empty(box_lo.shape[0], dtype=np.int64)
    best_face = 0
    for p in range(n):
        px, py, pz = points[p, 0], points[p, 1], points[p, 2]
        best = _triangle_distance2(px, py, pz, triangles[best_face])
        stack[0] = 0
        depth = 1
        while depth > 0:
            depth -= 1
            node = stack[depth]
            if _box_distance2(px, py, pz, box_lo, box_hi, node) >= best:
                continue
            if left[node] < 0:
                for i in range(first[node], first[node] + count[node]):
                    f = order[i]
                    d2 = _triangle_distance2(px, py, pz, triangles[f])
                    if d2 < best:
                        best = d2
                        best_face = f
                continue
            a = left[node]
            b = a + 1
            # push the farther child first so that the nearer one is searched next
            if _box_distance2(px, py, pz, box_lo, box_hi, a) < _box_distance2(
                px, py, pz, box_lo, box_hi, b
            ):
                a, b = b, a
            stack[depth] = a
            stack[depth + 1] = b
            depth += 2
        out[p] = math.sqrt(best)
    return out


@kernel(F2, F3)
def winding_numbers(points, triangles):
    """Generalised winding numbers (n,) of (m, 3, 3) triangles around (n, 3) points.

    The solid angle of every triangle seen from the point (Van Oosterom and
    Strackee's formula), summed and divided by 4 pi: +-1 inside a closed,
    consistently oriented mesh, 0 outside, whatever its shape.
    """
    n = points.shape[0]
    m = triangles.shape[0]
    out = np.empty(n)
    for p in range(n):
        total = 0.0
        for f in range(m):
            ax = triangles[f, 0, 0] - points[p, 0]
            ay = triangles[f, 0, 1] - points[p, 1]
            az = triangles[f, 0, 2] - points[p, 2]
            bx = triangles[f, 1, 0] - points[p, 0]
            by = triangles[f, 1, 1] - points[p, 1]
            bz = triangles[f, 1, 2] - points[p, 2]
            cx = triangles[f, 2, 0] - points[p, 0]
            cy = triangles[f, 2, 1] - points[p, 1]
            cz = triangles[f, 2, 2] - points[p, 2]
            la = math.sqrt(ax * ax + ay * ay + az * az)
            lb = math.sqrt(bx * bx + by * by + bz * bz)
            lc = math.sqrt(cx * cx + cy * cy + cz * cz)
            det = (
                ax * (by * cz - bz * cy)
                - ay * (bx * cz - bz * cx)
                + az * (bx * cy - by * cx)
            )
            den = (
                la * lb * lc
                + (ax * bx + ay * by + az * bz) * lc
                + (ax * cx + ay * cy + az * cz) * lb
                + (bx * cx + by * cy + bz * cz) * la
            )
            total += 2.0 * math.atan2(det, den)
        out[p] = total / (4.0 * math.pi)
    return out
