"""Collision over FCL (python-fcl): cloth against the body (:mod:`.body`) and against itself (:mod:`.cloth`).

This package is the only place that imports ``fcl``. FCL builds a bounding-volume hierarchy
(OBB-RSS) over a triangle mesh and answers proximity and intersection queries between such
objects. Its PyPI build cannot refit a hierarchy, so a moving mesh is rebuilt; callers query with
a margin and reuse the candidates while nothing has moved further than it.

* :mod:`.broad` — FCL broad phase over boxes round clusters of points and of triangles (the body's);
* :mod:`.grid` — a compiled uniform-grid broad phase (the cloth's own candidate pairs);
* :mod:`.closest`, :mod:`.inside` — closest point on a surface, inside a closed surface (compiled);
* :mod:`.body` — :class:`BodyCollider`, Carignan Eq. 9–14;
* :mod:`.cloth`, :mod:`.cloth_kernels` — :class:`SelfCollider`, Eq. 5–8;
* :mod:`.intersect`, :mod:`.crossings` — whether a mesh passes through itself (triangle pairs by FCL;
  edges through triangles, compiled, per frame);
* :mod:`.untangle` — crossings already made pushed back apart;
* :mod:`.contacts` — :class:`Contacts`, what a response hands to the next implicit step.
"""

from .body import BodyCollider
from .gap import body_gap
from .broad import TriangleBoxes, bvh_object, clustered_query, sphere_query
from .cloth import SELF_COLLISION_MODES, Layers, SelfCollider
from .margins import SELF_MARGIN, self_margin
from .contacts import NO_CONTACTS, Contacts
from .crossings import edge_crossings
from .inside import InsideTest, points_inside
from .intersect import self_intersections
from .untangle import untangle

__all__ = ["BodyCollider", "body_gap", "SelfCollider", "Layers", "SELF_COLLISION_MODES", "SELF_MARGIN", "self_margin", "bvh_object", "points_inside", "InsideTest",
           "self_intersections", "edge_crossings", "untangle", "sphere_query", "clustered_query", "TriangleBoxes", "Contacts", "NO_CONTACTS"]
