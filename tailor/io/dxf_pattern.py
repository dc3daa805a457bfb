"""DXF pieces (:mod:`tailor.io.dxf`) to a tailor pattern: edges, suggested seams, placement.

**Edges.** A piece's outline is cut at its turn points into sides; a side with points between
its ends becomes a circular arc if they lie on one, else one cubic Bézier edge (least squares
through them, ends fixed); a side without is a straight edge.

**Seams** (DXF has none). Notches mark where two pieces are sewn: a side with notches is sewn to
the side of another piece with the same length (within :data:`SEAM_LENGTH_TOLERANCE`) and its
notches at the same distances from the end they meet at (within :data:`NOTCH_TOLERANCE_CM`),
the two running in opposite directions as two outlines wound alike do. Where several sides fit,
pieces named as counterparts (front/back, left/right, a piece and its mirrored copy) go first.
Sides without notches (hems, waists, necklines) stay open.

**Placement** from piece names and categories (:data:`PLACEMENTS`): waistbands above the waist,
collars round the neck, cuffs round the wrists, sleeves round the upper arms, trouser legs round
the thighs, bodices round the chest, skirt pieces, gores and the rest round the waist; at the front
(0°) or back (180°), to the body's left (+) or right (−). Waistbands, and the pieces of a skirt
alone (no waistband, no bodice), are held at the waist by their top edges.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from ..errors import PatternError
from .dxf import Piece, nearest_on_polyline

__all__ = ["pieces_to_pattern", "SEAM_LENGTH_TOLERANCE", "NOTCH_TOLERANCE_CM"]

SEAM_LENGTH_TOLERANCE = 0.01
"""Two sides are sewn together only if their lengths differ by at most this fraction."""

NOTCH_TOLERANCE_CM = 1.0
"""... and their notches lie this close to each other's, measured from the ends that meet."""

EASE = 0.25
"""A side eased onto a longer one (a sleeve cap) may be this much shorter, its notches then at the
same fractions of both (within :data:`NOTCH_FRACTION_TOLERANCE`)."""

NOTCH_FRACTION_TOLERANCE = 0.004

STRAIGHT_CM = 0.05
"""A side whose points all lie this close to its chord is a straight edge."""


@dataclass
class _Side:
    piece: int
    hole: int | None
    index: int
    points: np.ndarray  # (K, 2) from its start corner to its end corner
    length: float
    notches: np.ndarray  # distances of its notches from its start [cm], increasing

    @property
    def key(self):
        return self.piece, self.hole, self.index


def _mirrored(p: Piece) -> Piece:
    """The other piece of a pair: mirrored across the y axis, still counter-clockwise."""
    flip = np.array([-1.0, 1.0])
    def flipped(points, corners):
        order = np.roll(np.arange(len(points))[::-1], 1)
        return points[order] * flip, corners[order]

    outline, corners = flipped(p.outline, p.corners)
    return Piece(f"{p.name}_2", outline, corners, (180.0 - p.grain) % 180.0, p.notches * flip, 1, p.size, p.category,
                 [flipped(h, c) for h, c in p.holes], [(kind, pts * flip) for kind, pts in p.marks])


def _sides(k: int, p: Piece) -> list:
    """The sides of every loop of piece ``k`` (outline, then holes): runs between turn points."""
    out = []
    for hole, (loop, flags) in [(None, (p.outline, p.corners)), *enumerate(p.holes)]:
        corners = np.flatnonzero(flags)
        for s, a in enumerate(corners):
            b = corners[(s + 1) % len(corners)]
            idx = np.arange(a, b + 1) if b > a else np.concatenate([np.arange(a, len(loop)), np.arange(0, b + 1)])
            pts = loop[idx]
            along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
            found = [at for d, at in (nearest_on_polyline(pts, n) for n in p.notches)
                     if d < 0.3 and 1e-6 < at < along[-1] - 1e-6]  # notches on this side, by distance along it
            out.append(_Side(k, hole, s, pts, float(along[-1]), np.sort(found)))
    return out


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
    arc = _circle(points)
    if arc is not None:
        edge["curvature"] = {"type": "circle", "params": arc}
        return edge
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    t = t / t[-1]
    b = np.column_stack([(1 - t) ** 3, 3 * (1 - t) ** 2 * t, 3 * (1 - t) * t ** 2, t ** 3])
    rhs = points - np.outer(b[:, 0], p0) - np.outer(b[:, 3], p3)
    ctrl, *_ = np.linalg.lstsq(b[:, 1:3], rhs, rcond=None)
    rel = [[round(float((c - p0) @ chord / length ** 2), 5), round(float((c - p0) @ normal / length), 5)] for c in ctrl]
    edge["curvature"] = {"type": "cubic", "params": rel}
    return edge


