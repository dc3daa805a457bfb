"""Placing panels around a body before sewing (Carignan §4: "panels are placed around the body").

Two kinds of placement come from the pattern:

* an explicit rigid transform (GarmentCode's ``translation``/``rotation``), drafted for GarmentCode's
  neutral body: applied as it is, then moved with the body part the panel's label names onto the
  body being dressed (:mod:`tailor.retarget`);
* a body-relative :class:`~tailor.pattern.LandmarkPlacement`: the panel is rolled around the
  named landmark's cross-section (an ellipse for the trunk, a circle for a limb) at ``clearance``
  from the body, its anchor at the landmark's ``angle``, its +y along the landmark's axis and its
  outside facing out. Rolling onto a cylinder bends the panel without straining it; a panel whose
  widest row exceeds its share of the circumference (a flared skirt) is rolled on a wider
  cylinder, so panels never overlap: with n panels at one landmark at n different angles, each spans at most 360°/n.
  A flared panel round a circular waist arc (a circle skirt's) is laid on a cone instead (:func:`_cone`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np

from .curves import arc_center, sample_curve
from .errors import PatternError
from .geometry import vertex_normals
from .limbwalls import LimbWalls, limb_walls, no_walls  # re-exported: placement's other half
from .pattern import LandmarkPlacement, TransformPlacement
from .retarget import BodyRetarget

__all__ = ["place_panels", "limb_walls", "LimbWalls", "no_walls", "SLOPE", "LAYER_GAP"]

log = logging.getLogger(__name__)

SLOPE = 0.1
"""Largest change of a rolled panel's radius, and of its points' position around it, per unit height."""


def _frame(landmark):
    """Unit axis (panel +y), 'front' and 'left' directions in the plane of the cut."""
    axis = np.asarray(landmark.axis, float)
    axis = axis / np.linalg.norm(axis)
    front = np.array([0.0, -1.0, 0.0]) - axis * (-axis[1])
    if np.linalg.norm(front) < 1e-6:
        front = np.array([0.0, 0.0, -1.0]) - axis * (-axis[2])
    front /= np.linalg.norm(front)
    left = np.cross(axis, front)  # seen from outside at the front, +x runs towards the body's left (+X)
    if left @ np.array([1.0, 0.0, 0.0]) < 0 and abs(axis[2]) > 0.9:
        left = -left
    return axis, front, left


def _wrap(uv, anchor, lm, placement, share, inside=None):
    axis, front, left = _frame(lm)
    is_trunk = abs(axis[2]) > 0.9 and lm.width > 0 and lm.depth > 0
    if is_trunk:
        a0, b0 = 0.5 * lm.width, 0.5 * lm.depth
    else:
        a0 = b0 = lm.girth / (2.0 * math.pi)
    clearance = placement.clearance
    rel = uv - anchor
    a, b = a0 + clearance, b0 + clearance
    perimeter = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))
    # width of the panel along its height (1 cm bands), never narrower than nearer the anchor
    lo, hi = rel[:, 1].min(), rel[:, 1].max()
    edges = np.arange(lo, hi + 0.01, 0.01)
    band = np.clip(np.searchsorted(edges, rel[:, 1]) - 1, 0, max(len(edges) - 2, 0))
    width = np.zeros(max(len(edges) - 1, 1))
    for k in range(len(width)):
        members = rel[band == k, 0]
        width[k] = np.ptp(members) if len(members) > 1 else 0.0
    centre = np.argmin(np.abs(0.5 * (edges[:-1] + edges[1:]))) if len(edges) > 1 else 0
    width[centre:] = np.maximum.accumulate(width[centre:])
    width[: centre + 1] = np.maximum.accumulate(width[: centre + 1][::-1])[::-1]
    # one radius for the whole panel: rolling onto a cylinder is an isometry (no initial strain),
    # wide enough that the panel's widest row fits its share of the circumference
    grow = float(np.max(np.maximum(1.0, width / max(share, 1e-6) * 1.05 / perimeter), initial=1.0))
    # arc length → angle on the ellipse (scaled per band), from the anchor's azimuth
    phi = np.linspace(0.0, 2.0 * math.pi, 721)
    unit = np.column_stack([a * np.sin(phi), b * np.cos(phi)])
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(unit, axis=0).T))])
    s0 = np.interp(placement.angle % (2.0 * math.pi), phi, arc)
    height = rel[:, 1] + placement.offset

    def place(scale):
        """Rows rolled isometrically onto the ellipse scaled by ``scale`` (per vertex)."""
        ang = np.interp((s0 + rel[:, 0] / scale) % arc[-1], arc, phi)
        radial = (scale * a * np.sin(ang))[:, None] * left + (scale * b * np.cos(ang))[:, None] * front
        return np.asarray(lm.center) + radial + np.outer(height, axis), radial

    x, _ = place(np.full(len(uv), grow))
    if inside is None:
        return x
    # The landmark's cylinder fits its own cross-section, not the body above or below it (a
    # trouser leg rolled round the thigh runs into the hips): rows that would start inside the
    # body, or closer than half the clearance, are rolled onto wider cylinders, still isometric
    # along each row, the factor growing and shrinking gently from row to row.
    factors = np.linspace(1.0, 3.0, 21)
    bands = len(width)
    bad = np.zeros((len(factors), bands), bool)
    for k, factor in enumerate(factors):
        xk, radial = place(np.full(len(uv), grow * factor))
        probe = xk - 0.5 * clearance * radial / np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-12)
        bad[k] = np.bincount(band, weights=inside(probe).astype(float), minlength=bands) > 0
        if not bad[k].any():
            break
    clear = np.where(bad[: k + 1].all(axis=0), k, np.argmin(bad[: k + 1], axis=0))
    f = factors[clear]
    if np.all(f == 1.0):
        return x
    # a row rolled wider moves its points along the circumference by |s|·Δf/f: keep that and the
    # radius change below SLOPE per unit height, so the columns stay within ~1 % of their length
    step = SLOPE * 0.01 / max(float(np.abs(rel[:, 0]).max()), grow * max(a, b))
    for k in range(1, bands):
        f[k] = max(f[k], f[k - 1] - step)
    for k in range(bands - 2, -1, -1):
        f[k] = max(f[k], f[k + 1] - step)
    return place(grow * f[band])[0]


CONE_SLOPE_STEP = 0.1
"""Steps of the outward run per unit of slant (the sine of the cone's half-angle) tried, from the
isometric one down, until a flared panel's cone clears the body (the hands, the legs)."""


def _waist_arc(panel, anchor):
    """(centre, radius) of the panel's circular edge through ``anchor`` when the panel lies outside
    that circle (a circle or half-circle skirt round its waist arc), else None."""
    for edge in panel.edges:
        c = edge.curve
        if c.kind != "circle":
            continue
        centre = arc_center(c.start, c.end, c.radius, c.large_arc, c.sweep)[0]
        r = max(c.radius, 0.5 * float(np.linalg.norm(c.end - c.start)))
        if abs(np.linalg.norm(anchor - centre) - r) > 1e-3:
            continue
        outline = np.concatenate([sample_curve(e.curve, np.linspace(0.0, 1.0, 33)) for e in panel.edges])
        if (np.linalg.norm(outline - centre, axis=1) > r - 1e-3).all():
            return centre, r
    return None


class _Cone:
    """Cones round a landmark for a flared panel (:func:`_cone`): panel points in polar coordinates
    about its waist arc's centre, the arc laid along the landmark's ellipse at the clearance (arc
    length kept, the ellipse scaled so the arc fills the panel's share), each ray running down and
    out from it."""

    def __init__(self, uv, anchor, arc, lm, placement, share):
        self.axis, front, left = _frame(lm)
        self.centre, self.r0 = arc
        self.ta = math.atan2(*(anchor - self.centre)[::-1])
        self.span = float(np.ptp(self._polar(uv)[1]))
        a0, b0 = 0.5 * lm.width, 0.5 * lm.depth
        a, b = a0 + placement.clearance, b0 + placement.clearance
        perimeter = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))
        q = max(0.97 * self.r0 * self.span / (share * perimeter), (a0 + 0.5 * placement.clearance) / a)
        self.a, self.b, self.front, self.left = q * a, q * b, front, left
        self.phi = np.linspace(0.0, 2.0 * math.pi, 721)
        unit = np.column_stack([self.a * np.sin(self.phi), self.b * np.cos(self.phi)])
        self.arc_len = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(unit, axis=0).T))])
        self.s0 = np.interp(placement.angle % (2.0 * math.pi), self.phi, self.arc_len)
        tangent = np.array([-(anchor - self.centre)[1], (anchor - self.centre)[0]])
        self.sign = 1.0 if tangent[0] >= 0 else -1.0  # arc length along the waist grows with the panel's +x
        self.base = np.asarray(lm.center) + placement.offset * self.axis
        self.down = -1.0 if uv[:, 1].mean() < anchor[1] else 1.0

    def _polar(self, uv):
        rel = uv - self.centre
        dtheta = (np.arctan2(rel[:, 1], rel[:, 0]) - self.ta + math.pi) % (2.0 * math.pi) - math.pi
        return np.linalg.norm(rel, axis=1), dtheta

    def at(self, uv, slope: float):
        """(points (N, 3), outward directions (N, 3), slant (N,)) of ``uv`` on the cone of ``slope``."""
        rho, dtheta = self._polar(uv)
        ang = np.interp((self.s0 + self.sign * self.r0 * dtheta) % self.arc_len[-1], self.arc_len, self.phi)
        # out from the axis, not along the ellipse's normal: the normals of a wide ellipse fan out at
        # its sides and would stretch the cloth there by a third
        radial = (self.a * np.sin(ang))[:, None] * self.left + (self.b * np.cos(ang))[:, None] * self.front
        out = radial / np.linalg.norm(radial, axis=1, keepdims=True)
        waist = self.base + radial
        slant = rho - self.r0
        x = waist + (slant * slope)[:, None] * out + np.outer(self.down * slant * math.sqrt(1.0 - slope * slope), self.axis)
        return x, out, slant

    def probe(self, uv, step: float = 0.01):
        """Points every ``step`` [m] over the panel's polar extent (finer than its mesh) and a tenth
        beyond each side: where the seams to its neighbours will close."""
        rho, dtheta = self._polar(uv)
        rings = np.arange(self.r0, rho.max() + step, step)
        lo, hi = dtheta.min() - 0.1 * self.span, dtheta.max() + 0.1 * self.span
        pts = [np.column_stack([r * np.cos(t), r * np.sin(t)])
               for r in rings for t in [self.ta + np.arange(lo, hi, step / r)]]
        return self.centre + np.concatenate(pts)


