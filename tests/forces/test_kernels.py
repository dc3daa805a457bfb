"""The compiled kernels compute exactly what the numpy reference computes (forces and Jacobians)."""

import numpy as np
import pytest
import scipy.sparse as sp

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


@pytest.mark.parametrize("pairs", [False, True], ids=["plain", "with seam pairs"])
def test_implicit_blocks_are_the_jacobians_of_the_reference(deformed, pairs):
    """What the implicit step assembles in block form (Δt·C + Δt²·K, K·v; threaded by element
    colour classes) is the numpy reference's matrices (with seam pairs: the CSR path's, which
    adds them to the reference's)."""
    from tailor.forces.jacobian import implicit_blocks

    model, state = deformed
    if pairs:
        ids = RNG.choice(model.vertex_count, size=(40, 2), replace=False)
        model = model.with_pairs(ids, np.full(40, 50.0), np.full(40, 0.2))
    pattern = SparsePattern(model)
    k, c = (force_jacobians if pairs else jacobian_blocks)(model, state, pattern)
    dt = 0.02
    blocks, kv = implicit_blocks(model, state, pattern, dt)
    expect = (dt * c + dt * dt * k).tocsr()
    got = sp.bsr_matrix((blocks, pattern.block_cols, pattern.block_indptr), shape=expect.shape).tocsr()
    assert abs(got - expect).max() <= 1e-12 * abs(expect).max()
    ref_kv = k @ state.v.reshape(-1)
    assert np.abs(kv.reshape(-1) - ref_kv).max() <= 1e-12 * np.abs(ref_kv).max()


def test_element_chunks_of_a_class_share_no_vertex_and_cover_every_element_once():
    from tailor.forces.kernels import element_chunks

    model, _ = sheet(60, 40, 0.02, "denim", vertical=False)
    for nodes in (model.faces, model.hinge_vertices):
        nodes = np.asarray(nodes, np.int64)
        order, tasks, classes = element_chunks(nodes, model.vertex_count, 16)
        assert sorted(order) == list(range(len(nodes)))
        assert tasks[0] == 0 and tasks[-1] == len(nodes) and np.all(np.diff(tasks) > 0) and np.diff(tasks).max() == 16
        assert classes[0] == 0 and classes[-1] == len(tasks) - 1
        assert len(classes) - 1 <= 16 < len(tasks) - 1  # chunks of neighbours meet a few others
        for c in range(len(classes) - 1):
            members = [np.unique(nodes[order[tasks[k]:tasks[k + 1]]]) for k in range(classes[c], classes[c + 1])]
            joined = np.concatenate(members)
            assert len(np.unique(joined)) == len(joined)  # no vertex in two chunks of a class
        low = nodes.min(axis=1)[order]
        for k in range(len(tasks) - 1):
            assert np.all(np.diff(low[tasks[k]:tasks[k + 1]]) >= 0)  # a chunk in order of its lowest vertex


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
    from tailor.integrators.cg import inverse_3x3

    rng = np.random.default_rng(7)
    a = rng.standard_normal((500, 3, 3))
    spd = a @ a.transpose(0, 2, 1) + np.eye(3) * np.logspace(-6, 3, 500)[:, None, None]  # mass + Δt²·K
    inv = inverse_3x3(spd)
    assert np.allclose(np.einsum("kij,kjl->kil", spd, inv), np.eye(3), atol=1e-6)
    assert np.allclose(inv, np.linalg.inv(spd), rtol=1e-8, atol=1e-12 * np.abs(np.linalg.inv(spd)).max())


def test_elements_pinned_at_rest_are_left_out_and_change_nothing_the_solve_keeps(deformed):
    """Where much of the cloth is pinned at rest (an outfit's inner garment held while the next one
    sews) its elements are skipped: the assembly leaves them out, yet every block of a free row and
    all of K·v equal the full assembly's, and an implicit step from there ends bit for bit where it
    does with every element assembled."""
    from dataclasses import replace
    from unittest import mock

    from tailor.forces.jacobian import implicit_blocks
    from tailor.integrators import ImplicitEuler

    model, state = deformed
    x = state.x
    pinned = x[:, 0] < np.median(x[:, 0])
    v = state.v.copy()
    v[pinned] = 0.0
    held = model.with_pins(np.flatnonzero(pinned))
    start = held.state(x, v)
    pattern = SparsePattern(held)
    order, _, _ = pattern.colors_moving(0, pinned)
    faces = np.asarray(held.faces)
    still_faces = np.flatnonzero(pinned[faces].all(axis=1))
    assert len(still_faces) > 100 and np.array_equal(np.sort(np.concatenate([order, still_faces])), np.arange(len(faces)))
    dt = 0.02
    blocks, kv = implicit_blocks(held, start, pattern, dt)
    free = replace(held, vertex_pinned=np.zeros_like(pinned))
    full, full_kv = implicit_blocks(free, start, SparsePattern(free), dt)
    rows = ~pinned[pattern.block_rows]
    assert np.array_equal(blocks[rows], full[rows]) and np.array_equal(kv, full_kv)
    assert not np.array_equal(blocks, full)  # the pinned rows' blocks were left out

    def step():
        return ImplicitEuler().step(held, start, dt, lambda m, s: internal_forces(m, s)).state

    skipped = step()
    with mock.patch.object(SparsePattern, "colors_moving", lambda self, group, still: self.colors(group)):
        assembled = step()
    assert np.array_equal(skipped.x, assembled.x) and np.array_equal(skipped.v, assembled.v)
