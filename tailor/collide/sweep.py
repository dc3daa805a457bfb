"""Swept boxes cut in time: the self-collision search over a step whose motion is long against the mesh.

A pair of primitives can come within the search radius during a step only if the boxes round
their straight-line motion overlap (:mod:`tailor.collide.grid`). Over a whole step a flap of a
fine sheet swinging 8 cm relative to the cloth's centroid has boxes 8 cm long, and each overlaps
every box of the flap within 8 cm of it, though the flap's parts move together and never come
nearer. Cut the step into ``k`` parts: the pair must come within the radius during one of them,
where both positions lie in that part's boxes, so searching each part's boxes and taking the
union finds every pair the whole-step search must find, from boxes ``k`` times shorter. Steps
that move less than :data:`SWEEP_EDGES` mean edge lengths (every walking garment at 2 cm) are
searched whole, as before.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["SWEEP_EDGES", "MAX_SWEEP_PARTS", "sweep_parts", "part_boxes", "union_vertex_triangle", "union_edge_edge"]

SWEEP_EDGES = 4.0
"""A step is searched in parts of at most this many mean edge lengths of relative motion."""

MAX_SWEEP_PARTS = 8
"""At most this many parts a step (each part's search bins every box again)."""


def sweep_parts(step: float, mean_edge: float) -> int:
    """How many parts a step whose largest relative displacement is ``step`` [m] is searched in."""
    if not (math.isfinite(step) and mean_edge > 0.0):
        return 1
    return int(min(MAX_SWEEP_PARTS, max(1, math.ceil(step / (SWEEP_EDGES * mean_edge)))))


def part_boxes(x_prev, x, parts: int):
    """(lo, hi) per part: each vertex's box over times [k/parts, (k+1)/parts] of its straight-line
    motion from ``x_prev`` to ``x``."""
    d = x - x_prev
    start = x_prev
    for k in range(1, parts + 1):
        end = x if k == parts else x_prev + (k / parts) * d
        yield np.minimum(start, end), np.maximum(start, end)
        start = end


def union_vertex_triangle(found, face_count: int):
    """(vertex, triangle, near) of every pair in the parts' results ``found``, each once, sorted."""
    vertex, tri, near = (np.concatenate(p) for p in zip(*found))
    _, first = np.unique(vertex * face_count + tri, return_index=True)
    return vertex[first], tri[first], near[first]


def union_edge_edge(found, edges, n: int):
    """((E, 4), near) of every edge pair in the parts' results ``found``, each once (by the pair of
    rows of ``edges``, sorted by vertex, in either order), sorted by those rows."""
    ee, near = (np.concatenate(p) for p in zip(*found))
    keys = edges[:, 0] * n + edges[:, 1]
    a = np.searchsorted(keys, ee[:, 0] * n + ee[:, 1])
    b = np.searchsorted(keys, ee[:, 2] * n + ee[:, 3])
    _, first = np.unique(np.minimum(a, b) * len(keys) + np.maximum(a, b), return_index=True)
    return ee[first], near[first]
