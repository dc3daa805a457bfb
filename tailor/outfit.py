"""Outfits: several garments dressed together, layered, on one body.

People dress in outfits: a top over trousers, a skirt over a petticoat. CLO gives each pattern a
layer number (larger is further out) and 3ds Max's cloth pushes a higher layer outside a lower one;
GarmentCode merges an upper and a lower garment into one mesh. tailor does the last, keeping the
garments apart: :func:`outfit` makes one :class:`~tailor.pattern.Pattern` of several, its panels
named ``GARMENT/PANEL`` and its :attr:`~tailor.pattern.Pattern.pieces` saying which garment each
panel belongs to, so the whole driver (placement, sewing, contact, output) handles an outfit as it
handles one garment:

* **Order.** Garments go innermost first: by their pattern's ``layer`` (0 unless the file gives
  one), ties in the order given.
* **Placement.** Each garment is placed clear of the ones inside it: its landmark placements get
  their clearance plus :data:`~tailor.placement.LAYER_GAP` (:class:`~tailor.pattern.Piece`
  ``clearance``), and :func:`tailor.placement.place_panels` rolls any row that would start behind
  the cloth already placed further out.
* **Room for the layers inside** (:func:`ease_layers`): a loop of an outer garment round a
  landmark where an inner garment has one too (a skirt's waist over trousers' waistband) is widened
  until it keeps its own ease over the inner loop, one layer spacing out.
* **Sewing** in stages, innermost garment first, the outer ones waiting where they were placed
  (:meth:`tailor.dress.garment.Garment.sew_stage`); at its stage each is placed afresh, at its own
  clearance, over the sewn garments inside it (``place_panels(..., garment=k)``). Each panel keeps
  its own garment's fabric.
* **Tucked** (``outfit(..., tuck=True)``): a top's hem inside a bottom's waistband. The garments held
  at the waist go outside the top, and when such a garment is placed over the sewn top, the top's
  cloth its band will cover is gathered onto the body (each row straight in onto the body's hull,
  :func:`tuck_targets`) and held there while the band sews (:func:`tailor.dress.phases.sew`), then
  let go under the band; above the band the top may blouse over it, so there the layer rule
  gives way to the side the cloth is on while the body moves
  (:meth:`tailor.dress.garment.Garment.untucked`).
* **Contact between garments** is self-contact of the outfit's one mesh: perfectly inelastic
  (Carignan Eq. 5–8), over the same broad and narrow phases (:mod:`tailor.collide.cloth`), with
  the layer rule as a one-sided constraint once sewn (:class:`~tailor.collide.Layers`): a pair of
  two garments is judged by which one is outside, not by the side it was on, so an outer garment
  caught behind an inner one is put back outside.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .errors import PatternError
from .geometry import vertex_normals
from .pattern import Attachment, LandmarkPlacement, Pattern, Piece, Seam, SeamSide, TransformPlacement, validate_pattern
from .placement import LAYER_GAP
from .sizing import loop_girth, pattern_loops, scaled_panel

__all__ = ["outfit", "ease_layers", "garment_of_vertex", "out_of_order", "tuck_targets", "ATTACH_RISE"]

ATTACH_RISE = 0.015
"""How much higher [m] an outer garment held to a landmark an inner garment is held to is placed, for
each such garment inside it: its band's top edge then wraps over the inner band's instead of
meeting it edge to edge. Two held top edges at one height lie within one thickness of each other,
held there, and as the body moves they cross where no contact can part them (docs/outfits.md,
"Held a layer apart")."""

def _held_at_waist(pattern: Pattern) -> bool:
    """Whether ``pattern`` is a bottom: held to the body's waist (trousers, a skirt)."""
    return any(a.target == "waist" for a in pattern.attachments)


