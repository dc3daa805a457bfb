"""Cloth already through cloth, pushed back: a local untangling of edge–triangle crossings.

The self-collision response (Carignan Eq. 5–8) keeps cloth from crossing itself by judging each
pair by the side it was on at the last step; a crossing that arrives anyway (seams merged round
an armhole corner, a vertex squeezed through by two seams at once) is then kept, step after step,
because its history says it belongs there. Here every crossing the independent check
(:func:`~tailor.collide.crossings.edge_crossings`) finds is undone from the geometry alone, in the
spirit of Baraff, Witkin & Kass (2003, "Untangling cloth") but locally: the crossing edge's surface
lies on the side of the triangle's plane where the neighbourhoods of its two ends (their 1-rings,
less the edge and the triangle) lie together; the end on the other side poked through. That end
and the triangle are moved apart along the triangle's normal until the end is ``thickness`` on its
surface's side, in proportion to their inverse masses (pinned and attached vertices, inverse mass
0, do not move), never by more than half the crossing edge. When such a round makes no progress
(a pinned sheet's edges through a free one, whose sides their joint neighbourhood cannot tell),
only the clear pokes are pushed: an end whose own 1-ring lies on the other side, the other end's
not. Moves are averaged per vertex (Jacobi) and the check runs again, a few rounds at most; a
round that does not lower the number of crossings is undone and ends the call, so untangling never
makes a tangle worse (a knot these local moves cannot undo stays). Velocities are left alone: the
next self-collision pass, told the new positions, takes them as the sides to keep.

What the local pushes leave is then looked at globally, as Baraff, Witkin & Kass's global
intersection analysis does: the crossing edges are where the intersection contour cuts the
cloth, so with them removed from the mesh's edge graph, a closed contour cuts off a region of
vertices from the rest of its piece (a pocket of cloth pushed through a sheet, many vertices
deep, of which only the rim touches a crossing). The region lies on the wrong side: the crossed
triangles' normals, each oriented towards the side the crossing edge's outer end is on, average
to the way back, and every region vertex short of ``thickness`` past the crossed triangles'
mean centre along it is moved there (:func:`_region_moves`). Regions are tried smallest first, each kept only
when it lowers the number of crossings; a region holding more than :data:`MAX_REGION` of its
piece is never moved (a sheet cut in two by another has no wrong side to tell).
"""

from __future__ import annotations

from functools import partial

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .crossings import edge_crossings
from .grid import unique_edges, vertex_rings

__all__ = ["untangle", "cut_regions", "vertex_rings", "UNTANGLE_ROUNDS", "MAX_REGION"]

UNTANGLE_ROUNDS = 4
"""Rounds of check and push per call: a poke-through takes one, a fold crossed over two or three."""

GLOBAL_PASSES = 3
"""Local rounds and region moves alternate at most this often per call (each region moved lets the
local pushes finish its rim)."""

MAX_REGION = 0.25
"""Largest share of its piece's vertices a region cut off by crossings may hold to be moved back."""


def _ring_sums(x, rings, ends, other, tri, point, normal):
    """Per crossing, the summed signed distance from the triangle's plane of the 1-ring of ``ends``
    (the edge's other end and the triangle's corners left out)."""
    ptr, idx = rings
    deg = ptr[ends + 1] - ptr[ends]
    rows = np.repeat(np.arange(len(ends)), deg)
    nb = idx[np.repeat(ptr[ends], deg) + np.arange(int(deg.sum())) - np.repeat(np.cumsum(deg) - deg, deg)]
    keep = (nb != other[rows]) & (nb != tri[rows, 0]) & (nb != tri[rows, 1]) & (nb != tri[rows, 2])
    d = np.einsum("ij,ij->i", x[nb] - point[rows], normal[rows]) * keep
    return np.bincount(rows, d, minlength=len(ends))