def _cone(uv, anchor, arc, lm, placement, share, inside=None):
    """A flared panel (a circle or half-circle skirt) laid on a cone round the landmark (:class:`_Cone`).

    Rolling such a panel row by row puts its straight side seams, horizontal in the pattern, along
    the waist, 40–50 cm from the body; on the cone they run down its sides, where the next panel's
    meet them. A panel spanning Θ round its arc's centre, laid round its share of the body, lies on
    the cone of slope (sine of the half-angle) Θ / (2π·share) without strain: a full circle skirt
    flat, a half circle at 30°. That one is taken if it clears the body (the forearms, the hands,
    the legs) by half the clearance, tested every centimetre over the panel; else each steeper one
    in turn, compressing the cloth round the cone, which buckles into the folds it hangs in anyway.
    None for a panel hardly flared (a slope under two steps): it is rolled (:func:`_wrap`).
    """
    cone = _Cone(uv, anchor, arc, lm, placement, share)
    iso = min(1.0, cone.span / (2.0 * math.pi * share))
    if iso < 2.0 * CONE_SLOPE_STEP:
        return None  # hardly flared: rolled as it is
    probe = cone.probe(uv)
    for slope in np.arange(iso, 0.05, -CONE_SLOPE_STEP):
        p, out, slant = cone.at(probe, slope)
        below = slant > 0.05
        if inside is None or not inside(p[below] - 0.5 * placement.clearance * out[below]).any():
            break
    return cone.at(uv, slope)[0]


