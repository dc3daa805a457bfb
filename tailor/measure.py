"""Landmarks of any standing human mesh, found by slicing it like a tailor's tape.

The body (metres, Z up, facing −Y) is cut by horizontal planes every 5 mm. Each cut is a set of
closed outlines; the one around the body's vertical axis is the trunk, two beside it are the
arms (above the hands) or, below the crotch, the legs. From the girths (convex-hull perimeter,
what a tape measure reads) and the count of outlines:

* crotch: the lowest cut whose outline encloses the body axis (below it the legs are apart);
* armpits: the highest cut, below the shoulders, where the arms are still separate outlines;
* hips: the largest trunk girth in the 20 cm above the crotch; waist: the smallest between
  hips and armpits; chest/bust: the largest between waist and armpits; underbust: midway
  between waist and bust; neck: the smallest above the armpits; shoulders: where the outline above
  the armpits narrows to under twice the neck;
* legs: thighs just below the crotch, knees and ankles at the smallest leg girths;
* arms: each arm's axis by principal components of the vertices beyond the trunk, then cuts
  across it at the upper arm, elbow and wrist.

Pattern placements name these landmarks, so one pattern dresses bodies it has never seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import BodyError
from .landmarks import LANDMARKS

__all__ = ["Landmark", "find_landmarks", "girth_profile"]


@dataclass(frozen=True, slots=True)
class Landmark:
    """A cross-section of the body.

    Attributes
    ----------
    name : str
    center : (3,) [m]
        Centroid of the cross-section.
    axis : (3,)
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


def _outlines(mesh, z_values):
    """Closed outlines (list of shapely Polygons) of horizontal cuts at ``z_values``."""
    from shapely.geometry import Polygon

    sections = mesh.section_multiplane(plane_origin=[0, 0, 0], plane_normal=[0, 0, 1], heights=z_values)
    out = []
    for sec in sections:
        polys = []
        if sec is not None:
            for ring in sec.discrete:
                if len(ring) >= 4:
                    p = Polygon(ring)
                    if p.is_valid and p.area > 1e-6:
                        polys.append(p)
                    elif not p.is_valid:
                        p = p.buffer(0)
                        if p.area > 1e-6:
                            polys.extend(getattr(p, "geoms", [p]))
        out.append(polys)
    return out


def _landmark(name, poly, z, axis=(0.0, 0.0, 1.0)):
    hull = poly.convex_hull
    minx, miny, maxx, maxy = poly.bounds
    c = poly.centroid
    return Landmark(name, (float(c.x), float(c.y), float(z)), tuple(axis), float(hull.length), float(maxx - minx), float(maxy - miny))


def girth_profile(vertices, faces, step: float = 0.005):
    """Heights, trunk outline and number of outlines of every horizontal cut (for plots and tests)."""
    import trimesh
    from shapely.geometry import Point

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    z = np.arange(0.02, float(vertices[:, 2].max()) - 0.01, step)
    cuts = _outlines(mesh, z)
    axis_pt = Point(0.0, 0.0)
    trunk, counts = [], []
    for polys in cuts:
        inside = [p for p in polys if p.contains(axis_pt)]
        trunk.append(inside[0] if inside else None)
        counts.append(len(polys))
    return z, trunk, np.array(counts), cuts


def _argbest(z, values, lo, hi, pick):
    sel = np.flatnonzero((z >= lo) & (z <= hi) & np.isfinite(values))
    if not len(sel):
        return None
    return sel[np.argmax(values[sel])] if pick == "max" else sel[np.argmin(values[sel])]


