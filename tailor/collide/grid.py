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

from .bounds import axis_bounds
from .closest import closest_barycentric
from .patch_pairs import NO_PATCH_PAIRS, edge_edge_passes, vertex_triangle_passes

__all__ = ["overlapping_boxes", "vertex_rings", "Grid", "bin_boxes", "cell_of", "cell_span", "gap2", "owns", "vertex_triangle_pairs", "edge_edge_pairs", "element_pads", "MAX_CELLS", "PairRoom"]

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


_GUESS_CHUNK = 256
"""Queries (vertices, edges) a chunk of the one-pass searches takes in turn (:func:`_vt_pairs`, :func:`_ee_pairs_guessed`)."""

_GUESS_PAIRS = 32
"""Pairs per query a chunk of :func:`_ee_pairs_guessed` has room for without a :class:`PairRoom`, and
the most a :class:`PairRoom` gives: a cloth edge meets about 8 in one garment, 13-14 where an
outfit's layers overlap (a chunk over its room is searched twice)."""

_GUESS_TRIANGLES = _GUESS_PAIRS
"""Triangles per vertex a chunk of :func:`_vt_pairs` has room for without a :class:`PairRoom`."""

ROOM_LEAST, ROOM_SLACK = 16, 4
"""A query's room holds at least ROOM_LEAST pairs, and ROOM_SLACK beyond twice the pairs per query of
the search before (:class:`PairRoom`): on a walking T-shirt and an outfit, 0–4 % of the chunks then
overflow (a chunk's densest queries find up to 33 edge pairs, the mean 3–13)."""


