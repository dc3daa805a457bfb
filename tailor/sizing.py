"""Does a pattern fit a body: the pattern's closed loops against the body's girths, and grading.

A garment placed round a landmark (a skirt's panels round the waist, a T-shirt's round the
chest, a sleeve round the upper arm) is a closed loop there once sewn: its length is the sum
of the panels' widths across the row that lies on the landmark. A loop shorter than the body's
girth cannot close round it — the sewing would strain the seams until it timed out minutes
later — so :func:`check_loops` says so before any simulation, naming the loop, both lengths and
the fix.

:func:`grade` resizes a pattern to a body proportionally (a pattern maker's grading): the
landmarks of the body the pattern was drafted for (the caller's: ``tailor`` takes its default
mannequin, GarmentCode's mean body, or a body or GarmentCode measurement YAML given as
``--design-body``, since pattern files carry no body measurements) against the body's. Girths scale the panels across, lengths along, each region (trunk, arms, legs) by its own
ratio; a limb panel sewn to the trunk (a sleeve cap to its armhole, a trouser leg to its
waistband) then gives way across until those seams are as long relative to each other as they
were, so seams stay matched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .errors import FitError
from .pattern import LandmarkPlacement

__all__ = ["Loop", "pattern_loops", "check_loops", "loop_girth", "NEGATIVE_EASE", "FitError", "grade", "grade_scales",
           "scaled_panel"]

NEGATIVE_EASE = 0.05
"""Share by which a loop may be shorter than the girth it goes round (a snug, stretched fit)."""


@dataclass(frozen=True)
class Loop:
    """A closed loop of a pattern round a landmark.

    Attributes
    ----------
    landmark : str
    panels : tuple of str
        The panels that make it, in pattern order.
    length : float
        Its length across the landmark's row [m].
    girth : float or None
        The body's girth there [m] (None before a body is given).
    """

    landmark: str
    panels: tuple
    length: float
    girth: float | None = None

    @property
    def ease(self) -> float:
        """Length minus girth [m] (negative: tighter than the body)."""
        return self.length - self.girth


def _outline(panel):
    from shapely.geometry import Polygon

    from .curves import loop_polyline

    return Polygon(loop_polyline([e.curve for e in panel.loop(None)]))


def _row_width(panel) -> float:
    """The panel's width across the rows its placement puts on the landmark [m]: the widest row within
    4 cm (a curved waistline's highest point is narrower than the waist it makes; the openings of
    darts crossing a row are left out, as they are sewn shut)."""
    from shapely.geometry import LineString

    poly = _outline(panel)
    x0, y0, x1, y1 = poly.bounds
    pl = panel.placement
    anchor_y = pl.anchor[1] if pl.anchor is not None else y1
    rows = np.clip(anchor_y - pl.offset + np.linspace(-0.04, 0.04, 9), y0 + 1e-3, y1 - 1e-3)
    return max(float(poly.intersection(LineString([(x0 - 1.0, y), (x1 + 1.0, y)])).length) for y in rows)


def _is_ring(pattern, names) -> bool:
    """Whether the panels ``names`` are sewn into a ring (as many seams among them as panels, connected)."""
    index = {n: i for i, n in enumerate(names)}
    links = [(index[s.a.panel], index[s.b.panel]) for s in pattern.seams if s.a.panel in index and s.b.panel in index]
    if len(links) < len(names):
        return False
    parent = list(range(len(names)))

    def root(i):
        while parent[i] != i:
            i = parent[i]
        return i

    for a, b in links:
        parent[root(a)] = root(b)
    return len({root(i) for i in range(len(names))}) == 1


def pattern_loops(pattern) -> list[Loop]:
    """Every closed loop of ``pattern`` round a landmark (body-relative placements only).

    Panels at one landmark and one angle stack (a waistband above a skirt's front): the narrowest
    is the loop's part there (the band; a flared panel's straight row runs below its curved top).
    Panels round a landmark that are not sewn into a ring (an apron) make no loop.
    """
    groups: dict = {}
    for panel in pattern.panels:
        pl = panel.placement
        if isinstance(pl, LandmarkPlacement):
            key = round(pl.angle % (2 * math.pi), 6)
            groups.setdefault(pl.landmark, {}).setdefault(key, []).append(panel)
    out = []
    for landmark, by_angle in groups.items():
        panels = [p for stack in by_angle.values() for p in stack]
        names = tuple(p.name for p in pattern.panels if p in panels)
        if not _is_ring(pattern, names):
            continue
        length = sum(min(_row_width(p) for p in stack) for stack in by_angle.values())
        out.append(Loop(landmark, names, length))
    return out


def check_loops(pattern, landmarks, *, negative_ease: float = NEGATIVE_EASE) -> list[Loop]:
    """The pattern's loops with the body's girths; raises :class:`FitError` for one that cannot close.

    Parameters
    ----------
    landmarks : dict of name → Landmark
        The body's (:func:`tailor.measure.find_landmarks`).
    """
    out = []
    for loop in pattern_loops(pattern):
        girth = loop_girth(landmarks, loop.landmark)
        if girth is None:
            continue
        name = "bust" if loop.landmark == "chest" else loop.landmark
        loop = replace(loop, girth=girth)
        if loop.length < (1.0 - negative_ease) * loop.girth:
            raise FitError(
                f"{pattern.source}: the {loop.landmark.replace('_', ' ')} loop ({', '.join(loop.panels)}) is "
                f"{loop.length * 100:.1f} cm round but the body's {name.replace('_', ' ')} is {loop.girth * 100:.1f} cm: "
                f"it cannot close round it; grade the pattern to the body (tailor drape --grade auto, or tailor grade "
                f"PATTERN --body BODY --out PATTERN.json)"
            )
        out.append(loop)
    return out


def loop_girth(landmarks, landmark: str) -> float | None:
    """The body's girth [m] where a loop round ``landmark`` lies (a chest loop goes round the bust);
    None where the body has no such landmark."""
    mark = landmarks.get("bust" if landmark == "chest" else landmark) or landmarks.get(landmark)
    return None if mark is None else mark.girth


# ---- grading ---------------------------------------------------------------------------------------

REGIONS = {"arm": ("left_upper_arm", "right_upper_arm", "left_elbow", "right_elbow", "left_wrist", "right_wrist"),
           "leg": ("left_thigh", "right_thigh", "left_knee", "right_knee", "left_ankle", "right_ankle")}
"""Landmarks of the limbs; every other landmark is the trunk's."""