def _clear_rigid(x, placement, inside, body_axis, clearance=0.01, reach=0.3):
    """Move a rigidly placed panel out of the body along its normal, the least that clears it.

    Patterns placed for another body (GarmentCode's, made for its own mannequin) may cut into
    this one; the panel is slid away from the body's vertical axis, in 5 mm steps up to
    ``reach``, until no point ``clearance`` behind it is inside.
    """
    normal = np.asarray(placement.rotation, float)[:, 2]
    outward = np.append(x.mean(axis=0)[:2] - body_axis, 0.0)
    if normal @ outward < 0:
        normal = -normal
    for shift in np.arange(0.0, reach + 1e-9, 0.005):
        moved = x + shift * normal
        if not inside(moved - clearance * normal).any():
            return moved
    return x


LAYER_GAP = 0.01
"""Room [m] an outfit's outer garment is placed outside an inner one: added to the inner garment's
clearance in the outer one's landmark placements (:func:`tailor.outfit.outfit`), and kept from the
inner garment's placed cloth by every outer panel (:class:`_Outside`)."""


class _Outside:
    """``inside(points)`` for an outer garment: inside the body (``body``), or behind or within
    ``gap`` [m] of the garments already placed (panels before ``first``).

    A point is behind the placed cloth when its nearest placed vertex, less than 30 cm away, lies
    over it (within one and a half mesh edges sideways) and the point is less than ``gap`` out
    along that vertex's outward normal (placed panels face out: counter-clockwise is outside).
    """

    def __init__(self, body, x, mesh, first: int, gap: float):
        from scipy.spatial import cKDTree

        self.body, self.gap, self.side = body, gap, 1.5 * mesh.resolution
        keep = mesh.vertex_panel < first
        faces = mesh.faces[keep[mesh.faces].all(axis=1)]
        n = vertex_normals(x, faces)
        self.ids = np.flatnonzero(np.linalg.norm(n, axis=1) > 0)
        self.x = x[self.ids].copy()
        self.n = n[self.ids] / np.linalg.norm(n[self.ids], axis=1, keepdims=True)
        self.tree = cKDTree(self.x)

    def __call__(self, points):
        points = np.asarray(points, float)
        out = np.asarray(self.body(points), bool).copy()
        d, k = self.tree.query(points, distance_upper_bound=0.3)
        near = np.flatnonzero(np.isfinite(d))
        rel = points[near] - self.x[k[near]]
        along = np.einsum("ij,ij->i", rel, self.n[k[near]])
        sideways = np.linalg.norm(rel - along[:, None] * self.n[k[near]], axis=1)
        out[near] |= (along < self.gap) & (sideways < self.side)
        return out


