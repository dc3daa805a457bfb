"""Self-collision (Carignan Eq. 5–8): layers never pass through each other, momentum is exact."""

import numpy as np
import pytest

from tailor.collide import SelfCollider, self_intersections
from tailor.scenes import cloth_model, floor, rectangle, run_scene, sphere


def stacked(gap, lower_z, *, offset=0.03, size=0.4, resolution=0.025, fabric="cotton"):
    """Two square panels, one ``gap`` above the other, the upper shifted by ``offset``."""
    mesh, model = cloth_model([rectangle(size, size, "lower"), rectangle(size, size, "upper")], fabric, resolution)
    x0 = np.zeros((model.vertex_count, 3))
    for pi, z in ((0, lower_z), (1, lower_z + gap)):
        ids = mesh.panel_vertices(pi)
        x0[ids, :2] = mesh.uv[ids] - 0.5 * size + (offset if pi else 0.0)
        x0[ids, 2] = z
    return model, x0


def panel_vertices(model, panel):
    mask = np.zeros(model.vertex_count, bool)
    mask[np.unique(model.faces[model.face_panel == panel])] = True
    return mask


def intersections(frames, faces):
    return [len(self_intersections(f, faces)) for f in frames]


@pytest.mark.parametrize("mode", ["on", "auto"])
def test_panel_dropped_on_a_panel_on_the_floor_never_passes_through(mode):
    model, x0 = stacked(0.05, 0.004)
    result = run_scene(model, x0, body=floor(), duration=0.6, self_collision=mode)
    assert result.report["self_collision"]["contacts"] > 0
    assert intersections(result.frames, model.faces) == [0] * len(result.frames)
    upper = panel_vertices(model, 1)
    x = result.frames[-1]
    assert x[upper, 2].mean() > x[~upper, 2].mean() + 0.002  # resting on the lower panel, not in it


def test_without_self_collision_the_upper_panel_falls_into_the_lower():
    model, x0 = stacked(0.05, 0.004)
    result = run_scene(model, x0, body=floor(), duration=0.6, self_collision="off")
    upper = panel_vertices(model, 1)
    x = result.frames[-1]
    assert abs(x[upper, 2].mean() - x[~upper, 2].mean()) < 0.001  # both flat on the floor, one inside the other


def test_colliding_pair_in_free_space_conserves_linear_momentum():
    model, x0 = stacked(0.004, 0.0, offset=0.0, size=0.1, resolution=0.02)
    v0 = np.zeros_like(x0)
    lower = panel_vertices(model, 0)
    v0[lower, 2], v0[~lower, 2] = 0.5, -1.0  # head on, unequal speeds
    state = model.state(x0.copy(), v0)
    mass = np.asarray(model.vertex_mass)
    collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on")
    before = (mass[:, None] * state.v).sum(axis=0)
    count = collider.respond(1.0 / mass, state, 0.01)
    after = (mass[:, None] * state.v).sum(axis=0)
    assert count > 0
    assert np.abs(after - before).max() <= 1e-9 * np.abs(mass[:, None] * v0).sum()
    # perfectly inelastic along the normal: nothing approaches any more
    assert state.v[lower, 2].min() >= state.v[~lower, 2].max() - 1e-9
    # and the centre of mass did not move
    np.testing.assert_allclose((mass[:, None] * state.x).sum(0), (mass[:, None] * x0).sum(0), atol=1e-12)


def test_auto_skips_flat_cloth_far_from_itself():
    mesh, model = cloth_model([rectangle(0.6, 0.6, "sheet")], "cotton", 0.03)
    x0 = np.column_stack([mesh.uv - 0.3, np.full(model.vertex_count, 0.5)])
    collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="auto")
    assert len(collider.active_faces(x0)) == 0
    folded = x0.copy()
    right = folded[:, 0] > 0.0
    folded[right, 0] = -folded[right, 0]  # folded in two, 1 cm apart
    folded[right, 2] += 0.01
    assert len(collider.active_faces(folded)) > 0


def test_two_panels_on_a_sphere_intersect_far_less_than_without():
    model, x0 = stacked(0.02, 0.125)
    counts = {}
    for mode in ("off", "on"):
        result = run_scene(model, x0, body=sphere(0.12), duration=0.4, self_collision=mode)
        counts[mode] = intersections(result.frames[-1:], model.faces)[0]
    assert counts["off"] > 300
    assert counts["on"] < 0.2 * counts["off"]


def test_strip_piling_up_on_the_floor_is_sub_stepped_instead_of_tangling():
    mesh, model = cloth_model([rectangle(0.1, 0.8, "strip")], "jersey", 0.025)
    x0 = np.column_stack([mesh.uv[:, 0], 0.02 * np.sin(12 * mesh.uv[:, 1]), mesh.uv[:, 1] + 0.01])
    counts = {}
    for mode in ("off", "on"):
        result = run_scene(model, x0, body=floor(), duration=0.6, self_collision=mode)
        counts[mode] = intersections(result.frames[-1:], model.faces)[0]
        if mode == "on":
            assert result.report["self_collision"]["max_substeps"] > 1  # its top falls several thicknesses a step
    assert counts["off"] > 500
    assert counts["on"] < 0.3 * counts["off"]