def outfit(patterns, *, name: str | None = None, tuck: bool = False) -> Pattern:
    """One pattern dressing ``patterns`` together, innermost first (see the module).

    With ``tuck``, a top's hem goes inside the waistband of a bottom of its layer: garments held at
    the waist go outside those that are not, and such a garment's :class:`~tailor.pattern.Piece`
    ``tucks``: the cloth inside it below its top edge is gathered onto the body before it sews
    (:func:`tailor.dress.phases.sew`). A single pattern is returned as it is. Garments with one
    name are told apart as ``NAME``, ``NAME-2`` …. Raises PatternError for an empty list.
    """
    patterns = list(patterns)
    if not patterns:
        raise PatternError("an outfit needs at least one pattern")
    if len(patterns) == 1:
        return patterns[0]
    bottom = [tuck and _held_at_waist(p) for p in patterns]
    order = sorted(range(len(patterns)), key=lambda i: (patterns[i].layer, bottom[i], i))
    names = _unique([patterns[i].name for i in order])
    panels, seams, attachments, pieces = [], [], [], []
    room = 0.0  # how far out the garments placed so far reach
    held: list = []  # the landmarks each garment so far is held to
    for garment, i in zip(names, order):
        p = patterns[i]
        extra = room + LAYER_GAP if pieces else 0.0
        landmarks = {a.target for a in p.attachments}
        rise = ATTACH_RISE * sum(1 for inner in held if inner & landmarks)
        held.append(landmarks)
        tucks = bottom[i] and any(not bottom[j] for j in order[:len(pieces)])
        pieces.append(Piece(garment, len(panels), len(p.panels), p.layer, extra, rise=rise, tucks=tucks))
        panels += [replace(q, name=f"{garment}/{q.name}", fabric=q.fabric or p.fabric, placement=_raised(q.placement, rise))
                   for q in p.panels]
        seams += [_renamed_seam(s, garment, len(seams) + k) for k, s in enumerate(p.seams)]
        attachments += [_renamed_attachment(a, garment, len(attachments) + k) for k, a in enumerate(p.attachments)]
        room = extra + max((q.placement.clearance for q in p.panels if isinstance(q.placement, LandmarkPlacement)),
                           default=0.02)
    first = patterns[order[0]]
    combined = Pattern(name=name or "+".join(names), panels=tuple(panels), seams=tuple(seams),
                       attachments=tuple(attachments), fabric=first.fabric,
                       source=" + ".join(patterns[i].source for i in order), pieces=tuple(pieces))
    return validate_pattern(combined)


def _raised(placement, rise: float):
    """A placement ``rise`` [m] higher: a landmark placement's offset, a rigid one's translation (a
    GarmentCode skirt's band, left at its pants' band's height, crossed it as settling began and
    tore a band triangle 20×)."""
    if not rise:
        return placement
    if isinstance(placement, LandmarkPlacement):
        return replace(placement, offset=placement.offset + rise)
    if isinstance(placement, TransformPlacement):
        x, y, z = placement.translation
        return replace(placement, translation=(x, y, z + rise))
    return placement


def ease_layers(pattern: Pattern, landmarks, spacing: float) -> Pattern:
    """``pattern`` (an outfit) with each outer garment's loops widened where they go over an inner one's.

    A pattern is drafted for the bare body: a loop of length L round a girth G has the ease L − G.
    Worn over an inner garment's loop of length L_in at the same landmark, it must go round that
    loop one layer ``spacing`` [m] further out and keep its own ease there:

        L' = max(L, L_in + 2π·spacing + max(L − G, 0)),

    so the loop's panels are scaled across by L'/L (``Piece.ease``: the largest factor of a garment).
    Without it a skirt's waistband (88 cm on an 84 cm waist) must close over trousers' band of the
    same length and is pulled through it or torn apart by the squeeze (docs/outfits.md). ``landmarks``
    are the body's (:func:`tailor.measure.measure_body`); a loop round a landmark the body lacks is left.
    """
    if len(pattern.pieces) < 2:
        return pattern
    outermost: dict = {}  # landmark → length of the outermost loop round it so far
    scales: dict = {}  # panel name → factor across
    pieces = []
    for piece in pattern.pieces:
        factor = 1.0
        for loop in pattern_loops(_garment(pattern, piece)):
            girth = loop_girth(landmarks, loop.landmark)
            inner = outermost.get(loop.landmark)
            length = loop.length
            if inner is not None and girth is not None:
                length = max(length, inner + 2.0 * math.pi * spacing + max(loop.length - girth, 0.0))
                for name in loop.panels:
                    scales[name] = max(scales.get(name, 1.0), length / loop.length)
                factor = max(factor, length / loop.length)
            outermost[loop.landmark] = max(outermost.get(loop.landmark, 0.0), length)
        pieces.append(replace(piece, ease=factor))
    if not scales:
        return pattern
    panels = tuple(scaled_panel(p, scales[p.name], 1.0) if scales.get(p.name, 1.0) > 1.0 else p for p in pattern.panels)
    return validate_pattern(replace(pattern, panels=panels, pieces=tuple(pieces)))