def _region(landmark: str) -> str:
    return next((r for r, names in REGIONS.items() if landmark in names), "trunk")


def _lengths(marks) -> dict:
    """Per region, the length a panel there scales its height with [m]."""
    arm = np.mean([np.linalg.norm(np.subtract(marks[f"{s}_upper_arm"].center, marks[f"{s}_wrist"].center))
                   for s in ("left", "right")])
    return {"trunk": marks["neck"].height, "arm": float(arm), "leg": marks["crotch"].height}


def _girth(marks, landmark):
    return (marks.get("bust") if landmark == "chest" else marks[landmark]).girth


def grade_scales(pattern, body, design) -> dict:
    """Per panel name, (horizontal, vertical) scale taking ``design``'s landmarks to ``body``'s.

    A panel round a landmark scales across by that landmark's girth ratio and along by its region's
    length ratio (trunk: the neck's height; arms: upper arm to wrist; legs: the crotch's height). A
    rigidly placed panel scales by the mean of the bust, waist and hips ratios and by the trunk's.
    """
    lb, ld = _lengths(body), _lengths(design)
    mean = float(np.mean([_girth(body, k) / _girth(design, k) for k in ("bust", "waist", "hips")]))
    out = {}
    for panel in pattern.panels:
        pl = panel.placement
        if isinstance(pl, LandmarkPlacement):
            region = _region(pl.landmark)
            out[panel.name] = (_girth(body, pl.landmark) / _girth(design, pl.landmark), lb[region] / ld[region])
        else:
            out[panel.name] = (mean, lb["trunk"] / ld["trunk"])
    return out


def _scale_curve(curve, f):
    from .curves import Curve

    pts = tuple(tuple(map(float, f(np.asarray(p, float)))) for p in curve.points)
    if curve.kind != "circle":
        return replace(curve, points=pts)
    chord = 0.5 * float(np.linalg.norm(np.subtract(pts[-1], pts[0])))
    old_chord = 0.5 * float(np.linalg.norm(np.subtract(curve.points[-1], curve.points[0])))
    radius = max(curve.radius * chord / max(old_chord, 1e-12), chord * (1.0 + 1e-9))  # the same arc's share of a circle
    return Curve(curve.kind, pts, radius, curve.large_arc, curve.sweep)


