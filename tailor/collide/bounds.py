"""Bounding boxes of point sets: the grids and cubes of every proximity query start from one.

NumPy reduces an (N, 3) array along its first axis with a strided inner loop over three columns,
15× slower than one compiled pass over the rows (docs/measurements.md); a walking drape asks for
the box of its cloth, its body or their triangles a few thousand times.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["axis_bounds", "triangle_bounds"]


@njit(cache=True)
def _bounds(x):
    n, d = x.shape
    lo, hi = np.empty(d), np.empty(d)
    for a in range(d):
        lo[a], hi[a] = np.inf, -np.inf
    nan = False
    for i in range(n):
        for a in range(d):
            v = x[i, a]
            nan |= v != v
            lo[a] = min(lo[a], v)
            hi[a] = max(hi[a], v)
    if nan:  # as NumPy's: a NaN coordinate makes every bound NaN (the callers' guards see it)
        lo[:], hi[:] = np.nan, np.nan
    return lo, hi


def axis_bounds(points):
    """(lo, hi): the smallest and largest coordinate of ``points`` (N, D) along each axis, as
    ``points.min(axis=0), points.max(axis=0)`` (float64; N ≥ 1; all NaN if any coordinate is NaN).

    >>> axis_bounds(np.array([[0.0, 2.0], [1.0, -1.0]]))
    (array([ 0., -1.]), array([1., 2.]))
    """
    x = np.ascontiguousarray(points, dtype=np.float64)
    if not len(x):
        raise ValueError("axis_bounds of no points")
    return _bounds(x)


@njit(cache=True)
def triangle_bounds(vertices, faces, axes):
    """(lo, hi), each (F, axes): the box of each triangle ``faces`` (F, 3) of ``vertices`` over its
    first ``axes`` coordinates (2: the xy footprint), without gathering the corners first."""
    lo, hi = np.empty((len(faces), axes)), np.empty((len(faces), axes))
    for t in range(len(faces)):
        u, v, w = faces[t, 0], faces[t, 1], faces[t, 2]
        for a in range(axes):
            lo[t, a] = min(vertices[u, a], vertices[v, a], vertices[w, a])
            hi[t, a] = max(vertices[u, a], vertices[v, a], vertices[w, a])
    return lo, hi
