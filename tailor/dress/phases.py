"""The phases of a drape (Carignan §3–4), each short and testable alone on a :class:`Dressing`.

1. :func:`sew` — body still, gravity off, seaming forces (Eq. 15) pull the placed panels together
   and pairs merge (Eq. 16–18) until every seam is closed, or a time-out raises
   :class:`~tailor.errors.SimulationError` naming the widest open seam; the panels keep each other
   out (self-collision) except along the open seams, and the cloth's crossings through itself are
   untangled every frame (:meth:`~tailor.contact.ContactPipeline.untangle`), as in every phase;
2. :func:`settle` — gravity on, attachments hold (Eq. 19–20), the garment comes to rest;
3. :func:`transition` — a body dressed in its neutral pose moves into its motion's first frame;
4. :func:`animate` — the body moves; one frame every 1/fps s, frame 0 being the dressed garment.

Each returns the state it ends with and its :class:`~.report.PhaseReport`.
"""

from __future__ import annotations

import logging
import math
import time
from functools import partial

import numpy as np

from ..constraints import Gather, HeightHold, LimbWallContact
from ..errors import SimulationError, SimulationUnstable
from ..integrators import SolverSettings
from ..outfit import garment_of_vertex, out_of_order, tuck_targets
from ..sim import Guard, Stepper, max_stretch, most_stretched
from ..topology import boundary_edges
from .options import (BLOCKED_OVER, FREE_SEW_STEP, MIN_STRAGGLERS, MOTION, MOTION_MAX_STRETCH, MOTION_STRETCH_GROWTH, REST_FRAMES, REST_SPEED, ROUTE_AFTER,
                      ROUTE_BEYOND, SETTLING, SEWING, SLEEP_REACH, STRAGGLER_REACH, STRAGGLERS, TRANSITION, TUCK_BELOW, TUCK_GATHER_TIME,
                      TUCK_ROW, WELD_BATCH, DrapeOptions, PhaseSettings)
from .report import DrapeFrame, DrapeProgress, PhaseReport

__all__ = ["Dressing", "sew", "settle", "transition", "animate", "rms_speed"]

log = logging.getLogger(__name__)


