"""Pattern pieces from pattern-making CAD: DXF in the AAMA / ASTM D6673 layout (read with ezdxf).

The conventions readers use (the standard itself is not free): one BLOCK per piece, inserted in
model space; TEXT in the block ``Piece Name: …``, ``Size: …``, ``Quantity: …``, ``Category: …``
and a ``Units: METRIC|ENGLISH`` text (or the header's ``$INSUNITS``); layers by number:

====  ==========================  ===========================================================
1     boundary (cut line)          a closed POLYLINE or LWPOLYLINE (84: ASTM boundary)
2, 3  turn and curve points        POINTs on the boundary: corners, and points of curves
4     notches                      short LINEs (the end on the boundary) or POINTs
7     grain line                   a LINE: the warp direction
6, 8  mirror and internal lines    LINEs, kept as panel marks (85: ASTM internal)
13    drill holes                  CIRCLEs or POINTs, kept as panel marks (5 grade reference and
                                   14 sew lines are listed as ignored)
====  ==========================  ===========================================================

Exporters bend these rules; the reader is lenient and says what it ignored. Without turn
points, a boundary vertex where the outline turns by more than :data:`CORNER_DEG` is a corner.
ENGLISH files are in inches, METRIC in millimetres (the AAMA convention); without that text the
header's ``$INSUNITS`` counts; ``units`` overrides both. :mod:`tailor.io.dxf_pattern` turns the pieces into a pattern.
"""

from __future__ import annotations

import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import PatternError

__all__ = ["Piece", "read_dxf", "quiet_ezdxf", "nearest_on_polyline", "CORNER_DEG", "UNITS_CM"]

CORNER_DEG = 25.0
"""Without turn points, a boundary vertex where the outline turns more than this is a corner."""

UNITS_CM = {"mm": 0.1, "cm": 1.0, "in": 2.54, "m": 100.0}
"""File units to centimetres."""

_INSUNITS = {1: "in", 4: "mm", 5: "cm", 6: "m"}
_BOUNDARY, _TURN, _CURVE, _NOTCH, _GRAIN = ("1", "84"), "2", "3", "4", "7"
_IGNORED = {"14": "sew line", "5": "grade reference"}


@dataclass
class Piece:
    """One pattern piece, in centimetres, its outline counter-clockwise.

    ``corners`` flags the outline points that are turn points (the rest lie on curves);
    ``grain`` is the warp's direction [degrees from +x]; ``notches`` are points on the outline
    or a hole; ``holes`` are (points, corners) of the inner boundaries, wound as drawn.
    """

    name: str
    outline: np.ndarray
    corners: np.ndarray
    grain: float = 90.0
    notches: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    quantity: int = 1
    size: str | None = None
    category: str = ""
    holes: list = field(default_factory=list)
    marks: list = field(default_factory=list)  # (kind, points (k, 2) [cm]) kept from the file
    placement: dict | None = None  # tailor's own placement, when the file was written by tailor
    mirror: bool = True  # quantity 2 is a mirrored pair (a ``Mirror: N`` text: two alike)


def _fail(path, what: str):
    raise PatternError(f"{path}: {what}")


def _open(path: Path):
    """The DXF document (recovering a damaged file)."""
    try:
        import ezdxf
        from ezdxf import recover
    except ImportError:
        _fail(path, "reading DXF needs ezdxf: pip install -e \".[dxf]\" (or pip install ezdxf)")
    if not path.is_file():
        _fail(path, "no such file")
    quiet_ezdxf()
    try:
        doc, _auditor = recover.readfile(str(path))
    except (OSError, ezdxf.DXFStructureError, ValueError, UnicodeDecodeError) as exc:
        _fail(path, f"not a readable DXF file ({str(exc).strip() or type(exc).__name__})")
    return doc


def quiet_ezdxf() -> None:
    """ezdxf narrates every repair and every new document at INFO: warnings only."""
    logging.getLogger("ezdxf").setLevel(logging.WARNING)


def _texts(entities) -> dict:
    """``{"piece name": …, "quantity": …, …}`` from a piece's TEXT and MTEXT (``Key: value``)."""
    out = {}
    for e in entities:
        if e.dxftype() == "TEXT":
            text = e.dxf.text
        elif e.dxftype() == "MTEXT":
            text = e.plain_text()
        else:
            continue
        for line in str(text).splitlines():
            m = re.match(r"\s*([A-Za-z ]+?)\s*:\s*(.*?)\s*$", line)
            if m:
                out[m.group(1).lower()] = m.group(2)
    return out


def _units(doc, entities, override, path, notes) -> float:
    """Centimetres per file unit: ``override``, else the AAMA ``Units:`` text, else the header's
    $INSUNITS (which many writers leave at their default), else millimetres."""
    if override is not None:
        return UNITS_CM[override]
    said = _texts(entities).get("units", "").upper()
    if said.startswith("ENGLISH"):
        return UNITS_CM["in"]
    if said.startswith("METRIC"):
        return UNITS_CM["mm"]
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    if code in _INSUNITS:
        return UNITS_CM[_INSUNITS[code]]
    notes.append("no units in the file (header or 'Units:' text): millimetres assumed (--units to say)")
    return UNITS_CM["mm"]