def _push(x, inv_mass, faces, crossings, rings, thickness, joint):
    """One Jacobi round: each crossing's poking end and its triangle moved apart (module docstring)."""
    i, j, t = crossings.T
    tri = faces[t]
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    normal = np.cross(b - a, c - a)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    point = (a + b + c) / 3.0
    s_i = np.einsum("ij,ij->i", x[i] - point, normal)
    s_j = np.einsum("ij,ij->i", x[j] - point, normal)
    # an end poked through when its own neighbourhood lies on the other side of the plane; where
    # both or neither do, the crossing is no poke (two sheets cut through each other) and waits,
    # unless ``joint``: then the end on the other side from both ends' neighbourhoods together
    ring_i = _ring_sums(x, rings, i, j, tri, point, normal)
    ring_j = _ring_sums(x, rings, j, i, tri, point, normal)
    if joint:
        side = np.sign(ring_i + ring_j)
        side = np.where(side == 0, np.where(s_i + s_j >= 0, 1.0, -1.0), side)
        alone_i = np.sign(s_i) != side
        poke = np.ones(len(i), bool)
    else:
        alone_i = np.sign(ring_i) == -np.sign(s_i)
        poke = alone_i != (np.sign(ring_j) == -np.sign(s_j))
    i, j, tri, normal, s_i, s_j, alone_i = i[poke], j[poke], tri[poke], normal[poke], s_i[poke], s_j[poke], alone_i[poke]
    k = np.where(alone_i, i, j)
    s_k = np.where(alone_i, s_i, s_j)
    depth = -np.sign(s_k) * thickness - s_k  # along the normal: the end to ``thickness`` on its ring's side
    reach = 0.5 * np.linalg.norm(x[i] - x[j], axis=1)  # a push never carries a vertex past half its edge
    depth = np.clip(depth, -reach, reach)
    im_k, im_t = inv_mass[k], inv_mass[tri].mean(axis=1)
    total = im_k + im_t
    share = np.divide(im_k, total, out=np.zeros_like(total), where=total > 0)
    move = np.zeros_like(x)
    count = np.zeros(len(x))
    np.add.at(move, k, (share * depth)[:, None] * normal)
    np.add.at(count, k, 1.0)
    back = np.where(total > 0, (1.0 - share) * depth, 0.0)
    for corner in range(3):
        np.add.at(move, tri[:, corner], -back[:, None] * normal * (inv_mass[tri[:, corner]] > 0)[:, None])
        np.add.at(count, tri[:, corner], 1.0)
    x += move / np.maximum(count, 1.0)[:, None]


def _components(n: int, edges) -> np.ndarray:
    """Connected-component label of each of ``n`` vertices joined by ``edges`` (E, 2)."""
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def cut_regions(n: int, faces, crossings) -> list:
    """Vertex ids of each region the ``crossings`` (K, 3: edge ends, triangle) cut off from its piece
    of the mesh ``faces`` over ``n`` vertices, smallest first: the components of the edge graph less
    the crossing edges, bar each piece's largest, holding at most :data:`MAX_REGION` of the piece."""
    edges = unique_edges(faces, n)
    cut = np.unique(np.sort(np.asarray(crossings, np.int64)[:, :2], axis=1), axis=0)
    keep = ~np.isin(edges[:, 0] * n + edges[:, 1], cut[:, 0] * n + cut[:, 1])
    piece, part = _components(n, edges), _components(n, edges[keep])
    piece_size = np.bincount(piece)
    part_size = np.bincount(part)
    part_piece = np.zeros(len(part_size), np.int64)
    part_piece[part] = piece
    biggest = np.zeros(len(piece_size), np.int64)
    np.maximum.at(biggest, part_piece, part_size)
    small = (part_size <= MAX_REGION * piece_size[part_piece]) & (part_size < biggest[part_piece])
    regions = [np.flatnonzero(part == p) for p in np.flatnonzero(small)]
    return sorted(regions, key=len)


def _region_moves(x, faces, region, crossings, thickness: float):
    """(N, 3) moves taking a cut-off ``region`` back through the cloth it crossed (module docstring),
    or None when no crossing bounds it."""
    inside = np.zeros(len(x), bool)
    inside[region] = True
    i, j, t = np.asarray(crossings, np.int64).T
    rim = inside[i] != inside[j]
    if not rim.any():
        return None
    out = np.where(inside[i], j, i)[rim]
    tri = x[faces[t[rim]]]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    point = tri.mean(axis=1)
    normal *= np.where(np.einsum("ij,ij->i", x[out] - point, normal) >= 0.0, 1.0, -1.0)[:, None]
    way = normal.sum(axis=0)
    if not np.linalg.norm(way):
        return None
    way /= np.linalg.norm(way)
    lo = float((point @ way).mean())  # about where the crossed cloth lies
    depth = np.maximum(lo + thickness - x[region] @ way, 0.0)
    moves = np.zeros_like(x)
    moves[region] = depth[:, None] * way
    return moves