class Dressing:
    """One drape in progress: the garment, the body's timeline, the contacts and the step loop.

    It owns the frames produced so far and the settings of the current phase; the phases below
    drive it.
    """

    def __init__(self, options: DrapeOptions, garment, timeline, contacts, integrator, quality, *, walls=None,
                 placer=None, on_frame=None, sink=None, progress=None):
        self.options, self.garment, self.timeline, self.contacts = options, garment, timeline, contacts
        self.walls, self.attachments = walls, None
        self.placer = placer  # ``placer(x, garment)``: an outfit's garment dressed over the inner ones (dress.Placer)
        self.held_heights = None  # (mesh vertices, heights [m], under, ceilings [m]) of the attachments while sewing
        self.gathering = None  # (mesh vertices, start, target, t0 [s]) of a tuck's gather while the band sews
        self.integrator, self.quality = integrator, quality
        self.stepper = Stepper(integrator, contacts=contacts)
        self.on_frame, self.sink, self.progress = on_frame, sink, progress
        self.phase: PhaseSettings = SEWING
        self.motion_limit = MOTION_MAX_STRETCH
        self.emitted = 0  # frames out so far
        self.frames: list = []  # kept only with options.keep_frames
        self.body_frames: list = []
        self.loads: list = []  # (body contact, attachment) forces per welded vertex [N] of each frame
        self.out_of_layer: list = []  # an outfit's vertices inside a garment they should be over, per frame
        self._layers = None  # (weld, garment of each mesh vertex, open edge of each) the counts use, per weld
        self.topology: list = []  # (first frame, mesh, weld) after each cut or tear
        self.first_topology = (garment.mesh, garment.weld)  # frame 0's
        self.constrain()

    def constrain(self) -> None:
        """The contacts' constraints for the garment's current numbering: limb walls, attachments
        (while sewing, their heights), a tuck's gather; and which cloth a tuck leaves out of the
        layer rule (:meth:`Garment.untucked`)."""
        g = self.garment
        walls = None
        if self.walls is not None and self.walls.count:
            walls = LimbWallContact(self.walls, g.mesh, g.weld, g.thickness, simulated=g.model.vertex_count)
        held = None
        if self.held_heights is not None:  # an outfit's garments waiting to sew are not held yet
            ids, heights, under, ceilings = self.held_heights
            live = g.live
            now, now_under = live[ids], live[under]
            held = HeightHold(ids[now], heights[now], g.weld, under[now_under], ceilings[now_under])
        gather = None
        if self.gathering is not None:
            gather = Gather(*self.gathering, TUCK_GATHER_TIME, g.weld)
        self.contacts.constrain(walls, self.attachments, held, gather)
        self.contacts.untucked(g.untucked() if self.phase.moving else None)
        self.contacts.hold_still(g.still)

    @property
    def frame_dt(self) -> float:
        return 1.0 / self.options.fps

    def enter(self, phase: PhaseSettings) -> None:
        """Settings of ``phase`` for the integrator, the contacts (their constraints too,
        :meth:`constrain`) and the step loop."""
        self.phase = phase
        wind = self.options.wind if phase.wind else None
        self.integrator.configure(SolverSettings(phase.tolerance or self.quality.tolerance, phase.max_stretch_change, wind))
        self.contacts.configure(phase.contact)
        self.constrain()
        guard = Guard(max_stretch=phase.max_stretch or self.motion_limit)
        self.stepper.configure(forces=self.garment.forces(wind), guard=guard)
        self.contacts.limit_rescues(guard.max_stretch)

    def advance(self, state, duration: float, *, rescue: bool = True):
        """Simulate ``duration`` s on the current model (then free vertices trapped in the body)."""
        self.garment.stiffen_near_pairs(state.x)
        if self.phase.moving:
            dt = self.timeline.moving_step(state, duration)
        else:
            dt = self.garment.sewing.step  # sewing: the plain implicit step, or a stage's longer one
            if self.phase.gravity:
                dt = self.timeline.settling_step(state.t) if self.phase.quasi_static else self.timeline.still_step
        state = self.stepper.advance(self.garment.model, state, duration, dt)
        if rescue:
            self.contacts.rescue(self.garment.model, state)
        return state

    def emit(self, state, body_x) -> None:
        """A frame out: to the caller's ``on_frame`` and ``sink``, and into the result if it keeps frames;
        an outfit's layer order counted on it."""
        g = self.garment
        x = g.frame(state)
        contact, attached = (a.astype(np.float32) for a in self.contacts.loads.take(len(state.x)))
        if self.on_frame is not None:
            self.on_frame(self.emitted, x, body_x)
        if self.sink is not None:
            self.sink(DrapeFrame(self.emitted, x, body_x, contact, attached, g.mesh, g.weld))
        if self.options.keep_frames:
            self.frames.append(x.copy())
            self.body_frames.append(body_x.copy())
            self.loads.append((contact, attached))
        if g.pattern.pieces:
            self.out_of_layer.append(self._out_of_layer(x, body_x))
        self.emitted += 1

    def _out_of_layer(self, x, body_x) -> int:
        """An outfit's vertices at ``x`` (mesh numbering) found inside a garment they should be over
        (:func:`~tailor.outfit.out_of_order`): not the cloth of a tucked top outside its tuck, nor the
        open edges once the seams are welded (found again only when the weld changes)."""
        g = self.garment
        if self._layers is None or self._layers[0] is not g.weld:
            weld = g.weld
            edge = np.zeros(int(weld.max()) + 1, bool)
            edge[boundary_edges(weld[g.mesh.faces]).ravel()] = True
            self._layers = (weld, garment_of_vertex(g.pattern, g.mesh.vertex_panel), edge[weld])
        weld, garment, edge = self._layers
        loose = g.untucked()
        loose = None if loose is None else loose[weld]  # the frames' (mesh) numbering
        return int(out_of_order(x, garment, body_x, self.timeline.body.faces, loose=loose, edge=edge, faces=g.mesh.faces).sum())

    def tell(self, done: int, total: int, state) -> None:
        if self.progress is not None:
            self.progress(DrapeProgress(self.phase.name, done, total, float(state.t), self.stepper.steps))

    def weld(self, state):
        """The merged pairs welded; contacts follow the new numbering; trapped vertices freed."""
        state = self.garment.rebuild(state)
        self.contacts.follow(self.garment.friction, state.x)
        self.constrain()
        self.contacts.rescue(self.garment.model, state)
        self.contacts.untangle(self.garment.model, state)  # a merge can fold a seam corner through its neighbour
        return state

    def change(self, state, due: list):
        """Due cuts, then tearing; on a change, the contacts, the integrator and the constraints follow."""
        state, inverse = self.garment.change(state, due, self.timeline.motion_start)
        if inverse is None:
            return state
        if self.attachments is not None:
            self.attachments = self.attachments.renumbered(inverse)
        self.contacts.follow(self.garment.friction, state.x)
        self.contacts.forget()
        self.constrain()
        self.integrator.reset()
        self.topology.append((self.emitted, self.garment.mesh, self.garment.weld.copy()))
        return state


