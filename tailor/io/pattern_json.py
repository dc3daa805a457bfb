"""Read pattern files: GarmentCode's specification JSON plus tailor's extensions.

The only place where pattern units are converted: lengths by ``properties.units_in_meter``
(default 100, i.e. cm), angles from degrees, fabric from g/m², % and mm, and GarmentCode's
world frame (Y up, facing +Z, cm) into tailor's (Z up, facing −Y, m):
``p_tailor = (x, −z, y) / units_in_meter``. ``docs/pattern-format.md`` documents the format.

Examples
--------
>>> doc = {"pattern": {"panels": {"square": {
...     "vertices": [[0, 0], [100, 0], [100, 100], [0, 100]],
...     "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]},
...               {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}}}}
>>> p = pattern_from_dict(doc, source="flag.json")
>>> round(p.area, 6)
1.0
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..curves import Curve, sample_curve
from ..errors import FabricError, PatternError
from ..fabric import DEFAULT_FABRIC, Fabric, KawabataCurves, fabric_names, preset
from ..landmarks import LANDMARKS
from ..pattern import (
    ATTACHMENT_TARGETS,
    Attachment,
    Edge,
    LandmarkPlacement,
    Panel,
    Pattern,
    Seam,
    SeamSide,
    TransformPlacement,
    WAIST_LABEL,
    validate_pattern,
)
from ..units import DEG, G_PER_M2, MM, PERCENT
from ._fields import Node

__all__ = ["read_pattern", "pattern_from_dict", "reshaped_document", "GARMENTCODE_TO_TAILOR"]

GARMENTCODE_TO_TAILOR = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""Maps GarmentCode's world (Y up, facing +Z) to tailor's (Z up, facing −Y): (x, y, z) → (x, −z, y)."""

_TOP = {"pattern", "properties", "parameters", "parameter_order", "fabric", "name", "description", "layer"}
_PATTERN = {"panels", "stitches", "panel_order", "attachments"}
_PROPERTIES = {"units_in_meter", "curvature_coords", "normalize_panel_translation", "normalized_edge_loops"}
_PANEL = {"vertices", "edges", "translation", "rotation", "label", "holes", "grain", "fabric", "placement", "marks"}
_HOLE = {"vertices", "edges"}
_EDGE = {"endpoints", "curvature", "label"}
_CURVATURE = {"type", "params"}
_SIDE = {"panel", "edge", "hole", "range"}
_STITCH = {"between", "orientation", "label"}
_ATTACH = {"panel", "edge", "vertex", "hole", "range", "to"}
_PLACEMENT = {"landmark", "angle", "anchor", "offset", "clearance"}
_FABRIC = {"preset", "density", "stretch", "stretch_weft", "bending", "friction", "thickness", "kawabata", "tear_strain",
           "wearable_stretch"}
_KAWABATA = {"tensile_warp", "tensile_weft", "shear", "bending"}
# file units of each Kawabata curve → SI: (deformation, load) scale factors
_KAWABATA_UNITS = {
    "tensile_warp": (PERCENT, 1.0),  # [% strain, N/m]
    "tensile_weft": (PERCENT, 1.0),
    "shear": (DEG, 1.0),  # [degrees, N/m]
    "bending": (100.0, 1.0),  # [1/cm, N·m/m]
}
_ORIENTATIONS = ("auto", "opposite", "same")
_DECISIVE = 0.1  # placement must separate the two pairings by 10 % of the seam length