def _garment(pattern: Pattern, piece: Piece) -> Pattern:
    """One garment of an outfit as a pattern of its own panels and the seams among them."""
    panels = pattern.panels[piece.first:piece.first + piece.count]
    names = {p.name for p in panels}
    seams = tuple(s for s in pattern.seams if s.a.panel in names and s.b.panel in names)
    return replace(pattern, panels=panels, seams=seams, attachments=(), pieces=())


def _unique(names):
    """``names`` with repeats numbered: a, a-2, a-3."""
    seen: dict = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n}-{seen[n]}")
    return out


def _renamed_side(side: SeamSide, garment: str) -> SeamSide:
    return replace(side, panel=f"{garment}/{side.panel}")


def _renamed_seam(seam: Seam, garment: str, index: int) -> Seam:
    return replace(seam, a=_renamed_side(seam.a, garment), b=_renamed_side(seam.b, garment), index=index)


def _renamed_attachment(a: Attachment, garment: str, index: int) -> Attachment:
    return replace(a, panel=f"{garment}/{a.panel}", index=index)


def garment_of_vertex(pattern: Pattern, vertex_panel) -> np.ndarray:
    """(N,) index into ``pattern.pieces`` of each vertex's garment, from its panel (or of each face's,
    given the faces' panels)."""
    out = np.zeros(len(vertex_panel), np.intp)
    for k, piece in enumerate(pattern.pieces):
        out[(vertex_panel >= piece.first) & (vertex_panel < piece.first + piece.count)] = k
    return out


def out_of_order(x, garment, body_x, body_faces, *, reach: float = 0.02, loose=None, edge=None, faces=None) -> np.ndarray:
    """(G, G) counts: entry (i, j), i < j, is how many of garment j's vertices lie within ``reach``
    [m] of garment i's and nearer the body than the nearest of them, over the same side of the body
    (their nearest body points' normals within 90°) — an outer garment's cloth inside an inner one's.
    In a crease (an armpit, a crotch) a sleeve's cloth on the arm and a bodice's on the trunk face
    each other across the gap: neither lies inside the other. All zero when every garment keeps its
    layer. ``garment`` is :func:`garment_of_vertex`; distances and normals are
    :func:`tailor.collide.body_gap`'s.
    ``loose`` (N,) int, optional: per vertex, a garment it keeps no order against (a tucked top's
    cloth above the band, which may lie over it: :meth:`tailor.dress.garment.Garment.untucked`);
    a vertex whose nearest is such a vertex of the other garment is not counted.
    ``edge`` (N,) bool, optional: the vertices on a garment's open edges (hem, armholes, neckline);
    a vertex whose nearest is on an inner garment's edge is beyond that garment, not inside it (a
    sleeve reaching the body through a dress's armhole, the armhole's edge lifted beside it).
    ``faces`` (F, 3), optional: the garments' triangles; a vertex so found is then counted only if it
    lies on the body's side of the inner garment's surface (:func:`_under_surface`). Two layers side
    by side far from the body (a skirt hanging beside a trouser leg 5 cm off it) put an outer vertex
    a few millimetres nearer the body than the inner garment's nearest vertex without either being
    inside the other.
    """
    from scipy.spatial import cKDTree

    from .collide import body_gap

    x = np.asarray(x, float)
    faces = None if faces is None else np.asarray(faces)
    count = int(garment.max(initial=0)) + 1
    near = []  # (i, j, outer vertices within reach of garment i, their nearest vertex of garment i)
    for i in range(count):
        inner = np.flatnonzero(garment == i)
        tree = cKDTree(x[inner])
        for j in range(i + 1, count):
            outer = np.flatnonzero(garment == j)
            d, k = tree.query(x[outer], distance_upper_bound=reach)
            found = np.flatnonzero(np.isfinite(d))
            pair_outer, pair_inner = outer[found], inner[k[found]]
            keep = np.ones(len(pair_inner), bool) if edge is None else ~np.asarray(edge, bool)[pair_inner]
            if loose is not None:
                keep &= (loose[pair_inner] != j) & (loose[pair_outer] != i)
            pair_outer, pair_inner = pair_outer[keep], pair_inner[keep]
            near.append((i, j, pair_outer, pair_inner))
    ids = np.unique(np.concatenate([np.r_[a, b] for _, _, a, b in near] + [np.zeros(0, np.intp)]))
    gap, normal = np.zeros(len(x)), np.zeros((len(x), 3))
    if len(ids):  # the body's distance only where two garments overlap: the costly query
        gap[ids], normal[ids] = body_gap(x[ids], body_x, body_faces)
    out = np.zeros((count, count), np.intp)
    for i, j, outer, nearest in near:
        same_side = np.einsum("ij,ij->i", normal[outer], normal[nearest]) > 0.0
        inside = outer[(gap[outer] < gap[nearest]) & same_side]
        if faces is not None and len(inside):
            below = faces[garment[faces[:, 0]] == i]
            inside = inside[_under_surface(x, inside, below, _outward(x, below, nearest, normal[nearest]))]
        out[i, j] = len(inside)
    return out


