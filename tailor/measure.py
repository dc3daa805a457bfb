"""Landmarks of any standing human mesh, found by slicing it like a tailor's tape.

The body (metres, Z up, facing −Y, :func:`tailor.body.normalise_body`) is cut by horizontal
planes every 5 mm. The trunk is followed from cut to cut (:func:`tailor.sections.trunk_chain`)
from its largest outline at 60 % of the height, so the body may stand anywhere and its hands may
hang close beside it. Girths are convex-hull perimeters of the outlines (what a tape measure
reads). Heights are searched in fractions of the body's height H, so a child measures like an adult:

* crotch: the lowest cut of the trunk (below it the legs part);
* armpits: the first cut above 62 % of H where an arm joins the trunk (an outline beside it
  merges in: A-pose) or the trunk's outline widens by a third at once (an arm's underside: T-pose);
* hips: the largest trunk girth from 0.01 H to 0.12 H above the crotch; waist: the smallest between
  hips and armpits; chest/bust: the largest between waist and armpits; underbust: midway
  between waist and bust; neck: the smallest above the armpits; shoulders: where the outline above
  the armpits narrows to under twice the neck;
* legs: each followed down from the crotch; thighs 0.02 H below it, knees and ankles at the
  smallest girths between 22–36 % and 3–12 % of H;
* arms: the vertices beyond the trunk and legs (below the armpits) and beyond the chest (above
  them); each arm's axis by principal components, then cuts across it: the wrist at the smallest
  girth between 40 % and 85 % of the way from the armpit to the fingertips, the elbow 45 % and the
  upper arm 27 % of the way from the armpit to the wrist.

A body these rules cannot read raises one :class:`~tailor.errors.BodyError` naming what is
missing and the pose that would work. Pattern placements name these landmarks, so one pattern
dresses bodies it has never seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import BodyError
from .landmarks import LANDMARKS
from .sections import TrunkChain, horizontal_outlines, trunk_chain

__all__ = ["Landmark", "find_landmarks", "measure_body", "girth_profile", "Profile", "STEP"]

STEP = 0.005
"""Spacing of the horizontal cuts [m]."""

POSES = "a standing body, legs apart at least above the knees, arms away from the trunk (A-pose 20–60° down, or T-pose)"
"""The pose every landmark can be found in, for error messages."""


@dataclass(frozen=True, slots=True)
class Landmark:
    """A cross-section of the body.

    Attributes
    ----------
    name : str
    center : tuple (3,) [m]
        Centroid of the cross-section.
    axis : tuple (3,)
        Unit normal of the cut: +Z for the trunk and legs, towards the shoulder along an arm.
    girth : float [m]
        Convex-hull perimeter of the outline (a tape measure's reading).
    width, depth : float [m]
        Extent across the body (x for the trunk) and front to back.
    """

    name: str
    center: tuple
    axis: tuple
    girth: float
    width: float
    depth: float

    @property
    def height(self) -> float:
        """Height of the centre above the floor [m]."""
        return float(self.center[2])


def _landmark(name, poly, z, axis=(0.0, 0.0, 1.0)):
    minx, miny, maxx, maxy = poly.bounds
    c = poly.centroid
    return Landmark(name, (float(c.x), float(c.y), float(z)), tuple(axis), float(poly.convex_hull.length),
                    float(maxx - minx), float(maxy - miny))


@dataclass(frozen=True)
class Profile:
    """The body cut every :data:`STEP` from the floor up, with its trunk followed through the cuts.

    Attributes
    ----------
    z : (K,) cut heights [m]; cuts : list of lists of Polygons (largest first)
    chain : TrunkChain
    girth, width : (K,) trunk girth and width per cut [m] (NaN where the trunk is not)
    height : float
        H [m].
    """

    z: np.ndarray
    cuts: list
    chain: TrunkChain
    girth: np.ndarray
    width: np.ndarray
    height: float

    def trunk(self, k):
        """The trunk's outline in cut ``k`` (None outside the trunk)."""
        return self.chain.outline(self.cuts, k)

    def at(self, frac: float) -> int:
        """The cut nearest ``frac`` × H."""
        return int(np.clip(np.searchsorted(self.z, frac * self.height), 0, len(self.z) - 1))


def girth_profile(vertices, faces, step: float = STEP) -> Profile:
    """Cuts of the whole body and the trunk followed through them (for landmarks, plots and tests)."""
    v = np.asarray(vertices, float)
    height = float(v[:, 2].max())
    z = np.arange(0.01, height - 0.005, step)
    cuts = horizontal_outlines(v, faces, z)
    if len(z) < 20:
        raise BodyError(f"the body is {height * 100:.3g} cm tall: too small to measure")
    seed = int(np.clip(np.searchsorted(z, 0.6 * height), 0, len(z) - 1))
    chain = trunk_chain(cuts, seed)
    outlines = [chain.outline(cuts, k) for k in range(len(z))]
    girth = np.array([p.convex_hull.length if p is not None else np.nan for p in outlines])
    width = np.array([p.bounds[2] - p.bounds[0] if p is not None else np.nan for p in outlines])
    return Profile(z, cuts, chain, girth, width, height)


FLAT = 0.003
"""Girths within 3 mm of the extreme count as the extreme: the landmark is the middle of that band
(a waist is a flat stretch of the trunk; its lowest reading moves with the mesh)."""


def _argbest(z, values, lo, hi, pick):
    """The cut in heights [lo, hi] at the middle of the run of girths within :data:`FLAT` of the
    largest (``pick="max"``) or smallest, the run holding the extreme itself."""
    sel = np.flatnonzero((z >= lo) & (z <= hi) & np.isfinite(values))
    if not len(sel):
        return None
    v = values[sel] if pick == "min" else -values[sel]
    best = int(np.argmin(v))
    near = v <= v[best] + FLAT
    a = best
    while a > 0 and near[a - 1]:
        a -= 1
    b = best
    while b < len(v) - 1 and near[b + 1]:
        b += 1
    return int(sel[(a + b) // 2])


def _midline_share(poly, cx) -> float:
    """Depth of ``poly`` along the line x = ``cx`` over its largest depth (thighs pressed together: small)."""
    from shapely.geometry import LineString

    x0, y0, x1, y1 = poly.bounds
    cut = poly.intersection(LineString([(cx, y0 - 1.0), (cx, y1 + 1.0)]))
    return cut.length / max(y1 - y0, 1e-12)


def _crotch(p: Profile) -> int:
    """The lowest trunk cut above where the legs part, or where they press together (heavy thighs touch:
    the outline below the crotch is two lobes joined by a narrow neck at the body's midline)."""
    seed = p.at(0.6)
    cx = p.trunk(seed).centroid.x
    k = p.chain.split
    for j in range(seed - 1, max(k, 0) - 1, -1):
        if _midline_share(p.trunk(j), cx) < 0.5:
            k = j + 1
            break
    if k < 0 or p.z[k] < 0.3 * p.height:
        where = "reach the floor" if k < 0 else f"stay joined down to {p.z[k] * 100:.0f} cm"
        raise BodyError(f"no crotch found: the legs {where}; tailor needs {POSES}")
    return k


def _armpit(p: Profile, crotch: int) -> int:
    """The last cut below the first arm joining the trunk above 62 % of H (see the module docstring)."""
    top = p.at(0.9)
    for k in range(max(p.at(0.62), crotch + 2), top):
        if p.trunk(k) is None:
            break
        if p.chain.absorbed[k] or p.width[k] > 4.0 / 3.0 * p.width[k - 1]:
            return k - 1
    raise BodyError(f"no armpits found: the arms do not join the trunk between 62 % and 90 % of the height; tailor needs {POSES}")


def _torso(p: Profile):
    """The trunk's landmarks and the cuts of the crotch and armpits."""
    H, z, girth = p.height, p.z, p.girth
    kc = _crotch(p)
    ka = _armpit(p, kc)
    zc, za = z[kc], z[ka]
    found = {"crotch": kc}
    found["hips"] = _argbest(z, girth, zc + 0.01 * H, zc + 0.116 * H, "max")
    if found["hips"] is not None:
        found["waist"] = _argbest(z, girth, z[found["hips"]] + 0.03 * H, za - 0.058 * H, "min")
    if found.get("waist") is not None:
        # below 74.5 % of H too: arms raised to a T lift the armpits, and the back muscles beside them are no bust
        found["bust"] = _argbest(z, girth, z[found["waist"]] + 0.03 * H, min(za - 0.005, 0.745 * H), "max")
    if found.get("bust") is not None:
        found["underbust"] = int(np.argmin(np.abs(z - 0.5 * (z[found["waist"]] + z[found["bust"]]))))
    found["neck"] = _argbest(z, girth, za + 0.047 * H, 0.93 * H, "min")
    missing = [k for k in ("hips", "waist", "bust", "underbust", "neck") if found.get(k) is None or p.trunk(found[k]) is None]
    if missing:
        raise BodyError(f"no {', '.join(missing)} found between the crotch ({zc * 100:.0f} cm) and the armpits "
                        f"({za * 100:.0f} cm); tailor needs {POSES}")
    out = {name: _landmark(name, p.trunk(k), z[k]) for name, k in found.items()}
    out["chest"] = Landmark("chest", *[getattr(out["bust"], f) for f in ("center", "axis", "girth", "width", "depth")])
    out["armpits"] = _landmark("armpits", p.trunk(ka), za)
    neck_w = out["neck"].width
    kn = found["neck"]
    ks = next((k for k in range(ka + 1, kn) if p.width[k] < 2.0 * neck_w), kn)
    ks = max(ks - 1, ka + 1)
    out["shoulders"] = _landmark("shoulders", p.trunk(ks), z[ks])
    return out, kc, ka


def _half_cuts(cuts, cx, sign):
    """Every cut's outlines clipped to the side ``sign`` of the line x = ``cx`` (empty pieces dropped)."""
    from shapely.geometry import box

    side = box(cx, -10.0, cx + 10.0, 10.0) if sign > 0 else box(cx - 10.0, -10.0, cx, 10.0)
    def within(q):
        return q.bounds[0] >= cx if sign > 0 else q.bounds[2] <= cx

    out = []
    for polys in cuts:
        pieces = [q if within(q) else q.intersection(side) for q in polys]
        out.append([g for piece in pieces for g in getattr(piece, "geoms", [piece]) if g.geom_type == "Polygon" and g.area > 1e-6])
    return out


def _follow_down(cuts, k, poly):
    """{cut: outline} of the part below ``poly`` (in cut ``k + 1``), followed down by overlap."""
    out = {}
    above = poly
    for j in range(k, -1, -1):
        over = [above.intersection(q).area if q.intersects(above) else 0.0 for q in cuts[j]]
        if not over or max(over) <= 0:
            break
        above = out[j] = cuts[j][int(np.argmax(over))]
    return out


def _legs(p: Profile, kc: int):
    """Thigh, knee and ankle of each leg, and every cut's leg outlines (for the arms' search)."""
    H, z = p.height, p.z
    cx = p.trunk(kc).centroid.x
    out, legs = {}, {}
    for sign, prefix in ((1, "left"), (-1, "right")):
        half = _half_cuts(p.cuts[:kc], cx, sign)  # a leg stays on its side of the midline, even where thighs touch
        below = [q for q in half[kc - 1] if q.intersects(p.trunk(kc))] if kc else []
        if not below:
            raise BodyError(f"no {prefix} leg found below the crotch ({z[kc] * 100:.0f} cm); tailor needs {POSES}")
        top = max(below, key=lambda q: q.area)
        leg = _follow_down(half, kc - 2, top)
        leg[kc - 1] = top
        legs[prefix] = leg
        g = np.array([leg[k].convex_hull.length if k in leg else np.nan for k in range(len(z))])
        picks = {"thigh": max(kc - int(round(0.02 * H / STEP)), 0),
                 "knee": _argbest(z, g, 0.22 * H, 0.36 * H, "min"), "ankle": _argbest(z, g, 0.03 * H, 0.12 * H, "min")}
        for name, k in picks.items():
            if k is None or k not in leg:
                raise BodyError(f"no {prefix} {name} found: the leg ends above it; tailor needs {POSES}")
            out[f"{prefix}_{name}"] = _landmark(f"{prefix}_{name}", leg[k], z[k])
    return out, legs


def find_landmarks(vertices, faces) -> dict:
    """Every landmark of :data:`tailor.landmarks.LANDMARKS` on a normalised standing body.

    Raises
    ------
    BodyError
        One line naming the landmark not found and the pose that would work.
    """
    v = np.asarray(vertices, float)
    faces = np.asarray(faces)
    p = girth_profile(v, faces)
    if p.trunk(p.at(0.6)) is None:
        raise BodyError(f"no trunk found at 60 % of the height; tailor needs {POSES}")
    out, kc, ka = _torso(p)
    legs, leg_cuts = _legs(p, kc)
    out.update(legs)
    from .arms import arm_landmarks

    out.update(arm_landmarks(v, faces, p, kc, ka, leg_cuts))
    missing = [n for n in LANDMARKS if n not in out]
    if missing:  # pragma: no cover - every name above is produced
        raise BodyError(f"landmarks not found: {', '.join(missing)}")
    return out


def measure_body(body, pose=None) -> dict:
    """:func:`find_landmarks` of a :class:`~tailor.body.Body` (``pose``: other vertices of its mesh,
    default its rest pose, else its first frame); errors name the body's file."""
    if pose is None:
        pose = body.rest if body.rest is not None else body.vertices
    try:
        return find_landmarks(pose, body.faces)
    except BodyError as exc:
        raise BodyError(f"{body.report.get('source', body.name)}: {exc}") from None
