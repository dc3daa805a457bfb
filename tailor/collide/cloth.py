"""Cloth–cloth contact: perfectly inelastic self-collision (Carignan Eq. 5–8) over FCL.

Detection (Carignan §3.4: "any triangle, including those belonging to the cloth itself, within a
threshold distance from the cloth's vertices") runs in three stages:

1. **Regions** (``mode="auto"``, :mod:`tailor.collide.regions`): only patches that overlap a patch
   beyond their neighbourhood, or are folded, take part, and a candidate pair only between two
   patches that can touch (a patch with itself only if folded). Flat cloth is skipped, and so are
   the flat neighbourhoods of a patch that touches another (two layers of an outfit lying one over
   the other pair with each other, not with themselves).
2. **Broad phase**: the active triangles that come within ``thickness + margin`` of an active
   vertex anywhere on the step's straight-line motion, and the active edges that come that near one
   another, found between boxes swept from each vertex's place at the last step to its place now
   (relative to the cloth's centroid; a long step in parts, :mod:`.sweep`), over a compiled uniform
   grid rebuilt each query (:mod:`.grid`: python-fcl can neither refit nor hand back pairs without
   a Python object each). Each vertex is anchored where it was last queried; a pair stays valid
   while neither end moves ``margin / 2`` from its anchor (they approach by less than ``margin``).
   A ``partial`` collider (an outfit's) finds again only the pairs touching the vertices that have
   (the others' anchors are their boxes), unless most have. Vertices held still (an outfit's sewn
   garment while the next sews over it, :meth:`SelfCollider.hold_still`) are the frame instead of
   the centroid: a pair of two of them is no candidate, and one with a still end approaches only by
   its other end's drift, so it is searched within ``thickness + margin / 2``.
3. **Narrow phase** (compiled): a vertex whose projection falls on a candidate triangle not at the
   vertex is a contact if it is nearer than ``thickness``, if its velocity would bring it nearer
   within the next step, or if it crossed the triangle's plane since the last step (judged by the
   side it was on then, and only if it travelled that far relative to the triangle). **Edge–edge**
   pairs (none sharing an end) are judged alike at their closest points, their common normal's side
   remembered: two sheets sliding across each other cross edge through edge with no vertex ever
   over the other's triangle. A triangle touching the vertex's 1-ring (edges whose ends are
   neighbours) keeps only :data:`NEAR_THICKNESS` of the thickness: a sharp seam corner is close
   without touching, but a fold over one or two triangles must not pass through itself.

Response (Eq. 5–8): the vertex p₀ and the triangle point p₁ = Σ wᵢxᵢ get equal and opposite
impulses (p₁'s share spread over its vertices in proportion to wᵢ), so linear momentum is conserved
exactly. Along the normal the collision is perfectly inelastic: p₀ and p₁ leave with the normal
velocity of their centre of mass (Eq. 6–7), using the triangle point's effective mass 1/m₁ = Σ
wᵢ²/mᵢ, for which Eq. 7 holds exactly at p₁ (Carignan's interpolated m₁ misses it once the impulse
is spread). Two deliberate departures: the sliding part loses at most μ times the normal change
(Coulomb, as Eq. 14 for the body) instead of being cancelled too (with full cancellation layers
glue, and a glued layer is torn by its falling neighbours); and a predicted contact only has its
approach slowed so that it arrives at ``thickness`` at the end of the next step. Positions are
separated to ``thickness`` with the same weights (the centre of mass does not move). Contacts are
relaxed Gauss–Seidel style and detection repeats until no new contact appears.

Fast motion: a step whose candidate pairs' ends moved more than one thickness relative to each other
is replayed in up to :data:`MAX_SUBSTEPS` sub-steps of one thickness of it, contacts resolved after each.
"""

from __future__ import annotations

import math
import time
from functools import partial

import numpy as np

from ..errors import SimulationUnstable
from .cloth_kernels import (PARALLEL_PAIRS, detect_ee, detect_ee_serial, detect_vt, detect_vt_serial, pair_motion, resolve_contacts,
                            present, touching, touching_vt)
from .grid import PairRoom, edge_edge_pairs, vertex_rings, vertex_triangle_pairs
from .patch_pairs import NO_PATCH_PAIRS
from .layers import Layers
from .open_seams import OpenSeams
from .margins import MarginSchedule, self_margin
from .still import StillVertices
from .sweep import part_boxes, sweep_parts, union_edge_edge, union_vertex_triangle
from .regions import PATCH_EDGES, PATCH_MIN, Regions

