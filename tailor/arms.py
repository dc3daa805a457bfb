"""The arms' landmarks: each arm found beside the trunk, its axis, and cuts across it.

Below the armpits an arm is whatever lies outside the trunk's and legs' outlines on its side of
the trunk (so hands hanging beside the hips, and their fingers, are the arm's); above them it is
what lies beyond the chest's half width (the shoulder cap; in a T-pose, the whole arm). The
principal axis of the upper arm's vertices starts a centre-line trace: a cut across the arm every
centimetre, a step to the cut's centroid, a turn towards it — so an elbow bent forward and a hand
hanging off the forearm's line are followed. The girths along that line give the wrist (the
narrowest between 40 % and 85 % of the way from the armpit to the fingertips), the elbow (where
the line bends most, or 45 % of the way to a straight arm's wrist) and the upper arm (midway
from the armpit to the elbow).
"""

from __future__ import annotations

import numpy as np

from .errors import BodyError
from .measure import POSES, STEP, Landmark
from .sections import cut_outlines, plane_frame

__all__ = ["arm_landmarks"]

ARM_CUT = 0.01
"""Spacing of the cuts across an arm [m]."""


def _body_outline(p, k, kc, leg_cuts):
    """The trunk's outline (above the crotch) or the legs' convex hull (below it) in cut ``k``, or None."""
    import shapely

    if k >= kc:
        return p.trunk(k)
    legs = [leg[k] for leg in leg_cuts.values() if k in leg]
    return shapely.union_all(legs).convex_hull if legs else None


def _arm_points(v, p, kc, ka, leg_cuts, sign):
    """Vertices [m] of the arm on side ``sign`` (+1: the body's left, +X)."""
    import shapely

    chest = p.trunk(ka)
    cx = chest.centroid.x
    half = max(chest.bounds[2] - cx, cx - chest.bounds[0])
    side = sign * (v[:, 0] - cx) > 0
    k_of = np.clip(np.round((v[:, 2] - p.z[0]) / STEP).astype(int), 0, len(p.z) - 1)
    above = side & (v[:, 2] > p.z[ka]) & (v[:, 2] < p.z[ka] + 0.1 * p.height) & (sign * (v[:, 0] - cx) > half + 0.01)
    keep = above.copy()
    below = np.flatnonzero(side & (k_of <= ka) & (v[:, 2] > 0.3 * p.height))  # fingertips hang above 30 % of H
    order = below[np.argsort(k_of[below], kind="stable")]
    starts = np.searchsorted(k_of[order], np.arange(ka + 2))
    for k in range(ka + 1):
        ids = order[starts[k]:starts[k + 1]]
        if not len(ids):
            continue
        body = _body_outline(p, k, kc, leg_cuts)
        if body is not None:
            ids = ids[~shapely.contains_xy(body.buffer(0.01), v[ids, 0], v[ids, 1])]
        keep[ids] = True
    return v[keep], np.array([cx + sign * half, chest.centroid.y, p.z[ka]])


def _cut_at(mesh, point, axis, reach=0.02):
    """The outline (Polygon in the :func:`plane_frame` of ``axis`` about ``point``) of the cut through
    ``point`` across ``axis`` that is nearest ``point`` (within ``reach``), or None."""
    from shapely.geometry import Point

    best, best_d = None, reach
    for q in cut_outlines(mesh, point, axis):
        d = q.distance(Point(0.0, 0.0))
        if d < best_d:
            best, best_d = q, d
    return best


def _to_3d(poly, point, axis):
    u, w = plane_frame(axis)
    return point + poly.centroid.x * u + poly.centroid.y * w


def _trace(mesh, origin, direction, length, step=ARM_CUT):
    """The limb's centre line from ``origin`` along ``direction``: cut across it every ``step``, move to
    the cut's centroid, turn towards it. Stops at the limb's end, after ``length``, or where the cut
    grows to twice the last girth (the trunk). Returns a list of (centre, direction, outline)."""
    out = []
    p, d = np.asarray(origin, float), np.asarray(direction, float)
    last = None
    for _ in range(int(length / step)):
        q = p + step * d
        poly = _cut_at(mesh, q, d)
        if poly is None or (last is not None and poly.convex_hull.length > 2.0 * last):
            break
        centre = _to_3d(poly, q, d)
        turn = centre - p
        d = d + turn / max(np.linalg.norm(turn), 1e-12)
        d /= np.linalg.norm(d)
        p, last = centre, poly.convex_hull.length
        out.append((centre, d, poly))
    return out


