"""Gravity and air: weight is m·g, vacuum means no air force, drag opposes motion as v²."""

import numpy as np
import pytest

from conftest import sheet
from tailor.forces import air_forces, gravity_forces
from tailor.model import AIR_DENSITY
from tailor.units import GRAVITY


def test_weight_is_density_times_area_times_g():
    model, x0 = sheet(50, 40, 0.05, "denim", vertical=False)
    f = gravity_forces(model, model.state(x0))
    assert f[:, 2].sum() == pytest.approx(-0.4 * 0.5 * 0.4 * GRAVITY, rel=1e-12)
    assert model.total_mass == pytest.approx(0.4 * 0.2, rel=1e-12)  # Eq. 21: mass = ρ·area


def test_vacuum_has_no_air_force():
    model, x0 = sheet(20, 20, 0.05, vertical=False)
    assert np.all(air_forces(model, model.state(x0, np.ones_like(x0))) == 0)


def test_drag_opposes_normal_motion_and_scales_with_speed_squared():
    model, x0 = sheet(20, 20, 0.05, vertical=False, air_density=AIR_DENSITY)
    forces = [air_forces(model, model.state(x0, np.tile([0.3, 0.0, -u], (len(x0), 1)))) for u in (1.0, 2.0)]
    assert forces[0][:, 2].sum() > 0  # falling: pushed up
    assert forces[1][:, 2].sum() / forces[0][:, 2].sum() == pytest.approx(4.0, rel=1e-9)
    assert np.abs(forces[0][:, :2]).max() < 1e-12  # tangential motion feels no normal drag
    expected = 0.5 * AIR_DENSITY * model.drag_coefficient * 0.04 * 1.0
    assert forces[0][:, 2].sum() == pytest.approx(expected, rel=1e-9)


def test_wind_on_a_still_sheet_equals_drag_of_the_moving_sheet():
    model, x0 = sheet(20, 20, 0.05, vertical=False, air_density=AIR_DENSITY)
    blown = air_forces(model, model.state(x0), wind=[0.0, 0.0, 3.0])
    moving = air_forces(model, model.state(x0, np.tile([0.0, 0.0, -3.0], (len(x0), 1))))
    assert np.allclose(blown, moving)


def test_calm_wind_changes_nothing_and_force_scales_with_speed_squared():
    from tailor.forces.wind import Wind

    model, x0 = sheet(20, 20, 0.05, vertical=True, air_density=AIR_DENSITY)  # a flag facing ±y
    still = air_forces(model, model.state(x0))
    assert np.all(air_forces(model, model.state(x0), wind=Wind(speed=0.0)) == still)
    push = [air_forces(model, model.state(x0), wind=Wind(speed=u, direction=(0, 1, 0), turbulence=0.0))[:, 1].sum() for u in (5, 10)]
    assert push[1] / push[0] == pytest.approx(4.0, rel=1e-12)
    edge_on = air_forces(model, model.state(x0), wind=Wind(speed=10, direction=(1, 0, 0), turbulence=0.0))
    assert np.abs(edge_on).max() < 1e-12  # wind along the cloth's plane does not push it


def test_turbulent_wind_is_smooth_deterministic_and_has_the_requested_mean():
    from tailor.forces.wind import Wind

    rng = np.random.default_rng(1)
    p = rng.uniform(0, 3, (5000, 3))
    w = Wind(speed=8.0, direction=(1, 1, 0), turbulence=0.4, seed=3)
    v = w(p, 1.7)
    assert np.allclose(v, Wind(speed=8.0, direction=(1, 1, 0), turbulence=0.4, seed=3)(p, 1.7))
    assert np.linalg.norm(v.mean(axis=0) - 8.0 * np.array([1, 1, 0]) / np.sqrt(2)) < 0.5
    assert 0.2 < v.std(axis=0).mean() < 0.4 * 8.0  # gusty, within ±τ·U
    # smooth (differentiable): a ten times smaller step changes the field ten times less
    for shift in (lambda d: (p + d, 1.7), lambda d: (p, 1.7 + d)):
        big = np.abs(w(*shift(1e-4)) - v).max()
        small = np.abs(w(*shift(1e-5)) - v).max()
        assert 8.0 < big / small < 12.0 and big < 0.05


@pytest.mark.parametrize("wind", [None, [1.0, -2.0, 0.5], "per face", "field"])
def test_air_force_and_its_damping_are_each_faces_normal_drag_spread_to_its_corners(wind):
    """f = −½ρC_d·A·v_n|v_n|·n per face and −∂f/∂v = ρC_d·A·|v_n|·n nᵀ, a third to each corner, written
    out face by face here against the compiled loop (every wind form: none, one, per face, a field)."""
    from tailor.forces.external import air_damping

    rng = np.random.default_rng(5)
    model, x0 = sheet(12, 9, 0.05, vertical=False, air_density=AIR_DENSITY)
    state = model.state(x0 + rng.normal(0, 0.01, x0.shape), rng.normal(0, 1.0, x0.shape))
    if wind == "per face":
        wind = rng.normal(0, 2.0, (model.face_count, 3))
    elif wind == "field":
        wind = lambda p, t: np.column_stack([np.sin(p[:, 0]), p[:, 1], np.full(len(p), t + 1.0)])  # noqa: E731
    air = np.zeros((model.face_count, 3)) if wind is None else (
        wind(state.x[model.faces].mean(axis=1), state.t) if callable(wind) else np.broadcast_to(wind, (model.face_count, 3)))
    force, damping = np.zeros_like(x0), np.zeros((len(x0), 3, 3))
    rho_cd = model.air_density * model.drag_coefficient
    for f, (i, j, k) in enumerate(model.faces):
        cross = np.cross(state.x[j] - state.x[i], state.x[k] - state.x[i])
        area, n = 0.5 * np.linalg.norm(cross), cross / np.linalg.norm(cross)
        vn = (state.v[[i, j, k]].mean(axis=0) - air[f]) @ n
        force[[i, j, k]] += -0.5 * rho_cd * area * vn * abs(vn) / 3.0 * n
        damping[[i, j, k]] += rho_cd * area * abs(vn) / 3.0 * np.outer(n, n)
    assert np.abs(force).max() > 0 and np.abs(damping).max() > 0
    assert np.allclose(air_forces(model, state, wind=wind), force, rtol=1e-12, atol=1e-15)
    assert np.allclose(air_damping(model, state, wind), damping, rtol=1e-12, atol=1e-15)
