"""The self-collision query's default margin: how far beyond the thickness the broad phase looks.

A wide margin keeps candidates valid longer but pairs each edge with more of its neighbours; a
narrow one is cheaper per query but recognises a pair that crossed only as deep as it reaches. The
default scales with the mesh (:func:`self_margin`) so refining a mesh does not multiply the pairs
each vertex meets.
"""

from __future__ import annotations

__all__ = ["SELF_MARGIN", "SELF_MARGIN_EDGES", "self_margin"]

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
