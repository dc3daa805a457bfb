"""Discretise a pattern's panels into triangle meshes ready to sew.

Each edge is cut into intervals at the ends of every seam stretch on it; each interval is
sampled evenly **by arc length** with about one point per ``resolution``. The two sides of a
seam get the same point count (the larger of the two), so seam vertices pair one-to-one.
Panels are then triangulated with Shewchuk's Triangle (the ``triangle`` package, owned by
this module alone) as a constrained, quality (minimum angle 25°), area-bounded Delaunay mesh
that keeps the boundary samples exactly (no Steiner points on the boundary).

Rest 2D coordinates are kept per vertex as UVs, and each face carries its panel's grain.
The same input always gives the same mesh.

Examples
--------
>>> from tailor.io import pattern_from_dict
>>> sq = {"pattern": {"panels": {"p": {"vertices": [[0, 0], [20, 0], [20, 20], [0, 20]],
...       "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]},
...                 {"endpoints": [3, 0]}]}}}}
>>> m = discretise(pattern_from_dict(sq), resolution=0.02)
>>> m.boundary_count, round(float(m.face_rest_area.sum()), 6)
(40, 0.04)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import triangle as _triangle
from shapely.geometry import Polygon

from .curves import curve_length, loop_polyline, sample_curve
from .errors import MeshingError
from .geometry import face_angles, face_areas
from .pattern import Pattern

__all__ = ["GarmentMesh", "discretise", "DEFAULT_RESOLUTION", "MIN_ANGLE_DEG"]

DEFAULT_RESOLUTION = 0.015
"""Target edge length [m] (1.5 cm)."""

MIN_ANGLE_DEG = 25.0
"""Minimum triangle angle requested from Triangle [deg]."""


@dataclass(frozen=True, eq=False)
class GarmentMesh:
    """The panels of a pattern as triangle meshes, side by side in one index space, not yet sewn.

    Attributes
    ----------
    uv : ndarray, shape (N, 2)
        Rest position of each vertex in its panel's plane [m] (also the texture coordinates).
    faces : ndarray, shape (F, 3)
        Triangles; wound like their panel's outline (so normals face outward).
    vertex_panel, face_panel : ndarray, shape (N,), (F,)
        Panel index of each vertex / face.
    face_grain : ndarray, shape (F, 2)
        Unit warp direction of each face in the uv plane.
    seam_pairs : ndarray, shape (S, 2)
        Vertex pairs to be joined: column 0 on the seam's side ``a``, column 1 on side ``b``.
    seam_pair_seam : ndarray, shape (S,)
        Index of the seam (in ``pattern.seams``) each pair belongs to.
    edge_vertices : dict
        ``(panel index, hole or None, edge index)`` → vertex ids from the edge's start to end.
    panel_names : tuple of str
    resolution : float
        Target edge length used [m].
    boundary_count : int
        Number of boundary (outline and hole) vertices.
    """

    uv: np.ndarray
    faces: np.ndarray
    vertex_panel: np.ndarray
    face_panel: np.ndarray
    face_grain: np.ndarray
    seam_pairs: np.ndarray
    seam_pair_seam: np.ndarray
    edge_vertices: dict = field(repr=False)
    panel_names: tuple = ()
    resolution: float = DEFAULT_RESOLUTION
    boundary_count: int = 0

    @property
    def vertex_count(self) -> int:
        """Number of vertices N."""
        return len(self.uv)

    @property
    def face_count(self) -> int:
        """Number of triangles F."""
        return len(self.faces)

    @property
    def face_rest_area(self) -> np.ndarray:
        """Rest area of each triangle [m²], shape (F,)."""
        return face_areas(self.uv, self.faces)

    def min_angle(self) -> float:
        """Smallest interior angle of any triangle [deg]."""
        return float(np.degrees(face_angles(self.uv, self.faces).min())) if len(self.faces) else 0.0

    def panel_vertices(self, panel: int) -> np.ndarray:
        """Vertex ids of one panel."""
        return np.flatnonzero(self.vertex_panel == panel)

    def flat_positions(self, gap: float = 0.05) -> np.ndarray:
        """3D positions [m], shape (N, 3): the panels flat in z = 0, side by side along +x.

        Each panel's bounding box starts ``gap`` [m] after the previous one's, bottoms at y = 0.
        """
        x = np.zeros((self.vertex_count, 3))
        cursor = 0.0
        for pi in range(len(self.panel_names)):
            ids = self.panel_vertices(pi)
            uv = self.uv[ids]
            lo, hi = uv.min(axis=0), uv.max(axis=0)
            x[ids, :2] = uv - lo + [cursor, 0.0]
            cursor += hi[0] - lo[0] + gap
        return x


def _segment_count(length: float, h: float) -> int:
    return max(1, int(round(length / h)))


def _edge_plan(pattern: Pattern, h: float):
    """Per loop edge: breakpoints (arc-length fractions) and the point count of each interval."""
    keys = []
    for pi, panel in enumerate(pattern.panels):
        for hole in [None, *range(len(panel.holes))]:
            for ei in range(len(panel.loop(hole))):
                keys.append((pi, hole, ei))
    breaks = {k: {0.0, 1.0} for k in keys}
    sides = []
    for seam in pattern.seams:
        pair = []
        for side in (seam.a, seam.b):
            key = (pattern.panel_index(side.panel), side.hole, side.edge)
            breaks[key].update((side.lo, side.hi))
            pair.append((key, side.lo, side.hi))
        sides.append(pair)
    for att in pattern.attachments:
        if att.edge is not None:
            breaks[(pattern.panel_index(att.panel), att.hole, att.edge)].update((att.start, att.end))
    plan = {}
    for key in keys:
        pi, hole, ei = key
        curve = pattern.panels[pi].loop(hole)[ei].curve
        length = curve_length(curve)
        b = np.array(sorted(breaks[key]))
        counts = [_segment_count(length * (hi - lo), h) for lo, hi in zip(b[:-1], b[1:])]
        plan[key] = (b, counts)
    for pair in sides:  # a seam's two sides get the same count
        idx = [int(np.searchsorted(plan[k][0], lo)) for k, lo, _ in pair]
        n = max(plan[k][1][i] for (k, _, _), i in zip(pair, idx))
        for (k, _, _), i in zip(pair, idx):
            plan[k][1][i] = n
    return plan


def _edge_fractions(breaks, counts) -> np.ndarray:
    parts = [np.linspace(lo, hi, n + 1)[:-1] for lo, hi, n in zip(breaks[:-1], breaks[1:], counts)]
    return np.concatenate(parts + [[1.0]])


def _mesh_panel(pattern, pi, plan, h, min_angle):
    """Triangulate panel ``pi``: returns (uv, faces, {(hole, edge): local vertex ids}, boundary count)."""
    panel = pattern.panels[pi]
    points, segments, edge_ids, hole_points = [], [], {}, []
    for hole in [None, *range(len(panel.holes))]:
        loop = panel.loop(hole)
        start = sum(len(p) for p in points)
        loop_pts = []
        for ei, edge in enumerate(loop):
            breaks, counts = plan[(pi, hole, ei)]
            pts = sample_curve(edge.curve, _edge_fractions(breaks, counts))
            first = start + sum(len(p) for p in loop_pts)
            loop_pts.append(pts[:-1])
            edge_ids[(hole, ei)] = first + np.arange(len(pts))
        n = sum(len(p) for p in loop_pts)
        for ei in range(len(loop)):  # the last sample of each edge is the next edge's first
            ids = edge_ids[(hole, ei)]
            ids[-1] = start + (ids[-1] - start) % n
        ring = start + np.arange(n)
        segments.append(np.column_stack([ring, np.roll(ring, -1)]))
        points.extend(loop_pts)
        if hole is not None:
            rp = Polygon(loop_polyline([e.curve for e in loop])).representative_point()
            hole_points.append([rp.x, rp.y])
    pts = np.concatenate(points)
    n_boundary = len(pts)
    max_area = math.sqrt(3.0) / 4.0 * h * h
    data = {"vertices": pts, "segments": np.concatenate(segments)}
    if hole_points:
        data["holes"] = np.asarray(hole_points)
    try:
        out = _triangle.triangulate(data, f"pq{min_angle:g}a{max_area:.12f}YQ")
    except Exception as exc:  # Triangle reports failures as generic errors
        raise MeshingError(f"{pattern.source}: {panel.where()}: triangulation failed: {exc}") from None
    uv, faces = out["vertices"], out["triangles"].astype(np.intp)
    if len(uv) < n_boundary or not np.allclose(uv[:n_boundary], pts) or len(faces) == 0:
        raise MeshingError(
            f"{pattern.source}: {panel.where()}: boundary samples were not kept by the mesher "
            f"(edges shorter than the resolution? try a smaller --resolution)"
        )
    if panel.signed_area < 0:  # CW outline: wind triangles CW too so normals face outward
        faces = faces[:, ::-1].copy()
    return uv, faces, edge_ids, n_boundary


def discretise(pattern: Pattern, resolution: float = DEFAULT_RESOLUTION, *, min_angle: float = MIN_ANGLE_DEG) -> GarmentMesh:
    """Triangulate every panel of ``pattern`` at a target edge length.

    Parameters
    ----------
    pattern : Pattern
        A validated pattern.
    resolution : float
        Target edge length h [m]; triangles are at most the area of an equilateral one of side h.
    min_angle : float
        Minimum angle asked of Triangle [deg]; input corners sharper than it stay sharp.

    Returns
    -------
    GarmentMesh

    Raises
    ------
    MeshingError
        When a panel cannot be triangulated.
    """
    if not (isinstance(resolution, (int, float)) and math.isfinite(resolution) and resolution > 0):
        raise MeshingError(f"resolution must be a positive length, got {resolution!r}")
    plan = _edge_plan(pattern, resolution)
    uvs, faces, vpanel, fpanel, grains, edge_vertices = [], [], [], [], [], {}
    offset = boundary = 0
    for pi, panel in enumerate(pattern.panels):
        uv, f, ids, nb = _mesh_panel(pattern, pi, plan, resolution, min_angle)
        uvs.append(uv)
        faces.append(f + offset)
        vpanel.append(np.full(len(uv), pi, dtype=np.intp))
        fpanel.append(np.full(len(f), pi, dtype=np.intp))
        grains.append(np.tile([math.cos(panel.grain), math.sin(panel.grain)], (len(f), 1)))
        for (hole, ei), local in ids.items():
            edge_vertices[(pi, hole, ei)] = local + offset
        offset += len(uv)
        boundary += nb
    pairs, owners = [], []
    for si, seam in enumerate(pattern.seams):
        ends = [_side_vertices(pattern, plan, edge_vertices, s) for s in (seam.a, seam.b)]
        if len(ends[0]) != len(ends[1]):  # guaranteed by _edge_plan; guard the invariant
            raise MeshingError(f"{pattern.source}: pattern.stitches[{seam.index}]: seam sides sampled unequally")
        pairs.append(np.column_stack(ends))
        owners.append(np.full(len(ends[0]), si, dtype=np.intp))
    arrays = dict(
        uv=np.concatenate(uvs),
        faces=np.concatenate(faces),
        vertex_panel=np.concatenate(vpanel),
        face_panel=np.concatenate(fpanel),
        face_grain=np.concatenate(grains),
        seam_pairs=np.concatenate(pairs) if pairs else np.zeros((0, 2), np.intp),
        seam_pair_seam=np.concatenate(owners) if owners else np.zeros(0, np.intp),
    )
    for a in arrays.values():
        a.flags.writeable = False
    return GarmentMesh(
        **arrays,
        edge_vertices=edge_vertices,
        panel_names=tuple(p.name for p in pattern.panels),
        resolution=float(resolution),
        boundary_count=boundary,
    )


def _side_vertices(pattern, plan, edge_vertices, side) -> np.ndarray:
    """Vertex ids along a seam side, in the side's direction."""
    key = (pattern.panel_index(side.panel), side.hole, side.edge)
    breaks, counts = plan[key]
    fractions = _edge_fractions(breaks, counts)
    i0 = int(np.flatnonzero(np.isclose(fractions, side.lo))[0])
    i1 = int(np.flatnonzero(np.isclose(fractions, side.hi))[-1])
    ids = edge_vertices[key][i0 : i1 + 1]
    return ids[::-1] if side.reversed else ids


def disk_mesh(radii, resolution: float, *, min_angle: float = MIN_ANGLE_DEG) -> tuple[np.ndarray, np.ndarray, list]:
    """(uv, faces, rings) of a disk of radius ``max(radii)`` [m] with a ring of vertices on every
    circle of ``radii`` (the test specimen's clamp edge, its rim); ``rings[k]`` lists ring k's
    vertex ids counter-clockwise."""
    pts, segs, rings = [], [], []
    start = 0
    for radius in radii:
        n = max(12, int(math.ceil(2.0 * math.pi * radius / resolution)))
        t = 2.0 * math.pi * np.arange(n) / n
        pts.append(np.column_stack([radius * np.cos(t), radius * np.sin(t)]))
        ids = start + np.arange(n)
        segs.append(np.column_stack([ids, np.roll(ids, -1)]))
        rings.append(ids)
        start += n
    max_area = math.sqrt(3.0) / 4.0 * resolution**2
    out = _triangle.triangulate({"vertices": np.vstack(pts), "segments": np.vstack(segs)}, f"pq{min_angle:g}a{max_area:.12f}YQ")
    return out["vertices"], out["triangles"].astype(np.intp), rings

