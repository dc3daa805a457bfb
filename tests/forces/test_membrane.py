"""Carignan's elastic surface on triangles: energy/force consistency, invariances, constitutive law."""

import numpy as np
import pytest

from conftest import assert_minus_gradient, sheet
from tailor.fabric import preset
from tailor.forces import damping_forces, dissipation, stretch_energy, stretch_forces
from tailor.forces.membrane import green_strain

RNG = np.random.default_rng(7)


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r)) * (1 if np.linalg.det(q * np.sign(np.diag(r))) > 0 else -1)


@pytest.fixture(scope="module")
def patch():
    model, x0 = sheet(20, 20, 0.04, "jersey", vertical=False)  # anisotropic: warp 8 %, weft 15 %
    return model, x0


def test_rest_state_has_no_force(patch):
    model, x0 = patch
    f = stretch_forces(model, model.state(x0))
    assert np.abs(f).max() < 1e-12 * model.face_stretch_warp.max()


def test_rigid_motion_no_force_no_dissipation(patch):
    model, x0 = patch
    rot = random_rotation(RNG)
    x = x0 @ rot.T + [0.3, -1.0, 2.0]
    omega, u = RNG.normal(size=3), RNG.normal(size=3)
    v = np.cross(omega, x) + u  # any rigid velocity field
    state = model.state(x, v)
    scale = model.face_stretch_warp.max()
    assert np.abs(stretch_forces(model, state)).max() < 1e-10 * scale
    assert np.abs(damping_forces(model, state)).max() < 1e-10 * model.face_damping_warp.max()
    assert dissipation(model, state) < 1e-20


def test_force_is_minus_energy_gradient(patch):
    model, x0 = patch
    state = model.state(x0 + RNG.normal(0, 0.004, x0.shape))
    assert_minus_gradient(stretch_energy, stretch_forces, model, state)


def test_damping_is_minus_dissipation_gradient_in_velocity(patch):
    model, x0 = patch
    state = model.state(x0 + RNG.normal(0, 0.004, x0.shape), RNG.normal(0, 0.3, x0.shape))
    assert_minus_gradient(dissipation, damping_forces, model, state, wrt="v", eps=1e-6)


@pytest.mark.parametrize("forces", [stretch_forces, damping_forces])
def test_internal_forces_conserve_momentum(patch, forces):
    model, x0 = patch
    state = model.state(x0 + RNG.normal(0, 0.01, x0.shape), RNG.normal(0, 1.0, x0.shape))
    f = forces(model, state)
    scale = np.abs(f).sum()
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * scale  # linear
    assert np.abs(np.cross(state.x, f).sum(axis=0)).max() < 1e-12 * scale  # angular


def test_uniaxial_tension_follows_the_green_strain_law():
    fabric = preset("cotton")
    model, x0 = sheet(10, 10, 0.02, fabric, vertical=False, grain=0)  # warp along x
    s = 1.05
    x = x0 * [s, 1.0, 1.0]
    e11, e22, e12 = green_strain(model, x)
    assert np.allclose(e11, 0.5 * (s * s - 1)) and np.allclose(e22, 0) and np.allclose(e12, 0, atol=1e-12)
    f = stretch_forces(model, model.state(x))
    right = model.rest_uv[:, 0] > 0.1 - 1e-9
    # first Piola traction: s·η·E11 per unit rest width, over a 10 cm edge
    expected = s * model.face_stretch_warp[0] * 0.5 * (s * s - 1) * 0.10
    assert f[right, 0].sum() == pytest.approx(-expected, rel=1e-9)
    assert f[right, 1].sum() == pytest.approx(0, abs=1e-9 * expected)


