"""Tearing splits the mesh, conserving mass and momentum; the brush cuts holes; wind behaves."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import tailor
from tailor.forces.external import air_forces
from tailor.forces.wind import Wind
from tailor.io.obj import read_obj, write_obj
from tailor.model import AIR_DENSITY, build_model
from tailor.scenes import grid
from tailor.tearing import Cut, TearableCloth, boundary_loops, simulate_tearing

COTTON = tailor.preset("cotton")


def components(faces, n):
    a = coo_matrix((np.ones(faces.size), (faces.ravel(), np.roll(faces, 1, axis=1).ravel())), shape=(n, n))
    return connected_components(a)[0]


def assert_valid(faces):
    """No degenerate or duplicate triangles; consistently oriented (each directed edge used once)."""
    assert (faces[:, 0] != faces[:, 1]).all() and (faces[:, 1] != faces[:, 2]).all() and (faces[:, 0] != faces[:, 2]).all()
    assert len(np.unique(np.sort(faces, axis=1), axis=0)) == len(faces)
    directed = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)
    assert len(np.unique(directed, axis=0)) == len(directed)


def strip(tear=0.25, elastic="membrane"):
    mesh = grid(0.3, 0.1, 31, 11)
    left = np.flatnonzero(mesh.uv[:, 0] < 1e-9)
    right = np.flatnonzero(mesh.uv[:, 0] > 0.3 - 1e-9)
    cloth = TearableCloth(mesh, lambda m, pin: build_model(m, COTTON, gravity=(0, 0, 0), pinned=pin, elastic=elastic),
                          tear_strain=tear, pinned=np.r_[left, right])
    state = cloth.model.state(np.c_[mesh.uv, np.zeros(mesh.vertex_count)])
    return cloth, state, right


@pytest.mark.parametrize("elastic,intact_frame,first_tear", [
    ("membrane", 9, (0.364, 0.386)),  # uniform strain: it tears when the strip is stretched 25 %
    ("springs", 6, (0.26, 0.386)),  # a spring net strains most beside its pinned ends: it tears there first
])
def test_a_strip_pulled_beyond_its_tear_strain_splits_in_two_conserving_mass(elastic, intact_frame, first_tear):
    """Carignan's membrane and Walker's mass-spring net tear by the same criterion (Walker's tearing)."""
    cloth, state, right = strip(elastic=elastic)
    state.v[right, 0] = 0.2  # pulled at 20 cm/s: 25 % after 0.375 s
    mass = cloth.model.vertex_mass.sum()
    before = None
    for frame, _ in simulate_tearing(cloth, state, duration=0.8, fps=25):
        if frame == intact_frame:
            before = components(cloth.mesh.faces, cloth.mesh.vertex_count)
    assert before == 1  # not yet torn (frame 9 = 0.36 s: the membrane is stretched 24 %)
    assert cloth.tears > 0 and first_tear[0] <= cloth.events[0][0] <= first_tear[1]
    assert components(cloth.mesh.faces, cloth.mesh.vertex_count) == 2
    assert cloth.model.vertex_mass.sum() == pytest.approx(mass, rel=1e-12)
    assert_valid(cloth.mesh.faces)
    # the crack runs across the strip: the two pieces hang on the two pinned ends
    labels = connected_components(coo_matrix((np.ones(cloth.mesh.faces.size), (cloth.mesh.faces.ravel(),
                                  np.roll(cloth.mesh.faces, 1, axis=1).ravel())), shape=(cloth.mesh.vertex_count,) * 2))[1]
    pinned = np.flatnonzero(cloth.pinned)
    assert len(np.unique(labels[pinned])) == 2


def test_splitting_conserves_linear_momentum_exactly():
    cloth, state, _ = strip()
    rng = np.random.default_rng(3)
    state.x[:, 0] *= 1.3  # 30 % along the strip, beyond the tear strain
    state.x[:, 2] += 0.01 * rng.standard_normal(len(state.x))
    state.v[:] = rng.standard_normal(state.v.shape)
    m0 = np.asarray(cloth.model.vertex_mass)
    p0, total0 = m0 @ state.v, m0.sum()
    n0 = cloth.mesh.vertex_count
    splits = 0
    for _ in range(12):  # a crack across the strip, one edge per check
        new = cloth.tear(state)
        assert new is not None
        state = new
        splits = cloth.mesh.vertex_count - n0
    assert splits > 0
    m1 = np.asarray(cloth.model.vertex_mass)
    np.testing.assert_allclose(m1 @ state.v, p0, rtol=1e-12, atol=1e-15)
    assert m1.sum() == pytest.approx(total0, rel=1e-13)
    np.testing.assert_array_equal(state.x[n0:], state.x[cloth.origin[n0:]])  # copies sit where their vertex was
    assert_valid(cloth.mesh.faces)


def test_a_brush_cut_leaves_a_new_boundary_loop_in_the_obj(tmp_path):
    mesh = grid(1.0, 1.0, 21)
    cloth = TearableCloth(mesh, lambda m, pin: build_model(m, COTTON, gravity=(0, 0, 0), pinned=pin), tear_strain=0.0)
    x0 = np.c_[mesh.uv - 0.5, np.zeros(mesh.vertex_count)]
    state = cloth.model.state(x0)
    assert boundary_loops(mesh.faces) == 1
    frames = list(simulate_tearing(cloth, state, duration=0.2, fps=25,
                                   cuts=[Cut(0.1, [(0.0, 0.0, 0.0)], 0.15)]))
    state = frames[-1][1]
    write_obj(tmp_path / "cut.obj", state.x, cloth.mesh.faces, uv=cloth.mesh.uv)
    back = read_obj(tmp_path / "cut.obj")
    assert boundary_loops(back.faces) == 2
    assert len(back.faces) < len(mesh.faces) and components(back.faces, len(back.vertices)) == 1
    centroids = back.vertices[back.faces].mean(axis=1)
    assert np.linalg.norm(centroids[:, :2], axis=1).min() > 0.15  # the disc is gone
    assert_valid(back.faces)
    # a slit along a polyline
    cut = Cut(0.0, [(-0.3, 0.0, 0.0), (0.3, 0.0, 0.0)], 0.03)
    assert len(cut.samples()) > 10
    with pytest.raises(ValueError):
        Cut(0.0, [(0, 0, 0)], 0.0)


def test_a_separating_cut_splits_the_cloth_without_losing_any():
    """Scissors: the edges along the polyline break; no triangle goes, mass and momentum are exact."""
    mesh = grid(1.0, 1.0, 21)
    cloth = TearableCloth(mesh, lambda m, pin: build_model(m, COTTON, gravity=(0, 0, 0), pinned=pin), tear_strain=0.0)
    state = cloth.model.state(np.c_[mesh.uv - 0.5, np.zeros(mesh.vertex_count)])
    state.v[:] = np.random.default_rng(5).standard_normal(state.v.shape)
    m0 = np.asarray(cloth.model.vertex_mass)
    p0 = m0 @ state.v
    # a slit inside the cloth: a new boundary loop (its ends stay joined)
    state = cloth.cut(state, Cut(0.0, [(-0.3, 0.013, 0.0), (0.3, 0.013, 0.0)], 0.06, separate=True))
    assert cloth.mesh.face_count == mesh.face_count and boundary_loops(cloth.mesh.faces) == 2
    assert components(cloth.mesh.faces, cloth.mesh.vertex_count) == 1
    split = cloth.mesh.vertex_count - mesh.vertex_count
    assert 10 <= split <= 14  # 0.6 m of slit at 5 cm spacing: 11 vertices inside it split, its two ends do not
    m1 = np.asarray(cloth.model.vertex_mass)
    assert m1.sum() == pytest.approx(m0.sum(), rel=1e-13)
    np.testing.assert_allclose(m1 @ state.v, p0, rtol=1e-12, atol=1e-14)
    assert_valid(cloth.mesh.faces)
    # across the whole cloth, and on along a bend: two pieces
    state = cloth.cut(state, Cut(0.0, [(0.013, -0.6, 0.0), (0.013, 0.2, 0.0), (0.6, 0.3, 0.0)], 0.06, separate=True))
    assert components(cloth.mesh.faces, cloth.mesh.vertex_count) == 2
    assert cloth.mesh.face_count == mesh.face_count
    assert_valid(cloth.mesh.faces)
    with pytest.raises(ValueError, match="two points"):
        Cut(0.0, [(0, 0, 0)], 0.1, separate=True)


def flag(n=11):
    mesh = grid(1.0, 0.6, n, max(3, round(0.6 * n)))
    pole = np.flatnonzero(mesh.uv[:, 0] < 1e-9)
    x0 = np.c_[mesh.uv[:, 0], np.zeros(mesh.vertex_count), mesh.uv[:, 1] + 1.0]  # in the x-z plane
    return mesh, pole, x0


def test_zero_wind_changes_nothing():
    mesh, pole, x0 = flag()
    model = build_model(mesh, COTTON, air_density=AIR_DENSITY, pinned=pole)
    runs = []
    for wind in (None, Wind(speed=0.0, direction=(0, 1, 0), turbulence=0.5)):
        cloth = TearableCloth(mesh, lambda m, pin: build_model(m, COTTON, air_density=AIR_DENSITY, pinned=pin),
                              tear_strain=0.0, pinned=pole)
        runs.append([s.x.copy() for _, s in simulate_tearing(cloth, model.state(x0), duration=0.2, wind=wind)])
    np.testing.assert_array_equal(np.stack(runs[0]), np.stack(runs[1]))
    assert np.abs(runs[0][-1] - x0).max() > 1e-3  # it did move (gravity)


def test_the_flags_normal_force_grows_with_the_square_of_wind_speed():
    mesh, pole, x0 = flag()
    model = build_model(mesh, COTTON, air_density=AIR_DENSITY, pinned=pole)
    state = model.state(x0)
    area = 0.6
    normal = []
    for speed in (2.0, 4.0, 8.0, 16.0):
        f = air_forces(model, state, Wind(speed=speed, direction=(0.6, 0.8, 0.0), turbulence=0.0))
        normal.append(f[:, 1].sum())  # the flag's normal is ±y; wind along (0.6, 0.8, 0)
    normal = np.abs(normal)
    np.testing.assert_allclose(normal[1:] / normal[:-1], 4.0, rtol=1e-9)
    # and its size is the dynamic pressure of the normal wind component on the flag's area
    np.testing.assert_allclose(normal[0], 0.5 * AIR_DENSITY * 1.0 * (0.8 * 2.0) ** 2 * area, rtol=1e-6)


def test_fabric_tear_strain_from_presets_and_files():
    assert tailor.preset("cotton").tear_strain == 0.25 and tailor.preset("jersey").tear_strain == 1.0
    doc = {"fabric": {"preset": "silk", "tear_strain": 40},
           "pattern": {"panels": {"p": {"vertices": [[0, 0], [10, 0], [10, 10], [0, 10]],
                                        "edges": [{"endpoints": [i, (i + 1) % 4]} for i in range(4)]}}}}
    assert tailor.pattern_from_dict(doc).fabric.tear_strain == pytest.approx(0.4)
    doc["fabric"]["tear_strain"] = -1
    with pytest.raises(tailor.PatternError, match="tear_strain"):
        tailor.pattern_from_dict(doc, source="f.json")


def test_wind_at_a_large_implicit_step_is_stable_because_drag_is_implicit():
    # light silk in a 10 m/s wind: explicit drag's limit m/(ρ_air·C_d·|v_n|·A) is ~4 ms, the step 40 ms
    from tailor.sim import max_stretch

    mesh, pole, x0 = flag()
    silk = tailor.preset("silk")
    cloth = TearableCloth(mesh, lambda m, pin: build_model(m, silk, air_density=AIR_DENSITY, pinned=pin),
                          tear_strain=0.0, pinned=pole)
    frames = [s.x.copy() for _, s in simulate_tearing(cloth, cloth.model.state(x0), duration=1.0, dt=0.04,
                                                     wind=Wind(speed=10.0, direction=(1, 0.5, 0), turbulence=0.3))]
    assert np.isfinite(frames[-1]).all() and max_stretch(cloth.model, frames[-1]) < 2.0  # explicit drag: 63 m/s, stopped
    assert np.abs(frames[-1][:, 1]).max() > 0.05  # it was blown out of its plane


def test_air_damping_is_the_lumped_velocity_derivative_of_the_air_force():
    from tailor.forces.external import air_damping

    mesh, pole, x0 = flag()
    model = build_model(mesh, COTTON, air_density=AIR_DENSITY)
    rng = np.random.default_rng(1)
    state = model.state(x0 + 0.02 * rng.standard_normal(x0.shape), rng.standard_normal(x0.shape))
    wind = np.array([3.0, 1.0, -0.5])
    d = air_damping(model, state, wind)
    h = 1e-6
    for k in range(3):  # the same velocity change on every vertex: Δf_i = −(Σ_j ∂f_i/∂v_j)·Δv = −D_i·Δv
        e = np.zeros(3)
        e[k] = h
        plus, minus = model.state(state.x, state.v + e), model.state(state.x, state.v - e)
        df = (air_forces(model, plus, wind) - air_forces(model, minus, wind)) / (2 * h)
        np.testing.assert_allclose(df, -d[:, :, k], rtol=1e-5, atol=1e-9)
    assert (np.linalg.eigvalsh(d) > -1e-15).all()  # positive semi-definite: it only damps


def test_wind_ramps_from_calm_to_full_strength():
    w = Wind(speed=10.0, direction=(0, 1, 0), turbulence=0.0, ramp=2.0)
    pts = np.zeros((2, 3))
    np.testing.assert_allclose(w(pts, 0.0), 0.0)
    np.testing.assert_allclose(w(pts, 1.0), [[0, 5.0, 0]] * 2)
    np.testing.assert_allclose(w(pts, 3.0), [[0, 10.0, 0]] * 2)
    gusty = Wind(speed=10.0, turbulence=0.3, ramp=2.0)
    np.testing.assert_allclose(gusty(pts, 1.0), 0.5 * Wind(speed=10.0, turbulence=0.3)(pts, 1.0))