def _line(pts, sign):
    """(centre, unit axis pointing away from the body on side ``sign``) of points along a limb."""
    c = pts.mean(axis=0)
    axis = np.linalg.svd(pts - c, full_matrices=False)[2][0]
    return c, (axis if axis[0] * sign > 0 else -axis)


def _centre_line(mesh, pts, armpit, sign, name):
    """The arm's centre line from the armpit to the fingertips: (centres (K, 3), directions (K, 3), outlines)."""
    if len(pts) < 20:
        raise BodyError(f"no {name} arm found beside the trunk; tailor needs {POSES}")
    c, axis = _line(pts, sign)
    s = (pts - c) @ axis
    s_arm = float((armpit - c) @ axis)
    length = s.max() - s_arm
    if length < 0.15:
        raise BodyError(f"the {name} arm is {100 * length:.0f} cm long from the armpit: not an arm; tailor needs {POSES}")
    upper = pts[(s >= s_arm) & (s <= s_arm + 0.3 * length)]
    cu, au = _line(upper, sign) if len(upper) >= 10 else (c, axis)
    inward = _trace(mesh, cu, -au, max(float((cu - armpit) @ au), 0.0))
    outward = _trace(mesh, cu, au, 1.5 * length)
    rows = [(cen, -d, poly) for cen, d, poly in inward[::-1]] + outward
    if len(outward) < 5:
        raise BodyError(f"no {name} arm found: the cuts across it do not close; tailor needs {POSES}")
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows]), [r[2] for r in rows]


def _one_arm(mesh, pts, armpit, sign, name):
    """{part: Landmark} of the upper arm, elbow and wrist of one arm (see the module docstring)."""
    centres, dirs, polys = _centre_line(mesh, pts, armpit, sign, name)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(centres, axis=0), axis=1))])
    girth = np.array([q.convex_hull.length for q in polys])
    sel = np.flatnonzero((arc >= 0.4 * arc[-1]) & (arc <= 0.85 * arc[-1]))
    if not len(sel):
        raise BodyError(f"no {name} wrist found: the arm ends before it; tailor needs {POSES}")
    i_wrist = int(sel[np.argmin(girth[sel])])
    # the elbow: where the centre line bends most (a straight arm: 45 % of the way to the wrist)
    k = 4
    bend = np.array([np.arccos(np.clip(dirs[max(i - k, 0)] @ dirs[min(i + k, len(dirs) - 1)], -1, 1))
                     for i in range(len(dirs))])
    window = np.flatnonzero((arc > 0.25 * arc[i_wrist]) & (arc < 0.75 * arc[i_wrist]))
    i_elbow = int(window[np.argmax(bend[window])]) if len(window) and bend[window].max() > np.radians(15) else \
        int(np.argmin(np.abs(arc - 0.45 * arc[i_wrist])))
    i_upper = int(np.argmin(np.abs(arc - 0.5 * arc[i_elbow])))
    return {part: _arm_landmark(f"{name}_{part}", polys[i], centres[i], dirs[i])
            for part, i in (("upper_arm", i_upper), ("elbow", i_elbow), ("wrist", i_wrist))}


def arm_landmarks(v, faces, p, kc, ka, leg_cuts) -> dict:
    """Upper arm, elbow and wrist of each arm (see the module docstring)."""
    import trimesh

    out = {}
    for sign, name in ((1, "left"), (-1, "right")):
        pts, armpit = _arm_points(v, p, kc, ka, leg_cuts, sign)
        near = (sign * (v[faces].mean(axis=1)[:, 0] - armpit[0]) > -0.05)  # the arm's side: cuts need only its faces
        mesh = trimesh.Trimesh(v, faces[near], process=False)
        for part, mark in _one_arm(mesh, pts, armpit, sign, name).items():
            out[f"{name}_{part}"] = mark
    return out


def _arm_landmark(name, poly, centre, axis):
    minx, miny, maxx, maxy = poly.bounds
    return Landmark(name, tuple(np.asarray(centre, float).tolist()), tuple((-np.asarray(axis)).tolist()),
                    float(poly.convex_hull.length), float(maxx - minx), float(maxy - miny))
