"""A compiled uniform-grid broad phase: the pairs of boxes that come within a distance of each other.

The self-collision candidates change every few steps as the cloth moves, and python-fcl can
neither refit its hierarchies nor hand back pairs without one Python object each. Here the item
boxes are binned into a grid of cubes once per query; each query box, grown by the radius, visits
the cells it covers, and a pair is reported only from the cell holding the lower corner of the two
boxes' overlap, so each pair comes out once without a sort. Counting and filling are two parallel
passes over the queries (no shared state between threads). Used for vertex–triangle and
edge–edge candidates (:class:`~tailor.collide.cloth.SelfCollider`); FCL keeps the body's
proximity queries.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .closest import closest_barycentric

__all__ = ["overlapping_boxes", "vertex_rings", "Grid", "bin_boxes", "cell_of", "cell_span", "gap2", "owns", "vertex_triangle_pairs", "edge_edge_pairs", "MAX_CELLS"]

MAX_CELLS = 1 << 21
"""Cells a grid holds, about (one more per axis at most: 16 MB of cell pointers); coarser cells beyond."""


def overlapping_boxes(lo, hi):
    """(i, j), i < j, of the boxes (lo, hi) (K, 3) that overlap (touching counts), by sort and sweep
    along x: each box against those starting before its end. For the few hundred boxes of
    :class:`~tailor.collide.cloth.SelfCollider`'s patches; no grid, no Python object per pair."""
    lo, hi = np.ascontiguousarray(lo, np.float64), np.ascontiguousarray(hi, np.float64)
    if len(lo) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    order = np.argsort(lo[:, 0], kind="stable").astype(np.int64)
    none = np.zeros(0, np.int64)
    count = _sweep(lo, hi, order, False, none, none)  # counted, then written: no growing lists in compiled code
    i, j = np.empty(count, np.int64), np.empty(count, np.int64)
    _sweep(lo, hi, order, True, i, j)
    return i, j


@njit(cache=True)
def _sweep(lo, hi, order, fill, out_i, out_j):
    """Count (``fill`` False) or write the overlapping pairs of boxes taken in ``order`` (by lower x)."""
    found = 0
    for a in range(len(order)):
        p = order[a]
        for b in range(a + 1, len(order)):
            q = order[b]
            if lo[q, 0] > hi[p, 0]:
                break
            if lo[q, 1] > hi[p, 1] or lo[p, 1] > hi[q, 1] or lo[q, 2] > hi[p, 2] or lo[p, 2] > hi[q, 2]:
                continue
            if fill:
                out_i[found], out_j[found] = min(p, q), max(p, q)
            found += 1
    return found


