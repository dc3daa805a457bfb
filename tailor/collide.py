"""Collision queries over FCL (python-fcl): the only module that imports ``fcl``.

FCL builds a bounding-volume hierarchy (OBB-RSS) over a triangle mesh and answers proximity
and intersection queries between two such objects. Its PyPI build cannot refit a hierarchy, so
a moving mesh is rebuilt; callers should query with a margin and reuse candidates.
"""

from __future__ import annotations

import math

import fcl
import numpy as np
from numba import njit

from .errors import SimulationUnstable

__all__ = ["bvh_object", "self_intersections", "BodyCollider"]


def bvh_object(vertices, faces):
    """An FCL collision object over a triangle mesh (identity transform).

    """
    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(faces, dtype=np.int32))
    model.endModel()
    return fcl.CollisionObject(model, fcl.Transform())


def self_intersections(vertices, faces) -> np.ndarray:
    """Pairs of triangles of one mesh that intersect without sharing a vertex, shape (K, 2).

    FCL collides the mesh with itself; neighbouring triangles always touch along their shared
    edges or corners, so pairs that share a vertex are dropped. An empty result means the mesh
    does not pass through itself.
    """
    faces = np.asarray(faces)
    obj = bvh_object(vertices, faces)
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


@njit(cache=True)
def _closest_point_triangle(p, a, b, c):
    """Closest point to p on triangle abc and its barycentric coordinates (Ericson, RTCD 5.1.5)."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = ab @ ap
    d2 = ac @ ap
    if d1 <= 0.0 and d2 <= 0.0:
        return a, 1.0, 0.0, 0.0
    bp = p - b
    d3 = ab @ bp
    d4 = ac @ bp
    if d3 >= 0.0 and d4 <= d3:
        return b, 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return a + v * ab, 1.0 - v, v, 0.0
    cp = p - c
    d5 = ab @ cp
    d6 = ac @ cp
    if d6 >= 0.0 and d5 <= d6:
        return c, 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return a + w * ac, 1.0 - w, 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return b + w * (c - b), 0.0, 1.0 - w, w
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return a + ab * v + ac * w, 1.0 - v - w, v, w


@njit(cache=True)
def _nearest(x, ptr, tri, bx, faces, out_dist, out_tri, out_bary, out_normal):
    for i in range(len(ptr) - 1):
        best = 1e30
        for k in range(ptr[i], ptr[i + 1]):
            t = tri[k]
            a, b, c = bx[faces[t, 0]], bx[faces[t, 1]], bx[faces[t, 2]]
            q, u, v, w = _closest_point_triangle(x[i], a, b, c)
            d = x[i] - q
            dist2 = d @ d
            if dist2 < best:
                best = dist2
                n = np.cross(b - a, c - a)
                n = n / max(math.sqrt(n @ n), 1e-300)
                s = d @ n
                out_dist[i] = s if s != 0.0 else 0.0
                if abs(s) < 1e-12:
                    out_dist[i] = 0.0
                out_tri[i] = t
                out_bary[i, 0], out_bary[i, 1], out_bary[i, 2] = u, v, w
                out_normal[i] = n
        if best == 1e30:
            out_tri[i] = -1


class BodyCollider:
    """Cloth–body contact (Carignan Eq. 9–14) with FCL as the broad phase.

    FCL collides a sphere of radius ``margin`` around every cloth vertex with the body's
    bounding-volume hierarchy and returns the body triangles near each vertex. Those candidates
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
        self._bvh = {}
        self._cache = None  # (frame, positions at query, ptr, tri)
        self._previous = None  # signed distance of every vertex after the last response
        self.queries = 0

    def _body(self, frame):
        if frame not in self._bvh:
            self._bvh[frame] = bvh_object(self.frames[frame], self.faces)
        return self._bvh[frame]

    def candidates(self, x, frame: int, *, cache: bool = True):
        """CSR (ptr, tri) of body triangles within ``margin`` of each vertex (FCL broad phase).

        With ``cache`` the answer is reused while the same points stay within half the margin of
        where they were asked about, on the same body frame.
        """
        if not np.all(np.isfinite(x)):  # FCL would crash on NaN; the guard reports instabilities
            raise SimulationUnstable("cloth positions became NaN or infinite before the body collision query; "
                                     "try a smaller time step or the implicit integrator")
        c = self._cache
        if cache and c is not None and c[0] == frame and c[1].shape == x.shape and np.max(np.abs(x - c[1])) < 0.5 * self.margin:
            return c[2], c[3]
        geoms = [fcl.Sphere(self.margin) for _ in range(len(x))]
        objs = [fcl.CollisionObject(g, fcl.Transform(p)) for g, p in zip(geoms, x)]
        index = {id(g): i for i, g in enumerate(geoms)}
        manager = fcl.DynamicAABBTreeCollisionManager()
        manager.registerObjects(objs)
        manager.setup()
        request = fcl.CollisionRequest(num_max_contacts=64 * len(x) + 1000, enable_contact=True)
        data = fcl.CollisionData(request=request)
        manager.collide(self._body(frame), data, fcl.defaultCollisionCallback)
        pairs = []
        for contact in data.result.contacts:
            i = index.get(id(contact.o1))
            if i is None:
                pairs.append((index[id(contact.o2)], contact.b1))
            else:
                pairs.append((i, contact.b2))
        self.queries += 1
        if pairs:
            p = np.unique(np.array(pairs, dtype=np.int64), axis=0)
            ptr = np.concatenate([[0], np.cumsum(np.bincount(p[:, 0], minlength=len(x)))]).astype(np.int64)
            tri = p[:, 1].copy()
        else:
            ptr, tri = np.zeros(len(x) + 1, np.int64), np.zeros(0, np.int64)
        if cache:
            self._cache = (frame, x.copy(), ptr, tri)
        return ptr, tri

    def nearest(self, x, body_x, frame: int, *, cache: bool = True):
        """Signed distance [m] (positive outside), triangle, barycentrics and normal per vertex.

        Vertices with no body triangle within the margin get triangle −1 and distance +inf.
        """
        ptr, tri = self.candidates(x, frame, cache=cache)
        n = len(x)
        dist = np.full(n, np.inf)
        tri_out = np.full(n, -1, np.int64)
        bary = np.zeros((n, 3))
        normal = np.zeros((n, 3))
        _nearest(np.ascontiguousarray(x), ptr, tri, np.ascontiguousarray(body_x), self.faces, dist, tri_out, bary, normal)
        dist[tri_out < 0] = np.inf
        return dist, tri_out, bary, normal

    def respond(self, model, state, dt, body_x, body_v, frame: int, *, thickness: float, friction):
        """Eq. 9–14 on ``state`` in place: push out to ``thickness``, cancel approach, apply friction.

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
        push = np.maximum(thickness - dist[hit], 0.0)[:, None] * n
        state.x[hit] += push
        rel = state.v[hit] - vb  # Eq. 9
        vn = np.einsum("ij,ij->i", rel, n)  # Eq. 10
        approach = np.minimum(vn, 0.0)
        dv_n = -approach
        tangential = rel - vn[:, None] * n  # Eq. 11
        speed_t = np.linalg.norm(tangential, axis=1)
        mu = np.asarray(friction)[hit] if np.ndim(friction) else float(friction)
        # Eq. 14: friction removes at most μ·(normal velocity change); beyond that it stops sliding
        keep = np.where(speed_t > 0, np.maximum(0.0, 1.0 - mu * dv_n / np.maximum(speed_t, 1e-300)), 0.0)
        new_rel = np.where(vn[:, None] < 0, tangential * keep[:, None], rel)
        v_new = vb + new_rel
        # the step already moved the vertex with its old velocity: move it as the new one would
        state.x[hit] += dt * (v_new - state.v[hit])
        state.v[hit] = v_new
        return depth
