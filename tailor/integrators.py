"""Time integrators behind one interface: ``integrator.step(model, state, dt, forces) -> State``.

``forces(model, state)`` returns the total force [N], shape (N, 3). Pinned vertices are never
accelerated (infinite mass); they move with whatever velocity they have (zero for a fixed pin, a
body's velocity for an attachment). No integrator changes the model or the state it is given.

* ``forward`` — forward Euler, Walker Eq. 4–5: velocity and position from the old state.
* ``symplectic`` — symplectic (semi-implicit) Euler, Walker Eq. 4 and 6: position from the new
  velocity. Conserves a modified energy; the workhorse explicit method.
* ``verlet`` — position Verlet, Walker Eq. 7–8, bootstrapped by one symplectic Euler step because
  it needs x(t − Δt); velocity by the central difference of Eq. 8.
* ``rk4`` — classical fourth-order Runge–Kutta on (x, v), Bottino et al. §4.
* ``implicit`` — linearised backward Euler (Baraff & Witkin 1998): one Newton step of
  (M + Δt·C + Δt²·K)·Δv = Δt·(f − Δt·K·v), solved by block-Jacobi preconditioned conjugate
  gradients on 3×3 vertex blocks (compiled, threaded), with body contacts held in the solve. Unconditionally stable for the linear part: it takes steps many times Eq. 24's.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .errors import SimulationUnstable
from .forces.external import air_damping
from .forces.jacobian import SparsePattern, implicit_blocks
from .forces.kernels import block_pcg, bsr_rows, inverse_3x3
from .forces.membrane import face_stretch
from .model import State

__all__ = ["INTEGRATORS", "make_integrator", "ForwardEuler", "SymplecticEuler", "Verlet", "RK4", "ImplicitEuler", "Contacts"]


log = logging.getLogger(__name__)


def _acceleration(model, f):
    a = f / model.vertex_mass[:, None]
    a[model.vertex_pinned] = 0.0
    return a


class ForwardEuler:
    """Walker Eq. 4–5."""

    name = "forward"
    explicit = True

    def step(self, model, state, dt, forces):
        a = _acceleration(model, forces(model, state))
        return State(state.x + dt * state.v, state.v + dt * a, state.t + dt)


class SymplecticEuler:
    """Walker Eq. 4 and 6."""

    name = "symplectic"
    explicit = True

    def step(self, model, state, dt, forces):
        v = state.v + dt * _acceleration(model, forces(model, state))
        return State(state.x + dt * v, v, state.t + dt)


class Verlet:
    """Walker Eq. 7–8; the first step (no x(t − Δt) yet) is a symplectic Euler step."""

    name = "verlet"
    explicit = True

    def __init__(self):
        self._previous = None  # (positions at t − Δt, dt, t) of the state last returned

    def reset(self):
        """Forget the history (after positions were changed from outside)."""
        self._previous = None

    def step(self, model, state, dt, forces):
        a = _acceleration(model, forces(model, state))
        prev = self._previous
        if prev is None or prev[1] != dt or prev[2] != state.t:
            v = state.v + dt * a
            x = state.x + dt * v
        else:
            x = 2.0 * state.x - prev[0] + a * dt * dt
            x[model.vertex_pinned] = state.x[model.vertex_pinned] + dt * state.v[model.vertex_pinned]
            v = (x - prev[0]) / (2.0 * dt)
            v[model.vertex_pinned] = state.v[model.vertex_pinned]
        self._previous = (state.x.copy(), dt, state.t + dt)
        return State(x, v, state.t + dt)


class RK4:
    """Classical Runge–Kutta 4 on the first-order system (ẋ = v, v̇ = f/m)."""

    name = "rk4"
    explicit = True

    def step(self, model, state, dt, forces):
        def deriv(x, v, t):
            return v, _acceleration(model, forces(model, State(x, v, t)))

        x, v, t = state.x, state.v, state.t
        k1x, k1v = deriv(x, v, t)
        k2x, k2v = deriv(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v, t + 0.5 * dt)
        k3x, k3v = deriv(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v, t + 0.5 * dt)
        k4x, k4v = deriv(x + dt * k3x, v + dt * k3v, t + dt)
        x1 = x + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
        v1 = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        return State(x1, v1, t + dt)


@dataclass(frozen=True, slots=True)
class Contacts:
    """Body contacts to hold during the next implicit step (Baraff & Witkin's constraints).

    Vertex ``ids[k]`` ends the step with velocity ``normal_velocity[k]`` along the unit
    ``normals[k]`` (the body's own normal velocity: no approach), free in the tangent plane —
    unless ``stick[k]``: then it keeps the body's velocity ``body_velocity[k]`` entirely (static
    friction), as long as the reaction stays inside the Coulomb cone of ``friction[k]``.
    ``vertex_count`` is the size of the model they were found for; they are ignored on another.
    """

    ids: np.ndarray
    normals: np.ndarray
    normal_velocity: np.ndarray
    vertex_count: int
    stick: np.ndarray | None = None
    body_velocity: np.ndarray | None = None
    friction: np.ndarray | None = None


@dataclass(slots=True)
class _Held:
    """The working set of held contacts of one step."""

    ids: np.ndarray
    normals: np.ndarray
    target: np.ndarray  # (K, 3) velocity each must end with along its held directions
    stick: np.ndarray
    friction: np.ndarray

    @classmethod
    def empty(cls):
        return cls(np.zeros(0, np.intp), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.uint8), np.zeros(0))

    @classmethod
    def of(cls, c: Contacts, keep):
        k = int(keep.sum())
        n = np.asarray(c.normals, float)[keep]
        stick = np.zeros(k, np.uint8) if c.stick is None else np.asarray(c.stick, np.uint8)[keep]
        vb = np.zeros((k, 3)) if c.body_velocity is None else np.asarray(c.body_velocity, float)[keep]
        # the target's normal part is the prescribed normal velocity; its tangent part the body's
        vn = np.asarray(c.normal_velocity, float)[keep]
        target = vb + (vn - np.einsum("ij,ij->i", vb, n))[:, None] * n
        mu = np.full(k, np.inf) if c.friction is None else np.asarray(c.friction, float)[keep]
        return cls(np.ascontiguousarray(c.ids[keep], dtype=np.intp), np.ascontiguousarray(n), target, stick, mu)

    def __len__(self):
        return len(self.ids)

    def take(self, sel):
        return _Held(self.ids[sel], self.normals[sel], self.target[sel], self.stick[sel], self.friction[sel])

    def join(self, other):
        return _Held(*(np.concatenate([a, b]) for a, b in ((self.ids, other.ids), (self.normals, other.normals),
                                                          (self.target, other.target), (self.stick, other.stick),
                                                          (self.friction, other.friction))))


class ImplicitEuler:
    """Linearised backward Euler with a PSD Jacobian and block-Jacobi preconditioned CG.

    Parameters
    ----------
    tolerance : float
        Relative residual at which CG stops.
    max_iterations : int
        Of one CG solve. A stiff fabric on a fine mesh needs many (Bottino's fabric A with one
        Kawabata segment, 31 × 31 on the 9 cm sphere at 5 ms: 500–2 000 at tol 1e-5); stopping at 500
        halved the step 228 times in 80 steps, each after 500 wasted iterations (23 s against
        8.5 s for 0.4 s simulated at 2 000).
    max_halvings : int
        A step whose CG does not converge within ``max_iterations`` is taken as two half steps
        (M + Δt²K is better conditioned the smaller Δt is), at most this many times over.
        ``halvings`` counts how often that happened.
    max_stretch_change : float
        A step that would stretch any triangle by more than this (principal stretch, above the
        larger of its start and rest) is also taken as two half steps, up to ``max_halvings``
        deep (Baraff & Witkin 1998's adaptive step size: reject a step whose stretch changes too
        much). One linearised step rotates an edge about a held or stopped neighbour along the
        tangent, lengthening it by √(1 + θ²) for a rotation θ = |Δv|·Δt / length: cloth falling
        past a sphere's equator at 0.02–0.04 s steps was stretched 2–6× in one step (and the run
        stopped or not with round-off of the contact passes); halving the step quarters that.
        ``stretch_halvings`` counts these.

    Contacts
    --------
    Set :attr:`contacts` (a :class:`Contacts`) before a step and the solve itself keeps those
    vertices on the body (filtered CG): the cloth's stiffness then knows about the support within
    the step, instead of the support being imposed after a step that ignored it (which tears a
    fast-falling cloth apart where it meets a sphere at Δt = 0.01 s). The contacts are used for
    one step; afterwards :attr:`contact_ids` and :attr:`contact_impulse` give the normal
    impulse [N·s] each held vertex received (negative = the body had to pull: release it).
    :attr:`predict`, if set, is ``predict(model, state, x_end, v_end, dt, held_ids) -> Contacts`` for the
    vertices (other than those already held) the solved step would bring within the thickness of the body; they are held too
    (landing on the surface), stuck ones pulled harder than friction allows slide, and the step is
    solved again, at most :attr:`contact_passes` times. Friction inside the solve matters: a post-step friction that
    stops vertices the solve let slide leaves their neighbours stretched (2.7× on a sphere at 0.02 s).
    """

    name = "implicit"
    explicit = False

    def __init__(self, tolerance: float = 1e-5, max_iterations: int = 2000, max_halvings: int = 3,
                 max_stretch_change: float = 0.3):
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self.max_halvings = max_halvings
        self.max_stretch_change = max_stretch_change
        self.halvings = 0
        self.stretch_halvings = 0
        self._pattern = None
        self._pattern_model = None
        self._warm = None
        self.last_iterations = 0
        self.total_iterations = 0  # CG iterations over all solves (the cost measure of the bench)
        self.solves = 0
        self.contacts = None
        self.contact_ids = np.zeros(0, np.intp)
        self.contact_impulse = np.zeros(0)
        self.contact_vertex_count = 0
        self.predict = None
        self.contact_passes = 4
        self.predicted = 0  # contacts added by prediction, and stuck ones that slipped, over all steps
        self.slipped = 0
        self.released = 0  # held contacts the body would have had to pull on, let go within the step
        self.contact_stuck = np.zeros(0, bool)
        self.wind = None  # the air velocity the forces blow with: drag is implicit relative to it

    def reset(self):
        """Forget the warm start (the next solve starts from the explicit estimate)."""
        self._warm = None

    def _pattern_for(self, model):
        # the sparsity depends only on the topology arrays: copies of a model that share them
        # (other pair stiffnesses, pins) reuse it
        key = (id(model.faces), id(model.hinge_vertices), id(model.pair_vertices), model.has_bending, model.elastic)
        if self._pattern_model != key:
            self._pattern = SparsePattern(model)
            self._pattern_model = key
            self._warm = None
        return self._pattern

    def _held(self, model) -> _Held:
        """The contacts to hold this step: valid for this model, not pinned."""
        c = self.contacts
        if c is None or c.vertex_count != model.vertex_count or not len(c.ids):
            self.contacts = None
            return _Held.empty()
        return _Held.of(c, ~model.vertex_pinned[c.ids])

    def _solve(self, system, rhs, dv, v, held: _Held):
        """CG on A·Δv = rhs in place, holding the contacts' velocities; (iterations, converged)."""
        bptr, bcol, blocks, pinv = system
        ids, n = held.ids, held.normals
        if len(ids):
            dvk = dv.reshape(-1, 3)[ids]
            end = v.reshape(-1, 3)[ids] + dvk
            normal_fix = np.einsum("ij,ij->i", held.target - end, n)[:, None] * n
            dvk += np.where(held.stick[:, None] > 0, held.target - end, normal_fix)
            dv.reshape(-1, 3)[ids] = dvk
        return block_pcg(bptr, bcol, blocks, rhs, dv, pinv, self.tolerance, self.max_iterations, ids, n, held.stick)

    @staticmethod
    def _reactions(system, rhs, dv, held):
        """(K, 3) impulse [N·s] the held contacts exert: the residual A·Δv − b at their dofs."""
        if not len(held):
            return np.zeros((0, 3))
        out = np.empty((len(held), 3))
        bsr_rows(system[0], system[1], system[2], dv, held.ids, out)
        return out - rhs.reshape(-1, 3)[held.ids]

    def _halves(self, model, state, dt, forces, depth, carried):
        """The step taken as two half steps, each holding the contacts this one was given."""
        self._warm = None
        self.contacts = carried
        half = self.step(model, state, 0.5 * dt, forces, depth + 1)
        self.contacts = carried
        return self.step(model, half, 0.5 * dt, forces, depth + 1)

    def _overstretches(self, model, state, x_end) -> bool:
        """Whether ending at ``x_end`` stretches a triangle more than ``max_stretch_change`` this step."""
        if not model.face_count:
            return False
        end = face_stretch(model, x_end)
        limit = 1.0 + self.max_stretch_change
        if end.max(initial=1.0) <= limit:  # the common case: no triangle near it, no start needed
            return False
        return bool((end - np.maximum(face_stretch(model, state.x), 1.0)).max() > self.max_stretch_change)

    def step(self, model, state, dt, forces, _depth: int = 0):
        pattern = self._pattern_for(model)
        n = model.vertex_count
        f = forces(model, state).reshape(-1)
        blocks, kv = implicit_blocks(model, state, pattern, dt)
        m = model.vertex_mass
        free = np.repeat(~model.vertex_pinned, 3)
        v = state.v.reshape(-1)
        rhs = dt * (f - dt * kv.reshape(-1))
        diagonal = pattern.diagonal_block_index
        for a in range(3):
            blocks[diagonal, a, a] += m
        if not free.all():  # pinned vertices: Δv = 0 (their block rows and columns become the identity)
            pinned = model.vertex_pinned
            blocks[pinned[pattern.block_rows] | pinned[pattern.block_cols]] = 0.0
            blocks[diagonal[pinned]] = np.eye(3)
            rhs[~free] = 0.0
        # warm start: last step's Δv, or the explicit Euler estimate Δt·f/m on the first step
        if self._warm is not None and len(self._warm) == 3 * n:
            dv = self._warm.copy()
        else:
            dv = dt * f / np.repeat(m, 3) * free
        carried = self.contacts
        held = self._held(model)
        if model.air_density > 0.0:  # air drag and wind, implicitly (lumped on the diagonal blocks)
            drag = air_damping(model, state, self.wind)
            drag[model.vertex_pinned] = 0.0
            pattern.add_to_diagonal(blocks, dt * drag)
        system = (pattern.block_indptr, pattern.block_cols, blocks, inverse_3x3(pattern.diagonal_blocks(blocks)))
        iterations, converged = self._solve(system, rhs, dv, v, held)
        # Active set, a few passes at most: contacts the body would have to pull on are let go,
        # stuck contacts whose reaction leaves the Coulomb cone slide, and contacts the step would
        # make are held too, so the cloth lands on the body within the step instead of being
        # pushed out after it.
        let_go = np.zeros(0, np.intp)
        for _ in range(self.contact_passes if converged else 0):
            changed = False
            if len(held):
                r = self._reactions(system, rhs, dv, held)
                rn = np.einsum("ij,ij->i", r, held.normals)
                pulled = rn < 0.0
                if pulled.any():
                    # the body would have to pull this contact to hold it: let it go (the cloth
                    # leaves the body here), and solve again before judging friction
                    let_go = np.concatenate([let_go, held.ids[pulled]])
                    held = held.take(~pulled)
                    self.released += int(pulled.sum())
                    extra, converged = self._solve(system, rhs, dv, v, held)
                    iterations += extra
                    if not converged:
                        break
                    r = self._reactions(system, rhs, dv, held)
                    rn = np.einsum("ij,ij->i", r, held.normals)
                rn = np.maximum(rn, 0.0)  # a contact the new solve pulls on is let go next pass
                tangential = np.linalg.norm(r - rn[:, None] * held.normals, axis=1)
                limit = np.zeros_like(rn)  # μ may be inf (no sliding): never multiplied by rn = 0
                pressed = rn > 0.0
                limit[pressed] = held.friction[pressed] * rn[pressed]
                slip = (held.stick > 0) & (tangential > limit)
                if slip.any():
                    # a slipping contact keeps the friction it had, at its Coulomb limit (kinetic
                    # friction inside the solve, so the neighbours feel it); a tangential reaction
                    # of round-off size has no direction to drag in
                    rt = r - rn[:, None] * held.normals
                    drag = np.where(tangential > 1e-12 * (rn + 1e-30), limit / np.maximum(tangential, 1e-300), 0.0)
                    drag = drag[slip, None] * rt[slip]
                    np.add.at(rhs.reshape(n, 3), held.ids[slip], drag)
                    held.stick[slip] = 0
                    self.slipped += int(slip.sum())
                    changed = True
            if self.predict is not None:
                v1 = state.v + dv.reshape(n, 3)
                more = self.predict(model, state, state.x + dt * v1, v1, dt, held.ids)
                if more is not None and len(more.ids):
                    # not one let go earlier in this step: released for a pull, then predicted to land
                    # as its neighbours settle, it cycled, a solve each time (the response after the
                    # step still keeps it out of the body)
                    new = ~np.isin(more.ids, held.ids) & ~np.isin(more.ids, let_go) & ~model.vertex_pinned[more.ids]
                    if new.any():
                        held = held.join(_Held.of(more, new))
                        self.predicted += int(new.sum())
                        changed = True
            if not changed:
                break
            extra, converged = self._solve(system, rhs, dv, v, held)
            iterations += extra
        self.last_iterations = iterations
        self.total_iterations += iterations
        self.solves += 1
        if not converged and iterations >= self.max_iterations and _depth < self.max_halvings and np.all(np.isfinite(dv)):
            self.halvings += 1
            return self._halves(model, state, dt, forces, _depth, carried)
        if not converged:
            log.warning("implicit step at t = %.4f s: CG stopped after %d iterations before reaching %.0e", state.t, iterations, self.tolerance)
        if not np.all(np.isfinite(dv)) or (not converged and iterations < self.max_iterations):
            raise SimulationUnstable(
                f"implicit solve failed at t = {state.t:.4f} s (Δt = {dt:.3g} s): the system is not positive definite; "
                f"try a smaller time step"
            )
        dv[~free] = 0.0
        if _depth < self.max_halvings and self._overstretches(model, state, state.x + dt * (state.v + dv.reshape(n, 3))):
            self.stretch_halvings += 1
            return self._halves(model, state, dt, forces, _depth, carried)
        self._warm = dv
        self.contacts = None
        self.contact_vertex_count = n
        r = self._reactions(system, rhs, dv, held)
        self.contact_ids, self.contact_impulse = held.ids, np.einsum("ij,ij->i", r, held.normals)
        self.contact_stuck = held.stick > 0
        v1 = state.v + dv.reshape(n, 3)
        return State(state.x + dt * v1, v1, state.t + dt)


INTEGRATORS = {
    "forward": ForwardEuler,
    "symplectic": SymplecticEuler,
    "verlet": Verlet,
    "rk4": RK4,
    "implicit": ImplicitEuler,
}
"""Integrator classes by name."""


def make_integrator(name: str):
    """A fresh integrator called ``name`` (one of :data:`INTEGRATORS`)."""
    try:
        return INTEGRATORS[name]()
    except KeyError:
        raise ValueError(f"unknown integrator {name!r}; choose one of {', '.join(INTEGRATORS)}") from None