def _pieces_entities(doc):
    """[(block name, entities in model space)] of every inserted block with a boundary (or of every
    block with one, when nothing is inserted)."""
    msp = doc.modelspace()
    inserts = [e for e in msp if e.dxftype() == "INSERT"]
    if inserts:
        return [(e.dxf.name, list(e.virtual_entities())) for e in inserts]
    return [(b.name, list(b)) for b in doc.blocks if not b.name.startswith("*")
            and any(e.dxf.layer in _BOUNDARY for e in b)]


def _loops(entities, path, name):
    """The boundary's points (K, 2) (closed, without the repeated end) and those of the holes inside it."""
    from ezdxf import path as dxfpath
    from shapely.geometry import Point, Polygon

    found = [e for e in entities if e.dxftype() in ("LWPOLYLINE", "POLYLINE") and e.dxf.layer in _BOUNDARY]
    if not found:
        _fail(path, f"piece {name!r}: no boundary on layer 1 (a closed POLYLINE or LWPOLYLINE)")
    loops = [_clean(np.array([(v.x, v.y) for v in dxfpath.make_path(e).flattening(0.1)], float)) for e in found]
    loops = [p for p in loops if len(p) >= 3]
    if not loops or max(abs(_area(p)) for p in loops) < 1e-12:
        _fail(path, f"piece {name!r}: the layer 1 boundary encloses no area (or crosses itself)")
    loops.sort(key=lambda p: -abs(_area(p)))
    outer = Polygon(loops[0])
    holes = [p for p in loops[1:] if abs(_area(p)) > 1e-12 and outer.contains(Point(p.mean(axis=0)))]
    return loops[0], holes


def _clean(pts):
    keep = np.ones(len(pts), bool)
    keep[1:] = np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9
    pts = pts[keep]
    if len(pts) > 1 and np.linalg.norm(pts[0] - pts[-1]) < 1e-9:
        pts = pts[:-1]
    return pts