def _circle(points):
    """``[radius, large_arc, sweep]`` (SVG-style, as the pattern format's circle edges) if the points
    lie on one circular arc within :data:`STRAIGHT_CM`, else None (a least-squares circle fit)."""
    x, y = points[:, 0], points[:, 1]
    a = np.column_stack([x, y, np.ones(len(x))])
    (cx2, cy2, c), *_ = np.linalg.lstsq(a, x * x + y * y, rcond=None)
    centre = np.array([cx2 / 2, cy2 / 2])
    radius = float(np.sqrt(max(c + centre @ centre, 0.0)))
    if len(points) < 4 or radius <= 0 or np.abs(np.linalg.norm(points - centre, axis=1) - radius).max() > STRAIGHT_CM:
        return None
    rel = points - centre
    turn = np.arctan2(rel[:-1, 0] * rel[1:, 1] - rel[:-1, 1] * rel[1:, 0], np.einsum("ij,ij->i", rel[:-1], rel[1:]))
    swept = float(turn.sum())
    return [round(radius, 4), int(abs(swept) > np.pi), int(swept > 0)]


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


def _fits(a: _Side, b: _Side) -> str | None:
    """How ``a`` and ``b`` are sewn (``opposite``: a's start meets b's end; ``same``), or None.

    Equal lengths and notches at the same distances from the ends that meet; or, for a side eased
    onto a longer one (up to :data:`EASE`), notches at the same fractions of each side."""
    if a.key == b.key or not len(a.notches) or len(a.notches) != len(b.notches):
        return None
    ratio = min(a.length, b.length) / max(a.length, b.length)
    for orientation, bn in (("opposite", b.length - b.notches[::-1]), ("same", b.notches)):
        if ratio >= 1 - SEAM_LENGTH_TOLERANCE and np.all(np.abs(a.notches - bn) <= NOTCH_TOLERANCE_CM):
            return orientation
        if ratio >= 1 - EASE and np.all(np.abs(a.notches / a.length - bn / b.length) <= NOTCH_FRACTION_TOLERANCE):
            return orientation
    return None


def _seams(pieces, sides) -> list:
    """(side, side, orientation) to sew, counterparts first, each side used once."""
    flat = [s for ss in sides for s in ss]
    pairs = [(a, b, how) for i, a in enumerate(flat) for b in flat[i + 1:] if (how := _fits(a, b))]
    pairs.sort(key=lambda ab: (-_counterparts(pieces[ab[0].piece], pieces[ab[1].piece]), abs(ab[0].length - ab[1].length)))
    used, out = set(), []
    for a, b, how in pairs:
        if a.key not in used and b.key not in used:
            used |= {a.key, b.key}
            out.append((a, b, how))
    return out


PLACEMENTS = (
    # (words, landmark, limb (left_/right_ by the name), angle: "around" the body or "side" of a limb,
    #  anchor height as a fraction of the piece from its bottom ("widest": its widest row, a trouser
    #  leg's crotch), offset [cm], clearance [cm])
    ({"waistband", "band", "wb"}, "waist", False, "around", 1.0, 2.5, 1),
    ({"collar"}, "neck", False, "around", 1.0, 2.0, 1),
    ({"cuff"}, "wrist", True, "side", 1.0, 0.0, 1),
    ({"sleeve"}, "upper_arm", True, "side", 0.6, 8.0, 2),
    ({"skirt", "gore"}, "waist", False, "around", 1.0, -1.0, 2),
    ({"leg", "trouser", "trousers", "pant", "pants"}, "thigh", True, "front", "widest", 0.0, 2),
    ({"bodice", "top", "shirt", "blouse", "yoke", "dress", "torso", "body"}, "chest", False, "around", 0.7, 0.0, 2),
)
"""Where pieces go by the words of their name and category (the first rule that matches; none:
round the waist, top at the waist): body-relative placements of the pattern format."""


