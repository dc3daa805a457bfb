"""Regions of a cloth that can touch themselves: patches and the normal-cone test.

The garment is cut into patches about ``size`` metres across, never spanning two panels. A patch
takes part in self-collision only if its box (grown by half the query radius) overlaps a patch that
is not its neighbour or a neighbour's neighbour, or if it (or it with a nearby patch) is folded: a
surface whose normals all lie within 60° of one direction is a height field over it and cannot come
near itself except through its own neighbourhood (Volino & Magnenat-Thalmann's normal-cone
argument). Flat cloth is skipped (:class:`~tailor.collide.cloth.SelfCollider`, ``mode="auto"``).

The same test decides which *pairs* of patches may touch (:meth:`Regions.touching`): a patch may
touch itself only if folded, and another patch only if their boxes meet and they are not a
neighbourhood that is a height field together. A candidate pair of primitives is kept only if a
patch of each makes such a pair (:meth:`Regions.allowed_vertex_triangle`,
:meth:`Regions.allowed_edge_edge`): a
sleeve's patch near the torso touches the torso, not its own flat neighbours; two garments of an
outfit lying one over the other touch each other, not themselves.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from .cloth_kernels import unique_ints
from .grid import overlapping_boxes
from .patch_pairs import PatchPairs, edge_patches

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


@njit(cache=True, inline="always")
def _has(keys, q):
    """Whether ``q`` is in the sorted array ``keys`` (binary search)."""
    lo, hi = 0, len(keys)
    while lo < hi:
        mid = (lo + hi) // 2
        if keys[mid] < q:
            lo = mid + 1
        else:
            hi = mid
    return lo < len(keys) and keys[lo] == q


@njit(cache=True, parallel=True)
def _allowed_vt(vertex, tri, face_patch, ptr, patches, keys, count, out):
    for k in prange(len(vertex)):
        q = face_patch[tri[k]]
        ok = False
        for a in range(ptr[vertex[k]], ptr[vertex[k] + 1]):
            if _has(keys, patches[a] * count + q):
                ok = True
                break
        out[k] = ok


@njit(cache=True, inline="always")
def _on_edge(ptr, patches, a, b, p):
    """Whether patch ``p`` (one of ``a``'s) is also one of ``b``'s: a patch the edge a–b lies in."""
    for j in range(ptr[b], ptr[b + 1]):
        if patches[j] == p:
            return True
    return False


@njit(cache=True, parallel=True)
def _allowed_ee(ee, ptr, patches, keys, count, out):
    for k in prange(len(ee)):
        a0, a1, b0, b1 = ee[k, 0], ee[k, 1], ee[k, 2], ee[k, 3]
        ok = False
        for i in range(ptr[a0], ptr[a0 + 1]):
            p = patches[i]
            if ok or not _on_edge(ptr, patches, a0, a1, p):
                continue
            for j in range(ptr[b0], ptr[b0 + 1]):
                q = patches[j]
                if _on_edge(ptr, patches, b0, b1, q) and _has(keys, p * count + q):
                    ok = True
                    break
        out[k] = ok


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
        order = np.argsort(patch, kind="stable")
        self._starts = np.searchsorted(patch[order], np.arange(self.count))
        self._sorted_faces = np.ascontiguousarray(self.faces[order], np.int64)  # grouped by patch
        # each patch's vertices (CSR, grouped by patch): its box is theirs, a sixth of the faces' corners
        corner_keys = unique_ints(np.repeat(patch, 3).astype(np.int64) * max(self.n, 1) + self.faces.ravel())
        self._patch_vertices = corner_keys % max(self.n, 1)
        self._patch_vertex_starts = np.searchsorted(corner_keys // max(self.n, 1), np.arange(self.count))
        # each vertex's patches (CSR, sorted): a candidate pair's patches (allowed_vertex_triangle, allowed_edge_edge)
        vertex_keys = unique_ints(self.faces.ravel().astype(np.int64) * max(self.count, 1) + np.repeat(patch, 3))
        self._vertex_patches = vertex_keys % max(self.count, 1)
        self._vertex_patch_ptr = np.searchsorted(vertex_keys // max(self.count, 1), np.arange(self.n + 1)).astype(np.int64)
        # patches sharing a vertex are neighbours
        near = _shared_vertex_pairs(self.faces.ravel(), np.repeat(patch, 3), self.count)
        # neighbours of neighbours too: patches whose corners merely touch are not a fold either
        a = sp.coo_matrix((np.ones(len(near)), (near // self.count, near % self.count)),
                          shape=(self.count,) * 2).tocsr()
        a = a + a.T + sp.identity(self.count, format="csr")
        a2 = (a @ a).tocoo()
        self._adjacent = np.unique(a2.row.astype(np.int64) * self.count + a2.col)

    def touching(self, x, vertex_boxes, pad: float):
        """(faces of the patches that can touch themselves or one another, sorted keys ``p · count + q``
        of the patch pairs that can touch, both ways, ``p · count + p`` for a patch folded on itself),
        at ``x`` or, with ``vertex_boxes`` (lo, hi) per vertex, anywhere in them; patch boxes grown by
        ``pad``."""
        lo, hi = (x, x) if vertex_boxes is None else vertex_boxes
        lo = np.minimum.reduceat(lo[self._patch_vertices], self._patch_vertex_starts)
        hi = np.maximum.reduceat(hi[self._patch_vertices], self._patch_vertex_starts)
        mean, spread = self._cones(x)
        limit = math.acos(FOLDED_COS)
        active = spread > limit
        keys = [np.flatnonzero(active) * (self.count + 1)]
        i, j = overlapping_boxes(lo - pad, hi + pad)
        if len(i):
            key = np.minimum(i, j) * self.count + np.maximum(i, j)
            adjacent = in_sorted(self._adjacent, key)
            between = np.arccos(np.clip(np.einsum("ij,ij->i", mean[i], mean[j]), -1.0, 1.0))
            folded = 0.5 * between + np.maximum(spread[i], spread[j]) > limit
            hit = ~adjacent | folded
            i, j = i[hit], j[hit]
            active[i] = True
            active[j] = True
            keys += [i * self.count + j, j * self.count + i]
        return np.flatnonzero(active[self.face_patch]), unique_ints(np.concatenate(keys).astype(np.int64))

    def allowed_vertex_triangle(self, pairs, vertex, tri):
        """(K,) bool: whether each vertex–triangle candidate has a patch of its vertex and the triangle's
        patch among the patch ``pairs`` (sorted keys ``p · count + q``, :meth:`touching`)."""
        out = np.empty(len(vertex), np.bool_)
        if len(vertex):
            _allowed_vt(np.ascontiguousarray(vertex, np.int64), np.ascontiguousarray(tri, np.int64), self.face_patch,
                        self._vertex_patch_ptr, self._vertex_patches, pairs, self.count, out)
        return out

    def allowed_edge_edge(self, pairs, ee):
        """(K,) bool: whether each edge–edge candidate ((K, 4) end vertices) has a patch of each edge
        (one holding both its ends) making one of the patch ``pairs``."""
        out = np.empty(len(ee), np.bool_)
        if len(ee):
            _allowed_ee(np.ascontiguousarray(ee, np.int64), self._vertex_patch_ptr, self._vertex_patches, pairs,
                        self.count, out)
        return out

    def edge_patches(self, edges):
        """CSR (ptr, patches) of the patches holding both ends of each of ``edges`` ((E, 2) vertices)."""
        return edge_patches(edges, self._vertex_patch_ptr, self._vertex_patches)

    def patch_pairs(self, pairs, edge_csr, free=None) -> PatchPairs:
        """The patch ``pairs`` (sorted keys, :meth:`touching`) as the filter a grid search tests each
        candidate against before writing it out (:mod:`~tailor.collide.patch_pairs`); ``edge_csr``:
        :meth:`edge_patches` of the search's edges; ``free``: vertices whose pairs pass."""
        return PatchPairs(pairs, self.count, self._vertex_patch_ptr, self._vertex_patches,
                          np.ascontiguousarray(self.face_patch, np.int64), *edge_csr, free)

    def vertices_of(self, pairs):
        """(N,) bool: the vertices of the patches in the patch ``pairs`` (keys ``p · count + q``)."""
        patches = np.zeros(self.count, bool)
        patches[pairs // self.count] = patches[pairs % self.count] = True
        out = np.zeros(self.n, bool)
        out[self.faces[patches[self.face_patch]].ravel()] = True
        return out

    def _cones(self, x):
        """Each patch's normal cone at ``x``: (unit mean normals (P, 3), half-angles (P,) [rad])."""
        return _patch_cones(np.ascontiguousarray(x, np.float64), self._sorted_faces, self._starts)


@njit(cache=True, inline="always")
def _face_normal(x, face):
    """The area-weighted normal (twice the area, unnormalised) of triangle ``face`` at ``x``."""
    a, b, c = x[face[0]], x[face[1]], x[face[2]]
    u0, u1, u2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    v0, v1, v2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    return u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0


@njit(cache=True)
def _patch_cones(x, faces, starts):
    """(unit mean normals (P, 3), half-angles (P,) [rad]) of the patches whose faces are
    ``faces[starts[p]:starts[p + 1]]``: the mean of the area-weighted normals, and the widest angle
    between it and a face's own normal."""
    count = len(starts)
    mean = np.zeros((count, 3))
    spread = np.zeros(count)
    for p in range(count):
        f0, f1 = starts[p], starts[p + 1] if p + 1 < count else len(faces)
        m0, m1, m2 = 0.0, 0.0, 0.0
        for k in range(f0, f1):
            n0, n1, n2 = _face_normal(x, faces[k])
            m0, m1, m2 = m0 + n0, m1 + n1, m2 + n2
        length = max(math.sqrt(m0 * m0 + m1 * m1 + m2 * m2), 1e-300)
        m0, m1, m2 = m0 / length, m1 / length, m2 / length
        lowest = np.inf
        for k in range(f0, f1):
            n0, n1, n2 = _face_normal(x, faces[k])
            size = max(math.sqrt(n0 * n0 + n1 * n1 + n2 * n2), 1e-300)
            lowest = min(lowest, (n0 * m0 + n1 * m1 + n2 * m2) / size)
        mean[p, 0], mean[p, 1], mean[p, 2] = m0, m1, m2
        spread[p] = math.acos(min(max(lowest, -1.0), 1.0))
    return mean, spread
