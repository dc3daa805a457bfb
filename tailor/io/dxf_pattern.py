"""DXF pieces (:mod:`tailor.io.dxf`) to a tailor pattern: edges, suggested seams, placement.

**Edges.** A piece's outline is cut at its turn points into sides; a side with points between
its ends becomes one cubic Bézier edge (least squares through them, ends fixed), else a straight
edge.

**Seams** (DXF has none). Notches mark where two pieces are sewn: a side with notches is sewn to
the side of another piece with the same length (within :data:`SEAM_LENGTH_TOLERANCE`) and its
notches at the same distances from the end they meet at (within :data:`NOTCH_TOLERANCE_CM`),
the two running in opposite directions as two outlines wound alike do. Where several sides fit,
pieces named as counterparts (front/back, left/right, a piece and its mirrored copy) go first.
Sides without notches (hems, waists, necklines) stay open.

**Placement** from piece names and categories: skirt pieces and gores round the waist, bodice
fronts and backs round the chest, waistbands above the waist, sleeves round the upper arms, at the
front (0°) or back (180°), to the body's left (+) or right (−); a skirt with no waistband is held
at the waist by its top edges.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from .dxf import Piece

__all__ = ["pieces_to_pattern", "SEAM_LENGTH_TOLERANCE", "NOTCH_TOLERANCE_CM"]

SEAM_LENGTH_TOLERANCE = 0.01
"""Two sides are sewn together only if their lengths differ by at most this fraction."""

NOTCH_TOLERANCE_CM = 1.0
"""... and their notches lie this close to each other's, measured from the ends that meet."""

STRAIGHT_CM = 0.05
"""A side whose points all lie this close to its chord is a straight edge."""


@dataclass
class _Side:
    piece: int
    index: int
    points: np.ndarray  # (K, 2) from its start corner to its end corner
    length: float
    notches: np.ndarray  # distances of its notches from its start [cm], increasing


def _mirrored(p: Piece) -> Piece:
    """The other piece of a pair: mirrored across the y axis, still counter-clockwise."""
    flip = np.array([-1.0, 1.0])
    order = np.roll(np.arange(len(p.outline))[::-1], 1)
    return Piece(f"{p.name}_2", p.outline[order] * flip, p.corners[order], (180.0 - p.grain) % 180.0,
                 p.notches * flip, 1, p.size, p.category)


def _sides(k: int, p: Piece) -> list:
    corners = np.flatnonzero(p.corners)
    out = []
    for s, a in enumerate(corners):
        b = corners[(s + 1) % len(corners)]
        idx = np.arange(a, b + 1) if b > a else np.concatenate([np.arange(a, len(p.outline)), np.arange(0, b + 1)])
        pts = p.outline[idx]
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        along = np.concatenate([[0.0], np.cumsum(seg)])
        found = [at for d, at in (_project(pts, along, n) for n in p.notches)
                 if d < 0.3 and 1e-6 < at < along[-1] - 1e-6]  # notches on this side, by distance along it
        out.append(_Side(k, s, pts, float(along[-1]), np.sort(found)))
    return out


