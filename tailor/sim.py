"""The time-stepping driver and its stability guard.

:class:`Stepper` advances a :class:`~tailor.model.State` with an integrator, runs the contact
pipeline and optional ``hooks(model, state, dt)`` after every step, and checks the state;
:func:`simulate` yields one state per frame. It never writes files: the caller decides
what to do with frames. A state that goes non-finite, too fast, or stretched beyond anything
cloth survives raises :class:`~tailor.errors.SimulationUnstable` naming the time, the frame,
the step and a remedy — so no NaN or exploded frame ever leaves the simulator.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .errors import SimulationUnstable
from .forces import total_forces
from .forces.membrane import face_stretch
from .integrators import make_integrator

__all__ = ["Quality", "QUALITY", "DEFAULT_QUALITY", "Guard", "check_state", "simulate", "run", "max_stretch", "IMPLICIT_STEP", "Stepper", "quality"]

IMPLICIT_STEP = 0.01
"""Default step of the implicit integrator [s]: stable far beyond Eq. 24, four steps per 25 fps frame."""

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class Quality:
    """A speed/accuracy preset of the implicit integrator, chosen from the measured frontier (``tailor bench``).

    Attributes
    ----------
    step : float
        Largest time step [s].
    step_per_resolution : float
        Largest time step per metre of mesh resolution [s/m] on garments (finer meshes step smaller).
    tolerance : float
        Relative CG residual of each implicit solve.
    """

    name: str
    step: float
    step_per_resolution: float
    tolerance: float

    def garment_step(self, resolution: float) -> float:
        """The largest step [s] on a garment meshed at ``resolution`` [m]."""
        return min(self.step, self.step_per_resolution * resolution)


QUALITY = {
    "draft": Quality("draft", 0.04, 1.0, 1e-2),
    "normal": Quality("normal", 0.02, 0.5, 1e-2),
    "final": Quality("final", IMPLICIT_STEP, 0.25, 1e-5),
}
"""Presets by name. A loose CG tolerance costs no accuracy on a drape, where the folds set by the
step dominate the difference to ``final``, so draft and normal use 1e-2; ``final`` keeps 1e-5, the
garment tests' setting. Speeds against Blender's cloth: docs/measurements.md and
``benchmarks/compare_blender.py``."""


DEFAULT_QUALITY = "draft"
"""The preset garments drape at unless asked otherwise: the knee of the garment frontier, measured on
the T-shirt, skirt, trousers and dress walking at 2 cm against how far ``final`` lands from itself
(``benchmarks/garment_presets.py --floor``; the README's "Speed versus accuracy": within a few mm of
that on the T-shirt, the skirt and the dress, about 9 mm beyond it on the trousers, where ``normal``
is no nearer)."""


def quality(name: str) -> Quality:
    """The preset called ``name``; ValueError naming the choices otherwise."""
    try:
        return QUALITY[name]
    except KeyError:
        raise ValueError(f"unknown quality {name!r}; choose one of {', '.join(QUALITY)}") from None


@dataclass(frozen=True, slots=True)
class Guard:
    """Bounds beyond which a state is declared unstable.

    Attributes
    ----------
    max_speed : float
        [m/s]; no garment point moves faster than a few m/s, a walking body ~2 m/s.
    max_stretch : float
        Largest principal stretch of any triangle (1 = rest); woven cloth tears long before 3.
    strain_every : int
        Check strain every this many steps (speed and finiteness every step).
    retries : int
        A step that ends, after its contacts, with a triangle stretched beyond ``max_stretch`` is
        taken again from where it began as two half steps, up to this many times over (Δt/64 at
        most: a 256² sheet folding off the sphere at draft needs it);
        :class:`~tailor.errors.SimulationUnstable` only where the smallest did not help.
    """

    max_speed: float = 50.0
    max_stretch: float = 3.0
    strain_every: int = 50
    retries: int = 6


def max_stretch(model, x) -> float:
    """Largest principal stretch of any triangle (1 = rest)."""
    return float(face_stretch(model, x).max(initial=1.0))


def most_stretched(model, x) -> tuple:
    """(largest principal stretch of any triangle, that triangle's centroid (3,) [m], None without
    triangles): where a cloth is tightest."""
    stretch = face_stretch(model, x)
    if not len(stretch):
        return 1.0, None
    k = int(np.argmax(stretch))
    return float(max(stretch[k], 1.0)), np.asarray(x)[np.asarray(model.faces)[k]].mean(axis=0)


def _remedy(integrator: str, dt: float) -> str:
    tips = [f"a smaller time step (e.g. {dt / 4:.3g} s)"]
    if integrator != "implicit":
        tips.append("the implicit integrator")
    tips.append("a coarser resolution or a less stiff fabric")
    return "try " + ", ".join(tips[:-1]) + " or " + tips[-1]


def check_state(model, state, *, step: int, dt: float, integrator: str = "?", frame: int | None = None,
                guard: Guard = Guard(), strain: bool = True) -> None:
    """Raise :class:`SimulationUnstable` if ``state`` is non-finite, too fast or over-stretched."""
    where = f"t = {state.t:.4f} s" + (f" (frame {frame}, step {step}" if frame is not None else f" (step {step}") + f", Δt = {dt:.3g} s)"
    if not (np.isfinite(state.x).all() and np.isfinite(state.v).all()):
        raise SimulationUnstable(f"simulation unstable at {where}: positions became NaN or infinite; {_remedy(integrator, dt)}")
    speed = math.sqrt(float(np.einsum("ij,ij->i", state.v, state.v).max(initial=0.0)))
    if speed > guard.max_speed:
        raise SimulationUnstable(
            f"simulation unstable at {where}: a vertex moves at {speed:.3g} m/s (limit {guard.max_speed:g}); {_remedy(integrator, dt)}"
        )
    if strain and model.face_count:
        s, at = most_stretched(model, state.x)
        if s > guard.max_stretch:
            raise SimulationUnstable(
                f"simulation unstable at {where}: a triangle at ({at[0]:.3f}, {at[1]:.3f}, {at[2]:.3f}) m is stretched "
                f"{s:.3g}× its rest size (limit {guard.max_stretch:g}×); {_remedy(integrator, dt)}"
            )


class Stepper:
    """Advances a cloth by an integrator's steps, every contact after each, the guard watching.

    The one step loop of :func:`simulate`, :func:`tailor.scenes.run_scene`,
    :func:`tailor.tearing.simulate_tearing` and :func:`tailor.dress.drape`: a step holds the body contacts
    the last response left resting (implicit integrators), the :class:`~tailor.contact.ContactPipeline`
    responds, then the ``hooks(model, state, dt)`` run; :meth:`advance` covers a span exactly.

    Parameters
    ----------
    integrator : Integrator
    forces : callable ``forces(model, state) -> (N, 3)``
    contacts : ContactPipeline, optional
    hooks : sequence of callables ``hook(model, state, dt)``, run after the contacts
    guard : Guard
    """

    def __init__(self, integrator, *, forces=total_forces, contacts=None, hooks=(), guard: Guard = Guard()):
        self.integrator = integrator
        self.forces = forces
        self.contacts = contacts
        self.hooks = tuple(hooks)
        self.guard = guard
        self.steps = 0
        self.retried = 0  # steps undone and taken again in halves (Guard.retries)

    def configure(self, *, forces=None, guard: Guard | None = None) -> None:
        """The forces and the guard of the steps to come (a new phase, or a renumbered cloth)."""
        if forces is not None:
            self.forces = forces
        if guard is not None:
            self.guard = guard

    def step(self, model, state, h: float):
        """One step of ``h`` and every response after it; the new state (taken again in halves
        where it overstretched: :meth:`_step`)."""
        return self._step(model, state, h, 0)[0]

    def _step(self, model, state, h: float, depth: int):
        """(new state, whether it ends overstretched). A step whose end, after the contact responses,
        stretches a triangle beyond the guard's ``max_stretch`` (a flap swung through the response
        of a fold, a corner caught between two contacts), or whose responses stop it as unstable (the
        self-contact's: part of the cloth too fast for its candidates), is undone, the contacts restored to what
        they knew before it (:meth:`ContactPipeline.checkpoint`), and taken as two half steps, up to
        ``guard.retries`` deep: Baraff & Witkin's adaptive step size (1998) applied to the whole
        step, contacts included, where :class:`~tailor.integrators.ImplicitEuler` applies it to its
        solve. The hooks run on the steps kept."""
        pipe = self.contacts
        retry = depth < self.guard.retries and model.face_count > 0
        mark = pipe.checkpoint() if retry and pipe is not None else None
        try:
            new = self._take(model, state, h)
        except SimulationUnstable:  # a response's own guard (cloth moving too fast for its contacts)
            if not retry:
                raise
            new = None
        over = new is None or (model.face_count > 0 and max_stretch(model, new.x) > self.guard.max_stretch)
        if over and retry:
            self.retried += 1
            if pipe is not None:
                pipe.restore(mark, state.x)
            self.integrator.reset()
            half, over = self._step(model, state, 0.5 * h, depth + 1)
            return (half, over) if over else self._step(model, half, 0.5 * h, depth + 1)
        for hook in self.hooks:
            hook(model, new, h)
        self.steps += 1
        return new, over

    def _take(self, model, state, h: float):
        """The integrator's step from ``state`` (left as it was) and the contact responses on its end."""
        pipe = self.contacts
        if pipe is None:
            return self.integrator.step(model, state, h, self.forces).state
        result = self.integrator.step(model, state, h, self.forces, contacts=pipe.hold(model), predict=pipe.predict)
        pipe.respond(model, result.state, h, result.impulses, result.support)
        return result.state

    def advance(self, model, state, duration: float, dt: float | None = None, *, frame: int | None = None):
        """``state`` advanced by ``duration`` s in equal steps of at most ``dt`` (default: the
        integrator's, :meth:`time_step`); the time of the result is exactly the start plus ``duration``."""
        h, substeps = self.substeps(model, duration, dt)
        name = self.integrator.name
        start = state.t
        check_state(model, state, step=0, dt=h, integrator=name, frame=frame, guard=self.guard)
        for k in range(1, substeps + 1):
            state, over = self._step(model, state, h, 0)
            check_state(model, state, step=k, dt=h, integrator=name, frame=frame, guard=self.guard,
                        strain=over or k % self.guard.strain_every == 0)
        check_state(model, state, step=substeps, dt=h, integrator=name, frame=frame, guard=self.guard)
        state.t = start + duration
        return state

    def time_step(self, model, span: float) -> float:
        """The step when none is asked for: Eq. 24's for explicit integrators, else :data:`IMPLICIT_STEP`."""
        return model.time_step if self.integrator.explicit else min(IMPLICIT_STEP, span)

    def substeps(self, model, span: float, dt: float | None):
        """(step, count): equal steps of at most ``dt`` covering ``span``."""
        dt = self.time_step(model, span) if dt is None else dt
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"time step must be positive, got {dt!r}")
        count = max(1, math.ceil(span / dt - 1e-9))
        return span / count, count


