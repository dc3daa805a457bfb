"""An outfit's garments as layers of one cloth: which side of an inner garment an outer one belongs on
(:class:`Layers`, used by :class:`~tailor.collide.cloth.SelfCollider`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import vertex_normals

__all__ = ["Layers"]


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

    A contact between two garments keeps the outer one on the outer side, whatever side memory
    says (3ds Max cloth's layer rule as a one-sided constraint): a vertex of the outer garment on
    the side of an inner face its ``face_out`` names, a vertex of the inner one behind an outer face.
    """

    face_layer: np.ndarray
    face_out: np.ndarray
    loose: np.ndarray | None = None

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
        return cls(np.asarray(face_layer, np.int64), out, None if loose is None else np.asarray(loose, np.int64))

    def vertex_layer(self, faces, n: int) -> np.ndarray:
        """(N,) each vertex's garment (garments share no vertex)."""
        out = np.zeros(n, np.int64)
        out[faces] = np.asarray(self.face_layer)[:, None]
        return out

    def vertex_triangle_sides(self, vertex_layer, faces, vtx, tri) -> np.ndarray:
        """(V,) int8 per vertex–triangle pair: the side of the triangle's winding normal the vertex
        belongs on (±1), 0 within one garment or where either is loose against the other."""
        lv, lt = vertex_layer[vtx], np.asarray(self.face_layer)[tri]
        out = np.asarray(self.face_out, np.int8)[tri]
        side = np.where(lv > lt, out, np.where(lv < lt, -out, 0)).astype(np.int8)
        if self.loose is not None:
            free = (self.loose[vtx] == lt) | (self.loose[faces[tri]] == lv[:, None]).any(axis=1)
            side[free] = 0
        return side

    def edge_directions(self, vertex_layer, faces, x, pairs) -> np.ndarray:
        """(E, 3) per edge pair (a0, a1, b0, b1): the direction edge a belongs in from edge b (the
        inner edge's outward normal, signed), zero within one garment or where either is loose
        against the other."""
        out = np.zeros((len(pairs), 3))
        la, lb = vertex_layer[pairs[:, 0]], vertex_layer[pairs[:, 2]]
        free = la == lb  # most candidates lie within one garment: no normals for them
        if self.loose is not None:
            free |= (self.loose[pairs[:, :2]] == lb[:, None]).any(axis=1) | (self.loose[pairs[:, 2:]] == la[:, None]).any(axis=1)
        between = np.flatnonzero(~free)
        if not len(between):
            return out
        p = pairs[between]
        needed = np.zeros(len(x), bool)
        needed[p.ravel()] = True
        touch = np.flatnonzero(needed[faces].any(axis=1))  # every face at a vertex asked about, no other
        normal = vertex_normals(x, faces[touch], np.asarray(self.face_out)[touch])  # pointing out, away from the body
        a_outside = (la[between] > lb[between])[:, None]
        out[between] = np.where(a_outside, normal[p[:, 2]] + normal[p[:, 3]], -(normal[p[:, 0]] + normal[p[:, 1]]))
        return out