@pytest.mark.parametrize("c", [1.0, 0.3, 0.05])
def test_compression_is_softened_by_the_requested_fraction(c):
    from dataclasses import replace

    model, x0 = sheet(10, 10, 0.02, "cotton", vertical=False, grain=0)
    model = replace(model, compression=c)
    right = model.rest_uv[:, 0] > 0.1 - 1e-9
    pull = stretch_forces(model, model.state(x0 * [1.04, 1.0, 1.0]))[right, 0].sum()
    push = stretch_forces(model, model.state(x0 * [0.96, 1.0, 1.0]))[right, 0].sum()
    # first Piola traction s·k·E per unit rest width: tension keeps η, compression gets c·η
    e_pull, e_push = 0.5 * (1.04**2 - 1), 0.5 * (0.96**2 - 1)
    assert pull == pytest.approx(-1.04 * model.face_stretch_warp[0] * e_pull * 0.10, rel=1e-9)
    assert push == pytest.approx(-0.96 * c * model.face_stretch_warp[0] * e_push * 0.10, rel=1e-9)
    state = model.state(x0 * [0.97, 1.02, 1.0] + RNG.normal(0, 0.002, x0.shape))
    assert_minus_gradient(stretch_energy, stretch_forces, model, state)


def test_warp_and_weft_have_their_own_stiffness():
    jersey = preset("jersey")  # stretch 8 % warp, 15 % weft
    model, x0 = sheet(10, 10, 0.02, jersey, vertical=False, grain=90)  # warp along y
    pull_y = stretch_energy(model, model.state(x0 * [1.0, 1.02, 1.0]))
    pull_x = stretch_energy(model, model.state(x0 * [1.02, 1.0, 1.0]))
    assert pull_y / pull_x == pytest.approx(model.face_stretch_warp[0] / model.face_stretch_weft[0], rel=1e-9)
    assert model.face_stretch_warp[0] > model.face_stretch_weft[0]


def test_kawabata_stress_lies_on_the_measured_curve():
    from tailor.fabric import KAWABATA_FABRICS
    from tailor.forces import internal_forces

    fabric = KAWABATA_FABRICS["bottino_a"]
    for curves in (fabric.kawabata, fabric.kawabata.linearised()):
        model, x0 = sheet(10, 10, 0.02, fabric.with_values(kawabata=curves), vertical=False, grain=0, damping=0.0)
        s = 1.03
        f = internal_forces(model, model.state(x0 * [s, 1.0, 1.0]))
        e11 = 0.5 * (s * s - 1)
        xs = [0.0] + [p[0] for p in curves.tensile_warp]
        ys = [0.0] + [p[1] for p in curves.tensile_warp]
        right = model.rest_uv[:, 0] > 0.1 - 1e-9
        assert -f[right, 0].sum() == pytest.approx(s * np.interp(e11, xs, ys) * 0.10, rel=1e-9)


def test_kawabata_curves_from_a_pattern_file():
    from conftest import doc_with, rect_panel
    from tailor.io import pattern_from_dict

    kes = {"tensile_warp": [[1, 20], [3, 150]], "tensile_weft": [[2, 20]], "shear": [[5, 3]], "bending": [[1, 1e-5]]}
    p = pattern_from_dict(doc_with({"a": rect_panel(10, 10)}, fabric={"preset": "bottino_a", "kawabata": kes}))
    c = p.fabric.kawabata
    assert c.tensile_warp == ((0.01, 20.0), (0.03, 150.0)) and c.shear[0][0] == pytest.approx(np.radians(5))
    assert c.bending == ((100.0, 1e-5),)
    bad = {**kes, "tensile_warp": [[3, 150], [1, 20]]}
    from tailor.errors import PatternError

    with pytest.raises(PatternError, match=r"fabric.kawabata: .*tensile_warp: deformations must increase"):
        pattern_from_dict(doc_with({"a": rect_panel(10, 10)}, fabric={"kawabata": bad}), source="k.json")


def test_face_stretch_is_the_largest_principal_stretch(patch):
    """The compiled per-face stretch (the implicit step's overstretch check) is √ of FᵀF's larger eigenvalue."""
    from tailor.forces.membrane import deformation_gradient, face_stretch

    model, x0 = patch
    x = x0 * np.array([1.3, 0.9, 1.0]) + np.random.default_rng(3).normal(0, 0.002, x0.shape)
    f = deformation_gradient(model, x)
    expect = np.sqrt(np.linalg.eigvalsh(np.einsum("fki,fkj->fij", f, f))[:, -1])
    assert np.allclose(face_stretch(model, x), expect, rtol=1e-12)
    assert face_stretch(model, x).max() > 1.25  # the 1.3 stretch along x is seen