class PairRoom:
    """How many pairs a query's chunk makes room for in a search repeated step after step
    (:func:`vertex_triangle_pairs`, :func:`edge_edge_pairs`): twice the pairs per query the last
    search found plus :data:`ROOM_SLACK`, at least :data:`ROOM_LEAST` (the first search's), at most
    ``most``. A chunk denser than its room is searched again, so a small guess costs time, never a
    pair; a large one costs memory (room for 32 edge pairs a query took 1 KB an edge, the largest
    transient of a drape)."""

    def __init__(self, most: int = _GUESS_PAIRS):
        self.most = int(most)
        self.per = min(ROOM_LEAST, self.most)

    def learn(self, pairs: int, queries: int) -> None:
        """The last search found ``pairs`` for ``queries`` queries."""
        if queries:
            self.per = min(self.most, max(ROOM_LEAST, 2 * pairs // queries + ROOM_SLACK))


@njit(cache=True)
def _chunk_room(n, per, width):
    """The chunks of ``n`` queries (:data:`_GUESS_CHUNK` each), a chunk's room (``per`` pairs a query),
    rows for every chunk's room (``width`` 32-bit ints each, and a bool; the pairs joined are
    64-bit), and each chunk's count of pairs."""
    chunks = (n + _GUESS_CHUNK - 1) // _GUESS_CHUNK
    room = _GUESS_CHUNK * per
    return chunks, room, np.empty((chunks * room, width), np.int32), np.empty(chunks * room, np.bool_), np.zeros(chunks, np.int64)


@njit(cache=True)
def _joined(out, out_near, used, room):
    """The pairs of each chunk (``used[k]`` rows of ``out`` from row ``k · room``) joined in order:
    (pairs, near, each chunk's first row). A chunk that overflowed its room is left unwritten there,
    for the caller to search again into its rows."""
    starts = np.zeros(len(used), np.int64)
    total = 0
    for ch in range(len(used)):
        starts[ch] = total
        total += used[ch]
    pairs = np.empty((total, out.shape[1]), np.int64)
    near = np.empty(total, np.bool_)
    for ch in range(len(used)):
        if used[ch] <= room:
            pairs[starts[ch]:starts[ch] + used[ch]] = out[ch * room:ch * room + used[ch]]
            near[starts[ch]:starts[ch] + used[ch]] = out_near[ch * room:ch * room + used[ch]]
    return pairs, near, starts


@njit(cache=True)
def _vt_one(q, out, out_near, start, ring_ptr, ring_idx, verts, v_lo, v_hi, t_lo, t_hi, tris, faces, x, ptr, items, origin, cell, dims,
            r, v_pad, t_pad, pad_max, exact, patch_pairs, limit=-1):
    """Write (rows (vertex, triangle) of ``out`` from ``start``) and count the triangles within ``r``
    of active vertex ``q``, the two's pads (``v_pad[q]``, ``t_pad[t]``, at most ``pad_max``) added; with
    ``limit`` ≥ 0 none is written at or beyond it (they are still counted)."""
    p = verts[q]
    found = 0
    i0, j0, k0, i1, j1, k1 = cell_span(v_lo[q], v_hi[q], r + v_pad[q] + pad_max, origin, cell, dims)
    for c in range(k0, k1 + 1):
        for b in range(j0, j1 + 1):
            for a in range(i0, i1 + 1):
                key = a + dims[0] * (b + dims[1] * c)
                for m in range(ptr[key], ptr[key + 1]):
                    t = items[m]
                    f = faces[tris[t]]
                    rp = r + v_pad[q] + t_pad[t]
                    r2 = rp * rp
                    if _shares(p, f) or gap2(v_lo[q], v_hi[q], t_lo[t], t_hi[t]) > r2:
                        continue
                    if not owns(v_lo[q], t_lo[t], rp, a, b, c, origin, cell, dims):
                        continue
                    if not vertex_triangle_passes(patch_pairs, p, f, tris[t]):
                        continue
                    if exact:
                        u, v, w = closest_barycentric(x[p], x[f[0]], x[f[1]], x[f[2]])
                        d2 = 0.0
                        for e in range(3):
                            g = x[p, e] - (u * x[f[0], e] + v * x[f[1], e] + w * x[f[2], e])
                            d2 += g * g
                        if d2 > r2:
                            continue
                    if limit < 0 or start + found < limit:
                        out[start + found, 0] = p
                        out[start + found, 1] = tris[t]
                        out_near[start + found] = (_neighbours(ring_ptr, ring_idx, p, f[0])
                                                   or _neighbours(ring_ptr, ring_idx, p, f[1])
                                                   or _neighbours(ring_ptr, ring_idx, p, f[2]))
                    found += 1
    return found


@njit(cache=True, parallel=True)
def _vt_pairs(verts, v_lo, v_hi, tris, faces, t_lo, t_hi, x, origin, cell, dims, r, v_pad, t_pad, exact, ring_ptr, ring_idx, patch_pairs,
              per):
    """The triangles of every active vertex in one pass where they fit, ``per`` a vertex (as :func:`_ee_pairs_guessed`)."""
    ptr, items = bin_boxes(t_lo, t_hi, origin, cell, dims)
    pad_max = t_pad.max() if len(t_pad) else 0.0
    n = len(verts)
    chunks, room, out, out_near, used = _chunk_room(n, per, 2)
    for ch in prange(chunks):
        written = 0
        for q in range(ch * _GUESS_CHUNK, min(n, (ch + 1) * _GUESS_CHUNK)):
            written += _vt_one(q, out, out_near, ch * room + written, ring_ptr, ring_idx, verts, v_lo, v_hi, t_lo, t_hi, tris,
                               faces, x, ptr, items, origin, cell, dims, r, v_pad, t_pad, pad_max, exact, patch_pairs, (ch + 1) * room)
        used[ch] = written
    pairs, near, starts = _joined(out, out_near, used, room)
    for ch in range(chunks):
        if used[ch] > room:  # overflowed: written again, in full
            pos = starts[ch]
            for q in range(ch * _GUESS_CHUNK, min(n, (ch + 1) * _GUESS_CHUNK)):
                pos += _vt_one(q, pairs, near, pos, ring_ptr, ring_idx, verts, v_lo, v_hi, t_lo, t_hi, tris, faces, x, ptr, items,
                               origin, cell, dims, r, v_pad, t_pad, pad_max, exact, patch_pairs)
    return pairs, near


@njit(cache=True, parallel=True)
def _boxes_of(lo, hi, elements, rows):
    """(lo, hi) (K, 3) of the box round each element ``elements[rows[k]]`` (vertex indices: a face's
    three, an edge's two) from its vertices' boxes ``lo``/``hi``."""
    out_lo, out_hi = np.empty((len(rows), 3)), np.empty((len(rows), 3))
    for k in prange(len(rows)):
        e = elements[rows[k]]
        for a in range(3):
            out_lo[k, a], out_hi[k, a] = lo[e[0], a], hi[e[0], a]
            for m in range(1, len(e)):
                out_lo[k, a] = min(out_lo[k, a], lo[e[m], a])
                out_hi[k, a] = max(out_hi[k, a], hi[e[m], a])
    return out_lo, out_hi


def vertex_triangle_pairs(verts, tris, faces, lo, hi, x, radius: float, cell: float, ring, *, exact: bool,
                          patch_pairs=NO_PATCH_PAIRS, room: PairRoom | None = None, pad=None):
    """(vertex, triangle, near) of the pairs, grouped by vertex in the order of ``verts``: each of
    ``verts`` against each of the triangles ``tris`` (rows of ``faces``) not at it whose boxes come
    within ``radius``; ``near``: whether a corner of the triangle is a neighbour of the vertex
    (``ring`` = (ptr, idx): each vertex's neighbours, CSR: :func:`vertex_rings`).

    ``pad`` (N,), optional: each vertex's own reach beyond ``radius`` [m]; a pair then comes within
    ``radius`` plus the vertex's pad plus the largest of the triangle's corners' (:func:`element_pads`).

    ``lo``/``hi`` (N, 3) are boxes round every vertex (its motion over a step; both ``x`` for points).
    With ``exact`` the triangle itself must come within ``radius`` of the vertex at ``x``. Only the
    pairs ``patch_pairs`` lets through (:meth:`~tailor.collide.patch_pairs.PatchPairs.arrays`; default: all).
    ``room`` sizes the search's chunks and learns from it (default: :data:`_GUESS_TRIANGLES` a vertex).
    """
    verts = np.ascontiguousarray(verts, np.int64)
    tris = np.ascontiguousarray(tris, np.int64)
    if not len(verts) or not len(tris):
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, bool)
    lo, hi = np.ascontiguousarray(lo, np.float64), np.ascontiguousarray(hi, np.float64)
    faces = np.ascontiguousarray(faces, np.int64)
    t_lo, t_hi = _boxes_of(lo, hi, faces, tris)
    v_lo, v_hi = lo[verts], hi[verts]
    v_pad, t_pad = element_pads(pad, verts[:, None], len(verts)), element_pads(pad, faces[tris], len(tris))
    reach = radius + float(v_pad.max(initial=0.0)) + float(t_pad.max(initial=0.0))
    (t_min, _), (_, t_max) = axis_bounds(t_lo), axis_bounds(t_hi)
    (v_min, _), (_, v_max) = axis_bounds(v_lo), axis_bounds(v_hi)
    grid = Grid(np.vstack([t_min, v_min - reach]), np.vstack([t_max, v_max + reach]), cell)
    pairs, near = _vt_pairs(verts, v_lo, v_hi, tris, faces, t_lo, t_hi, np.ascontiguousarray(x, np.float64), grid.origin,
                            grid.cell, grid.dims, float(radius), v_pad, t_pad, bool(exact), *ring, patch_pairs,
                            _GUESS_TRIANGLES if room is None else room.per)
    if room is not None:
        room.learn(len(pairs), len(verts))
    return np.ascontiguousarray(pairs[:, 0]), np.ascontiguousarray(pairs[:, 1]), near


@njit(cache=True)
def _ee_one(q, fill, out, out_near, start, ring_ptr, ring_idx, ids, edges, e_lo, e_hi, dirty, ptr, items, origin, cell, dims, r,
            pad, pad_max, patch_pairs, limit=-1):
    """Count (``fill`` False) or write the edges within ``r`` of edge ``q``, the two's pads (``pad``,
    at most ``pad_max``) added, sharing no end: every clean one, and the dirty ones after it (each
    dirty pair once); with ``limit`` ≥ 0 none is written at or beyond it (they are still counted)."""
    a0, a1 = edges[ids[q], 0], edges[ids[q], 1]
    found = 0
    i0, j0, k0, i1, j1, k1 = cell_span(e_lo[q], e_hi[q], r + pad[q] + pad_max, origin, cell, dims)
    for c in range(k0, k1 + 1):
        for b in range(j0, j1 + 1):
            for a in range(i0, i1 + 1):
                key = a + dims[0] * (b + dims[1] * c)
                for m in range(ptr[key], ptr[key + 1]):
                    s = items[m]
                    if s == q or (dirty[s] and s < q):
                        continue
                    b0, b1 = edges[ids[s], 0], edges[ids[s], 1]
                    if a0 == b0 or a0 == b1 or a1 == b0 or a1 == b1:
                        continue
                    rp = r + pad[q] + pad[s]
                    if gap2(e_lo[q], e_hi[q], e_lo[s], e_hi[s]) > rp * rp:
                        continue
                    if not owns(e_lo[q], e_lo[s], rp, a, b, c, origin, cell, dims):
                        continue
                    if not edge_edge_passes(patch_pairs, ids[q], ids[s], a0, a1, b0, b1):
                        continue
                    if fill and (limit < 0 or start + found < limit):
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
def _ee_pairs_guessed(ids, edges, e_lo, e_hi, queries, dirty, origin, cell, dims, r, pad, ring_ptr, ring_idx, patch_pairs, per):
    """:func:`_ee_pairs` in one pass where it can: each chunk of :data:`_GUESS_CHUNK` queries writes
    into room for ``per`` pairs a query; the chunks' pairs are joined in order and only a chunk that
    overflowed is searched again, straight into its place (the same pairs, in the same order)."""
    ptr, items = bin_boxes(e_lo, e_hi, origin, cell, dims)
    pad_max = pad.max() if len(pad) else 0.0
    nq = len(queries)
    chunks, room, out, out_near, used = _chunk_room(nq, per, 4)
    for ch in prange(chunks):
        first, end = ch * room, (ch + 1) * room
        written = 0
        for k in range(ch * _GUESS_CHUNK, min(nq, (ch + 1) * _GUESS_CHUNK)):
            written += _ee_one(queries[k], True, out, out_near, first + written, ring_ptr, ring_idx, ids, edges, e_lo, e_hi,
                               dirty, ptr, items, origin, cell, dims, r, pad, pad_max, patch_pairs, end)
        used[ch] = written
    pairs, near, starts = _joined(out, out_near, used, room)
    for ch in range(chunks):
        if used[ch] > room:  # overflowed: written again, in full
            pos = starts[ch]
            for k in range(ch * _GUESS_CHUNK, min(nq, (ch + 1) * _GUESS_CHUNK)):
                pos += _ee_one(queries[k], True, pairs, near, pos, ring_ptr, ring_idx, ids, edges, e_lo, e_hi, dirty, ptr, items,
                               origin, cell, dims, r, pad, pad_max, patch_pairs)
    return pairs, near


@njit(cache=True, parallel=True)
def _ee_pairs(ids, edges, e_lo, e_hi, queries, dirty, origin, cell, dims, r, pad, ring_ptr, ring_idx, patch_pairs):
    """The edge pairs of every query, counted in one pass and written in a second: the reference
    :func:`_ee_pairs_guessed` is checked against (tests/test_grid.py)."""
    ptr, items = bin_boxes(e_lo, e_hi, origin, cell, dims)
    pad_max = pad.max() if len(pad) else 0.0
    counts = np.zeros(len(queries), np.int64)
    dummy = np.zeros((0, 4), np.int64)
    no = np.zeros(0, np.bool_)
    for k in prange(len(queries)):
        counts[k] = _ee_one(queries[k], False, dummy, no, 0, ring_ptr, ring_idx, ids, edges, e_lo, e_hi, dirty, ptr, items, origin,
                            cell, dims, r, pad, pad_max, patch_pairs)
    starts = np.zeros(len(queries) + 1, np.int64)
    starts[1:] = np.cumsum(counts)
    out = np.empty((starts[-1], 4), np.int64)
    out_near = np.empty(starts[-1], np.bool_)
    for k in prange(len(queries)):
        _ee_one(queries[k], True, out, out_near, starts[k], ring_ptr, ring_idx, ids, edges, e_lo, e_hi, dirty, ptr, items, origin,
                cell, dims, r, pad, pad_max, patch_pairs)
    return out, out_near


def element_pads(pad, elements, count: int) -> np.ndarray:
    """(count,) each element's pad: the largest of its vertices' (``elements`` (count, m) vertex
    indices); zeros without ``pad``. A pair of elements is searched within the radius plus both pads:
    an element whose every vertex is held still needs none of the reach its vertices' drift would."""
    if pad is None:
        return np.zeros(count)
    return np.ascontiguousarray(np.asarray(pad, np.float64)[elements].max(axis=1) if count else np.zeros(0))


def edge_edge_pairs(ids, edges, lo, hi, radius: float, cell: float, ring, *, dirty=None, patch_pairs=NO_PATCH_PAIRS,
                    room: PairRoom | None = None, pad=None):
    """((E, 4) end vertices, (E,) near) of the pairs among the edges ``ids`` (rows of ``edges``) that
    share no end and whose boxes (round their ends' boxes ``lo``/``hi``) come within ``radius``, each
    pair once; ``near``: whether an end of one is a neighbour of an end of the other (``ring`` as in
    :func:`vertex_triangle_pairs`). With ``dirty`` ((len(ids),) bool), only the pairs with at least
    one dirty edge (the others are known from an earlier query). Only the pairs ``patch_pairs`` lets
    through (as in :func:`vertex_triangle_pairs`; its edges are the rows of ``edges``); ``room`` and
    ``pad`` as there."""
    ids = np.ascontiguousarray(ids, np.int64)
    if len(ids) < 2:
        return np.zeros((0, 4), np.int64), np.zeros(0, bool)
    dirty = np.ones(len(ids), np.bool_) if dirty is None else np.ascontiguousarray(dirty, np.bool_)
    edges = np.ascontiguousarray(edges, np.int64)
    e_lo, e_hi = _boxes_of(np.ascontiguousarray(lo, np.float64), np.ascontiguousarray(hi, np.float64), edges, ids)
    e_pad = element_pads(pad, edges[ids], len(ids))
    reach = radius + 2.0 * float(e_pad.max())
    grid = Grid(axis_bounds(e_lo)[0][None] - reach, axis_bounds(e_hi)[1][None] + reach, cell)
    queries = np.flatnonzero(dirty).astype(np.int64)
    pairs, near = _ee_pairs_guessed(ids, edges, e_lo, e_hi, queries, dirty, grid.origin, grid.cell, grid.dims, float(radius), e_pad,
                                    *ring, patch_pairs, _GUESS_PAIRS if room is None else room.per)
    if room is not None:
        room.learn(len(pairs), len(queries))
    return pairs, near
