"""Cloth–body collision over FCL (python-fcl); :mod:`tailor.collide` is the only package that imports ``fcl``.

FCL builds a bounding-volume hierarchy (OBB-RSS) over a triangle mesh and answers proximity
and intersection queries between two such objects. Its PyPI build cannot refit a hierarchy, so
a moving mesh is rebuilt; callers should query with a margin and reuse candidates.
"""

from __future__ import annotations

import math

import fcl
import numpy as np
from numba import njit, prange

from ..errors import SimulationUnstable

__all__ = ["bvh_object", "boxes", "manager_contacts", "sphere_query", "clustered_query", "TriangleBoxes", "self_intersections", "points_inside", "InsideTest", "BodyCollider"]

_NO_CONTACTS = (np.zeros(0, np.intp), np.zeros((0, 3)), np.zeros(0), np.zeros(0, bool), np.zeros((0, 3)), np.zeros(0))


def bvh_object(vertices, faces):
    """An FCL collision object over a triangle mesh (identity transform)."""
    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def self_intersections(vertices, faces) -> np.ndarray:
    """Pairs of triangles of one mesh that intersect without sharing a vertex, shape (K, 2).

    FCL collides the mesh with itself. Neighbouring triangles always touch along their shared
    edges or corners, and python-fcl builds a Python object per touching pair (≈ 20 per
    triangle: 0.2 s a frame on an 1 800-triangle T-shirt, a quarter of its drape), so each triangle
    is first shrunk towards its centroid by a relative 1e-6: neighbours then part, crossing
    triangles still cross (missed only where the whole crossing lies within 1e-6 of an edge).
    Pairs that share a vertex (a fold laying a neighbour over it) are dropped. An empty result
    means the mesh does not pass through itself.
    """
    faces = np.asarray(faces)
    if not len(faces):
        return np.zeros((0, 2), np.intp)
    corners = np.asarray(vertices, dtype=np.float64)[faces]
    centre = corners.mean(axis=1, keepdims=True)
    soup = (centre + (1.0 - 1e-6) * (corners - centre)).reshape(-1, 3)
    obj = bvh_object(soup, np.arange(3 * len(faces)).reshape(-1, 3))
    request = fcl.CollisionRequest(num_max_contacts=100 * len(faces) + 1000, enable_contact=True)
    result = fcl.CollisionResult()
    fcl.collide(obj, obj, request, result)
    if not result.contacts:
        return np.zeros((0, 2), np.intp)
    pairs = np.unique(np.sort(np.array([(c.b1, c.b2) for c in result.contacts], dtype=np.intp), axis=1), axis=0)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    fa, fb = faces[pairs[:, 0]], faces[pairs[:, 1]]
    shared = (fa[:, :, None] == fb[:, None, :]).any(axis=(1, 2))
    return pairs[~shared]


def manager_contacts(geoms, transforms, target=None, *, limit: int):
    """Contacts of FCL objects ``geoms`` at ``transforms`` with ``target`` (or among themselves).

    ``target`` may be a collision object or another manager. Returns the contacts and a map
    ``id(geometry) → index`` of ``geoms``. Contacts are requested without
    geometry (``enable_contact=False``); python-fcl still builds one Python object per pair,
    which is the dominant cost (≈ 6 µs a pair here). FCL stops silently at ``num_max_contacts``,
    so a full answer is asked again with four times the room.
    """
    objs = [fcl.CollisionObject(g, t) for g, t in zip(geoms, transforms)]
    index = {id(g): i for i, g in enumerate(geoms)}
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(objs)
    manager.setup()
    while True:
        data = fcl.CollisionData(request=fcl.CollisionRequest(num_max_contacts=limit, enable_contact=False))
        if target is None:
            manager.collide(data, fcl.defaultCollisionCallback)
        else:
            manager.collide(target, data, fcl.defaultCollisionCallback)
        if len(data.result.contacts) < limit:
            return data.result.contacts, index
        limit *= 4


def sphere_query(points, radius, target, *, per_point: float = 64.0):
    """FCL broad phase: (point, triangle) index pairs of ``target``'s triangles within ``radius`` of each point."""
    contacts, index = manager_contacts([fcl.Sphere(radius) for _ in range(len(points))],
                                       [fcl.Transform(p) for p in points], target,
                                       limit=int(per_point * len(points)) + 1000)
    point, tri = [], []
    for contact in contacts:
        i = index.get(id(contact.o1))
        if i is None:
            point.append(index[id(contact.o2)])
            tri.append(contact.b1)
        else:
            point.append(i)
            tri.append(contact.b2)
    return np.asarray(point, np.int64), np.asarray(tri, np.int64)


