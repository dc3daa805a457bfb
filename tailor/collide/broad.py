"""Broad phase over FCL: boxes round clusters of points against boxes round clusters of triangles.

FCL's dynamic AABB tree managers collide the boxes; one Python object per cluster pair instead of
per vertex–triangle pair keeps python-fcl's per-contact cost off the hot path. Its PyPI build cannot
refit a hierarchy, so callers query with a margin and reuse the candidates while nothing has moved
further than it.
"""

from __future__ import annotations

import fcl
import numpy as np
from numba import njit, prange

from .closest import closest_barycentric

__all__ = ['bvh_object', 'boxes', 'manager_contacts', 'sphere_query', 'clustered_query', 'corner_bounds', 'run_starts', 'TriangleBoxes', 'TriangleGeometry', 'NearCubes', 'BOX_CELL', 'POINT_CELL']


def bvh_object(vertices, faces):
    """An FCL collision object over a triangle mesh (identity transform)."""
    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


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

    Element-wise over the few corners: NumPy's ``min(axis=1)`` over a short middle axis is several
    times slower (docs/measurements.md)."""
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
"""Side [m] of the cubes :func:`clustered_query` bins a target's triangles into."""

POINT_CELL = 0.09
"""Side [m] of the cubes :func:`clustered_query` bins the query points into: coarser than the
triangles' cubes, since each points' box is grown by the radius on every side (a third fewer FCL
pairs against a body, the same pairs found: docs/measurements.md)."""


class TriangleGeometry:
    """A triangle mesh's triangles at one instant, as a query's test reads them: ``corners`` (F, 3, 3)
    and each triangle's bounding box ``lo``, ``hi`` (F, 3) — or, with ``vertex_boxes`` (lo, hi), each
    (V, 3), the box round its corners' boxes (where they are over a span: a box, no longer exact)."""

    def __init__(self, vertices, faces, vertex_boxes=None):
        faces = np.asarray(faces, dtype=np.int64)
        self.corners = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64)[faces])
        if vertex_boxes is None:
            self.lo, self.hi = corner_bounds(self.corners)
        else:
            self.lo, self.hi = corner_bounds(vertex_boxes[0][faces])[0], corner_bounds(vertex_boxes[1][faces])[1]


class TriangleBoxes:
    """A triangle mesh's triangles binned by centroid into cubes of side ``cell``, one FCL box each.

    The target side of :func:`clustered_query`: per triangle its bounding box, per cube the box
    round its triangles, in an FCL dynamic AABB tree. Build one per body frame (or cloth state).
    With ``vertex_boxes`` (lo, hi), each (V, 3), a box per vertex (where it is over a step, or a
    span of a body's frames), each triangle's box is the one round its corners' boxes: one target
    serves every instant inside them, each asked with its own :class:`TriangleGeometry`.
    """

    def __init__(self, vertices, faces, cell: float = 0.06, vertex_boxes=None):
        tris = self.geometry = TriangleGeometry(vertices, faces, vertex_boxes)
        self.swept = vertex_boxes is not None
        self.order, self.ptr = np.zeros(0, np.int64), np.zeros(1, np.int64)
        self.manager, self.index = None, {}
        if not len(tris.corners):
            return
        order, self.ptr, _, _ = _cluster(tris.corners.mean(axis=1), cell)
        self.order = order.astype(np.int64)
        geoms, transforms = boxes(np.minimum.reduceat(tris.lo[self.order], self.ptr[:-1], axis=0),
                                  np.maximum.reduceat(tris.hi[self.order], self.ptr[:-1], axis=0))
        self.manager = fcl.DynamicAABBTreeCollisionManager()
        self.manager.registerObjects([fcl.CollisionObject(g, t) for g, t in zip(geoms, transforms)])
        self.manager.setup()
        self.index = {id(g): i for i, g in enumerate(geoms)}

    def __len__(self):
        return len(self.geometry.lo)


def clustered_query(points, radius, target: TriangleBoxes, *, cell: float = POINT_CELL, point_boxes=None, geometry=None):
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
    ``radius`` — a superset of the pairs that come that near at any moment in them. With
    ``geometry`` (:class:`TriangleGeometry`: the triangles at one instant inside those boxes) and
    points, not boxes: exactly the pairs within ``radius`` at that instant.
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
    g = target.geometry if geometry is None else geometry
    exact = point_boxes is None and (geometry is not None or not target.swept)
    return _expand_boxes(pairs, p_ptr, p_order.astype(np.int64), target.ptr, target.order, np.ascontiguousarray(lo),
                         np.ascontiguousarray(hi), g.lo, g.hi, g.corners, float(radius), exact)


