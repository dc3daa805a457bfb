"""The garment being dressed: the one owner of its vertex numbering.

Sewing welds seam pairs (Carignan Eq. 16–18), and cuts and tears split vertices; each changes the
numbering of the simulated vertices. :class:`Garment` holds the mesh, the weld (mesh vertex →
simulated vertex), the model built on it, the friction and pins per simulated vertex, and after
each change says so, so the contacts and the integrator can follow.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import cKDTree

from ..constraints import Attachments
from ..forces import total_forces
from ..forces.membrane import face_stretch
from ..model import AIR_DENSITY, build_model
from ..outfit import garment_of_vertex
from ..seams import Sewing, merge_state
from ..tearing import TearableCloth
from ..units import GRAVITY
from .options import ANCHORED_NEAR, COMPRESSION, FREEZE_RINGS, FREEZE_STRETCH, NEAR_RATE, NEAR_SEAM

__all__ = ["Garment", "Stage", "attachment_vertices"]


@dataclass(frozen=True)
class Stage:
    """One sewing stage (:meth:`Garment.stage_plan`): the pairs sewing (S,) bool, the mesh vertices
    waiting out of the simulation (those of the garments outside), the outfit's garment sewing and
    whether the stage is its first (it is dressed over the garments inside it then)."""

    sewing: np.ndarray
    waiting: np.ndarray
    garment: int
    dresses: bool


def attachment_vertices(pattern, mesh, attachment) -> np.ndarray:
    """Mesh vertices of one of the pattern's attachments (a panel corner, or a stretch of an edge)."""
    pi = pattern.panel_index(attachment.panel)
    if attachment.vertex is not None:
        panel = pattern.panels[pi]
        edge = next(k for k, e in enumerate(panel.edges) if e.endpoints[0] == attachment.vertex)
        return mesh.edge_vertices[(pi, None, edge)][:1]
    ids = mesh.edge_vertices[(pi, attachment.hole, attachment.edge)]
    t = np.linspace(0.0, 1.0, len(ids))
    lo, hi = min(attachment.start, attachment.end), max(attachment.start, attachment.end)
    return ids[(t >= lo - 1e-9) & (t <= hi + 1e-9)]


def layer_spacing(fabrics: dict) -> float:
    """Distance kept from the body and between layers of cloth [m]: the thickest of ``fabrics``
    (panel index → Fabric) plus 2 mm."""
    return max(f.thickness for f in fabrics.values()) + 0.002


