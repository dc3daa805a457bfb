"""Regions of a cloth that can touch themselves: patches and the normal-cone test.

The garment is cut into patches about ``size`` metres across, never spanning two panels. A patch
takes part in self-collision only if its box (grown by half the query radius) overlaps a patch that
is not its neighbour or a neighbour's neighbour, or if it (or it with a nearby patch) is folded: a
surface whose normals all lie within 60° of one direction is a height field over it and cannot come
near itself except through its own neighbourhood (Volino & Magnenat-Thalmann's normal-cone
argument). Flat cloth is skipped (:class:`~tailor.collide.cloth.SelfCollider`, ``mode="auto"``).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from .cloth_kernels import unique_ints
from .grid import overlapping_boxes

__all__ = ["Regions", "in_sorted", "FOLDED_COS", "PATCH_EDGES", "PATCH_MIN"]

FOLDED_COS = 0.5
"""A patch (or two neighbouring patches) whose normals spread wider than 60° may touch itself."""
PATCH_EDGES = 2.5
"""Default patch size of ``auto``, in mean edge lengths of the cloth, and at least :data:`PATCH_MIN`:
a 10 cm patch of a sleeve (a tube of 5 cm radius) spreads its normals over 115° and takes part,
though no sleeve touches itself there (docs/measurements.md, "Third speed day")."""
PATCH_MIN = 0.05
"""See ``PATCH_EDGES`` [m]: smaller patches cost more box pairs than they save."""


def _shared_vertex_pairs(vertex, patch, count: int):
    """Sorted distinct keys ``i · count + j`` (i < j) of the patches that share a vertex, from each
    face corner's ``vertex`` and ``patch``: the distinct (vertex, patch) rows sorted by vertex,
    each row paired with the rows 1, 2, … after it while they are of the same vertex."""
    key = np.unique(np.asarray(vertex, np.int64) * count + patch)
    v, p = key // count, key % count
    keys = []
    for d in range(1, len(key)):
        same = np.flatnonzero(v[d:] == v[:-d])
        if not len(same):
            break
        keys.append(p[same] * count + p[same + d])  # sorted by patch within a vertex: p[i] < p[i + d]
    return np.unique(np.concatenate(keys)) if keys else np.zeros(0, np.int64)


def in_sorted(keys, q):
    """Whether each of ``q`` is in the sorted, non-empty 1-D array ``keys``: a binary search
    (``np.isin`` sorts both arrays on every call)."""
    at = np.minimum(np.searchsorted(keys, q), len(keys) - 1)
    return keys[at] == q


class Regions:
    """The patches of a cloth mesh ``faces`` ((F, 3), ``n`` vertices), cut from positions ``x`` by
    panel (``group``, (F,)) and cubes of ``size`` [m]."""

    def __init__(self, faces, group, x, size: float):
        self.faces = faces
        self.n = len(x)
        centroid = x[self.faces].mean(axis=1)
        cell = np.floor(centroid / size).astype(np.int64)
        key = np.column_stack([group, cell])
        _, patch = np.unique(key, axis=0, return_inverse=True)
        patch = patch.ravel()
        self.face_patch = patch
        self.count = int(patch.max()) + 1 if len(patch) else 0
        self._order = np.argsort(patch, kind="stable")
        self._starts = np.searchsorted(patch[self._order], np.arange(self.count))
        # each patch's vertices (CSR, grouped by patch): its box is theirs, a sixth of the faces' corners
        corner_keys = unique_ints(np.repeat(patch, 3).astype(np.int64) * max(self.n, 1) + self.faces.ravel())
        self._patch_vertices = corner_keys % max(self.n, 1)
        self._patch_vertex_starts = np.searchsorted(corner_keys // max(self.n, 1), np.arange(self.count))
        # patches sharing a vertex are neighbours
        near = _shared_vertex_pairs(self.faces.ravel(), np.repeat(patch, 3), self.count)
        # neighbours of neighbours too: patches whose corners merely touch are not a fold either
        a = sp.coo_matrix((np.ones(len(near)), (near // self.count, near % self.count)),
                          shape=(self.count,) * 2).tocsr()
        a = a + a.T + sp.identity(self.count, format="csr")
        a2 = (a @ a).tocoo()
        self._adjacent = np.unique(a2.row.astype(np.int64) * self.count + a2.col)

    def active_faces(self, x, vertex_boxes, pad: float):
        """Faces of the patches that can touch themselves or one another, at ``x`` or, with
        ``vertex_boxes`` (lo, hi) per vertex, anywhere in them; patch boxes grown by ``pad``."""
        corners = x[self.faces[self._order]]  # (F, 3, 3) sorted by patch
        lo, hi = (x, x) if vertex_boxes is None else vertex_boxes
        lo = np.minimum.reduceat(lo[self._patch_vertices], self._patch_vertex_starts)
        hi = np.maximum.reduceat(hi[self._patch_vertices], self._patch_vertex_starts)
        e1 = corners[:, 1] - corners[:, 0]
        e2 = corners[:, 2] - corners[:, 0]
        fn = np.cross(e1, e2)  # area-weighted normals
        mean = np.add.reduceat(fn, self._starts)
        mean /= np.maximum(np.linalg.norm(mean, axis=1, keepdims=True), 1e-300)
        unit = fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)
        cos_face = np.einsum("ij,ij->i", unit, np.repeat(mean, np.diff(np.append(self._starts, len(unit))), axis=0))
        spread = np.arccos(np.clip(np.minimum.reduceat(cos_face, self._starts), -1.0, 1.0))  # cone half-angle
        limit = math.acos(FOLDED_COS)
        active = spread > limit
        i, j = overlapping_boxes(lo - pad, hi + pad)
        if len(i):
            key = np.minimum(i, j) * self.count + np.maximum(i, j)
            adjacent = in_sorted(self._adjacent, key)
            between = np.arccos(np.clip(np.einsum("ij,ij->i", mean[i], mean[j]), -1.0, 1.0))
            folded = 0.5 * between + np.maximum(spread[i], spread[j]) > limit
            hit = ~adjacent | folded
            active[i[hit]] = True
            active[j[hit]] = True
        return np.flatnonzero(active[self.face_patch])

