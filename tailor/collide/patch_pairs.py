"""Which candidate pairs a cloth's patches let touch, tested inside the grid search.

:class:`~tailor.collide.regions.Regions` decides which *patch pairs* of a cloth can touch (the
normal-cone test); a vertex–triangle or edge–edge candidate is wanted only if a patch of each of
its two primitives makes such a pair. Most pairs a broad phase finds lie within one flat patch or
two neighbouring ones (in a walking outfit three in five edge pairs), so the grid search
(:mod:`tailor.collide.grid`) tests the rule before writing a pair out, against a bit per patch
pair and each primitive's patches listed beforehand: a vertex's (CSR), a triangle's (one), an
edge's (those holding both its ends, CSR).

A filter is the tuple :meth:`PatchPairs.arrays` returns; ``free`` ((N,) bool, or empty) marks
vertices whose pairs pass whatever their patches (an open seam's two sides, which the caller then
checks pair by pair).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["PatchPairs", "NO_PATCH_PAIRS", "edge_patches", "vertex_triangle_passes", "edge_edge_passes"]


@njit(cache=True, inline="always")
def _shared(ptr, patches, a, b, out, start):
    """How many patches vertices ``a`` and ``b`` share (their sorted rows merged), written to ``out``
    from ``start`` unless ``out`` is empty."""
    k, j = start, ptr[b]
    for i in range(ptr[a], ptr[a + 1]):
        while j < ptr[b + 1] and patches[j] < patches[i]:
            j += 1
        if j < ptr[b + 1] and patches[j] == patches[i]:
            if len(out):
                out[k] = patches[i]
            k += 1
    return k - start


@njit(cache=True)
def _edge_patches(edges, ptr, patches):
    """CSR (ptr, patches) per edge of the patches holding both its ends (``ptr``/``patches``: each
    vertex's patches, sorted): counted, then written."""
    counts = np.zeros(len(edges) + 1, np.int64)
    none = np.zeros(0, np.int64)
    for e in range(len(edges)):
        counts[e + 1] = counts[e] + _shared(ptr, patches, edges[e, 0], edges[e, 1], none, 0)
    out = np.empty(counts[-1], np.int64)
    for e in range(len(edges)):
        _shared(ptr, patches, edges[e, 0], edges[e, 1], out, counts[e])
    return counts, out


def edge_patches(edges, vertex_ptr, vertex_patches):
    """CSR (ptr, patches) of the patches holding both ends of each edge ((E, 2) vertex pairs)."""
    return _edge_patches(np.ascontiguousarray(edges, np.int64), np.ascontiguousarray(vertex_ptr, np.int64),
                         np.ascontiguousarray(vertex_patches, np.int64))


@njit(cache=True)
def _bits(keys, count):
    """One bit per patch pair ``p · count + q``: set for ``keys``."""
    bits = np.zeros((count * count + 7) // 8, np.uint8)
    for k in keys:
        bits[k >> 3] |= np.uint8(1 << (k & 7))
    return bits


@njit(cache=True, inline="always")
def _allowed(bits, k):
    return (bits[k >> 3] >> (k & 7)) & 1


@njit(cache=True, inline="always")
def vertex_triangle_passes(patch_pairs, p, f, tri):
    """Whether the filter lets vertex ``p`` meet triangle ``tri`` (corners ``f``)."""
    use, bits, count, vptr, vpat, face_patch, eptr, epat, free = patch_pairs
    if not use or (len(free) and free[p] and (free[f[0]] or free[f[1]] or free[f[2]])):
        return True
    q = face_patch[tri]
    for a in range(vptr[p], vptr[p + 1]):
        if _allowed(bits, vpat[a] * count + q):
            return True
    return False


@njit(cache=True, inline="always")
def edge_edge_passes(patch_pairs, ea, eb, a0, a1, b0, b1):
    """Whether the filter lets edge ``ea`` (ends a0, a1) meet edge ``eb`` (b0, b1)."""
    use, bits, count, vptr, vpat, face_patch, eptr, epat, free = patch_pairs
    if not use or (len(free) and (free[a0] or free[a1]) and (free[b0] or free[b1])):
        return True
    for i in range(eptr[ea], eptr[ea + 1]):
        for j in range(eptr[eb], eptr[eb + 1]):
            if _allowed(bits, epat[i] * count + epat[j]):
                return True
    return False


@dataclass(frozen=True)
class PatchPairs:
    """The patch pairs that can touch (sorted keys ``p · count + q``, both ways) of a cloth's ``count``
    patches, with each vertex's (CSR), face's and edge's (CSR) patches, and ``free`` ((N,) bool or
    None): vertices whose pairs pass regardless."""

    keys: np.ndarray
    count: int
    vertex_ptr: np.ndarray
    vertex_patches: np.ndarray
    face_patch: np.ndarray
    edge_ptr: np.ndarray
    edge_patches: np.ndarray
    free: np.ndarray | None = None

    def arrays(self):
        """The filter tuple the compiled searches take."""
        free = np.zeros(0, np.bool_) if self.free is None else np.ascontiguousarray(self.free, np.bool_)
        return (True, _bits(np.ascontiguousarray(self.keys, np.int64), int(self.count)), int(self.count), self.vertex_ptr,
                self.vertex_patches, self.face_patch, self.edge_ptr, self.edge_patches, free)


_NONE = np.zeros(0, np.int64)
NO_PATCH_PAIRS = (False, np.zeros(0, np.uint8), 1, _NONE, _NONE, _NONE, _NONE, _NONE, np.zeros(0, np.bool_))
"""The compiled searches' filter that lets every pair through."""