def _project(pts, along, q):
    """(distance, arc length along the polyline ``pts``) of the point of the polyline nearest ``q``."""
    a, b = pts[:-1], pts[1:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    d = np.linalg.norm(a + t[:, None] * ab - q, axis=1)
    j = int(np.argmin(d))
    return float(d[j]), float(along[j] + t[j] * np.linalg.norm(ab[j]))


def _edge(points, start: int, end: int) -> dict:
    """The edge from vertex ``start`` to ``end`` through ``points``, with relative cubic curvature."""
    edge = {"endpoints": [start, end]}
    p0, p3 = points[0], points[-1]
    chord = p3 - p0
    length = float(np.linalg.norm(chord))
    inner = points[1:-1]
    if not len(inner) or length < 1e-9:
        return edge
    normal = np.array([-chord[1], chord[0]]) / length
    if np.abs((inner - p0) @ normal).max() < STRAIGHT_CM:
        return edge
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    t = t / t[-1]
    b = np.column_stack([(1 - t) ** 3, 3 * (1 - t) ** 2 * t, 3 * (1 - t) * t ** 2, t ** 3])
    rhs = points - np.outer(b[:, 0], p0) - np.outer(b[:, 3], p3)
    ctrl, *_ = np.linalg.lstsq(b[:, 1:3], rhs, rcond=None)
    rel = [[round(float((c - p0) @ chord / length ** 2), 5), round(float((c - p0) @ normal / length), 5)] for c in ctrl]
    edge["curvature"] = {"type": "cubic", "params": rel}
    return edge


def _words(piece: Piece) -> set:
    return set(re.findall(r"[a-z]+", f"{piece.name} {piece.category}".lower()))


def _counterparts(a: Piece, b: Piece) -> int:
    """How surely two pieces are sewn together by their names: 3 for the front and back of one side
    (a side seam), 2 for the left and right of one face (a centre seam) or a piece and its mirrored
    copy, 0 otherwise."""
    wa, wb = _words(a), _words(b)
    sides = {"left", "right"}
    front_back = ("front" in wa and "back" in wb) or ("back" in wa and "front" in wb)
    if front_back and (wa & sides) and (wa & sides) == (wb & sides):
        return 3
    if a.name + "_2" == b.name or b.name + "_2" == a.name:
        return 2
    if front_back or (("left" in wa and "right" in wb) or ("right" in wa and "left" in wb)):
        return 2
    return 0


def _fits(a: _Side, b: _Side) -> bool:
    if a.piece == b.piece or not len(a.notches) or len(a.notches) != len(b.notches):
        return False
    if abs(a.length - b.length) > SEAM_LENGTH_TOLERANCE * max(a.length, b.length):
        return False
    # running in opposite directions: a's notch at distance s from its start meets b's at s from b's end
    return bool(np.all(np.abs(a.notches - (b.length - b.notches[::-1])) <= NOTCH_TOLERANCE_CM))


def _seams(pieces, sides) -> list:
    """Pairs of sides to sew, counterparts first, each side used once."""
    flat = [s for ss in sides for s in ss]
    pairs = [(a, b) for i, a in enumerate(flat) for b in flat[i + 1:] if _fits(a, b)]
    pairs.sort(key=lambda ab: (-_counterparts(pieces[ab[0].piece], pieces[ab[1].piece]), abs(ab[0].length - ab[1].length)))
    used, out = set(), []
    for a, b in pairs:
        if (a.piece, a.index) not in used and (b.piece, b.index) not in used:
            used |= {(a.piece, a.index), (b.piece, b.index)}
            out.append((a, b))
    return out


def _placement(piece: Piece, corners, has_band: bool):
    """(placement dict, hold the top at the waist) from the piece's name and category."""
    w = _words(piece)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    side = 1.0 if "left" in w else -1.0 if "right" in w else 0.0
    base = 180.0 if "back" in w else 0.0
    turn = 45.0 if ("front" in w or "back" in w) else 90.0
    angle = base + (side * turn if base == 0.0 else -side * turn)
    top = [round(float(0.5 * (lo[0] + hi[0])), 2), round(float(hi[1]), 2)]
    if w & {"waistband", "band", "wb"}:
        return {"landmark": "waist", "angle": angle, "anchor": top, "offset": 2.5, "clearance": 1}, False
    if w & {"sleeve"}:
        limb = "right_upper_arm" if "right" in w else "left_upper_arm"
        return {"landmark": limb, "angle": base, "anchor": top, "offset": 5, "clearance": 2}, False
    if w & {"bodice", "top", "shirt", "blouse", "yoke", "dress"}:
        anchor = [top[0], round(float(lo[1] + 0.7 * (hi[1] - lo[1])), 2)]
        return {"landmark": "chest", "angle": angle, "anchor": anchor, "offset": 0, "clearance": 2}, False
    return {"landmark": "waist", "angle": angle, "anchor": top, "offset": -1, "clearance": 2}, not has_band


def _top_side(sides, corners_ids) -> int:
    """The side without notches whose middle is highest (a skirt's waist)."""
    free = [s for s in sides if not len(s.notches)] or sides
    return max(free, key=lambda s: s.points[len(s.points) // 2][1]).index


def pieces_to_pattern(pieces, name: str, *, seams: str = "auto") -> tuple[dict, list]:
    """(pattern dict in tailor's JSON layout, notes) from DXF pieces; ``seams`` ``auto`` or ``none``."""
    expanded = []
    for p in pieces:
        expanded.append(p)
        if p.quantity >= 2:
            expanded.append(_mirrored(p))
    names = [p.name for p in expanded]
    if len(set(names)) < len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        expanded = [Piece(f"{p.name}_{i}" if p.name in dup else p.name, p.outline, p.corners, p.grain, p.notches,
                          1, p.size, p.category) for i, p in enumerate(expanded)]
    sides = [_sides(k, p) for k, p in enumerate(expanded)]
    has_band = any(_words(p) & {"waistband", "band", "wb"} for p in expanded)
    panels, attachments = {}, []
    for p, ss in zip(expanded, sides):
        corners = p.outline[p.corners] - p.outline.min(axis=0)
        ids = np.arange(len(corners))
        edges = [_edge(s.points - p.outline.min(axis=0), int(i), int((i + 1) % len(corners))) for i, s in zip(ids, ss)]
        placement, hold = _placement(p, corners, has_band)
        panels[p.name] = {"vertices": np.round(corners, 3).tolist(), "edges": edges, "grain": round(p.grain, 3),
                          "label": p.category or "piece", "placement": placement}
        if hold:
            attachments.append({"panel": p.name, "edge": _top_side(ss, ids), "to": "waist"})
    stitches = []
    if seams == "auto":
        for a, b in _seams(expanded, sides):
            stitches.append({"between": [{"panel": expanded[a.piece].name, "edge": a.index},
                                         {"panel": expanded[b.piece].name, "edge": b.index}], "orientation": "opposite"})
    notes = [f"{len(expanded)} pieces ({', '.join(p.name for p in expanded)}), {len(stitches)} seams suggested"]
    open_notched = sum(1 for ss in sides for s in ss if len(s.notches)) - 2 * len(stitches)
    if seams == "auto" and open_notched:
        notes.append(f"{open_notched} notched sides found no partner of the same length and notches: left open")
    pattern = {"name": name, "description": f"imported from {name}.dxf", "fabric": "cotton",
               "pattern": {"panels": panels, "stitches": stitches, "attachments": attachments},
               "properties": {"units_in_meter": 100, "curvature_coords": "relative"}}
    return pattern, notes