def corner_bounds(corners):
    """(lo, hi) over axis 1 of ``corners`` (K, C, D): the boxes round triangles' (or edges') corners.

    Element-wise over the few corners: NumPy's ``min(axis=1)`` over a short middle axis took
    6.7 ms for the mannequin's 18 k triangles, this 0.9 ms (1.3 s of a walking T-shirt's drape)."""
    lo, hi = corners[:, 0].copy(), corners[:, 0].copy()
    for c in range(1, corners.shape[1]):
        np.minimum(lo, corners[:, c], out=lo)
        np.maximum(hi, corners[:, c], out=hi)
    return lo, hi


def run_starts(a):
    """Indices where a sorted 1-D array's runs of equal values begin."""
    return np.flatnonzero(np.r_[True, a[1:] != a[:-1]])


def _cluster(points, cell):
    """(order, ptr, lo, hi): points binned into cubes of side ``cell``, as CSR over the occupied cubes."""
    if not len(points):
        return np.zeros(0, np.intp), np.zeros(1, np.intp), np.zeros((0, 3)), np.zeros((0, 3))
    key = np.floor(points / cell).astype(np.int64)
    key -= key.min(axis=0)
    span = key.max(axis=0) + 1
    if float(span[0]) * float(span[1]) * float(span[2]) < 2.0**62:
        # one integer per cube, in the cubes' lexicographic order: a 1-D stable sort (np.unique over
        # rows sorts structured rows, 5 ms a call, a tenth of a walking T-shirt's drape)
        flat = (key[:, 0] * span[1] + key[:, 1]) * span[2] + key[:, 2]
        order = np.argsort(flat, kind="stable")
        flat = flat[order]
        ptr = np.append(run_starts(flat), len(flat))
    else:  # exploded coordinates: cube indices too far apart for one integer
        _, cluster, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        order = np.argsort(cluster.ravel(), kind="stable")
        ptr = np.concatenate([[0], np.cumsum(counts)])
    return order, ptr, np.minimum.reduceat(points[order], ptr[:-1], axis=0), np.maximum.reduceat(points[order], ptr[:-1], axis=0)


def boxes(lo, hi):
    """FCL box geometries [lo, hi] (rows of corners) and their transforms."""
    return ([fcl.Box(*np.maximum(h - l, 1e-9)) for l, h in zip(lo, hi)],
            [fcl.Transform(0.5 * (l + h)) for l, h in zip(lo, hi)])


BOX_CELL = 0.06
"""Side [m] of the cubes :func:`clustered_query` bins points and triangles into."""


class TriangleBoxes:
    """A triangle mesh's triangles binned by centroid into cubes of side ``cell``, one FCL box each.

    The target side of :func:`clustered_query`: per triangle its bounding box, per cube the box
    round its triangles, in an FCL dynamic AABB tree. Build one per body frame (or cloth state).
    With ``vertex_boxes`` (lo, hi), each (V, 3), a box per vertex (where it is over a step, say),
    each triangle's box is the one round its corners' boxes.
    """

    def __init__(self, vertices, faces, cell: float = 0.06, vertex_boxes=None):
        faces = np.asarray(faces, dtype=np.int64)
        corners = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64)[faces])
        self.corners = corners
        if vertex_boxes is None:
            self.lo, self.hi = corner_bounds(corners)
        else:
            self.lo, self.hi = corner_bounds(vertex_boxes[0][faces])[0], corner_bounds(vertex_boxes[1][faces])[1]
        self.swept = vertex_boxes is not None
        self.order, self.ptr = np.zeros(0, np.int64), np.zeros(1, np.int64)
        self.manager, self.index = None, {}
        if not len(corners):
            return
        order, self.ptr, _, _ = _cluster(corners.mean(axis=1), cell)
        self.order = order.astype(np.int64)
        geoms, transforms = boxes(np.minimum.reduceat(self.lo[self.order], self.ptr[:-1], axis=0),
                                  np.maximum.reduceat(self.hi[self.order], self.ptr[:-1], axis=0))
        self.manager = fcl.DynamicAABBTreeCollisionManager()
        self.manager.registerObjects([fcl.CollisionObject(g, t) for g, t in zip(geoms, transforms)])
        self.manager.setup()
        self.index = {id(g): i for i, g in enumerate(geoms)}

    def __len__(self):
        return len(self.lo)


