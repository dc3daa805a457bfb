"""Geometry of pattern edges: straight lines, quadratic/cubic Bézier curves and circular arcs.

Pure functions of 2D panel coordinates [m]. An edge's shape is a :class:`Curve`: its kind
and its absolute control points (start, controls..., end), or for an arc the radius and the
SVG-style flags. Sampling is by **arc length**, so sample spacing on a curved edge is even
and two sewn edges sampled with the same count pair point-for-point along their length.

Conventions (those of GarmentCode's specification JSON, converted at load time):

* Panel coordinates are y-up. A circular arc with ``sweep=True`` turns counter-clockwise
  (increasing polar angle) from start to end; ``large_arc`` picks the longer of the two arcs.

Examples
--------
>>> c = Curve("circle", ((1.0, 0.0), (-1.0, 0.0)), radius=1.0, large_arc=False, sweep=True)
>>> round(curve_length(c), 6)   # half a unit circle
3.141593
>>> sample_curve(c, [0.5]).round(6).tolist()
[[0.0, 1.0]]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Curve",
    "CURVE_KINDS",
    "arc_center",
    "evaluate_curve",
    "curve_length",
    "sample_curve",
    "dense_polyline",
    "loop_polyline",
    "loop_area",
]

CURVE_KINDS = ("straight", "quadratic", "cubic", "circle")

_DENSE = 1024  # Bézier parameter samples for arc-length tables (length error ~1e-7 relative)


@dataclass(frozen=True, slots=True)
class Curve:
    """Shape of one edge in panel coordinates [m].

    Attributes
    ----------
    kind : str
        One of ``CURVE_KINDS``.
    points : tuple of (x, y)
        Start, Bézier control points (none for straight and circle), end [m].
    radius : float
        Arc radius [m] (``circle`` only).
    large_arc, sweep : bool
        SVG arc flags (``circle`` only); ``sweep`` means counter-clockwise.
    """

    kind: str
    points: tuple[tuple[float, float], ...]
    radius: float = 0.0
    large_arc: bool = False
    sweep: bool = False

    @property
    def start(self) -> np.ndarray:
        """Start point [m], shape (2,)."""
        return np.asarray(self.points[0], dtype=float)

    @property
    def end(self) -> np.ndarray:
        """End point [m], shape (2,)."""
        return np.asarray(self.points[-1], dtype=float)


def arc_center(p0, p1, radius: float, large_arc: bool, sweep: bool):
    """Centre and angles of an SVG-style circular arc (SVG 1.1 F.6.5, y-up, sweep = CCW).

    Parameters
    ----------
    p0, p1 : array_like, shape (2,)
        Arc end points [m].
    radius : float
        Radius [m]; must be at least half the chord (checked by the pattern validator).

    Returns
    -------
    center : ndarray, shape (2,)
    theta0 : float
        Polar angle of ``p0`` about the centre [rad].
    dtheta : float
        Signed swept angle [rad], positive counter-clockwise.
    """
    p0 = np.asarray(p0, dtype=float)
    p1 = np.asarray(p1, dtype=float)
    chord = p1 - p0
    half = 0.5 * float(np.hypot(*chord))
    if half == 0.0:
        raise ValueError("arc end points coincide")
    r = max(float(radius), half)  # SVG rule: a radius that is too small is scaled up
    h = math.sqrt(max(r * r - half * half, 0.0))
    left = np.array([-chord[1], chord[0]]) / (2.0 * half)
    side = 1.0 if bool(sweep) != bool(large_arc) else -1.0
    center = 0.5 * (p0 + p1) + side * h * left
    theta0 = math.atan2(p0[1] - center[1], p0[0] - center[0])
    theta1 = math.atan2(p1[1] - center[1], p1[0] - center[0])
    dtheta = theta1 - theta0
    if sweep:
        while dtheta <= 0.0:
            dtheta += 2.0 * math.pi
    else:
        while dtheta >= 0.0:
            dtheta -= 2.0 * math.pi
    return center, theta0, dtheta


def evaluate_curve(curve: Curve, t) -> np.ndarray:
    """Points at curve parameters ``t`` in [0, 1] (not arc length), shape (n, 2) [m]."""
    t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
    p = np.asarray(curve.points, dtype=float)
    if curve.kind == "straight":
        return p[0] + t * (p[-1] - p[0])
    if curve.kind == "quadratic":
        s = 1.0 - t
        return s * s * p[0] + 2.0 * s * t * p[1] + t * t * p[2]
    if curve.kind == "cubic":
        s = 1.0 - t
        return s**3 * p[0] + 3.0 * s * s * t * p[1] + 3.0 * s * t * t * p[2] + t**3 * p[3]
    if curve.kind == "circle":
        c, th0, dth = arc_center(p[0], p[-1], curve.radius, curve.large_arc, curve.sweep)
        r = max(curve.radius, 0.5 * float(np.hypot(*(p[-1] - p[0]))))
        ang = th0 + t[:, 0] * dth
        out = c + r * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        out[t[:, 0] == 0.0] = p[0]  # end points exact, not rounded through trig
        out[t[:, 0] == 1.0] = p[-1]
        return out
    raise ValueError(f"unknown curve kind {curve.kind!r}")


def _arclength_table(curve: Curve):
    """(t, cumulative length) samples of a Bézier curve."""
    t = np.linspace(0.0, 1.0, _DENSE + 1)
    pts = evaluate_curve(curve, t)
    seg = np.hypot(*np.diff(pts, axis=0).T)
    return t, np.concatenate([[0.0], np.cumsum(seg)])


def curve_length(curve: Curve) -> float:
    """Arc length [m]: exact for lines and arcs, to ~1e-7 relative for Bézier curves."""
    p = np.asarray(curve.points, dtype=float)
    if curve.kind == "straight":
        return float(np.hypot(*(p[-1] - p[0])))
    if curve.kind == "circle":
        _, _, dth = arc_center(p[0], p[-1], curve.radius, curve.large_arc, curve.sweep)
        r = max(curve.radius, 0.5 * float(np.hypot(*(p[-1] - p[0]))))
        return abs(dth) * r
    return float(_arclength_table(curve)[1][-1])


def sample_curve(curve: Curve, fractions) -> np.ndarray:
    """Points at arc-length ``fractions`` in [0, 1] along the curve, shape (n, 2) [m].

    Lines and arcs are uniform in their parameter already; Bézier curves are inverted
    through a dense arc-length table, then evaluated exactly (points lie on the curve).
    """
    s = np.clip(np.atleast_1d(np.asarray(fractions, dtype=float)), 0.0, 1.0)
    if curve.kind in ("straight", "circle"):
        return evaluate_curve(curve, s)
    t, cum = _arclength_table(curve)
    total = cum[-1]
    if total == 0.0:
        return evaluate_curve(curve, s)
    return evaluate_curve(curve, np.interp(s * total, cum, t))


def dense_polyline(curve: Curve, max_segment: float | None = None, min_points: int = 2) -> np.ndarray:
    """The curve as a polyline from start to end (both included), shape (n, 2) [m].

    Straight edges give their two end points; curves get ``min_points`` or enough points
    for segments no longer than ``max_segment`` (default: 64 segments).
    """
    if curve.kind == "straight":
        return np.asarray([curve.points[0], curve.points[-1]], dtype=float)
    n = 64
    if max_segment is not None:
        n = max(int(math.ceil(curve_length(curve) / max_segment)), 1)
    n = max(n, min_points - 1)
    return sample_curve(curve, np.linspace(0.0, 1.0, n + 1))


def loop_polyline(curves, max_segment: float | None = None) -> np.ndarray:
    """A closed loop of curves as one polyline without the repeated closing point, shape (n, 2)."""
    parts = [dense_polyline(c, max_segment)[:-1] for c in curves]
    return np.concatenate(parts, axis=0)


def loop_area(curves) -> float:
    """Signed area [m²] enclosed by a loop of curves (Green's theorem; positive = CCW).

    Curved edges are sampled at 4096 segments each, so the result is the exact area to
    ~1e-7 relative; use it as the reference the mesher is checked against.
    """
    pts = []
    for c in curves:
        if c.kind == "straight":
            pts.append(np.asarray([c.points[0]], dtype=float))
        else:
            pts.append(sample_curve(c, np.linspace(0.0, 1.0, 4097))[:-1])
    p = np.concatenate(pts, axis=0)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
