"""Rigid placements drafted for GarmentCode's neutral body, moved onto the body being dressed.

GarmentCode places every panel by a rigid transform (``translation``/``rotation``) in its own world,
for the body its pattern was drafted on: by default its neutral body, whose tape measurements
tailor's default mannequin is built from (:mod:`tailor.mannequin`). On another body those panels
are wherever that body's parts are not: GarmentCode's sleeves, drafted round arms 45.5° down
whose upper arms are 1.23 m up, start 4 cm under the arms of MakeHuman's man and close round his
shoulder instead of his arm; its trouser legs, drafted round legs straight down, bunch at the crotch
of a man whose knees are 6 cm further apart; on a 2 m man its T-shirt starts at his belly. A rigidly
placed panel that names the body part it dresses (GarmentCode's panel ``label``) is therefore
moved with that part, from where the part is on the neutral body (:data:`NEUTRAL`) to where it is
on this one (the landmarks :func:`tailor.measure.find_landmarks` finds):

* ``arm``: the rigid motion that takes the neutral upper arm (centre and axis) on the panel's
  side to this body's;
* ``leg``, a panel on one side of the body (a trouser leg): the same with the thigh (its centre,
  and the direction from it to the knee);
* ``body``, and ``leg`` across both legs (a skirt): raised or lowered by the trunk's change of
  height at the panel's centre, interpolated between the crotch's and the shoulders' (the two
  trunk landmarks every body has at a stable place; the waist and bust are found at the
  narrowest and widest girths, which move by 10 cm from body to body while the skeleton does not).

Panels are moved as wholes (never bent or stretched), so a pattern's flat layout stays its rest
shape; the seams between panels moved differently start a little further apart or closer, which
sewing closes. A panel that would move less than :data:`MIN_MOVE` stays where it was drafted: on
the default mannequin every GarmentCode pattern is placed exactly as GarmentCode placed it.
Panels with any other label, or none, are placed as given.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BodyRetarget", "NEUTRAL", "MIN_MOVE", "body_part"]

NEUTRAL = {
    "crotch": (0.0001, 0.0018, 0.775), "shoulders": (-0.0001, 0.0079, 1.455),
    "left_thigh": (0.1004, -0.0002, 0.74), "left_knee": (0.0956, 0.0017, 0.445),
    "right_thigh": (-0.1003, -0.0002, 0.74), "right_knee": (-0.0954, 0.0017, 0.445),
    "left_upper_arm": ((0.299, 0.0079, 1.2288), (-0.7076, 0.0013, 0.7066)),
    "right_upper_arm": ((-0.3, 0.0079, 1.2276), (0.7024, -0.0022, 0.7117)),
}
"""Landmark centres [m] (and the upper arms' axes, towards the shoulder) that
:func:`~tailor.measure.find_landmarks` finds on GarmentCode's neutral body: tailor's default
mannequin (``bodies/mannequin.obj``; ``tests/test_retarget.py`` measures it again)."""

TRUNK = ("crotch", "shoulders")
"""The trunk landmarks whose changes of height, interpolated between them, move a ``body`` panel."""

MIN_MOVE = 0.01
"""[m] A panel no point of which would move further than this is placed as drafted."""

ONE_SIDE = 0.9
"""Share of a ``leg`` panel's points on one side of the body's mid-plane for it to dress that leg
alone (a trouser leg); less, and it dresses both (a skirt): moved with the trunk."""


def body_part(label: str, x) -> tuple[str | None, str]:
    """(part, side) a rigidly placed panel labelled ``label`` dresses, placed at ``x`` (n, 3) [m]:
    part ``"arm"``, ``"leg"`` (one side of the body only), ``"trunk"`` (``body``, or ``leg`` across
    both legs: a skirt) or None (any other label); side ``"left"`` or ``"right"`` of its points' mean."""
    part = (label or "").strip().lower()
    side = "left" if len(x) and float(np.mean(x[:, 0])) > 0.0 else "right"
    if part == "leg" and np.mean(np.sign(x[:, 0]) == (1.0 if side == "left" else -1.0)) < ONE_SIDE:
        part = "body"  # across both legs
    return {"arm": "arm", "leg": "leg", "body": "trunk"}.get(part), side


def _rotation(a, b) -> np.ndarray:
    """The smallest rotation (3, 3) taking the unit vector ``a`` to the unit vector ``b`` (Rodrigues)."""
    a, b = np.asarray(a, float) / np.linalg.norm(a), np.asarray(b, float) / np.linalg.norm(b)
    c = float(a @ b)
    if c < -1.0 + 1e-9:  # opposite: half a turn about any axis across them
        axis = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    v = np.cross(a, b)
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + k + k @ k / (1.0 + c)


class BodyRetarget:
    """Moves rigidly placed panels from GarmentCode's neutral body onto a body (module docstring).

    Parameters
    ----------
    landmarks : dict of name → Landmark
        The body's landmarks (:func:`tailor.measure.find_landmarks`); a part whose landmarks are
        missing leaves its panels where they were drafted.
    """

    def __init__(self, landmarks: dict):
        self.landmarks = landmarks
        known = [n for n in TRUNK if n in landmarks]  # bottom to top
        self._heights = np.array([NEUTRAL[n][2] for n in known])
        self._rise = np.array([landmarks[n].center[2] - NEUTRAL[n][2] for n in known])

    def move(self, label: str, x) -> np.ndarray:
        """Points ``x`` (n, 3) [m] of one panel labelled ``label``, moved onto the body (or ``x``
        itself, where the label names no part, the part is missing or the move is under :data:`MIN_MOVE`)."""
        x = np.asarray(x, float)
        if not len(x):
            return x
        part, side = body_part(label, x)
        if part is None:
            return x
        moved = {"arm": self._arm, "leg": self._leg, "trunk": self._trunk}[part](x, side)
        if moved is None or np.sqrt(np.einsum("ij,ij->i", moved - x, moved - x).max()) < MIN_MOVE:
            return x
        return moved

    def _arm(self, x, side):
        lm = self.landmarks.get(f"{side}_upper_arm")
        if lm is None:
            return None
        centre, axis = NEUTRAL[f"{side}_upper_arm"]
        return self._rigid(x, np.array(centre), np.array(axis), np.asarray(lm.center, float), np.asarray(lm.axis, float))

    def _leg(self, x, side):
        thigh, knee = self.landmarks.get(f"{side}_thigh"), self.landmarks.get(f"{side}_knee")
        if thigh is None or knee is None:
            return None
        ref = np.array(NEUTRAL[f"{side}_thigh"])
        there = np.asarray(thigh.center, float)
        return self._rigid(x, ref, np.subtract(NEUTRAL[f"{side}_knee"], ref), there, np.asarray(knee.center, float) - there)

    def _trunk(self, x, side):
        if not len(self._heights):
            return None
        return x + np.array([0.0, 0.0, np.interp(float(x[:, 2].mean()), self._heights, self._rise)])

    @staticmethod
    def _rigid(x, origin, axis, to_origin, to_axis):
        """``x`` carried by the rigid motion taking (``origin``, ``axis``) to (``to_origin``, ``to_axis``)."""
        return to_origin + (x - origin) @ _rotation(axis, to_axis).T
