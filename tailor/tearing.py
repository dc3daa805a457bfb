"""Tearing and cutting that split the mesh: Walker's tearing cloth, finished.

Walker tears a mass-spring net when a spring stretches too far; his rendered mesh does not tear
with it. Here the **mesh** separates: an interior edge breaks when the cloth is stretched across
it beyond the fabric's ``tear_strain`` — the stretch along the edge's rest normal, ``|F n| − 1``
with F the deformation gradient of each adjacent triangle (their mean), because it is the stress
*across* a line that opens a crack along it (a strip pulled lengthwise breaks transversely, not
into ribbons). A broken edge no longer joins its two triangles: every vertex whose ring of
triangles falls apart into k groups (a crack reaching the boundary, or two broken edges meeting)
becomes k vertices, each keeping its group. The triangles keep their rest shapes, the copies the
position and velocity of their vertex, and the lumped masses are recomputed from the triangles —
so total mass and linear momentum are conserved exactly. Per check only the most stretched edge
breaks (and those within 2 % of it): the crack localises at the weakest point and runs on in the
following steps, as stress concentrates at its tip (Walker's chain reaction).

A **cut** (the brush) removes the triangles whose centroid lies within ``radius`` of a point or
of a polyline at a given time; the vertices left without triangles go with them. A *separating*
cut loses no cloth: the edges between the triangles on the two sides of its polyline break, and
the mesh splits along them exactly as a tear does (mass and momentum exact).
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from .errors import SimulationError
from .forces import total_forces
from .collide import BodyCollider
from .contact import ContactPipeline, StaticBody, body_margin
from .integrators import make_integrator
from .sim import Guard, Stepper, check_state

__all__ = ["Cut", "TearableCloth", "simulate_tearing", "boundary_loops", "TEAR_RATIO", "TEAR_STEP"]

log = logging.getLogger(__name__)

TEAR_RATIO = 0.98
"""Edges breaking together in one check: those stretched within 2 % of the most stretched one."""


@dataclass(frozen=True)
class Cut:
    """A scripted cut: at ``time`` [s] remove the cloth within ``radius`` [m] of ``points``.

    ``points`` is one point (a round hole) or a polyline (a slit as wide as 2·radius), shape (k, 3) [m].
    With ``separate`` the polyline instead cuts the cloth apart without removing any: the mesh edges
    between the triangles on its two sides (within ``radius`` of it, which should exceed the mesh's
    edge length) break, as scissors would cut.
    """

    time: float
    points: tuple
    radius: float
    separate: bool = False

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=float).reshape(-1, 3)
        if not len(pts) or not np.all(np.isfinite(pts)):
            raise ValueError("a cut needs at least one finite point (x, y, z)")
        if not self.radius > 0:
            raise ValueError(f"a cut's radius must be positive, got {self.radius!r}")
        if self.separate and len(pts) < 2:
            raise ValueError("a separating cut needs a polyline of at least two points")
        object.__setattr__(self, "points", tuple(map(tuple, pts)))

    def sides(self, centroid, normal):
        """Side of the polyline of each triangle (centroid, unit normal): +1, −1, or 0 if farther than
        ``radius`` or beyond its ends. The side is that of ``(c − p) · (t × n)`` with p the nearest
        point of the polyline and t its direction there."""
        pts = np.asarray(self.points)
        a, b = pts[:-1], pts[1:]
        ab = b - a
        length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
        s = np.einsum("fsj,sj->fs", centroid[:, None, :] - a[None], ab) / length2  # (F, S)
        inner = np.clip(s, 0.0, 1.0)
        near = a[None] + inner[..., None] * ab[None]
        dist = np.linalg.norm(centroid[:, None, :] - near, axis=2)
        k = np.argmin(dist, axis=1)
        rows = np.arange(len(centroid))
        beyond = ((k == 0) & (s[rows, k] < 0.0)) | ((k == len(ab) - 1) & (s[rows, k] > 1.0))
        side = np.sign(np.einsum("ij,ij->i", centroid - near[rows, k], np.cross(ab[k], normal)))
        side[(dist[rows, k] > self.radius) | beyond] = 0.0
        return side.astype(np.int64)

    def samples(self) -> np.ndarray:
        """Points along the polyline no farther apart than half the radius, shape (m, 3)."""
        pts = np.asarray(self.points)
        out = [pts[:1]]
        for a, b in zip(pts[:-1], pts[1:]):
            n = max(1, math.ceil(np.linalg.norm(b - a) / (0.5 * self.radius)))
            out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
        return np.concatenate(out)


def _edge_table(faces):
    """(E, 2) sorted vertex pairs of the face edges, and for each (face, local edge) its row."""
    corners = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)  # edge k: f[k] → f[k+1]
    keys = np.sort(corners, axis=1)
    edges, inverse = np.unique(keys, axis=0, return_inverse=True)
    return edges, inverse.reshape(-1, 3)


def boundary_loops(faces) -> int:
    """Number of boundary loops of a triangle mesh (edges used by one triangle, chained)."""
    faces = np.asarray(faces)
    edges, inverse = _edge_table(faces)
    count = np.bincount(inverse.ravel(), minlength=len(edges))
    directed = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)[count[inverse.ravel()] == 1]
    nxt = {}
    for a, b in directed:
        nxt.setdefault(int(a), []).append(int(b))
    seen, loops = set(), 0
    for a, b in directed:
        if (int(a), int(b)) in seen:
            continue
        loops += 1
        cur = (int(a), int(b))
        while cur not in seen:
            seen.add(cur)
            outs = [c for c in nxt.get(cur[1], []) if (cur[1], c) not in seen]
            if not outs:
                break
            cur = (cur[1], outs[0])
    return loops


def _fan_groups(faces, broken, v) -> list:
    """The triangles around vertex ``v`` in groups joined through unbroken edges (v, w) (union–find)."""
    inc = [int(f) for f in np.flatnonzero((faces == v).any(axis=1))]
    parent = {f: f for f in inc}

    def find(f):
        while parent[f] != f:
            parent[f] = parent[parent[f]]
            f = parent[f]
        return f

    owner = {}
    for f in inc:
        for k in range(3):
            a, b = faces[f, k], faces[f, (k + 1) % 3]
            if v not in (a, b) or broken[f, k]:
                continue
            w = int(a + b - v)
            if w in owner:
                parent[find(f)] = find(owner[w])
            else:
                owner[w] = f
    groups: dict = {}
    for f in inc:
        groups.setdefault(find(f), []).append(f)
    return list(groups.values())


class TearableCloth:
    """A cloth mesh that can break and be cut, with its model rebuilt after every change.

    Parameters
    ----------
    mesh : GarmentMesh
    build : callable
        Builds the model of a (changed) mesh: ``build(mesh, pinned_mask)``, or with ``weld``
        ``build(mesh, pinned_mask, weld)``; the fabric, elastic model, air etc. live here.
    tear_strain : float
        Stretch across an edge beyond which it breaks (0.25 = 25 %); 0 = never tears.
    pinned : bool mask or indices, optional
        Of the simulated (welded) vertices.
    weld : (N,) int, optional
        A sewn garment: the simulated vertex of each mesh vertex (seam vertices share one). The
        cloth's state, pins and ``origin`` are then per welded vertex; a crack may run through a
        panel or along a seam (unpicking it), and splits the welded vertices it passes.
    """

    def __init__(self, mesh, build, *, tear_strain: float, pinned=None, weld=None):
        if tear_strain < 0:
            raise ValueError(f"tear_strain must be >= 0, got {tear_strain!r}")
        self.mesh, self.build, self.tear_strain = mesh, build, float(tear_strain)
        self.welded = weld is not None
        self.weld = np.arange(mesh.vertex_count) if weld is None else np.asarray(weld, np.intp).copy()
        n = int(self.weld.max()) + 1 if len(self.weld) else 0
        mask = np.zeros(n, bool)
        if pinned is not None:
            pinned = np.asarray(pinned)
            mask[pinned if pinned.dtype != bool else np.flatnonzero(pinned)] = True
        self.pinned = mask
        self.origin = np.arange(n)  # simulated vertex → vertex it was copied from, at the start
        self.broken = np.zeros((mesh.face_count, 3), bool)  # (face, local edge k: f[k]→f[k+1])
        uv = mesh.uv[mesh.faces]
        dm = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)  # (F, 2, 2)
        self._dm_inv = np.linalg.inv(dm)
        e = np.roll(uv, -1, axis=1) - uv  # (F, 3, 2) rest edge vectors
        nrm = np.stack([e[..., 1], -e[..., 0]], axis=-1)
        self._normal = nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)  # (F, 3, 2) rest normal of each edge
        self.tears = 0
        self.events: list = []
        self.model = self._build()
        self._refresh()

    def _build(self):
        return self.build(self.mesh, self.pinned, self.weld) if self.welded else self.build(self.mesh, self.pinned)

    @property
    def faces(self) -> np.ndarray:
        """Triangles in simulated (welded) vertex indices."""
        return self.weld[self.mesh.faces]

    def _refresh(self):
        self._edges, self._face_edge = _edge_table(self.faces)
        use = np.bincount(self._face_edge.ravel(), minlength=len(self._edges))
        self._interior = use == 2

    def change(self, state, pending: list, *, t0: float = 0.0, tol: float = 1e-12):
        """Make the cuts of ``pending`` (sorted by time, counted from ``t0``) that are due at ``state.t``
        (removing them), then tear; returns (state, whether the mesh changed)."""
        before = self.mesh
        while pending and pending[0].time <= state.t - t0 + tol:
            state = self.cut(state, pending.pop(0))
        torn = self.tear(state)
        state = torn if torn is not None else state
        if not self.mesh.face_count:
            raise SimulationError(f"at t = {state.t:.3f} s no cloth is left (every triangle was cut away)")
        return state, self.mesh is not before

    # -- tearing ------------------------------------------------------------------------------
    def across_stretch(self, x) -> np.ndarray:
        """Stretch of the cloth across each (face, local edge), shape (F, 3) (1 = rest)."""
        p = np.asarray(x)[self.faces]
        ds = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]], axis=2)  # (F, 3, 2)
        deform = ds @ self._dm_inv  # (F, 3, 2)
        return np.linalg.norm(np.einsum("fij,fkj->fki", deform, self._normal), axis=-1)

    def edge_strain(self, x) -> np.ndarray:
        """Strain across every mesh edge (mean of its faces; −inf for boundary or broken edges), shape (E,)."""
        s = self.across_stretch(x) - 1.0
        total = np.bincount(self._face_edge.ravel(), weights=np.where(self.broken, 0.0, s).ravel(),
                            minlength=len(self._edges))
        live = np.bincount(self._face_edge.ravel(), weights=(~self.broken).ravel(), minlength=len(self._edges))
        strain = np.full(len(self._edges), -np.inf)
        ok = self._interior & (live == 2)
        strain[ok] = total[ok] / 2.0
        return strain

    def tear(self, state):
        """Break the edges stretched beyond ``tear_strain``; returns the new State or None if none broke."""
        if self.tear_strain <= 0 or not self.mesh.face_count:
            return None
        strain = self.edge_strain(state.x)
        worst = strain.max(initial=-np.inf)
        if not worst > self.tear_strain:
            return None
        breaking = np.array([int(np.argmax(strain))])  # one edge per check: the crack localises
        hit = np.isin(self._face_edge, breaking)
        self.broken |= hit
        self.tears += len(breaking)
        self.events.append((float(state.t), len(breaking)))
        return self._split(state, np.unique(self._edges[breaking]))

    def _split(self, state, vertices):
        """Give each group of triangles around ``vertices`` (simulated indices) beyond the first its own vertex.

        In a sewn garment a group's corners are mesh vertices welded to the split one: a mesh vertex
        whose triangles all lie in the group moves to the new simulated vertex (a seam unpicked);
        one shared with another group is copied (a crack through a panel).
        """
        wf = self.faces
        faces = self.mesh.faces.copy()
        weld = list(self.weld)
        mesh_src = list(range(self.mesh.vertex_count))
        w_src = []
        next_w = len(self.pinned)
        for v in vertices:
            groups = _fan_groups(wf, self.broken, v)
            if len(groups) < 2:
                continue
            corner = {f: int(np.flatnonzero(wf[f] == v)[0]) for members in groups for f in members}
            owner = {}  # mesh vertex at v → groups of its triangles there
            for gi, members in enumerate(groups):
                for f in members:
                    owner.setdefault(int(self.mesh.faces[f, corner[f]]), set()).add(gi)
            for gi, members in enumerate(groups[1:], start=1):
                copies = {}
                for f in members:
                    o = int(self.mesh.faces[f, corner[f]])
                    if owner[o] == {gi}:  # all of this mesh vertex's triangles here: it moves
                        weld[o] = next_w
                    else:
                        if o not in copies:
                            copies[o] = len(mesh_src)
                            mesh_src.append(o)
                            weld.append(next_w)
                        faces[f, corner[f]] = copies[o]
                w_src.append(int(v))
                next_w += 1
        if not w_src:
            return state
        src_w = np.concatenate([np.arange(len(self.pinned)), np.asarray(w_src, np.intp)])
        return self._rebuild(state, faces, np.asarray(mesh_src, np.intp), np.asarray(weld, np.intp), src_w)

    # -- cutting ------------------------------------------------------------------------------
    def cut(self, state, cut: Cut):
        """Remove the triangles within ``cut.radius`` of its points (or, for a separating cut, break
        the edges along its polyline); returns the new State."""
        if cut.separate:
            return self._separate(state, cut)
        centroid = np.asarray(state.x)[self.faces].mean(axis=1)
        pts = cut.samples()
        near = np.zeros(len(centroid), bool)
        for chunk in np.array_split(pts, max(1, len(pts) // 64)):
            near |= (np.linalg.norm(centroid[:, None, :] - chunk[None], axis=2) <= cut.radius).any(axis=1)
        if not near.any():
            log.info("cut at t = %.3f s touches no cloth", cut.time)
            return state
        keep = ~near
        if not keep.any():
            raise SimulationError(f"the cut at t = {cut.time:g} s removes all of the cloth")
        used = np.unique(self.mesh.faces[keep])
        remap = np.full(self.mesh.vertex_count, -1, np.intp)
        remap[used] = np.arange(len(used))
        used_w = np.unique(self.weld[used])
        remap_w = np.full(len(self.pinned), -1, np.intp)
        remap_w[used_w] = np.arange(len(used_w))
        self.broken = self.broken[keep]
        self._dm_inv, self._normal = self._dm_inv[keep], self._normal[keep]
        self.events.append((float(state.t), -int(near.sum())))
        return self._rebuild(state, remap[self.mesh.faces[keep]], used, remap_w[self.weld[used]], used_w,
                             face_keep=keep)

    def _separate(self, state, cut: Cut):
        p = np.asarray(state.x)[self.faces]
        normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        side = cut.sides(p.mean(axis=1), normal)
        # an interior edge between triangles on opposite sides breaks (in both its faces)
        f_of = np.repeat(np.arange(self.mesh.face_count), 3)
        e = self._face_edge.ravel()
        order = np.argsort(e, kind="stable")
        e_sorted, f_sorted = e[order], f_of[order]
        twin = np.flatnonzero(e_sorted[1:] == e_sorted[:-1])
        fa, fb = f_sorted[twin], f_sorted[twin + 1]
        breaking = np.unique(e_sorted[twin][side[fa] * side[fb] < 0])
        if not len(breaking):
            log.info("separating cut at t = %.3f s crosses no cloth", cut.time)
            return state
        self.broken |= np.isin(self._face_edge, breaking)
        self.events.append((float(state.t), int(len(breaking))))
        return self._split(state, np.unique(self._edges[breaking]))

    # -- shared ---------------------------------------------------------------------------------
    def _rebuild(self, state, faces, src, weld, src_w, face_keep=None):
        """New mesh: mesh vertices ``src`` (indices into the current ones), ``faces`` in new indices,
        ``weld`` the new simulated vertex of each, whose state is that of the old ``src_w``."""
        m = self.mesh
        fk = slice(None) if face_keep is None else face_keep
        old_to_new = {int(s): i for i, s in enumerate(src)}
        edge_vertices = {k: np.array([old_to_new[int(i)] for i in v if int(i) in old_to_new], np.intp)
                         for k, v in m.edge_vertices.items()}
        self.mesh = replace(m, uv=m.uv[src], faces=faces, vertex_panel=m.vertex_panel[src], face_panel=m.face_panel[fk],
                            face_grain=m.face_grain[fk], seam_pairs=np.zeros((0, 2), np.intp),
                            seam_pair_seam=np.zeros(0, np.intp), edge_vertices=edge_vertices)
        self.weld = weld
        self.last_source = src_w  # new simulated vertex → the old one it continues
        self.pinned = self.pinned[src_w]
        self.origin = self.origin[src_w]
        self.model = self._build()
        self._refresh()
        cls = type(state)
        return cls(np.asarray(state.x)[src_w].copy(), np.asarray(state.v)[src_w].copy(), state.t)


TEAR_STEP = 0.005
"""Default implicit step [s] of :func:`simulate_tearing`: a crack runs on by one check per step, so
the step sets how fast it can run (half :data:`tailor.sim.IMPLICIT_STEP`)."""


def simulate_tearing(cloth: TearableCloth, state, *, duration: float, fps: float = 25.0, integrator: str = "implicit",
                     dt: float | None = None, wind=None, cuts=(), hooks=(), body=None, thickness: float = 0.002,
                     friction: float = 0.4, guard: Guard | None = None):
    """Advance a :class:`TearableCloth` for ``duration`` s, yielding ``(frame, state)`` every 1/fps s.

    After every step the contacts respond (a static body ``(vertices, faces)``, Eq. 9–14, through
    the :class:`~tailor.contact.ContactPipeline`), the hooks run (``hook(model, state, dt)``), due
    cuts are made and the cloth may tear; a change rebuilds the model (``cloth.model``,
    ``cloth.mesh``: read them with each frame, the topology changes) and the integrator and the
    contacts forget what they knew per vertex. ``wind`` is a :class:`tailor.forces.wind.Wind` or
    an air velocity.
    """
    guard = guard or Guard()
    contacts = None
    if body is not None:
        bx = np.asarray(body[0], float)
        contacts = ContactPipeline(BodyCollider(bx[None], body[1], margin=body_margin(thickness)), StaticBody(bx),
                                   thickness=thickness, friction=friction)
    integ = make_integrator(integrator)
    integ.configure(replace(integ.settings, wind=wind))  # the solve treats drag relative to this air
    # no step taken again for stretch: a tearing cloth stretches until it tears (its guard checks no strain)
    stepper = Stepper(integ, forces=functools.partial(total_forces, wind=wind), contacts=contacts, hooks=hooks,
                      guard=replace(guard, retries=0))
    frame_dt = 1.0 / fps
    h, substeps = stepper.substeps(cloth.model, frame_dt, min(TEAR_STEP, frame_dt) if dt is None and not integ.explicit else dt)
    pending = sorted(cuts, key=lambda c: c.time)
    check_state(cloth.model, state, step=0, dt=h, integrator=integ.name, frame=0, guard=guard)
    yield 0, state
    for frame in range(1, int(round(duration * fps)) + 1):
        for k in range(substeps):
            state = stepper.step(cloth.model, state, h)
            state, changed = cloth.change(state, pending)
            if changed:  # what the integrator and the contacts knew per vertex belongs to the old mesh
                integ.reset()
                if contacts is not None:
                    contacts.forget()
            check_state(cloth.model, state, step=k + 1, dt=h, integrator=integ.name, frame=frame, guard=guard,
                        strain=False)
        yield frame, state
