"""The main job: place, sew and drape a garment on a (moving) body (Carignan §3–4).

:func:`drape` is short orchestration over named parts: :mod:`.options` (what is asked, and every
phase's settings), :mod:`.timeline` (the body over time), :mod:`.garment` (the one owner of the
vertex numbering), the :class:`~tailor.contact.ContactPipeline` (walls, attachments, body,
self-contact, rescue), :mod:`.phases` (sew, settle, transition, animate) and :mod:`.report`.
Nothing here writes files: frames go to the caller (``on_frame``, ``sink``) and, unless ``keep_frames`` is
off, into the result.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..collide import BodyCollider, InsideTest, edge_crossings
from ..contact import ContactPipeline, body_margin
from ..errors import SimulationError
from ..integrators import make_integrator
from ..measure import measure_body
from ..mesh import discretise
from ..outfit import ease_layers, garment_of_vertex, outfit
from ..limbwalls import limb_walls
from ..placement import place_panels
from ..sim import max_stretch, quality as sim_quality
from ..sizing import check_loops
from .garment import Garment, layer_spacing
from .options import DRAPE_RESOLUTION, SETTLE_QUALITY, DrapeOptions, settle_step
from .phases import Dressing, animate, settle, sew, transition
from .report import DrapeFrame, DrapeProgress, DrapeReport, DrapeResult, PhaseReport
from .timeline import Timeline

log = logging.getLogger(__name__)

__all__ = ["drape", "prepare", "DrapeResult", "DrapeReport", "DrapeProgress", "DrapeFrame", "DrapeOptions", "PhaseReport", "DRAPE_RESOLUTION"]


def drape(pattern, body, fabric=None, *, on_frame=None, sink=None, progress=None, options: DrapeOptions | None = None,
          tuck: bool = False, **kwargs) -> DrapeResult:
    """Dress ``body`` in ``pattern`` and animate it.

    Parameters
    ----------
    pattern : Pattern or list of Pattern
        A list dresses an outfit: the garments together, innermost first or by their ``layer``
        (:func:`tailor.outfit.outfit`); with ``tuck``, a top's hem inside a bottom's waistband.
    body : Body
        Static or moving (:func:`tailor.io.body_files.read_body`).
    fabric : Fabric or str, optional
        Overrides the pattern's fabric (panels with their own keep theirs).
    on_frame : callable ``on_frame(index, garment_x, body_x)``, optional
    sink : callable ``sink(DrapeFrame)``, optional
        Each frame with its loads and mesh as it leaves the simulation (:class:`DrapeFrame`): a
        writer streaming the frames to disk (:class:`tailor.io.garment.DrapeWriter`), with
        ``keep_frames=False`` so the result holds none of them.
    progress : callable ``progress(DrapeProgress)``, optional
        Called after every frame of every phase.
    options : DrapeOptions, optional
        Or its fields as keyword arguments:

        - ``frames`` (25): frames to produce after the garment is dressed (frame 0 included);
        - ``fps`` (25); ``resolution``: mesh edge length [m] (:data:`DRAPE_RESOLUTION`, 2 cm);
        - ``integrator`` ("implicit"): see :mod:`tailor.integrators`;
        - ``sew_timeout`` (4 s), ``settle`` (at most 1 s: settling ends once the garment is still);
        - ``record_sewing``: also return the sewing and settling as frames (before frame 0);
        - ``self_collision`` ("auto"): cloth–cloth contact from the moment the garment is sewn;
          ``auto`` checks only the regions that can touch themselves, ``on``, ``off``;
        - ``quality`` (:data:`tailor.sim.DEFAULT_QUALITY`): implicit step and solver tolerance (:data:`tailor.sim.QUALITY`);
          ``draft`` is the knee of the garment frontier (README, "Speed versus accuracy");
        - ``wind``: a :class:`~tailor.forces.wind.Wind` or (3,) air velocity, blowing once sewn;
        - ``cuts``: :class:`~tailor.tearing.Cut` on the dressed garment, ``time`` from frame 0,
          points in the body's frame [m]; made after the first step ending at or after its time;
        - ``tear``: the garment tears where stretched across an edge beyond its fabric's
          ``tear_strain``. With cuts or tearing see :attr:`DrapeResult.topology`;
        - ``limb_walls`` (True): each leg's panels keep to their side of the plane between the legs;
        - ``keep_frames`` (True): keep every frame in the result (off: they only go to ``on_frame``
          and ``sink``, and memory does not grow with the frame count).

    Raises
    ------
    SimulationError
        An invalid option; seams that do not close within ``sew_timeout``; SimulationUnstable.
    """
    t_start = time.perf_counter()
    if isinstance(pattern, (list, tuple)):
        pattern = outfit(pattern, tuck=tuck)
    elif tuck:
        raise SimulationError("tuck applies to a list of patterns (a top and a bottom), or make the outfit with "
                              "tailor.outfit(patterns, tuck=True)")
    opts = options or DrapeOptions(fabric=fabric, **kwargs)
    if options is not None and (fabric is not None or kwargs):
        opts = replace(options, **kwargs, **({"fabric": fabric} if fabric is not None else {}))
    d, loops, x0 = prepare(pattern, body, opts, on_frame, progress, sink)
    pattern = d.garment.pattern  # an outfit's, eased (tailor.outfit.ease_layers)
    report = _header(d, pattern, body, loops, opts)
    report.placement_crossings = _placement_crossings(x0, d.garment.mesh, pattern)
    report.garments = _garments(pattern, d.garment.mesh)
    state, report.phases["sewing"] = sew(d, x0)
    state, report.phases["settling"] = settle(d, state)
    report.max_triangle_stretch_dressed = max_stretch(d.garment.model, state.x)
    state, phase = transition(d, state)
    if phase is not None:
        report.phases["transition"] = phase
    state, report.phases["motion"], report.max_penetration_m_per_frame, report.crossings_per_frame = animate(d, state)
    _close(report, d, t_start)
    return DrapeResult(d.frames, d.body_frames, *d.first_topology, body.faces, pattern, report, topology=d.topology,
                       contact_forces=[c for c, _ in d.loads], attachment_forces=[a for _, a in d.loads])


def prepare(pattern, body, opts: DrapeOptions, on_frame=None, progress=None, sink=None):
    """The garment placed round the body, the timeline, the contacts: a :class:`Dressing` ready to
    sew; also the pattern's loops checked against the body and the placed positions."""
    base = opts.fabric or pattern.fabric
    fabrics = {i: (p.fabric or base) for i, p in enumerate(pattern.panels)}
    integ = make_integrator(opts.integrator)
    q = sim_quality(opts.quality)
    # implicit steps shrink with the mesh: body contact is resolved once a step, so a vertex must
    # not move far compared with its triangles (docs/measurements.md)
    still = settle = ramp = None  # explicit integrators keep Eq. 24's step
    if not integ.explicit:  # settling is quasi-static: every preset settles alike, at coarse steps after a ramp
        still = q.garment_step(opts.resolution)
        settle = max(still, settle_step(opts.resolution))
        ramp = max(still, SETTLE_QUALITY.garment_step(opts.resolution))
    timeline = Timeline(body, still, settle_step=settle, ramp_step=ramp)
    landmarks = measure_body(body, timeline.pose)
    pattern = ease_layers(pattern, landmarks, layer_spacing(fabrics))  # an outfit's outer loops round the inner ones
    mesh = discretise(pattern, opts.resolution)
    loops = check_loops(pattern, landmarks)  # a loop too small for the body fails now, not at the sewing time-out
    placer = Placer(pattern, mesh, landmarks, InsideTest(timeline.pose, body.faces))
    x0 = placer()
    placed = [x0[mesh.panel_vertices(k)] for k in range(len(pattern.panels))]
    walls = limb_walls(pattern, landmarks, timeline.pose, placed) if opts.limb_walls else None
    garment = Garment(pattern, mesh, fabrics, merge_distance=max(0.3 * opts.resolution, 0.002))
    if walls is not None and walls.count:
        placer = replace(placer, walls=walls, margin=garment.thickness)
        x0 = walls.separate(x0, mesh, garment.thickness)
    x0 = placer.uncrossed(x0)
    collider = BodyCollider(timeline.collider_frames, body.faces, margin=body_margin(garment.thickness))
    timeline.follow_collider(collider.margin, collider.sure)
    panel_layer = garment_of_vertex(pattern, np.arange(len(pattern.panels))) if pattern.pieces else None
    contacts = ContactPipeline(collider, timeline, thickness=garment.thickness, friction=garment.friction,
                               self_collision=opts.self_collision, panel_layer=panel_layer)
    d = Dressing(opts, garment, timeline, contacts, integ, q, walls=walls, placer=placer, on_frame=on_frame, sink=sink,
                 progress=progress)
    return d, loops, x0


