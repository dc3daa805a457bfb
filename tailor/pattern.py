"""Sewing patterns in SI: panels with curved edges, seams, attachments and placements.

A :class:`Pattern` is what :func:`tailor.io.read_pattern` returns once a file has been parsed
and converted (cm → m, degrees → radians, GarmentCode's Y-up world → tailor's Z-up world).
Everything here is frozen. :func:`validate_pattern` checks what needs geometry (outlines that
cross themselves, holes outside their panel, edges sewn twice, seams of incompatible length)
and raises :class:`~tailor.errors.PatternError` naming the file and the field.

Field names in messages follow the file: ``pattern.panels.front.edges[3]``,
``pattern.stitches[2][1]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from shapely.geometry import LinearRing, Polygon
from shapely.validation import explain_validity, make_valid

from .curves import Curve, curve_length, loop_area, loop_polyline
from .errors import PatternError, SeamError
from .fabric import Fabric

__all__ = [
    "Edge",
    "Panel",
    "SeamSide",
    "Seam",
    "Attachment",
    "TransformPlacement",
    "LandmarkPlacement",
    "Pattern",
    "validate_pattern",
    "MAX_SEAM_EASE",
    "ATTACHMENT_TARGETS",
]

MAX_SEAM_EASE = 0.25
"""Largest allowed relative length difference of two sewn edges, (L_long − L_short)/L_long.

Sleeve caps are eased into armholes by a few percent and gathered skirts more; a quarter is
the limit beyond which the seam is almost surely a mistake (wrong edge index).
"""

ATTACHMENT_TARGETS = ("pin", "body")
"""Attachment targets besides landmark names: a pin fixed in space, or the nearest body point."""


@dataclass(frozen=True, slots=True)
class Edge:
    """One edge of a panel loop.

    Attributes
    ----------
    curve : Curve
        Its shape in panel coordinates [m].
    endpoints : tuple of int
        Indices of its start and end in the loop's vertex list (as in the file).
    label : str
        Free label from the file (e.g. ``left_armhole``).
    """

    curve: Curve
    endpoints: tuple[int, int]
    label: str = ""

    @property
    def length(self) -> float:
        """Arc length [m]."""
        return curve_length(self.curve)


@dataclass(frozen=True, slots=True)
class TransformPlacement:
    """An explicit rigid placement: world = rotation @ (x, y, 0) + translation.

    Attributes
    ----------
    rotation : tuple of 3 tuples
        Rotation matrix, shape (3, 3), into tailor's world frame (Z up, facing −Y).
    translation : tuple of 3 floats
        Panel origin in the world [m].
    """

    rotation: tuple[tuple[float, float, float], ...]
    translation: tuple[float, float, float]

    def apply(self, uv) -> np.ndarray:
        """World positions [m], shape (n, 3), of panel points ``uv`` [m], shape (n, 2)."""
        uv = np.asarray(uv, dtype=float)
        local = np.column_stack([uv, np.zeros(len(uv))])
        return local @ np.asarray(self.rotation).T + np.asarray(self.translation)


@dataclass(frozen=True, slots=True)
class LandmarkPlacement:
    """A body-relative placement: wrap the panel around a body landmark.

    Attributes
    ----------
    landmark : str
        Name from :data:`tailor.landmarks.LANDMARKS`.
    angle : float
        Azimuth of the panel's anchor around the landmark's axis [rad]; 0 = front (−Y),
        π/2 = the body's left (+X), π = back.
    anchor : tuple of 2 floats or None
        Panel point [m] put on the landmark; ``None`` = top centre of the panel's bounding box.
    offset : float
        Distance of the anchor above (+) or below (−) the landmark along its axis [m].
    clearance : float
        Gap between the body surface and the wrapped panel [m].
    """

    landmark: str
    angle: float = 0.0
    anchor: tuple[float, float] | None = None
    offset: float = 0.0
    clearance: float = 0.02


@dataclass(frozen=True, slots=True)
class Panel:
    """A flat piece of fabric.

    Attributes
    ----------
    name : str
    vertices : tuple of (x, y)
        Outline corner points in panel coordinates [m].
    edges : tuple of Edge
        The outline: a closed loop, edge ``i`` ends where edge ``i + 1`` starts. Its winding
        says which side faces outward (counter-clockwise: the +z side of the panel plane).
    holes : tuple of tuple of Edge
        Inner loops cut out of the panel.
    grain : float
        Direction of the warp in the panel plane [rad] from the panel's +x axis.
    placement : TransformPlacement, LandmarkPlacement or None
    fabric : Fabric or None
        Per-panel fabric; ``None`` = the pattern's.
    label : str
    marks : tuple of (kind, points)
        Pattern-maker's marks the simulation does not use, kept from CAD and drawn: ``notch`` and
        ``drill_hole`` (points), ``internal_line`` and ``mirror_line`` (two points each) [m].
    """

    name: str
    vertices: tuple[tuple[float, float], ...]
    edges: tuple[Edge, ...]
    holes: tuple[tuple[Edge, ...], ...] = ()
    grain: float = 0.5 * np.pi
    placement: TransformPlacement | LandmarkPlacement | None = None
    fabric: Fabric | None = None
    label: str = ""
    marks: tuple = ()

    def loop(self, hole: int | None = None) -> tuple[Edge, ...]:
        """The outline (``hole=None``) or hole number ``hole``."""
        return self.edges if hole is None else self.holes[hole]

    def where(self, edge: int | None = None, hole: int | None = None) -> str:
        """The file field naming this panel or one of its edges, for messages."""
        base = f"pattern.panels.{self.name}"
        if hole is not None:
            base += f".holes[{hole}]"
        return base if edge is None else f"{base}.edges[{edge}]"

    @property
    def signed_area(self) -> float:
        """Exact area [m²] of outline minus holes, signed by the outline's winding."""
        outer = loop_area([e.curve for e in self.edges])
        inner = sum(abs(loop_area([e.curve for e in h])) for h in self.holes)
        return outer - np.sign(outer) * inner

    @property
    def area(self) -> float:
        """Exact fabric area [m²] (curved edges included)."""
        return abs(self.signed_area)