def find_landmarks(vertices, faces) -> dict:
    """Every landmark of :data:`tailor.landmarks.LANDMARKS` on a normalised standing body.

    Raises
    ------
    BodyError
        When the mesh does not look like a standing human (no crotch or no separate arms).
    """
    import trimesh

    v = np.asarray(vertices, float)
    height = float(v[:, 2].max())
    z, trunk, counts, cuts = girth_profile(v, faces)
    girth = np.array([t.convex_hull.length if t is not None else np.nan for t in trunk])
    has_trunk = np.array([t is not None for t in trunk])
    # crotch: lowest cut above the knees whose outline encloses the axis
    above_knees = np.flatnonzero(has_trunk & (z > 0.3 * height))
    if not len(above_knees):
        raise BodyError("no trunk found: is this a standing human, centred, feet on the floor?")
    i_crotch = above_knees[0]
    # armpits: highest cut below 0.9 H with separate arm outlines beside the trunk
    side = np.array([sum(1 for p in c if abs(p.centroid.x) > 0.12) for c in cuts])
    arm_rows = np.flatnonzero((side >= 2) & (z > z[i_crotch] + 0.1) & (z < 0.9 * height))
    if not len(arm_rows):
        raise BodyError("no arms apart from the body found: tailor needs an A-pose or T-pose body")
    breaks = np.flatnonzero(np.diff(arm_rows) > 1)
    i_armpit = arm_rows[breaks[0]] if len(breaks) else arm_rows[-1]  # top of the first run of separate arms
    zc, za = z[i_crotch], z[i_armpit]
    out = {}
    i_hips = _argbest(z, girth, zc, zc + 0.2, "max")
    i_waist = _argbest(z, girth, z[i_hips] + 0.05, za - 0.1, "min")
    i_bust = _argbest(z, girth, z[i_waist] + 0.05, za - 0.03, "max")  # clear of the arm roots
    i_under = int(np.argmin(np.abs(z - 0.5 * (z[i_waist] + z[i_bust]))))  # tape line midway, as GarmentCode measures
    i_neck = _argbest(z, girth, za + 0.08, 0.93 * height, "min")
    for name, i in (("crotch", i_crotch), ("hips", i_hips), ("waist", i_waist), ("bust", i_bust),
                    ("underbust", i_under), ("neck", i_neck)):
        out[name] = _landmark(name, trunk[i], z[i])
    out["chest"] = Landmark("chest", *[getattr(out["bust"], k) for k in ("center", "axis", "girth", "width", "depth")])
    neck_w = out["neck"].width
    i_sh = next((i for i in range(i_armpit + 1, i_neck) if trunk[i] is not None and trunk[i].bounds[2] - trunk[i].bounds[0] < 2.0 * neck_w), i_neck)
    i_sh = max(i_sh - 1, i_armpit + 1)
    out["shoulders"] = _landmark("shoulders", trunk[i_sh], z[i_sh])
    # legs: outlines left (+x) and right (−x) below the crotch
    for sign, prefix in ((1, "left"), (-1, "right")):
        def leg(i):
            polys = [p for p in cuts[i] if sign * p.centroid.x > 0.02]
            return max(polys, key=lambda p: p.area) if polys else None

        legs = [leg(i) for i in range(len(z))]
        leg_girth = np.array([g.convex_hull.length if g is not None else np.nan for g in legs])
        i_thigh = max(i_crotch - int(0.03 / 0.005), 0)
        i_knee = _argbest(z, leg_girth, 0.22 * height, 0.36 * height, "min")
        i_ankle = _argbest(z, leg_girth, 0.03 * height, 0.12 * height, "min")
        for name, i in (("thigh", i_thigh), ("knee", i_knee), ("ankle", i_ankle)):
            if i is None or legs[i] is None:
                raise BodyError(f"no {prefix} {name} found")
            out[f"{prefix}_{name}"] = _landmark(f"{prefix}_{name}", legs[i], z[i])
    # arms: vertices beyond the trunk at armpit height
    from shapely.geometry import Point, Polygon

    mesh = trimesh.Trimesh(v, faces, process=False)
    torso_half = max(abs(b) for b in trunk[i_armpit].bounds[::2])
    for sign, prefix in ((1, "left"), (-1, "right")):
        pts = v[(sign * v[:, 0] > torso_half + 0.02) & (v[:, 2] > zc)]
        if len(pts) < 20:
            raise BodyError(f"no {prefix} arm found")
        c = pts.mean(axis=0)
        _, _, vt = np.linalg.svd(pts - c, full_matrices=False)
        axis = vt[0] * np.sign(vt[0][0] * sign)  # from the shoulder outwards
        s = (pts - c) @ axis
        s0, s1 = s.min(), s.max()
        length = s1 - s0
        proximal = -axis  # landmark axis points towards the shoulder
        for name, frac in (("upper_arm", 0.22), ("elbow", 0.5), ("wrist", 0.8)):
            p0 = c + (s0 + frac * length) * axis
            sec = mesh.section(plane_origin=p0, plane_normal=axis)
            if sec is None:
                raise BodyError(f"no {prefix} {name} section found")
            u = np.cross(axis, [0.0, 1.0, 0.0])
            u /= np.linalg.norm(u)
            w = np.cross(axis, u)
            polys = []
            for ring in sec.discrete:
                if len(ring) >= 4:
                    q = Polygon(np.column_stack([(ring - p0) @ u, (ring - p0) @ w]))
                    polys.append(q if q.is_valid else q.buffer(0))
            polys = [q for q in polys if q.area > 1e-6]
            if not polys:
                raise BodyError(f"no {prefix} {name} section found")
            best = min(polys, key=lambda q: q.distance(Point(0, 0)))
            cen = p0 + best.centroid.x * u + best.centroid.y * w
            minx, miny, maxx, maxy = best.bounds
            out[f"{prefix}_{name}"] = Landmark(
                f"{prefix}_{name}", tuple(cen.tolist()), tuple(proximal.tolist()),
                float(best.convex_hull.length), float(maxx - minx), float(maxy - miny),
            )
    missing = [n for n in LANDMARKS if n not in out]
    if missing:  # pragma: no cover - every name above is produced
        raise BodyError(f"landmarks not found: {', '.join(missing)}")
    return out