def _widen_merging(sewing, t: float, options: DrapeOptions) -> None:
    """Late in sewing, Eq. 16's d grows: stragglers held apart by two seams at a corner (half the
    time-out), then the last few pairs caught on the body (:data:`~.options.STRAGGLERS`), after ¾ of
    it or as soon as every one of them stopped closing (GarmentCode's T-shirt at 2 cm: its last pair
    held 3–4 cm apart round the arm for 0.2 s while the pull stretched the cloth beside it 3 → 10×)."""
    if t >= 0.5 * options.sew_timeout:
        sewing.merge_distance = max(sewing.merge_distance, 0.6 * options.resolution)
    stragglers = max(MIN_STRAGGLERS, STRAGGLERS * int(sewing.active.sum()))
    if (t >= 0.75 * options.sew_timeout or sewing.all_stalled) and sewing.sewing_count <= stragglers:
        sewing.merge_distance = max(sewing.merge_distance, STRAGGLER_REACH * options.resolution)


def sew(d: Dressing, x0):
    """Phase 1: the placed panels at ``x0`` sewn, one frame at a time, welding what closed.

    An outfit sews in stages, innermost garment first, each given the whole ``sew_timeout``: the
    garments outside wait where they were placed while the one inside closes, so no garment is
    drawn in through another (:meth:`Garment.sew_stage`); each is then placed afresh over the sewn
    ones inside it (:func:`_dress_over`) and sews."""
    t0 = time.perf_counter()
    d.enter(SEWING)
    g, sewing = d.garment, d.garment.sewing
    state = g.model.state(x0)
    attached = g.attached
    if len(attached):
        under, ceilings = g.attached_ceilings(x0)
        d.held_heights = (attached, x0[attached, 2], under, ceilings)
        d.constrain()
        # the innermost garment's attached panels, held: their seams are stiffened only when near (an
        # outer band over an inner one is stretched by its seams as before: it needs the room the
        # simulated layers inside it take, docs/outfits.md)
        sewing.anchor(np.intersect1d(under, g.garment_vertices(0)))
    frames, total = 0, 0.0
    merge_distance = sewing.merge_distance
    plan = g.stage_plan()
    meet = partial(_clear_of_body, d)  # where pairs routed round the body meet
    for stage in plan:
        if len(plan) > 1:
            state = g.sew_stage(state, stage)
            if stage.dresses and stage.garment:
                state = _dress_over(d, state, stage.garment)
            state = g.sleep_far(state, stage.garment, SLEEP_REACH)
            sewing.merge_distance = merge_distance
            d.contacts.follow(g.friction, state.x)
            d.constrain()
        sewing.step = _sew_step(d, stage.garment)
        t, unwelded = 0.0, 0  # pairs merged since the last weld (held by their seam springs meanwhile)
        sewing.route_around(None)
        if d.placer is not None and sewing.block(g.frame(state), d.placer.inside, over=BLOCKED_OVER):  # over it from the start
            sewing.route_around(meet, beyond=ROUTE_BEYOND, stuck=False)
        while sewing.sewing_count and t < d.options.sew_timeout:
            state = _wake_near(d, _sew_frame(d, state), stage.garment)
            t += d.frame_dt
            frames += 1
            _widen_merging(sewing, t, d.options)
            if t >= ROUTE_AFTER * d.options.sew_timeout and not sewing.routes_stuck:  # stuck on the body
                sewing.route_around(meet, beyond=ROUTE_BEYOND)
            merged = sewing.close(g.frame(state))
            unwelded += merged
            if unwelded and (unwelded >= WELD_BATCH * len(sewing.pairs) or not merged or not sewing.sewing_count):
                state, unwelded = d.weld(state), 0
            else:  # panels closing in on each other cross between welds too (a skirt's top over a bodice's)
                d.contacts.untangle(g.model, state)
            if d.options.record_sewing:
                d.emit(state, d.timeline.pose)
            d.tell(len(sewing.pairs) - sewing.open_count, len(sewing.pairs), state)
        total += t
        if sewing.sewing_count:
            raise SimulationError(_open_seams(g, state, d.options.sew_timeout))
    sewing.route_around(None)
    sewing.step = None
    # where sewing ended tightest: a garment caught on the body shows there (the shipped dress's
    # armholes, cut 4 cm too shallow, ended 2.4–5.5× under an arm); so do held waistbands (2.3–5×)
    worst, at = most_stretched(g.model, state.x)
    return state, PhaseReport(total, time.perf_counter() - t0, frames,
                              {"max_gap_at_merge_m": sewing.max_gap_at_merge, "rebuilds": g.rebuilds, "max_triangle_stretch": worst,
                               "most_stretched_at_m": None if at is None else at.round(4).tolist()})