def simulate(model, state, *, duration: float, frame_rate: float = 25.0, integrator="symplectic", dt: float | None = None,
             hooks=(), forces=total_forces, guard: Guard = Guard(), progress=None, contacts=None):
    """Advance ``state`` for ``duration`` seconds, yielding ``(frame index, State)`` at each frame.

    Frame 0 is the initial state. Steps per frame are chosen so frames fall exactly on
    multiples of 1/frame_rate with a step no larger than ``dt`` (default: the model's Eq. 24
    step for explicit integrators — shortened every frame by the stiffening of the most
    stretched triangle — and :data:`IMPLICIT_STEP` for ``implicit``).

    Parameters
    ----------
    integrator : str or Integrator
        See :mod:`tailor.integrators`.
    hooks : sequence of callables ``hook(model, state, dt)``
        Applied in order after every step (after ``contacts``); they may modify ``state`` in place.
    forces : callable ``forces(model, state) -> (N, 3)``
    progress : callable ``progress(frame, frame_count, state)``, optional
    contacts : :class:`~tailor.contact.ContactPipeline`, optional
    """
    integ = make_integrator(integrator) if isinstance(integrator, str) else integrator
    stepper = Stepper(integ, forces=forces, contacts=contacts, hooks=hooks, guard=guard)
    frame_dt = 1.0 / frame_rate
    adapt = dt is None and integ.explicit  # Eq. 24 step, kept stable as the cloth stretches
    h, _ = stepper.substeps(model, frame_dt, dt)
    check_state(model, state, step=0, dt=h, integrator=integ.name, frame=0, guard=guard)
    yield 0, state
    frames = int(round(duration * frame_rate))
    for frame in range(1, frames + 1):
        state = stepper.advance(model, state, frame_dt, h, frame=frame)
        if adapt and model.face_count:
            # Eq. 24 uses the rest stiffness; a Green-strain membrane stretched s times is stiffer,
            # its tangent modulus (3s² − 1)/2 times the rest one, so its waves are faster by the root
            s = max_stretch(model, state.x)
            h = frame_dt / max(1, math.ceil(frame_dt * math.sqrt(max(1.0, 0.5 * (3.0 * s * s - 1.0))) / model.time_step - 1e-9))
        if progress is not None:
            progress(frame, frames, state)
        yield frame, state


def run(model, state, **kwargs):
    """Run :func:`simulate` to the end and return the final State."""
    final = state
    for _, final in simulate(model, state, **kwargs):  # noqa: B007 - the loop keeps the last state
        continue
    return final
