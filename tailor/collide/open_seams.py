"""Which of a cloth's self-contact candidates the open seams leave out while it sews.

While sewing, the vertices along open seams take no part in self-contact (as a vertex, a triangle's
corner or an edge's end): a seam's two sides must be free to meet edge to edge. Some vertex pairs
still keep contact (the neighbourhoods of a seam's two sides keep out of each other), and so does
every pair between two garments of an outfit: an open seam passes through its own garment, never
through another (a skirt's band closing over trousers').
"""

from __future__ import annotations

import numpy as np

from .cloth_kernels import touching, unique_ints
from .memory import same_optional
from .regions import in_sorted

__all__ = ["OpenSeams"]


class OpenSeams:
    """The vertices left out of self-contact and the pairs among them that keep it, for ``n`` vertices;
    ``garment`` ((n,) int, optional) each vertex's garment of an outfit."""

    def __init__(self, n: int, garment=None):
        self.n, self.garment = int(n), garment
        self.ignored = None  # (n,) bool: vertices that take no part (None: none)
        self.kept = None  # sorted vertex-pair keys that keep contact though ignored
        self.keeping = None  # (n,) bool: the vertices of those pairs

    def set(self, vertices, keep=None) -> bool:
        """From now on the ``vertices`` ((n,) bool, or None) take no part, but the vertex pairs ``keep``
        ((K, 2)); returns whether that changed anything."""
        mask = None if vertices is None or not np.any(vertices) else np.asarray(vertices, bool)
        keys = None
        if mask is not None and keep is not None and len(keep):
            p = np.asarray(keep, np.int64).reshape(-1, 2)
            keys = unique_ints(np.r_[p[:, 0] * self.n + p[:, 1], p[:, 1] * self.n + p[:, 0]])
        if same_optional(mask, self.ignored) and same_optional(keys, self.kept):
            return False
        self.ignored, self.kept, self.keeping = mask, keys, None
        if keys is not None:
            self.keeping = np.zeros(self.n, bool)
            self.keeping[keys // self.n] = True
        return True

    def is_kept(self, a, b):
        """Whether each vertex pair (a, b) keeps contact though ignored."""
        if self.kept is None:
            return np.zeros(np.broadcast(a, b).shape, bool)
        return in_sorted(self.kept, a * self.n + b)

    def drop(self, faces, vertex, tri, near, ee, ee_near):
        """The vertex–triangle (``vertex``, ``tri`` of ``faces``, ``near``) and edge–edge (``ee``,
        ``ee_near``) candidates without the ignored vertices (but the kept pairs and those between garments)."""
        if self.ignored is None:
            return vertex, tri, near, ee, ee_near
        corners = faces[tri]
        keep = ~(self.ignored[vertex] | touching(corners, self.ignored))
        touched = np.flatnonzero(~keep)  # only these can be saved by a kept pair
        keep[touched] = self.is_kept(vertex[touched, None], corners[touched]).any(axis=1)
        if self.garment is not None:
            keep |= self.garment[vertex] != self.garment[corners[:, 0]]
        if len(ee):
            keep_ee = ~touching(ee, self.ignored)
            touched = np.flatnonzero(~keep_ee)
            a, b = ee[touched, :2], ee[touched, 2:]
            keep_ee[touched] = self.is_kept(a[:, :, None], b[:, None, :]).reshape(len(a), 4).any(axis=1)
            if self.garment is not None:
                keep_ee |= self.garment[ee[:, 0]] != self.garment[ee[:, 2]]
            ee, ee_near = ee[keep_ee], ee_near[keep_ee]
        return vertex[keep], tri[keep], near[keep], ee, ee_near
