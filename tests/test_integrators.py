"""Integrators: free fall, momentum, Walker's instability observation, and the stability guard."""

import numpy as np
import pytest

from conftest import sheet
from tailor.errors import SimulationUnstable
from tailor.fabric import PRESETS
from tailor.forces import internal_forces, total_forces
from tailor.integrators import INTEGRATORS, ImplicitEuler, make_integrator
from tailor.sim import run, simulate
from tailor.units import GRAVITY

FIRST_ORDER = {"forward", "symplectic", "implicit", "verlet"}  # Verlet: its symplectic-Euler first step lags it


@pytest.fixture(scope="module")
def falling_sheet():
    # a horizontal 1 m sheet at a realistic 150 g/m², in vacuum
    from tailor.fabric import preset

    return sheet(100, 100, 0.05, preset("cotton").with_values(density=0.150), vertical=False)


@pytest.mark.parametrize("name", list(INTEGRATORS))
def test_free_fall_is_flat_and_straight(falling_sheet, name):
    model, x0 = falling_sheet
    x0 = x0 + [0.0, 0.0, 2.0]
    dt = model.time_step if name != "implicit" else 0.01
    t = 0.4
    state = run(model, model.state(x0), duration=t, frame_rate=25, integrator=name, dt=dt)
    drop = x0[:, 2] - state.x[:, 2]
    exact = 0.5 * GRAVITY * t * t
    steps = round(t / dt)
    h = t / steps
    # RK4 is exact for constant acceleration; the Euler variants are off by ½·g·t·Δt
    tolerance = 0.5 * GRAVITY * t * h * (1 + 1e-6) if name in FIRST_ORDER else 1e-9
    assert np.abs(drop - exact).max() <= tolerance
    assert np.ptp(drop) < 1e-9  # every point falls the same: the sheet stays flat
    assert np.abs(state.x[:, :2] - x0[:, :2]).max() < 1e-10  # no lateral drift (round-off only)
    assert np.abs(internal_forces(model, state)).max() < 1e-9  # no internal deformation


def test_internal_forces_conserve_momentum_and_rigid_motion_loses_no_energy():
    from tailor.forces import dissipation

    model, x0 = sheet(40, 30, 0.04, "jersey", vertical=False, gravity=(0, 0, 0))
    rng = np.random.default_rng(0)
    x = x0 * [1.03, 0.98, 1.0] + rng.normal(0, 0.002, x0.shape)  # stretched, crumpled
    v = rng.normal(0, 0.5, x0.shape)
    state = model.state(x, v)
    f = internal_forces(model, state)
    scale = np.abs(f).sum()
    assert np.abs(f.sum(axis=0)).max() <= 1e-9 * scale
    assert np.abs(np.cross(x, f).sum(axis=0)).max() <= 1e-9 * scale
    # a spinning, translating sheet: no strain rate, so no internal damping
    spin = model.state(x0, np.cross([0.3, -1.2, 2.0], x0) + [0.5, 0.0, -1.0])
    assert dissipation(model, spin) == pytest.approx(0.0, abs=1e-18)
    # symplectic Euler conserves momentum exactly under internal forces (Σf = 0, Σx×f = 0)
    m = model.vertex_mass[:, None]
    p0, l0 = (m * v).sum(axis=0), np.cross(x, m * v).sum(axis=0)
    end = run(model, state, duration=0.02, frame_rate=100, integrator="symplectic")
    p1, l1 = (m * end.v).sum(axis=0), np.cross(end.x, m * end.v).sum(axis=0)
    assert np.abs(p1 - p0).max() <= 1e-9 * np.abs(m * v).sum()
    assert np.abs(l1 - l0).max() <= 1e-9 * np.abs(np.cross(x, m * v)).sum()