def place_panels(pattern, mesh, landmarks=None, inside=None, *, garment: int | None = None, x=None,
                 again=None) -> np.ndarray:
    """Initial 3D positions [m], shape (N, 3), of every mesh vertex from its panel's placement.

    Parameters
    ----------
    pattern : Pattern
    mesh : GarmentMesh
    landmarks : dict of name → Landmark, optional
        Needed by body-relative placements (:func:`tailor.measure.find_landmarks`).
    inside : callable ``inside(points) -> (n,) bool``, optional
        Whether points lie inside the body (:func:`tailor.collide.points_inside`); rows of a
        rolled panel that would start inside it are rolled on wider cylinders.
    garment : int, optional
        Place only this garment of an outfit (index into ``pattern.pieces``), its panels at their
        own clearance, clear of the garments inside it as they lie at ``x`` (N, 3), sewn: the
        outer garment is dressed over the inner one as it fits, not as it was placed (an inner
        garment's placement is wider than its sewn shape, and an outer panel rolled round it
        would start a hand's breadth off the body, its seams too far apart to close). Every other
        vertex keeps its position in ``x``.
    again : list of int, optional
        Place only these panels again (in order), each clear of the cloth placed before it as it lies
        at ``x`` (:class:`_Outside`; panels placed through each other,
        :meth:`tailor.dress.Placer.uncrossed`); the others keep ``x``.

    Without ``garment``, an outfit's garments are placed innermost first, each garment's landmark
    placements at their clearance plus the room of the garments inside it
    (:attr:`~tailor.pattern.Piece.clearance`), and clear of their placed cloth.

    Raises
    ------
    PatternError
        A panel without a placement, or a landmark placement without a body.
    """
    if again is not None:
        out, panels = np.array(x, float), again
    elif garment is None:
        out, panels = np.zeros((mesh.vertex_count, 3)), range(len(pattern.panels))
    else:
        piece = pattern.pieces[garment]
        out, panels = np.array(x, float), range(piece.first, piece.first + piece.count)
    body_axis = np.zeros(2)
    if landmarks:
        body_axis = np.mean([np.asarray(lm.center)[:2] for lm in landmarks.values()], axis=0)
    pieces = [pattern.piece_of(pi) for pi in range(len(pattern.panels))]
    counts = _panels_round(pattern, pieces)

    def place(pi, test):
        ids = mesh.panel_vertices(pi)
        extra = pieces[pi].clearance if garment is None else 0.0
        out[ids] = _place_panel(pattern, pi, mesh.uv[ids], landmarks, test, counts[pi], body_axis, extra)

    if again is not None:
        for pi in panels:
            place(pi, _Outside(inside, out, mesh, pi, LAYER_GAP))
        return out
    first = None
    for pi in panels:
        if pieces[pi].first and pieces[pi].first != first and inside is not None:  # an outer garment: clear of the inner ones too
            first = pieces[pi].first
            clear = _Outside(inside, out, mesh, first, LAYER_GAP)
        place(pi, clear if first else inside)
    return out


