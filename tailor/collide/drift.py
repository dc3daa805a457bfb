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
from numba import njit, prange

from .bounds import axis_bounds
from .grid import MAX_CELLS

__all__ = ["BodyDrift", "DRIFT_CELL"]

DRIFT_CELL = 0.06
"""Side [m] of the cubes :class:`BodyDrift` keeps displacement boxes in (the body query's cubes)."""

DRIFT_SLABS = 8
"""Slabs of cubes along x that :func:`_bin_drift` fills in parallel (each scans every triangle's span)."""


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
        lo_all, hi_all = axis_bounds(x_to)
        lo_all = lo_all - reach
        span = hi_all + reach - lo_all
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


@njit(cache=True, parallel=True)
def _bin_drift(x, disp, faces, origin, cell, dims, reach):
    """Per cube the box (lo, hi) of the displacements ``disp`` of the triangles whose box at ``x``,
    grown by ``reach``, meets it. Each thread fills the cubes of its own slab along x, from every
    triangle's span of cubes (min and max: the same boxes on any thread count)."""
    lo = np.full((dims[0] * dims[1] * dims[2], 3), np.inf)
    hi = np.full((dims[0] * dims[1] * dims[2], 3), -np.inf)
    span = np.empty((faces.shape[0], 6), np.int64)
    for t in prange(faces.shape[0]):
        u, v, w = faces[t, 0], faces[t, 1], faces[t, 2]
        for a in range(3):
            span[t, 2 * a], span[t, 2 * a + 1] = _cells(x[u, a], x[v, a], x[w, a], origin[a], cell, dims[a], reach)
    slabs = min(dims[0], DRIFT_SLABS)
    for s in prange(slabs):
        first, end = s * dims[0] // slabs, (s + 1) * dims[0] // slabs
        for t in range(faces.shape[0]):
            i0, i1 = max(span[t, 0], first), min(span[t, 1], end - 1)
            if i0 > i1:
                continue
            u, v, w = faces[t, 0], faces[t, 1], faces[t, 2]
            for i in range(i0, i1 + 1):
                for j in range(span[t, 2], span[t, 3] + 1):
                    for k in range(span[t, 4], span[t, 5] + 1):
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