def test_single_mass_is_critically_damped():
    # Eq. 26 makes "the ideal case of a single mass" return to rest without oscillating:
    # one free corner of an equilateral triangle, stretched 10 % and released.
    from tailor.fabric import preset
    from tailor.io import pattern_from_dict
    from tailor.mesh import discretise
    from tailor.model import build_model

    doc = {"pattern": {"panels": {"t": {"vertices": [[0, 0], [4, 0], [2, 3.4641016]],
                                        "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 0]}]}}}}
    model = build_model(discretise(pattern_from_dict(doc), 0.1), preset("cotton"), gravity=(0, 0, 0)).with_pins([0, 1])
    assert model.vertex_count == 3
    x0 = np.column_stack([model.rest_uv, np.zeros(3)])
    x = x0.copy()
    x[2, 1] *= 1.10
    ys = [s.x[2, 1] for _, s in simulate(model, model.state(x), duration=0.03, frame_rate=20000, integrator="rk4", dt=1e-6)]
    initial = x[2, 1] - x0[2, 1]
    assert (x0[2, 1] - min(ys)) <= 0.01 * initial  # overshoot below 1 % of the initial stretch
    assert abs(ys[-1] - x0[2, 1]) < 1e-3 * initial  # and back at rest


def hanging(fabric="cotton", resolution=0.05, size=50):
    model, x0 = sheet(size, size, resolution, fabric)
    top = np.flatnonzero(x0[:, 2] > size / 100 - 1e-9)
    return model.with_pins(top), x0


def test_forward_euler_blows_up_and_the_guard_stops_it():
    model, x0 = hanging("cotton", 0.05)
    frames = []
    with pytest.raises(SimulationUnstable, match=r"t = .* s \(frame \d+, step \d+, Δt = .* s\).*try a smaller time step"):
        for _, state in simulate(model, model.state(x0), duration=2.0, integrator="forward", dt=3.0 * model.time_step):
            frames.append(state)
    assert frames and all(np.isfinite(s.x).all() for s in frames)  # nothing non-finite was ever handed out


@pytest.mark.parametrize("name", ["symplectic", "verlet", "rk4", "implicit"])
@pytest.mark.parametrize("fabric", ["chiffon", "cotton", "heavy_leather"])
def test_stable_at_eq24_step_quick(name, fabric):
    model, x0 = hanging(fabric, 0.05, size=30)
    dt = None if name == "implicit" else model.time_step
    state = run(model, model.state(x0), duration=0.5, integrator=name, dt=dt)
    assert np.isfinite(state.x).all() and np.abs(state.v).max() < 5.0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["symplectic", "verlet", "rk4", "implicit"])
@pytest.mark.parametrize("fabric", list(PRESETS))
def test_stable_at_eq24_step_every_preset_5s(name, fabric):
    model, x0 = hanging(fabric, 0.05, size=30)
    dt = None if name == "implicit" else model.time_step
    state = run(model, model.state(x0), duration=5.0, integrator=name, dt=dt)
    assert np.isfinite(state.x).all() and np.abs(state.v).max() < 1.0


def test_unknown_integrator():
    with pytest.raises(ValueError, match="unknown integrator 'euler'; choose one of forward, symplectic"):
        make_integrator("euler")


def test_walker_mass_spring_cloth_hangs_stably_near_the_membrane():
    # Walker's net (structural, shear, flexion springs with dampers) calibrated to the membrane's
    # energy: it hangs like it to within the crudeness of springs on an irregular mesh.
    model, x0 = sheet(100, 100, 0.05, "cotton", elastic="springs")
    model = model.with_pins(np.flatnonzero(x0[:, 2] > 1 - 1e-9))
    bottom = np.flatnonzero(x0[:, 2] < 1e-9)
    states = [s for _, s in simulate(model, model.state(x0), duration=2.0, frame_rate=10, integrator="symplectic")]
    stretch = np.mean([-s.x[bottom, 2].mean() for s in states[-10:]])
    assert np.isfinite(states[-1].x).all()
    assert 0.01 * 0.7 < stretch < 0.01 * 1.6  # cotton: λ = 1 %


class ExplicitStart(ImplicitEuler):
    """The implicit step whose first solve always starts from the explicit estimate Δt·f/m: from it
    a smaller step needs fewer iterations (from rest, on a rough state, about as many)."""

    @staticmethod
    def _first_guess(model, system, dt, f):
        return dt * f / np.repeat(model.vertex_mass, 3) * system.free


def test_implicit_step_halves_when_cg_does_not_converge():
    model, x0 = sheet(12, 12, 0.02, "denim", vertical=False)
    rng = np.random.default_rng(5)
    state = model.state(x0 * 1.02 + rng.normal(0, 0.002, x0.shape))
    dt = 0.02

    def iterations(h):
        solver = ExplicitStart(max_iterations=100000)
        return solver.step(model, state, h, total_forces).iterations

    full, half = iterations(dt), iterations(0.5 * dt)
    assert half < full  # a smaller step is better conditioned
    reference = ExplicitStart(max_iterations=100000)
    expected = reference.step(model, reference.step(model, state, 0.5 * dt, total_forces).state, 0.5 * dt, total_forces).state
    limited = ExplicitStart(max_iterations=half + 2)
    got = limited.step(model, state, dt, total_forces).state
    assert limited.counters.halvings == 1 and got.t == pytest.approx(state.t + dt)
    assert np.allclose(got.x, expected.x, atol=1e-9) and np.allclose(got.v, expected.v, atol=1e-6)


@pytest.mark.parametrize("name", ["symplectic", "verlet", "rk4"])
def test_soft_cloth_stretched_at_its_pins_stays_stable_at_the_default_explicit_step(name):
    # a 10 % fabric hanging from two corners stretches 1.8x there; at the rest-stiffness Eq. 24
    # step the stiffened corner blew up (a vertex at 10^13 m) at t = 0.32 s; the step now shortens
    from tailor.fabric import Fabric
    from tailor.model import build_model
    from tailor.scenes import grid
    from tailor.sim import max_stretch

    n = 13
    mesh = grid(0.5, 0.5, n)
    model = build_model(mesh, Fabric("soft", 0.15, 0.10, 0.10, 8.0), pinned=[n * (n - 1), n * n - 1])
    state = model.state(np.c_[mesh.uv - 0.25, np.full(n * n, 1.0)])
    final = run(model, state, duration=0.5, integrator=name)
    assert np.isfinite(final.x).all()
    assert 1.3 < max_stretch(model, final.x) < 2.5  # really stretched at the pins, not exploded


def test_implicit_step_halves_where_one_linearised_step_would_overstretch():
    # A horizontal sheet falling at 3 m/s past a pinned corner: one 0.04 s linearised step swings
    # the edges at the pin along their tangent, θ = |Δx| / length ≫ 1, lengthening them by √(1 + θ²).
    from tailor.integrators import ImplicitEuler
    from tailor.sim import face_stretch

    model, x0 = sheet(20, 20, 0.02, "cotton", vertical=False)
    model = model.with_pins([int(np.argmin(x0[:, 0] + x0[:, 1]))])
    v0 = np.where(model.vertex_pinned[:, None], 0.0, [0.0, 0.0, -3.0])
    state = model.state(x0, v0)
    assert face_stretch(model, x0).max() == pytest.approx(1.0, abs=1e-9)

    unchecked = ImplicitEuler(max_stretch_change=np.inf)
    assert face_stretch(model, unchecked.step(model, state, 0.04, total_forces).state.x).max() > 2.0
    assert unchecked.counters.stretch_halvings == 0

    checked = ImplicitEuler()
    got = checked.step(model, state, 0.04, total_forces).state
    assert got.t == pytest.approx(0.04) and checked.counters.stretch_halvings >= 1
    assert face_stretch(model, got.x).max() < 1.0 + 2 * checked.settings.max_stretch_change  # each half step within the bound


def test_the_first_solve_starts_from_the_explicit_estimate_or_from_rest_whichever_is_nearer():
    """A model's first solve has no last step to start from: in free fall Δt·g is the exact Δv and is
    kept (no iteration needed); on a stretched stiff sheet Δt·f/m overshoots by far (its stiffness
    is what the implicit step is for), so the solve starts from rest and needs fewer iterations."""
    model, x0 = sheet(12, 12, 0.02, "denim", vertical=False)
    assert ImplicitEuler().step(model, model.state(x0), 0.01, total_forces).iterations == 0
    rng = np.random.default_rng(5)
    state = model.state(x0 * 1.02 + rng.normal(0, 0.002, x0.shape))
    chosen = ImplicitEuler(max_iterations=100000).step(model, state, 0.01, total_forces)
    explicit = ExplicitStart(max_iterations=100000).step(model, state, 0.01, total_forces)
    assert chosen.iterations < explicit.iterations
    gap = np.abs(chosen.state.v - explicit.state.v).max()
    assert gap < 0.01 * np.abs(explicit.state.v).max()  # the same step, to the solver's tolerance


def test_garments_not_sewn_together_are_solved_each_to_its_own_tolerance():
    """Two sheets in one model (an outfit's garments): the implicit matrix has two independent parts
    and each is solved alone, so the light sheet steps exactly as it would alone. One CG over both
    judged the light sheet's residual against the tense one's right-hand side and stopped early."""
    from conftest import doc_with, rect_panel
    from tailor.fabric import preset
    from tailor.forces.jacobian import SparsePattern
    from tailor.io import pattern_from_dict
    from tailor.mesh import discretise
    from tailor.model import build_model

    def model_of(panels):
        return build_model(discretise(pattern_from_dict(doc_with(panels)), 0.02), preset("denim"))

    both, alone = model_of({"a": rect_panel(40, 40), "b": rect_panel(30, 40)}), model_of({"b": rect_panel(30, 40)})
    k = both.vertex_count - alone.vertex_count
    assert [(p.lo, p.hi) for p in SparsePattern(both).parts] == [(0, k), (k, both.vertex_count)]
    rng = np.random.default_rng(1)
    flat = np.c_[both.rest_uv, np.zeros(both.vertex_count)]
    x = np.concatenate([flat[:k] * 1.03 + rng.normal(0, 0.002, (k, 3)),  # the tense sheet
                        flat[k:] + [0.0, 0.0, 0.5] + rng.normal(0, 1e-4, (alone.vertex_count, 3))])  # the light one
    v = np.concatenate([np.zeros((k, 3)), rng.normal(0, 0.01, (alone.vertex_count, 3))])
    got = ImplicitEuler(tolerance=1e-2).step(both, both.state(x, v), 0.02, total_forces).state
    own = ImplicitEuler(tolerance=1e-2).step(alone, alone.state(x[k:], v[k:]), 0.02, total_forces).state
    assert np.allclose(got.v[k:], own.v, rtol=0.0, atol=1e-12)  # the forces' sums differ in the last bit

    class Joint(ImplicitEuler):  # one CG over the whole matrix, as before
        def _solve(self, system, dv, v, held):
            system.parts = system.parts[:0]
            return super()._solve(system, dv, v, held)

    joint = Joint(tolerance=1e-2).step(both, both.state(x, v), 0.02, total_forces).state
    exact = ImplicitEuler(tolerance=1e-10).step(alone, alone.state(x[k:], v[k:]), 0.02, total_forces).state
    assert np.linalg.norm(joint.v[k:] - exact.v) > 4 * np.linalg.norm(own.v - exact.v)  # 8.5× here


def test_block_parts_cut_only_where_no_block_crosses():
    """Runs of coupled vertices: 0–299, 300–309 and 310–699 each a chain; interleaved pairs (i, i + 2)
    cannot be cut anywhere. A run shorter than MIN_PART_VERTICES joins the part before it."""
    from tailor.forces.jacobian import MIN_PART_VERTICES, block_parts

    def csr(n, pairs):
        rows = [{i} for i in range(n)]
        for a, b in pairs:
            rows[a].add(b)
            rows[b].add(a)
        bcol = np.concatenate([sorted(r) for r in rows]).astype(np.int32)
        return np.concatenate([[0], np.cumsum([len(r) for r in rows])]).astype(np.int32), bcol

    chains = [(i, i + 1) for i in range(699) if i + 1 not in (300, 310)]
    assert MIN_PART_VERTICES > 10
    parts = block_parts(*csr(700, chains))
    assert [(p.lo, p.hi) for p in parts] == [(0, 300), (300, 700)]
    bptr, bcol = csr(700, chains)
    second = parts[1]
    assert np.array_equal(second.bcol, bcol[bptr[300]:] - 300) and second.bptr[-1] == len(second.bcol)
    assert [(p.lo, p.hi) for p in block_parts(*csr(700, [(i, i + 2) for i in range(698)]))] == [(0, 700)]
