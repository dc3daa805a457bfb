"""Untangling (`tailor/collide/untangle.py`): a vertex poked through cloth goes back to its own side,
pinned cloth stays, and a tangle the local pushes cannot improve is left exactly as it was."""

import sys

import numpy as np
import pytest

from tailor.collide import edge_crossings, untangle
from tailor.collide.untangle import cut_regions

untangle_module = sys.modules["tailor.collide.untangle"]
from tailor.scenes import grid


def _two_sheets(poke):
    """A 5 × 5 sheet 2 mm above a 5 × 5 sheet, vertex 12 (the upper one's centre) pushed ``poke`` m down."""
    mesh = grid(0.08, 0.08, 5)
    flat = np.c_[mesh.uv - 0.04, np.zeros(mesh.vertex_count)]
    lower = flat + [0.003, 0.004, 0.0]  # offset: the poked vertex meets a triangle's interior
    upper = flat + [0.0, 0.0, 0.002]
    upper[12, 2] -= poke
    x = np.vstack([lower, upper])
    faces = np.vstack([mesh.faces, mesh.faces + mesh.vertex_count])
    return x, faces


def test_a_vertex_poked_through_a_sheet_goes_back_to_its_own_side():
    x, faces = _two_sheets(0.006)  # 4 mm below the lower sheet
    assert len(edge_crossings(x, faces)) > 0
    before = x.copy()
    found, left = untangle(x, faces, np.ones(len(x)), 0.001)
    assert found > 0 and left == 0 and len(edge_crossings(x, faces)) == 0
    assert x[25 + 12, 2] > x[12, 2]  # the poked vertex above the lower sheet's centre again
    assert np.linalg.norm(x - before, axis=1).max() < 0.006  # a nudge, not a jump


def test_pinned_vertices_stay_and_the_free_side_takes_the_whole_push():
    x, faces = _two_sheets(0.006)
    inv_mass = np.r_[np.zeros(25), np.ones(25)]  # the lower sheet pinned
    before = x.copy()
    found, left = untangle(x, faces, inv_mass, 0.001)
    assert found > 0 and left == 0
    assert np.array_equal(x[:25], before[:25])
    assert x[25 + 12, 2] == pytest.approx(0.001)  # the whole push: thickness above the pinned sheet


def test_crossings_among_vertices_held_still_alone_are_neither_looked_for_nor_undone():
    """An outfit's sewn garment is held still while the next sews over it: its own crossings (a sheet
    through a sheet, both still) can neither have been made since it was last looked at nor be
    undone; a moving sheet poked through a still one is found and pushed back as ever."""
    poke, poke_faces = _two_sheets(0.006)
    tangle, tangle_faces = _sheet_through_sheet()
    x = np.vstack([poke, tangle + [1.0, 0.0, 0.0]])
    faces = np.vstack([poke_faces, tangle_faces + len(poke)])
    still = np.ones(len(x), bool)
    still[25:50] = False  # the poked sheet moves
    every = edge_crossings(x, faces)
    among_still = still[every[:, :2]].all(axis=1) & still[faces[every[:, 2]]].all(axis=1)
    assert among_still.any() and (~among_still).any()
    got = edge_crossings(x, faces, still=still)
    assert {tuple(r) for r in got.tolist()} == {tuple(r) for r in every[~among_still].tolist()}
    found, left = untangle(x, faces, np.where(still, 0.0, 1.0), 0.001, still=still)
    assert found == int((~among_still).sum()) and left == 0
    assert len(edge_crossings(x, faces)) == int(among_still.sum())  # the still tangle as it was


def _sheet_through_sheet():
    # a sheet straight through another, edge-on: half of it on each side, no side to push to
    mesh = grid(0.1, 0.1, 6)
    a = np.c_[mesh.uv - 0.05, np.zeros(mesh.vertex_count)]
    b = np.c_[mesh.uv[:, 0] - 0.05 + 0.004, np.full(mesh.vertex_count, 0.003), mesh.uv[:, 1] - 0.05]  # upright
    return np.vstack([a, b]), np.vstack([mesh.faces, mesh.faces + mesh.vertex_count])


def test_a_tangle_local_pushes_cannot_improve_is_left_exactly_as_it_was(monkeypatch):
    x, faces = _sheet_through_sheet()
    count = len(edge_crossings(x, faces))
    assert count > 0
    before = x.copy()
    monkeypatch.setattr(untangle_module, "_slide_borders", lambda x, faces, im, th, crossings, edges, borders: crossings)
    found, left = untangle(x, faces, np.ones(len(x)), 0.001)
    assert found == left == count  # every crossing has a poked end on each side, or none: no push is tried
    assert np.array_equal(x, before)


def test_a_cut_reaching_a_border_is_unzipped_from_it_but_never_made_worse():
    """Where the cut meets a sheet's border the sheets are hooked: sliding off the border lowers the
    crossings (the cut through the middle stays), moving no vertex more than an edge (2 cm)."""
    x, faces = _sheet_through_sheet()
    before = x.copy()
    found, left = untangle(x, faces, np.ones(len(x)), 0.001)
    assert 0 < left < found and len(edge_crossings(x, faces)) == left
    assert np.linalg.norm(x - before, axis=1).max() <= 0.02 * np.sqrt(3)


