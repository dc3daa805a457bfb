"""Collision over FCL (python-fcl): cloth against the body (:mod:`.body`) and against itself (:mod:`.cloth`).

This package is the only place that imports ``fcl``. FCL builds a bounding-volume hierarchy
(OBB-RSS) over a triangle mesh and answers proximity and intersection queries between such
objects. Its PyPI build cannot refit a hierarchy, so a moving mesh is rebuilt; callers query with
a margin and reuse the candidates while nothing has moved further than it.
"""

from .body import BodyCollider, InsideTest, TriangleBoxes, bvh_object, clustered_query, points_inside, self_intersections, sphere_query
from .cloth import SELF_COLLISION_MODES, SelfCollider

__all__ = ["BodyCollider", "SelfCollider", "SELF_COLLISION_MODES", "bvh_object", "points_inside", "InsideTest",
           "self_intersections", "sphere_query", "clustered_query", "TriangleBoxes"]