def scaled_panel(panel, sx, sy):
    """``panel`` scaled by (sx, sy) about its anchor (a rigid placement: about its origin, moving it too)."""
    pl = panel.placement
    if isinstance(pl, LandmarkPlacement):
        lo = np.min(panel.vertices, axis=0)
        hi = np.max(panel.vertices, axis=0)
        pivot = np.asarray(pl.anchor if pl.anchor is not None else (0.5 * (lo[0] + hi[0]), hi[1]), float)
        placement = replace(pl, offset=pl.offset * sy)
    else:
        pivot = np.zeros(2)
        t = np.asarray(pl.translation, float)
        placement = replace(pl, translation=(t[0] * sx, t[1] * sx, t[2] * sy)) if pl is not None else None
    s = np.array([sx, sy])

    def f(p):
        return pivot + s * (p - pivot)

    def edges(loop):
        return tuple(replace(e, curve=_scale_curve(e.curve, f)) for e in loop)

    out = replace(panel, vertices=tuple(tuple(map(float, f(np.asarray(v, float)))) for v in panel.vertices),
                  edges=edges(panel.edges), holes=tuple(edges(h) for h in panel.holes), placement=placement)
    if isinstance(pl, LandmarkPlacement) and pl.anchor is not None:
        out = replace(out, placement=replace(placement, anchor=_on_outline(pl.anchor, panel, out)))
    return out


def _on_outline(anchor, panel, scaled):
    """``anchor`` of ``panel`` on ``scaled``'s outline where it lay on ``panel``'s (else as it is).

    The anchor is the scaling's pivot, so a straight edge through it stays through it; a circular
    edge is rescaled as a circle (:func:`_scale_curve`), and its new arc passes beside the pivot: a
    circle skirt's waist, eased over trousers, ran 1 cm below its anchor, which then no longer named
    the skirt's waist arc and the skirt was rolled instead of laid on its cone."""
    a = np.asarray(anchor, float)
    if np.linalg.norm(_nearest_on_outline(panel, a) - a) > 1e-3:
        return anchor
    q = _nearest_on_outline(scaled, a)
    return anchor if np.linalg.norm(q - a) < 1e-9 else tuple(map(float, q))


def _nearest_on_outline(panel, point) -> np.ndarray:
    """The point of ``panel``'s outline (each edge a polyline of 256 segments) nearest ``point``."""
    from .curves import sample_curve

    lines = [sample_curve(e.curve, np.linspace(0.0, 1.0, 257)) for e in panel.edges]
    p0 = np.concatenate([p[:-1] for p in lines])
    d = np.concatenate([np.diff(p, axis=0) for p in lines])
    t = np.clip(np.einsum("ij,ij->i", point - p0, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-30), 0.0, 1.0)
    q = p0 + t[:, None] * d
    return q[np.argmin(np.linalg.norm(q - point, axis=1))]


def _match_seams(pattern, graded, scales):
    """Limb panels sewn to trunk panels rescaled across until those seams are as long, relative to each
    other, as in ``pattern`` (a sleeve cap to its armhole, a trouser leg's top to its waistband)."""
    region = {p.name: _region(p.placement.landmark) if isinstance(p.placement, LandmarkPlacement) else "trunk"
              for p in pattern.panels}
    for panel in pattern.panels:
        if region[panel.name] == "trunk":
            continue
        own = [(s.a, s.b) if s.a.panel == panel.name else (s.b, s.a) for s in pattern.seams
               if (s.a.panel == panel.name) != (s.b.panel == panel.name)
               and region[(s.b if s.a.panel == panel.name else s.a).panel] == "trunk"]
        if not own:
            continue
        target = sum(graded.side_length(o) * pattern.side_length(m) / pattern.side_length(o) for m, o in own)
        sx, sy = scales[panel.name]
        lo, hi = 0.5, 2.0
        for _ in range(40):  # the seam's length grows with the panel's width: bisect the factor
            k = 0.5 * (lo + hi)
            trial = replace(graded, panels=tuple(scaled_panel(p, sx * k, sy) if p.name == panel.name else q
                                                 for p, q in zip(pattern.panels, graded.panels)))
            lo, hi = (k, hi) if sum(trial.side_length(m) for m, _ in own) < target else (lo, k)
        graded = trial
        scales[panel.name] = (sx * k, sy)
    return graded


def grade(pattern, body, design):
    """``pattern`` graded from the ``design`` body's landmarks to ``body``'s (see the module docstring).

    Returns
    -------
    (Pattern, dict)
        The graded pattern (validated) and the (horizontal, vertical) scale of each panel.
    """
    from .pattern import validate_pattern

    scales = grade_scales(pattern, body, design)
    graded = replace(pattern, panels=tuple(scaled_panel(p, *scales[p.name]) for p in pattern.panels))
    graded = _match_seams(pattern, graded, scales)
    return validate_pattern(graded), scales
