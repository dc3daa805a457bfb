"""The time-stepping driver and its stability guard.

:func:`simulate` advances a :class:`~tailor.model.State` with an integrator, calls optional
``hooks(model, state, dt)`` after every step (collisions, seams and attachments plug in here),
checks the state, and yields one state per frame. It never writes files: the caller decides
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
from .integrators import Contacts, make_integrator

__all__ = ["Quality", "QUALITY", "Guard", "check_state", "simulate", "run", "max_stretch", "IMPLICIT_STEP", "held_impulse", "hold_contacts", "halved_steps"]

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


QUALITY = {
    "draft": Quality("draft", 0.04, 1.0, 1e-2),
    "normal": Quality("normal", 0.02, 0.5, 1e-2),
    "final": Quality("final", IMPLICIT_STEP, 0.25, 1e-5),
}
"""Presets by name. A loose CG tolerance costs no accuracy on a drape, where the folds set by the
step dominate the difference to ``final``, so draft and normal use 1e-2; ``final`` keeps 1e-5, the
garment tests' setting. Speeds against Blender's cloth: docs/measurements.md and
``benchmarks/compare_blender.py``."""


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
    """

    max_speed: float = 50.0
    max_stretch: float = 3.0
    strain_every: int = 50


def max_stretch(model, x) -> float:
    """Largest principal stretch of any triangle (1 = rest)."""
    return float(face_stretch(model, x).max(initial=1.0))


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
        stretch = face_stretch(model, state.x)
        s = float(stretch.max(initial=1.0))
        if s > guard.max_stretch:
            at = np.asarray(state.x)[np.asarray(model.faces)[int(np.argmax(stretch))]].mean(axis=0)
            raise SimulationUnstable(
                f"simulation unstable at {where}: a triangle at ({at[0]:.3f}, {at[1]:.3f}, {at[2]:.3f}) m is stretched "
                f"{s:.3g}× its rest size (limit {guard.max_stretch:g}×); {_remedy(integrator, dt)}"
            )


def simulate(model, state, *, duration: float, frame_rate: float = 25.0, integrator="symplectic", dt: float | None = None,
             hooks=(), forces=total_forces, guard: Guard = Guard(), progress=None):
    """Advance ``state`` for ``duration`` seconds, yielding ``(frame index, State)`` at each frame.

    Frame 0 is the initial state. Steps per frame are chosen so frames fall exactly on
    multiples of 1/frame_rate with a step no larger than ``dt`` (default: the model's Eq. 24
    step for explicit integrators — shortened every frame by the stiffening of the most
    stretched triangle — and :data:`IMPLICIT_STEP` for ``implicit``).

    Parameters
    ----------
    integrator : str or integrator object
        See :mod:`tailor.integrators`.
    hooks : sequence of callables ``hook(model, state, dt)``
        Applied in order after every step; they may modify ``state`` in place.
    forces : callable ``forces(model, state) -> (N, 3)``
    progress : callable ``progress(frame, frame_count, state)``, optional
    """
    integ = make_integrator(integrator) if isinstance(integrator, str) else integrator
    name = getattr(integ, "name", "?")
    adapt = dt is None and getattr(integ, "explicit", True)  # Eq. 24 step, kept stable as the cloth stretches
    if dt is None:
        dt = model.time_step if getattr(integ, "explicit", True) else min(IMPLICIT_STEP, 1.0 / frame_rate)
    if not (dt > 0 and math.isfinite(dt)):
        raise ValueError(f"time step must be positive, got {dt!r}")
    frame_dt = 1.0 / frame_rate
    substeps = max(1, math.ceil(frame_dt / dt - 1e-9))
    h = frame_dt / substeps
    frames = int(round(duration * frame_rate))
    check_state(model, state, step=0, dt=h, integrator=name, frame=0, guard=guard)
    yield 0, state
    step = 0
    for frame in range(1, frames + 1):
        for _ in range(substeps):
            state = integ.step(model, state, h, forces)
            for hook in hooks:
                hook(model, state, h)
            step += 1
            check_state(model, state, step=step, dt=h, integrator=name, frame=frame, guard=guard,
                        strain=step % guard.strain_every == 0)
        check_state(model, state, step=step, dt=h, integrator=name, frame=frame, guard=guard)
        if adapt and model.face_count:
            # Eq. 24 uses the rest stiffness; a Green-strain membrane stretched s times is stiffer,
            # its tangent modulus (3s² − 1)/2 times the rest one, so its waves are faster by the root
            s = max_stretch(model, state.x)
            substeps = max(1, math.ceil(frame_dt * math.sqrt(max(1.0, 0.5 * (3.0 * s * s - 1.0))) / dt - 1e-9))
            h = frame_dt / substeps
        if progress is not None:
            progress(frame, frames, state)
        yield frame, state


def run(model, state, **kwargs):
    """Run :func:`simulate` to the end and return the final State."""
    final = state
    for _, final in simulate(model, state, **kwargs):  # noqa: B007 - the loop keeps the last state
        continue
    return final


def halved_steps(integ) -> dict:
    """How often an implicit integrator took a step as two halves, by cause (zeros for explicit ones)."""
    return {"unconverged": int(getattr(integ, "halvings", 0)), "overstretch": int(getattr(integ, "stretch_halvings", 0))}


def held_impulse(integ, model):
    """(N,) normal impulse [N·s] the implicit solve gave the contacts it held (None if it held none)."""
    ids = getattr(integ, "contact_ids", None)
    if ids is None or not len(ids) or integ.contact_vertex_count != model.vertex_count:
        return None
    out = np.zeros(model.vertex_count)
    out[ids] = integ.contact_impulse
    return out


def hold_contacts(integ, model, contact_set) -> None:
    """Hand body contacts (ids, normals, body normal velocity, stuck, body velocity, μ) to an implicit
    integrator for its next step."""
    if hasattr(integ, "contacts"):
        ids, normals, vn, stuck, vb, mu = contact_set
        integ.contacts = Contacts(ids, normals, vn, model.vertex_count, stick=stuck, body_velocity=vb, friction=mu)