def _outward(x, faces, ids, body_normal) -> float:
    """+1 if the surface ``faces`` (of vertices ``x``) is wound with its normals away from the body
    (as tailor places panels), −1 if towards it: the sign of its vertex normals at ``ids`` summed
    against the body's outward normals there (``body_normal``). One sign for the whole garment: a
    welded garment is wound consistently, and the body's normal under one vertex is a poor guide in a
    crease (under a buttock the body faces down, the trousers' cloth spanning the fold faces back)."""
    return 1.0 if np.einsum("ij,ij->", vertex_normals(x, faces)[ids], body_normal) >= 0.0 else -1.0


def _under_surface(x, ids, faces, outward: float) -> np.ndarray:
    """Whether each of the points ``x[ids]`` lies on the body's side of the surface ``faces`` (of
    vertices ``x``, wound away from the body where ``outward`` is +1, towards it where −1): its
    signed distance to the surface's nearest point, along the surface's normal there, is negative."""
    from .collide import body_gap

    used, local = np.unique(faces, return_inverse=True)
    distance = body_gap(x[ids], x[used], local.reshape(-1, 3))[0]
    return outward * distance < 0.0


def tuck_targets(points, body_x, body_faces, *, clearance: float, row: float):
    """Where a tuck draws ``points`` (M, 3) of a top's hem: (ids of the points moved, their targets).

    The points go in rows ``row`` [m] high; each row goes straight in, at its own height, onto the
    convex hull of the body's outlines its loop encloses (the hips, or both legs below the crotch:
    a band wraps the hull, not into the gap between the legs), ``clearance`` [m] out, along the
    ray from the hull's centre. Heights are kept and each row's order round its loop too (a ray
    from inside a convex outline meets its boundary once), so the cloth is compressed along the
    loop, never folded through itself. Points whose row encloses no outline stay where they are.
    """
    from shapely.geometry import MultiPoint, Point

    from .sections import horizontal_outlines

    points = np.asarray(points, float)
    band = np.floor(points[:, 2] / row).astype(np.int64)
    rows, which = np.unique(band, return_inverse=True)
    heights = np.array([points[which == k, 2].mean() for k in range(len(rows))])
    outlines = horizontal_outlines(body_x, body_faces, heights)
    ids, targets = [], []
    for k, polys in enumerate(outlines):
        mine = np.flatnonzero(which == k)
        if len(mine) < 3 or not polys:
            continue
        loop = MultiPoint([tuple(p) for p in points[mine, :2]]).convex_hull
        inside = [p for p in polys if loop.contains(Point(p.centroid.coords[0]))]
        if not inside:
            continue
        hull = MultiPoint([c for p in inside for c in p.exterior.coords]).convex_hull
        xy = _radially_onto(np.asarray(hull.exterior.coords)[:-1], np.asarray(hull.centroid.coords[0]), points[mine, :2], clearance)
        ids.append(mine)
        targets.append(np.column_stack([xy, points[mine, 2]]))
    if not ids:
        return np.zeros(0, np.intp), np.zeros((0, 3))
    return np.concatenate(ids), np.concatenate(targets)


def _radially_onto(hull, centre, points, clearance: float):
    """``points`` (M, 2) moved along the rays from ``centre`` onto the boundary of the convex polygon
    ``hull`` (K, 2; ``centre`` inside it), ``clearance`` further out."""
    d = points - centre
    a, e = hull, np.roll(hull, -1, axis=0) - hull
    ac = a - centre
    denom = _cross(d[:, None, :], e[None])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(ac[None], e[None]) / denom
        s = _cross(ac[None], d[:, None, :]) / denom
    t = np.where((np.abs(denom) > 1e-15) & (s >= -1e-9) & (s <= 1 + 1e-9) & (t > 0), t, 0.0).max(axis=1)
    length = np.maximum(np.linalg.norm(d, axis=1), 1e-12)
    return centre + d * (t + clearance / length)[:, None]


def _cross(u, v):
    """The z component of 2-D cross products."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