def _untangle_regions(x, faces, inv_mass, thickness: float, crossings, find):
    """The regions the ``crossings`` cut off moved back, in place, each kept only when the crossings
    drop; the crossings left."""
    for region in cut_regions(len(x), faces, crossings):
        region = region[inv_mass[region] > 0]
        moves = _region_moves(x, faces, region, crossings, thickness) if len(region) else None
        if moves is None:
            continue
        after = find(x + moves)
        if len(after) < len(crossings):
            x += moves
            crossings = after
        if not len(crossings):
            break
    return crossings


class _Borders:
    """The mesh's border edges (those of one face): per face which of its edges is one, per border
    edge its face's third vertex (the side the cloth lies on)."""

    def __init__(self, faces, n: int):
        self.n = n
        keys = np.stack([_key(faces[:, k], faces[:, (k + 1) % 3], n) for k in range(3)], axis=1)
        distinct, count = np.unique(keys, return_counts=True)
        self.border = distinct[count == 1]
        self.face_border = np.isin(keys, self.border)  # (F, 3): edge k of face f (corners k, k + 1) is a border edge
        f, k = np.nonzero(self.face_border)
        self.border_third = faces[f, (k + 2) % 3][np.argsort(keys[f, k])]  # aligned with the sorted ``border``

    def third(self, i, j):
        """(K,) the third vertex of the face of each edge (i, j), or −1 where it is no border edge."""
        key = _key(i, j, self.n)
        if not len(self.border):
            return np.full(len(key), -1, np.int64)
        at = np.minimum(np.searchsorted(self.border, key), len(self.border) - 1)
        return np.where(self.border[at] == key, self.border_third[at], -1)


def _key(i, j, n):
    return np.minimum(i, j).astype(np.int64) * n + np.maximum(i, j)


def _beyond(x, a, b, third):
    """Unit directions in the plane of each edge a–b and its face's ``third`` vertex, perpendicular to
    the edge and pointing away from that vertex: out of the face, beyond the edge."""
    e = x[b] - x[a]
    e /= np.maximum(np.linalg.norm(e, axis=1, keepdims=True), 1e-300)
    w = x[a] - x[third]
    out = w - np.einsum("ij,ij->i", w, e)[:, None] * e
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-300)


def _border_slides(x, faces, inv_mass, thickness: float, crossings, borders: _Borders):
    """(N, 3) moves sliding cloth off a border it is hooked on, or None.

    A hook is two crossings at once: an edge through a triangle that has a border edge, and that
    border edge through a triangle at the first edge (a top tucked in a band, crossing the band just
    under its top edge while the band's top edge passes through the top). The edge's ends go over
    the border (the top goes over the band), and the triangles the border edge passes through slide
    off beyond it; never by more than the crossing edge (its triangle's longest edge), so a cut far
    from any border is no hook. Moves are averaged per vertex; pinned vertices stay."""
    i, j, t = np.asarray(crossings, np.int64).T
    tri = faces[t]
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    normal = np.cross(b - a, c - a)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    si, sj = np.einsum("ij,ij->i", x[i] - a, normal), np.einsum("ij,ij->i", x[j] - a, normal)
    pierce = x[i] + (si / np.where(si != sj, si - sj, 1.0))[:, None] * (x[j] - x[i])
    hooks = _hooks(i, j, t, faces, borders)
    move, count = np.zeros_like(x), np.zeros(len(x))

    def add(ids, shift, limit):
        free = (inv_mass[ids] > 0) & (np.linalg.norm(shift, axis=1) <= limit)
        np.add.at(move, ids[free], shift[free])
        np.add.at(count, ids[free], 1.0)

    for k in range(3):  # the crossed triangle's border edge k (corners k, k + 1) in a hook: the edge goes over it
        rows = np.flatnonzero(hooks[:, k])
        p, q, r = tri[rows, k], tri[rows, (k + 1) % 3], tri[rows, (k + 2) % 3]
        way = _beyond(x, p, q, r)
        shift = (np.einsum("ij,ij->i", x[p] - pierce[rows], way) + thickness)[:, None] * way
        limit = np.linalg.norm(x[i[rows]] - x[j[rows]], axis=1)
        for end in (i[rows], j[rows]):
            add(end, shift, limit)
    rows = np.flatnonzero(hooks[:, 3])  # the crossing edge a border in a hook: the triangle slides off beyond it
    w = borders.third(i[rows], j[rows])
    out = _beyond(x, i[rows], j[rows], w)
    h = np.max(np.einsum("ikj,ij->ik", pierce[rows, None] - x[tri[rows]], out), axis=1) + thickness
    limit = np.linalg.norm(x[tri[rows]] - x[np.roll(tri[rows], 1, axis=1)], axis=2).max(axis=1)
    for corner in range(3):
        add(tri[rows, corner], h[:, None] * out, limit)
    if not count.any():
        return None
    return move / np.maximum(count, 1.0)[:, None]


