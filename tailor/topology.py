"""Mesh topology built once per model: hinges (edge-adjacent triangle pairs) and spring sets.

Pure index arithmetic on ``faces (F, 3)``; no geometry beyond rest lengths.
"""

from __future__ import annotations

import numpy as np

__all__ = ["hinges", "boundary_edges"]


def _directed_edges(faces):
    f = np.asarray(faces)
    tail = f.reshape(-1)
    head = f[:, [1, 2, 0]].reshape(-1)
    opposite = f[:, [2, 0, 1]].reshape(-1)
    return tail, head, opposite


def hinges(faces):
    """Interior edges with their two opposite vertices, and the two triangles.

    Returns
    -------
    vertices : ndarray, shape (B, 4)
        ``[e0, e1, o0, o1]``: triangle (e0, e1, o0) holds the directed edge e0→e1 and triangle
        (e1, e0, o1) the reverse, so for a consistently oriented mesh the dihedral angle's sign is
        well defined.
    faces : ndarray, shape (B, 2)
        The two triangles' indices, in the same order.

    Edges shared by more than two triangles (non-manifold) are skipped.
    """
    tail, head, opp = _directed_edges(faces)
    key = _edge_key(tail, head)
    order = np.argsort(key, kind="stable")
    k = key[order]
    starts = np.flatnonzero(np.r_[True, k[1:] != k[:-1]]) if len(k) else np.zeros(0, np.intp)
    counts = np.diff(np.r_[starts, len(k)])
    pairs = starts[counts == 2]
    a, b = order[pairs], order[pairs + 1]
    verts = np.column_stack([tail[a], head[a], opp[a], opp[b]]).astype(np.intp)
    return verts.reshape(-1, 4), np.column_stack([a // 3, b // 3]).astype(np.intp).reshape(-1, 2)


def _edge_key(tail, head):
    base = int(max(tail.max(initial=0), head.max(initial=0))) + 1
    return np.minimum(tail, head).astype(np.int64) * base + np.maximum(tail, head)


def boundary_edges(faces) -> np.ndarray:
    """Edges used by exactly one triangle, as directed in that triangle, shape (E, 2)."""
    tail, head, _ = _directed_edges(faces)
    _, inverse, counts = np.unique(_edge_key(tail, head), return_inverse=True, return_counts=True)
    single = counts[inverse] == 1
    return np.column_stack([tail[single], head[single]]).astype(np.intp)
