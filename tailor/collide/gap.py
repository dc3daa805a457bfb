"""The exact signed distance from points to a body surface, at any distance: a per-frame measurement
(an outfit's layer order, fit maps), not the simulation's contact query (:class:`~.body.BodyCollider`).

The body vertex nearest a point is on the surface, so the surface is no farther than it: every
triangle that could hold a nearer point has its bounding box within that bound. Those are each
point's candidates, found by a compiled pass over a uniform grid of the triangles' boxes (counted,
then written: CSR), and the closest of them by the narrow phase the body collider uses
(:func:`~.closest.nearest_into`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from scipy.spatial import cKDTree

from .bounds import axis_bounds, triangle_bounds
from .closest import nearest_into
from .grid import Grid, bin_boxes, cell_span, gap2, owns

__all__ = ["body_gap"]

GAP_CELL = 5.0
"""The candidate grid's cells, in the body triangles' mean box side (about 0.6 of a mean edge)."""


@njit(cache=True)
def _within(q, fill, out, start, x, bound, t_lo, t_hi, ptr, items, origin, cell, dims):
    """Count (``fill`` False) or write the triangles whose box comes within ``bound[q]`` of point ``q``,
    each once: from the cell holding the lower corner of the overlap of its box and the point's grown."""
    p = x[q]
    r = bound[q]
    found = 0
    i0, j0, k0, i1, j1, k1 = cell_span(p, p, r, origin, cell, dims)
    for c in range(k0, k1 + 1):
        for b in range(j0, j1 + 1):
            for a in range(i0, i1 + 1):
                key = a + dims[0] * (b + dims[1] * c)
                for m in range(ptr[key], ptr[key + 1]):
                    t = items[m]
                    if gap2(p, p, t_lo[t], t_hi[t]) > r * r or not owns(p, t_lo[t], r, a, b, c, origin, cell, dims):
                        continue
                    if fill:
                        out[start + found] = t
                    found += 1
    return found


@njit(cache=True, parallel=True)
def _candidates(x, bound, t_lo, t_hi, origin, cell, dims):
    """CSR (lo, hi, triangles) of each point's triangles whose box lies within its bound."""
    ptr, items = bin_boxes(t_lo, t_hi, origin, cell, dims)
    n = len(x)
    counts = np.zeros(n, np.int64)
    none = np.zeros(0, np.int64)
    for q in prange(n):
        counts[q] = _within(q, False, none, 0, x, bound, t_lo, t_hi, ptr, items, origin, cell, dims)
    hi = np.cumsum(counts)
    lo = hi - counts
    out = np.empty(hi[-1] if n else 0, np.int64)
    for q in prange(n):
        _within(q, True, out, lo[q], x, bound, t_lo, t_hi, ptr, items, origin, cell, dims)
    return lo, hi, out


def body_gap(x, body_x, body_faces):
    """Signed distance [m] from each point to the body surface (negative inside) and the body's
    outward normal at its nearest point (:func:`~tailor.collide.closest.nearest_into`), exact at any
    distance (module docstring)."""
    x = np.ascontiguousarray(x, float)
    body_x = np.ascontiguousarray(body_x, float)
    faces = np.ascontiguousarray(body_faces, np.int64)
    n = len(x)
    dist, tri, bary, normal = np.full(n, np.inf), np.full(n, -1, np.int64), np.zeros((n, 3)), np.zeros((n, 3))
    if not n:
        return dist, normal
    bound = cKDTree(body_x, balanced_tree=False, compact_nodes=False).query(x)[0] * (1.0 + 1e-9) + 1e-12
    t_lo, t_hi = triangle_bounds(body_x, faces, 3)
    (lo, _), (_, hi) = axis_bounds(t_lo), axis_bounds(t_hi)
    (near_lo, _), (_, near_hi) = axis_bounds(x - bound[:, None]), axis_bounds(x + bound[:, None])
    grid = Grid(np.vstack([lo, near_lo]), np.vstack([hi, near_hi]), GAP_CELL * float(np.mean(t_hi - t_lo)))
    start, end, candidates = _candidates(x, bound, t_lo, t_hi, grid.origin, grid.cell, grid.dims)
    nearest_into(x, start, end, candidates, body_x, faces, dist, tri, bary, normal, np.arange(n, dtype=np.int64))
    return dist, normal
