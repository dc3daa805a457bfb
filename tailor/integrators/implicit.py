"""Linearised backward Euler (Baraff & Witkin 1998) with body contacts held inside the solve.

One Newton step of (M + Δt·C + Δt²·K)·Δv = Δt·(f − Δt·K·v), solved by block-Jacobi
preconditioned conjugate gradients on 3×3 vertex blocks (:mod:`.cg`, compiled, threaded).
Unconditionally stable for the linear part: it takes steps many times Eq. 24's.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..collide.contacts import Contacts
from ..errors import SimulationUnstable
from ..forces.external import air_damping
from ..forces.jacobian import BlockPart, SparsePattern, implicit_blocks
from ..forces.membrane import face_stretch
from ..model import State
from .base import IntegratorBase, SolverSettings, StepResult
from .cg import block_pcg, bsr_rows, inverse_3x3

__all__ = ["ImplicitEuler"]

log = logging.getLogger(__name__)


@dataclass(slots=True)
class _Held:
    """The working set of held contacts of one step.

    ``force`` [N] is each contact's lagged normal force (0: none known), ``drag`` (K, 3, 3) and
    ``push`` (K, 3) its regularised friction's terms in the system (:func:`_friction_terms`; zero
    where it has none)."""

    ids: np.ndarray
    normals: np.ndarray
    target: np.ndarray  # (K, 3) velocity each must end with along its normal; its tangent part the body's
    friction: np.ndarray
    force: np.ndarray
    drag: np.ndarray
    push: np.ndarray

    @classmethod
    def empty(cls):
        return cls(np.zeros(0, np.intp), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0),
                   np.zeros((0, 3, 3)), np.zeros((0, 3)))

    @classmethod
    def of(cls, c: Contacts, keep):
        k = int(keep.sum())
        n = np.asarray(c.normals, float)[keep]
        vb = np.zeros((k, 3)) if c.body_velocity is None else np.asarray(c.body_velocity, float)[keep]
        # the target's normal part is the prescribed normal velocity; its tangent part the body's
        vn = np.asarray(c.normal_velocity, float)[keep]
        target = vb + (vn - np.einsum("ij,ij->i", vb, n))[:, None] * n
        mu = np.full(k, np.inf) if c.friction is None else np.asarray(c.friction, float)[keep]
        force = np.zeros(k) if c.normal_force is None else np.asarray(c.normal_force, float)[keep]
        return cls(np.ascontiguousarray(c.ids[keep], dtype=np.intp), np.ascontiguousarray(n), target, mu, force,
                   np.zeros((k, 3, 3)), np.zeros((k, 3)))

    @classmethod
    def given(cls, contacts: Contacts | None, model):
        """The contacts to hold this step: valid for this model, not pinned."""
        if contacts is None or not contacts.valid_for(model):
            return cls.empty()
        return cls.of(contacts, ~model.vertex_pinned[contacts.ids])

    def __len__(self):
        return len(self.ids)

    def _fields(self):
        return (self.ids, self.normals, self.target, self.friction, self.force, self.drag, self.push)

    def take(self, sel):
        return _Held(*(a[sel] for a in self._fields()))

    def join(self, other):
        return _Held(*(np.concatenate([a, b]) for a, b in zip(self._fields(), other._fields())))


def _friction_terms(held: _Held, v, f, mass, dt, stick_speed):
    """(Δt·c·P, −Δt·c·P·u) of each held contact: Coulomb friction as a drag c on its tangent
    velocity u relative to the body (P: the projection onto the tangent plane).

    Eq. 14 removes at most μ·|Δv_n| of the tangent velocity a step would have had; as a force with
    the lagged normal force F, at most the budget b = μF·Δt/m. With u* = u + Δt·f_t/m the tangent
    velocity the step would reach without friction, Coulomb ends it at u*·(1 − b/|u*|) when
    |u*| > b, at rest otherwise; the implicit drag c = μF / max(|u*| − b, ε) ends it there too,
    (u* / (1 + Δt·c/m)), for ε = ``stick_speed``: held, it creeps at most ε. The drag is in the
    matrix (Baraff & Witkin 1998's implicit damping; the lagged, regularised friction of
    incremental potential contact), so no contact switches between stuck and sliding within a
    step, and, a drag, it never reverses a contact's slide. Contacts with no known force, or no
    finite μ, get none."""
    n = held.normals
    ids = held.ids
    u = v.reshape(-1, 3)[ids] - held.target
    u -= np.einsum("ij,ij->i", u, n)[:, None] * n
    free = u + dt * f.reshape(-1, 3)[ids] / mass[ids, None]
    free -= np.einsum("ij,ij->i", free, n)[:, None] * n
    limit = np.where(np.isfinite(held.friction), held.friction, 0.0) * np.maximum(held.force, 0.0)
    c = limit / np.maximum(np.linalg.norm(free, axis=1) - limit * dt / mass[ids], stick_speed)
    drag = (dt * c)[:, None, None] * (np.eye(3)[None] - n[:, :, None] * n[:, None, :])
    return drag, -(dt * c)[:, None] * u


@dataclass(slots=True)
class _System:
    """A step's linear system A·Δv = rhs in 3×3 block-CSR form, with its preconditioner."""

    bptr: np.ndarray
    bcol: np.ndarray
    blocks: np.ndarray
    pinv: np.ndarray
    rhs: np.ndarray
    free: np.ndarray  # (3N,) dofs not pinned
    rhs0: np.ndarray  # the right-hand side as assembled: before pinned rows were cleared and friction added
    parts: list  # the matrix's independent parts (BlockPart), each solved alone
    diagonal: np.ndarray  # (N,) index of each vertex's diagonal block

    def rub(self, held: _Held, sign: float = 1.0) -> None:
        """Add (``sign`` −1: take out) the held contacts' friction terms to their rows."""
        if not len(held):
            return
        at = self.diagonal[held.ids]
        self.blocks[at] += sign * held.drag
        self.rhs.reshape(-1, 3)[held.ids] += sign * held.push
        self.pinv[held.ids] = inverse_3x3(self.blocks[at])

    def reactions(self, dv, held: _Held):
        """(K, 3) impulse [N·s] the held contacts exert: the residual A·Δv − b at their dofs."""
        if not len(held):
            return np.zeros((0, 3))
        out = np.empty((len(held), 3))
        bsr_rows(self.bptr, self.bcol, self.blocks, dv, held.ids, out)
        return out - self.rhs.reshape(-1, 3)[held.ids]


