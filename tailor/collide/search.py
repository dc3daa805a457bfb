"""The self-collision's broad phase over one cloth mesh: which vertex–triangle and edge–edge pairs
come within a radius, among the faces that take part now (:class:`~tailor.collide.cloth.SelfCollider`).

Each search bins one set of boxes into the compiled grid of :mod:`tailor.collide.grid` and queries
it with another. A single garment's active faces are searched among themselves. An outfit's are
searched by layer: each garment's patches that can touch its own among themselves, and, for two
garments, the patches of each that can touch the other's against those. Two layers lying flat one
over the other then never visit their own layer's cloth beside them, which is most of what a grid
cell holds; which patch pairs may touch at all is :class:`~tailor.collide.regions.Regions`'.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from .cloth_kernels import touching, unique_ints
from .grid import edge_edge_pairs, vertex_rings, vertex_triangle_pairs

__all__ = ["PairSearch", "GRID_EDGES"]

GRID_EDGES = 2.0
"""Side of the broad phase's grid cells, in mean edge lengths of the cloth."""


def _none(count: int = 5) -> tuple:
    """The last ``count`` of (vertex, triangle, near, ee, ee near), empty."""
    return (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, bool), np.zeros((0, 4), np.int64), np.zeros(0, bool))[-count:]


def _joined(parts) -> tuple:
    """(vertex, triangle, near, ee, ee near) of several searches, one after another."""
    return tuple(np.concatenate(p) for p in zip(*parts)) if parts else _none()


class PairSearch:
    """Candidate pairs of a cloth mesh ``faces`` ((F, 3) over the vertices of ``x``) within ``radius``
    [m] of each other; edge–edge pairs too unless ``edges`` is false."""

    def __init__(self, faces, x, radius: float, *, edges: bool = True):
        self.faces = np.ascontiguousarray(faces, np.int64)
        n = max(len(x), 1)
        self.radius, self.edges = float(radius), bool(edges)
        self.ring = vertex_rings(self.faces, len(x))  # each vertex's neighbours across an edge
        e = np.sort(self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        keys, face_edge = np.unique(e[:, 0] * n + e[:, 1], return_inverse=True)  # one integer per undirected edge
        self.edge_ends = np.column_stack([keys // n, keys % n])
        self.face_edges = face_edge.reshape(-1, 3).astype(np.int64)
        length = np.linalg.norm(np.diff(np.asarray(x, float)[self.edge_ends], axis=1)[:, 0], axis=1)
        self.mean_edge = float(np.mean(length)) if len(length) else 0.0
        self.cell = GRID_EDGES * self.mean_edge if len(length) else 1.0
        self._face_patch = self._patch_garment = None

    def by_layer(self, face_patch, garment) -> None:
        """From now on an outfit's faces are searched by layer: ``face_patch`` (F,) each face's patch
        (one panel's, so one garment's), ``garment`` (N,) each vertex's garment."""
        self._face_patch = np.asarray(face_patch, np.int64)
        count = int(self._face_patch.max()) + 1 if len(self._face_patch) else 0
        self._patch_garment = np.zeros(count, np.int64)
        self._patch_garment[self._face_patch] = np.asarray(garment, np.int64)[self.faces[:, 0]]

    def __call__(self, x, lo, hi, faces, pairs, dirty, *, exact: bool) -> tuple:
        """(vertex, triangle, near, ee, ee near) among the active ``faces`` whose boxes (round each
        vertex's ``lo``/``hi``) come within the radius: every pair, or (``dirty`` (N,) bool) those
        with a dirty vertex. ``pairs``: sorted keys ``p · count + q`` of the patch pairs that can
        touch (None: any), which set the layered searches; the caller still keeps only those pairs."""
        find = partial(vertex_triangle_pairs, faces=self.faces, lo=lo, hi=hi, x=x, radius=self.radius, cell=self.cell,
                       ring=self.ring, exact=exact)
        parts = []
        for a, b in self._searches(faces, pairs):
            ee = self._edge_pairs(a, b, lo, hi, dirty)
            if b is None:
                parts.append(self._vertex_triangle(find, a, a, dirty) + ee)
            else:  # each side's vertices against the other's triangles
                parts += [self._vertex_triangle(find, a, b, dirty) + ee, self._vertex_triangle(find, b, a, dirty) + _none(2)]
        return _joined(parts)

    def _searches(self, faces, pairs) -> list:
        """(faces, None): among themselves; (faces a, faces b): between the two (module docstring)."""
        if pairs is None or self._patch_garment is None:
            return [(faces, None)]
        count = len(self._patch_garment)
        p, q = pairs // count, pairs % count
        gp, gq = self._patch_garment[p], self._patch_garment[q]
        patch = self._face_patch[faces]
        out = []
        for g in np.unique(gp):
            own = (gp == g) & (gq == g)
            if own.any():
                out.append((faces[np.isin(patch, p[own])], None))
            for h in np.unique(gq[(gp == g) & (gq > g)]):
                across = (gp == g) & (gq == h)
                out.append((faces[np.isin(patch, p[across])], faces[np.isin(patch, q[across])]))
        return out

    def _vertex_triangle(self, find, faces, tris, dirty) -> tuple:
        """(vertex, triangle, near) of the vertices of ``faces`` against the triangles ``tris``: all, or
        (``dirty``) those touching a dirty vertex."""
        verts = unique_ints(self.faces[faces].ravel())
        if dirty is None:
            return find(verts, tris)
        moved = dirty[verts]
        parts = (find(verts[moved], tris), find(verts[~moved], tris[touching(self.faces[tris], dirty)]))
        return tuple(np.concatenate(p) for p in zip(*parts))

    def _edge_pairs(self, faces, others, lo, hi, dirty) -> tuple:
        """(ee, near) of the edges of ``faces`` among themselves, or against those of ``others``: all,
        or (``dirty``) the pairs with a dirty end."""
        if not self.edges:
            return _none(2)
        pairs = partial(edge_edge_pairs, edges=self.edge_ends, lo=lo, hi=hi, radius=self.radius, cell=self.cell, ring=self.ring)
        a = unique_ints(self.face_edges[faces].ravel())
        if others is None:
            return pairs(a, dirty=None if dirty is None else touching(self.edge_ends[a], dirty))
        b = unique_ints(self.face_edges[others].ravel())
        if dirty is None:
            return pairs(a, others=b)
        da, db = touching(self.edge_ends[a], dirty), touching(self.edge_ends[b], dirty)
        parts = (pairs(a[da], others=b), pairs(a[~da], others=b[db]))
        return tuple(np.concatenate(p) for p in zip(*parts))
