"""Whether a cloth mesh passes through itself: the check the simulator's own proximity does not make.
"""

from __future__ import annotations

import fcl
import numpy as np

from .broad import bvh_object

__all__ = ['self_intersections']


def self_intersections(vertices, faces) -> np.ndarray:
    """Pairs of triangles of one mesh that intersect without sharing a vertex, shape (K, 2).

    FCL collides the mesh with itself. Neighbouring triangles always touch along their shared
    edges or corners, and python-fcl builds a Python object per touching pair (≈ 20 per
    triangle: a large part of a drape's time), so each triangle
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