def test_cloth_hooked_over_a_border_edge_goes_over_it():
    """A top tucked in a band crossing it just under its top edge while the top edge passes through
    the top (a tucked T-shirt at the band's side seam): no local push can tell a side, the border
    slide takes the top over the band's edge; the band, attached, stays."""
    band = grid(0.1, 0.04, 6, 3)  # upright, its top border at z = 4 cm
    x = np.vstack([np.c_[band.uv[:, 0] - 0.05, np.zeros(band.vertex_count), band.uv[:, 1]],
                   [[0.0, -0.005, 0.03], [0.0, 0.005, 0.05], [0.03, 0.002, 0.045]]])  # inside below, outside above
    n = band.vertex_count
    faces = np.vstack([band.faces, [[n, n + 1, n + 2]]])
    crossings = edge_crossings(x, faces)
    assert len(crossings) == 2 and {tuple(sorted(c[:2])) for c in crossings} >= {(n, n + 1)}
    before = x.copy()
    found, left = untangle(x, faces, np.r_[np.zeros(n), np.ones(3)], 0.001)
    assert (found, left) == (2, 0) and len(edge_crossings(x, faces)) == 0
    assert np.array_equal(x[:n], before[:n])
    assert np.all(x[n:, 2] > before[n:, 2])  # up, over the band's top edge


def test_the_contact_pipeline_untangles_and_self_collision_then_keeps_the_new_sides():
    # two 10 cm squares 3 mm apart, a vertex of the upper one 4 mm through the lower one for a step:
    # untangled, the self-collision pass must take the new sides as the ones to keep, not push back
    from tailor.contact import ContactPipeline
    from tailor.integrators import make_integrator
    from tailor.scenes import cloth_model, rectangle
    from tailor.sim import Stepper

    mesh, model = cloth_model([rectangle(0.1, 0.1, "lower"), rectangle(0.1, 0.1, "upper")], "cotton", 0.02,
                              air_density=0.0)
    upper = np.asarray(mesh.vertex_panel) == 1
    x = np.c_[model.rest_uv - model.rest_uv.mean(axis=0), np.zeros(model.vertex_count)]
    x[upper] += [0.003, 0.004, 0.003]
    inner = np.flatnonzero(upper)[np.argmin(np.linalg.norm(x[upper, :2] - [0.003, 0.004], axis=1))]
    x[inner, 2] = -0.004
    pipe = ContactPipeline(None, None, thickness=0.001, friction=0.4, self_collision="on")
    stepper = Stepper(make_integrator("implicit"), contacts=pipe, forces=lambda m, s: np.zeros_like(s.x))
    state = stepper.step(model, model.state(x), 0.005)  # the self-collision pass learns the crossed sides
    assert len(edge_crossings(state.x, model.faces))
    found, left = pipe.untangle(model, state)
    assert found > 0 and left == 0
    for _ in range(5):
        state = stepper.step(model, state, 0.005)
        assert len(edge_crossings(state.x, model.faces)) == 0
    lower = np.flatnonzero(~upper)
    below = lower[np.argmin(np.linalg.norm(state.x[lower, :2] - state.x[inner, :2], axis=1))]
    assert state.x[inner, 2] > state.x[below, 2]  # above the lower sheet where it is, it stays


def _pocket(depth):
    """An 11 × 11 sheet 2 mm above a wider one, its middle 5 × 5 vertices pushed ``depth`` m down:
    a pocket through the lower sheet whose rim alone touches a crossing."""
    mesh = grid(0.1, 0.1, 11)
    upper = np.c_[mesh.uv - 0.05, np.full(mesh.vertex_count, 0.002)]
    lower_mesh = grid(0.16, 0.16, 9)
    lower = np.c_[lower_mesh.uv - 0.08 + [0.003, 0.004], np.zeros(lower_mesh.vertex_count)]
    ij = np.rint((upper[:, :2] + 0.05) / 0.01).astype(int)
    pocket = np.flatnonzero((abs(ij[:, 0] - 5) <= 2) & (abs(ij[:, 1] - 5) <= 2))
    upper[pocket, 2] -= depth
    x = np.vstack([lower, upper])
    faces = np.vstack([lower_mesh.faces, mesh.faces + lower_mesh.vertex_count])
    return x, faces, pocket + lower_mesh.vertex_count


def test_a_pocket_pushed_through_a_sheet_is_cut_off_by_its_crossings_and_goes_back():
    x, faces, pocket = _pocket(0.008)
    crossings = edge_crossings(x, faces)
    assert len(crossings) > 0
    regions = cut_regions(len(x), faces, crossings)
    assert any(set(pocket) <= set(r) for r in regions)  # the contour cuts the pocket off from its sheet
    found, left = untangle(x, faces, np.ones(len(x)), 0.001)
    assert found == len(crossings) and left == 0 and len(edge_crossings(x, faces)) == 0
    assert np.all(x[pocket, 2] > 0.0)  # above the lower sheet again


def test_a_pocket_is_beyond_the_local_pushes_alone(monkeypatch):
    # the case the global pass exists for: with no region ever small enough to move, the rim pushes
    # alone leave the pocket through
    import importlib
    monkeypatch.setattr(importlib.import_module("tailor.collide.untangle"), "MAX_REGION", 0.0)
    x, faces, _ = _pocket(0.008)
    found, left = untangle(x, faces, np.ones(len(x)), 0.001)
    assert left > 0 and len(edge_crossings(x, faces)) == left