class NearCubes:
    """:func:`clustered_query` against one ``target`` at one ``radius``, remembering per cube of
    space the target's boxes near it.

    The points are binned into cubes of side ``cell`` on a fixed lattice; FCL collides each cube
    not seen before, whole and grown by ``radius``, with the target's boxes, and the cube keeps the
    boxes it met. A later query whose points lie in known cubes asks FCL nothing: its pairs come
    from the compiled pass alone. A body collider asks a frame's body about the whole cloth once
    and then, step by step, about the few vertices that moved (each FCL call has a fixed cost and
    python-fcl a Python object per pair: docs/measurements.md).
    """

    LATTICE = 1 << 20
    """Cubes per axis either side of the origin a key can name (at 9 cm: 94 km)."""

    def __init__(self, target: TriangleBoxes, radius: float, cell: float = POINT_CELL):
        self.target, self.radius, self.cell = target, float(radius), float(cell)
        self._known = np.zeros(0, np.int64)  # sorted keys of the cubes asked about
        self._ptr = np.zeros(1, np.int64)  # their target boxes, CSR in the order of ``_known``
        self._boxes = np.zeros(0, np.int64)
        self.fcl_calls = 0

    def query(self, points, geometry=None):
        """(point, triangle) index pairs of the target's triangles within the radius of each point
        (as they are in ``geometry``, :class:`TriangleGeometry`, if given: any instant inside the
        target's boxes; else as the target was built)."""
        points = np.ascontiguousarray(points, dtype=np.float64)
        if not len(points) or not len(self.target):
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        cube = np.floor(points / self.cell)
        if np.abs(cube).max() >= self.LATTICE:  # too far out for a key: no lattice
            return clustered_query(points, self.radius, self.target, cell=self.cell, geometry=geometry)
        cube = cube.astype(np.int64) + self.LATTICE
        key = (cube[:, 0] << 42) | (cube[:, 1] << 21) | cube[:, 2]
        order = np.argsort(key, kind="stable").astype(np.int64)
        starts = run_starts(key[order])
        cubes = key[order[starts]]
        self._learn(cubes)
        at = np.searchsorted(self._known, cubes)
        count = self._ptr[at + 1] - self._ptr[at]
        pairs = np.empty((int(count.sum()), 2), np.int64)
        pairs[:, 0] = np.repeat(np.arange(len(cubes)), count)
        first = np.repeat(self._ptr[at] - np.concatenate([[0], np.cumsum(count)[:-1]]), count)
        pairs[:, 1] = self._boxes[first + np.arange(len(pairs))]
        t = self.target
        g = t.geometry if geometry is None else geometry
        return _expand_boxes(pairs, np.append(starts, len(key)).astype(np.int64), order, t.ptr, t.order, points, points,
                             g.lo, g.hi, g.corners, self.radius, geometry is not None or not t.swept)

    def _learn(self, cubes) -> None:
        """Ask FCL about the ``cubes`` (sorted keys) not yet known."""
        at = np.searchsorted(self._known, cubes)  # both sorted: a binary search, not ``isin``'s sorts
        known = at < len(self._known)
        known[known] = self._known[at[known]] == cubes[known]
        new = cubes[~known]
        if not len(new):
            return
        self.fcl_calls += 1
        ijk = np.stack([(new >> 42) & (2 * self.LATTICE - 1), (new >> 21) & (2 * self.LATTICE - 1),
                        new & (2 * self.LATTICE - 1)], axis=1) - self.LATTICE
        lo = ijk * self.cell - self.radius
        contacts, mine = manager_contacts(*boxes(lo, lo + self.cell + 2 * self.radius), self.target.manager,
                                          limit=64 * len(new) + 1000)
        theirs = self.target.index
        cube, box = np.empty(len(contacts), np.int64), np.empty(len(contacts), np.int64)
        for k, c in enumerate(contacts):
            a = mine.get(id(c.o1))
            cube[k], box[k] = (a, theirs[id(c.o2)]) if a is not None else (mine[id(c.o2)], theirs[id(c.o1)])
        keys = np.concatenate([np.repeat(self._known, np.diff(self._ptr)), new[cube]])
        boxes_ = np.concatenate([self._boxes, box])
        self._known = np.union1d(self._known, new)
        order = np.argsort(keys, kind="stable")
        self._boxes = boxes_[order]
        self._ptr = np.searchsorted(keys[order], np.append(self._known, np.iinfo(np.int64).max)).astype(np.int64)