def _support(model, system: _System, dv, held: _Held):
    """(N, 3) impulse [N·s] the held contacts and the pins gave the cloth in a solved step (None: none).

    A held vertex's is the residual A·Δv − b of the system as assembled (its normal reaction and
    any friction, static or at the Coulomb limit); a pinned vertex's is what cancels the rest of
    its momentum balance, −b (its Δv is held at 0: exact for a pin at rest, as the attachments of
    a settled garment are)."""
    pinned = model.vertex_pinned
    if not len(held) and not pinned.any():
        return None
    base = system.rhs0.reshape(-1, 3)
    out = np.zeros_like(base)
    out[pinned] = -base[pinned]
    if len(held):  # the friction drag is in the matrix: its part of A·Δv is the cloth's, not the contact's
        r = np.empty((len(held), 3))
        bsr_rows(system.bptr, system.bcol, system.blocks, dv, held.ids, r)
        out[held.ids] += r - base[held.ids] - np.einsum("kij,kj->ki", held.drag, dv.reshape(-1, 3)[held.ids])
    return out


class ImplicitEuler(IntegratorBase):
    """Linearised backward Euler with a PSD Jacobian and block-Jacobi preconditioned CG.

    Parameters
    ----------
    tolerance : float
        Relative residual at which CG stops.
    max_iterations : int
        Of one CG solve; a stiff fabric on a fine mesh needs 500–2 000 at 1e-5.
    max_halvings : int
        A step whose CG does not converge within ``max_iterations`` is taken as two half steps
        (M + Δt²K is better conditioned the smaller Δt is), at most this many times over.
    max_stretch_change : float
        A step that would stretch any triangle by more than this (principal stretch, above the
        larger of its start and rest) is also taken as two half steps, up to ``max_halvings``
        deep (Baraff & Witkin 1998's adaptive step size). One linearised step rotates an edge
        about a held neighbour along the tangent, lengthening it by √(1 + θ²) for a rotation
        θ = |Δv|·Δt / length; halving the step quarters that.
    stick_speed : float
        [m/s] The slowest slide the friction's drag allows (:func:`_friction_terms`): a contact
        that friction can hold creeps relative to the body at most this fast.

    Contacts
    --------
    ``contacts`` given to :meth:`step` are held by the solve itself (filtered CG): the cloth's
    stiffness then knows about the support within the step, instead of the support being
    imposed after a step that ignored it. Their friction is a drag in the matrix
    (:func:`_friction_terms`), so the neighbours feel it and no contact changes between stuck and
    sliding within the step. Contacts the body would have to pull on are let go, and ``predict``
    adds the vertices the solved step would bring onto the body; the step is solved again after
    either, at most :attr:`contact_passes` times.
    """

    name = "implicit"
    explicit = False

    def __init__(self, tolerance: float = 1e-5, max_iterations: int = 2000, max_halvings: int = 3,
                 max_stretch_change: float = 0.3, stick_speed: float = 5e-4):
        super().__init__()
        self.stick_speed = stick_speed
        self.max_iterations = max_iterations
        self.max_halvings = max_halvings
        self.contact_passes = 4
        self.settings = SolverSettings(tolerance, max_stretch_change, None)
        self._pattern = None
        self._pattern_model = None
        self._warm = None

    def reset(self) -> None:
        """Forget the warm start (the next solve starts from the explicit estimate)."""
        self._warm = None

    def _pattern_for(self, model):
        # the sparsity depends only on the topology arrays: copies of a model that share them
        # (other pair stiffnesses, pins) reuse it; the key holds the arrays, so their ids stay theirs
        arrays = (model.faces, model.hinge_vertices, model.pair_vertices)
        key = (tuple(id(a) for a in arrays), model.has_bending, model.elastic, arrays)
        if self._pattern_model is None or self._pattern_model[:3] != key[:3]:
            self._pattern = SparsePattern(model)
            self._pattern_model = key
            self._warm = None
        return self._pattern

    def _system(self, model, state, dt, f):
        """Assemble (M + Δt·C + Δt²·K) and Δt·(f − Δt·K·v), pinned rows the identity."""
        pattern = self._pattern_for(model)
        blocks, kv = implicit_blocks(model, state, pattern, dt)
        free = np.repeat(~model.vertex_pinned, 3)
        rhs = dt * (f - dt * kv.reshape(-1))
        rhs0 = rhs.copy()
        diagonal = pattern.diagonal_block_index
        for a in range(3):
            blocks[diagonal, a, a] += model.vertex_mass
        if not free.all():  # pinned vertices: Δv = 0 (their block rows and columns become the identity)
            pinned = model.vertex_pinned
            blocks[pinned[pattern.block_rows] | pinned[pattern.block_cols]] = 0.0
            blocks[diagonal[pinned]] = np.eye(3)
            rhs[~free] = 0.0
        if model.air_density > 0.0:  # air drag and wind, implicitly (lumped on the diagonal blocks)
            drag = air_damping(model, state, self.settings.wind)
            drag[model.vertex_pinned] = 0.0
            pattern.add_to_diagonal(blocks, dt * drag)
        pinv = inverse_3x3(pattern.diagonal_blocks(blocks))
        return _System(pattern.block_indptr, pattern.block_cols, blocks, pinv, rhs, free, rhs0, pattern.parts, diagonal)

    @staticmethod
    def _first_guess(model, system: _System, dt, f):
        """Δv to start the first solve of a model from: the explicit Euler estimate Δt·f/m, or zero
        where that leaves the larger residual (a stiff state: a sewn garment's tension), chosen for
        each independent part (an outfit's garments: one sewn and tense, one falling)."""
        dv = dt * f / np.repeat(model.vertex_mass, 3) * system.free
        r = np.empty((model.vertex_count, 3))
        bsr_rows(system.bptr, system.bcol, system.blocks, dv, np.arange(model.vertex_count), r)
        starts = np.array([3 * p.lo for p in system.parts], np.intp)
        worse = np.add.reduceat((system.rhs - r.reshape(-1)) ** 2, starts) >= np.add.reduceat(system.rhs ** 2, starts)
        for part in np.flatnonzero(worse):
            dv[3 * system.parts[part].lo:3 * system.parts[part].hi] = 0.0
        return dv

    def _solve(self, system: _System, dv, v, held: _Held):
        """CG on A·Δv = rhs in place, holding the contacts' velocities; (iterations, converged).

        Each independent part of the matrix (:attr:`SparsePattern.parts`: an outfit's garments) is
        solved alone to the tolerance of its own right-hand side: one CG over all of them would
        iterate every part as long as the slowest, and judge a light garment's residual against a
        tense one's. The iterations are the most any part took."""
        ids, n = held.ids, held.normals
        if len(ids):
            dvk = dv.reshape(-1, 3)[ids]
            end = v.reshape(-1, 3)[ids] + dvk
            dvk += np.einsum("ij,ij->i", held.target - end, n)[:, None] * n
            dv.reshape(-1, 3)[ids] = dvk
        if len(system.parts) < 2:
            return block_pcg(system.bptr, system.bcol, system.blocks, system.rhs, dv, system.pinv, self.settings.tolerance,
                             self.max_iterations, ids, n)
        iterations, converged = 0, True
        for part in system.parts:
            its, ok = self._solve_part(system, part, dv, held)
            iterations, converged = max(iterations, its), converged and ok
        return iterations, converged

    def _solve_part(self, system: _System, part: BlockPart, dv, held: _Held):
        """:meth:`_solve` on one independent part, on views of the system's arrays."""
        lo, hi = part.lo, part.hi
        mine = (held.ids >= lo) & (held.ids < hi)
        return block_pcg(part.bptr, part.bcol, system.blocks[part.first:part.last], system.rhs[3 * lo:3 * hi],
                         dv[3 * lo:3 * hi], system.pinv[lo:hi], self.settings.tolerance, self.max_iterations,
                         held.ids[mine] - lo, np.ascontiguousarray(held.normals[mine]))

    def _release_pulled(self, system, dv, held, let_go):
        """Let go the held contacts the body would have to pull on (the cloth leaves the body there).

        Returns (held, let_go, whether any was let go)."""
        rn = np.einsum("ij,ij->i", system.reactions(dv, held), held.normals)
        pulled = rn < 0.0
        if not pulled.any():
            return held, let_go, False
        let_go = np.concatenate([let_go, held.ids[pulled]])
        system.rub(held.take(pulled), -1.0)  # a contact let go has no friction either
        self.counters.released += int(pulled.sum())
        return held.take(~pulled), let_go, True

    def _new_landings(self, model, state, dt, dv, held, let_go, predict):
        """(contacts, which of them are new): those the solved step would make, less the ones held, the
        ones let go this step (released for a pull, then predicted to land as its neighbours settle,
        one would cycle) and pinned vertices; (None, None) if there are none."""
        n = model.vertex_count
        v1 = state.v + dv.reshape(n, 3)
        more = predict(model, state, state.x + dt * v1, v1, dt, held.ids)
        if more is None or not len(more.ids):
            return None, None
        taken = np.array(model.vertex_pinned, bool)  # by a mask: two ``isin`` calls sort all four arrays
        taken[held.ids] = True
        taken[let_go] = True
        new = ~taken[more.ids]
        return (more, new) if new.any() else (None, None)

    def _landing(self, model, state, dt, dv, held, let_go, predict):
        """``held`` with the new contacts the solved step would make, and whether there were any."""
        more, new = self._new_landings(model, state, dt, dv, held, let_go, predict)
        if more is None:
            return held, False
        self.counters.predicted += int(new.sum())
        return held.join(_Held.of(more, new)), True

    def _active_set(self, model, state, dt, system, dv, held, predict):
        """A few passes at most: release pulled contacts, hold landing ones, solving again after
        each change. Returns (held, iterations, converged, settled: no vertex still landing after
        the last pass)."""
        v = state.v.reshape(-1)
        let_go = np.zeros(0, np.intp)
        iterations, converged = 0, True
        for _ in range(self.contact_passes):
            changed = False
            if len(held):
                held, let_go, changed = self._release_pulled(system, dv, held, let_go)
            if predict is not None:
                held, landed = self._landing(model, state, dt, dv, held, let_go, predict)
                changed = changed or landed
            if not changed:
                return held, iterations, converged, True
            extra, converged = self._solve(system, dv, v, held)
            iterations += extra
        settled = (predict is None or not converged
                   or self._new_landings(model, state, dt, dv, held, let_go, predict)[0] is None)
        return held, iterations, converged, settled

    def _halves(self, model, state, dt, forces, contacts, predict, depth):
        """The step taken as two half steps, each holding the contacts this one was given."""
        self._warm = None
        half = self._step(model, state, 0.5 * dt, forces, contacts, predict, depth + 1)
        end = self._step(model, half.state, 0.5 * dt, forces, contacts, predict, depth + 1)
        # the second half's normal impulses at the whole step's rate: over dt they give its force
        impulses = None if end.impulses is None else 2.0 * end.impulses
        support = end.support if half.support is None else half.support if end.support is None else half.support + end.support
        return replace(end, impulses=impulses, support=support)

    def _overstretches(self, model, state, x_end) -> bool:
        """Whether ending at ``x_end`` stretches a triangle more than ``max_stretch_change`` this step."""
        if not model.face_count:
            return False
        end = face_stretch(model, x_end)
        change = self.settings.max_stretch_change
        if end.max(initial=1.0) <= 1.0 + change:  # the common case: no triangle near it, no start needed
            return False
        return bool((end - np.maximum(face_stretch(model, state.x), 1.0)).max() > change)

    def step(self, model, state, dt, forces, *, contacts=None, predict=None) -> StepResult:
        """One step of ``dt`` holding ``contacts`` (and those ``predict`` adds) within the solve."""
        self.counters.steps += 1
        return self._step(model, state, dt, forces, contacts, predict, 0)

    def _step(self, model, state, dt, forces, contacts, predict, depth) -> StepResult:
        result = self._attempt(model, state, dt, forces, contacts, predict, depth)
        if result is None:  # taken as two halves, the whole step's system freed first (one at a time alive)
            return self._halves(model, state, dt, forces, contacts, predict, depth)
        return result

    def _attempt(self, model, state, dt, forces, contacts, predict, depth) -> StepResult | None:
        """The step solved whole; None where it is to be taken as two half steps instead (its CG did
        not converge within the iterations, a landing was still unsettled, or its end overstretches),
        up to ``max_halvings`` deep."""
        n = model.vertex_count
        f = forces(model, state).reshape(-1)
        system = self._system(model, state, dt, f)
        # warm start: last step's Δv, or the explicit Euler estimate Δt·f/m on the first step
        if self._warm is not None and len(self._warm) == 3 * n:
            dv = self._warm.copy()
        else:
            dv = self._first_guess(model, system, dt, f)
        held = _Held.given(contacts, model)
        held.drag, held.push = _friction_terms(held, state.v, f, model.vertex_mass, dt, self.stick_speed)
        system.rub(held)
        iterations, converged = self._solve(system, dv, state.v.reshape(-1), held)
        settled = True
        if converged:
            held, extra, converged, settled = self._active_set(model, state, dt, system, dv, held, predict)
            iterations += extra
        self.counters.iterations += iterations
        self.counters.solves += 1
        if not converged and iterations >= self.max_iterations and depth < self.max_halvings and np.all(np.isfinite(dv)):
            self.counters.halvings += 1
            return None
        if not settled and depth < self.max_halvings:
            self.counters.landing_halvings += 1
            return None
        self._check(state, dt, dv, converged, iterations)
        dv[~system.free] = 0.0
        x_end = state.x + dt * (state.v + dv.reshape(n, 3))
        if depth < self.max_halvings and self._overstretches(model, state, x_end):
            self.counters.stretch_halvings += 1
            return None
        self._warm = dv
        impulses = None
        if len(held):
            impulses = np.zeros(n)
            impulses[held.ids] = np.einsum("ij,ij->i", system.reactions(dv, held), held.normals)
        v1 = state.v + dv.reshape(n, 3)
        return StepResult(State(state.x + dt * v1, v1, state.t + dt), impulses, iterations,
                          _support(model, system, dv, held))

    def _check(self, state, dt, dv, converged, iterations) -> None:
        """Warn of an unconverged solve; raise on a non-finite or indefinite one."""
        if not converged:
            log.warning("implicit step at t = %.4f s: CG stopped after %d iterations before reaching %.0e", state.t,
                        iterations, self.settings.tolerance)
        if not np.all(np.isfinite(dv)) or (not converged and iterations < self.max_iterations):
            raise SimulationUnstable(
                f"implicit solve failed at t = {state.t:.4f} s (Δt = {dt:.3g} s): the system is not positive definite; "
                f"try a smaller time step"
            )
