"""A pattern to DXF in the AAMA layout (``tailor export-pattern --format dxf-aama``), so a pattern
goes to pattern-making CAD and comes back with ``tailor import`` (:mod:`tailor.io.dxf`).

Per panel one block, inserted side by side in model space, in millimetres (``Units: METRIC``):
the outline and its holes on layer 1 (each edge sampled every :data:`SAMPLE_MM`), its corners as
turn points (layer 2) and the samples of curved edges as curve points (layer 3), the grain line
(layer 7), ``Piece Name:``, ``Quantity: 1`` and ``Category:`` texts, and **notches** (layer 4)
that say which sides are sewn together, as CAD does: seam k puts 1 + k mod 4 notches on both of
its sides, at fractions (j + 1) / (n + 1) + 0.03·(1 + k div 4) of each side, measured from the
ends that meet (a seam's sides run so that the points at equal fractions meet); :mod:`tailor.io.dxf_pattern` pairs sides by them. A seam on part of an edge gets
turn points where it starts and ends: in the DXF that stretch is a side of its own. The panel's
marks go with it (drill holes, internal and mirror lines; not its notches: the seam codes are).
"""

from __future__ import annotations

import numpy as np

from ..curves import sample_curve
from ..errors import PatternError
from .atomic import atomic_path
from .dxf import quiet_ezdxf

__all__ = ["write_dxf", "seam_notch_fractions", "SAMPLE_MM"]

SAMPLE_MM = 5.0
"""Largest distance between two points of a curved edge written to the DXF [mm]."""


def seam_notch_fractions(k: int) -> np.ndarray:
    """Fractions along a side, from the end where it meets its partner, of seam ``k``'s notches."""
    n = 1 + k % 4
    return (np.arange(1, n + 1) / (n + 1) + 0.03 * (1 + k // 4)) % 1.0


def _marks(pattern):
    """({(panel, hole, edge): notch fractions along the edge}, {(panel, hole, edge): turn fractions
    inside it}): each seam's notches on both its sides, and where a seam on part of an edge starts
    and ends (a turn point there makes that stretch a side of its own in the DXF)."""
    notches, turns = {}, {}
    for k, seam in enumerate(pattern.seams):
        f = seam_notch_fractions(k)  # the point at f along side a meets the point at f along side b
        for side in (seam.a, seam.b):
            key = (side.panel, side.hole, side.edge)
            notches.setdefault(key, []).extend(side.start + f * (side.end - side.start))
            turns.setdefault(key, set()).update(t for t in (side.lo, side.hi) if 1e-9 < t < 1 - 1e-9)
    return notches, turns


def _edge_points(edge, splits, mm):
    """Points of an edge from its start (included) to its end (excluded), at most SAMPLE_MM apart
    when curved, with the points at the fractions ``splits``; and which of them are turn points."""
    n = 1 if edge.curve.kind == "straight" else max(1, int(np.ceil(edge.length * mm / SAMPLE_MM)))
    fractions = np.union1d(np.linspace(0.0, 1.0, n + 1), list(splits))
    turn = np.isin(fractions, [0.0, *splits])
    return sample_curve(edge.curve, fractions[:-1]), turn[:-1]


def _loop(block, edges, key, marks, mm):
    """One loop (outline or hole) of a panel: boundary, turn and curve points, notches."""
    notches, turns = marks
    pts = []
    for i, e in enumerate(edges):
        line, turn = _edge_points(e, sorted(turns.get((*key, i), ())), mm)
        for p, t in zip(line, turn):
            block.add_point(tuple(p * mm), dxfattribs={"layer": "2" if t else "3"})
        pts.append(line)
        for f in notches.get((*key, i), ()):
            block.add_point(tuple(sample_curve(e.curve, [f])[0] * mm), dxfattribs={"layer": "4"})
    block.add_lwpolyline([tuple(p) for p in np.concatenate(pts) * mm], close=True, dxfattribs={"layer": "1"})
    return np.concatenate(pts).min(axis=0)


def _placement_text(panel, origin) -> list:
    """``Tailor Placement: {json}`` of a body-relative placement (anchor in cm from ``origin``, the
    low corner of the written outline's bounding box, where the importer puts the panel's origin):
    other readers ignore it, tailor's import places the panel as it was."""
    import json
    import math

    from ..pattern import LandmarkPlacement

    pl = panel.placement
    if not isinstance(pl, LandmarkPlacement):
        return []
    anchor = None if pl.anchor is None else [round((a - o) * 100, 4) for a, o in zip(pl.anchor, origin)]
    value = {"landmark": pl.landmark, "angle": round(math.degrees(pl.angle), 6), "offset": round(pl.offset * 100, 4),
             "clearance": round(pl.clearance * 100, 4), **({"anchor": anchor} if anchor is not None else {})}
    return [f"Tailor Placement: {json.dumps(value)}"]


def _write_marks(block, marks, mm) -> None:
    """A panel's drill holes (layer 13), internal (8) and mirror lines (6). Its notches are not
    written: the seams' notch codes are, and another notch on a seam's side would hide its code."""
    layers = {"drill_hole": "13", "internal_line": "8", "mirror_line": "6"}
    for kind, pts in marks:
        p = np.asarray(pts) * mm
        if kind == "drill_hole":
            block.add_circle(tuple(p[0]), 2.0, dxfattribs={"layer": layers[kind]})
        elif kind in layers:
            block.add_line(tuple(p[0]), tuple(p[1]), dxfattribs={"layer": layers[kind]})


def write_dxf(pattern, path) -> None:
    """Write ``pattern`` as an AAMA DXF at ``path`` (atomically)."""
    try:
        import ezdxf
    except ImportError:
        raise PatternError(f"{path}: writing DXF needs ezdxf: pip install -e \".[dxf]\" (or pip install ezdxf)") from None
    quiet_ezdxf()
    mm = 1000.0
    doc = ezdxf.new("R2000")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    msp.add_text("Units: METRIC", dxfattribs={"layer": "1"})
    marks = _marks(pattern)
    x = 0.0
    for k, panel in enumerate(pattern.panels):
        block = doc.blocks.new(f"PIECE{k}")
        outline_min = _loop(block, panel.edges, (panel.name, None), marks, mm)
        for h, hole in enumerate(panel.holes):
            _loop(block, hole, (panel.name, h), marks, mm)
        v = np.asarray(panel.vertices) * mm
        lo, hi = v.min(axis=0), v.max(axis=0)
        centre, reach = 0.5 * (lo + hi), 0.25 * float((hi - lo).min())
        d = np.array([np.cos(panel.grain), np.sin(panel.grain)]) * reach
        block.add_line(tuple(centre - d), tuple(centre + d), dxfattribs={"layer": "7"})
        _write_marks(block, panel.marks, mm)
        for text in (f"Piece Name: {panel.name}", "Quantity: 1", f"Category: {panel.label or 'piece'}",
                     *_placement_text(panel, outline_min)):
            block.add_text(text, dxfattribs={"layer": "15"})
        msp.add_blockref(f"PIECE{k}", (x - lo[0], -lo[1]))
        x += float(hi[0] - lo[0]) + 50.0
    with atomic_path(path) as tmp:
        doc.saveas(tmp)
