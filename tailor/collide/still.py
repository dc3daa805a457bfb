"""The vertices of a cloth held still, and what self-contact need not ask about them.

While an outfit's outer garment sews, the sewn garments inside it are held still (pinned: CLO's
"freeze"). A pair of two still vertices can never come to touch, nor be parted: it is no candidate.
A pair with one still end approaches only by its other end's drift, half the margin at most before
the candidates are found again, so it is searched within ``thickness + margin / 2`` where a pair of
two moving ends needs the whole margin; the still vertices are the frame the others' drift is
measured in (the cloth's centroid, which the moving garment drags, would make them drift too).
"""

from __future__ import annotations

import numpy as np

from .cloth_kernels import touching, touching_vt
from .memory import same_optional

__all__ = ["StillVertices"]


class StillVertices:
    """Which of a cloth's vertices are held still (none at first)."""

    def __init__(self):
        self.mask = None  # (N,) bool, None: none

    def set(self, still) -> bool:
        """``still`` ((N,) bool, or None for none) from now on; returns whether that changed anything."""
        still = None if still is None or not np.any(still) else np.asarray(still, bool)
        if same_optional(still, self.mask):
            return False
        self.mask = still
        return True

    def origin(self, x) -> np.ndarray:
        """The point vertices at ``x`` are anchored relative to: the still vertices' centroid, else the
        whole cloth's (falling or carried as a whole, the cloth then adds no candidates)."""
        return x.mean(axis=0) if self.mask is None else x[self.mask].mean(axis=0)

    def reach(self, thickness: float, margin: float):
        """(radius, pad): the candidates' search radius [m] and each vertex's pad beyond it (None: every
        pair within ``thickness + margin``); a pair is searched within the radius plus both ends' pads,
        half the margin each for a moving vertex, none for a still one."""
        if self.mask is None:
            return thickness + margin, None
        return thickness, np.where(self.mask, 0.0, 0.5 * margin)

    def drop(self, faces, vertex, tri, near, ee, ee_near):
        """The vertex–triangle (``vertex``, ``tri`` of ``faces``, ``near``) and edge–edge (``ee``,
        ``ee_near``) candidates with at least one vertex that moves."""
        if self.mask is None:
            return vertex, tri, near, ee, ee_near
        moves = touching_vt(np.ascontiguousarray(vertex, np.int64), np.ascontiguousarray(tri, np.int64), faces, ~self.mask)
        keep = touching(ee, ~self.mask)
        return vertex[moves], tri[moves], near[moves], ee[keep], ee_near[keep]