def _hooks(i, j, t, faces, borders: _Borders):
    """(K, 4) bool per crossing (edge i–j through triangle t): column k < 3, the triangle's edge k
    (corners k, k + 1) is a border edge passing through a triangle at i or j; column 3, the edge i–j
    is a border edge and an edge of the triangle passes through the border's face (at i and j).
    Crossings are few when this is asked (the local and region moves are stuck): a loop."""
    through = {}  # edge key → the corner sets of the triangles it passes through
    for key, tr in zip(_key(i, j, borders.n).tolist(), t.tolist()):
        through.setdefault(key, []).append(set(faces[tr].tolist()))
    out = np.zeros((len(i), 4), bool)
    lone = borders.face_border[t]
    sides = np.stack([_key(faces[t, k], faces[t, (k + 1) % 3], borders.n) for k in range(3)], axis=1).tolist()
    for r, (a, b, keys) in enumerate(zip(i.tolist(), j.tolist(), sides)):
        for k in range(3):
            out[r, k] = lone[r, k] and any(a in c or b in c for c in through.get(keys[k], ()))
        out[r, 3] = any(a in c and b in c for key in keys for c in through.get(key, ()))
    out[:, 3] &= borders.third(i, j) >= 0
    return out


def _slide_borders(x, faces, inv_mass, thickness: float, crossings, find, borders):
    """:func:`_border_slides` applied in place when it lowers the crossings; the crossings left."""
    moves = _border_slides(x, faces, inv_mass, thickness, crossings, borders)
    if moves is None:
        return crossings
    after = find(x + moves)
    if len(after) < len(crossings):
        x += moves
        return after
    return crossings


def _local_rounds(x, faces, inv_mass, thickness: float, crossings, rings, find, rounds: int):
    """Up to ``rounds`` rounds of local pushes, in place, each kept only when the crossings drop;
    the crossings left."""
    for _ in range(rounds):
        if not len(crossings):
            break
        for joint in (True, False):  # every crossing by both ends' side; only the clear pokes when that is stuck
            y = x.copy()
            _push(y, inv_mass, faces, crossings, rings, thickness, joint)
            after = find(y)
            if len(after) < len(crossings):
                break
        if len(after) >= len(crossings):  # a tangle these local pushes make no better: left as it is
            break
        x[:] = y
        crossings = after
    return crossings


def untangle(x, faces, inv_mass, thickness: float, *, rounds: int = UNTANGLE_ROUNDS, rings=None, edges=None, still=None):
    """Push apart, in place, the edges of ``faces`` that pass through their own triangles at ``x``:
    rounds of local pushes, then the regions cut off by what is left moved back, and again while
    that helps (at most :data:`GLOBAL_PASSES` times).

    ``inv_mass`` (N,) is 1/m per vertex (0: pinned or attached). Returns (crossings found, crossings
    left): both from :func:`~tailor.collide.crossings.edge_crossings`, before the first and after the
    last round; with ``still`` ((N,) bool: vertices held still), not those among still vertices alone.
    """
    faces = np.asarray(faces, np.int64)
    inv_mass = np.asarray(inv_mass, float)
    rings = vertex_rings(faces, len(x)) if rings is None else rings
    edges = unique_edges(faces, len(x)) if edges is None else edges
    find = partial(_crossings_at, faces=faces, edges=edges, still=still)
    crossings = find(x)
    found = len(crossings)
    borders = None  # found only when the local and region moves are stuck
    for _ in range(GLOBAL_PASSES):
        crossings = _local_rounds(x, faces, inv_mass, thickness, crossings, rings, find, rounds)
        if not len(crossings):
            break
        before = len(crossings)
        crossings = _untangle_regions(x, faces, inv_mass, thickness, crossings, find)
        if len(crossings) == before:
            borders = _Borders(faces, len(x)) if borders is None else borders
            crossings = _slide_borders(x, faces, inv_mass, thickness, crossings, find, borders)
        if len(crossings) == before:
            break
    return found, len(crossings)


def _crossings_at(x, *, faces, edges, still):
    """The crossings at positions ``x`` (:func:`~tailor.collide.crossings.edge_crossings`)."""
    return edge_crossings(x, faces, edges, still)
