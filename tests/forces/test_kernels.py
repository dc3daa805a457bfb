"""The compiled kernels compute exactly what the numpy reference computes (forces and Jacobians)."""

import numpy as np
import pytest

from conftest import sheet
from tailor.forces import bending_forces, damping_forces, internal_forces, stretch_forces
from tailor.forces.jacobian import SparsePattern, force_jacobians, jacobian_blocks

RNG = np.random.default_rng(11)


@pytest.fixture(scope="module", params=[1.0, 0.1], ids=["symmetric", "soft-compression"])
def deformed(request):
    from dataclasses import replace

    model, x0 = sheet(30, 20, 0.03, "denim", vertical=False)
    model = replace(model, compression=request.param)
    x = x0 * 1.01 + RNG.normal(0, 0.005, x0.shape)  # some triangles stretched, some compressed
    return model, model.state(x, RNG.normal(0, 0.5, x0.shape))


def test_forces_match_reference(deformed):
    model, state = deformed
    ref = stretch_forces(model, state) + damping_forces(model, state) + bending_forces(model, state)
    fast = internal_forces(model, state)
    assert np.abs(fast - ref).max() <= 1e-12 * np.abs(ref).max()


def test_jacobians_match_reference(deformed):
    model, state = deformed
    pattern = SparsePattern(model)
    k1, c1 = force_jacobians(model, state, pattern)
    k2, c2 = jacobian_blocks(model, state, pattern)
    assert abs(k1 - k2).max() <= 1e-12 * abs(k2).max()
    assert abs(c1 - c2).max() <= 1e-12 * abs(c2).max()


def test_stiffness_is_symmetric_positive_semidefinite_and_predicts_force_change(deformed):
    model, state = deformed
    k, c = force_jacobians(model, state, SparsePattern(model))
    assert abs(k - k.T).max() < 1e-12 * abs(k).max()
    dense = k.toarray()
    assert np.linalg.eigvalsh(dense).min() > -1e-9 * abs(dense).max()
    # the damping force is linear in v: C·v reproduces it exactly
    f_damp = damping_forces(model, state).reshape(-1)
    assert np.allclose(-(c @ state.v.reshape(-1)), f_damp, rtol=1e-10, atol=1e-12 * np.abs(f_damp).max())


def test_block_jacobi_inverse_matches_lapack_on_stiff_and_ill_conditioned_blocks():
    from tailor.forces.kernels import inverse_3x3

    rng = np.random.default_rng(7)
    a = rng.standard_normal((500, 3, 3))
    spd = a @ a.transpose(0, 2, 1) + np.eye(3) * np.logspace(-6, 3, 500)[:, None, None]  # mass + Δt²·K
    inv = inverse_3x3(spd)
    assert np.allclose(np.einsum("kij,kjl->kil", spd, inv), np.eye(3), atol=1e-6)
    assert np.allclose(inv, np.linalg.inv(spd), rtol=1e-8, atol=1e-12 * np.abs(np.linalg.inv(spd)).max())