def unique_edges(faces, n: int) -> np.ndarray:
    """(E, 2) each undirected edge of ``faces`` over ``n`` vertices once, lower index first, sorted
    (one integer key per edge: far quicker than ``np.unique`` on rows)."""
    e = np.sort(np.asarray(faces, np.int64)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keys = np.unique(e[:, 0] * n + e[:, 1])
    return np.column_stack([keys // n, keys % n])


def vertex_rings(faces, n: int):
    """CSR (ptr, idx) of each vertex's neighbours across an edge of ``faces``."""
    e = np.asarray(faces, np.int64)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    keys = np.unique(np.concatenate([e[:, 0] * n + e[:, 1], e[:, 1] * n + e[:, 0]]))
    return np.searchsorted(keys // n, np.arange(n + 1)).astype(np.int64), (keys % n).astype(np.int64)


class Grid:
    """Cubes of side ``cell`` over the boxes (lo, hi) of a query (at most :data:`MAX_CELLS`)."""

    def __init__(self, lo, hi, cell: float):
        self.origin = np.asarray(lo, float).min(axis=0)
        extent = np.maximum(np.asarray(hi, float).max(axis=0) - self.origin, 1e-9)
        cell = max(float(cell), float(np.prod(extent) / MAX_CELLS) ** (1.0 / 3.0), 1e-6)
        self.dims = (np.floor(extent / cell).astype(np.int64) + 1)
        self.cell = cell


@njit(cache=True, inline="always")
def cell_of(p, origin, cell, dims, axis):
    return min(max(int(math.floor((p - origin[axis]) / cell)), 0), dims[axis] - 1)


@njit(cache=True, inline="always")
def cell_span(lo, hi, r, origin, cell, dims):
    """(i0, j0, k0, i1, j1, k1): the first and last cell along each axis of the box (lo, hi) grown by ``r``."""
    return (cell_of(lo[0] - r, origin, cell, dims, 0), cell_of(lo[1] - r, origin, cell, dims, 1),
            cell_of(lo[2] - r, origin, cell, dims, 2), cell_of(hi[0] + r, origin, cell, dims, 0),
            cell_of(hi[1] + r, origin, cell, dims, 1), cell_of(hi[2] + r, origin, cell, dims, 2))


@njit(cache=True)
def bin_boxes(lo, hi, origin, cell, dims):
    """CSR (ptr, items) of the boxes (lo[k], hi[k]) meeting each cell, items in increasing order
    within a cell: a counting sort over the cells (two passes, no comparison sort)."""
    cells = dims[0] * dims[1] * dims[2]
    ptr = np.zeros(cells + 1, np.int64)
    for k in range(len(lo)):
        i0, j0, k0, i1, j1, k1 = cell_span(lo[k], hi[k], 0.0, origin, cell, dims)
        for c in range(k0, k1 + 1):
            for b in range(j0, j1 + 1):
                for a in range(i0, i1 + 1):
                    ptr[a + dims[0] * (b + dims[1] * c) + 1] += 1
    for m in range(cells):
        ptr[m + 1] += ptr[m]
    fill = ptr[:-1].copy()
    items = np.empty(ptr[cells], np.int64)
    for k in range(len(lo)):
        i0, j0, k0, i1, j1, k1 = cell_span(lo[k], hi[k], 0.0, origin, cell, dims)
        for c in range(k0, k1 + 1):
            for b in range(j0, j1 + 1):
                for a in range(i0, i1 + 1):
                    key = a + dims[0] * (b + dims[1] * c)
                    items[fill[key]] = k
                    fill[key] += 1
    return ptr, items


@njit(cache=True, inline="always")
def gap2(q_lo, q_hi, i_lo, i_hi):
    """Squared distance between two boxes."""
    d2 = 0.0
    for a in range(3):
        g = max(i_lo[a] - q_hi[a], 0.0, q_lo[a] - i_hi[a])
        d2 += g * g
    return d2


@njit(cache=True, inline="always")
def owns(q_lo, i_lo, r, a, b, c, origin, cell, dims):
    """Whether cell (a, b, c) holds the lower corner of the overlap of the grown query box and the item's box."""
    return (a == cell_of(max(q_lo[0] - r, i_lo[0]), origin, cell, dims, 0)
            and b == cell_of(max(q_lo[1] - r, i_lo[1]), origin, cell, dims, 1)
            and c == cell_of(max(q_lo[2] - r, i_lo[2]), origin, cell, dims, 2))


@njit(cache=True, inline="always")
def _neighbours(ring_ptr, ring_idx, p, q):
    """Whether vertices ``p`` and ``q`` are the same or share an edge (``q`` in ``p``'s CSR row)."""
    for m in range(ring_ptr[p], ring_ptr[p + 1]):
        if ring_idx[m] == q:
            return True
    return False


@njit(cache=True, inline="always")
def _shares(p, face):
    return face[0] == p or face[1] == p or face[2] == p


@njit(cache=True)
def _vt_one(q, fill, out_v, out_t, out_near, start, ring_ptr, ring_idx, verts, v_lo, v_hi, t_lo, t_hi, tris, faces, x, motion, check, ptr,
            items, origin, cell, dims, r):
    """Count (``fill`` False) or write the triangles within ``r`` of active vertex ``q`` (at ``x``, plus how
    far the vertex moved relative to the triangle's corners: ``motion`` (N, 3) per vertex over the step)."""
    p = verts[q]
    found = 0
    r2 = r * r
    i0, j0, k0, i1, j1, k1 = cell_span(v_lo[q], v_hi[q], r, origin, cell, dims)
    for c in range(k0, k1 + 1):
        for b in range(j0, j1 + 1):
            for a in range(i0, i1 + 1):
                key = a + dims[0] * (b + dims[1] * c)
                for m in range(ptr[key], ptr[key + 1]):
                    t = items[m]
                    f = faces[tris[t]]
                    if _shares(p, f) or gap2(v_lo[q], v_hi[q], t_lo[t], t_hi[t]) > r2:
                        continue
                    if not owns(v_lo[q], t_lo[t], r, a, b, c, origin, cell, dims):
                        continue
                    if check:
                        u, v, w = closest_barycentric(x[p], x[f[0]], x[f[1]], x[f[2]])
                        d2 = 0.0
                        for e in range(3):
                            g = x[p, e] - (u * x[f[0], e] + v * x[f[1], e] + w * x[f[2], e])
                            d2 += g * g
                        reach = r + max(_apart(motion, p, f[0]), _apart(motion, p, f[1]), _apart(motion, p, f[2]))
                        if d2 > reach * reach:
                            continue
                    if fill:
                        out_v[start + found] = p
                        out_t[start + found] = tris[t]
                        out_near[start + found] = (_neighbours(ring_ptr, ring_idx, p, f[0])
                                                   or _neighbours(ring_ptr, ring_idx, p, f[1])
                                                   or _neighbours(ring_ptr, ring_idx, p, f[2]))
                    found += 1
    return found


@njit(cache=True, parallel=True)
def _vt_pairs(verts, v_lo, v_hi, tris, faces, t_lo, t_hi, x, motion, check, origin, cell, dims, r, ring_ptr, ring_idx):
    """Counted by boxes, written with the distance ``check``, then packed (each distance computed once)."""
    ptr, items = bin_boxes(t_lo, t_hi, origin, cell, dims)
    counts = np.zeros(len(verts), np.int64)
    dummy = np.zeros(0, np.int64)
    no = np.zeros(0, np.bool_)
    for q in prange(len(verts)):
        counts[q] = _vt_one(q, False, dummy, dummy, no, 0, ring_ptr, ring_idx, verts, v_lo, v_hi, t_lo, t_hi, tris, faces, x, motion,
                            False, ptr, items, origin, cell, dims, r)
    starts = np.zeros(len(verts) + 1, np.int64)
    starts[1:] = np.cumsum(counts)
    out_v = np.empty(starts[-1], np.int64)
    out_t = np.empty(starts[-1], np.int64)
    out_near = np.empty(starts[-1], np.bool_)
    for q in prange(len(verts)):
        counts[q] = _vt_one(q, True, out_v, out_t, out_near, starts[q], ring_ptr, ring_idx, verts, v_lo, v_hi, t_lo, t_hi, tris, faces, x,
                            motion, check, ptr, items, origin, cell, dims, r)
    keep = _packed(starts, counts)
    return out_v[keep], out_t[keep], out_near[keep]


def vertex_triangle_pairs(verts, tris, faces, lo, hi, x, radius: float, cell: float, ring, *, exact: bool, xp=None):
    """(vertex, triangle, near) of the pairs, grouped by vertex in the order of ``verts``: each of
    ``verts`` against each of the triangles ``tris`` (rows of ``faces``) not at it whose boxes come
    within ``radius``; ``near``: whether a corner of the triangle is a neighbour of the vertex
    (``ring`` = (ptr, idx): each vertex's neighbours, CSR: :func:`vertex_rings`).

    ``lo``/``hi`` (N, 3) are boxes round every vertex (its motion over a step from ``xp`` to ``x``;
    both ``x`` for points). Given ``xp``, the triangle at ``x`` must also come within ``radius`` of the
    vertex plus the most the vertex moved relative to any of its corners (a pair left out is farther
    than ``radius`` apart all along the step's straight-line motion); with ``exact`` (points), within
    ``radius``.
    """
    verts = np.ascontiguousarray(verts, np.int64)
    tris = np.ascontiguousarray(tris, np.int64)
    if not len(verts) or not len(tris):
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, bool)
    corners_lo, corners_hi = lo[faces[tris]], hi[faces[tris]]
    t_lo, t_hi = np.ascontiguousarray(corners_lo.min(axis=1)), np.ascontiguousarray(corners_hi.max(axis=1))
    v_lo, v_hi = np.ascontiguousarray(lo[verts]), np.ascontiguousarray(hi[verts])
    grid = Grid(np.vstack([t_lo, v_lo - radius]), np.vstack([t_hi, v_hi + radius]), cell)
    motion = np.zeros((len(x), 3)) if exact or xp is None else np.ascontiguousarray(x - xp, np.float64)
    return _vt_pairs(verts, v_lo, v_hi, tris, faces, t_lo, t_hi, np.ascontiguousarray(x, np.float64), motion,
                     bool(exact or xp is not None), grid.origin, grid.cell, grid.dims, float(radius), *ring)


@njit(cache=True, inline="always")
def _apart(d, i, j):
    """|d[i] − d[j]|: how much closer two points can have come over a step that moved them by ``d``."""
    g = 0.0
    for k in range(3):
        h = d[i, k] - d[j, k]
        g += h * h
    return math.sqrt(g)


@njit(cache=True, inline="always")
def _segment_distance2(x, a0, a1, b0, b1):
    """Squared distance between the segments a0–a1 and b0–b1 (rows of ``x``)."""
    d1 = (x[a1, 0] - x[a0, 0], x[a1, 1] - x[a0, 1], x[a1, 2] - x[a0, 2])
    d2 = (x[b1, 0] - x[b0, 0], x[b1, 1] - x[b0, 1], x[b1, 2] - x[b0, 2])
    r = (x[a0, 0] - x[b0, 0], x[a0, 1] - x[b0, 1], x[a0, 2] - x[b0, 2])
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    f = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2]
    c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2]
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    den = a * e - b * b
    s = min(max((b * f - c * e) / den, 0.0), 1.0) if den > 1e-30 and a > 1e-30 else 0.0
    t = (b * s + f) / e if e > 1e-30 else 0.0
    if t < 0.0 or t > 1.0:  # clamp t, then s again for the clamped t
        t = min(max(t, 0.0), 1.0)
        s = min(max((t * b - c) / a, 0.0), 1.0) if a > 1e-30 else 0.0
    g = 0.0
    for k in range(3):
        h = r[k] + s * d1[k] - t * d2[k]
        g += h * h
    return g


@njit(cache=True)
def _ee_one(q, fill, out, out_near, start, ring_ptr, ring_idx, ids, edges, e_lo, e_hi, x, motion, check, ptr, items, origin,
            cell, dims, r):
    """Count (``fill`` False) or write the edges after active edge ``q`` within ``r`` of it, sharing no end
    (the segments at ``x`` closer than ``r`` plus how far their ends moved relative to each other:
    ``motion`` (N, 3) per vertex over the step)."""
    a0, a1 = edges[ids[q], 0], edges[ids[q], 1]
    found = 0
    r2 = r * r
    i0, j0, k0, i1, j1, k1 = cell_span(e_lo[q], e_hi[q], r, origin, cell, dims)
    for c in range(k0, k1 + 1):
        for b in range(j0, j1 + 1):
            for a in range(i0, i1 + 1):
                key = a + dims[0] * (b + dims[1] * c)
                for m in range(ptr[key], ptr[key + 1]):
                    s = items[m]
                    if s <= q:
                        continue
                    b0, b1 = edges[ids[s], 0], edges[ids[s], 1]
                    if a0 == b0 or a0 == b1 or a1 == b0 or a1 == b1:
                        continue
                    if gap2(e_lo[q], e_hi[q], e_lo[s], e_hi[s]) > r2:
                        continue
                    if not owns(e_lo[q], e_lo[s], r, a, b, c, origin, cell, dims):
                        continue
                    if check:
                        reach = r + max(_apart(motion, a0, b0), _apart(motion, a0, b1), _apart(motion, a1, b0),
                                        _apart(motion, a1, b1))
                        if _segment_distance2(x, a0, a1, b0, b1) > reach * reach:
                            continue
                    if fill:
                        out[start + found, 0] = a0
                        out[start + found, 1] = a1
                        out[start + found, 2] = b0
                        out[start + found, 3] = b1
                        out_near[start + found] = (_neighbours(ring_ptr, ring_idx, a0, b0)
                                                   or _neighbours(ring_ptr, ring_idx, a0, b1)
                                                   or _neighbours(ring_ptr, ring_idx, a1, b0)
                                                   or _neighbours(ring_ptr, ring_idx, a1, b1))
                    found += 1
    return found


@njit(cache=True, parallel=True)
def _ee_pairs(ids, edges, e_lo, e_hi, x, motion, check, origin, cell, dims, r, ring_ptr, ring_idx):
    """Counted by boxes, written with the distance ``check``, then packed (each distance computed once)."""
    ptr, items = bin_boxes(e_lo, e_hi, origin, cell, dims)
    counts = np.zeros(len(ids), np.int64)
    dummy = np.zeros((0, 4), np.int64)
    no = np.zeros(0, np.bool_)
    for q in prange(len(ids)):
        counts[q] = _ee_one(q, False, dummy, no, 0, ring_ptr, ring_idx, ids, edges, e_lo, e_hi, x, motion, False, ptr, items,
                            origin, cell, dims, r)
    starts = np.zeros(len(ids) + 1, np.int64)
    starts[1:] = np.cumsum(counts)
    out = np.empty((starts[-1], 4), np.int64)
    out_near = np.empty(starts[-1], np.bool_)
    for q in prange(len(ids)):
        counts[q] = _ee_one(q, True, out, out_near, starts[q], ring_ptr, ring_idx, ids, edges, e_lo, e_hi, x, motion, check, ptr,
                            items, origin, cell, dims, r)
    keep = _packed(starts, counts)
    return out[keep], out_near[keep]


@njit(cache=True)
def _packed(starts, counts):
    """The slots in use when each query ``q`` filled the first ``counts[q]`` of its ``starts[q]``… range."""
    out = np.empty(counts.sum(), np.int64)
    at = 0
    for q in range(len(counts)):
        for k in range(starts[q], starts[q] + counts[q]):
            out[at] = k
            at += 1
    return out


def edge_edge_pairs(ids, edges, lo, hi, radius: float, cell: float, ring, x=None, xp=None):
    """((E, 4) end vertices, (E,) near) of the pairs among the edges ``ids`` (rows of ``edges``) that
    share no end and come within ``radius`` of each other, each pair once; ``near``: whether an end
    of one is a neighbour of an end of the other (``ring`` as in :func:`vertex_triangle_pairs`).

    ``lo``/``hi`` (N, 3) are boxes round every vertex: where it is over a step, from where it was
    (``xp``; points at ``x`` without it) to ``x``. Given ``x``, a pair is also kept only when the
    segments at ``x`` are closer than ``radius`` plus the most any end of one moved relative to any
    end of the other (a point of either moves as a mean of its ends): a pair left out is farther
    than ``radius`` apart all along the step's straight-line motion. Without ``x``, boxes alone."""
    ids = np.ascontiguousarray(ids, np.int64)
    if len(ids) < 2:
        return np.zeros((0, 4), np.int64), np.zeros(0, bool)
    ends = edges[ids]
    e_lo = np.ascontiguousarray(np.minimum(lo[ends[:, 0]], lo[ends[:, 1]]))
    e_hi = np.ascontiguousarray(np.maximum(hi[ends[:, 0]], hi[ends[:, 1]]))
    grid = Grid(e_lo - radius, e_hi + radius, cell)
    check = x is not None
    x = np.ascontiguousarray(lo if x is None else x, np.float64)
    motion = np.zeros_like(x) if xp is None else np.ascontiguousarray(x - xp, np.float64)
    return _ee_pairs(ids, np.ascontiguousarray(edges, np.int64), e_lo, e_hi, x, motion, check, grid.origin, grid.cell,
                     grid.dims, float(radius), *ring)