@njit(cache=True, inline="always")
def _within(p, t, p_lo, p_hi, tri_lo, tri_hi, corners, r2, exact):
    """Whether point (or box) ``p`` comes within √r2 of triangle ``t``'s box, and, if ``exact``, of the triangle."""
    d2 = 0.0
    for a in range(3):
        g = max(tri_lo[t, a] - p_hi[p, a], 0.0, p_lo[p, a] - tri_hi[t, a])
        d2 += g * g
    if d2 > r2:  # the bounding boxes are out of reach: so is the triangle
        return False
    if not exact:
        return True
    a, b, c = corners[t, 0], corners[t, 1], corners[t, 2]
    u, v, w = closest_barycentric(p_lo[p], a, b, c)
    d2 = 0.0
    for e in range(3):
        g = p_lo[p, e] - (u * a[e] + v * b[e] + w * c[e])
        d2 += g * g
    return d2 <= r2


@njit(cache=True, inline="always")
def _box_bounds(first, last, t_order, tri_lo, tri_hi, lo, hi):
    """The bounds (lo, hi) of the triangles ``t_order[first:last]`` (one target box, as they are now)."""
    for a in range(3):
        lo[a], hi[a] = np.inf, -np.inf
    for m in range(first, last):
        t = t_order[m]
        for a in range(3):
            lo[a] = min(lo[a], tri_lo[t, a])
            hi[a] = max(hi[a], tri_hi[t, a])


@njit(cache=True, inline="always")
def _reaches(p, p_lo, p_hi, lo, hi, r2):
    """Whether point (or box) ``p`` comes within √r2 of the bounds (lo, hi)."""
    d2 = 0.0
    for a in range(3):
        g = max(lo[a] - p_hi[p, a], 0.0, p_lo[p, a] - hi[a])
        d2 += g * g
    return d2 <= r2


@njit(cache=True, parallel=True)
def _expand_boxes(pairs, p_ptr, p_order, t_ptr, t_order, p_lo, p_hi, tri_lo, tri_hi, corners, radius, exact):
    """The (point, triangle) pairs of met clusters whose boxes come within ``radius``, and, if
    ``exact`` (points, not swept boxes), whose triangle itself does.

    Each met cluster pair is tested once, in parallel, into a mask of its own slots (a point out of
    reach of the target box's triangles as a whole is not tested against each of them); the pairs
    are then written in the order of the cluster pairs (the result does not depend on the thread
    count)."""
    r2 = radius * radius
    n = len(pairs)
    start = np.zeros(n + 1, np.int64)
    for k in range(n):
        start[k + 1] = start[k] + (t_ptr[pairs[k, 1] + 1] - t_ptr[pairs[k, 1]]) * (p_ptr[pairs[k, 0] + 1] - p_ptr[pairs[k, 0]])
    mask = np.zeros(start[n], np.uint8)
    found = np.zeros(n + 1, np.int64)
    for k in prange(n):
        lo, hi = np.empty(3), np.empty(3)
        m0, m1 = t_ptr[pairs[k, 1]], t_ptr[pairs[k, 1] + 1]
        q0, q1 = p_ptr[pairs[k, 0]], p_ptr[pairs[k, 0] + 1]
        _box_bounds(m0, m1, t_order, tri_lo, tri_hi, lo, hi)
        hits = 0
        for q in range(q0, q1):
            p = p_order[q]
            if not _reaches(p, p_lo, p_hi, lo, hi, r2):
                continue
            for m in range(m0, m1):
                if _within(p, t_order[m], p_lo, p_hi, tri_lo, tri_hi, corners, r2, exact):
                    mask[start[k] + (m - m0) * (q1 - q0) + (q - q0)] = 1
                    hits += 1
        found[k + 1] = hits
    for k in range(n):
        found[k + 1] += found[k]
    out_p, out_t = np.empty(found[n], np.int64), np.empty(found[n], np.int64)
    for k in prange(n):
        slot, at = start[k], found[k]
        for m in range(t_ptr[pairs[k, 1]], t_ptr[pairs[k, 1] + 1]):
            for q in range(p_ptr[pairs[k, 0]], p_ptr[pairs[k, 0] + 1]):
                if mask[slot]:
                    out_p[at], out_t[at] = p_order[q], t_order[m]
                    at += 1
                slot += 1
    return out_p, out_t