def _panels_round(pattern, pieces) -> list:
    """Per panel, how many of its garment's panels share its landmark at distinct angles (1 for a
    rigid placement): each takes that share of the circumference (bands stack vertically)."""
    angles: dict = {}
    for p, piece in zip(pattern.panels, pieces):
        if isinstance(p.placement, LandmarkPlacement):
            angles.setdefault((piece.name, p.placement.landmark), set()).add(round(p.placement.angle % (2 * math.pi), 6))
    return [len(angles[(piece.name, p.placement.landmark)]) if isinstance(p.placement, LandmarkPlacement) else 1
            for p, piece in zip(pattern.panels, pieces)]


def _place_panel(pattern, pi: int, uv, landmarks, inside, count: int, body_axis, extra: float) -> np.ndarray:
    """(n, 3) positions of panel ``pi``'s points ``uv``, its placement ``extra`` [m] further out."""
    panel = pattern.panels[pi]
    pl = panel.placement
    if pl is None:
        pattern.fail(panel.where(), "the panel has no placement (give 'placement' or 'translation'/'rotation')")
    if isinstance(pl, TransformPlacement):  # drafted for GarmentCode's neutral body: moved onto this one
        drafted = pl.apply(uv)
        x = drafted if not landmarks else BodyRetarget(landmarks).move(panel.label, drafted)
        if x is not drafted:
            log.info("%s: panel %s moved with the body up to %.1f cm from where it was drafted", pattern.source,
                     panel.name, 100 * float(np.sqrt(np.einsum("ij,ij->i", x - drafted, x - drafted).max())))
        return x if inside is None else _clear_rigid(x, pl, inside, body_axis, clearance=0.01 + extra)
    if landmarks is None:
        raise PatternError(f"{pattern.source}: {panel.where()}.placement: a landmark placement needs a body")
    if extra:
        pl = replace(pl, clearance=pl.clearance + extra)
    name = "bust" if pl.landmark == "chest" else pl.landmark
    lm = landmarks.get(name) or landmarks.get(pl.landmark)
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    anchor = np.array(pl.anchor) if pl.anchor is not None else np.array([0.5 * (lo[0] + hi[0]), hi[1]])
    arc = _waist_arc(panel, anchor) if lm.width > 0 and lm.depth > 0 else None
    coned = _cone(uv, anchor, arc, lm, pl, 1.0 / count, inside) if arc is not None else None
    return coned if coned is not None else _wrap(uv, anchor, lm, pl, 1.0 / count, inside)
