"""Walker's mass-spring model: Eq. 1–2 forces, no duplicate springs, damping only along the spring."""

import numpy as np
import pytest

from conftest import assert_minus_gradient, sheet
from tailor.forces import spring_energy, spring_forces

RNG = np.random.default_rng(5)


@pytest.fixture(scope="module")
def net():
    return sheet(20, 20, 0.04, "cotton", vertical=False, elastic="springs")


def test_no_duplicate_springs(net):
    model, _ = net
    pairs = np.sort(model.spring_vertices, axis=1)
    assert len(np.unique(pairs, axis=0)) == len(pairs)
    assert np.all(pairs[:, 0] != pairs[:, 1])


def test_spring_force_is_minus_energy_gradient(net):
    model, x0 = net
    assert_minus_gradient(spring_energy, spring_forces, model, model.state(x0 + RNG.normal(0, 0.005, x0.shape)))


def test_dampers_ignore_rigid_motion(net):
    model, x0 = net
    v = np.cross([0.0, 0.0, 2.0], x0) + [1.0, 0.0, 0.0]
    f = spring_forces(model, model.state(x0, v))
    assert np.abs(f).max() < 1e-12
