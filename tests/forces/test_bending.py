"""Bending: dihedral-angle energy, its exact gradient, the continuum calibration, and c = 0."""

import numpy as np
import pytest

from conftest import assert_minus_gradient, sheet
from tailor.fabric import preset
from tailor.forces import bending_energy, bending_forces
from tailor.geometry import hinge_angle_gradients, hinge_angles

RNG = np.random.default_rng(3)


def test_dihedral_gradient_matches_finite_differences():
    x = RNG.normal(size=(4, 3))
    hv = np.array([[0, 1, 2, 3]])
    g = hinge_angle_gradients(x, hv)[0]
    eps = 1e-6
    for i in range(4):
        for k in range(3):
            up, dn = x.copy(), x.copy()
            up[i, k] += eps
            dn[i, k] -= eps
            assert g[i, k] == pytest.approx((hinge_angles(up, hv) - hinge_angles(dn, hv))[0] / (2 * eps), abs=1e-7)


def test_force_is_minus_energy_gradient():
    model, x0 = sheet(20, 20, 0.04, "denim", vertical=False)
    state = model.state(x0 + RNG.normal(0, 0.01, x0.shape))
    assert_minus_gradient(bending_energy, bending_forces, model, state)
    f = bending_forces(model, state)
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * np.abs(f).sum()
    assert np.abs(np.cross(state.x, f).sum(axis=0)).max() < 1e-12 * np.abs(f).sum()


@pytest.mark.parametrize("h", [0.04, 0.02])
@pytest.mark.parametrize("angle", [0.0, 0.5])
def test_rolling_onto_a_cylinder_costs_the_continuum_energy(h, angle):
    # ½·B·κ²·A for a 1 m² sheet rolled to radius R, in any direction, at any resolution
    model, x0 = sheet(100, 100, h, "wool", vertical=False)
    radius = 0.3
    c, s = np.cos(angle), np.sin(angle)
    a = x0[:, 0] * c + x0[:, 1] * s
    b = -x0[:, 0] * s + x0[:, 1] * c
    x = np.column_stack([radius * np.sin(a / radius), b, radius * (1 - np.cos(a / radius))])
    rigidity = model.params[0].bending_rigidity
    assert bending_energy(model, model.state(x)) == pytest.approx(0.5 * rigidity * 1.0 / radius**2, rel=0.03)


def test_zero_bending_constant_means_no_bending_force():
    fabric = preset("silk").with_values(bending=0.0)
    model, x0 = sheet(20, 20, 0.04, fabric, vertical=False)
    assert not model.has_bending
    state = model.state(x0 + RNG.normal(0, 0.01, x0.shape))
    assert np.all(bending_forces(model, state) == 0.0)
    assert bending_energy(model, state) == 0.0
    # and the internal force is pure membrane: folding the sheet along a line costs nothing
    fold = x0.copy()
    left = fold[:, 0] < 0.1
    fold[left, 2] = 0.1 - fold[left, 0]
    fold[left, 0] = 0.1
    assert bending_energy(model, model.state(fold)) == 0.0
