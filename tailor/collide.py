"""Collision queries over FCL (python-fcl): the only module that imports ``fcl``.

FCL builds a bounding-volume hierarchy (OBB-RSS) over a triangle mesh and answers proximity
and intersection queries between two such objects. Its PyPI build cannot refit a hierarchy, so
a moving mesh is rebuilt; callers should query with a margin and reuse candidates.
"""

from __future__ import annotations

import numpy as np

import fcl

__all__ = ["bvh_object", "self_intersections"]


def bvh_object(vertices, faces):
    """An FCL collision object over a triangle mesh (identity transform)."""
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