def _widest_row(corners) -> float:
    """Height of the outline's widest horizontal row through one of its corners."""
    from shapely.geometry import LineString, Polygon

    poly = Polygon(corners)
    lo, hi = corners[:, 0].min() - 1.0, corners[:, 0].max() + 1.0
    width = [(poly.intersection(LineString([(lo, y), (hi, y)])).length, y) for y in np.unique(corners[:, 1])]
    return float(max(width)[1])


def _placement(piece: Piece, corners, skirt_only: bool):
    """(placement dict, hold the top at the waist) from the piece's name and category."""
    w = _words(piece)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    side = 1.0 if "left" in w else -1.0 if "right" in w else 0.0
    base = 180.0 if "back" in w else 0.0
    turn = 45.0 if ("front" in w or "back" in w) else 90.0
    around = base + (side * turn if base == 0.0 else -side * turn)
    centre = round(float(0.5 * (lo[0] + hi[0])), 2)
    for words, landmark, limb, how, height, offset, clearance in PLACEMENTS:
        if w & words:
            name = (("right_" if "right" in w else "left_") + landmark) if limb else landmark
            angle = {"around": around, "front": base, "side": 90.0 * (side or 1.0)}[how]
            y = _widest_row(corners) if height == "widest" else float(lo[1] + height * (hi[1] - lo[1]))
            hold = (landmark == "waist") and (bool(w & {"waistband", "band", "wb"}) or skirt_only)
            return {"landmark": name, "angle": angle, "anchor": [centre, round(y, 2)], "offset": offset,
                    "clearance": clearance}, hold
    top = [centre, round(float(hi[1]), 2)]
    return {"landmark": "waist", "angle": around, "anchor": top, "offset": -1, "clearance": 2}, False


def _loop_dict(corners, sides, origin) -> dict:
    """``{"vertices", "edges"}`` of one loop, its sides in order."""
    n = len(corners)
    return {"vertices": np.round(corners, 3).tolist(),
            "edges": [_edge(s.points - origin, i, (i + 1) % n) for i, s in enumerate(sides)]}


def _marks_dict(marks, origin) -> dict:
    """``{"marks": {"notches": [...], ...}}`` in panel coordinates (empty if none)."""
    keys = {"notch": "notches", "drill_hole": "drill_holes", "internal_line": "internal_lines",
            "mirror_line": "mirror_lines"}
    out: dict = {}
    for kind, pts in marks:
        rel = np.round(np.asarray(pts) - origin, 3).tolist()
        out.setdefault(keys[kind], []).append(rel[0] if len(rel) == 1 else rel)
    return {"marks": out} if out else {}


def _side_ref(pieces, side: _Side) -> dict:
    ref = {"panel": pieces[side.piece].name, "edge": side.index}
    return {**ref, "hole": side.hole} if side.hole is not None else ref