def _area(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _points(entities, layer):
    return np.array([(e.dxf.location.x, e.dxf.location.y) for e in entities
                     if e.dxftype() == "POINT" and e.dxf.layer == layer], float).reshape(-1, 2)


def _corners(outline, turn, curve) -> np.ndarray:
    """Which outline points are corners: those at a turn point (layer 2), else where it turns sharply."""
    tol = 1e-3 * float(np.ptp(outline, axis=0).max())
    if len(turn):
        d = np.linalg.norm(outline[:, None] - turn[None], axis=2).min(axis=1)
        return d < tol
    a, b = outline - np.roll(outline, 1, axis=0), np.roll(outline, -1, axis=0) - outline
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
    sharp = np.degrees(np.arccos(np.clip(cos, -1, 1))) > CORNER_DEG
    if len(curve):
        sharp &= np.linalg.norm(outline[:, None] - curve[None], axis=2).min(axis=1) >= tol
    return sharp


def _grain(entities) -> float:
    for e in entities:
        if e.dxftype() == "LINE" and e.dxf.layer == _GRAIN:
            d = e.dxf.end - e.dxf.start
            return math.degrees(math.atan2(d.y, d.x)) % 180.0
    return 90.0


def _notches(entities, outline) -> np.ndarray:
    """Notch points: POINTs, or of each short LINE the end nearer the outline."""
    pts = [_points(entities, _NOTCH)]
    for e in entities:
        if e.dxftype() == "LINE" and e.dxf.layer == _NOTCH:
            ends = np.array([(e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y)])
            pts.append(ends[[int(np.argmin([_distance(outline, q) for q in ends]))]])
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def _distance(outline, q) -> float:
    """Distance from point ``q`` to the closed outline."""
    return nearest_on_polyline(np.vstack([outline, outline[:1]]), q)[0]


def nearest_on_polyline(points, q) -> tuple[float, float]:
    """(distance, arc length from the start) of the point of the polyline ``points`` nearest ``q``."""
    a, b = points[:-1], points[1:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    d = np.linalg.norm(a + t[:, None] * ab - q, axis=1)
    j = int(np.argmin(d))
    seg = np.linalg.norm(ab, axis=1)
    return float(d[j]), float(seg[:j].sum() + t[j] * seg[j])


def _piece(name, entities, scale, path) -> Piece:
    texts = _texts(entities)
    label = texts.get("piece name") or name
    outline, holes = _loops(entities, path, label)
    turn, curve = _points(entities, _TURN), _points(entities, _CURVE)
    loops = []
    for k, loop in enumerate([outline, *holes]):
        if k == 0 and _area(loop) < 0:  # the outline counter-clockwise (holes as drawn)
            loop = np.roll(loop[::-1], 1, axis=0)
        corners = _corners(loop, turn, curve)
        if corners.sum() < 2:
            corners[[0, len(loop) // 2]] = True
        loops.append((loop, corners))
    (outline, corners), holes = loops[0], loops[1:]
    try:
        quantity = max(1, int(re.match(r"\s*(\d+)", texts.get("quantity", "1")).group(1)))
    except (AttributeError, ValueError):
        quantity = 1
    _simple(outline, path, label, scale)
    every = np.concatenate([outline, *(h for h, _ in holes)])
    notches = _notches(entities, every) * scale
    marks = [("notch", n[None]) for n in notches] + [(kind, pts * scale) for kind, pts in _marks(entities)]
    return Piece(label.strip(), outline * scale, corners, _grain(entities), notches, quantity, texts.get("size"),
                 texts.get("category", "").strip(), [(h * scale, c) for h, c in holes], marks,
                 _tailor_placement(texts.get("tailor placement")),
                 not texts.get("mirror", "yes").strip().lower().startswith(("n", "0", "false")))


def _simple(outline, path, name, scale) -> None:
    """A one-line error naming the piece, the layer and where, if its boundary crosses itself."""
    from shapely.geometry import LineString, Polygon
    from shapely.validation import explain_validity

    poly = Polygon(outline)
    if LineString(np.vstack([outline, outline[:1]])).is_simple and poly.is_valid:
        return
    why = explain_validity(poly)
    at = re.search(r"\[([-\d.e]+)\s+([-\d.e]+)\]", why)
    where = f" near ({float(at.group(1)) * scale:.1f}, {float(at.group(2)) * scale:.1f}) cm" if at else ""
    _fail(path, f"piece {name!r}: the layer 1 boundary crosses itself{where}")


def _tailor_placement(text):
    """The placement a ``Tailor Placement: {json}`` text carries (anchor in cm from the outline's
    lowest corner of its bounding box, as :mod:`tailor.io.dxf_export` writes it), or None."""
    import json

    try:
        value = json.loads(text) if text else None
    except ValueError:
        return None
    return value if isinstance(value, dict) and "landmark" in value else None


_MARKS = {"13": "drill_hole", "8": "internal_line", "85": "internal_line", "6": "mirror_line"}


def _marks(entities) -> list:
    """(kind, points) of the drill holes (a CIRCLE's centre or a POINT) and internal and mirror LINEs."""
    out = []
    for e in entities:
        kind = _MARKS.get(e.dxf.layer)
        if kind == "drill_hole" and e.dxftype() in ("CIRCLE", "POINT"):
            c = e.dxf.center if e.dxftype() == "CIRCLE" else e.dxf.location
            out.append((kind, np.array([[c.x, c.y]])))
        elif kind in ("internal_line", "mirror_line") and e.dxftype() == "LINE":
            out.append((kind, np.array([[e.dxf.start.x, e.dxf.start.y], [e.dxf.end.x, e.dxf.end.y]])))
    return out


def read_dxf(path, *, units: str | None = None, size: str | None = None):
    """(pieces, notes): every piece of an AAMA/ASTM DXF file in centimetres, and what was ignored.

    ``units`` (``mm``, ``cm``, ``in``, ``m``) overrides the file's; ``size`` picks one size of a
    graded file (default: the first size listed). Raises :class:`PatternError` naming the file
    (and the piece and layer) on a file that cannot be read.
    """
    path = Path(path)
    if units is not None and units not in UNITS_CM:
        _fail(path, f"--units: choose one of {', '.join(UNITS_CM)}, got {units!r}")
    doc = _open(path)
    blocks = _pieces_entities(doc)
    if not blocks:
        _fail(path, "no pattern pieces: no block with a boundary on layer 1 (AAMA/ASTM DXF expected)")
    notes: list = []
    scale = _units(doc, [e for _, ents in blocks for e in ents] + list(doc.modelspace()), units, path, notes)
    pieces = [_piece(name, ents, scale, path) for name, ents in blocks]
    unnamed = [name for name, ents in blocks if "piece name" not in _texts(ents)]
    if unnamed:
        notes.append(f"no 'Piece Name:' text: named after their blocks: {', '.join(unnamed)}")
    ignored = sorted({f"{_IGNORED[e.dxf.layer]} (layer {e.dxf.layer})" for _, ents in blocks for e in ents
                      if e.dxf.layer in _IGNORED})
    if ignored:
        notes.append("ignored: " + ", ".join(ignored))
    return _one_size(pieces, size, path, notes), notes


def _one_size(pieces, size, path, notes):
    sizes = list(dict.fromkeys(p.size for p in pieces if p.size))
    if size is not None and size not in sizes:
        _fail(path, f"--size {size}: the file has sizes {', '.join(sizes) or '(none)'}")
    if len(sizes) <= 1 and size is None:
        return pieces
    chosen = size or sizes[0]
    if size is None:
        notes.append(f"sizes {', '.join(sizes)} in the file: size {chosen} read (--size to choose)")
    return [p for p in pieces if p.size in (None, chosen)]
