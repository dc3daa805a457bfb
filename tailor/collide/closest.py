"""Closest point on a body surface per cloth vertex (compiled narrow phase), with the outward normal there.
"""

from __future__ import annotations

import math

from numba import njit, prange

__all__ = ['nearest_into', 'TIE']


@njit(cache=True, inline="always")
def _dot3(x0, x1, x2, y0, y1, y2):
    return x0 * y0 + x1 * y1 + x2 * y2


@njit(cache=True)
def closest_barycentric(p, a, b, c):
    """Barycentric coordinates (u, v, w) of the point of triangle abc closest to p (Ericson, RTCD 5.1.5).

    Scalar arithmetic throughout: no temporary arrays in the innermost loop of the narrow phase.
    """
    ab0, ab1, ab2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    ac0, ac1, ac2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    d1 = _dot3(ab0, ab1, ab2, p[0] - a[0], p[1] - a[1], p[2] - a[2])
    d2 = _dot3(ac0, ac1, ac2, p[0] - a[0], p[1] - a[1], p[2] - a[2])
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0  # vertex region a
    d3 = _dot3(ab0, ab1, ab2, p[0] - b[0], p[1] - b[1], p[2] - b[2])
    d4 = _dot3(ac0, ac1, ac2, p[0] - b[0], p[1] - b[1], p[2] - b[2])
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0  # vertex region b
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0  # edge ab
    d5 = _dot3(ab0, ab1, ab2, p[0] - c[0], p[1] - c[1], p[2] - c[2])
    d6 = _dot3(ac0, ac1, ac2, p[0] - c[0], p[1] - c[1], p[2] - c[2])
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0  # vertex region c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w  # edge ac
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w  # edge bc
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return 1.0 - v - w, v, w  # face


@njit(cache=True, inline="always")
def _gradient(a, b, c, d0, d1, d2, dist2):
    """(g0, g1, g2, cos) for a point at offset d from its closest point on triangle abc.

    g is the unsigned direction of the distance field's gradient: d/|d| off the surface (over an
    edge or a vertex, the same whichever face sharing it is asked), the face normal on it; cos is
    d/|d| · (the face normal), the face's own vote on which side the point lies.
    """
    e0, e1, e2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    f0, f1, f2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    n0, n1, n2 = e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0
    nl = max(math.sqrt(n0 * n0 + n1 * n1 + n2 * n2), 1e-300)
    n0, n1, n2 = n0 / nl, n1 / nl, n2 / nl
    dl = math.sqrt(dist2)
    if dl > 1e-9:
        g0, g1, g2 = d0 / dl, d1 / dl, d2 / dl
        return g0, g1, g2, g0 * n0 + g1 * n1 + g2 * n2
    return n0, n1, n2, 0.0


@njit(cache=True, inline="always")
def _box_distance2(p, a, b, c):
    """Squared distance from p to the bounding box of triangle abc: a lower bound of its distance²."""
    d2 = 0.0
    for e in range(3):
        g = max(min(a[e], b[e], c[e]) - p[e], 0.0, p[e] - max(a[e], b[e], c[e]))
        d2 += g * g
    return d2


TIE = 1e-9
"""Relative difference of squared distances below which two body triangles are equally close."""


@njit(cache=True, parallel=True)
def nearest_into(x, lo, hi, tri, bx, faces, out_dist, out_tri, out_bary, out_normal, rows):
    """Closest body triangle per point, its signed distance and the outward normal there.

    Over an edge or a vertex several triangles are equally close. The side is the vote of the one
    whose face normal is most nearly along the offset (not the first one found: a point outside a
    box's corner, level with one of its faces, would read inside from that face's zero vote).
    Equally close triangles with different closest points (a point inside a body, on the medial
    plane between two faces) average their directions, so the push does not depend on the order
    of the triangles (a symmetric drop stays symmetric). Only the points ``rows`` are looked at, point
    i against the triangles ``tri[lo[i]:hi[i]]``."""
    for j in prange(len(rows)):
        i = rows[j]
        best = 1e30
        out_tri[i] = -1
        a0 = a1 = a2 = 0.0
        vote = -1.0
        side = 1.0
        v0 = v1 = v2 = 0.0
        for k in range(lo[i], hi[i]):
            t = tri[k]
            a, b, c = bx[faces[t, 0]], bx[faces[t, 1]], bx[faces[t, 2]]
            if _box_distance2(x[i], a, b, c) > (best * (1.0 + TIE) + 1e-30) * (1.0 + 1e-12):
                continue  # even its bounding box is farther than the closest so far (a tie included)
            u, v, w = closest_barycentric(x[i], a, b, c)
            d0 = x[i, 0] - (u * a[0] + v * b[0] + w * c[0])
            d1 = x[i, 1] - (u * a[1] + v * b[1] + w * c[1])
            d2 = x[i, 2] - (u * a[2] + v * b[2] + w * c[2])
            dist2 = d0 * d0 + d1 * d1 + d2 * d2
            if dist2 < best * (1.0 - TIE) - 1e-30:
                best = dist2
                a0, a1, a2, cs = _gradient(a, b, c, d0, d1, d2, dist2)
                vote, side = abs(cs), (1.0 if cs >= 0.0 else -1.0)
                v0, v1, v2 = a0, a1, a2
                out_tri[i] = t
                out_bary[i, 0], out_bary[i, 1], out_bary[i, 2] = u, v, w
            elif dist2 <= best * (1.0 + TIE) + 1e-30:
                g0, g1, g2, cs = _gradient(a, b, c, d0, d1, d2, dist2)
                a0, a1, a2 = a0 + g0, a1 + g1, a2 + g2
                if abs(cs) > vote:
                    vote, side = abs(cs), (1.0 if cs >= 0.0 else -1.0)
                    v0, v1, v2 = g0, g1, g2
        if out_tri[i] < 0:
            continue
        dl = math.sqrt(best)
        out_dist[i] = side * dl if dl > 1e-12 else 0.0
        al = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if al < 1e-6:  # opposite directions cancelled (a thin sheet's medial plane): the decisive one's
            a0, a1, a2, al = v0, v1, v2, 1.0
        out_normal[i, 0], out_normal[i, 1], out_normal[i, 2] = side * a0 / al, side * a1 / al, side * a2 / al