def clustered_query(points, radius, target: TriangleBoxes, *, cell: float = 0.06, point_boxes=None):
    """(point, triangle) index pairs of ``target``'s triangles within ``radius`` of each point (FCL, by clusters).

    The FCL broad phase by clusters on both sides. python-fcl builds one Python object per
    contact pair (≈ 6 µs), and asking once per point against a triangle hierarchy
    (:func:`sphere_query`) pays for every (point, triangle) pair, though neighbouring points
    share most of their triangles (a 2 cm sphere round a cloth vertex meets ~23 triangles of the
    mannequin). Here the points are binned into cubes of side ``cell``; FCL's dynamic AABB trees
    collide the points' boxes grown by ``radius`` with ``target``'s boxes, and a compiled pass
    hands each triangle of a met box to the points of the other whose sphere meets the triangle
    itself: the same pairs as :func:`sphere_query` (2 894 points 5 mm off the mannequin within
    2 cm: 67.0 k pairs in 35–70 ms against 350 ms, and 25 ms to build the boxes against 58 ms
    for the hierarchy; 6 cm cubes).

    With ``point_boxes`` (lo, hi) round the points and a ``target`` built with vertex boxes (each
    box holding where its point or vertex is over a step): the pairs whose boxes come within
    ``radius`` — a superset of the pairs that come that near at any moment in them.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    if not len(points) or not len(target):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lo, hi = (points, points) if point_boxes is None else point_boxes
    p_order, p_ptr, _, _ = _cluster(points, cell)
    p_lo = np.minimum.reduceat(lo[p_order], p_ptr[:-1], axis=0)
    p_hi = np.maximum.reduceat(hi[p_order], p_ptr[:-1], axis=0)
    contacts, mine = manager_contacts(*boxes(p_lo - radius, p_hi + radius), target.manager, limit=64 * len(p_lo) + 1000)
    theirs = target.index
    pairs = np.empty((len(contacts), 2), np.int64)
    for k, c in enumerate(contacts):
        a = mine.get(id(c.o1))
        pairs[k] = (a, theirs[id(c.o2)]) if a is not None else (mine[id(c.o2)], theirs[id(c.o1)])
    exact = point_boxes is None and not target.swept
    return _expand_boxes(pairs, p_ptr, p_order.astype(np.int64), target.ptr, target.order, np.ascontiguousarray(lo),
                         np.ascontiguousarray(hi), target.lo, target.hi, target.corners, float(radius), exact)


@njit(cache=True)
def _expand_boxes(pairs, p_ptr, p_order, t_ptr, t_order, p_lo, p_hi, tri_lo, tri_hi, corners, radius, exact):
    """The (point, triangle) pairs of met clusters whose boxes come within ``radius``, and, if
    ``exact`` (points, not swept boxes), whose triangle itself does."""
    r2 = radius * radius
    count = 0
    out_p, out_t = np.empty(0, np.int64), np.empty(0, np.int64)
    for pas in range(2):
        if pas == 1:
            out_p, out_t = np.empty(count, np.int64), np.empty(count, np.int64)
            count = 0
        for k in range(len(pairs)):
            for m in range(t_ptr[pairs[k, 1]], t_ptr[pairs[k, 1] + 1]):
                t = t_order[m]
                for q in range(p_ptr[pairs[k, 0]], p_ptr[pairs[k, 0] + 1]):
                    p = p_order[q]
                    d2 = 0.0
                    for a in range(3):
                        g = max(tri_lo[t, a] - p_hi[p, a], 0.0, p_lo[p, a] - tri_hi[t, a])
                        d2 += g * g
                    if d2 > r2:  # the bounding boxes are out of reach: so is the triangle
                        continue
                    if exact:
                        a, b, c = corners[t, 0], corners[t, 1], corners[t, 2]
                        u, v, w = _closest_barycentric(p_lo[p], a, b, c)
                        d2 = 0.0
                        for e in range(3):
                            g = p_lo[p, e] - (u * a[e] + v * b[e] + w * c[e])
                            d2 += g * g
                        if d2 > r2:
                            continue
                    if pas == 1:
                        out_p[count], out_t[count] = p, t
                    count += 1
    return out_p, out_t


@njit(cache=True)
def _grid_triangles(xy_lo, xy_hi, origin, cell, nx, ny):
    """CSR over an (nx, ny) grid of the triangles whose xy bounding box touches each cell."""
    count = np.zeros(nx * ny + 1, np.int64)
    for t in range(len(xy_lo)):
        i0, i1 = int((xy_lo[t, 0] - origin[0]) / cell), int((xy_hi[t, 0] - origin[0]) / cell)
        j0, j1 = int((xy_lo[t, 1] - origin[1]) / cell), int((xy_hi[t, 1] - origin[1]) / cell)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                count[i * ny + j + 1] += 1
    ptr = np.cumsum(count)
    fill = ptr[:-1].copy()
    out = np.empty(ptr[-1], np.int64)
    for t in range(len(xy_lo)):
        i0, i1 = int((xy_lo[t, 0] - origin[0]) / cell), int((xy_hi[t, 0] - origin[0]) / cell)
        j0, j1 = int((xy_lo[t, 1] - origin[1]) / cell), int((xy_hi[t, 1] - origin[1]) / cell)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                out[fill[i * ny + j]] = t
                fill[i * ny + j] += 1
    return ptr, out


@njit(cache=True)
def _upward_crossings(p, vertices, faces, ptr, tri, origin, cell, nx, ny, out):
    for k in range(len(p)):
        i, j = int((p[k, 0] - origin[0]) / cell), int((p[k, 1] - origin[1]) / cell)
        if i < 0 or j < 0 or i >= nx or j >= ny:
            continue
        c = i * ny + j
        n = 0
        for m in range(ptr[c], ptr[c + 1]):
            t = tri[m]
            a, b, d = vertices[faces[t, 0]], vertices[faces[t, 1]], vertices[faces[t, 2]]
            # barycentric coordinates of p's xy in the triangle's xy projection
            det = (b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1])
            if det == 0.0:
                continue
            u = ((p[k, 0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (p[k, 1] - a[1])) / det
            v = ((b[0] - a[0]) * (p[k, 1] - a[1]) - (p[k, 0] - a[0]) * (b[1] - a[1])) / det
            if u < 0.0 or v < 0.0 or u + v > 1.0:
                continue
            if a[2] + u * (b[2] - a[2]) + v * (d[2] - a[2]) > p[k, 2]:
                n += 1
        out[k] = n % 2 == 1


def points_inside(points, vertices, faces, *, cell: float = 0.02) -> np.ndarray:
    """Whether each point lies inside a closed triangle surface, shape (N,) bool.

    Counts the crossings of a vertical ray from each point upwards (odd = inside), testing only
    the triangles binned to the point's cell of an xy grid. Exact for a watertight surface; the
    query is nudged by an irrational offset so rays do not run through edges or vertices. Asking
    often about one surface: :class:`InsideTest` bins it once.

    >>> import trimesh
    >>> box = trimesh.creation.box((1.0, 1.0, 1.0))
    >>> points_inside(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.7], [0.45, -0.3, 0.2]]), box.vertices, box.faces).tolist()
    [True, False, True]
    """
    return InsideTest(vertices, faces, cell=cell)(points)


class InsideTest:
    """:func:`points_inside` for one surface, its triangles binned once (placement asks ~100 times:
    binning the mannequin's 18 k triangles each time took 1 s of a T-shirt's drape)."""

    def __init__(self, vertices, faces, *, cell: float = 0.02):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self.cell = float(cell)
        corners = self.vertices[:, :2][self.faces]
        xy_lo, xy_hi = corner_bounds(corners)
        self.origin = xy_lo.min(axis=0) - cell
        self.nx, self.ny = (int((xy_hi.max(axis=0) - self.origin)[k] / cell) + 2 for k in range(2))
        self.ptr, self.tri = _grid_triangles(xy_lo, xy_hi, self.origin, self.cell, self.nx, self.ny)

    def __call__(self, points) -> np.ndarray:
        p = np.ascontiguousarray(points, dtype=np.float64) + np.array([1.2345e-9, 2.3456e-9, 0.0])
        out = np.zeros(len(p), np.bool_)
        _upward_crossings(p, self.vertices, self.faces, self.ptr, self.tri, self.origin, self.cell, self.nx, self.ny, out)
        return out


@njit(cache=True, inline="always")
def _dot3(x0, x1, x2, y0, y1, y2):
    return x0 * y0 + x1 * y1 + x2 * y2


@njit(cache=True)
def _closest_barycentric(p, a, b, c):
    """Barycentric coordinates (u, v, w) of the point of triangle abc closest to p (Ericson, RTCD 5.1.5).

    Scalar arithmetic throughout: no temporary arrays in the innermost loop of the narrow phase.
    """
    ab0, ab1, ab2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    ac0, ac1, ac2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    d1 = _dot3(ab0, ab1, ab2, p[0] - a[0], p[1] - a[1], p[2] - a[2])
    d2 = _dot3(ac0, ac1, ac2, p[0] - a[0], p[1] - a[1], p[2] - a[2])
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0  # vertex region a
    d3 = _dot3(ab0, ab1, ab2, p[0] - b[0], p[1] - b[1], p[2] - b[2])
    d4 = _dot3(ac0, ac1, ac2, p[0] - b[0], p[1] - b[1], p[2] - b[2])
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0  # vertex region b
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0  # edge ab
    d5 = _dot3(ab0, ab1, ab2, p[0] - c[0], p[1] - c[1], p[2] - c[2])
    d6 = _dot3(ac0, ac1, ac2, p[0] - c[0], p[1] - c[1], p[2] - c[2])
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0  # vertex region c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w  # edge ac
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w  # edge bc
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return 1.0 - v - w, v, w  # face


@njit(cache=True, inline="always")
def _gradient(a, b, c, d0, d1, d2, dist2):
    """(g0, g1, g2, cos) for a point at offset d from its closest point on triangle abc.

    g is the unsigned direction of the distance field's gradient: d/|d| off the surface (over an
    edge or a vertex, the same whichever face sharing it is asked), the face normal on it; cos is
    d/|d| · (the face normal), the face's own vote on which side the point lies.
    """
    e0, e1, e2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    f0, f1, f2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    n0, n1, n2 = e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0
    nl = max(math.sqrt(n0 * n0 + n1 * n1 + n2 * n2), 1e-300)
    n0, n1, n2 = n0 / nl, n1 / nl, n2 / nl
    dl = math.sqrt(dist2)
    if dl > 1e-9:
        g0, g1, g2 = d0 / dl, d1 / dl, d2 / dl
        return g0, g1, g2, g0 * n0 + g1 * n1 + g2 * n2
    return n0, n1, n2, 0.0


TIE = 1e-9
"""Relative difference of squared distances below which two body triangles are equally close."""


@njit(cache=True, parallel=True)
def _nearest(x, ptr, tri, bx, faces, out_dist, out_tri, out_bary, out_normal, rows):
    """Closest body triangle per point, its signed distance and the outward normal there.

    Over an edge or a vertex several triangles are equally close. The side is the vote of the one
    whose face normal is most nearly along the offset (the first one found decided before: a point
    outside a box's corner, level with one of its faces, read 15 mm *inside* from that face's zero
    vote and was thrown 15 mm off — the cube scene exploded at first contact). Equally close
    triangles with different closest points (a point inside a body, on the medial plane between two
    faces: a cloth dropped on a sphere's top, predicted a step ahead) average their directions, so
    the push does not depend on the order of the triangles (picking the first tilted a symmetric
    drop sideways, friction turned that into a drift of the patch). Only the points ``rows`` are
    looked at."""
    for j in prange(len(rows)):
        i = rows[j]
        best = 1e30
        out_tri[i] = -1
        a0 = a1 = a2 = 0.0
        vote = -1.0
        side = 1.0
        v0 = v1 = v2 = 0.0
        for k in range(ptr[i], ptr[i + 1]):
            t = tri[k]
            a, b, c = bx[faces[t, 0]], bx[faces[t, 1]], bx[faces[t, 2]]
            u, v, w = _closest_barycentric(x[i], a, b, c)
            d0 = x[i, 0] - (u * a[0] + v * b[0] + w * c[0])
            d1 = x[i, 1] - (u * a[1] + v * b[1] + w * c[1])
            d2 = x[i, 2] - (u * a[2] + v * b[2] + w * c[2])
            dist2 = d0 * d0 + d1 * d1 + d2 * d2
            if dist2 < best * (1.0 - TIE) - 1e-30:
                best = dist2
                a0, a1, a2, cs = _gradient(a, b, c, d0, d1, d2, dist2)
                vote, side = abs(cs), (1.0 if cs >= 0.0 else -1.0)
                v0, v1, v2 = a0, a1, a2
                out_tri[i] = t
                out_bary[i, 0], out_bary[i, 1], out_bary[i, 2] = u, v, w
            elif dist2 <= best * (1.0 + TIE) + 1e-30:
                g0, g1, g2, cs = _gradient(a, b, c, d0, d1, d2, dist2)
                a0, a1, a2 = a0 + g0, a1 + g1, a2 + g2
                if abs(cs) > vote:
                    vote, side = abs(cs), (1.0 if cs >= 0.0 else -1.0)
                    v0, v1, v2 = g0, g1, g2
        if out_tri[i] < 0:
            continue
        dl = math.sqrt(best)
        out_dist[i] = side * dl if dl > 1e-12 else 0.0
        al = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if al < 1e-6:  # opposite directions cancelled (a thin sheet's medial plane): the decisive one's
            a0, a1, a2, al = v0, v1, v2, 1.0
        out_normal[i, 0], out_normal[i, 1], out_normal[i, 2] = side * a0 / al, side * a1 / al, side * a2 / al


class BodyCollider:
    """Cloth–body contact (Carignan Eq. 9–14) with FCL as the broad phase.

    FCL finds the body triangles within ``margin`` of every cloth vertex, by clusters: boxes
    round nearby cloth vertices against boxes round nearby body triangles
    (:func:`clustered_query`, built once per body frame). Those candidates
    are kept while no cloth vertex has moved more than half the margin and the body frame is the
    same; each step a compiled narrow phase finds, on the body as it is at that instant, the
    closest point, its barycentric coordinates and the outward normal.

    Parameters
    ----------
    frames : (T, N, 3) body positions [m]; faces : (F, 3)
    margin : float
        Query radius [m]; must exceed the distance a cloth vertex moves between queries.
    """

    def __init__(self, frames, faces, *, margin: float = 0.02):
        self.frames = np.asarray(frames, float)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self.margin = float(margin)
        self._boxes = {}  # body frame → its TriangleBoxes
        self._cache = None  # (frame, each vertex's position when last asked, sorted keys vertex·F + triangle)
        self._previous = None  # signed distance of every vertex after the last response
        self.contact_set = _NO_CONTACTS
        self.queries = 0
        self.queried_points = 0

    def forget(self) -> None:
        """Drop what is remembered per cloth vertex (the cloth's vertices were renumbered: a cut or a tear)."""
        self._cache = None
        self._previous = None
        self.contact_set = _NO_CONTACTS

    def _body(self, frame):
        if frame not in self._boxes:
            if len(self._boxes) >= 2:  # a walk moves on frame by frame: keep the last two, not all
                self._boxes.pop(next(iter(self._boxes)))
            self._boxes[frame] = TriangleBoxes(self.frames[frame], self.faces, BOX_CELL)
        return self._boxes[frame]

    def candidates(self, x, frame: int, *, cache: bool = True):
        """CSR (ptr, tri) of body triangles within ``margin`` of each vertex (FCL broad phase).

        With ``cache`` each vertex keeps its answer, on the same body frame, until it has moved
        more than half the margin from where it was asked about; only the vertices that did are
        asked again (sewing moves a few fast, settling and walking move most slowly).
        """
        if not np.all(np.isfinite(x)):  # FCL would crash on NaN; the guard reports instabilities
            raise SimulationUnstable("cloth positions became NaN or infinite before the body collision query; "
                                     "try a smaller time step or the implicit integrator")
        c = self._cache
        if cache and c is not None and c[0] == frame and c[1].shape == x.shape:
            _, anchor, keys = c
            moved = np.flatnonzero(np.max(np.abs(x - anchor), axis=1) >= 0.5 * self.margin)
            if len(moved):
                anchor = anchor.copy()
                anchor[moved] = x[moved]
                mask = np.zeros(len(x), bool)
                mask[moved] = True
                keys = np.concatenate([keys[~mask[keys // len(self.faces)]], self._query(x[moved], frame, moved)])
                keys.sort(kind="stable")  # by vertex; two sorted runs: a stable (merge) sort is ~20× quicker
                self._cache = (frame, anchor, keys)
        else:
            keys = self._query(x, frame, np.arange(len(x)))
            if cache:
                self._cache = (frame, x.copy(), keys)
        return self._csr(keys, len(x))

    def _csr(self, keys, n):
        """(ptr, tri) of sorted keys ``vertex · F + triangle`` over ``n`` vertices."""
        ptr = np.concatenate([[0], np.cumsum(np.bincount(keys // len(self.faces), minlength=n))]).astype(np.int64)
        return ptr, keys % len(self.faces)

    def _closest(self, x, ptr, tri, body_x, rows=None):
        """Narrow phase: signed distance, triangle (−1: none), barycentrics and normal per point
        (of the points ``rows`` only, if given: the others get none)."""
        n = len(x)
        dist, tri_out, bary, normal = np.full(n, np.inf), np.full(n, -1, np.int64), np.zeros((n, 3)), np.zeros((n, 3))
        rows = np.arange(n, dtype=np.int64) if rows is None else np.asarray(rows, np.int64)
        _nearest(np.ascontiguousarray(x), ptr, tri, np.ascontiguousarray(body_x), self.faces, dist, tri_out, bary, normal, rows)
        dist[tri_out < 0] = np.inf
        return dist, tri_out, bary, normal

    def _query(self, points, frame, ids, radius=None):
        """Sorted keys ``vertex · F + triangle`` of body triangles within the margin (or ``radius``) of ``points``."""
        radius = self.margin if radius is None else radius
        point, tri = clustered_query(points, radius, self._body(frame), cell=BOX_CELL)
        self.queries += 1
        self.queried_points += len(points)
        keys = np.asarray(ids, np.int64)[point] * len(self.faces) + tri
        keys.sort()  # grouped by vertex is all the CSR needs (a repeated pair would only be tested twice)
        return keys

    def nearest(self, x, body_x, frame: int, *, cache: bool = True):
        """Signed distance [m] (positive outside), triangle, barycentrics and normal per vertex.

        Vertices with no body triangle within the margin get triangle −1 and distance +inf.
        """
        found = self._closest(x, *self.candidates(x, frame, cache=cache), body_x)
        return self._confirm_deep(x, found, body_x) if cache else found  # uncached: complete within the margin

    def _confirm_deep(self, x, found, body_x):
        """``found`` with the vertices read deeper than half the margin checked against the closed surface.

        The cached candidates hold every triangle within half the margin of a vertex, but only
        some of those farther off. Beyond half the margin the closest of them is still farther than
        half the margin (the true distance is too), but its side is the vote of whichever faces
        happened to be cached: a vertex 15 mm outside a cube's corner, level with one face and with
        only that face's triangles cached, read 15 mm *inside*, counted as having crossed, and was
        thrown 15 mm off (the cube scene exploded at first contact). Such vertices are tested
        against the closed surface (:func:`points_inside`, as :meth:`rescue` does: the body must be
        watertight for either); those outside are out of reach.
        """
        dist, tri, bary, normal = found
        deep = np.flatnonzero((tri >= 0) & (dist < -0.5 * self.margin))
        if len(deep):
            out = deep[~points_inside(x[deep], body_x, self.faces)]
            tri[out], dist[out] = -1, np.inf
        return dist, tri, bary, normal

    def rescue(self, model, state, body_x, body_v, frame: int, *, thickness: float, reach: float = 0.15) -> int:
        """Return cloth vertices trapped inside the body to its surface; how many were moved.

        :meth:`respond` trusts only contacts within half the margin, or vertices it saw cross,
        so a vertex that arrives deep inside without crossing (a merged seam vertex at the
        centroid of its partners round a shoulder, or one squeezed through a crease) stays
        there. Here every vertex is tested against the closed surface (:func:`points_inside`);
        those inside, and confirmed by the closest triangle within ``reach`` facing away, are
        put ``thickness`` outside it at the body's velocity (inelastic, as Eq. 9–10).
        """
        inside = np.flatnonzero(points_inside(state.x, body_x, self.faces) & ~model.vertex_pinned)
        if not len(inside):
            return 0
        keys = self._query(state.x[inside], frame, np.arange(len(inside)), radius=reach)
        dist, tri, bary, normal = self._closest(state.x[inside], *self._csr(keys, len(inside)), body_x)
        ok = (tri >= 0) & (dist < 0.0)
        ids, dist, tri, bary, normal = inside[ok], dist[ok], tri[ok], bary[ok], normal[ok]
        state.x[ids] += (thickness - dist)[:, None] * normal
        state.v[ids] = (body_v[self.faces[tri]] * bary[:, :, None]).sum(axis=1)
        if self._previous is not None and len(self._previous) == len(state.x):
            self._previous[ids] = thickness
        return len(ids)

    def landing(self, model, x_end, v_end, dt, body_x, body_v, frame: int, *, thickness: float, skip=None):
        """Vertices a step would bring within ``thickness`` of the body: (ids, normals, normal velocity).

        ``skip``: ids not to test (the contacts the solve already holds: most of a resting cloth's).

        ``x_end``, ``v_end`` are where a solved step would leave the cloth. A vertex that started
        the step outside (or just inside) the thickness and would end closer gets the normal
        velocity that makes it land exactly at the thickness, relative to the body; an implicit
        solve holding that (:class:`tailor.integrators.ImplicitEuler` ``predict``) lands the cloth
        within the step instead of having it pushed out afterwards.
        """
        rows = None
        if skip is not None and len(skip):
            test = ~model.vertex_pinned
            test[skip] = False
            rows = np.flatnonzero(test)
        dist, tri, bary, normal = self._confirm_deep(x_end, self._closest(x_end, *self.candidates(x_end, frame), body_x, rows),
                                                     body_x)
        close = np.flatnonzero((tri >= 0) & (dist < thickness) & ~model.vertex_pinned)
        if not len(close):
            return np.zeros(0, np.intp), np.zeros((0, 3)), np.zeros(0)
        n = normal[close]
        vb = np.einsum("kij,ki->kj", body_v[self.faces[tri[close]]], bary[close])
        vn = np.einsum("ij,ij->i", v_end[close] - vb, n)
        start = dist[close] - dt * vn  # where it started, relative to the body
        ok = (vn < 0) & (start > -0.5 * self.margin)
        close, n, vb, start = close[ok], n[ok], vb[ok], start[ok]
        return close, n, np.einsum("ij,ij->i", vb, n) - np.maximum(start - thickness, 0.0) / dt

    def respond(self, model, state, dt, body_x, body_v, frame: int, *, thickness: float, friction, impulse=None):
        """Eq. 9–14 on ``state`` in place: push out to ``thickness``, cancel approach, apply friction.

        ``impulse`` (N,) [N·s], optional: the normal impulse the integrator's solve already gave
        each vertex it held on the body (:attr:`contact_set` of the previous call); it counts
        towards the friction budget of Eq. 14 like the approach cancelled here. Afterwards
        :attr:`contact_set` = (ids, normals, body normal velocity, stuck, body velocity, μ) of the
        vertices resting on the body and not being pulled into it, for the next implicit step to
        hold (stuck ones entirely: friction stopped them here).

        Returns the deepest penetration [m] found before the response (0 if none).
        """
        dist, tri, bary, normal = self.nearest(state.x, body_x, frame)
        # A vertex found deeper than half the margin either crossed the surface this step (it was
        # outside before: push it back) or lies near the far side of a thin or concave part
        # (armpit, crotch) where the closest triangle is not the one it entered by: leave those.
        # A resting band above the thickness keeps resting contact from flickering on and off.
        prev = self._previous if self._previous is not None and len(self._previous) == len(dist) else None
        crossed = (prev >= 0.0) & (dist < 0.0) if prev is not None else np.zeros(len(dist), bool)
        plausible = (dist > -0.5 * self.margin) | crossed
        hit = np.flatnonzero((tri >= 0) & (dist < 1.5 * thickness) & plausible)
        self._previous = np.where(tri >= 0, dist, np.inf)
        self.contact_set = _NO_CONTACTS
        if not len(hit):
            return 0.0
        depth = float(max(0.0, -dist[hit].min()))
        self._previous[hit] = thickness  # pushed back out below
        f = self.faces[tri[hit]]
        w = bary[hit]
        vb = (body_v[f] * w[:, :, None]).sum(axis=1)  # body velocity at the contact point (Eq. 9)
        n = normal[hit]
        movable = ~model.vertex_pinned[hit]
        hit, n, vb = hit[movable], n[movable], vb[movable]
        rel = state.v[hit] - vb  # Eq. 9
        vn = np.einsum("ij,ij->i", rel, n)  # Eq. 10
        # a vertex that started the step above the thickness falls until it lands on it (its
        # position moves with the approach up to there), then rests: normal velocity cancelled
        start_gap = dist[hit] - dt * vn
        land = np.where(vn < 0, np.maximum(vn, -np.maximum(start_gap - thickness, 0.0) / dt), vn)
        dv_n = -np.minimum(vn, 0.0)  # the approach cancelled here
        # contacts the solve held had their friction there (stuck, or sliding at the Coulomb limit)
        held = np.zeros(len(hit)) if impulse is None else np.asarray(impulse)[hit] / model.vertex_mass[hit]
        tangential = rel - vn[:, None] * n  # Eq. 11
        speed_t = np.linalg.norm(tangential, axis=1)
        mu = np.asarray(friction)[hit] if np.ndim(friction) else float(friction)
        # Eq. 14: friction removes at most μ·(normal velocity change); beyond that it stops sliding
        keep = np.where(speed_t > 0, np.maximum(0.0, 1.0 - mu * dv_n / np.maximum(speed_t, 1e-300)), 0.0)
        pressed = ((vn < 0) | (held > 0))[:, None]
        new_rel = np.where(pressed, tangential * keep[:, None] + np.maximum(vn, 0.0)[:, None] * n, rel)
        v_new = vb + new_rel
        # the step already moved the vertex with its old velocity: move it as the new one would
        # (with the landing approach), then out to the thickness if it started closer
        shift = dt * (v_new - state.v[hit] + np.where(pressed, np.minimum(land, 0.0)[:, None] * n, 0.0))
        gap = dist[hit] + np.einsum("ij,ij->i", shift, n)
        state.x[hit] += shift + np.maximum(thickness - gap, 0.0)[:, None] * n
        state.v[hit] = v_new
        # resting (not leaving) and not held by a pull last step: hold it during the next one,
        # first stuck to the body; the solve lets it slide, at the Coulomb limit, if it must
        rest = (np.einsum("ij,ij->i", new_rel, n) <= 1e-9) & (held >= 0)
        stuck = np.ones(len(hit), bool)
        mu = np.broadcast_to(mu, hit.shape)
        self.contact_set = (hit[rest], n[rest], np.einsum("ij,ij->i", vb[rest], n[rest]), stuck[rest], vb[rest], mu[rest])
        return depth
