"""Explicit integrators (Walker Eq. 4–8; Bottino et al. §4): stable below Eq. 24's step only.

They hold no body contacts within the step (the response after it does the work) and ignore
``contacts`` and ``predict``.
"""

from __future__ import annotations

from ..model import State
from .base import IntegratorBase, StepResult, acceleration

__all__ = ["ForwardEuler", "SymplecticEuler", "Verlet", "RK4"]


class ForwardEuler(IntegratorBase):
    """Walker Eq. 4–5: velocity and position from the old state."""

    name = "forward"

    def step(self, model, state, dt, forces, *, contacts=None, predict=None) -> StepResult:
        a = acceleration(model, forces(model, state))
        self.counters.steps += 1
        return StepResult(State(state.x + dt * state.v, state.v + dt * a, state.t + dt))


class SymplecticEuler(IntegratorBase):
    """Walker Eq. 4 and 6: position from the new velocity (conserves a modified energy)."""

    name = "symplectic"

    def step(self, model, state, dt, forces, *, contacts=None, predict=None) -> StepResult:
        v = state.v + dt * acceleration(model, forces(model, state))
        self.counters.steps += 1
        return StepResult(State(state.x + dt * v, v, state.t + dt))


class Verlet(IntegratorBase):
    """Walker Eq. 7–8; the first step (no x(t − Δt) yet) is a symplectic Euler step.

    The velocity lives in x(t) − x(t − Δt). A vertex whose position or velocity was changed after
    the last step (a contact response, an attachment) continues from x(t) − Δt·v(t) instead, so
    the change holds: a contact that stopped a vertex's approach is not undone by its history.
    """

    name = "verlet"

    def __init__(self):
        super().__init__()
        self._previous = None  # (x(t − Δt), dt, t, x and v as returned) of the state last returned

    def reset(self) -> None:
        """Forget x(t − Δt) (after the vertices were renumbered or moved from outside)."""
        self._previous = None

    def _history(self, state, dt):
        """x(t − Δt) to continue from, or None to start again."""
        prev = self._previous
        # the history continues only from the state this returned (its time may have been rounded to a frame's)
        if prev is None or abs(prev[1] - dt) > 1e-9 * dt or abs(prev[2] - state.t) > 1e-6 * dt or len(prev[0]) != len(state.x):
            return None
        x_prev = prev[0].copy()
        changed = (state.x != prev[3]).any(axis=1) | (state.v != prev[4]).any(axis=1)
        x_prev[changed] = state.x[changed] - dt * state.v[changed]
        return x_prev

    def step(self, model, state, dt, forces, *, contacts=None, predict=None) -> StepResult:
        a = acceleration(model, forces(model, state))
        x_prev = self._history(state, dt)
        if x_prev is None:
            v = state.v + dt * a
            x = state.x + dt * v
        else:
            x = 2.0 * state.x - x_prev + a * dt * dt
            x[model.vertex_pinned] = state.x[model.vertex_pinned] + dt * state.v[model.vertex_pinned]
            v = (x - x_prev) / (2.0 * dt)
            v[model.vertex_pinned] = state.v[model.vertex_pinned]
        self._previous = (state.x.copy(), dt, state.t + dt, x.copy(), v.copy())
        self.counters.steps += 1
        return StepResult(State(x, v, state.t + dt))


class RK4(IntegratorBase):
    """Classical Runge–Kutta 4 on the first-order system (ẋ = v, v̇ = f/m)."""

    name = "rk4"

    def step(self, model, state, dt, forces, *, contacts=None, predict=None) -> StepResult:
        def deriv(x, v, t):
            return v, acceleration(model, forces(model, State(x, v, t)))

        x, v, t = state.x, state.v, state.t
        k1x, k1v = deriv(x, v, t)
        k2x, k2v = deriv(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v, t + 0.5 * dt)
        k3x, k3v = deriv(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v, t + 0.5 * dt)
        k4x, k4v = deriv(x + dt * k3x, v + dt * k3v, t + dt)
        x1 = x + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        v1 = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        self.counters.steps += 1
        return StepResult(State(x1, v1, t + dt))