@dataclass(frozen=True)
class Placer:
    """Where panels start on the body's rest pose (:func:`~tailor.placement.place_panels`), the legs'
    panels kept to their side of the limb walls: all of them (``placer()``), or one garment of an
    outfit dressed over the inner ones as they lie at ``x`` (``placer(x, garment)``)."""

    pattern: object
    mesh: object
    landmarks: dict
    inside: object
    walls: object = None
    margin: float = 0.0

    def __call__(self, x=None, garment: int | None = None) -> np.ndarray:
        out = place_panels(self.pattern, self.mesh, self.landmarks, inside=self.inside, garment=garment, x=x)
        return out if self.walls is None else self.walls.separate(out, self.mesh, self.margin)

    def uncrossed(self, x) -> np.ndarray:
        """``x`` with the later of each two panels still placed through each other (after the limb
        walls parted the legs) placed again clear of the cloth placed before it, as an outer
        garment's panels are (``place_panels(…, again=…)``); ``x`` itself when none cross.

        Panels rolled round landmarks at different heights can meet there: on MakeHuman's man, whose
        waist is 19 cm under his hips, the front legs' tops (rolled round the thighs and widened to
        clear the hips) came in through each other and through the waistband at the centre front,
        and sewing them stretched a waistband triangle tenfold."""
        crossings = edge_crossings(x, self.mesh.faces)
        a, b = self.mesh.vertex_panel[crossings[:, 0]], self.mesh.face_panel[crossings[:, 2]]
        again = sorted(set(np.maximum(a, b)[a != b].tolist()))
        if not again:
            return x
        out = place_panels(self.pattern, self.mesh, self.landmarks, inside=self.inside, x=x, again=again)
        return out if self.walls is None else self.walls.separate(out, self.mesh, self.margin)


