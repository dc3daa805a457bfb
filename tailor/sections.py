"""Horizontal cross-sections of a body, and the trunk followed through them.

A tape measure reads a closed outline; a mesh cut by a plane gives rings, open where the mesh has
holes and crossing itself where it has folds. A cut is made from the mesh's crossed edges: each
crossed face gives a segment whose ends are named by (cut, edge), and segments sharing an edge
chain into rings, all cuts at once. :func:`horizontal_outlines` turns the rings of many cuts into
valid polygons (a nearly closed ring is closed, a self-crossing one repaired).
:func:`trunk_chain` follows the trunk from cut to cut by overlap, so it needs no assumption about
where the body stands: the trunk is the largest outline at mid-height, and each cut's trunk is the
outline that overlaps the one next to it most.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["horizontal_outlines", "trunk_chain", "TrunkChain", "second_moments", "rings", "plane_frame", "cut_outlines"]

MIN_AREA = 2e-5
"""Smallest outline kept [m²] (a 5 mm disc): slivers from noise, folds and open rings are dropped."""


GAP = 0.05
"""Largest hole [m] an outline is closed across: a cut through a hole in the mesh is an open line."""

MAX_PIECES = 200
"""Most open pieces one cut's outlines are joined from (a holed body has a few)."""


def _crossed(z, faces, heights):
    """Every (face, cut) pair where cut ``heights[k]`` crosses the face: a vertex counts as above a
    cut at its own height, so a crossed face has vertices strictly below and at or above it, and
    exactly two crossed edges. Returns the pairs' faces and cuts (``heights`` ascending)."""
    zf = z[faces]
    first = np.searchsorted(heights, zf.min(1), "right")
    count = np.searchsorted(heights, zf.max(1), "right") - first
    face = np.repeat(np.arange(len(faces)), count)
    start = np.cumsum(count) - count
    cut = np.arange(len(face)) - np.repeat(start, count) + np.repeat(first, count)
    return face, cut


def _segments(points, faces, heights, face, cut):
    """The section segment of each crossed (face, cut): its two ends on the face's crossed edges,
    as (S, 2, 2) points across the cut's normal and (S, 2) integer keys naming (cut, edge)."""
    n = len(points)
    tri = faces[face]
    a, b = tri, np.roll(tri, -1, axis=1)
    za, zb = points[a, 2], points[b, 2]
    h = heights[cut][:, None]
    crossed = (za >= h) != (zb >= h)
    pick = np.argsort(~crossed, axis=1, kind="stable")[:, :2]
    a, b = np.take_along_axis(a, pick, 1), np.take_along_axis(b, pick, 1)
    za, zb = np.take_along_axis(za, pick, 1), np.take_along_axis(zb, pick, 1)
    t = ((h - za) / (zb - za))[..., None]
    ends = points[a, :2] + t * (points[b, :2] - points[a, :2])
    keys = (cut[:, None] * n + np.minimum(a, b)) * n + np.maximum(a, b)
    return ends, keys


def _partners(keys):
    """For each segment end (flattened ``keys``), the other end sharing its key, or −1 (an open end,
    or a key more than two segments share: a non-manifold edge)."""
    flat = keys.ravel()
    order = np.argsort(flat, kind="stable")
    sk = flat[order]
    same_next = np.append(sk[1:] == sk[:-1], False)
    same_prev = np.insert(sk[1:] == sk[:-1], 0, False)
    pair = same_next & ~same_prev & ~np.append(same_next[1:], False)
    partner = np.full(len(flat), -1)
    i = np.flatnonzero(pair)
    partner[order[i]], partner[order[i + 1]] = order[i + 1], order[i]
    return partner


def _walk(partner, start):
    """Segments chained from segment ``start`` through shared ends: (the segment ends in order, as
    indices into the flattened ends; whether the chain closes; the segments it took)."""
    chain, end, seen = [2 * start, 2 * start + 1], 2 * start + 1, {start}
    while partner[end] >= 0 and partner[end] // 2 not in seen:
        s = partner[end] // 2
        seen.add(s)
        end = 4 * s + 1 - partner[end]  # the segment's other end
        chain.append(end)
    closed = partner[end] >= 0 and partner[end] // 2 == start
    if not closed:  # open: extend backwards from the start too
        back = 2 * start
        while partner[back] >= 0 and partner[back] // 2 not in seen:
            s = partner[back] // 2
            seen.add(s)
            back = 4 * s + 1 - partner[back]
            chain.insert(0, back)
    return chain, closed, seen


