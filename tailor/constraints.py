"""Constraints the contact pipeline applies after every step, before the body's response
(:class:`~tailor.contact.ContactPipeline`): attachments to body points (Carignan Eq. 19–20), a tuck's
gathered cloth, the heights attached vertices keep while sewing, and the planes between the legs.
Each has ``apply(state, body_x, body_v)``, changing the state in place."""

from __future__ import annotations

import numpy as np

__all__ = ["Attachments", "Gather", "HeightHold", "LimbWallContact"]


class Attachments:
    """Vertices held to body points (Eq. 19–20): barycentric on a body triangle, offset along its normal."""

    def __init__(self, ids, tri, bary, offset, faces):
        self.ids, self.tri, self.bary, self.offset, self.faces = ids, tri, bary, offset, faces

    def apply(self, state, body_x, body_v) -> None:
        f = self.faces[self.tri]
        p = (body_x[f] * self.bary[:, :, None]).sum(axis=1)
        a, b, c = body_x[f[:, 0]], body_x[f[:, 1]], body_x[f[:, 2]]
        n = np.cross(b - a, c - a)
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        state.x[self.ids] = p + self.offset[:, None] * n
        state.v[self.ids] = (body_v[f] * self.bary[:, :, None]).sum(axis=1)

    def renumbered(self, inverse) -> "Attachments":
        """The same attachments after a renumbering (``inverse``: old vertex → new, −1 gone)."""
        ids = inverse[self.ids]
        ok = ids >= 0
        return Attachments(ids[ok], self.tri[ok], self.bary[ok], self.offset[ok], self.faces)


class Gather:
    """Vertices carried in a straight line from ``start`` to ``target`` over ``duration`` s from time
    ``t0``, then held there (they are pinned in the model meanwhile): an inner garment's cloth
    gathered onto the body under a band about to close over it (a tucked top, :func:`tailor.outfit.outfit`).
    ``ids`` are mesh vertices, numbered by ``weld``."""

    def __init__(self, ids, start, target, t0: float, duration: float, weld):
        self.ids, first = np.unique(weld[ids], return_index=True)
        self.start, self.target = np.asarray(start)[first], np.asarray(target)[first]
        self.t0, self.duration = float(t0), float(duration)

    def apply(self, state, body_x, body_v) -> None:
        a = min(1.0, max(0.0, (state.t - self.t0) / self.duration))
        state.x[self.ids] = self.start + a * (self.target - self.start)
        state.v[self.ids] = (self.target - self.start) / self.duration if a < 1.0 else 0.0


class HeightHold:
    """Vertices kept at their heights while free to slide across (an attachment while sewing), and
    the rest of their panels kept from rising above them.

    Before gravity is on, a light panel (a waistband) sewn to a heavy one (the skirt) is pulled
    to it, since the seaming springs (Eq. 15) move the lighter side further; holding the attached
    edge's height draws the skirt up to the band instead, while the band's own seams still close
    round the body, and the band's ceiling keeps the skirt coming up from folding it up over its
    top. ``ids`` are mesh vertices and ``heights`` theirs [m]; ``under`` and ``ceilings`` [m] the
    mesh vertices held below a height; ``weld`` numbers the simulated vertices (a welded vertex
    takes its members' mean height, and the lowest ceiling).
    """

    def __init__(self, ids, heights, weld, under=(), ceilings=()):
        self.ids, first = np.unique(weld[ids], return_inverse=True)
        self.heights = np.bincount(first, heights) / np.bincount(first)
        under = weld[np.asarray(under, np.intp)]
        self.under = np.unique(under)
        self.ceilings = np.full(len(self.under), np.inf)
        np.minimum.at(self.ceilings, np.searchsorted(self.under, under), np.asarray(ceilings, float))

    def apply(self, state, body_x, body_v) -> None:
        z = state.x[self.under, 2]
        over = z > self.ceilings
        if over.any():
            i = self.under[over]
            state.x[i, 2] = self.ceilings[over]
            state.v[i, 2] = np.minimum(state.v[i, 2], 0.0)
        state.x[self.ids, 2] = self.heights
        state.v[self.ids, 2] = 0.0


class LimbWallContact:
    """A leg's panels stay on their side of the plane between the legs, below the limb's landmark,
    as the body moves (:func:`~tailor.limbwalls.limb_walls`): inelastic, like a body contact.

    ``walls`` are the garment's :class:`~tailor.limbwalls.LimbWalls`; ``mesh`` and ``weld`` number
    its vertices (a welded vertex whose members agree on one wall keeps to it); only the first
    ``simulated`` of them are (default: all; an outfit's garments waiting to sew come last).
    """

    def __init__(self, walls, mesh, weld, thickness: float, *, simulated: int | None = None):
        self.walls, self.thickness = walls, thickness
        nw = int(weld.max()) + 1
        lo, hi = np.full(nw, walls.count), np.full(nw, -1)
        of = walls.of(mesh)
        np.minimum.at(lo, weld, of)
        np.maximum.at(hi, weld, of)
        self.ids = np.flatnonzero((lo == hi) & (hi >= 0))
        if simulated is not None:
            self.ids = self.ids[self.ids < simulated]
        self.which = hi[self.ids]

    def apply(self, state, body_x, body_v) -> None:
        if not len(self.ids):
            return
        normal, offset, height, speed = self.walls.at(body_x, body_v)
        n, x = normal[self.which], state.x[self.ids]
        depth = self.thickness - (np.einsum("ij,ij->i", x, n) - offset[self.which])
        hit = (depth > 0) & (x[:, 2] < height[self.which])
        if hit.any():
            i, nh = self.ids[hit], n[hit]
            state.x[i] += depth[hit, None] * nh
            vn = np.einsum("ij,ij->i", state.v[i], nh) - speed[self.which[hit]]
            state.v[i] -= np.minimum(vn, 0.0)[:, None] * nh