@dataclass(frozen=True, slots=True)
class SeamSide:
    """One side of a seam: a stretch of one edge.

    The stretch runs from arc-length fraction ``start`` to ``end`` of the edge (in the
    edge's own direction); ``end < start`` means the side runs backward along the edge.
    """

    panel: str
    edge: int
    hole: int | None = None
    start: float = 0.0
    end: float = 1.0

    @property
    def lo(self) -> float:
        """Smaller of the two fractions."""
        return min(self.start, self.end)

    @property
    def hi(self) -> float:
        """Larger of the two fractions."""
        return max(self.start, self.end)

    @property
    def reversed(self) -> bool:
        """Whether the side runs against the edge's direction."""
        return self.end < self.start


@dataclass(frozen=True, slots=True)
class Seam:
    """Two sides sewn together: the point at fraction s along ``a`` meets the point at s along ``b``.

    ``orientation`` records how the pairing was decided: ``opposite`` (a's start meets b's
    end, the half-edge rule for consistently wound panels), ``same``, or with an ``auto:``
    prefix when chosen from the placed 3D positions.
    """

    a: SeamSide
    b: SeamSide
    orientation: str = "opposite"
    label: str = ""
    index: int = 0


WAIST_LABEL = "lower_interface"
"""GarmentCode's edge label where a lower garment meets an upper one: a dress's bodice-to-skirt
seam, or on a skirt's or trousers' free top edge, the waist."""


@dataclass(frozen=True, slots=True)
class Attachment:
    """Part of a panel held to the body or to a pin (Carignan Eq. 19–20).

    Exactly one of ``edge`` and ``vertex`` is set. ``target`` is ``pin`` (fixed in space at
    its placed position), ``body`` (the nearest body point, following the body) or a landmark.
    """

    panel: str
    target: str
    edge: int | None = None
    vertex: int | None = None
    hole: int | None = None
    start: float = 0.0
    end: float = 1.0
    index: int = 0


@dataclass(frozen=True, slots=True)
class Piece:
    """One garment of an outfit (:func:`tailor.outfit.outfit`): panels ``first`` to
    ``first + count − 1`` of the outfit's pattern.

    ``layer`` orders the garments (larger is further out); ``clearance`` [m] is what its placement
    adds to its panels' own: the room the garments inside it take; ``ease`` is how much wider across
    its loops that lie over another garment's were made (:func:`tailor.outfit.ease_layers`; 1: as drafted);
    ``rise`` [m] how much higher than drafted its placements put it (:data:`tailor.outfit.ATTACH_RISE`);
    ``tucks``: the garments inside it are tucked into it (``outfit(..., tuck=True)``).
    """

    name: str
    first: int
    count: int
    layer: int = 0
    clearance: float = 0.0
    ease: float = 1.0
    rise: float = 0.0
    tucks: bool = False


