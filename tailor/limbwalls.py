"""Walls between a pair of limbs: each leg's panels keep to their side of the plane between the legs.

Rolled round a thigh, the two legs' panels overlap between the legs and up to the crotch;
:func:`limb_walls` finds, per panel, the limb it is placed round (or lies over), and the plane
between that limb and its pair; :class:`LimbWalls` moves placed points onto their own side and,
as the body moves, gives the walls where the legs are (:class:`tailor.contact.LimbWallContact`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .pattern import LandmarkPlacement

__all__ = ["LimbWalls", "limb_walls", "no_walls", "LEGS", "SIDE_TOLERANCE"]


def _pair_plane(name, landmarks):
    """(unit normal towards ``name``'s side, point, the pair's name) of the plane between a limb and its pair, or None."""
    for own, other in (("left_", "right_"), ("right_", "left_")):
        if name.startswith(own) and other + name[len(own):] in landmarks:
            c_own = np.asarray(landmarks[name].center, float)
            c_other = np.asarray(landmarks[other + name[len(own):]].center, float)
            n = (c_own - c_other) * np.array([1.0, 1.0, 0.0])
            if np.linalg.norm(n) < 1e-9:
                return None
            return n / np.linalg.norm(n), 0.5 * (c_own + c_other), other + name[len(own):]
    return None


@dataclass(frozen=True)
class LimbWalls:
    """The planes between paired limbs that a garment's left and right halves keep to (:func:`limb_walls`).

    Attributes
    ----------
    panel : (P,) int
        Wall of each panel, −1 for none (:meth:`of` gives a mesh's vertices theirs).
    normal : (W, 3)
        Unit normal of each wall in the rest pose, pointing to its own side.
    point : (W, 3)
        A point of each wall (midway between the two limbs' centres) in the rest pose [m].
    below : (W,)
        Height [m] below which each wall holds in the rest pose (the limb landmark's).
    limbs : tuple of ((K,) int, (L,) int)
        Per wall, the body vertices round its own limb and round the pair at the landmark (empty:
        the wall does not follow the body).
    centre : (W, 3) or None
        Midpoint of those two groups' means in the rest pose [m]; the wall moves as it does.
    """

    panel: np.ndarray
    normal: np.ndarray
    point: np.ndarray
    below: np.ndarray
    limbs: tuple = ()
    centre: np.ndarray | None = None

    @property
    def count(self) -> int:
        return len(self.normal)

    def of(self, mesh) -> np.ndarray:
        """(N,) wall of each vertex of ``mesh`` (a garment mesh of the pattern, possibly cut), −1 for none."""
        return self.panel[mesh.vertex_panel]

    def separate(self, x, mesh, margin: float) -> np.ndarray:
        """Placed positions ``x`` (rest pose) with every point of a wall's panels that reaches across
        the wall, or nearer it than ``margin``, moved onto its own side at ``margin``: the two legs'
        rolled panels overlap between the legs and up to the crotch, and placement must not start
        them through each other. At every height: above the landmark the two halves meet at the
        wall too (the centre seams)."""
        out = np.array(x, float)
        of = self.of(mesh)
        for w in range(self.count):
            ids = np.flatnonzero(of == w)
            depth = margin - (out[ids] @ self.normal[w] - self.normal[w] @ self.point[w])
            out[ids[depth > 0]] += depth[depth > 0, None] * self.normal[w]
        return out

    def at(self, body_x=None, body_v=None):
        """(normals (W, 3), offsets n·p (W,), heights (W,), normal speeds (W,)) with the body at ``body_x``.

        Each wall moves with the mean of the two limbs' vertices round it (a body swaying or
        walking forward carries it along) and keeps its rest orientation.
        """
        point, below, speed = self.point.copy(), self.below.copy(), np.zeros(self.count)
        if body_x is not None and self.limbs:
            shift = _midpoints(body_x, self.limbs) - self.centre
            point += shift
            below += shift[:, 2]
            if body_v is not None:
                speed = np.einsum("ij,ij->i", self.normal, _midpoints(body_v, self.limbs))
        return self.normal, np.einsum("ij,ij->i", self.normal, point), below, speed


def no_walls(panel_count: int) -> LimbWalls:
    """Walls for a garment none of whose panels lies round one of a pair of limbs."""
    return LimbWalls(np.full(panel_count, -1), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))


LEGS = ("left_thigh", "right_thigh")
"""The limbs whose wall a rigidly placed panel (GarmentCode's) keeps to when it lies on that side."""

SIDE_TOLERANCE = 0.02
"""How far [m] a rigidly placed panel's points below a limb's landmark may reach across the wall
and the panel still count as that limb's (a trouser leg's inseam placed on the midplane)."""


def _limb_of(pattern, pi, landmarks, placed) -> str | None:
    """The limb landmark whose wall panel ``pi`` keeps to, or None.

    A landmark placement names it. A rigid placement (GarmentCode's translations) names none: the
    panel is a leg's when all its placed points (``placed[pi]``) below a thigh lie on that thigh's
    side of the plane between the thighs (a skirt's panels span both sides)."""
    pl = pattern.panels[pi].placement
    if isinstance(pl, LandmarkPlacement):
        return pl.landmark if _pair_plane(pl.landmark, landmarks) is not None else None
    if placed is None:
        return None
    for name in LEGS:
        plane = _pair_plane(name, landmarks) if name in landmarks else None
        if plane is None:
            continue
        pts = np.asarray(placed[pi], float)
        low = pts[pts[:, 2] < landmarks[name].height]
        if len(low) and ((low - plane[1]) @ plane[0]).min() > -SIDE_TOLERANCE:
            return name
    return None


def limb_walls(pattern, landmarks, body_x=None, placed=None) -> LimbWalls:
    """The plane each panel rolled round one of a pair of limbs (trouser legs round the thighs) may
    not cross below that limb's landmark, as a :class:`LimbWalls` following the body ``body_x``
    (rest pose, (V, 3); None: fixed planes). ``placed``, per panel its placed points ((K, 3) [m]),
    finds the legs among rigidly placed panels (:func:`_limb_of`).

    A trouser leg's upper rows are rolled on cylinders wide enough to clear the hips, and the two
    legs' cylinders overlap between the legs; lower down, trouser legs are wider than legs and the
    two tubes meet at the midplane while their inseams close. Sewn freely, the crotch extensions
    and the knees of the two legs pass through each other, and the self-collision pass that starts
    once the garment is sewn then holds them crossed. A garment's left and right halves meet at the
    plane between the limbs: the drape keeps each leg's panels on their side of it
    (:func:`tailor.dress.drape`). Walking, the legs' inner sides would scissor past each other with
    the thighs, so the walls follow the body through the motion (docs/measurements.md).
    """
    index = np.full(len(pattern.panels), -1)
    walls: dict = {}
    for pi in range(len(pattern.panels)):
        limb = _limb_of(pattern, pi, landmarks, placed) if landmarks else None
        if limb is not None:
            index[pi] = walls.setdefault(limb, (len(walls), _pair_plane(limb, landmarks)))[0]
    if not walls:
        return no_walls(len(pattern.panels))
    names = sorted(walls, key=lambda k: walls[k][0])
    normal = np.array([walls[k][1][0] for k in names])
    point = np.array([walls[k][1][1] for k in names])
    below = np.array([landmarks[k].height for k in names])
    if body_x is None:
        return LimbWalls(index, normal, point, below)
    body_x = np.asarray(body_x, float)
    limbs = tuple((_round_limb(body_x, landmarks[k]), _round_limb(body_x, landmarks[walls[k][1][2]])) for k in names)
    return LimbWalls(index, normal, point, below, limbs, _midpoints(body_x, limbs))


def _midpoints(values, limbs):
    """(W, 3): per wall, the midpoint of the means of ``values`` over its two limbs' vertices."""
    return np.array([0.5 * (values[a].mean(axis=0) + values[b].mean(axis=0)) for a, b in limbs])


def _round_limb(body_x, landmark, band: float = 0.02):
    """Body vertices on the landmark's cross-section (within ``band`` of its plane and 1 cm of its outline)."""
    c = np.asarray(landmark.center, float)
    axis = np.asarray(landmark.axis, float) / np.linalg.norm(landmark.axis)
    d = body_x - c
    along = d @ axis
    across = np.linalg.norm(d - along[:, None] * axis, axis=1)
    ids = np.flatnonzero((np.abs(along) < band) & (across < 0.5 * max(landmark.width, landmark.depth) + 0.01))
    return ids if len(ids) else np.array([int(np.argmin(np.linalg.norm(d, axis=1)))])