class Garment:
    """A discretised pattern's simulated vertices, as sewing and tearing renumber them.

    Parameters
    ----------
    pattern : Pattern
    mesh : GarmentMesh
    fabrics : dict panel index → Fabric
    merge_distance : float
        Eq. 16's d [m] at the start of sewing.
    """

    def __init__(self, pattern, mesh, fabrics: dict, merge_distance: float):
        self.pattern, self.mesh, self.fabrics = pattern, mesh, fabrics
        self.unwelded = build_model(mesh, fabrics, air_density=AIR_DENSITY, compression=COMPRESSION)
        self.mass = np.asarray(self.unwelded.vertex_mass)
        self._panel_friction = np.array([fabrics[i].friction for i in range(len(pattern.panels))])
        self.sewing = Sewing(mesh.seam_pairs, merge_distance=merge_distance, seam=mesh.seam_pair_seam)
        self.weld = np.arange(mesh.vertex_count)
        self.friction = self._panel_friction[mesh.vertex_panel]
        self.pins = np.zeros(0, np.intp)  # mesh vertices held to the body
        self.waiting = np.zeros(0, np.intp)  # mesh vertices of an outfit's garments not sewing yet: out of the model
        self._parked = np.zeros((0, 3))  # positions of the waiting garments' simulated vertices (the last of the numbering)
        self.gathered = np.zeros(0, np.intp)  # mesh vertices tucked under a band while it sews, carried by a Gather
        self.frozen = np.zeros(0, np.intp)  # mesh vertices of sewn inner garments held still while an outer one sews
        self.asleep = np.zeros(0, np.intp)  # frozen mesh vertices out of the model too, far from the garment sewing (sleep_far)
        self._sleepers = None  # a k-d tree of the asleep vertices' places (they do not move), or None
        self._tuck = None  # (mesh vertices tucked, the garment tucking them) once a band closed over them
        self.gravity = False
        self.rebuilds = 0
        self.cloth: TearableCloth | None = None
        pairs = self.sewing.open_pairs(self.weld)
        self.model = replace(self.unwelded, gravity=np.zeros(3)).with_pairs(pairs, np.zeros(len(pairs)), np.zeros(len(pairs)))

    @property
    def thickness(self) -> float:
        """Distance kept from the body and between layers [m] (:func:`layer_spacing`)."""
        return layer_spacing(self.fabrics)

    def frame(self, state) -> np.ndarray:
        """Positions of every mesh vertex (seam copies included), as frames are written; an outfit's
        garments waiting to sew where they wait."""
        return self._whole(state.x, self._parked)[self.weld]

    @staticmethod
    def _whole(a, parked):
        return np.concatenate([a, parked]) if len(parked) else a

    def forces(self, wind=None):
        """``forces(model, state)``: the cloth's own (Eq. 1–4, wind) plus the open seams' pull (Eq. 15)."""
        def forces(model, state):
            return self.sewing.forces(model, state, self.weld, total_forces(model, state, wind=wind))
        return forces

    def stiffen_near_pairs(self, x) -> None:
        """Open seam pairs closer than :data:`NEAR_SEAM` (:data:`ANCHORED_NEAR` when joining a held
        panel to a free one) get stiff implicit springs for the next frame."""
        m = self.model
        if len(m.pair_vertices):
            k, c = self.sewing.near_stiffness(x, m.pair_vertices, m.vertex_mass, near=NEAR_SEAM, rate=NEAR_RATE,
                                              weld=self.weld, anchored_near=ANCHORED_NEAR)
            self.model = replace(m, pair_stiffness=k, pair_damping=c)

    def rebuild(self, state):
        """Weld the merged pairs into one particle each and carry the state over (Eq. 17–18)."""
        x_orig = self._whole(state.x, self._parked)[self.weld]
        v_orig = self._whole(state.v, np.zeros_like(self._parked))[self.weld]
        new = self._live_first(self.sewing.weld_map(self.mesh.vertex_count))
        xw, vw = merge_state(x_orig, v_orig, self.mass, new)
        m = build_model(self.mesh, self.fabrics, air_density=AIR_DENSITY, weld=new, compression=COMPRESSION,
                        gravity=(0.0, 0.0, -GRAVITY if self.gravity else 0.0))
        held = np.union1d(np.union1d(self.pins, self.gathered), self.frozen)
        if len(held):
            m = m.with_pins(np.unique(new[held]))
        if self.sewing.open_count:
            pairs = self.sewing.open_pairs(new)
            m = m.with_pairs(pairs, np.zeros(len(pairs)), np.zeros(len(pairs)))
        count = int(new[self.live].max()) + 1  # the rest (waiting, asleep) are numbered last
        self.weld, self.model, self._parked = new, m.prefix(count), xw[count:]
        self.friction = self._panel_friction[self.mesh.vertex_panel[np.unique(new, return_index=True)[1]]][:count]
        self.rebuilds += 1
        out = self.model.state(xw[:count], vw[:count], 0.0)
        out.t = state.t
        return out

    def _live_first(self, weld) -> np.ndarray:
        """``weld`` renumbered so the welded vertices simulated now come first, the rest (an outfit's
        garments waiting to sew, :attr:`asleep` ones) after them, each in its order. The model is
        then a prefix (:meth:`~tailor.model.Model.prefix`): no element may join the two parts."""
        live = self.live
        if live.all():
            return weld
        awake = np.zeros(int(weld.max()) + 1, bool)
        awake[weld[live]] = True
        if awake[weld[~live]].any():
            raise ValueError("a welded vertex both simulated and out of the model")
        order = np.empty(len(awake), np.intp)
        order[np.argsort(~awake, kind="stable")] = np.arange(len(awake))
        return order[weld]

    @property
    def still(self):
        """(simulated vertices,) bool: those held still (:attr:`frozen`, an outfit's sewn garments while
        the next sews over them); None when none is."""
        if not len(self.frozen):
            return None
        out = np.zeros(len(self.weld), bool)
        out[self.weld[self.frozen]] = True
        return out[:self.model.vertex_count]

    def tuck(self, ids, into: int) -> None:
        """Mesh vertices ``ids`` of the garments inside ``into`` tucked under its band: held (pinned)
        while it sews, free again once the outfit is attached (:meth:`attach`), and the inner layer
        against ``into`` from then on (:meth:`untucked`)."""
        self.gathered = np.asarray(ids, np.intp)
        self._tuck = (self.gathered, int(into))

    def untucked(self):
        """(simulated vertices,) int: for the cloth of a tucked garment outside its tuck (a top's blouse
        above the band), the garment tucking it, against which it keeps the side it is on; −1 for
        the rest. None without a tuck. Above the band the top lies over the bottom, under it
        beneath: neither is the outer layer there (:class:`~tailor.collide.Layers`)."""
        if self._tuck is None:
            return None
        ids, into = self._tuck
        inner = garment_of_vertex(self.pattern, self.mesh.vertex_panel) < into
        out = np.full(int(self.weld.max()) + 1, -1, np.int64)
        out[self.weld[inner]] = into
        out[self.weld[ids]] = -1
        return out[:self.model.vertex_count]

    @property
    def live(self) -> np.ndarray:
        """(mesh vertices,) bool: those simulated now (not waiting to sew, nor :attr:`asleep`)."""
        out = np.ones(self.mesh.vertex_count, bool)
        out[self.waiting] = False
        out[self.asleep] = False
        return out

    def stage_plan(self) -> list:
        """The :class:`Stage` of each sewing stage, in order.

        An outfit sews one garment at a time, innermost first, the garments outside waiting where
        they were placed. Within a garment, the seams joining its upper part to its lower part
        (:meth:`~tailor.pattern.Pattern.joins_at_waist`: a dress's bodice to its skirt) sew after
        the rest: the bodice closes over the shoulders first and hangs there, instead of being drawn
        down to the heavier skirt below the shoulders, where its straps could no longer meet.
        """
        pattern, pairs = self.pattern, self.sewing.pairs
        garment = garment_of_vertex(pattern, self.mesh.vertex_panel)
        late = np.array([pattern.joins_at_waist(seam) for seam in pattern.seams], bool)
        late = late[self.sewing.seam] if self.sewing.seam is not None else np.zeros(len(pairs), bool)
        plan = []
        for k in range(max(1, len(pattern.pieces))):
            for part in (~late, late):
                sewing = (garment[pairs[:, 0]] == k) & part
                if sewing.any():
                    dresses = not plan or plan[-1].garment != k
                    plan.append(Stage(sewing, np.flatnonzero(garment > k), k, dresses))
        return plan or [Stage(np.ones(len(pairs), bool), np.zeros(0, np.intp), 0, True)]

    @property
    def stages(self) -> int:
        """Sewing stages (:meth:`stage_plan`): one for a single garment without a waist seam."""
        return len(self.stage_plan())

    def sew_stage(self, state, stage: Stage):
        """Begin a sewing ``stage`` of :meth:`stage_plan`: only its pairs pull and merge, the garments
        outside wait where they were placed, out of the model (their forces, solve and contacts cost
        nothing until they sew), and those inside, sewn, are held still (:meth:`_frozen_under`).
        Returns the state of the rebuilt model."""
        self.sewing.sew_only(stage.sewing)
        self.waiting, self.asleep, self._sleepers = stage.waiting, np.zeros(0, np.intp), None
        self.frozen = self._frozen_under(stage.garment, state.x)
        state = self.rebuild(state)
        state.v[np.unique(self.weld[self.frozen])] = 0.0
        return state

    def _frozen_under(self, garment: int, x) -> np.ndarray:
        """Mesh vertices of the sewn garments inside ``garment`` held still while it sews (CLO's
        "freeze"): their forces then cost no solve and they never move for their contacts, where
        otherwise their own tension draws them into the body each step (sewing holds no body contact)
        and the response pushes them out. Not if ``garment`` is held to the body (a band closing over
        an inner band: the inner one must give way) or tucks them in; and not round the triangles
        their sewing left stretched beyond :data:`~.options.FREEZE_STRETCH` (a sleeve caught round
        the arm), :data:`~.options.FREEZE_RINGS` rings wide, which keep relaxing."""
        if not self.pattern.pieces or garment == 0:
            return np.zeros(0, np.intp)
        if self.pattern.pieces[garment].tucks or np.intersect1d(self.attached, self.garment_vertices(garment)).size:
            return np.zeros(0, np.intp)
        faces = np.asarray(self.model.faces)
        loose = np.zeros(len(self.weld), bool)  # asleep ones (out of the model) stay still
        loose[faces[face_stretch(self.model, x) > FREEZE_STRETCH].ravel()] = True
        for _ in range(FREEZE_RINGS):
            loose[faces[loose[faces].any(axis=1)].ravel()] = True
        inner = np.flatnonzero(garment_of_vertex(self.pattern, self.mesh.vertex_panel) < garment)
        return inner[~loose[self.weld[inner]]]

    def sleep_far(self, state, garment: int, reach: float):
        """The frozen vertices (:meth:`sew_stage`) farther than ``reach`` [m] from every vertex of the
        outfit's ``garment`` (sewing now), and :data:`~.options.FREEZE_RINGS` rings from any vertex
        that moves, taken out of the model like the garments waiting outside (:attr:`asleep`): held
        still, they cost the stage's forces, solve and contacts nothing (trousers' legs under a
        T-shirt sewing at the hips). The elements they drop join held vertices alone. Returns the
        state of the model rebuilt if the sleepers changed (else ``state``)."""
        far = np.zeros(0, np.intp)
        x = self.frame(state)
        if len(self.frozen):
            frozen = np.zeros(self.mesh.vertex_count, bool)
            frozen[self.frozen] = True
            faces = np.asarray(self.mesh.faces)
            awake = self._welded_mask(~frozen)
            for _ in range(FREEZE_RINGS + 1):  # a hinge or a bending spring reaches two rings
                awake[faces[awake[faces].any(axis=1)].ravel()] = True
                awake = self._welded_mask(awake)
            ids = np.flatnonzero(frozen & ~awake)
            near = cKDTree(x[self.garment_vertices(garment)]).query(x[ids], distance_upper_bound=reach)[0]
            far = ids[~np.isfinite(near)]
        if np.array_equal(far, self.asleep):
            return state
        self.asleep = far
        self._sleepers = cKDTree(x[far]) if len(far) else None
        return self.rebuild(state)

    def wake_near(self, state, garment: int, reach: float):
        """The state of the model rebuilt with every sleeper (:meth:`sleep_far`) back in, for the rest of
        the stage, once the outfit's ``garment`` has come within ⅔ of ``reach`` of one; None while it
        keeps its distance: sewing may carry cloth far (GarmentCode's T-shirt on MakeHuman's
        thin woman came within 1 mm of the pants' cloth asleep 15 cm from it, and crossed it unseen)."""
        if self._sleepers is None:
            return None
        d = self._sleepers.query(self.frame(state)[self.garment_vertices(garment)], distance_upper_bound=2.0 * reach / 3.0)[0]
        if not np.isfinite(d).any():
            return None
        self.asleep, self._sleepers = np.zeros(0, np.intp), None
        return self.rebuild(state)

    def _welded_mask(self, mask) -> np.ndarray:
        """(mesh vertices,) bool ``mask`` spread to every copy of a welded vertex one of whose copies has it."""
        welded = np.zeros(int(self.weld.max()) + 1, bool)
        welded[self.weld[mask]] = True
        return welded[self.weld]

    def garment_vertices(self, k: int) -> np.ndarray:
        """Mesh vertices of the outfit's garment ``k`` (every vertex for a single garment)."""
        if not self.pattern.pieces:
            return np.arange(self.mesh.vertex_count)
        return np.flatnonzero(garment_of_vertex(self.pattern, self.mesh.vertex_panel) == k)

    def moved(self, state, ids, x):
        """``state`` with the unwelded mesh vertices ``ids`` (none merged yet) put at ``x`` at rest."""
        w = self.weld[ids]
        if len(w) and w.max() >= len(state.x):
            raise ValueError("moved: the vertices must be simulated (not an outfit's garment waiting to sew)")
        state.x[w], state.v[w] = x, 0.0
        return state

    @property
    def attached(self) -> np.ndarray:
        """Mesh vertices of the pattern's attachments (sorted, unique; empty without any)."""
        held = [attachment_vertices(self.pattern, self.mesh, a) for a in self.pattern.attachments]
        return np.unique(np.concatenate(held)) if held else np.zeros(0, np.intp)

    def attached_ceilings(self, x) -> tuple:
        """(mesh vertices, ceilings [m]) of the panels with attachments: no higher than their
        attached vertices at ``x`` (per panel, the highest of them)."""
        ids, tops = [], []
        for a in self.pattern.attachments:
            held = attachment_vertices(self.pattern, self.mesh, a)
            panel = self.mesh.panel_vertices(self.pattern.panel_index(a.panel))
            ids.append(panel)
            tops.append(np.full(len(panel), x[held, 2].max()))
        return (np.concatenate(ids), np.concatenate(tops)) if ids else (np.zeros(0, np.intp), np.zeros(0))

    def attach(self, state, collider, pose):
        """Gravity on, the pattern's attachments pinned where they lie on the body (Eq. 19–20).

        Returns (state of the rebuilt model, :class:`~tailor.contact.Attachments` or None)."""
        ids, x = self.attached, self.frame(state)  # every mesh vertex's place, those out of the model too
        self.gravity = True
        self.waiting = np.zeros(0, np.intp)  # every garment sewn
        self.frozen = self.asleep = np.zeros(0, np.intp)  # and free
        self._sleepers = None
        self.gathered = np.zeros(0, np.intp)  # a tucked garment's gathered cloth is free again, under the band
        if len(ids):
            dist, tri, bary, _ = collider.nearest(x[ids], pose, 0, cache=False)
            ok = tri >= 0
            self.pins = ids[ok]
        state = self.rebuild(state)
        if not len(self.pins):
            return state, None
        wid, first = np.unique(self.weld[self.pins], return_index=True)
        # an outfit's garment k is held k + 1 thicknesses out, as the body keeps it (ContactPipeline.
        # body_thickness): a band pinned over an inner garment's band would otherwise be pinned within
        # one thickness of it, where no contact can part them
        layer = garment_of_vertex(self.pattern, self.mesh.vertex_panel)[self.pins[first]] if self.pattern.pieces else 0
        floor = self.thickness * (1.0 + layer)
        return state, Attachments(wid, tri[ok][first], bary[ok][first], np.maximum(dist[ok][first], floor),
                                  collider.faces)

    def allow_changes(self, tear: bool) -> float:
        """From now on the mesh may be cut (and torn, with ``tear``): a TearableCloth owns it.

        Returns the tear strain (the smallest among the panels' fabrics; 0: no tearing)."""
        strain = min((f.tear_strain for f in self.fabrics.values() if f.tear_strain > 0), default=0.0) if tear else 0.0

        def build(mesh_, pinned, weld):
            m = build_model(mesh_, self.fabrics, air_density=AIR_DENSITY, weld=weld, compression=COMPRESSION)
            return m.with_pins(np.flatnonzero(pinned)) if pinned.any() else m

        self.cloth = TearableCloth(self.mesh, build, tear_strain=strain, pinned=self.model.vertex_pinned, weld=self.weld)
        self.model = self.cloth.model
        return strain

    def tearing_report(self, t0: float) -> dict | None:
        """What was cut and torn (None if the mesh could not change); event times from ``t0``."""
        c = self.cloth
        if c is None:
            return None
        return {"tear_strain": c.tear_strain, "edges_torn": c.tears,
                "events": [{"t_s": round(t - t0, 6), "edges": e} for t, e in c.events]}

    def change(self, state, due: list, t0: float):
        """Cuts of ``due`` (times from ``t0``; removed from it), then tearing; returns (state, old → new
        vertex map or None)."""
        old = self.cloth.model.vertex_count
        state, changed = self.cloth.change(state, due, t0=t0, tol=1e-9)
        if not changed:
            return state, None
        inverse = np.full(old, -1, np.intp)  # old simulated vertex → its new index (the first copy)
        inverse[self.cloth.last_source[::-1]] = np.arange(len(self.cloth.last_source))[::-1]
        self.model, self.weld, self.mesh = self.cloth.model, self.cloth.weld, self.cloth.mesh
        self.friction = self._panel_friction[self.mesh.vertex_panel[np.unique(self.weld, return_index=True)[1]]]
        return state, inverse
