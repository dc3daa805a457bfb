"""An outfit's garments as layers of one cloth: which side of an inner garment an outer one belongs on
(:class:`Layers`, used by :class:`~tailor.collide.cloth.SelfCollider`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..geometry import vertex_normals
from ..topology import boundary_edges

__all__ = ["Layers", "INNER_SIDE_COS"]

INNER_SIDE_COS = 0.25
"""An inner vertex's side of an outer triangle is judged only where the triangle's normal and the
vertex's outward normal are within acos(0.25) ≈ 75° of parallel or antiparallel
(:meth:`Layers.vertex_triangle_sides`); nearer perpendicular the pair keeps its side."""


@dataclass(frozen=True)
class Layers:
    """An outfit's garments as layers of one cloth (:mod:`tailor.outfit`).

    Attributes
    ----------
    face_layer : (F,) int
        Each face's garment, innermost 0.
    face_out : (F,) int
        +1 where a face's winding normal (b − a) × (c − a) points away from the body, −1 where it
        points at it.

    loose : (N,) int, optional
        Per vertex, a garment against which it keeps the side it is on (side memory, as within one
        garment), −1 for none: a tucked top's cloth above the band tucking it, which lies over the
        band there though it is the inner garment (:meth:`tailor.dress.garment.Garment.untucked`).
    rim : (N,) bool, optional
        The vertices on the garments' open edges (a waistband's top, a hem, an armhole). Against an
        inner garment's rim the outer one keeps the side it is on: beyond the rim the inner garment
        has no outside (a skirt's band rising over the top of trousers' band lies on the body there),
        and forcing the outer cloth over the rim's triangles pumped the rim until it tore
        (docs/outfits.md: GarmentCode's garments on MakeHuman's bodies). The report's layer count
        exempts the same vertices (:func:`~tailor.outfit.out_of_order`).

    A contact between two garments keeps the outer one on the outer side, whatever side memory
    says (3ds Max cloth's layer rule as a one-sided constraint): a vertex of the outer garment on
    the side of an inner face its ``face_out`` names, a vertex of the inner one behind an outer face.
    """

    face_layer: np.ndarray
    face_out: np.ndarray
    loose: np.ndarray | None = None
    rim: np.ndarray | None = None

    @classmethod
    def round_body(cls, face_layer, face_panel, x, faces, body_x, body_faces, loose=None) -> "Layers":
        """The layers of cloth at ``x`` round a body at ``body_x``. A panel's faces share its winding,
        so one side of a panel faces out: the side most of its area turns to the body's normal at
        the body vertex nearest each face (a hand beside a skirt, a fold, turns a few faces away)."""
        from scipy.spatial import cKDTree

        body_x = np.asarray(body_x, float)
        body_normal = vertex_normals(body_x, body_faces)
        body_normal /= np.maximum(np.linalg.norm(body_normal, axis=1, keepdims=True), 1e-300)
        tri = np.asarray(x, float)[faces]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # length: twice the area
        nearest = cKDTree(body_x).query(tri.mean(axis=1))[1]
        vote = np.bincount(face_panel, weights=np.einsum("ij,ij->i", normal, body_normal[nearest]))
        out = np.where(vote[face_panel] >= 0.0, 1, -1).astype(np.int8)
        rim = np.zeros(len(x), bool)
        rim[boundary_edges(faces).ravel()] = True
        return cls(np.asarray(face_layer, np.int64), out, None if loose is None else np.asarray(loose, np.int64), rim)

    def vertex_layer(self, faces, n: int) -> np.ndarray:
        """(N,) each vertex's garment (garments share no vertex)."""
        out = np.zeros(n, np.int64)
        out[faces] = np.asarray(self.face_layer)[:, None]
        return out

    def vertex_triangle_sides(self, vertex_layer, faces, vtx, tri, x) -> np.ndarray:
        """(V,) int8 per vertex–triangle pair at ``x``: the side of the triangle's winding normal the
        vertex belongs on (±1), 0 within one garment, where either is loose against the other or at
        the inner garment's :attr:`rim`.

        A vertex of the outer garment belongs on the side of the inner triangle its ``face_out``
        names. A vertex of the inner garment belongs on the side of the outer triangle the body is
        on, and that is read from the inner garment's own cloth round the vertex (its faces' normals
        turned out by ``face_out``), not from the outer panel's ``face_out``: an outer garment's
        folds turn its faces over (a circle skirt's hem landing on trousers' legs folds back on
        itself, and its panel's side then pushed the trousers through the fold's under layer and
        tore it). Where the triangle stands within :data:`INNER_SIDE_COS` of perpendicular to the
        vertex's normal the pair keeps the side it is on (0)."""
        lv, lt = vertex_layer[vtx], np.asarray(self.face_layer)[tri]
        out = np.asarray(self.face_out, np.int8)[tri]
        side = np.where(lv > lt, out, 0).astype(np.int8)
        inner = lv < lt
        if inner.any():
            _inner_sides(np.ascontiguousarray(vtx, np.int64), np.ascontiguousarray(tri, np.int64), inner,
                         np.ascontiguousarray(faces, np.int64), np.asarray(self.face_out, np.int64),
                         np.ascontiguousarray(x, np.float64), INNER_SIDE_COS, side)
        if self.loose is not None:
            free = (self.loose[vtx] == lt) | (self.loose[faces[tri]] == lv[:, None]).any(axis=1)
            side[free] = 0
        if self.rim is not None:  # the inner one's rim: the triangle's (an outer vertex), the vertex (an inner one)
            side[np.where(lv > lt, self.rim[faces[tri]].any(axis=1), self.rim[vtx])] = 0
        return side

    def edge_directions(self, vertex_layer, faces, x, pairs) -> np.ndarray:
        """(E, 3) per edge pair (a0, a1, b0, b1): the direction edge a belongs in from edge b (the
        inner edge's outward normal, signed: the sum of its ends' area-weighted normals, each face's
        turned out by ``face_out``), zero within one garment, where either is loose against the
        other or where the inner edge touches its garment's :attr:`rim`. Compiled: asked at every
        self-contact query of an outfit."""
        out = np.zeros((len(pairs), 3))
        loose = np.zeros(0, np.int64) if self.loose is None else np.asarray(self.loose, np.int64)
        rim = np.zeros(0, np.bool_) if self.rim is None else np.asarray(self.rim, np.bool_)
        if len(pairs):
            _edge_directions(np.ascontiguousarray(pairs, np.int64), np.asarray(vertex_layer, np.int64), loose, rim,
                             np.ascontiguousarray(faces, np.int64), np.asarray(self.face_out, np.int64),
                             np.ascontiguousarray(x, np.float64), out)
        return out


@njit(cache=True)
def _edge_directions(pairs, layer, loose, rim, faces, face_out, x, out):
    """:meth:`Layers.edge_directions` into ``out`` (``loose``, ``rim`` empty: none): the pairs between
    garments first, then the normals at their ends only (faces in order, as :func:`vertex_normals` sums them)."""
    between = np.zeros(len(pairs), np.bool_)
    needed = np.zeros(len(x), np.bool_)
    for k in range(len(pairs)):
        la, lb = layer[pairs[k, 0]], layer[pairs[k, 2]]
        free = la == lb
        if not free and len(loose):
            free = loose[pairs[k, 0]] == lb or loose[pairs[k, 1]] == lb or loose[pairs[k, 2]] == la or loose[pairs[k, 3]] == la
        if not free and len(rim):  # the inner edge on its garment's rim
            i = 0 if la < lb else 2
            free = rim[pairs[k, i]] or rim[pairs[k, i + 1]]
        if not free:
            between[k] = True
            for m in range(4):
                needed[pairs[k, m]] = True
    normal = _outward_normals(x, faces, face_out, needed)
    for k in range(len(pairs)):
        if not between[k]:
            continue
        a0, a1, b0, b1 = pairs[k, 0], pairs[k, 1], pairs[k, 2], pairs[k, 3]
        if layer[a0] > layer[b0]:
            for d in range(3):
                out[k, d] = normal[b0, d] + normal[b1, d]
        else:
            for d in range(3):
                out[k, d] = -(normal[a0, d] + normal[a1, d])


@njit(cache=True)
def _face_normal(x, faces, f, s):
    """Face ``f``'s winding normal at ``x`` (twice its area long), times ``s``."""
    i, j, k = faces[f, 0], faces[f, 1], faces[f, 2]
    u0, u1, u2 = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
    w0, w1, w2 = x[k, 0] - x[i, 0], x[k, 1] - x[i, 1], x[k, 2] - x[i, 2]
    return (u1 * w2 - u2 * w1) * s, (u2 * w0 - u0 * w2) * s, (u0 * w1 - u1 * w0) * s


@njit(cache=True)
def _outward_normals(x, faces, face_out, needed):
    """(N, 3): at the ``needed`` vertices, the sum of their faces' area-weighted normals turned out by
    ``face_out`` (faces in order, as :func:`vertex_normals` sums them); zero elsewhere."""
    normal = np.zeros((len(x), 3))
    for f in range(len(faces)):
        if not (needed[faces[f, 0]] or needed[faces[f, 1]] or needed[faces[f, 2]]):
            continue
        n0, n1, n2 = _face_normal(x, faces, f, float(face_out[f]))
        for c in range(3):
            v = faces[f, c]
            normal[v, 0] += n0
            normal[v, 1] += n1
            normal[v, 2] += n2
    return normal


@njit(cache=True)
def _inner_sides(vtx, tri, pick, faces, face_out, x, cos_min, side):
    """:meth:`Layers.vertex_triangle_sides` of the pairs ``pick`` (an inner vertex, an outer triangle)
    into ``side``: −1 where the triangle's winding normal points the way the vertex's outward normal
    does (the vertex belongs behind it), +1 where it points against it, 0 near perpendicular."""
    needed = np.zeros(len(x), np.bool_)
    for k in range(len(vtx)):
        if pick[k]:
            needed[vtx[k]] = True
    normal = _outward_normals(x, faces, face_out, needed)
    for k in range(len(vtx)):
        if not pick[k]:
            continue
        t0, t1, t2 = _face_normal(x, faces, tri[k], 1.0)
        v = vtx[k]
        d = t0 * normal[v, 0] + t1 * normal[v, 1] + t2 * normal[v, 2]
        size = np.sqrt((t0 * t0 + t1 * t1 + t2 * t2) * (normal[v, 0] ** 2 + normal[v, 1] ** 2 + normal[v, 2] ** 2))
        side[k] = 0 if size <= 0.0 or abs(d) < cos_min * size else (1 if d < 0.0 else -1)
