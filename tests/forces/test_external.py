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