def _wake_near(d: Dressing, state, garment: int):
    """``state``, or, if the outfit's ``garment`` came near held cloth asleep out of the model
    (:meth:`Garment.wake_near`), that of the model with it back, the contacts following."""
    woken = d.garment.wake_near(state, garment, SLEEP_REACH)
    if woken is None:
        return state
    d.contacts.follow(d.garment.friction, woken.x)
    d.constrain()
    return woken


def _sew_step(d: Dressing, garment: int) -> float | None:
    """The step [s] a stage sewing ``garment`` takes: :data:`~.options.FREE_SEW_STEP` when it holds
    none of that garment's heights (an implicit drape only), else the plain one (None). An outfit's
    stage is judged by its own garment: a T-shirt over held trousers sews at the longer step, the
    trousers below it at the plain one."""
    if d.timeline.still_step is None:
        return None
    held = d.held_heights[0] if d.held_heights is not None else np.zeros(0, np.intp)
    return None if np.isin(held, d.garment.garment_vertices(garment)).any() else FREE_SEW_STEP


def _dress_over(d: Dressing, state, garment: int):
    """An outfit's ``garment`` placed afresh over the garments inside it, now sewn (their sewn
    shape is far tighter than their placement, which it waited outside of), before it sews; if it
    tucks them in, their cloth below its top edge is gathered onto the body (:func:`_gather`)."""
    if d.placer is None:
        return state
    g = d.garment
    ids = g.garment_vertices(garment)
    state = g.moved(state, ids, d.placer(g.frame(state), garment)[ids])
    d.contacts.forget()
    if g.pattern.pieces[garment].tucks:
        state = _gather(d, state, garment)
    return state


def _gather(d: Dressing, state, garment: int):
    """A tuck: the inner garments' cloth lower than :data:`~.options.TUCK_BELOW` above the top edge of
    ``garment`` (placed, about to sew) carried onto the body one thickness out over
    :data:`~.options.TUCK_GATHER_TIME` s and held there while ``garment`` sews (let go when settling
    attaches the outfit). Each row goes straight in at its height onto the hull of the body within
    its loop (:func:`~tailor.outfit.tuck_targets`): a top's hem drawn in round the hips as a hand
    tucks it, compressed along its loop, not folded."""
    g = d.garment
    x = g.frame(state)
    inner = np.flatnonzero(garment_of_vertex(g.pattern, g.mesh.vertex_panel) < garment)
    top = x[g.garment_vertices(garment), 2].max()
    low = inner[x[inner, 2] < top + TUCK_BELOW]
    if d.contacts.body is None or not len(low):
        return state
    found, target = tuck_targets(x[low], d.timeline.pose, d.contacts.body.faces, clearance=g.thickness, row=TUCK_ROW)
    low = low[found]
    g.tuck(low, garment)
    d.gathering = (low, x[low], target, float(state.t))
    state = g.rebuild(state)
    d.contacts.follow(g.friction, state.x)
    d.constrain()
    return state


