"""Time integrators behind one interface (:class:`Integrator`).

``integrator.step(model, state, dt, forces, *, contacts=None, predict=None) -> StepResult``;
``configure(SolverSettings)`` sets what a driver may change between steps, ``reset()`` forgets
history after the vertices were renumbered. Pinned vertices are never accelerated (infinite mass);
they move with whatever velocity they have (zero for a fixed pin, a body's velocity for an
attachment). No integrator changes the model or the state it is given.

* ``forward`` — forward Euler, Walker Eq. 4–5: velocity and position from the old state.
* ``symplectic`` — symplectic (semi-implicit) Euler, Walker Eq. 4 and 6: position from the new
  velocity. Conserves a modified energy; the workhorse explicit method.
* ``verlet`` — position Verlet, Walker Eq. 7–8, bootstrapped by one symplectic Euler step because
  it needs x(t − Δt); velocity by the central difference of Eq. 8.
* ``rk4`` — classical fourth-order Runge–Kutta on (x, v), Bottino et al. §4.
* ``implicit`` — linearised backward Euler (Baraff & Witkin 1998), body contacts held in the
  solve (:mod:`.implicit`).
"""

from __future__ import annotations

from ..collide.contacts import Contacts
from .base import Counters, Integrator, IntegratorBase, SolverSettings, StepResult
from .explicit import RK4, ForwardEuler, SymplecticEuler, Verlet
from .implicit import ImplicitEuler

__all__ = ["INTEGRATORS", "make_integrator", "Integrator", "IntegratorBase", "SolverSettings", "StepResult", "Counters",
           "ForwardEuler", "SymplecticEuler", "Verlet", "RK4", "ImplicitEuler", "Contacts"]

INTEGRATORS = {
    "forward": ForwardEuler,
    "symplectic": SymplecticEuler,
    "verlet": Verlet,
    "rk4": RK4,
    "implicit": ImplicitEuler,
}
"""Integrator classes by name."""


def make_integrator(name: str) -> Integrator:
    """A fresh integrator called ``name`` (one of :data:`INTEGRATORS`)."""
    try:
        return INTEGRATORS[name]()
    except KeyError:
        raise ValueError(f"unknown integrator {name!r}; choose one of {', '.join(INTEGRATORS)}") from None
