"""Every contact the cloth has, after every step, in one order: the :class:`ContactPipeline`.

After a step the cloth is kept on its side of the limb walls (garments rolled round one of a pair
of limbs, :func:`~tailor.placement.limb_walls`), attached vertices follow their body points
(Carignan Eq. 19–20), the body pushes the cloth out with friction (Eq. 9–14,
:class:`~tailor.collide.BodyCollider`) and the cloth is kept from passing through itself (Eq. 5–8,
:class:`~tailor.collide.SelfCollider`): after the body, so a layer the body pushed out pushes the
next one. The body's resting contacts are handed to the next implicit step, which holds them
within its solve, and the landing prediction tells that step which vertices it will bring onto
the body. :func:`tailor.sim.simulate`, :func:`tailor.scenes.run_scene`,
:func:`tailor.tearing.simulate_tearing` and :func:`tailor.dress.drape` all use this one pipeline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Protocol

import numpy as np

from .collide import SELF_COLLISION_MODES, BodyCollider, Contacts, Layers, SelfCollider, untangle
from .collide.cloth import PARTIAL_SHARE
from .collide.grid import unique_edges
from .collide.untangle import vertex_rings
from .constraints import Attachments, HeightHold, LimbWallContact
from .errors import SimulationError
from .forces.kernels import face_stretch_into

__all__ = ["ContactPipeline", "ContactLoads", "ContactSettings", "StaticBody", "Attachments", "HeightHold", "LimbWallContact", "BODY_MARGIN",
           "body_margin", "check_self_collision"]

BODY_MARGIN = 0.03
"""Body contact query radius [m]: candidates are reused while no cloth vertex moves its budget (half
of it, :data:`~tailor.collide.body.SPEND`), a vertex found deeper than the rest (the sure radius) is
judged against the closed surface, and a walking step carries no body point near the cloth further
than that (walking limbs move ~1 cm a step)."""


def _bearable(model, x, limit: float, ids, out) -> np.ndarray:
    """(K,) bool: which of the moves of vertices ``ids`` (of ``x``) to ``out`` leave every triangle of
    theirs stretched within ``limit`` or no more than before; a triangle over it takes its moved
    corners back (a few rounds: a corner taken back can put a neighbour's triangle over)."""
    faces = np.asarray(model.faces)
    moved = np.zeros(len(x), bool)
    moved[ids] = True
    touched = np.flatnonzero(moved[faces].any(axis=1))
    sub, dm = np.ascontiguousarray(faces[touched]), np.ascontiguousarray(model.face_dm_inv[touched])
    before, after = np.empty(len(touched)), np.empty(len(touched))
    face_stretch_into(np.ascontiguousarray(x, float), sub, dm, before)
    y = np.array(x, float)
    y[ids] = out
    for _ in range(4):
        face_stretch_into(y, sub, dm, after)
        back = np.unique(sub[(after > limit) & (after > before)])
        back = back[moved[back]]
        if not len(back):
            break
        y[back], moved[back] = x[back], False
    return moved[ids]


def body_margin(thickness: float) -> float:
    """The body contact margin for cloth ``thickness`` [m]: :data:`BODY_MARGIN`, or twice the thickness."""
    return max(BODY_MARGIN, 2.0 * thickness)


def check_self_collision(mode: str) -> str:
    """``mode`` if it names a self-collision mode; a one-line SimulationError otherwise."""
    if mode not in SELF_COLLISION_MODES:
        raise SimulationError(f"self_collision must be one of {', '.join(SELF_COLLISION_MODES)}, got {mode!r}")
    return mode


@dataclass(frozen=True, slots=True)
class ContactSettings:
    """What contact does in a phase of a simulation.

    Attributes
    ----------
    friction_scale : float
        Fraction of the fabric's friction acting on the body (0 while sewing: panels slide into place).
    hold : bool
        Hand resting body contacts to the next implicit step and predict landings within it.
    self_collision : bool
        Whether cloth–cloth contact acts (while sewing it leaves the open seams and their
        neighbours free, :meth:`ContactPipeline._open_seams`: seam edges must be free to meet).
    layers : bool
        Whether contact between an outfit's garments keeps their order whatever side they are on
        (:class:`~tailor.collide.Layers`); off while sewing, where a pair keeps the side it was
        on (docs/outfits.md: with the rule the dress under a T-shirt stops sooner).
    """

    friction_scale: float = 1.0
    hold: bool = True
    self_collision: bool = True
    layers: bool = True


class BodyMotion(Protocol):
    """The body over time: ``at(t) -> (positions, velocities, collider frame)``."""

    def at(self, t: float): ...


class StaticBody:
    """A body that does not move (the reference scenes' sphere, floor and boxes)."""

    def __init__(self, vertices):
        self.x = np.asarray(vertices, float)
        self.v = np.zeros_like(self.x)

    def at(self, t: float):
        return self.x, self.v, 0


class ContactLoads:
    """The forces the body and the attachments exert on the cloth, per vertex, averaged over the
    steps since they were last taken (one frame): what a fit map reads as contact and pressure.

    Each step adds the impulses of the implicit solve's held contacts and pins
    (:attr:`~tailor.integrators.StepResult.support`) and of the body's response after the step
    (the velocity change of Eq. 9–14, normal and friction, times the vertex mass). A renumbering
    of the vertices (a weld, a tear) starts the sums afresh.
    """

    def __init__(self):
        self._body = self._attached = None
        self._elapsed = 0.0

    def add(self, model, dt: float, support=None, response=None) -> None:
        """One step of ``dt``: ``support`` (N, 3) [N·s] from the solve, ``response`` (N, 3) [N·s] after it."""
        n = model.vertex_count
        if self._body is None or len(self._body) != n:
            self._body, self._attached, self._elapsed = np.zeros((n, 3)), np.zeros((n, 3)), 0.0
        if support is not None:
            pinned = model.vertex_pinned
            self._body[~pinned] += support[~pinned]
            self._attached[pinned] += support[pinned]
        if response is not None:
            self._body += response
        self._elapsed += dt

    def checkpoint(self):
        """What :meth:`restore` needs to forget the steps added after now."""
        copy = None if self._body is None else (self._body.copy(), self._attached.copy())
        return copy, self._elapsed

    def restore(self, mark) -> None:
        """The sums as they were at :meth:`checkpoint` ``mark`` (restored once: its arrays are taken)."""
        copy, self._elapsed = mark
        self._body, self._attached = (None, None) if copy is None else copy

    def take(self, n: int):
        """(body force, attachment force), each (n, 3) [N], averaged since the last take (zeros when
        nothing was summed for ``n`` vertices); the sums start again."""
        body, attached, elapsed = self._body, self._attached, self._elapsed
        self._body = self._attached = None
        if body is None or len(body) != n or elapsed <= 0:
            return np.zeros((n, 3)), np.zeros((n, 3))
        return body / elapsed, attached / elapsed


@dataclass(frozen=True)
class _Mark:
    """The contacts' knowledge before a step (:meth:`ContactPipeline.checkpoint`)."""

    pending: Contacts | None
    start: np.ndarray | None
    loads: tuple
    body: tuple | None
    collider: SelfCollider | None
    previous: np.ndarray | None


class ContactPipeline:
    """The contacts of one cloth over a (moving) body, after every step (module docstring).

    Parameters
    ----------
    body : BodyCollider, optional
        The body's collider (None: no body).
    motion : BodyMotion
        Where the body is at a time (:class:`StaticBody` for one that does not move).
    thickness : float
        Distance kept from the body and between layers of cloth [m].
    friction : float or (N,) per vertex
        Coulomb coefficient of the cloth on the body (and, averaged, on itself).
    self_collision : {"auto", "on", "off"}
    self_margin : float, optional
        Query margin of the self-collision broad phase [m] (default: the mesh's,
        :func:`~tailor.collide.margins.self_margin`).
    panel_layer : (P,) int, optional
        An outfit's garment of each panel, innermost 0: contact between garments keeps their order
        (:class:`~tailor.collide.Layers`). None for a single garment.
    """

    def __init__(self, body: BodyCollider | None, motion: BodyMotion | None, *, thickness: float, friction,
                 self_collision: str = "off", self_margin: float | None = None, panel_layer=None):
        self.body, self.motion, self.thickness = body, motion, float(thickness)
        self.friction = friction
        self.self_mode = check_self_collision(self_collision)
        self.self_margin = self_margin
        self.panel_layer = None if panel_layer is None else np.asarray(panel_layer, np.int64)
        self.settings = ContactSettings()
        self.constraints: tuple = ()
        self.pending: Contacts | None = None  # body contacts the next implicit step holds
        self.rescued = 0
        self._rescue_limit = math.inf  # how far a rescue may stretch a triangle (limit_rescues)
        self.loads = ContactLoads()
        self._version = 0  # topology changes (cuts, tears) so far
        self._self: SelfCollider | None = None
        self._self_key = None
        self._mesh_topology = None  # (numbering, each vertex's neighbours, the unique edges) for untangling
        self._start = None  # (N, 3) where the next step starts after a renumbering (follow), for the self-collider
        self._layer_thickness = None  # (numbering, (N,) body thickness per vertex) of an outfit
        self._untucked = None  # (N,) int: a tucked top's cloth outside its tuck, the garment it keeps its side against
        self._untucked_version = 0
        self._still = None  # (N,) bool: vertices held still (hold_still)

    def configure(self, settings: ContactSettings) -> None:
        """What contact does from now on (a new phase)."""
        self.settings = settings

    def limit_rescues(self, max_stretch: float) -> None:
        """The stretch [×] the step guard stops at from now on: a rescue (:meth:`rescue`) leaves every
        triangle within it, or no more stretched than it was. A rescue comes after a frame's last
        check, so a triangle it overstretched would stop the drape at the next frame's first, where no
        smaller step can help: GarmentCode's T-shirt sewing at 4 cm on MakeHuman's thin woman had 7
        vertices pulled into the shoulder, its worst triangle 7.3× (the sewing guard's limit 10×); put
        out to the nearest surface, each its own way, they left it 11.1×. Left inside, they come out
        with their neighbours at the next steps' responses."""
        self._rescue_limit = float(max_stretch)

    def constrain(self, *constraints) -> None:
        """Constraints applied before the body each step (``apply(state, body_x, body_v)``): limb walls, attachments."""
        self.constraints = tuple(c for c in constraints if c is not None)

    def untucked(self, against) -> None:
        """``against`` (N,) int per vertex of the current numbering: the garment against which the
        vertex keeps the side it is on instead of the layer rule's, −1 for none (a tucked top's
        cloth above the band it is tucked into, :meth:`tailor.dress.garment.Garment.untucked`);
        None: the layer rule holds between every two garments."""
        new = None if against is None or not (np.asarray(against) >= 0).any() else np.asarray(against, np.int64)
        old = self._untucked
        if (new is None) != (old is None) or (new is not None and not np.array_equal(new, old)):
            self._untucked = new
            self._untucked_version += 1  # a layered collider is built afresh with it

    def hold_still(self, still) -> None:
        """``still`` (N,) bool per vertex of the current numbering: held still until told otherwise (an
        outfit's sewn garment while the next one sews over it); neither the self-contact
        (:meth:`SelfCollider.hold_still`) nor the untangling looks at a pair among them alone. None: none."""
        self._still = None if still is None or not np.any(still) else np.asarray(still, bool)

    def _held_still(self, model):
        """(N,) bool of the vertices of ``model``'s numbering held still (:meth:`hold_still`), or None."""
        return self._still if self._still is not None and len(self._still) == model.vertex_count else None

    def follow(self, friction, x=None) -> None:
        """The cloth's vertices were welded or moved between steps (their count changed; the colliders
        notice by it): the friction per new vertex, and ``x``, where the next step starts from in the
        new numbering: the self-collider built for it keeps the cloth on the sides it has there, as
        the one it replaces kept them step to step (otherwise a crossing the first step after a weld
        makes would be taken as a side to keep)."""
        self.friction = friction
        self._start = None if x is None else np.array(x, float)

    def _restart(self, x) -> None:
        """Positions moved in place between steps: the next step starts from ``x`` if it is to
        start a new self-collider (:meth:`follow`)."""
        if self._start is not None and len(self._start) == len(x):
            self._start = np.array(x, float)

    def forget(self) -> None:
        """The cloth's topology changed (a cut or a tear): drop everything known per vertex."""
        self._version += 1
        self.pending = None
        if self.body is not None:
            self.body.forget()

    def checkpoint(self) -> "_Mark":
        """What the contacts know before a step, for :meth:`restore` to take them back to if the step
        is undone (:meth:`tailor.sim.Stepper._step`)."""
        collider = self._self
        return _Mark(self.pending, self._start, self.loads.checkpoint(), None if self.body is None else self.body.checkpoint(),
                     collider, None if collider is None else collider.previous)

    def restore(self, mark: "_Mark", x) -> None:
        """The contacts as :meth:`checkpoint` found them; the cloth is back at ``x``, where the step
        undone began."""
        self.pending, self._start = mark.pending, mark.start
        self.loads.restore(mark.loads)
        if self.body is not None:
            self.body.restore(mark.body)
        if self._self is not None:
            if self._self is mark.collider and mark.previous is not None:
                self._self.rewind(mark.previous)
            else:  # built during the step undone (a renumbering): it starts from ``x``
                self._self.moved(x)

    def predict(self, model, state, x_end, v_end, dt, held) -> Contacts | None:
        """The vertices a solved step would bring onto the body, as it is at the step's end."""
        if self.body is None or not self.settings.hold:
            return None
        bx, bv, k = self.motion.at(state.t + dt)
        return self.body.landing(model, x_end, v_end, dt, bx, bv, k, thickness=self.body_thickness(model), skip=held)

    def hold(self, model) -> Contacts | None:
        """The body contacts the next step on ``model`` should hold (those the last response left resting)."""
        p = self.pending
        return p if p is not None and p.vertex_count == model.vertex_count else None

    def respond(self, model, state, dt: float, impulses=None, support=None) -> None:
        """Every contact of ``state`` after a step, in place; ``impulses`` the step's held-contact
        normal impulses, ``support`` its held contacts' and pins' whole impulses (for :attr:`loads`)."""
        bx, bv, k = self.motion.at(state.t) if self.motion is not None else (None, None, 0)
        for constraint in self.constraints:
            constraint.apply(state, bx, bv)
        response = None
        if self.body is not None:
            mu = self.friction * self.settings.friction_scale
            v0 = state.v.copy()
            contacts = self.body.respond(model, state, dt, bx, bv, k, thickness=self.body_thickness(model), friction=mu,
                                         impulse=impulses)
            self.pending = contacts if self.settings.hold else None
            response = (state.v - v0) * np.asarray(model.vertex_mass)[:, None]
        self.loads.add(model, dt, support, response)
        if self.self_mode != "off" and self.settings.self_collision:
            collider = self.self_collider(model, state.x, bx)
            collider.ignore(*self._open_seams(model))
            collider.hold_still(self._held_still(model))
            # pinned vertices (attached, a tuck's gathered cloth) do not move: read each step, since
            # pins change without the vertex count changing
            collider.respond(np.where(model.vertex_pinned, 0.0, 1.0 / np.asarray(model.vertex_mass)), state, dt)

    def _open_seams(self, model):
        """((N,) bool, (K, 2) int) while sewing (None, None: no seam open): the vertices of the open seam
        pairs and their neighbours, which the self-collision leaves free so that each seam's two sides
        meet edge to edge, and the vertex pairs among them that keep contact all the same: each pair's
        neighbours on one side against its neighbours on the other (the pair's own two vertices left
        out), so that the two sides do not fold through each other as they close."""
        pairs = np.asarray(model.pair_vertices, np.int64)
        if not len(pairs):
            return None, None
        ptr, nbr = self._neighbours(model)
        mask = np.zeros(model.vertex_count, bool)
        mask[pairs.ravel()] = True
        sides = []
        for end in (pairs[:, 0], pairs[:, 1]):
            lens = ptr[end + 1] - ptr[end]
            rows = np.repeat(ptr[end] - np.r_[0, np.cumsum(lens)[:-1]], lens) + np.arange(lens.sum())
            sides.append((np.repeat(np.arange(len(end)), lens), nbr[rows]))
        (pa, va), (pb, vb) = sides
        ring = ~mask  # not a pair's own vertex
        mask[va] = mask[vb] = True
        pa, va = pa[ring[va]], va[ring[va]]
        pb, vb = pb[ring[vb]], vb[ring[vb]]
        order = np.argsort(pb, kind="stable")
        starts = np.searchsorted(pb[order], np.arange(len(pairs) + 1))
        count = starts[pa + 1] - starts[pa]  # each side-a neighbour against its pair's side-b neighbours
        rows = np.repeat(starts[pa] - np.r_[0, np.cumsum(count)[:-1]], count) + np.arange(count.sum())
        return mask, np.column_stack([np.repeat(va, count), vb[order][rows]])

    def _neighbours(self, model):
        """Each vertex's neighbours across an edge (CSR), for ``model``'s numbering (kept for untangling too)."""
        return self._topology(model)[0]

    def _topology(self, model):
        """(each vertex's neighbours across an edge (CSR), the unique edges) of ``model``'s numbering, kept
        while it stands: untangling checks the crossings every frame."""
        key = (model.vertex_count, self._version)
        if self._mesh_topology is None or self._mesh_topology[0] != key:
            self._mesh_topology = (key, vertex_rings(model.faces, model.vertex_count), unique_edges(model.faces, model.vertex_count))
        return self._mesh_topology[1:]

    def self_collider(self, model, x, body_x=None) -> SelfCollider:
        """The self-collider of ``model``'s numbering, built from positions ``x`` (and, for an
        outfit's layers, the body at ``body_x``) when it changed."""
        layered = self.panel_layer is not None and body_x is not None and self.settings.layers
        key = (model.vertex_count, self._version, layered, self._untucked_version if layered else 0)
        start = self._start  # where the next step starts, when told (follow)
        if self._self is None or self._self_key != key:
            if start is None and self._self is not None and self._self_key[:2] == key[:2]:
                start = self._self.previous  # the same numbering under new settings: where the last one ended
            stats = self._self.stats if self._self is not None else None
            friction = float(np.mean(self.friction * self.settings.friction_scale))
            layers = None
            if layered:
                loose = self._untucked if self._untucked is not None and len(self._untucked) == model.vertex_count else None
                layers = Layers.round_body(self.panel_layer[model.face_panel], model.face_panel, x, model.faces, body_x,
                                           self.body.faces, loose=loose)
            self._self = SelfCollider(model.faces, model.face_panel, x, thickness=self.thickness, margin=self.self_margin,
                                      mode=self.self_mode, friction=friction, layers=layers,
                                      partial=PARTIAL_SHARE if self.panel_layer is not None else 0.0,
                                      garment=self._vertex_garment(model))
            if stats is not None:
                self._self.carry_stats(stats)
            self._self_key = key
        if start is not None and len(start) == model.vertex_count:
            self._self.moved(start)
        self._start = None
        return self._self

    def body_thickness(self, model):
        """Distance [m] the body keeps each vertex of ``model`` at: the thickness, and for an outfit's
        garment k (innermost 0) k + 1 thicknesses, so that the body's response never pushes two layers
        to one offset (where the self-collision must then part them every step, or cannot)."""
        if self.panel_layer is None:
            return self.thickness
        key = (model.vertex_count, self._version)
        if self._layer_thickness is None or self._layer_thickness[0] != key:
            self._layer_thickness = (key, self.thickness * (1.0 + self._vertex_garment(model)))
        return self._layer_thickness[1]

    def _vertex_garment(self, model):
        """(N,) an outfit's garment of each vertex of ``model`` (None for one garment)."""
        if self.panel_layer is None:
            return None
        out = np.zeros(model.vertex_count, np.int64)
        out[model.faces] = self.panel_layer[model.face_panel][:, None]
        return out

    def untangle(self, model, state) -> tuple:
        """The cloth's edges through its own triangles pushed apart in place (:func:`~tailor.collide.untangle`),
        then any vertex so pushed into the body freed; (crossings found, crossings left). Nothing
        is done with self-collision off."""
        if self.self_mode == "off":
            return 0, 0
        key = (model.vertex_count, self._version)
        rings, edges = self._topology(model)
        inv_mass = np.where(model.vertex_pinned, 0.0, 1.0 / np.asarray(model.vertex_mass))
        found, left = untangle(state.x, model.faces, inv_mass, self.thickness, rings=rings, edges=edges, still=self._held_still(model))
        if found:
            if self._self is not None and self._self_key[:2] == key:
                self._self.moved(state.x)
            self._restart(state.x)
            self.rescue(model, state)
        return found, left

    def rescue(self, model, state) -> int:
        """Vertices trapped inside the body go back out (:meth:`BodyCollider.rescue`); how many."""
        if self.body is None:
            return 0
        bx, bv, k = self.motion.at(state.t)
        keep = None if math.isinf(self._rescue_limit) else partial(_bearable, model, state.x, self._rescue_limit)
        moved = self.body.rescue(model, state, bx, bv, k, thickness=self.body_thickness(model), keep=keep)
        if moved:
            self._restart(state.x)
        self.rescued += moved
        return moved

    def penetration(self, x, t: float) -> float:
        """How deep [m] the deepest vertex of ``x`` is inside the body at time ``t`` (0: none)."""
        if self.body is None:
            return 0.0
        bx, _, k = self.motion.at(t)
        return self.body.depth(x, bx, k)

    def self_report(self) -> dict:
        """What the self-collision pass did, for report.json."""
        return self._self.report() if self._self is not None else {"mode": self.self_mode}

    @property
    def deepest(self) -> float:
        """Deepest penetration [m] any body response had to undo."""
        return self.body.deepest if self.body is not None else 0.0