def _clear_of_body(d: Dressing, points):
    """(ids, points moved out) of the ``points`` inside the still body: where seam pairs meet
    (:meth:`~tailor.seams.Sewing.route_around`), two thicknesses out."""
    body = d.contacts.body
    if body is None:
        return np.zeros(0, np.intp), np.zeros((0, 3))
    ids, _, _, out = body.push_out(points, d.timeline.pose, 0, clearance=2.0 * d.garment.thickness)
    return ids, out


def _sew_frame(d: Dressing, state):
    """One frame of sewing. An instability while seam pairs have stopped closing names the widest of
    them: a seam pulled at but unable to close, more than the step, is then the likely cause (a
    garment too small for the body: GarmentCode's T-shirt, drafted for 1.7 m, on MakeHuman's 2.06 m
    man stalled with its shoulder seams 18 cm open and tore a triangle 0.4 s later)."""
    try:
        return d.advance(state, d.frame_dt)
    except SimulationUnstable as exc:
        sewing = d.garment.sewing
        stalled = sewing.stalled & ~sewing.merged & sewing.active
        if not stalled.any():
            raise
        pattern, seam, gap, _ = _widest(d.garment, state, stalled)
        raise SimulationUnstable(f"{exc}; {pattern.source}: by then {int(stalled.sum())} seam vertex pairs had stopped closing "
                                 f"(widest gap {gap * 100:.1f} cm, pattern.stitches[{seam.index}]: {_side(seam.a)} to "
                                 f"{_side(seam.b)}): the garment may be too small for this body") from None


def _widest(garment, state, among):
    """(pattern, seam, gap [m], pair) of the widest open pair of the pairs ``among`` ((S,) bool)."""
    sewing, pattern = garment.sewing, garment.pattern
    gaps = np.where(among, sewing.gaps(garment.frame(state)), 0.0)
    w = int(np.argmax(gaps))
    return pattern, pattern.seams[sewing.seam[w]], float(gaps[w]), w


def _side(sd) -> str:
    return f"{sd.panel}" + (f" hole {sd.hole}" if sd.hole is not None else "") + f" edge {sd.edge}"


def _open_seams(garment, state, timeout: float) -> str:
    """The sewing time-out's message: the stitch with the widest open gap, and, if that pair had
    stopped closing, that more time will not close it (GarmentCode's pants, an 84 cm waistband, on
    MakeHuman's heavy woman, a 98 cm waist: 24 pairs held 28 cm apart)."""
    sewing = garment.sewing
    pattern, seam, gap, w = _widest(garment, state, ~sewing.merged & sewing.active)
    advice = ("they had stopped closing: the garment may be too small for this body, or check that stitch and the placements"
              if sewing.stalled[w] else "check that stitch and the placements, or allow more time (--sew-timeout)")
    return (f"{pattern.source}: pattern.stitches[{seam.index}]: {sewing.open_count} of {len(sewing.pairs)} seam vertex "
            f"pairs are still open after {timeout:g} s of sewing (widest gap {gap * 100:.1f} cm, on the stitch "
            f"{_side(seam.a)} to {_side(seam.b)}); {advice}")


