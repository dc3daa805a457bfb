"""The self-collision query's default margin: how far beyond the thickness the broad phase looks.

A wide margin keeps candidates valid longer but pairs each edge with more of its neighbours; a
narrow one is cheaper per query but recognises a pair that crossed only as deep as it reaches. The
default scales with the mesh (:func:`self_margin`) so refining a mesh does not multiply the pairs
each vertex meets.
"""

from __future__ import annotations

__all__ = ["SELF_MARGIN", "SELF_MARGIN_EDGES", "self_margin", "MarginSchedule", "MARGIN_SHRINK", "MARGIN_FLOOR", "GROW_AFTER"]

SELF_MARGIN = 0.01
"""[m] The widest default query margin (:func:`self_margin`). Candidates are the pairs within the
thickness plus the margin anywhere on the step's motion, kept while no vertex moves half of it; the
margin also sets how deep a pair that crossed is still recognised as one (docs/measurements.md,
ninth day: narrower ones let some 2 cm drapes cross or tear)."""

SELF_MARGIN_EDGES = 0.65
"""Default query margin in mean edge lengths, up to :data:`SELF_MARGIN`: a 2 cm garment (16.6 mm
edges) keeps the full centimetre, a finer mesh a margin in proportion, so the pairs an edge meets
do not grow as the mesh is refined (at 1 cm an edge of a 7.9 mm sheet met 29 others in a fold)."""


def self_margin(mean_edge: float) -> float:
    """[m] The default query margin of a cloth of ``mean_edge`` [m] (:data:`SELF_MARGIN_EDGES`)."""
    return min(SELF_MARGIN, SELF_MARGIN_EDGES * float(mean_edge)) if mean_edge > 0 else SELF_MARGIN


MARGIN_SHRINK = 0.7
"""A full query after candidates that lasted one step takes this share of the last margin."""
MARGIN_FLOOR = 0.3
"""The narrowest a margin shrinks to, as a share of the default (and never below the thickness)."""
GROW_AFTER = 3
"""Candidates that lasted this many steps widen the margin again (by 1 / :data:`MARGIN_SHRINK`, to the default)."""


class MarginSchedule:
    """The margin of a cloth's self-collision queries while it moves.

    A margin keeps candidates valid until a vertex moves half of it, at the price of every pair
    within the thickness plus the margin. Where the cloth moves half the default margin in a step
    (a walking garment: the trousers asked again at 333 of 372 steps with 1 cm, docs/measurements.md,
    ninth day) every step asks again whatever the margin, and the margin only costs pairs: each
    full query there takes :data:`MARGIN_SHRINK` of the last margin, down to the floor
    (:data:`MARGIN_FLOOR` of the default, at least the thickness); once candidates last
    :data:`GROW_AFTER` steps it widens again, up to the default. The margin stays the default while
    ``adapt`` is off (open seams sewing: a narrow margin there let a 2 cm dress merge a seam pair
    5.8 cm apart, and a skirt sewn over trousers stop, ninth day). A margin changes only at a full
    query, so every candidate was found with the margin its validity is judged by.
    """

    def __init__(self, default: float, thickness: float, *, fixed: bool = False):
        # fixed: a margin the caller chose, never narrowed
        self.default = float(default)
        self.floor = self.default if fixed else min(self.default, max(float(thickness), MARGIN_FLOOR * self.default))
        self.value = self.default
        self._since = None  # steps since the last query (None: none yet)

    def stepped(self) -> None:
        """A step was taken (queried or not)."""
        if self._since is not None:
            self._since += 1

    def query(self, full: bool, adapt: bool, forced: bool = False) -> float:
        """The margin of a query now (``full``: every pair found again; ``forced``: asked for, not
        the cloth's motion: no evidence either way); ``adapt`` off keeps the default."""
        since, self._since = (None if forced else self._since), 0
        if full and not adapt:
            self.value = self.default
        elif full and since is not None and since <= 1:
            self.value = max(self.floor, MARGIN_SHRINK * self.value)
        elif full and since is not None and since >= GROW_AFTER:
            self.value = min(self.default, self.value / MARGIN_SHRINK)
        return self.value