def _chains(ends, keys, cut, cut_count):
    """Per cut, the closed rings and open pieces (arrays of 2D points) the segments chain into."""
    partner = _partners(keys).tolist()
    points = ends.reshape(-1, 2)
    closed = [[] for _ in range(cut_count)]
    pieces = [[] for _ in range(cut_count)]
    done = np.zeros(len(keys), bool)
    for s in range(len(keys)):
        if done[s]:
            continue
        chain, is_closed, seen = _walk(partner, s)
        done[list(seen)] = True
        pts = points[chain]
        keep = np.append(True, np.any(np.abs(np.diff(pts, axis=0)) > 1e-12, axis=1))
        (closed if is_closed else pieces)[cut[s]].append(pts[keep])
    return closed, pieces


def _sections(points, faces, heights):
    """Per height (ascending), the rings (closed, open) of the mesh cut by the plane z = height."""
    faces = np.asarray(faces)
    face, cut = _crossed(points[:, 2], faces, heights)
    ends, keys = _segments(points, faces, heights, face, cut)
    return _chains(ends, keys, cut, len(heights))


def rings(closed, pieces):
    """The closed rings of one cut: ``closed`` as they are, the open ``pieces`` joined end to end
    across holes.

    A mesh with holes cuts into open polylines. Each open piece is extended by the piece whose end
    is nearest its own end, while that gap is under :data:`GAP` and nearer than its own start; then
    it is closed. A cut in more than :data:`MAX_PIECES` open pieces is no body's (a triangle soup):
    only its closed rings count.
    """
    closed = list(closed)
    if not pieces or len(pieces) > MAX_PIECES:
        return closed
    heads = np.array([p[0] for p in pieces]).reshape(len(pieces), -1)
    tails = np.array([p[-1] for p in pieces]).reshape(len(pieces), -1)
    free = np.ones(len(pieces), bool)
    for i in range(len(pieces)):
        if not free[i]:
            continue
        free[i] = False
        ring = [pieces[i]]
        start, end = heads[i], tails[i]
        while free.any():
            d = np.where(free[:, None], np.stack([np.linalg.norm(heads - end, axis=1), np.linalg.norm(tails - end, axis=1)], 1), np.inf)
            j, flip = np.unravel_index(np.argmin(d), d.shape)
            if d[j, flip] > min(GAP, np.linalg.norm(start - end)):
                break
            free[j] = False
            ring.append(pieces[j][::-1] if flip else pieces[j])
            end = heads[j] if flip else tails[j]
        if np.linalg.norm(start - end) <= GAP:
            closed.append(np.vstack(ring))
    return closed


def _polygons(closed):
    """Valid polygons (area ≥ :data:`MIN_AREA`) from the 2D rings of one cut."""
    from shapely.geometry import Polygon

    out = []
    for ring in closed:
        if len(ring) < 4:
            continue
        p = Polygon(ring)
        if not p.is_valid:
            p = p.buffer(0)
        out.extend(q for q in getattr(p, "geoms", [p]) if q.area >= MIN_AREA)
    # an outline inside another (the inner wall of a hollow part, a pocket) is not a separate body part
    out.sort(key=lambda q: -q.area)
    kept = []
    for q in out:
        if not any(k.contains(q.representative_point()) for k in kept):
            kept.append(q)
    return kept


def horizontal_outlines(vertices, faces, heights):
    """Closed outlines (lists of shapely Polygons, largest first) of the body cut at ``heights`` [m]."""
    heights = np.asarray(heights, float)
    order = np.argsort(heights, kind="stable")
    closed, pieces = _sections(np.asarray(vertices, float), faces, heights[order])
    out = [None] * len(heights)
    for j, k in enumerate(order):
        out[k] = _polygons(rings(closed[j], pieces[j]))
    return out