def _garments(pattern, mesh) -> dict | None:
    """An outfit's section per garment for the report (None for a single garment)."""
    if not pattern.pieces:
        return None
    count = len(pattern.pieces)
    vertices = np.bincount(garment_of_vertex(pattern, mesh.vertex_panel), minlength=count)
    faces = np.bincount(garment_of_vertex(pattern, mesh.face_panel), minlength=count)
    return {piece.name: {"layer": piece.layer,
                         "panels": [p.name for p in pattern.panels[piece.first:piece.first + piece.count]],
                         "vertices": int(vertices[k]), "faces": int(faces[k]),
                         "placement_clearance_added_m": round(piece.clearance, 6),
                         "loops_eased_across": round(piece.ease, 4), "placement_raised_m": round(piece.rise, 6)}
            for k, piece in enumerate(pattern.pieces)}


def _placement_crossings(x0, mesh, pattern) -> int:
    """Edges of the placed, unsewn panels that pass through a panel's triangle (0: placement starts
    no panel through another); logged as a warning when there are any."""
    crossings = edge_crossings(x0, mesh.faces)
    if len(crossings):
        panels = sorted({pattern.panels[p].name for p in mesh.vertex_panel[crossings[:, :2].ravel()]})
        log.warning("%s: %d edges of the placed panels pass through other panels (%s) before sewing; "
                    "check their placements", pattern.source, len(crossings), ", ".join(panels))
    return int(len(crossings))


def _header(d: Dressing, pattern, body, loops, opts: DrapeOptions) -> DrapeReport:
    """The report's inputs and derived parameters, known before the simulation starts."""
    g, q = d.garment, d.quality
    unwelded = g.unwelded
    walls = d.walls
    return DrapeReport(
        vertices=int(g.mesh.vertex_count), faces=int(g.mesh.face_count), resolution_m=opts.resolution, fps=opts.fps,
        integrator=opts.integrator, time_step_eq24_s=unwelded.time_step, seam_pairs=len(g.sewing.pairs),
        loops={lp.landmark: {"panels": list(lp.panels), "length_cm": round(lp.length * 100, 1),
                             "body_cm": round(lp.girth * 100, 1), "ease_cm": round(lp.ease * 100, 1)} for lp in loops},
        fabrics={p.name: g.fabrics[i].name for i, p in enumerate(pattern.panels)},
        panels={p.name: {"grain_deg": round(math.degrees(p.grain), 6),
                         "wearable_stretch_pct": round(g.fabrics[i].wearable_stretch * 100, 6)}
                for i, p in enumerate(pattern.panels)},
        body={**body.report, "name": body.name, "fps": body.fps, "frames": body.frame_count},
        params={p.name: unwelded.params[i].as_dict() for i, p in enumerate(pattern.panels)},
        quality={"name": q.name, "max_step_s": q.step, "solver_tolerance": q.tolerance},
        active={"bending": unwelded.has_bending, "air": True, "wind": opts.wind is not None, "body_collision": True,
                "self_collision": opts.self_collision,
                "limb_walls": [p.name for i, p in enumerate(pattern.panels) if walls is not None and walls.panel[i] >= 0],
                **({"cuts": len(opts.cuts), "tearing": opts.tear} if opts.cuts or opts.tear else {})},
        skipped=[reason for cond, reason in (
            (not unwelded.has_bending, "bending (every fabric has bending number 0)"),
            (opts.self_collision == "off", "self-collision (--self-collision off)"),
            (True, "body triangles farther than the contact margin from the cloth (FCL broad phase)"),
        ) if cond])


def _close(report: DrapeReport, d: Dressing, t_start: float) -> None:
    """The report's totals once the last frame is out."""
    counters = d.integrator.counters
    report.out_of_layer_per_frame = d.out_of_layer if d.garment.pattern.pieces and not d.topology else None
    pen = report.max_penetration_m_per_frame
    report.max_penetration_m = max(pen) if pen else 0.0
    report.wall_s = time.perf_counter() - t_start
    report.steps = d.stepper.steps
    report.cg_iterations = counters.iterations
    report.halved_steps = {**counters.halved_steps(), "overstretched_by_contacts": d.stepper.retried}
    report.body_bvh_queries = d.contacts.body.queries
    report.max_contact_correction_m = d.contacts.deepest
    report.vertices_rescued_from_inside_body = d.contacts.rescued
    report.welded_vertices = int(d.garment.model.vertex_count)
    report.self_collision = d.contacts.self_report()
    tearing = d.garment.tearing_report(d.timeline.motion_start)
    if tearing is not None:
        report.tearing = {**tearing, "topology_changes": len(d.topology)}
