"""Where a mesh's edges pass through its own triangles: the crossings a renderer shows as cloth through cloth.

An edge crosses a triangle when the segment meets the triangle's interior and the two share no
vertex (Möller & Trumbore's ray–triangle test, limited to the segment). Two triangles that
intersect always have an edge of one through the other (unless coplanar), so no crossing means
no intersecting triangle pair; the count says how much cloth passes through, edge by edge.
Compiled over a uniform grid of cells about two mean edge lengths wide: independent of the
simulator's own proximity queries, and cheap enough to run on every frame.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .bounds import axis_bounds
from .grid import Grid, bin_boxes, cell_span, gap2, owns, unique_edges

__all__ = ["edge_crossings"]

EPS = 1e-12
"""Relative size below which a segment is taken as parallel to a triangle's plane (no crossing)."""


@njit(cache=True, inline="always")
def _crosses(p, q, a, b, c):
    """Whether segment pq passes through the interior of triangle abc (Möller–Trumbore)."""
    d0, d1, d2 = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    e10, e11, e12 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    e20, e21, e22 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    h0, h1, h2 = d1 * e22 - d2 * e21, d2 * e20 - d0 * e22, d0 * e21 - d1 * e20
    det = e10 * h0 + e11 * h1 + e12 * h2
    scale = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) * math.sqrt(e10 * e10 + e11 * e11 + e12 * e12) \
        * math.sqrt(e20 * e20 + e21 * e21 + e22 * e22)
    if abs(det) <= EPS * scale:
        return False
    f = 1.0 / det
    s0, s1, s2 = p[0] - a[0], p[1] - a[1], p[2] - a[2]
    u = f * (s0 * h0 + s1 * h1 + s2 * h2)
    if u < 0.0 or u > 1.0:
        return False
    r0, r1, r2 = s1 * e12 - s2 * e11, s2 * e10 - s0 * e12, s0 * e11 - s1 * e10
    v = f * (d0 * r0 + d1 * r1 + d2 * r2)
    if v < 0.0 or u + v > 1.0:
        return False
    t = f * (e20 * r0 + e21 * r1 + e22 * r2)
    return 0.0 <= t <= 1.0


@njit(cache=True)
def _crossed_by(k, fill, out, start, x, faces, edges, e_lo, e_hi, t_lo, t_hi, ptr, tri, origin, cell, dims):
    """Count (``fill`` False) or write the triangles edge ``k`` passes through. Each (edge, triangle)
    pair is tested once: from the cell holding the lower corner of their boxes' overlap."""
    i, j = edges[k, 0], edges[k, 1]
    found = 0
    i0, j0, k0, i1, j1, k1 = cell_span(e_lo[k], e_hi[k], 0.0, origin, cell, dims)
    for c in range(k0, k1 + 1):
        for b in range(j0, j1 + 1):
            for a in range(i0, i1 + 1):
                key = a + dims[0] * (b + dims[1] * c)
                for m in range(ptr[key], ptr[key + 1]):
                    t = tri[m]
                    f0, f1, f2 = faces[t, 0], faces[t, 1], faces[t, 2]
                    if f0 == i or f1 == i or f2 == i or f0 == j or f1 == j or f2 == j:
                        continue
                    if gap2(e_lo[k], e_hi[k], t_lo[t], t_hi[t]) > 0.0:
                        continue
                    if not owns(e_lo[k], t_lo[t], 0.0, a, b, c, origin, cell, dims):
                        continue
                    if _crosses(x[i], x[j], x[f0], x[f1], x[f2]):
                        if fill:
                            out[start + found] = t
                        found += 1
    return found


@njit(cache=True, parallel=True)
def _edge_crossings(x, faces, edges, origin, cell, dims):
    """(K, 2) rows (edge, triangle) of the crossings, by edge: counted, then written, each a
    parallel pass over the edges."""
    t_lo = np.empty((len(faces), 3))
    t_hi = np.empty((len(faces), 3))
    for t in prange(len(faces)):
        for e in range(3):
            t_lo[t, e] = min(x[faces[t, 0], e], x[faces[t, 1], e], x[faces[t, 2], e])
            t_hi[t, e] = max(x[faces[t, 0], e], x[faces[t, 1], e], x[faces[t, 2], e])
    ptr, tri = bin_boxes(t_lo, t_hi, origin, cell, dims)
    e_lo = np.minimum(x[edges[:, 0]], x[edges[:, 1]])
    e_hi = np.maximum(x[edges[:, 0]], x[edges[:, 1]])
    counts = np.zeros(len(edges), np.int64)
    none = np.zeros(0, np.int64)
    for k in prange(len(edges)):
        counts[k] = _crossed_by(k, False, none, 0, x, faces, edges, e_lo, e_hi, t_lo, t_hi, ptr, tri, origin, cell, dims)
    starts = np.zeros(len(edges) + 1, np.int64)
    starts[1:] = np.cumsum(counts)
    res = np.empty((starts[-1], 2), np.int64)
    for k in prange(len(edges)):
        if counts[k]:
            res[starts[k]:starts[k + 1], 0] = k
            _crossed_by(k, True, res[:, 1], starts[k], x, faces, edges, e_lo, e_hi, t_lo, t_hi, ptr, tri, origin, cell, dims)
    return res


def edge_crossings(vertices, faces, edges=None, still=None) -> np.ndarray:
    """(K, 3): the edges (two vertex indices) of a mesh that pass through one of its own triangles
    sharing no vertex with them, and that triangle. Empty: the mesh does not pass through itself.

    ``edges``: the mesh's :func:`~tailor.collide.grid.unique_edges`, if the caller keeps them (a check
    every frame of one mesh). ``still`` ((N,) bool, optional): vertices held still; an edge and a
    triangle all of whose vertices are still are not tested (nothing can have moved them through
    each other since they were last looked at, and nothing can part them)."""
    x = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if not len(faces):
        return np.zeros((0, 3), np.int64)
    edges = unique_edges(faces, len(x)) if edges is None else np.ascontiguousarray(edges, dtype=np.int64)
    length = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1)
    cell = max(2.0 * float(np.mean(length)), 1e-6)
    used = np.zeros(len(x), bool)
    used[edges.ravel()] = True
    lo, hi = axis_bounds(x[used])
    grid = Grid(lo[None], hi[None], cell)
    if still is None:
        parts = [(edges, np.arange(len(faces)))]
    else:  # the moving edges through any triangle, the still ones through a triangle that moves
        moving_edge, moving_face = ~np.asarray(still, bool)[edges].all(axis=1), ~np.asarray(still, bool)[faces].all(axis=1)
        parts = [(edges[moving_edge], np.arange(len(faces))), (edges[~moving_edge], np.flatnonzero(moving_face))]
    found = [np.zeros((0, 3), np.int64)]
    for e, tri in parts:
        if len(e) and len(tri):
            pairs = _edge_crossings(x, np.ascontiguousarray(faces[tri]), e, grid.origin, grid.cell, grid.dims)
            found.append(np.column_stack([e[pairs[:, 0]], tri[pairs[:, 1]]]).astype(np.int64))
    return np.concatenate(found)