def settle(d: Dressing, state):
    """Phase 2: gravity on, the attachments pinned, the garment comes to rest: for ``settle`` s at
    most, ending early once it is still (:data:`~.options.REST_SPEED`); stepped coarsely after its
    first :data:`~.options.SETTLE_RAMP` s (:meth:`~.timeline.Timeline.settling_step`)."""
    t0 = time.perf_counter()
    state, d.attachments = d.garment.attach(state, d.contacts.body, d.timeline.pose)
    d.timeline.start_settling(state.t)
    d.held_heights = d.gathering = None
    d.contacts.follow(d.garment.friction, state.x)
    d.enter(SETTLING)  # and the constraints of the new numbering (Dressing.enter)
    count, still, done = int(round(d.options.settle * d.options.fps)), 0, 0
    while done < count and still < REST_FRAMES:
        state = d.advance(state, d.frame_dt)
        d.contacts.untangle(d.garment.model, state)
        if d.options.record_sewing:
            d.emit(state, d.timeline.pose)
        done += 1
        speed = rms_speed(d.garment.model, state)
        log.debug("settling frame %d: rms speed %.4f m/s", done, speed)
        still = still + 1 if speed < REST_SPEED else 0
        d.tell(count if still >= REST_FRAMES else done, count, state)
    d.motion_limit = max(MOTION_MAX_STRETCH, MOTION_STRETCH_GROWTH * max_stretch(d.garment.model, state.x))
    return state, PhaseReport(done * d.frame_dt, time.perf_counter() - t0, done)


def rms_speed(model, state) -> float:
    """The garment's root-mean-square speed [m/s], weighted by mass: √(2·kinetic energy / mass)."""
    m = model.vertex_mass
    return float(np.sqrt((m * (state.v * state.v).sum(axis=1)).sum() / max(m.sum(), 1e-30)))


def transition(d: Dressing, state):
    """Phase 3: a body dressed in its neutral pose moves into the first frame of its motion."""
    t0 = time.perf_counter()
    d.timeline.start_transition(state.t)
    d.enter(TRANSITION)
    if not d.timeline.keys:
        return state, None
    count = int(math.ceil(d.timeline.transition_s * d.options.fps - 1e-9))
    for i in range(count):
        state = d.advance(state, d.frame_dt)
        d.contacts.untangle(d.garment.model, state)
        if d.options.record_sewing:
            d.emit(state, d.timeline.at(state.t)[0])
        d.tell(i + 1, count, state)
    return state, PhaseReport(count * d.frame_dt, time.perf_counter() - t0)


def animate(d: Dressing, state):
    """Phase 4: the body moves; ``frames`` frames, one every 1/fps s (frame 0: the dressed garment).

    With cuts or tearing the garment may change between steps: the frame's steps are taken one
    at a time (a crack runs on from step to step, with any integrator). Each frame's crossings of the
    cloth through itself are untangled before it is written. Returns (state, report, per-frame
    penetration [m], per-frame crossings left: edges through a triangle of the garment)."""
    t0 = time.perf_counter()
    opts, tl = d.options, d.timeline
    tl.start_motion(state.t)
    d.first_topology = (d.garment.mesh, d.garment.weld)
    d.enter(MOTION)
    due = list(opts.cuts)
    changing = bool(opts.cuts) or opts.tear
    if changing:  # the mesh may change: a TearableCloth owns it (and the weld) from here on
        d.garment.allow_changes(opts.tear)
    step = tl.motion_step
    sub = d.stepper.substeps(d.garment.model, d.frame_dt, step)[1]  # the steps of a frame (explicit: Eq. 24's)
    penetration, crossings, untangled = [], [], []
    for f in range(opts.frames):
        if f and not changing:
            state = d.advance(state, d.frame_dt)
        elif f:
            for _ in range(sub):
                state = d.change(d.advance(state, d.frame_dt / sub, rescue=False), due)
            d.contacts.rescue(d.garment.model, state)
        elif changing:
            state = d.change(state, due)
        found, left = d.contacts.untangle(d.garment.model, state)  # the cloth through itself, pushed back
        penetration.append(d.contacts.penetration(state.x, state.t))
        crossings.append(left)
        untangled.append(found - left)
        d.emit(state, tl.at(state.t)[0])
        d.tell(f + 1, opts.frames, state)
    used = tl.steps_used
    report = PhaseReport((opts.frames - 1) / opts.fps, time.perf_counter() - t0, opts.frames,
                         {"time_step_s": step, "time_step_still_s": tl.still_step, "body_max_speed_m_s": tl.max_speed,
                          "time_step_near_s": [min(used), max(used)] if used else None,
                         "untangled_per_frame": untangled})
    return state, report, penetration, crossings