def plane_frame(axis):
    """Two unit vectors across ``axis``: across the body (nearest X) and the third."""
    u = np.cross(axis, [0.0, 1.0, 0.0])
    if np.linalg.norm(u) < 1e-6:
        u = np.cross(axis, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


def cut_outlines(mesh, point, axis, min_area: float = 1e-6) -> list:
    """Every outline (shapely geometry in the :func:`plane_frame` of ``axis``, about ``point``) of the
    trimesh ``mesh`` cut by the plane through ``point`` across ``axis``."""
    from shapely.geometry import Polygon

    u, w = plane_frame(axis)
    rel = np.asarray(mesh.vertices, float) - point
    local = np.column_stack([rel @ u, rel @ w, rel @ np.asarray(axis, float)])
    closed, pieces = _sections(local, mesh.faces, np.zeros(1))
    out = []
    for ring in rings(closed[0], pieces[0]):
        if len(ring) < 4:
            continue
        q = Polygon(ring)
        q = q if q.is_valid else q.buffer(0)
        if q.area > min_area:
            out.append(q)
    return out


def second_moments(poly) -> np.ndarray:
    """(2, 2) second moments of area of a polygon's outline about its centroid, per unit area."""
    xy = np.asarray(poly.exterior.coords)
    c = np.asarray(poly.centroid.coords[0])
    a, b = xy[:-1] - c, xy[1:] - c
    cross = a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]
    area = 0.5 * cross.sum()
    ixx = (cross * (a[:, 0] ** 2 + a[:, 0] * b[:, 0] + b[:, 0] ** 2)).sum() / 12.0
    iyy = (cross * (a[:, 1] ** 2 + a[:, 1] * b[:, 1] + b[:, 1] ** 2)).sum() / 12.0
    ixy = (cross * (a[:, 0] * b[:, 1] + 2 * a[:, 0] * a[:, 1] + 2 * b[:, 0] * b[:, 1] + b[:, 0] * a[:, 1])).sum() / 24.0
    return np.array([[ixx, ixy], [ixy, iyy]]) / area if area else np.zeros((2, 2))


@dataclass(frozen=True)
class TrunkChain:
    """The trunk followed through a stack of cuts (:func:`trunk_chain`).

    Attributes
    ----------
    index : (K,) int
        Per cut, the index of the trunk's outline in that cut's list, −1 where there is none.
    split : int
        The lowest cut the trunk reaches from above: the cut below it holds two outlines overlapping
        it (the legs part there: the crotch), or none; −1 if the trunk reaches the lowest cut.
    absorbed : (K,) bool
        Cuts whose trunk outline overlaps another outline of the cut below besides that cut's
        trunk: something joins the trunk there from below (an arm at the armpit, a hand touching).
    """

    index: np.ndarray
    split: int
    absorbed: np.ndarray

    def outline(self, cuts, k):
        """The trunk's polygon in cut ``k``, or None."""
        i = int(self.index[k])
        return cuts[k][i] if i >= 0 else None


def _overlaps(poly, candidates):
    """Overlap area of ``poly`` with each candidate (bounding boxes first: most pairs are apart)."""
    out = np.zeros(len(candidates))
    x0, y0, x1, y1 = poly.bounds
    for j, q in enumerate(candidates):
        a0, b0, a1, b1 = q.bounds
        if a0 < x1 and x0 < a1 and b0 < y1 and y0 < b1:
            out[j] = poly.intersection(q).area
    return out


def trunk_chain(cuts, seed: int) -> TrunkChain:
    """Follow the trunk from cut ``seed`` (its largest outline) up and down through ``cuts``.

    Cuts are ordered bottom to top. Going up, each cut's trunk is the outline overlapping the trunk
    below it most; the chain ends at the top of the head. Going down it ends where two outlines,
    each over a tenth of the trunk's area, overlap the trunk above by a fifth of their own area (the
    legs part), or where none overlaps it.
    """
    k_count = len(cuts)
    index = np.full(k_count, -1)
    absorbed = np.zeros(k_count, bool)
    if not cuts[seed]:
        return TrunkChain(index, -1, absorbed)
    index[seed] = 0
    for k in range(seed + 1, k_count):
        below = cuts[k - 1][index[k - 1]]
        over = _overlaps(below, cuts[k])
        if not over.any():
            break
        index[k] = int(np.argmax(over))
        others = [q for j, q in enumerate(cuts[k - 1]) if j != index[k - 1]]
        absorbed[k] = bool(others) and bool((_overlaps(cuts[k][index[k]], others) > 0.2 * MIN_AREA).any())
    split = -1
    for k in range(seed - 1, -1, -1):
        above = cuts[k + 1][index[k + 1]]
        over = _overlaps(above, cuts[k])
        area = np.array([q.area for q in cuts[k]])
        legs = (over > 0.2 * area) & (area > 0.1 * above.area)  # slivers at the crotch are no legs
        if not over.any() or np.count_nonzero(legs) >= 2:
            split = k + 1
            break
        index[k] = int(np.argmax(over))
    return TrunkChain(index, split, absorbed)
