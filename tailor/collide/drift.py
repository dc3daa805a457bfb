"""How far the body moved near each point, relative to the point: :class:`BodyDrift`.

The body collider's bounds (candidates kept while nothing moved more than its budget, a
vertex out of reach while its last distance exceeds what it and the body moved since) need the
body's motion between two of its states. A walking body's feet move 8 cm a frame while its trunk
moves 1 cm, and the cloth on the trunk moves with it: the largest motion anywhere on the body says
nothing about the shirt. Here the body's triangles are binned into cubes, each cube keeping the
box of the displacements of the triangles near it; a point's bound is the farthest that box gets
from the point's own displacement: how much closer any body point near it can have come.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .grid import MAX_CELLS

__all__ = ["BodyDrift", "DRIFT_CELL"]

DRIFT_CELL = 0.06
"""Side [m] of the cubes :class:`BodyDrift` keeps displacement boxes in (the body query's cubes)."""


class BodyDrift:
    """The body's displacement from ``x_from`` to ``x_to`` (each (N, 3) [m]) near every point.

    For a point at ``p`` (near the body at ``x_to``) that moved by ``m`` over the same time,
    :meth:`relative` bounds |m − d| over the displacements d of every body point whose triangle
    comes within ``reach`` of ``p`` (at ``x_to``): a body triangle at distance s from the point
    before is at least s minus that bound from it now. Zero where no triangle comes within reach.
    """

    def __init__(self, x_from, x_to, faces, reach: float, cell: float = DRIFT_CELL):
        x_from, x_to = np.asarray(x_from, np.float64), np.asarray(x_to, np.float64)
        faces = np.ascontiguousarray(faces, np.int64)
        self.still = x_from is x_to
        lo_all = x_to.min(axis=0) - reach
        span = x_to.max(axis=0) + reach - lo_all
        cell = max(float(cell), float(np.cbrt(np.prod(span + 1e-9) / MAX_CELLS)))
        self.origin, self.cell = lo_all, cell
        self.dims = np.maximum(np.ceil(span / cell).astype(np.int64), 1)
        self.lo, self.hi = _bin_drift(x_to, x_to - x_from, faces, self.origin, cell, self.dims, float(reach))

    def relative(self, points, moved) -> np.ndarray:
        """(K,) bound [m] on how much closer the body near each point came to it, the point having moved ``moved`` (K, 3)."""
        points, moved = np.ascontiguousarray(points, np.float64), np.ascontiguousarray(moved, np.float64)
        if self.still:
            return np.sqrt(np.einsum("ij,ij->i", moved, moved))
        return _relative(points, moved, self.origin, self.cell, self.dims, self.lo, self.hi)


@njit(cache=True)
def _bin_drift(x, disp, faces, origin, cell, dims, reach):
    """Per cube the box (lo, hi) of the displacements ``disp`` of the triangles whose box at ``x``,
    grown by ``reach``, meets it."""
    lo = np.full((dims[0] * dims[1] * dims[2], 3), np.inf)
    hi = np.full((dims[0] * dims[1] * dims[2], 3), -np.inf)
    for t in range(faces.shape[0]):
        u, v, w = faces[t, 0], faces[t, 1], faces[t, 2]
        i0, i1 = _cells(x[u, 0], x[v, 0], x[w, 0], origin[0], cell, dims[0], reach)
        j0, j1 = _cells(x[u, 1], x[v, 1], x[w, 1], origin[1], cell, dims[1], reach)
        k0, k1 = _cells(x[u, 2], x[v, 2], x[w, 2], origin[2], cell, dims[2], reach)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                for k in range(k0, k1 + 1):
                    c = (i * dims[1] + j) * dims[2] + k
                    for a in range(3):
                        lo[c, a] = min(lo[c, a], disp[u, a], disp[v, a], disp[w, a])
                        hi[c, a] = max(hi[c, a], disp[u, a], disp[v, a], disp[w, a])
    return lo, hi


@njit(cache=True, inline="always")
def _cells(p, q, r, origin, cell, n, reach):
    """The first and last cube along one axis met by the span of ``p, q, r`` grown by ``reach``."""
    first = int(math.floor((min(p, q, r) - reach - origin) / cell))
    last = int(math.floor((max(p, q, r) + reach - origin) / cell))
    return min(max(first, 0), n - 1), min(max(last, 0), n - 1)


@njit(cache=True)
def _relative(points, moved, origin, cell, dims, lo, hi):
    """Per point the largest |moved − d| over the displacement box of its cube (0 outside the grid or in an empty cube)."""
    out = np.zeros(len(points))
    for p in range(len(points)):
        c = 0
        inside = True
        for a in range(3):
            k = int(math.floor((points[p, a] - origin[a]) / cell))
            if k < 0 or k >= dims[a]:
                inside = False
                break
            c = c * dims[a] + k
        if not inside or lo[c, 0] > hi[c, 0]:
            continue
        s = 0.0
        for a in range(3):
            g = max(abs(moved[p, a] - lo[c, a]), abs(moved[p, a] - hi[c, a]))
            s += g * g
        out[p] = math.sqrt(s)
    return out