def _top_side(sides) -> int:
    """The side without notches whose middle is highest (a skirt's waist)."""
    free = [s for s in sides if not len(s.notches)] or sides
    return max(free, key=lambda s: s.points[len(s.points) // 2][1]).index


def _sidecar_side(ref, where, pieces, sides):
    """The side a sidecar names: ``{"piece": name, "edge": i}`` (the i-th side of its outline) or
    ``{"piece": name, "notch": n}`` (the side holding its n-th notch, counted from 1 along the outline)."""
    names = [p.name for p in pieces]
    if not isinstance(ref, dict) or ref.get("piece") not in names or ("edge" in ref) == ("notch" in ref):
        raise PatternError(f"{where}: expected {{\"piece\": one of {names}, \"edge\": i}} or {{..., \"notch\": n}}, got {ref!r}")
    own = [s for s in sides[names.index(ref["piece"])] if s.hole is None]
    if "edge" in ref:
        if not isinstance(ref["edge"], int) or not 0 <= ref["edge"] < len(own):
            raise PatternError(f"{where}.edge: piece {ref['piece']!r} has sides 0 to {len(own) - 1}, got {ref['edge']!r}")
        return own[ref["edge"]]
    notched = [s for s in own for _ in s.notches]
    n = ref["notch"]
    if not isinstance(n, int) or not 1 <= n <= len(notched):
        raise PatternError(f"{where}.notch: piece {ref['piece']!r} has notches 1 to {len(notched)}, got {n!r}")
    return notched[n - 1]


def _sidecar_seams(sidecar, pieces, sides) -> list:
    """The stitches a sidecar lists (``{"seams": [{"between": [side, side]}, …]}``), oriented by their
    notches where they agree, else ``auto`` (from the placed panels)."""
    doc, source = sidecar
    out = []
    for k, seam in enumerate(doc.get("seams", [])):
        where = f"{source}: seams[{k}]"
        if not isinstance(seam, dict) or not isinstance(seam.get("between"), list) or len(seam["between"]) != 2:
            raise PatternError(f"{where}: expected {{\"between\": [side, side]}}")
        a, b = (_sidecar_side(r, f"{where}.between[{i}]", pieces, sides) for i, r in enumerate(seam["between"]))
        out.append({"between": [_side_ref(pieces, a), _side_ref(pieces, b)], "orientation": _fits(a, b) or "auto"})
    return out


def pieces_to_pattern(pieces, name: str, *, seams: str = "auto", sidecar=None) -> tuple[dict, list]:
    """(pattern dict in tailor's JSON layout, notes) from DXF pieces; ``seams`` ``auto`` or ``none``.

    ``sidecar``: (parsed SEAMS.json, its file name) whose ``seams`` replace the suggested ones and
    whose ``placement`` (piece name → a placement object) overrides the guessed placements."""
    expanded = []
    for p in pieces:
        expanded.append(p)
        if p.quantity >= 2:
            expanded.append(_mirrored(p) if p.mirror else replace(p, name=f"{p.name}_2", quantity=1))
    names = [p.name for p in expanded]
    if len(set(names)) < len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        expanded = [Piece(f"{p.name}_{i}" if p.name in dup else p.name, p.outline, p.corners, p.grain, p.notches,
                          1, p.size, p.category, p.holes, p.marks, p.placement, p.mirror) for i, p in enumerate(expanded)]
    sides = [_sides(k, p) for k, p in enumerate(expanded)]
    # held at the waist by their top edges: waistbands, or the skirt pieces of a skirt alone
    skirt_only = all(_words(p) & {"skirt", "gore"} for p in expanded)
    panels, attachments = {}, []
    for p, ss in zip(expanded, sides):
        origin = p.outline.min(axis=0)
        panel = _loop_dict(p.outline[p.corners] - origin, [s for s in ss if s.hole is None], origin)
        placement, hold = _placement(p, p.outline[p.corners] - origin, skirt_only)
        placement = p.placement or placement  # written by tailor: its own
        holes = [_loop_dict(h[c] - origin, [s for s in ss if s.hole == k], origin) for k, (h, c) in enumerate(p.holes)]
        panels[p.name] = {**panel, **({"holes": holes} if holes else {}), "grain": round(p.grain, 3),
                          "label": p.category or "piece", "placement": placement, **_marks_dict(p.marks, origin)}
        if hold:
            attachments.append({"panel": p.name, "edge": _top_side([s for s in ss if s.hole is None]), "to": "waist"})
    stitches = []
    if sidecar is not None:
        stitches = _sidecar_seams(sidecar, expanded, sides)
        for piece, placement in sidecar[0].get("placement", {}).items():
            if piece not in panels:
                raise PatternError(f"{sidecar[1]}: placement.{piece}: no such piece (pieces: {', '.join(panels)})")
            panels[piece]["placement"] = placement
        seams = "sidecar"
    elif seams == "auto":
        for a, b, how in _seams(expanded, sides):
            stitches.append({"between": [_side_ref(expanded, a), _side_ref(expanded, b)], "orientation": how})
    notes = [f"{len(expanded)} pieces ({', '.join(p.name for p in expanded)}), {len(stitches)} seams "
             + ("from the sidecar" if seams == "sidecar" else "suggested")]
    open_notched = sum(1 for ss in sides for s in ss if len(s.notches)) - 2 * len(stitches)
    if seams != "auto":
        open_notched = 0
    if seams == "auto" and open_notched:
        notes.append(f"{open_notched} notched sides found no partner of the same length and notches: left open")
    pattern = {"name": name, "description": f"imported from {name}.dxf", "fabric": "cotton",
               "pattern": {"panels": panels, "stitches": stitches, "attachments": attachments},
               "properties": {"units_in_meter": 100, "curvature_coords": "relative"}}
    return pattern, notes
