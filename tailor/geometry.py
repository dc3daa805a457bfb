"""Array geometry of triangle soups: areas, angles, edges. numpy only, vectorised.

Shapes follow trimesh's convention: ``points (n, d)`` with d = 2 or 3, ``faces (F, 3)`` int.

Examples
--------
>>> import numpy as np
>>> pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
>>> face_areas(pts, np.array([[0, 1, 2]])).tolist()
[0.5]
>>> np.degrees(face_angles(pts, np.array([[0, 1, 2]]))).round(6).tolist()
[[90.0, 45.0, 45.0]]
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "face_areas",
    "face_signed_areas_2d",
    "face_angles",
    "vertex_normals",
    "unique_edges",
    "connected_components",
    "hinge_angles",
    "hinge_angle_gradients",
]


def _cross(a, b):
    if a.shape[-1] == 2:
        return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return np.cross(a, b)


def face_signed_areas_2d(points, faces) -> np.ndarray:
    """Signed areas of 2D triangles [m²], shape (F,); positive for counter-clockwise."""
    p = np.asarray(points, dtype=float)[faces]
    return 0.5 * _cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def face_areas(points, faces) -> np.ndarray:
    """Unsigned triangle areas [m²], shape (F,), for 2D or 3D points."""
    p = np.asarray(points, dtype=float)[faces]
    c = _cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    if c.ndim == 1:
        return 0.5 * np.abs(c)
    return 0.5 * np.linalg.norm(c, axis=1)


def vertex_normals(points, faces, face_sign=None) -> np.ndarray:
    """(N, 3) sums of the winding normals (b − a) × (c − a) of the faces at each vertex (area-weighted,
    not normalised; zero at a vertex without faces), each face's times ``face_sign`` if given.

    >>> vertex_normals(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]]), np.array([[0, 1, 2]])).tolist()
    [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]
    """
    p = np.asarray(points, dtype=float)
    faces = np.asarray(faces)
    t = p[faces]
    fn = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    if face_sign is not None:
        fn = fn * np.asarray(face_sign, float)[:, None]
    corner = faces.ravel()
    return np.column_stack([np.bincount(corner, weights=np.repeat(fn[:, k], 3), minlength=len(p)) for k in range(3)])


def face_angles(points, faces) -> np.ndarray:
    """Interior angles [rad] at each corner, shape (F, 3), column k at vertex ``faces[:, k]``."""
    p = np.asarray(points, dtype=float)[faces]
    out = np.empty((len(p), 3))
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        out[:, k] = np.arccos(np.clip(cos, -1.0, 1.0))
    return out


def unique_edges(faces) -> np.ndarray:
    """Undirected edges of a triangle mesh, each once with the smaller index first, shape (E, 2)."""
    f = np.asarray(faces)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    e.sort(axis=1)
    if not len(e):
        return e.reshape(0, 2)
    n = int(e.max()) + 1
    keys = np.unique(e[:, 0].astype(np.int64) * n + e[:, 1])  # one integer per edge: a 1-D sort, not rows
    return np.column_stack([keys // n, keys % n]).astype(e.dtype, copy=False)


def connected_components(vertex_count: int, faces) -> np.ndarray:
    """Component label of each vertex (vertices joined by faces), shape (N,)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components as cc

    e = unique_edges(faces)
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(vertex_count, vertex_count))
    return cc(g, directed=False)[1]


def _rowdot(a, b):
    return np.einsum("ij,ij->i", a, b)


def hinge_angles(x, hinge_vertices) -> np.ndarray:
    """Signed dihedral angle of each hinge [rad], 0 when flat, shape (B,)."""
    e0, e1, o0, o1 = (x[hinge_vertices[:, k]] for k in range(4))
    e = e1 - e0
    n0 = np.cross(e, o0 - e0)
    n1 = np.cross(o1 - e1, e)
    el = np.linalg.norm(e, axis=1)
    sin = _rowdot(np.cross(n0, n1), e) / el
    cos = _rowdot(n0, n1)
    return np.arctan2(sin, cos)


def hinge_angle_gradients(x, hinge_vertices):
    """∂θ/∂x of each hinge's four vertices [rad/m], shape (B, 4, 3), order ``[e0, e1, o0, o1]``."""
    e0, e1, o0, o1 = (x[hinge_vertices[:, k]] for k in range(4))
    e = e1 - e0
    el = np.linalg.norm(e, axis=1)
    n0 = np.cross(e, o0 - e0)
    n1 = np.cross(o1 - e1, e)
    q0 = n0 / _rowdot(n0, n0)[:, None]
    q1 = n1 / _rowdot(n1, n1)[:, None]
    eh = e / el[:, None]
    g_o0 = -el[:, None] * q0
    g_o1 = -el[:, None] * q1
    g_e0 = -_rowdot(o0 - e1, eh)[:, None] * q0 - _rowdot(o1 - e1, eh)[:, None] * q1
    g_e1 = _rowdot(o0 - e0, eh)[:, None] * q0 + _rowdot(o1 - e0, eh)[:, None] * q1
    return np.stack([g_e0, g_e1, g_o0, g_o1], axis=1)