def read_pattern(path, *, validate: bool = True) -> Pattern:
    """Read and validate a pattern file.

    Parameters
    ----------
    path : str or Path
        A JSON pattern file (GarmentCode specification JSON or tailor's superset).
    validate : bool
        Also run :func:`tailor.pattern.validate_pattern` (geometry and seams).

    Returns
    -------
    Pattern
        In SI units and tailor's world frame.

    Raises
    ------
    PatternError
        With a one-line message ``FILE: FIELD: what is wrong``.
    """
    path = Path(path)
    source = path.name
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise PatternError(f"{path}: no such pattern file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PatternError(f"{path}: cannot read: {exc}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PatternError(f"{source}: line {exc.lineno} column {exc.colno}: malformed JSON: {exc.msg}") from None
    except RecursionError:
        raise PatternError(f"{source}: malformed JSON: nested too deeply") from None
    return pattern_from_dict(doc, source=source, name=path.stem, validate=validate)


def pattern_from_dict(doc, *, source: str = "<pattern>", name: str | None = None, validate: bool = True) -> Pattern:
    """Build a :class:`Pattern` from a parsed JSON document (see :func:`read_pattern`)."""
    root = Node(doc, "", source)
    root.as_object(_TOP)
    props = root.key("properties", {})
    props.as_object(_PROPERTIES)
    units = props.key("units_in_meter", 100).as_number(positive=True)
    scale = 1.0 / units
    relative = props.key("curvature_coords", "relative").as_str(("relative", "absolute")) == "relative"
    if root.has("name"):
        name = root.key("name").as_str()
    fabric = _fabric(root.key("fabric", DEFAULT_FABRIC))
    layer = root.key("layer").as_int(what="layer") if root.has("layer") else 0

    pat = root.key("pattern")
    pat.as_object(_PATTERN)
    panels_node = pat.key("panels")
    if not panels_node.as_object():
        panels_node.fail("a pattern needs at least one panel")
    panels = tuple(_panel(str(k), n, scale, relative) for k, n in panels_node.entries())
    by_name = {p.name: p for p in panels}
    stitches = pat.key("stitches", [])
    seams = tuple(_seam(n, i, by_name) for i, n in enumerate(stitches.items()))
    if pat.has("attachments"):
        attachments = tuple(_attachment(n, i, by_name) for i, n in enumerate(pat.key("attachments").items()))
    else:
        attachments = _waist_holds(panels, seams)
    pattern = Pattern(
        name=name or "pattern",
        panels=panels,
        seams=seams,
        attachments=attachments,
        fabric=fabric,
        source=source,
        layer=layer,
    )
    return validate_pattern(pattern) if validate else pattern


# -- fabric -------------------------------------------------------------------------------
def _fabric(node: Node) -> Fabric:
    if isinstance(node.value, str):
        return _checked(node, lambda: preset(node.value))
    node.as_object(_FABRIC)
    base_name = node.key("preset", DEFAULT_FABRIC).as_str(fabric_names())
    base = preset(base_name)
    values = {}
    if node.has("density"):
        values["density"] = node.key("density").as_number(positive=True) * G_PER_M2
    if node.has("stretch"):
        s = node.key("stretch").as_number(positive=True, maximum=100) * PERCENT
        values["stretch_warp"] = values["stretch_weft"] = s
    if node.has("stretch_weft"):
        values["stretch_weft"] = node.key("stretch_weft").as_number(positive=True, maximum=100) * PERCENT
    if node.has("bending"):
        values["bending"] = node.key("bending").as_number(minimum=0)
    if node.has("friction"):
        values["friction"] = node.key("friction").as_number(minimum=0)
    if node.has("thickness"):
        values["thickness"] = node.key("thickness").as_number(positive=True) * MM
    if node.has("kawabata"):
        values["kawabata"] = _kawabata(node.key("kawabata"))
    if node.has("tear_strain"):
        values["tear_strain"] = node.key("tear_strain").as_number(minimum=0) * PERCENT
    if node.has("wearable_stretch"):
        values["wearable_stretch"] = node.key("wearable_stretch").as_number(positive=True, maximum=500) * PERCENT
    label = base_name if not values else f"{base_name} (custom)"
    return _checked(node, lambda: base.with_values(name=label, **values))


def _kawabata(node: Node) -> KawabataCurves:
    node.as_object(_KAWABATA)
    curves = {}
    for name, (sx, sy) in _KAWABATA_UNITS.items():
        c = node.key(name)
        c.as_list(min_length=1)
        curves[name] = tuple((p[0] * sx, p[1] * sy) for p in (pt.as_point(2) for pt in c.items()))
    return _checked(node, lambda: KawabataCurves(**curves))


def _checked(node: Node, make):
    try:
        return make()
    except FabricError as exc:
        node.fail(str(exc))


# -- panels -------------------------------------------------------------------------------
def _panel(name: str, node: Node, scale: float, relative: bool) -> Panel:
    if not name or not name.isprintable():
        node.fail("a panel name must be a non-empty, printable, single-line string")
    node.as_object(_PANEL)
    vertices, edges = _loop(node, scale, relative)
    holes = tuple(_loop(h, scale, relative, keys=_HOLE)[1] for h in node.key("holes", []).items())
    grain = node.key("grain", 90.0).as_number() * DEG
    placement = None
    if node.has("placement"):
        if node.has("translation") or node.has("rotation"):
            node.key("placement").fail("give either 'placement' or 'translation'/'rotation', not both")
        placement = _landmark_placement(node.key("placement"), scale)
    elif node.has("translation") or node.has("rotation"):
        placement = _transform(node, scale)
    fabric = _fabric(node.key("fabric")) if node.has("fabric") else None
    label = node.key("label", "").as_str()
    marks = _marks(node.key("marks"), scale) if node.has("marks") else ()
    return Panel(name, vertices, edges, holes, grain, placement, fabric, label, marks)


MARK_KINDS = {"notches": ("notch", 1), "drill_holes": ("drill_hole", 1), "internal_lines": ("internal_line", 2),
              "mirror_lines": ("mirror_line", 2)}
"""A panel's ``marks``: file key → (kind, points per mark)."""


def _marks(node: Node, scale: float) -> tuple:
    """((kind, points [m]), …) of a panel's ``marks``: points, or lines as two points each."""
    node.as_object(set(MARK_KINDS))
    out = []
    for key, child in node.entries():
        kind, per = MARK_KINDS[key]
        child.as_list()
        for item in child.items():
            if per == 1:
                x, y = item.as_point(2)
                out.append((kind, ((x * scale, y * scale),)))
            else:
                item.as_list(length=2)
                out.append((kind, tuple((x * scale, y * scale) for x, y in (q.as_point(2) for q in item.items()))))
    return tuple(out)


def _loop(node: Node, scale: float, relative: bool, keys=None):
    if keys is not None:
        node.as_object(keys)
    vnode = node.key("vertices")
    vnode.as_list(min_length=3)
    vertices = tuple((x * scale, y * scale) for x, y in (v.as_point(2) for v in vnode.items()))
    enode = node.key("edges")
    items = enode.items()
    enode.as_list(min_length=1)
    ends = []
    for e in items:
        e.as_object(_EDGE)
        ep = e.key("endpoints")
        ep.as_list(length=2)
        a, b = (i.as_int(minimum=0, below=len(vertices), what="vertex index") for i in ep.items())
        if a == b:
            ep.fail(f"edge starts and ends at the same vertex {a}")
        ends.append((a, b))
    for k, (_, b) in enumerate(ends):
        nxt = ends[(k + 1) % len(ends)]
        if b != nxt[0]:
            j = (k + 1) % len(ends)
            items[k].key("endpoints").fail(
                f"edges do not form a closed loop: edge {k} ends at vertex {b} but edge {j} starts at vertex {nxt[0]}"
            )
    edges = tuple(
        Edge(_curve(e, vertices[a], vertices[b], scale, relative), (a, b), e.key("label", "").as_str())
        for e, (a, b) in zip(items, ends)
    )
    return vertices, edges


def _curve(node: Node, p0, p1, scale: float, relative: bool) -> Curve:
    if not node.has("curvature"):
        return Curve("straight", (p0, p1))
    c = node.key("curvature")
    c.as_object(_CURVATURE)
    kind = c.key("type").as_str(("quadratic", "cubic", "circle"))
    params = c.key("params")
    chord = math.dist(p0, p1)
    if kind == "circle":
        params.as_list(length=3)
        r_node, large, sweep = params.items()
        radius = r_node.as_number(positive=True) * scale
        if chord <= 1e-12:
            node.fail("a circular arc needs two different end points (this edge starts and ends at the same place)")
        if radius < 0.5 * chord * (1.0 - 1e-6):
            r_node.fail(f"arc radius {radius / scale:g} is smaller than half the chord {0.5 * chord / scale:g}")
        return Curve("circle", (p0, p1), radius, large.as_bool(), sweep.as_bool())
    count = 1 if kind == "quadratic" else 2
    params.as_list(length=count)
    controls = []
    a, b = np.asarray(p0), np.asarray(p1)
    d = b - a
    for pt in params.items():
        u, v = pt.as_point(2)
        if relative:
            q = a + u * d + v * np.array([-d[1], d[0]])
        else:
            q = np.array([u, v]) * scale
        controls.append((float(q[0]), float(q[1])))
    return Curve(kind, (p0, *controls, p1))


def _transform(node: Node, scale: float) -> TransformPlacement:
    t = node.key("translation", [0, 0, 0]).as_point(3)
    rx, ry, rz = (a * DEG for a in node.key("rotation", [0, 0, 0]).as_point(3))
    cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    rot_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rot_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rot_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    c = GARMENTCODE_TO_TAILOR
    rotation = c @ rot_z @ rot_y @ rot_x
    translation = c @ (np.asarray(t) * scale)
    return TransformPlacement(tuple(map(tuple, rotation.tolist())), tuple(translation.tolist()))


def _landmark_placement(node: Node, scale: float) -> LandmarkPlacement:
    node.as_object(_PLACEMENT)
    anchor = None
    if node.has("anchor"):
        ax, ay = node.key("anchor").as_point(2)
        anchor = (ax * scale, ay * scale)
    return LandmarkPlacement(
        landmark=node.key("landmark").as_str(LANDMARKS),
        angle=node.key("angle", 0.0).as_number() * DEG,
        anchor=anchor,
        offset=node.key("offset", 0.0).as_number() * scale,
        clearance=node.key("clearance", 2.0).as_number(minimum=0) * scale,
    )


# -- seams and attachments ----------------------------------------------------------------
def _edge_ref(node: Node, panels: dict, *, vertex_ok: bool = False):
    """(panel, edge or None, vertex or None, hole, lo, hi) of a side/attachment reference."""
    pname = node.key("panel").as_str()
    if pname not in panels:
        node.key("panel").as_str(tuple(panels))  # fails with a did-you-mean
    panel = panels[pname]
    hole = None
    if node.has("hole"):
        hole = node.key("hole").as_int(minimum=0, below=len(panel.holes), what="hole index")
    loop = panel.loop(hole)
    edge = vertex = None
    if vertex_ok and node.has("vertex"):
        if node.has("edge") or hole is not None:
            node.fail("a 'vertex' attachment names an outline vertex: give no 'edge' or 'hole' with it")
        vertex = node.key("vertex").as_int(minimum=0, below=len(panel.vertices), what="vertex index")
    else:
        edge = node.key("edge").as_int(minimum=0, below=len(loop), what="edge index")
    lo, hi = 0.0, 1.0
    if node.has("range"):
        r = node.key("range")
        r.as_list(length=2)
        lo, hi = (x.as_number(minimum=0, maximum=1) for x in r.items())
        if lo == hi:
            r.fail("range is empty")
    return pname, edge, vertex, hole, lo, hi


def _seam(node: Node, index: int, panels: dict) -> Seam:
    orientation, label = "auto", ""
    if isinstance(node.value, dict):
        node.as_object(_STITCH)
        orientation = node.key("orientation", "auto").as_str(_ORIENTATIONS)
        label = node.key("label", "").as_str()
        node = node.key("between")
    node.as_list(length=2)
    sides = []
    for s in node.items():
        s.as_object(_SIDE)
        pname, edge, _, hole, lo, hi = _edge_ref(s, panels)
        sides.append(SeamSide(pname, edge, hole, lo, hi))
    a, b = sides
    flipped = SeamSide(b.panel, b.edge, b.hole, b.end, b.start)
    if orientation == "same":
        return Seam(a, b, "same", label, index)
    if orientation == "opposite":
        return Seam(a, flipped, "opposite", label, index)
    chosen = _auto_orientation(a, b, panels)
    return Seam(a, b if chosen == "same" else flipped, f"auto:{chosen}", label, index)


def _side_ends_3d(side: SeamSide, panel: Panel):
    uv = sample_curve(panel.loop(side.hole)[side.edge].curve, [side.start, side.end])
    return panel.placement.apply(uv)


def _auto_orientation(a: SeamSide, b: SeamSide, panels: dict) -> str:
    """Half-edge rule ('opposite'), unless both panels are placed in 3D and clearly say otherwise.

    With explicit placements the pairing with the smaller summed endpoint distance wins, but
    only when it beats the other by ``_DECISIVE`` of the seam length; for a short edge far from
    its partner the distances cannot tell, and the half-edge rule stands.
    """
    pa, pb = panels[a.panel], panels[b.panel]
    if not (isinstance(pa.placement, TransformPlacement) and isinstance(pb.placement, TransformPlacement)):
        return "opposite"
    (a0, a1), (b0, b1) = _side_ends_3d(a, pa), _side_ends_3d(b, pb)
    same = np.linalg.norm(a0 - b0) + np.linalg.norm(a1 - b1)
    opposite = np.linalg.norm(a0 - b1) + np.linalg.norm(a1 - b0)
    # Far-apart short edges barely tell: trust the placement only when it is decisive.
    length = 0.5 * (np.linalg.norm(a1 - a0) + np.linalg.norm(b1 - b0))
    return "same" if opposite - same > _DECISIVE * length else "opposite"


def _waist_holds(panels, seams) -> tuple:
    """Attachments to the waist of the free (unsewn) edges labelled :data:`WAIST_LABEL`.

    GarmentCode files carry no attachments; a skirt or trousers held only by friction slides down
    over the hips while it settles. A file with its own ``attachments`` (even empty) keeps them."""
    sewn = {(s.panel, s.hole, s.edge) for seam in seams for s in (seam.a, seam.b)}
    free = [(p.name, k) for p in panels for k, e in enumerate(p.edges)
            if e.label == WAIST_LABEL and (p.name, None, k) not in sewn]
    return tuple(Attachment(name, "waist", k, index=i) for i, (name, k) in enumerate(free))


def _attachment(node: Node, index: int, panels: dict) -> Attachment:
    node.as_object(_ATTACH)
    pname, edge, vertex, hole, lo, hi = _edge_ref(node, panels, vertex_ok=True)
    target = node.key("to").as_str(ATTACHMENT_TARGETS + LANDMARKS)
    return Attachment(pname, target, edge, vertex, hole, lo, hi, index)


# -- writing a reshaped pattern back ----------------------------------------------------------------
def _curve_params(curve: Curve, scale: float, relative: bool):
    """The file's ``curvature.params`` of ``curve`` (file units, relative or absolute control points)."""
    if curve.kind == "circle":
        return [curve.radius / scale, bool(curve.large_arc), bool(curve.sweep)]
    a, b = curve.start, curve.end
    d = b - a
    out = []
    for q in curve.points[1:-1]:
        q = np.asarray(q, float)
        if relative:  # q = a + u·d + v·d⊥
            u, v = np.linalg.solve(np.column_stack([d, [-d[1], d[0]]]), q - a)
            out.append([float(u), float(v)])
        else:
            out.append([float(q[0] / scale), float(q[1] / scale)])
    return out


def _reshape_loop(node: dict, vertices, edges, scale: float, relative: bool) -> None:
    node["vertices"] = [[x / scale, y / scale] for x, y in vertices]
    for enode, edge in zip(node["edges"], edges):
        if "curvature" in enode:
            enode["curvature"]["params"] = _curve_params(edge.curve, scale, relative)


def reshaped_document(doc: dict, pattern: Pattern) -> dict:
    """A copy of the pattern document ``doc`` with the geometry of ``pattern`` (the same panels, edges and
    seams reshaped, as :func:`tailor.sizing.grade` does): vertices, curvatures, placements' offsets and
    translations. Everything else of the file (seams, fabrics, labels, parameters) is kept."""
    import copy

    out = copy.deepcopy(doc)
    props = out.get("properties", {})
    scale = 1.0 / float(props.get("units_in_meter", 100))
    relative = props.get("curvature_coords", "relative") == "relative"
    for name, node in out["pattern"]["panels"].items():
        panel = pattern.panel(name)
        _reshape_loop(node, panel.vertices, panel.edges, scale, relative)
        for hnode, hole in zip(node.get("holes", []), panel.holes):
            corners = [None] * len(hnode["vertices"])
            for edge in hole:
                corners[edge.endpoints[0]] = edge.curve.points[0]
            _reshape_loop(hnode, corners, hole, scale, relative)
        pl = panel.placement
        if "placement" in node and isinstance(pl, LandmarkPlacement):
            node["placement"]["offset"] = pl.offset / scale
        elif "translation" in node and pl is not None:
            node["translation"] = (GARMENTCODE_TO_TAILOR.T @ np.asarray(pl.translation) / scale).tolist()
    return out
