"""Does a pattern fit a body: the pattern's closed loops against the body's girths, and grading.

A garment placed round a landmark (a skirt's panels round the waist, a T-shirt's round the
chest, a sleeve round the upper arm) is a closed loop there once sewn: its length is the sum
of the panels' widths across the row that lies on the landmark. A loop shorter than the body's
girth cannot close round it — the sewing would strain the seams until it timed out minutes
later — so :func:`check_loops` says so before any simulation, naming the loop, both lengths and
the fix.

:func:`grade` resizes a pattern to a body proportionally (a pattern maker's grading): the
pattern's design measurements (GarmentCode's body parameters where the file has them, otherwise
those of tailor's default mannequin) against the body's landmarks. Girths scale the panels
horizontally, lengths vertically, each region by its own ratio; a seam's two sides are then
made equal again by scaling the shorter edge's panel along it, so seams stay matched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .errors import PatternError
from .pattern import LandmarkPlacement

__all__ = ["Loop", "pattern_loops", "check_loops", "NEGATIVE_EASE", "FitError"]

NEGATIVE_EASE = 0.05
"""Share by which a loop may be shorter than the girth it goes round (a snug, stretched fit)."""


class FitError(PatternError):
    """A pattern that cannot close round the body it is to dress."""


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
    """The panel's width across the row its placement puts on the landmark [m]."""
    from shapely.geometry import LineString

    poly = _outline(panel)
    x0, y0, x1, y1 = poly.bounds
    pl = panel.placement
    anchor_y = pl.anchor[1] if pl.anchor is not None else y1
    y = float(np.clip(anchor_y - pl.offset, y0 + 1e-3, y1 - 1e-3))
    return float(poly.intersection(LineString([(x0 - 1.0, y), (x1 + 1.0, y)])).length)


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
        name = "bust" if loop.landmark == "chest" else loop.landmark
        mark = landmarks.get(name) or landmarks.get(loop.landmark)
        if mark is None:
            continue
        loop = replace(loop, girth=mark.girth)
        if loop.length < (1.0 - negative_ease) * loop.girth:
            raise FitError(
                f"{pattern.source}: the {loop.landmark.replace('_', ' ')} loop ({', '.join(loop.panels)}) is "
                f"{loop.length * 100:.1f} cm round but the body's {name.replace('_', ' ')} is {loop.girth * 100:.1f} cm: "
                f"it cannot close round it; grade the pattern to the body (tailor drape --grade auto, or tailor grade "
                f"PATTERN --body BODY --out PATTERN.json)"
            )
        out.append(loop)
    return out