@dataclass(frozen=True, slots=True)
class Pattern:
    """A garment pattern in SI units.

    Attributes
    ----------
    name : str
    panels : tuple of Panel
    seams : tuple of Seam
    attachments : tuple of Attachment
    fabric : Fabric
        Default fabric of every panel without its own.
    source : str
        Where it came from (file name), prefixed to every message.
    layer : int
        Its place in an outfit (:mod:`tailor.outfit`): larger is further out; 0 by default.
    pieces : tuple of Piece
        The garments of an outfit, innermost first; empty for a single garment.
    """

    name: str
    panels: tuple[Panel, ...]
    seams: tuple[Seam, ...] = ()
    attachments: tuple[Attachment, ...] = ()
    fabric: Fabric | None = None
    source: str = "<pattern>"
    layer: int = 0
    pieces: tuple[Piece, ...] = ()
    _index: dict = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_index", {p.name: i for i, p in enumerate(self.panels)})

    def panel_index(self, name: str) -> int:
        """Position of panel ``name`` in :attr:`panels`."""
        return self._index[name]

    def panel(self, name: str) -> Panel:
        """The panel called ``name``."""
        return self.panels[self._index[name]]

    def piece_of(self, panel: int) -> Piece:
        """The garment panel number ``panel`` belongs to (the whole pattern for a single garment)."""
        for piece in self.pieces:
            if piece.first <= panel < piece.first + piece.count:
                return piece
        return Piece(self.name, 0, len(self.panels), self.layer)

    @property
    def area(self) -> float:
        """Total fabric area [m²]."""
        return float(sum(p.area for p in self.panels))

    def side_label(self, side: SeamSide) -> str:
        """The file's label of a seam side's edge ("" without one)."""
        return self.panel(side.panel).loop(side.hole)[side.edge].label

    def joins_at_waist(self, seam: Seam) -> bool:
        """Whether ``seam`` joins an upper garment to a lower one: one of its edges is labelled
        :data:`WAIST_LABEL` (a dress's skirt, sewn to its bodice)."""
        return WAIST_LABEL in (self.side_label(seam.a), self.side_label(seam.b))

    def side_length(self, side: SeamSide) -> float:
        """Length [m] of a seam side's stretch of edge."""
        edge = self.panel(side.panel).loop(side.hole)[side.edge]
        return edge.length * (side.hi - side.lo)

    def fail(self, where: str, message: str, error=PatternError):
        """Raise ``error`` with the one-line ``source: where: message`` form."""
        raise error(f"{self.source}: {where}: {message}")


def validate_pattern(pattern: Pattern) -> Pattern:
    """Check a pattern's geometry and seams; return it unchanged or raise PatternError.

    Checks: each outline and hole is a simple closed curve of non-zero area (shapely), holes
    lie inside their outline and apart from each other, every seam side is a real edge, no
    stretch of edge is sewn twice, and sewn lengths differ by at most :data:`MAX_SEAM_EASE`.
    """
    for panel in pattern.panels:
        _validate_panel(pattern, panel)
    _validate_seams(pattern)
    return pattern


def _loop_polygon(pattern, panel, hole):
    curves = [e.curve for e in panel.loop(hole)]
    where = panel.where(hole=hole)
    with np.errstate(invalid="ignore", over="ignore"):
        pts = loop_polyline(curves)
        if not np.all(np.isfinite(pts)):  # a curve's parameters beyond what a float can place
            edge = next(k for k, c in enumerate(curves) if not np.all(np.isfinite(loop_polyline([c]))))
            pattern.fail(panel.where(edge=edge, hole=hole), "curve is out of range (its points are not finite numbers)")
    poly = Polygon(pts)
    if make_valid(poly).area < 1e-8:  # below 0.01 cm² of fabric
        pattern.fail(where, "outline has zero area")
    if not LinearRing(pts).is_simple or not poly.is_valid:
        pattern.fail(where, f"outline crosses itself ({_cm_text(explain_validity(poly))})")
    return poly


def _cm_text(reason: str) -> str:
    """Shapely's 'Self-intersection[x y]' with coordinates in cm."""
    import re

    def repl(m):
        x, y = float(m.group(1)), float(m.group(2))
        return f" at ({x * 100:.1f}, {y * 100:.1f}) cm"

    return re.sub(r"\[([-\d.eE+]+) ([-\d.eE+]+)\]", repl, reason).lower()


def _validate_panel(pattern: Pattern, panel: Panel) -> None:
    outer = _loop_polygon(pattern, panel, None)
    holes = []
    for k in range(len(panel.holes)):
        poly = _loop_polygon(pattern, panel, k)
        if not outer.contains(poly):
            pattern.fail(panel.where(hole=k), "hole is not inside the panel outline")
        for j, other in enumerate(holes):
            if poly.intersects(other):
                pattern.fail(panel.where(hole=k), f"hole overlaps holes[{j}]")
        holes.append(poly)


def _validate_seams(pattern: Pattern) -> None:
    used: dict[tuple, list] = {}
    for seam in pattern.seams:
        for k, side in enumerate((seam.a, seam.b)):
            where = f"pattern.stitches[{seam.index}][{k}]"
            key = (side.panel, side.hole, side.edge)
            for lo, hi, other in used.get(key, []):
                if side.lo < hi - 1e-9 and lo < side.hi - 1e-9:
                    pattern.fail(
                        where,
                        f"edge {side.edge} of panel {side.panel!r} is already sewn by pattern.stitches[{other}]",
                        SeamError,
                    )
            used.setdefault(key, []).append((side.lo, side.hi, seam.index))
        la, lb = pattern.side_length(seam.a), pattern.side_length(seam.b)
        longest = max(la, lb)
        if longest <= 0:
            pattern.fail(f"pattern.stitches[{seam.index}]", "seam has zero length", SeamError)
        ease = abs(la - lb) / longest
        if ease > MAX_SEAM_EASE:
            pattern.fail(
                f"pattern.stitches[{seam.index}]",
                f"sewn lengths differ too much: {la * 100:.1f} cm ({seam.a.panel} edge {seam.a.edge}) vs "
                f"{lb * 100:.1f} cm ({seam.b.panel} edge {seam.b.edge}), {ease:.0%} > the {MAX_SEAM_EASE:.0%} ease limit",
                SeamError,
            )
