"""The interface every integrator implements, and what a step returns."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np

from ..collide.contacts import Contacts

__all__ = ["SolverSettings", "StepResult", "Counters", "Integrator", "IntegratorBase", "acceleration"]


@dataclass(frozen=True, slots=True)
class SolverSettings:
    """What a driver may set on an integrator between steps (:meth:`Integrator.configure`).

    Attributes
    ----------
    tolerance : float
        Relative CG residual of each implicit solve.
    max_stretch_change : float
        An implicit step stretching a triangle further than this in one step is taken as two
        halves (``inf``: never).
    wind : Wind or (3,) air velocity, optional
        The air the forces blow with; the implicit solve treats drag relative to it.
    """

    tolerance: float = 1e-5
    max_stretch_change: float = 0.3
    wind: object = None


@dataclass(slots=True)
class Counters:
    """What an integrator did over all its steps (the cost measures of the bench and report)."""

    steps: int = 0
    solves: int = 0
    iterations: int = 0  # CG iterations over all solves
    halvings: int = 0  # steps taken as halves because CG did not converge
    stretch_halvings: int = 0  # ... because a triangle would stretch too far in one step
    landing_halvings: int = 0  # ... because vertices were still landing on the body after every contact pass
    predicted: int = 0  # contacts added by the landing prediction
    released: int = 0  # held contacts the body would have had to pull on

    def halved_steps(self) -> dict:
        """Steps taken as two halves, by cause."""
        return {"unconverged": self.halvings, "overstretch": self.stretch_halvings, "landing": self.landing_halvings}


@dataclass(frozen=True, slots=True)
class StepResult:
    """One step: the new state, the normal impulse [N·s] the solve gave each vertex it held on the
    body ((N,), None if it held none; of a step taken as halves, the last half's at the whole
    step's rate, so that over the step it gives the force that holds the vertex now), the CG iterations it took, and ``support`` ((N, 3) [N·s],
    None if nothing held the cloth): the whole impulse, friction included, that the held body
    contacts and the pinned vertices' attachments gave the cloth during the step."""

    state: object
    impulses: np.ndarray | None = None
    iterations: int = 0
    support: np.ndarray | None = None


Forces = Callable[[object, object], np.ndarray]
Predict = Callable[..., Contacts | None]


class Integrator(Protocol):
    """``step(model, state, dt, forces, *, contacts, predict) -> StepResult``.

    ``forces(model, state)`` returns the total force [N], shape (N, 3). ``contacts`` are the body
    contacts to hold within the step (implicit only); ``predict(model, state, x_end, v_end, dt,
    held_ids) -> Contacts`` names the vertices the solved step would bring onto the body, to hold
    too. No integrator changes the model or the state it is given.
    """

    name: str
    explicit: bool
    counters: Counters
    settings: SolverSettings

    def configure(self, settings: SolverSettings) -> None: ...

    def reset(self) -> None: ...

    def step(self, model, state, dt: float, forces: Forces, *, contacts: Contacts | None = None,
             predict: Predict | None = None) -> StepResult: ...


class IntegratorBase:
    """Defaults of :class:`Integrator`: no settings, no history, counters."""

    name = "?"
    explicit = True

    def __init__(self):
        self.counters = Counters()
        self.settings = SolverSettings()

    def configure(self, settings: SolverSettings) -> None:
        """Settings for the steps to come (explicit integrators have no solver: the forces carry the wind)."""
        self.settings = settings

    def reset(self) -> None:
        """Forget any history (the vertices were renumbered, or moved from outside)."""


def acceleration(model, f):
    """f/m per vertex, zero at pinned vertices (infinite mass)."""
    a = f / model.vertex_mass[:, None]
    a[model.vertex_pinned] = 0.0
    return a