__all__ = ["SelfCollider", "SELF_COLLISION_MODES", "Layers"]

SELF_COLLISION_MODES = ("auto", "on", "off")
GRID_EDGES = 2.0
"""Side of the broad phase's grid cells, in mean edge lengths of the cloth."""
MAX_SUBSTEPS = 32
"""At most this many contact sub-steps per step (each covers one thickness of relative motion): a
panel springing back as settling begins moves 4–5 cm in a step, two garments deep at an armpit."""

PARTIAL_SHARE = 0.5
"""A ``partial`` collider's share: when more of the vertices than this have moved from their anchors,
every candidate is found again; fewer, only the pairs touching them."""

REANCHOR = 0.5
"""A partial query also anchors again the vertices this far through their ``margin / 2``."""

MAX_RELATIVE_SPEED, MAX_RELATIVE_JUMP = 20.0, 0.05
"""[m/s], [m] No part of a garment moves this fast relative to the rest (drapes stay under 5 m/s); a
step beyond it and the jump (a body's push between responses, in however short a step) is an exploding
state, whose swept query would take minutes: it stops with :class:`SimulationUnstable` instead."""


class SelfCollider:
    """Self-collision of one cloth mesh (module docstring).

    Parameters
    ----------
    faces : (F, 3) int
        Triangles of the (welded) cloth.
    face_group : (F,) int
        Panel of each face; patches never span two panels.
    x : (N, 3)
        Positions the patches are cut from [m].
    thickness : float
        Distance kept between the cloth and itself [m].
    margin : float, optional
        Extra query radius [m]; candidates live until a vertex moves ``margin / 2`` (default:
        :func:`self_margin` of the mesh's mean edge length at ``x``, narrower while the cloth moves
        that far every step, :class:`~tailor.collide.margins.MarginSchedule`).
    mode : {"auto", "on"}
        ``auto`` checks only regions that can touch; ``on`` checks every vertex.
    patch : float, optional
        Patch size [m] for ``auto`` (default: :data:`PATCH_EDGES` mean edge lengths, at least
        :data:`PATCH_MIN`).
    friction : float
        Cloth-on-cloth Coulomb coefficient for the sliding part (``inf``: Carignan's full Eq. 7).
    edges : bool
        Also check edge–edge pairs (:func:`detect_ee`); off, only vertex–triangle pairs.
    layers : Layers, optional
        An outfit's garments: contacts between them keep their order (:class:`Layers`).
    partial : float
        Share of the vertices up to which, when they have moved from their anchors, only the pairs
        touching them are found again (:data:`PARTIAL_SHARE`; 0: all, always). It pays where part
        of the cloth lies still while the rest moves (an outfit's sewn garment while the next sews).
    garment : (N,) int, optional
        An outfit's garment of each vertex, innermost 0 (default: from ``layers``): the open seams
        :meth:`ignore` leaves free pass only through their own garment, never through another (a
        skirt's band closing over trousers'), and ``layers`` judges pairs between garments by it.
    """

    def __init__(self, faces, face_group, x, *, thickness: float, margin: float | None = None, mode: str = "auto",
                 patch: float | None = None, friction: float = 0.4, edges: bool = True, layers: Layers | None = None,
                 partial: float = 0.0, garment=None):
        if mode not in ("auto", "on"):
            raise ValueError(f"self-collision mode must be 'auto' or 'on', got {mode!r}")
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self.n = len(x)
        self.thickness, self.friction, self.edges = float(thickness), float(friction), bool(edges)
        self.mode, self.layers, self.partial = mode, layers, float(partial)
        if garment is None and layers is not None:
            garment = layers.vertex_layer(self.faces, self.n)
        self._garment = None if garment is None else np.asarray(garment, np.int64)  # each vertex's garment (its layer)
        e = self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        self._ring_csr = vertex_rings(self.faces, self.n)  # each vertex's neighbours across an edge
        # undirected edges and each face's edges, for edge–edge pairs
        e = np.sort(e, axis=1)
        keys, face_edge = np.unique(e[:, 0] * max(self.n, 1) + e[:, 1], return_inverse=True)  # one integer per edge
        self._edges = np.column_stack([keys // max(self.n, 1), keys % max(self.n, 1)])
        self._face_edges = face_edge.reshape(-1, 3).astype(np.int64)
        length = np.linalg.norm(np.diff(np.asarray(x, float)[self._edges], axis=1)[:, 0], axis=1)
        mean_edge = self._mean_edge = float(np.mean(length)) if len(length) else 0.0
        self._margins = MarginSchedule(self_margin(mean_edge) if margin is None else float(margin), self.thickness,
                                       fixed=margin is not None)
        self._grid_cell = GRID_EDGES * mean_edge if len(length) else 1.0
        if patch is None:
            patch = max(PATCH_MIN, PATCH_EDGES * mean_edge) if len(length) else 0.1
        self.regions = Regions(self.faces, np.asarray(face_group), np.asarray(x, float), patch)
        self._edge_patches = self.regions.edge_patches(self._edges)  # each edge's patches, for the searches' filter
        self._ee = np.zeros((0, 4), np.int64)
        self._rooms = (PairRoom(), PairRoom())  # the searches' room per query, vertex–triangle and edge–edge
        self._anchor = None  # (N, 3) each vertex's position relative to the centroid when last queried
        self._active = None  # (F,) bool: the faces the candidates were found among
        self._pairs = None  # sorted keys of the patch pairs the candidates were found among (None: all)
        self._reach = self.margin  # how deep a pair may have crossed in a step (the narrow phase cut-off beyond thickness)
        self._vtx, self._tri, self._tri_side = np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int8)
        self._ee_toward, self._x_prev = np.zeros((0, 3)), None
        self._seams = OpenSeams(self.n, self._garment)  # the open seams' vertices left out while sewing
        self._still = StillVertices()  # vertices held still (hold_still)
        self.stats = {"steps": 0, "active_steps": 0, "queries": 0, "contacts": 0, "max_active_vertices": 0, "max_edge_pairs": 0,
                      "max_substeps": 1, "partial_queries": 0, "query_s": 0.0, "response_s": 0.0, "min_margin_m": self.margin}

    @property
    def margin(self) -> float:
        """The query margin [m] of the candidates held (:class:`~tailor.collide.margins.MarginSchedule`)."""
        return self._margins.value

    def active_faces(self, x, vertex_boxes=None):
        """Faces that can touch themselves or one another (``auto``: :meth:`Regions.touching`), at
        ``x`` or, with ``vertex_boxes`` (lo, hi) per vertex, anywhere in them."""
        return self._touching(x, vertex_boxes)[0]

    def _touching(self, x, vertex_boxes):
        """(faces that can touch, sorted keys of the patch pairs that can, or None: every pair)."""
        if self.mode == "on" or self.regions.count <= 1:
            return np.arange(len(self.faces)), None
        return self.regions.touching(x, vertex_boxes, 0.5 * (self.thickness + self.margin))

    # -- broad phase -----------------------------------------------------------------------------
    def _drift(self, rx, rxp):
        """(N,) each vertex's squared distance from its anchor, now (``rx``) or at the last step
        (``rxp``), positions relative to the centroid; None: no anchors."""
        if self._anchor is None or len(self._anchor) != len(rx):
            return None
        d = np.einsum("ij,ij->i", rx - self._anchor, rx - self._anchor)
        if rxp is not None:
            d = np.maximum(d, np.einsum("ij,ij->i", rxp - self._anchor, rxp - self._anchor))
        return d

    def _query(self, rx, rxp, step, moving=None):
        """Candidates: the pairs that come within ``thickness + margin`` anywhere on the step's
        straight-line motion from ``rxp`` to ``rx`` (positions relative to the centroid; swept boxes
        round each vertex and triangle: fast but uniform motion, cloth falling as a whole, adds no
        pairs). Each vertex is anchored where it was queried; a pair stays valid while neither end
        moves ``margin / 2`` from its anchor (they then approach by less than ``margin``). With
        ``moving`` (the vertices that did), only the pairs touching them are found again, the others
        kept: their anchors are boxes too. ``step`` (the step's largest relative displacement) bounds
        how deep a pair can have crossed: the narrow phase ignores pairs further apart."""
        t0 = time.perf_counter()
        self._reach = self.margin + (2.0 * step if math.isfinite(step) else 0.0)
        lo, hi = (rx, rx) if rxp is None else (np.minimum(rx, rxp), np.maximum(rx, rxp))  # each vertex's box over the step
        if moving is not None:  # the others stay at their anchors
            still = ~moving
            lo, hi = np.where(still[:, None], self._anchor, lo), np.where(still[:, None], self._anchor, hi)
        faces, pairs = self._touching(rx, (lo, hi))
        dirty = None
        if moving is not None:
            # faces and patch pairs no query has seen: their vertices are queried as if they had moved
            moving = moving.copy()
            moving[self.faces[faces[~self._active[faces]]].ravel()] = True
            if pairs is not None and self._pairs is not None:
                moving[self.regions.vertices_of(np.setdiff1d(pairs, self._pairs, assume_unique=True))] = True
                pairs = np.union1d(pairs, self._pairs)
            dirty = moving
            self._active[faces] = True
            faces = np.flatnonzero(self._active)
            self._anchor[moving] = rx[moving]
            self.stats["partial_queries"] += 1
        else:
            self._active = np.zeros(len(self.faces), bool)
            self._active[faces] = True
            self._anchor = rx.copy()
            self.stats["queries"] += 1
        self._pairs = pairs
        parts = 1 if moving is not None or rxp is None else sweep_parts(step, self._mean_edge)
        boxes = [(lo, hi)] if parts == 1 else list(part_boxes(rxp, rx, parts))
        self._find(rx, boxes, faces, dirty, exact=rxp is None)
        self.stats["query_s"] += time.perf_counter() - t0

    def _patch_pairs(self):
        """The filter the searches test each candidate against before writing it out
        (:meth:`Regions.patch_pairs`): the patch pairs that can touch, and the vertices of the pairs
        :meth:`ignore` keeps across an open seam (the seam's two sides, closing edge to edge, lie flat
        together: their patches would not be a pair that can touch). Every pair if no patch pairs."""
        if self._pairs is None:
            return NO_PATCH_PAIRS
        return self.regions.patch_pairs(self._pairs, self._edge_patches, self._seams.keeping).arrays()

    def _in_touching_patches(self, vertex, tri, ee):
        """(vertex–triangle, edge–edge) candidates kept of those the filtered search let through: every
        one of a patch pair that can touch, and of those it let through for a kept pair's vertex at
        each end, only the kept pairs."""
        keep_vt, keep_ee = np.ones(len(vertex), bool), np.ones(len(ee), bool)
        if self._pairs is None or self._seams.kept is None:
            return keep_vt, keep_ee
        free, kept = self._seams.keeping, self._seams.is_kept
        out = np.flatnonzero(free[vertex] & free[self.faces[tri]].any(axis=1))
        keep_vt[out] = (self.regions.allowed_vertex_triangle(self._pairs, vertex[out], tri[out])
                        | kept(vertex[out, None], self.faces[tri[out]]).any(axis=1))
        out = np.flatnonzero(free[ee[:, :2]].any(axis=1) & free[ee[:, 2:]].any(axis=1))
        keep_ee[out] = (self.regions.allowed_edge_edge(self._pairs, ee[out])
                        | kept(ee[out, :2, None], ee[out, None, 2:]).reshape(len(out), 4).any(axis=1))
        return keep_vt, keep_ee

    def _find(self, x, boxes, faces, dirty, *, exact):
        """The candidates among ``faces`` and their vertices (boxes (lo, hi) round each vertex over the
        step, or each part of it: :mod:`.sweep`): all of them, or (``dirty`` (N,) bool, the step whole)
        the pairs touching a dirty vertex added to the kept ones that touch none."""
        verts = present(self.faces[faces].ravel(), self.n)
        radius, pad = self._still.reach(self.thickness, self.margin)
        # a triangle at the vertex is never a contact; one touching its 1-ring only once crossed
        # (ignoring those, a strip crumpling over one or two triangles passed through itself)
        patch_pairs = self._patch_pairs()
        find = partial(vertex_triangle_pairs, faces=self.faces, x=x, radius=radius, cell=self._grid_cell,
                       ring=self._ring_csr, exact=exact, patch_pairs=patch_pairs, room=self._rooms[0], pad=pad)
        edge_ids = present(self._face_edges[faces].ravel(), len(self._edges))
        if dirty is None and self._still.mask is not None and len(boxes) == 1:  # pairs among the still left out
            (lo, hi), = boxes
            (vertex, tri, near), (ee, ee_near) = self._pairs_meeting(find, verts, faces, edge_ids, lo, hi, ~self._still.mask,
                                                                     patch_pairs)
        elif dirty is None:
            (vertex, tri, near), (ee, ee_near) = self._search(find, verts, faces, edge_ids, boxes, patch_pairs)
        else:
            (lo, hi), = boxes
            (vertex, tri, near), (ee, ee_near) = self._pairs_meeting(find, verts, faces, edge_ids, lo, hi, dirty, patch_pairs)
        keep_vt, keep_ee = self._in_touching_patches(vertex, tri, ee)
        vertex, tri, near, ee, ee_near = vertex[keep_vt], tri[keep_vt], near[keep_vt], ee[keep_ee], ee_near[keep_ee]
        vertex, tri, near, ee, ee_near = self._seams.drop(self.faces, vertex, tri, near, ee, ee_near)
        vertex, tri, near, ee, ee_near = self._still.drop(self.faces, vertex, tri, near, ee, ee_near)
        tri_side = self._tri_sides(x, vertex, tri)
        if dirty is not None:  # the kept candidates: no end moved
            keep = ~touching_vt(self._vtx, self._tri, self.faces, dirty)
            vertex, tri, near, tri_side = (np.concatenate([a[keep], b]) for a, b in
                                           ((self._vtx, vertex), (self._tri, tri), (self._tri_near, near), (self._tri_side, tri_side)))
            keep = ~touching(self._ee, dirty)
            ee, ee_near = np.concatenate([self._ee[keep], ee]), np.concatenate([self._ee_near[keep], ee_near])
        self._vtx, self._tri = np.ascontiguousarray(vertex, dtype=np.int64), np.ascontiguousarray(tri, dtype=np.int64)
        self._tri_near, self._tri_side = near, tri_side
        self._ee, self._ee_near, self._ee_toward = ee, ee_near, self._edge_directions(x, ee)
        self.stats["max_active_vertices"] = max(self.stats["max_active_vertices"], len(verts))
        self.stats["max_edge_pairs"] = max(self.stats["max_edge_pairs"], len(self._ee))

    def _search(self, find, verts, faces, edge_ids, boxes, patch_pairs):
        """((vertex, triangle, near), (edge pairs, near)) of every pair whose boxes meet in one of ``boxes``."""
        found = [self._pairs_meeting(find, verts, faces, edge_ids, lo, hi, None, patch_pairs) for lo, hi in boxes]
        return found[0] if len(found) == 1 else (union_vertex_triangle([f[0] for f in found], len(self.faces)),
                                                 union_edge_edge([f[1] for f in found], self._edges, max(self.n, 1)))

    def _pairs_meeting(self, find, verts, faces, edge_ids, lo, hi, dirty, patch_pairs):
        """((vertex, triangle, near), (edge pairs, near)) whose boxes (lo, hi) meet: all, or (``dirty``
        (N,) bool) those with a dirty vertex."""
        find = partial(find, lo=lo, hi=hi)
        if dirty is None:
            return find(verts, faces), self._edge_pairs(edge_ids, lo, hi, None, patch_pairs)
        moved = dirty[verts]
        parts = (find(verts[moved], faces), find(verts[~moved], faces[touching(self.faces[faces], dirty)]))
        return (tuple(np.concatenate(p) for p in zip(*parts)),
                self._edge_pairs(edge_ids, lo, hi, touching(self._edges[edge_ids], dirty), patch_pairs))

    def _edge_pairs(self, ids, lo, hi, dirty, patch_pairs):
        if not self.edges:
            return np.zeros((0, 4), np.int64), np.zeros(0, bool)
        radius, pad = self._still.reach(self.thickness, self.margin)
        return edge_edge_pairs(ids, self._edges, lo, hi, radius, self._grid_cell, self._ring_csr,
                               dirty=dirty, patch_pairs=patch_pairs, room=self._rooms[1], pad=pad)

    def _tri_sides(self, x, vertex, tri):
        """Each vertex–triangle candidate's fixed side at ``x`` (:class:`Layers`; none for a single garment)."""
        if self.layers is None:
            return np.zeros(len(tri), np.int8)
        return self.layers.vertex_triangle_sides(self._garment, self.faces, vertex, tri, x)

    def _edge_directions(self, x, ee):
        """Each edge–edge candidate's outward direction at ``x`` (:class:`Layers`; a single garment: one zero row for all)."""
        if self.layers is None:
            return np.broadcast_to(np.zeros(3), (len(ee), 3))
        return self.layers.edge_directions(self._garment, self.faces, x, ee)

    def ignore(self, vertices, keep=None) -> None:
        """From now on the ``vertices`` ((N,) bool, or None for none) take no part in any contact
        except between the vertex pairs ``keep`` ((K, 2)) and between garments (:mod:`.open_seams`)."""
        if self._seams.set(vertices, keep):
            self._anchor = None  # query again

    def hold_still(self, still) -> None:
        """From now on the vertices ``still`` ((N,) bool, or None for none) do not move (pinned):
        :mod:`.still` says what the candidates then leave out."""
        if self._still.set(still):
            self._anchor = None  # query again

    @property
    def candidate_pairs(self) -> int:
        """Vertex–triangle pairs the narrow phase checks each step."""
        return len(self._tri)

    # -- response --------------------------------------------------------------------------------
    def respond(self, inv_mass, state, dt: float, *, rounds: int = 4, sweeps: int = 8) -> int:
        """Resolve self-contacts of ``state`` in place (Eq. 5–8); returns the number of contacts.

        ``inv_mass`` (N,) is 1/m per vertex, 0 for pinned or attached vertices.
        """
        x, v = state.x, state.v
        if len(x) != self.n:
            raise ValueError(f"self-collider built for {self.n} vertices, state has {len(x)}")
        if not (np.isfinite(x).all() and np.isfinite(v).all()):
            raise SimulationUnstable("cloth positions became NaN or infinite before the self-collision query; "
                                     "try a smaller time step or the implicit integrator")
        self.stats["steps"] += 1
        xp = self._x_prev if self._x_prev is not None and len(self._x_prev) == len(x) else None
        self._update(x, xp, dt, state.t)
        xp = x if xp is None else xp
        total = 0
        if len(self._tri):
            t0 = time.perf_counter()
            # fast relative motion: replay the step's motion in sub-steps of at most one thickness
            # of any candidate pair's relative motion, resolving contacts after each, so no pair
            # jumps through another between two checks
            rel = pair_motion(x - xp, self._vtx, self._tri, self.faces, self._ee)
            sub = int(min(MAX_SUBSTEPS, max(1, math.ceil(rel / self.thickness))))
            self.stats["max_substeps"] = max(self.stats["max_substeps"], sub)
            im = np.ascontiguousarray(inv_mass, dtype=np.float64)
            motion = (x - xp) / sub
            v_start = v.copy()
            x[:] = xp
            keys = np.zeros(0, np.int64)
            for _ in range(sub):
                before = x.copy()
                x += motion + (v - v_start) * (dt / sub)  # the motion, changed by what contacts did to v
                keys = self._resolve_at(x, before, v, im, dt / sub, keys, rounds, sweeps)
            total = len(keys)
            self.stats["response_s"] += time.perf_counter() - t0
        if total:
            self.stats["active_steps"] += 1
            self.stats["contacts"] += total
        self._x_prev = x.copy()
        return total

    def _update(self, x, xp, dt, t) -> None:
        """The candidates for the step from ``xp`` to ``x``: found again for the vertices that moved
        ``margin / 2`` from their anchors (relative to the centroid), all of them when most did."""
        rx = x - self._still.origin(x)
        rxp = None if xp is None else xp - self._still.origin(xp)
        self._margins.stepped()
        drift = self._drift(rx, rxp)
        if drift is not None and drift.max(initial=0.0) < (0.5 * self.margin) ** 2:
            return
        # found again with those that moved half as far: they would be next
        moving = None if drift is None else drift >= (REANCHOR * 0.5 * self.margin) ** 2
        step = math.inf if rxp is None else float(np.sqrt(np.einsum("ij,ij->i", rx - rxp, rx - rxp).max()))
        if rxp is not None and step > max(MAX_RELATIVE_SPEED * dt, MAX_RELATIVE_JUMP):
            raise SimulationUnstable(
                f"simulation unstable at t = {t:.4f} s (Δt = {dt:.3g} s): part of the cloth moved {step:.3g} m "
                f"relative to the rest in one step ({step / dt:.3g} m/s, limit {MAX_RELATIVE_SPEED:g}); try a smaller "
                f"time step (e.g. {dt / 4:.3g} s), a coarser resolution or a less stiff fabric")
        if moving is not None and moving.mean() > self.partial:
            moving = None
        self._margins.query(moving is None, adapt=self._seams.ignored is None, forced=drift is None)
        self.stats["min_margin_m"] = min(self.stats["min_margin_m"], self.margin)
        self._query(rx, rxp, step, moving)

    def _resolve_at(self, x, xp, v, im, dt, keys, rounds, sweeps):
        """Detect and resolve contacts at ``x`` (side memory ``xp``) until nothing new; returns the contact keys."""
        m = len(self._tri) + len(self._ee)
        ci, ca, cn, ch = np.empty((m, 4), np.int64), np.empty((m, 4)), np.empty((m, 3)), np.empty(m)
        hit = np.zeros(m, np.bool_)
        weight = np.array([self.n ** 3, self.n ** 2, self.n, 1], np.int64)
        lists = []
        seen = np.zeros(0, np.int64)
        vt_sel, ee_sel = np.arange(len(self._tri)), np.arange(len(self._ee))
        for _ in range(rounds):  # detect, resolve all contacts so far, detect again until nothing new
            self._detect(x, xp, v, dt, ci, ca, cn, ch, hit, vt_sel, ee_sel)
            found = np.flatnonzero(hit)
            key = np.sort(ci[found], axis=1) @ weight
            edge = found >= len(self._tri)
            key[edge] = -1 - key[edge]  # edge pairs apart from vertex–triangle pairs of the same four vertices
            new = np.flatnonzero(~np.isin(key, seen))
            if not len(new):
                break
            seen = np.concatenate([seen, key[new]])
            new = found[new]
            lists.append((ci[new], ca[new], cn[new], ch[new]))
            all_i, all_a, all_n, all_h = (np.concatenate(c) for c in zip(*lists))
            resolve_contacts(x, v, im, all_i, all_a, all_n, all_h, dt, self.friction, sweeps)
            # only pairs with a vertex the response moved can have changed
            changed = np.zeros(self.n, bool)
            changed[all_i.ravel()] = True
            vt_sel = np.flatnonzero(touching_vt(self._vtx, self._tri, self.faces, changed))
            ee_sel = np.flatnonzero(touching(self._ee, changed))
        return np.union1d(keys, seen)

    def _detect(self, x, xp, v, dt, ci, ca, cn, ch, hit, vt_sel, ee_sel) -> None:
        """The candidates ``vt_sel`` and ``ee_sel`` judged at ``x`` (the others keep their last verdict)."""
        parallel = len(vt_sel) + len(ee_sel) >= PARALLEL_PAIRS
        vt, ee = (detect_vt, detect_ee) if parallel else (detect_vt_serial, detect_ee_serial)
        vt(x, xp, v, dt, self.faces, self._vtx, self._tri, self._tri_near, self._tri_side, self.thickness,
           self.thickness + self._reach, ci, ca, cn, ch, hit, vt_sel)
        if self.edges:
            ee(x, xp, v, dt, self._ee, self._ee_near, self._ee_toward, self.thickness, self.thickness + self._reach,
               ci, ca, cn, ch, hit, len(self._tri), ee_sel)

    @property
    def previous(self):
        """(N, 3) the positions the last response ended at (None before the first)."""
        return self._x_prev

    def moved(self, x) -> None:
        """Positions were changed between steps (untangled): they are the sides to keep from now on,
        and the candidates are found again at the next step."""
        self._x_prev = np.array(x, float)
        self._anchor = None

    def rewind(self, previous) -> None:
        """A step undone: taken again from ``previous``, the sides there kept (the candidates hold for any path)."""
        self._x_prev = previous

    def carry_stats(self, stats: dict) -> None:
        """Continue the counters of a collider this one replaces (welding renumbered the cloth)."""
        for k, v in stats.items():
            own = self.stats[k]
            self.stats[k] = max(own, v) if k.startswith("max_") else min(own, v) if k.startswith("min_") else own + v

    def report(self) -> dict:
        """What ran, for report.json."""
        s = self.stats
        return {**s, "mode": self.mode, "query_s": round(s["query_s"], 3), "response_s": round(s["response_s"], 3),
                "patches": self.regions.count}
