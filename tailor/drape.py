"""The main job: place, sew and drape a garment on a (moving) body (Carignan §3–4).

:func:`drape` runs four phases:

1. **sewing** — body still, gravity off (GarmentCode's zero-gravity warm-up), seaming forces
   (Eq. 15) pull the placed panels together and pairs merge (Eq. 16–18) until every seam is
   closed, or a time-out raises :class:`~tailor.errors.SimulationError` naming the open seams;
2. **settling** — gravity on, attachments hold (Eq. 19–20), the garment comes to rest;
3. **transition** — a moving body that has a neutral pose (:attr:`~tailor.body.Body.rest`, as the
   shipped walk has) is dressed in that pose and then moves into its first frame in
   :data:`TRANSITION` seconds, so panels are never placed round a leg in mid-stride;
4. **motion** — the body moves; one frame every 1/fps s, frame 0 being the dressed garment. Each
   frame's step carries no body point that can reach the cloth within the frame more than half
   the contact margin (the feet do not shorten a T-shirt's steps).

Body contact (Eq. 9–14) acts in every phase through :class:`~tailor.collide.BodyCollider`, and
panels rolled round one of a pair of limbs (trouser legs) keep to their side of the plane between
the limbs below the limb's landmark, the plane following the body (:func:`~tailor.placement.limb_walls`).
Nothing here writes files: frames go to the caller (``on_frame``) and into the result.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.spatial import cKDTree

from .collide import SELF_COLLISION_MODES, BodyCollider, InsideTest, SelfCollider, self_intersections
from .errors import SimulationError
from .fabric import Fabric, preset
from .forces import total_forces
from .measure import measure_body
from .mesh import discretise
from .model import AIR_DENSITY, build_model
from .placement import limb_walls, place_panels
from .integrators import Contacts, make_integrator
from .seams import Sewing, merge_state
from .sim import Guard, quality as sim_quality, halved_steps, held_impulse, hold_contacts, max_stretch, simulate
from .sizing import check_loops
from .tearing import Cut, TearableCloth

__all__ = ["drape", "DrapeResult", "DrapeProgress", "NEAR_SEAM", "NEAR_RATE", "DRAPE_RESOLUTION"]

DRAPE_RESOLUTION = 0.02
"""Default garment mesh edge length [m] of :func:`drape` and ``tailor drape`` (2 cm)."""

NEAR_SEAM = 0.08
"""Seam pairs closer than this [m] are pulled by stiff implicit springs."""

NEAR_RATE = 80000.0
"""Their rate k [1/s²] (Eq. 15's k·η folded in): strong enough to stretch a waistband into place."""

COMPRESSION = 0.1
"""Fraction of the stretch stiffness resisting compression in garments (eased seams gather)."""

SEWING_MAX_STRETCH = 10.0
"""Sewing is assembly: a corner pulled three ways may stretch its triangles this far before merging."""


TRANSITION = 1.0
"""Seconds a body dressed in its rest pose takes to move into the first frame of its motion."""

TRANSITION_KEYS = 25
"""Key poses (collision hierarchies) along that transition."""

MOTION_MAX_STRETCH = 5.0
"""While the body moves, a triangle stretched further than this (or than ``MOTION_STRETCH_GROWTH``
times the dressed garment's worst) means the run has gone wrong; a hem kicked by a heel reaches 4."""

MOTION_STRETCH_GROWTH = 1.5
"""See ``MOTION_MAX_STRETCH``."""

SEWING_FRICTION = 0.0
"""Fraction of the fabric's friction acting while sewing (panels slide into place)."""

STRAGGLERS = 0.02
"""After ¾ of the sewing time-out, when at most this fraction of pairs (or :data:`MIN_STRAGGLERS`) is still open, ..."""

MIN_STRAGGLERS = 3
"""... (GarmentCode's fitted dress at 4 cm held the last 3 of 116 pairs, at a dart's mouth, 13.6 cm apart on
the body from 1.1 s on, one over 2 % of its pairs: it sewed at 3.5 and 4.5 cm and failed at 4) ..."""

STRAGGLER_REACH = 4.0
"""... pairs closer than this many mesh resolutions are merged where they are."""

log = logging.getLogger(__name__)


class _NearBodySpeed:
    """The largest speed [m/s] of the body vertices that can reach the cloth within a frame.

    Per body vertex, its speed over each interval of the motion (looping, as :meth:`Body.at`) and,
    with a rest ``pose``, over the transition. A body vertex can touch the cloth within ``duration``
    only if it is nearer than the contact margin plus how far both can travel meanwhile (the cloth
    at up to twice its fastest vertex's speed plus 1 m/s) plus the longest body edge (a triangle
    reaches that far from its corners); the others do not limit the step.
    """

    def __init__(self, body, pose, margin: float):
        f = np.asarray(body.frames, dtype=np.float64)
        self.speeds = np.linalg.norm(np.roll(f, -1, axis=0) - f, axis=2) * body.fps if len(f) > 1 else None
        self.ease = None if pose is None else np.linalg.norm(f[0] - pose, axis=1) / TRANSITION
        faces = np.asarray(body.faces)
        self.edge = float(np.linalg.norm(f[0][faces] - f[0][np.roll(faces, 1, axis=1)], axis=2).max())
        self.fps, self.margin = body.fps, margin

    def __call__(self, x, v, body_x, duration: float, span) -> float:
        """``span`` is (start, end) in the motion's time [s], or None during the transition."""
        if span is None:
            speed = self.ease
        elif self.speeds is None:
            return 0.0
        else:
            k0 = int(math.floor(span[0] * self.fps + 1e-9))
            k1 = max(k0 + 1, int(math.ceil(span[1] * self.fps - 1e-9)))
            speed = self.speeds[np.arange(k0, k1) % len(self.speeds)].max(axis=0)
        if speed is None or not len(x):
            return 0.0
        cloth = float(np.sqrt((v * v).sum(axis=1).max())) if len(v) else 0.0
        reach = self.margin + (float(speed.max()) + 2.0 * cloth + 1.0) * duration + self.edge
        d, _ = cKDTree(x).query(body_x, distance_upper_bound=reach)
        near = np.isfinite(d)
        return float(speed[near].max()) if near.any() else 0.0


@dataclass
class DrapeResult:
    """Frames of a drape and everything needed to write them.

    Attributes
    ----------
    frames : list of (N, 3) arrays [m]
        Garment vertex positions, frame 0 = dressed and settled.
    body_frames : list of (M, 3) arrays [m]
        The body at the same instants.
    mesh : GarmentMesh
    weld : (N,) int
        Index of each vertex in the welded garment (merged seam vertices share one).
    body_faces : (F, 3) int
        Triangles of the body frames.
    pattern : Pattern
    report : dict
        Inputs, derived parameters, steps and wall time per phase, seam gaps, penetration.
    topology : list of (frame, GarmentMesh, weld)
        Where a cut or a tear changed the garment's mesh: from that frame on, frames hold the
        vertices of that mesh (``mesh`` and ``weld`` above are frame 0's). Empty if it never changed.
    """

    frames: list
    body_frames: list
    mesh: object
    weld: np.ndarray
    body_faces: np.ndarray
    pattern: object
    report: dict = field(default_factory=dict)
    topology: list = field(default_factory=list)

    def topology_at(self, frame: int):
        """``(mesh, weld)`` of frame ``frame``."""
        mesh, weld = self.mesh, self.weld
        for first, m, w in self.topology:
            if first <= frame:
                mesh, weld = m, w
        return mesh, weld


@dataclass(frozen=True)
class DrapeProgress:
    """What :func:`drape` reports to its ``progress`` callback after every frame.

    Attributes
    ----------
    phase : str
        ``sewing``, ``settling``, ``transition`` (into the motion's first pose) or ``motion``.
    done, total : int
        Seam vertex pairs welded (sewing) or frames simulated (other phases) of this phase.
    simulated_s : float
        Simulated time so far, all phases [s].
    steps : int
        Integrator steps so far, all phases.
    """

    phase: str
    done: int
    total: int
    simulated_s: float
    steps: int


def _attachment_vertices(pattern, mesh, attachment):
    pi = pattern.panel_index(attachment.panel)
    if attachment.vertex is not None:
        panel = pattern.panels[pi]
        edge = next(k for k, e in enumerate(panel.edges) if e.endpoints[0] == attachment.vertex)
        return mesh.edge_vertices[(pi, None, edge)][:1]
    ids = mesh.edge_vertices[(pi, attachment.hole, attachment.edge)]
    t = np.linspace(0.0, 1.0, len(ids))
    lo, hi = min(attachment.start, attachment.end), max(attachment.start, attachment.end)
    return ids[(t >= lo - 1e-9) & (t <= hi + 1e-9)]


class _Attachments:
    """Vertices held to body points (barycentric on a body triangle, offset along its normal)."""

    def __init__(self, ids, tri, bary, offset, faces):
        self.ids, self.tri, self.bary, self.offset, self.faces = ids, tri, bary, offset, faces

    def apply(self, state, body_x, body_v):
        f = self.faces[self.tri]
        p = (body_x[f] * self.bary[:, :, None]).sum(axis=1)
        a, b, c = body_x[f[:, 0]], body_x[f[:, 1]], body_x[f[:, 2]]
        n = np.cross(b - a, c - a)
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        state.x[self.ids] = p + self.offset[:, None] * n
        state.v[self.ids] = (body_v[f] * self.bary[:, :, None]).sum(axis=1)


def drape(pattern, body, fabric=None, *, frames: int = 25, fps: float = 25.0, resolution: float = DRAPE_RESOLUTION,
          integrator: str = "implicit", sew_timeout: float = 4.0, settle: float = 1.0, record_sewing: bool = False,
          self_collision: str = "auto", quality: str = "final", wind=None, cuts=(), tear: bool = False, on_frame=None,
          progress=None) -> DrapeResult:
    """Dress ``body`` in ``pattern`` and animate it.

    Parameters
    ----------
    pattern : Pattern
    body : Body
        Static or moving (:func:`tailor.io.body_files.read_body`).
    fabric : Fabric or str, optional
        Overrides the pattern's fabric (panels with their own keep theirs).
    frames : int
        Frames to produce after the garment is dressed (frame 0 included).
    resolution : float
        Mesh edge length [m] (:data:`DRAPE_RESOLUTION`, 2 cm, as ``tailor drape``).
    record_sewing : bool
        Also return the sewing and settling as frames (before frame 0).
    self_collision : {"auto", "on", "off"}
        Cloth–cloth contact (:class:`~tailor.collide.SelfCollider`) from the moment the garment is
        sewn (during sewing, seam edges must be free to meet); ``auto`` (default) checks only the
        regions that can touch themselves.
    quality : {"draft", "normal", "final"}
        Implicit step and solver tolerance (:data:`tailor.sim.QUALITY`); ``final`` is the setting
        the garment tests validate.
    wind : Wind or (3,) air velocity [m/s], optional
        Blows on the garment once it is sewn (:class:`tailor.forces.wind.Wind`: turbulent Perlin noise).
    cuts : sequence of :class:`~tailor.tearing.Cut`
        The brush on the dressed garment: ``time`` counts from frame 0, points are in the body's
        frame [m]. A cut is made after the first step ending at or after its time.
    tear : bool
        Let the garment tear where it is stretched across an edge beyond its fabric's
        ``tear_strain`` (the smallest among its panels' fabrics), from frame 0 on.
        With cuts or tearing the mesh may change: see :attr:`DrapeResult.topology`.
    on_frame : callable ``on_frame(index, garment_x, body_x)``, optional
    progress : callable ``progress(DrapeProgress)``, optional
        Called after every frame of every phase.

    Raises
    ------
    SimulationError
        Seams that do not close within ``sew_timeout`` seconds; SimulationUnstable from the guard.
    """
    t_start = time.perf_counter()
    if self_collision not in SELF_COLLISION_MODES:
        raise ValueError(f"self_collision must be one of {', '.join(SELF_COLLISION_MODES)}, got {self_collision!r}")
    cuts = sorted(cuts, key=lambda c: c.time)
    if not all(isinstance(c, Cut) for c in cuts):
        raise TypeError("cuts must be tailor.tearing.Cut objects")
    if isinstance(fabric, str):
        fabric = preset(fabric)
    base = fabric if isinstance(fabric, Fabric) else pattern.fabric
    fabrics = {i: (p.fabric or base) for i, p in enumerate(pattern.panels)}
    mesh = discretise(pattern, resolution)
    n = mesh.vertex_count
    # a moving body with a neutral pose is dressed in that pose, then eased into its first frame
    moving = body.frame_count > 1
    has_rest = moving and body.rest is not None
    pose = body.rest if has_rest else body.frames[0]
    keys = TRANSITION_KEYS if has_rest else 0
    landmarks = measure_body(body, pose)
    loops = check_loops(pattern, landmarks)  # a loop too small for the body fails now, not at the sewing time-out
    x0 = place_panels(pattern, mesh, landmarks, inside=InsideTest(pose, body.faces))
    walls = limb_walls(pattern, landmarks, pose)
    thickness = max(f.thickness for f in fabrics.values()) + 0.002
    unwelded = build_model(mesh, fabrics, air_density=AIR_DENSITY, compression=COMPRESSION)
    mass = np.asarray(unwelded.vertex_mass)
    panel_friction = np.array([fabrics[i].friction for i in range(len(pattern.panels))])
    friction_of = panel_friction[mesh.vertex_panel]
    sewing = Sewing(mesh.seam_pairs, merge_distance=max(0.3 * resolution, 0.002))
    # collider frames: the dressing pose, the transition's key poses, then the motion
    if keys:
        steps = np.arange(1, keys + 1)[:, None, None] / keys
        collider_frames = np.concatenate([pose[None], pose + steps * (body.frames[0] - pose), body.frames])
    else:
        collider_frames = body.frames
    collider = BodyCollider(collider_frames, body.faces, margin=max(0.03, 2 * thickness))
    walk0 = 1 + keys if keys else 0  # collider index of motion frame 0
    integ = make_integrator(integrator)
    preset_q = sim_quality(quality)
    if hasattr(integ, "tolerance"):
        # sewing is assembly at the same step in every preset, with stiff seam springs pulling panels
        # metres: a loose solve there (draft's 1e-2) let cotton T-shirt corners stretch 10x and blow
        # up; the preset's tolerance applies once the garment is sewn
        integ.tolerance = sim_quality("final").tolerance
    settle_stretch_change = getattr(integ, "max_stretch_change", None)
    if settle_stretch_change is not None:
        # and the seams' pull stretches the triangles at the seams far in a step by design (merged
        # and relaxed afterwards): halving those steps only slows the assembly down
        integ.max_stretch_change = math.inf
    report = {"vertices": int(n), "faces": int(mesh.face_count), "resolution_m": resolution, "fps": fps,
              "integrator": integrator, "time_step_eq24_s": unwelded.time_step, "phases": {}, "seam_pairs": len(sewing.pairs),
              "loops": {lp.landmark: {"panels": list(lp.panels), "length_cm": round(lp.length * 100, 1),
                                      "body_cm": round(lp.girth * 100, 1), "ease_cm": round(lp.ease * 100, 1)} for lp in loops},
              "fabrics": {p.name: fabrics[i].name for i, p in enumerate(pattern.panels)},
              "body": {**body.report, "name": body.name, "fps": body.fps, "frames": body.frame_count},
              "params": {p.name: unwelded.params[i].as_dict() for i, p in enumerate(pattern.panels)},
              "quality": {"name": preset_q.name, "max_step_s": preset_q.step, "solver_tolerance": preset_q.tolerance},
              "active": {"bending": unwelded.has_bending, "air": True, "wind": wind is not None, "body_collision": True,
                         "self_collision": self_collision,
                         "limb_walls": [p.name for i, p in enumerate(pattern.panels) if walls.panel[i] >= 0]},
              "skipped": [reason for cond, reason in (
                  (not unwelded.has_bending, "bending (every fabric has bending number 0)"),
                  (self_collision == "off", "self-collision (--self-collision off)"),
                  (True, "body triangles farther than the contact margin from the cloth (FCL broad phase)"),
              ) if cond]}
    sim = {"weld": np.arange(n), "model": unwelded, "gravity": False, "pins": np.zeros(0, np.intp), "friction": friction_of,
           "attach": None, "motion_start": None, "transition_start": None, "rebuilds": 0, "rescued": 0, "self": None,
           "self_key": None, "topology": 0, "wall": None, "wall_weld": None, "mesh": mesh,
           "steps": 0}

    def tell(phase, done, total, state):
        if progress:
            progress(DrapeProgress(phase, done, total, float(state.t), sim["steps"]))

    def rebuild(state_x, state_v):
        """Weld the merged pairs into one particle each and carry the state over (Eq. 17–18)."""
        old = sim["weld"]
        x_orig, v_orig = state_x[old], state_v[old]
        new = sewing.weld_map(n)
        xw, vw = merge_state(x_orig, v_orig, mass, new)
        m = build_model(mesh, fabrics, air_density=AIR_DENSITY, weld=new, compression=COMPRESSION,
                        gravity=(0.0, 0.0, -9.80665) if sim["gravity"] else (0.0, 0.0, 0.0))
        if len(sim["pins"]):
            m = m.with_pins(np.unique(new[sim["pins"]]))
        if sewing.open_count:
            pairs = sewing.open_pairs(new)
            m = m.with_pairs(pairs, np.zeros(len(pairs)), np.zeros(len(pairs)))
        sim["weld"], sim["model"] = new, m
        sim["friction"] = friction_of[np.unique(new, return_index=True)[1]]  # per welded vertex
        sim["rebuilds"] += 1
        return m.state(xw, vw, 0.0)

    def body_state(t):
        """Body positions, velocities and collider frame at time ``t``."""
        ease, start = sim["transition_start"], sim["motion_start"]
        if ease is None or (start is None and not keys):
            return pose, np.zeros_like(pose), 0
        if start is None:  # transition: rest pose → first frame at constant speed
            a = min(max((t - ease) / TRANSITION, 0.0), 1.0)
            return (pose + a * (body.frames[0] - pose), (body.frames[0] - pose) / TRANSITION,
                    1 + min(keys - 1, int(a * keys)))
        if not moving:
            return pose, np.zeros_like(pose), 0
        tb = max(0.0, t - start)
        bx, bv = body.at(tb)
        return bx, bv, walk0 + int(round(tb * body.fps)) % body.frame_count

    deepest = [0.0]

    def landing(model_, state, x_end, v_end, dt, held):
        """Contacts the solved step would make with the body as it is at the step's end (sewn garments)."""
        if not sim["gravity"]:
            return None
        bx, bv, k = body_state(state.t + dt)
        return Contacts(*collider.landing(model_, x_end, v_end, dt, bx, bv, k, thickness=thickness, skip=held),
                        model_.vertex_count)

    if hasattr(integ, "predict"):
        integ.predict = landing

    def wall(state, bx, bv):
        """A leg's panels stay on their side of the plane between the legs, below the crotch, as the
        body moves (:func:`~tailor.placement.limb_walls`): inelastic, like a body contact."""
        if not walls.count:
            return
        if sim["wall_weld"] is not sim["weld"]:  # welded vertices whose members agree on one wall
            w, nw = sim["weld"], int(sim["weld"].max()) + 1
            lo = np.full(nw, walls.count)
            hi = np.full(nw, -1)
            of = walls.of(sim["mesh"])
            np.minimum.at(lo, w, of)
            np.maximum.at(hi, w, of)
            ids = np.flatnonzero((lo == hi) & (hi >= 0))
            sim["wall"] = (ids, hi[ids])
            sim["wall_weld"] = sim["weld"]
        ids, which = sim["wall"]
        if not len(ids):
            return
        normal, offset, height, speed = walls.at(bx, bv)
        n, x = normal[which], state.x[ids]
        depth = thickness - (np.einsum("ij,ij->i", x, n) - offset[which])
        hit = (depth > 0) & (x[:, 2] < height[which])
        if hit.any():
            i, nh = ids[hit], n[hit]
            state.x[i] += depth[hit, None] * nh
            vn = np.einsum("ij,ij->i", state.v[i], nh) - speed[which[hit]]
            state.v[i] -= np.minimum(vn, 0.0)[:, None] * nh

    def hook(model_, state, dt):
        sim["steps"] += 1
        bx, bv, k = body_state(state.t)
        wall(state, bx, bv)
        if sim["attach"] is not None:
            sim["attach"].apply(state, bx, bv)
        # sewing is assembly: panels slide over the body into place without friction
        mu = sim["friction"] if sim["gravity"] else sim["friction"] * SEWING_FRICTION
        deepest[0] = max(deepest[0], collider.respond(model_, state, dt, bx, bv, k, thickness=thickness, friction=mu,
                                                      impulse=held_impulse(integ, model_)))
        if sim["gravity"]:  # sewn: the solve holds resting contacts (sewing slides panels over the body freely)
            hold_contacts(integ, model_, collider.contact_set)
        if self_collision != "off" and sim["gravity"]:  # sewn: layers may no longer pass through each other
            selfc = sim["self"]
            key = (model_.vertex_count, sim["topology"])
            if selfc is None or sim["self_key"] != key:
                # welding (or a cut or a tear) renumbered the vertices
                stats = selfc.stats if selfc is not None else None
                selfc = sim["self"] = SelfCollider(model_.faces, model_.face_panel, state.x, thickness=thickness,
                                                   mode=self_collision, friction=float(np.mean(mu)))
                if stats is not None:
                    selfc.carry_stats(stats)
                sim["self_key"] = key
                sim["self_inv_mass"] = np.where(model_.vertex_pinned, 0.0, 1.0 / np.asarray(model_.vertex_mass))
            selfc.respond(sim["self_inv_mass"], state, dt)

    def forces(model_, state):
        return sewing.forces(model_, state, sim["weld"], total_forces(model_, state, wind=wind if sim["gravity"] else None))

    # while the body moves, no body point may travel more than half the contact margin in one step
    body_speed = float(np.abs(np.diff(body.frames, axis=0)).max() * body.fps) if moving else 0.0
    if keys:
        body_speed = max(body_speed, float(np.abs(body.frames[0] - pose).max()) / TRANSITION)
    # implicit steps shrink with the mesh: body contact is resolved once a step, so a vertex must not
    # move far compared with its triangles (2 cm jersey at 0.01 s crumpled at the shoulders, 4.9x
    # stretched; at 0.005 s it hangs at 1.8x, as the 4 cm mesh does at 0.01 s)
    still_dt = min(preset_q.step, preset_q.step_per_resolution * resolution) if not integ.explicit else None
    motion_dt = still_dt
    if body_speed > 0:
        motion_dt = min(still_dt or 0.01, 0.5 * collider.margin / body_speed)
    # ... but only body points near the cloth count: a swinging hand or foot far from a T-shirt does
    # not shorten its steps (per body vertex, its speed in each interval of the motion, looping, and
    # during the transition)
    near_speed = _NearBodySpeed(body, pose if keys else None, collider.margin) if body_speed > 0 else None
    steps_used = []

    def moving_step(state, duration):
        """The step for the next ``duration`` s while the body moves (see ``near_speed``); explicit
        integrators keep their Eq. 24 step (None), far below it (a given 7 ms step diverged)."""
        if integ.explicit:
            return None
        if near_speed is None:
            return motion_dt
        bx = body_state(state.t)[0]
        start = sim["motion_start"]
        span = None if start is None else (state.t - start, state.t - start + duration)
        fastest = near_speed(state.x, state.v, bx, duration, span)
        dt = min(still_dt or 0.01, 0.5 * collider.margin / fastest) if fastest > 0 else (still_dt or 0.01)
        steps_used.append(dt)
        return dt

    def advance(state, duration, rescue_after=True):
        """Simulate ``duration`` seconds on the current welded model; return the final state."""
        t = state.t
        last = state
        m = sim["model"]
        if len(m.pair_vertices):  # near seam pairs get stiff implicit springs for this frame
            k, c = sewing.near_stiffness(state.x, m.pair_vertices, m.vertex_mass, near=NEAR_SEAM, rate=NEAR_RATE)
            sim["model"] = replace(m, pair_stiffness=k, pair_damping=c)
        # sewing is assembly, not physics: corners pulled three ways may stretch far until merged
        # and relaxed, so the guard is looser until the body starts moving; then it watches for growth
        moving_now = sim["transition_start"] is not None
        guard = Guard(max_stretch=sim["motion_limit"]) if moving_now else Guard(max_stretch=SEWING_MAX_STRETCH)
        # sewing keeps the plain implicit step: the seams must move the panels far, and do
        dt = moving_step(state, duration) if moving_now else (still_dt if sim["gravity"] else None)
        for _, last in simulate(sim["model"], state, duration=duration, frame_rate=1.0 / duration, integrator=integ,
                                hooks=[hook], forces=forces, guard=guard, dt=dt):
            continue
        last.t = t + duration
        if rescue_after:
            rescue(last)
        return last

    def rescue(state):
        """Once a frame (and after every merge): vertices trapped inside the body go back out."""
        bx, bv, k = body_state(state.t)
        sim["rescued"] += collider.rescue(sim["model"], state, bx, bv, k, thickness=thickness)

    out_frames, body_frames = [], []

    def emit(state, bx):
        x = state.x[sim["weld"]]
        if on_frame is not None:
            on_frame(len(out_frames), x, bx)
        out_frames.append(x.copy())
        body_frames.append(bx.copy())

    frame_dt = 1.0 / fps
    # 1. sewing, gravity off: one frame at a time, welding what closed
    t0 = time.perf_counter()
    sim["model"] = replace(unwelded, gravity=np.zeros(3))
    pairs0 = sewing.open_pairs(sim["weld"])
    sim["model"] = sim["model"].with_pairs(pairs0, np.zeros(len(pairs0)), np.zeros(len(pairs0)))
    state = sim["model"].state(x0)
    sew_frames = 0
    t = 0.0
    while sewing.open_count and t < sew_timeout:
        state = advance(state, frame_dt)
        t += frame_dt
        sew_frames += 1
        if t >= 0.5 * sew_timeout:  # stragglers held apart by two seams at a corner: Eq. 16's d grows
            sewing.merge_distance = max(sewing.merge_distance, 0.6 * resolution)
        if t >= 0.75 * sew_timeout and sewing.open_count <= max(MIN_STRAGGLERS, STRAGGLERS * len(sewing.pairs)):
            # the last few pairs caught on the body (an underarm corner behind the arm): stitch them
            # where they are, as a tailor would, if they are within a few triangles of each other
            sewing.merge_distance = max(sewing.merge_distance, STRAGGLER_REACH * resolution)
        if sewing.close(state.x[sim["weld"]]):
            state = rebuild(state.x, state.v)
            state.t = t
            rescue(state)
        if record_sewing:
            emit(state, pose)
        tell("sewing", len(sewing.pairs) - sewing.open_count, len(sewing.pairs), state)
    if sewing.open_count:
        gaps = np.where(sewing.merged, 0.0, sewing.gaps(state.x[sim["weld"]]))
        w = int(np.argmax(gaps))
        seam = pattern.seams[mesh.seam_pair_seam[w]]

        def side(sd):
            return f"{sd.panel}" + (f" hole {sd.hole}" if sd.hole is not None else "") + f" edge {sd.edge}"

        raise SimulationError(
            f"{pattern.source}: pattern.stitches[{seam.index}]: {sewing.open_count} of {len(sewing.pairs)} seam vertex "
            f"pairs are still open after {sew_timeout:g} s of sewing (widest gap {gaps[w] * 100:.1f} cm, on the stitch "
            f"{side(seam.a)} to {side(seam.b)}); check that stitch and the placements, or allow more time (--sew-timeout)"
        )
    report["phases"]["sewing"] = {"simulated_s": t, "frames": sew_frames, "wall_s": time.perf_counter() - t0,
                                  "max_gap_at_merge_m": sewing.max_gap_at_merge, "rebuilds": sim["rebuilds"]}
    # 2. attachments, then settling under gravity
    t0 = time.perf_counter()
    held = [_attachment_vertices(pattern, mesh, a) for a in pattern.attachments]
    sim["gravity"] = True
    if hasattr(integ, "tolerance"):
        integ.tolerance = preset_q.tolerance
    if settle_stretch_change is not None:
        integ.max_stretch_change = settle_stretch_change
    if hasattr(integ, "wind"):
        integ.wind = wind  # the solve treats drag relative to this air implicitly
    if held:
        ids = np.unique(np.concatenate(held))
        dist, tri, bary, _ = collider.nearest(state.x[sim["weld"][ids]], pose, 0, cache=False)
        ok = tri >= 0
        sim["pins"] = ids[ok]
    state = rebuild(state.x, state.v)
    state.t = t
    if len(sim["pins"]):
        wid = sim["weld"][sim["pins"]]
        wid, first = np.unique(wid, return_index=True)
        sim["attach"] = _Attachments(wid, tri[ok][first], bary[ok][first],
                                     np.maximum(dist[ok][first], thickness), collider.faces)
    settle_frames = int(round(settle * fps))
    for i in range(settle_frames):
        state = advance(state, frame_dt)
        if record_sewing:
            emit(state, pose)
        tell("settling", i + 1, settle_frames, state)
    report["phases"]["settling"] = {"simulated_s": settle, "wall_s": time.perf_counter() - t0}
    dressed_stretch = max_stretch(sim["model"], state.x)
    sim["motion_limit"] = max(MOTION_MAX_STRETCH, MOTION_STRETCH_GROWTH * dressed_stretch)
    report["max_triangle_stretch_dressed"] = dressed_stretch
    # 3. transition: a body dressed in its neutral pose moves into the first frame of its motion
    t0 = time.perf_counter()
    sim["transition_start"] = state.t
    if keys:
        transition_frames = int(round(TRANSITION * fps))
        for i in range(transition_frames):
            state = advance(state, frame_dt)
            if record_sewing:
                emit(state, body_state(state.t)[0])
            tell("transition", i + 1, transition_frames, state)
        report["phases"]["transition"] = {"simulated_s": TRANSITION, "wall_s": time.perf_counter() - t0}
    # 4. motion, one frame every 1/fps
    t0 = time.perf_counter()
    sim["motion_start"] = state.t
    penetration, crossings = [], []
    cloth, segments, weld_frame0 = None, [], sim["weld"]
    if cuts or tear:  # the mesh may change: a TearableCloth owns it (and the weld) from here on
        strain = min((f_.tear_strain for f_ in fabrics.values() if f_.tear_strain > 0), default=0.0) if tear else 0.0

        def build(mesh_, pinned, weld):
            m = build_model(mesh_, fabrics, air_density=AIR_DENSITY, weld=weld, compression=COMPRESSION)
            return m.with_pins(np.flatnonzero(pinned)) if pinned.any() else m

        cloth = TearableCloth(mesh, build, tear_strain=strain, pinned=sim["model"].vertex_pinned, weld=sim["weld"])
        sim["model"] = cloth.model
        report["active"].update(cuts=len(cuts), tearing=tear)
        report["tearing"] = {"tear_strain": strain}

    def change(state):
        """Due cuts, then tearing; on a change, everything that numbers the vertices follows."""
        old = cloth.model.vertex_count
        before = cloth.mesh
        while cuts and cuts[0].time <= state.t - sim["motion_start"] + 1e-9:
            state = cloth.cut(state, cuts.pop(0))
        torn = cloth.tear(state)
        state = torn if torn is not None else state
        if cloth.mesh is before:
            return state
        inverse = np.full(old, -1, np.intp)  # old simulated vertex → its new index (the first copy)
        inverse[cloth.last_source[::-1]] = np.arange(len(cloth.last_source))[::-1]
        if sim["attach"] is not None:
            a = sim["attach"]
            ids = inverse[a.ids]
            ok = ids >= 0
            sim["attach"] = _Attachments(ids[ok], a.tri[ok], a.bary[ok], a.offset[ok], a.faces)
        sim["model"], sim["weld"], sim["mesh"] = cloth.model, cloth.weld, cloth.mesh
        sim["friction"] = panel_friction[cloth.mesh.vertex_panel[np.unique(cloth.weld, return_index=True)[1]]]
        sim["topology"] += 1
        collider.forget()
        integ.reset()
        if hasattr(integ, "contacts"):
            integ.contacts = None
        segments.append((len(out_frames), cloth.mesh, cloth.weld.copy()))
        return state

    sub = max(1, int(np.ceil(frame_dt / motion_dt - 1e-9))) if motion_dt else 1
    for f in range(frames):
        if f and cloth is None:
            state = advance(state, frame_dt)
        elif f:  # one step at a time: a crack runs on from step to step
            for _ in range(sub):
                state = change(advance(state, frame_dt / sub, rescue_after=False))
            rescue(state)
        elif cloth is not None:
            state = change(state)
        bx, _, k = body_state(state.t)
        dist, tri, _, _ = collider.nearest(state.x, bx, k)
        inside = dist[tri >= 0]
        penetration.append(float(max(0.0, -inside.min())) if len(inside) else 0.0)
        crossings.append(len(self_intersections(state.x, sim["model"].faces)))  # the cloth through itself
        emit(state, bx)
        tell("motion", f + 1, frames, state)
    report["phases"]["motion"] = {"simulated_s": (frames - 1) / fps, "frames": frames, "wall_s": time.perf_counter() - t0,
                                  "time_step_s": motion_dt, "time_step_still_s": still_dt, "body_max_speed_m_s": body_speed,
                                  "time_step_near_s": [min(steps_used), max(steps_used)] if steps_used else None}
    report["max_penetration_m_per_frame"] = penetration
    report["max_penetration_m"] = max(penetration) if penetration else 0.0
    report["self_intersections_per_frame"] = crossings  # intersecting triangle pairs (none sharing a vertex)
    report["wall_s"] = time.perf_counter() - t_start
    report["steps"] = sim["steps"]
    report["cg_iterations"] = int(getattr(integ, "total_iterations", 0))
    # implicit steps taken as halves: CG did not converge, or a step would stretch a triangle too far
    report["halved_steps"] = halved_steps(integ)
    report["body_bvh_queries"] = collider.queries
    report["max_contact_correction_m"] = deepest[0]  # deepest penetration any step had to undo
    report["vertices_rescued_from_inside_body"] = sim["rescued"]
    report["welded_vertices"] = int(sim["model"].vertex_count)
    report["self_collision"] = sim["self"].report() if sim["self"] is not None else {"mode": self_collision}
    if cloth is not None:
        report["tearing"].update(edges_torn=cloth.tears, topology_changes=len(segments),
                                 events=[{"t_s": round(t_ - sim["motion_start"], 6), "edges": e} for t_, e in cloth.events])
    return DrapeResult(out_frames, body_frames, mesh, weld_frame0, body.faces, pattern, report, topology=segments)
