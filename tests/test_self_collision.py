"""Self-collision (Carignan Eq. 5–8): layers never pass through each other, momentum is exact."""

import numpy as np
import pytest

from tailor.collide import SelfCollider, self_intersections
from tailor.model import State
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


def sphere_drop(size, resolution, duration, mode):
    model, x0 = stacked(0.02, 0.125, size=size, resolution=resolution)
    result = run_scene(model, x0, body=sphere(0.12), duration=duration, self_collision=mode)
    return intersections(result.frames, model.faces)


def strip_drop(length, duration, mode):
    """A jersey strip held on end in a wave, dropped on the floor: it piles up and folds on itself."""
    mesh, model = cloth_model([rectangle(0.1, length, "strip")], "jersey", 0.025)
    x0 = np.column_stack([mesh.uv[:, 0], 0.02 * np.sin(12 * mesh.uv[:, 1]), mesh.uv[:, 1] + 0.01])
    result = run_scene(model, x0, body=floor(), duration=duration, self_collision=mode)
    return intersections(result.frames, model.faces), result.report["self_collision"]


@pytest.mark.parametrize("mode", ["on", "auto"])
def test_two_panels_dropped_on_a_sphere_never_intersect(mode):
    assert sphere_drop(0.3, 0.03, 0.3, mode) == [0] * 9
    if mode == "on":
        assert max(sphere_drop(0.3, 0.03, 0.3, "off")) > 100  # the scene does make them cross


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["on", "auto"])
def test_two_large_panels_dropped_on_a_sphere_never_intersect(mode):
    counts = sphere_drop(0.4, 0.025, 0.4, mode)
    assert counts == [0] * len(counts)


@pytest.mark.parametrize("mode", ["on", "auto"])
def test_strip_piling_up_on_the_floor_never_passes_through_itself(mode):
    counts, report = strip_drop(0.5, 0.4, mode)
    assert counts == [0] * len(counts)
    assert report["max_substeps"] > 1  # its top falls several thicknesses a step: sub-stepped
    if mode == "on":
        assert max(strip_drop(0.5, 0.4, "off")[0]) > 100  # without the pass it does


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["on", "auto"])
def test_long_strip_piling_up_on_the_floor_never_passes_through_itself(mode):
    counts, _ = strip_drop(0.8, 0.6, mode)
    assert counts == [0] * len(counts)


def test_edge_edge_crossing_is_caught():
    """Two triangles whose edges are about to cross with no vertex over the other triangle:
    only the edge–edge pair sees it, and its impulse conserves momentum."""
    faces = np.array([[0, 1, 2], [3, 4, 5]])
    x = np.array([[-0.01, 0.0, 0.0], [0.01, 0.0, 0.0], [0.005, 0.01, 0.0],  # lower: edge 0-1 along x
                  [0.0, -0.008, 0.004], [0.0, 0.012, 0.004], [0.0, -0.005, 0.01]])  # upper: edge 3-4 along y, 4 mm up
    v = np.zeros_like(x)
    v[3:, 2] = -1.0  # the upper triangle falls through the lower one's edge within the step
    counts = {}
    for edges in (False, True):
        state = State(x.copy(), v.copy())
        collider = SelfCollider(faces, np.zeros(2, int), x, thickness=0.003, mode="on", edges=edges)
        counts[edges] = collider.respond(np.ones(6), state, 0.01)
    assert counts[False] == 0 and counts[True] > 0
    # the closest points (middle of 0-1, 40 % along 3-4) now close only the 1 mm to the thickness this step
    closing = 0.5 * (state.v[0, 2] + state.v[1, 2]) - (0.6 * state.v[3, 2] + 0.4 * state.v[4, 2])
    assert closing <= (0.004 - 0.003) / 0.01 + 1e-6
    np.testing.assert_allclose(state.v.sum(axis=0), v.sum(axis=0), atol=1e-12)


def test_self_intersections_finds_crossings_and_ignores_neighbours():
    # a strip of two triangles sharing an edge, folded flat onto itself (neighbours: not counted),
    # and a separate triangle pierced by a third one just inside its edge (counted)
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1e-9, 0, 0], [0, 1, 1e-9]], float)
    assert len(self_intersections(v, [[0, 1, 2], [3, 1, 4]])) == 0
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    for inside in (0.3, 1e-3):  # the piercing edge passes this far inside the edge x = 0
        pierce = np.array([[inside, 0.2, -0.5], [inside, 0.2, 0.5], [inside + 0.5, 3.0, 0.0]])
        found = self_intersections(np.r_[tri, pierce], [[0, 1, 2], [3, 4, 5]])
        assert found.tolist() == [[0, 1]]
    apart = np.array([[-0.1, 0.2, -0.5], [-0.1, 0.2, 0.5], [-0.6, 3.0, 0.0]])  # outside the edge: no crossing
    assert len(self_intersections(np.r_[tri, apart], [[0, 1, 2], [3, 4, 5]])) == 0
    assert self_intersections(np.zeros((0, 3)), np.zeros((0, 3), int)).shape == (0, 2)


def test_edge_crossings_find_every_intersecting_triangle_pair_and_ignore_neighbours():
    from tailor.collide import edge_crossings
    from tailor.collide.grid import unique_edges

    tri = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert len(edge_crossings(np.r_[tri, [[1.0, 1.0, 0.0]]], [[0, 1, 2], [1, 3, 2]])) == 0  # neighbours
    pierce = np.array([[0.2, 0.2, -0.5], [0.3, 0.2, 0.5], [0.25, 0.6, 0.5]])  # through the first triangle
    found = edge_crossings(np.r_[tri, pierce], [[0, 1, 2], [3, 4, 5]])
    assert len(found) == 2 and set(found[:, 2]) == {0}  # its two edges from below pass through triangle 0
    apart = pierce + [0.0, 0.0, 1.0]
    assert len(edge_crossings(np.r_[tri, apart], [[0, 1, 2], [3, 4, 5]])) == 0
    rng = np.random.default_rng(3)  # random soups: a triangle pair intersects iff an edge of one crosses the other
    for _ in range(20):
        v = rng.uniform(0, 1, (6, 3))
        pairs = len(self_intersections(v, [[0, 1, 2], [3, 4, 5]]))
        assert (len(edge_crossings(v, [[0, 1, 2], [3, 4, 5]])) > 0) == (pairs > 0)
    soup = np.r_[tri, pierce, [[50.0, 50.0, 50.0]]]  # a vertex in no face: not in the grid
    kept = unique_edges(np.array([[0, 1, 2], [3, 4, 5]]), 7)  # a caller's kept edges: the same answer
    assert np.array_equal(edge_crossings(soup, [[0, 1, 2], [3, 4, 5]], kept), found)


def test_ignored_vertices_take_no_part_in_any_contact():
    """While sewing, the open seams and their neighbours are left free (their two sides must meet
    edge to edge); the rest of the panels keep each other out."""
    model, x0 = stacked(0.002, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    v0 = np.zeros_like(x0)
    v0[upper, 2] = -1.0  # the upper panel falls onto the lower one
    counts = []
    for ignored in (None, upper, ~upper, np.zeros(len(x0), bool)):
        state = model.state(x0.copy(), v0.copy())
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on")
        collider.ignore(ignored)
        counts.append(collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01))
    assert counts[0] > 0 and counts[1] == 0 and counts[2] == 0 and counts[3] == counts[0]


def test_ignored_vertices_far_from_every_candidate_change_nothing():
    """A free zone no candidate pair touches (here a flat panel 2 m away, which ``auto`` leaves out
    of the query) drops no pair of the rest: the contacts are those found with nothing ignored,
    kept pairs or not."""
    model, x0 = stacked(0.002, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    x0[~upper, 2] += 2.0
    top = upper & (x0[:, 0] > 0.0)  # the upper panel folded over on itself, its top half falling
    x0[top, 0] *= -1.0
    x0[top, 2] += 0.005
    v0 = np.zeros_like(x0)
    v0[top, 2] = -1.0
    counts = []
    lower = np.flatnonzero(~upper)
    for ignored, keep in ((None, None), (~upper, None), (~upper, np.column_stack([lower[:-1], lower[1:]]))):
        state = model.state(x0.copy(), v0.copy())
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="auto")
        collider.ignore(ignored, keep)
        counts.append(collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01))
    assert counts[0] > 0 and counts[1] == counts[0] and counts[2] == counts[0]


def test_an_open_seams_two_sides_keep_out_of_each_other_but_its_pairs_meet():
    """The neighbourhoods of an open seam's two sides are left free of the rest of the cloth, but
    not of each other: ignored with their pairs kept, a panel falling onto another is caught; the
    contacts are only those between kept pairs, so a kept pair's own vertices still meet freely."""
    model, x0 = stacked(0.002, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    v0 = np.zeros_like(x0)
    v0[upper, 2] = -1.0
    a, b = np.flatnonzero(~upper), np.flatnonzero(upper)
    everything = np.column_stack([np.repeat(a, len(b)), np.tile(b, len(a))])
    counts = []
    for keep in (None, everything, everything[1::2]):
        state = model.state(x0.copy(), v0.copy())
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on")
        collider.ignore(np.ones(len(x0), bool), keep)
        counts.append(collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01))
    assert counts[0] == 0 and counts[1] > 0 and 0 < counts[2] <= counts[1]


def test_the_open_seams_free_zone_keeps_each_pairs_two_neighbourhoods_apart():
    """ContactPipeline's zone round the open pairs: the pair vertices and their 1-rings are free,
    and each pair's ring on one side keeps contact with its ring on the other, its own two vertices
    left out (they must meet)."""
    from types import SimpleNamespace
    from tailor.contact import ContactPipeline

    faces = np.array([[0, 1, 3], [1, 4, 3], [1, 2, 4], [2, 5, 4], [6, 7, 8]])
    model = SimpleNamespace(pair_vertices=np.array([[0, 5]]), faces=faces, vertex_count=9)
    mask, kept = ContactPipeline(None, None, thickness=0.003, friction=0.1)._open_seams(model)
    assert mask.tolist() == [True] * 6 + [False] * 3
    assert sorted(map(tuple, kept.tolist())) == [(1, 2), (1, 4), (3, 2), (3, 4)]


def test_an_outfits_layers_put_an_outer_panel_caught_behind_an_inner_one_back_outside():
    """Side memory keeps a pair on the side it was on; an outfit's layers (Layers) keep the outer
    garment outside even where it already started the step a millimetre behind the inner one."""
    from tailor.collide import Layers

    model, x0 = stacked(-0.001, 0.0, offset=0.0, size=0.1, resolution=0.02)  # "upper" just under "lower"
    outer = panel_vertices(model, 1)
    tri = x0[model.faces]
    up = np.where(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2] > 0, 1, -1)
    v0 = np.zeros_like(x0)
    v0[outer, 2] = -0.2  # and moving further in
    ends = []
    for layers in (None, Layers(model.face_panel.astype(np.int64), up.astype(np.int8))):
        state = model.state(x0.copy(), v0.copy())
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on", layers=layers)
        momentum = (state.v * np.asarray(model.vertex_mass)[:, None]).sum(axis=0)
        assert collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01) > 0
        np.testing.assert_allclose((state.v * np.asarray(model.vertex_mass)[:, None]).sum(axis=0), momentum, atol=1e-12)
        ends.append(state.x[outer, 2].mean() - state.x[~outer, 2].mean())
    assert ends[0] < 0.0 < 0.002 < ends[1]


def test_cloth_loose_against_a_garment_keeps_its_side_there():
    """Layers.loose: a vertex loose against the other garment (a tucked top's cloth above the band)
    keeps the side it was on, as within one garment, and so does every face it is a corner of; the
    rest of the two garments keeps the layer rule."""
    from tailor.collide import Layers

    model, x0 = stacked(-0.001, 0.0, offset=0.0, size=0.1, resolution=0.02)  # "upper" just under "lower"
    outer = panel_vertices(model, 1)
    tri = x0[model.faces]
    up = np.where(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2] > 0, 1, -1).astype(np.int8)
    mid = np.median(x0[outer, 0])
    loose = np.where(outer & (x0[:, 0] < mid), 0, -1)  # the outer panel's left half, loose against panel 0
    v0 = np.zeros_like(x0)
    v0[outer, 2] = -0.2
    state = model.state(x0.copy(), v0.copy())
    layers = Layers(model.face_panel.astype(np.int64), up, loose)
    collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on", layers=layers)
    assert collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01) > 0
    z_inner = state.x[~outer, 2].mean()
    span = np.ptp(x0[outer, 0])
    left, right = outer & (x0[:, 0] < mid - 0.25 * span), outer & (x0[:, 0] > mid + 0.25 * span)
    assert state.x[left, 2].max() < z_inner < state.x[right, 2].min()  # behind as it was; kept outside


def test_edge_pairs_between_garments_point_out_of_the_inner_edge():
    """Layers.edge_directions: zero within a garment; between two, the inner edge's outward normal
    (pointing from it towards where the outer edge belongs), negated when edge a is the inner one."""
    from tailor.collide import Layers

    model, x0 = stacked(-0.004, 0.0, offset=0.0, size=0.1, resolution=0.02)  # panel 1 just under panel 0
    tri = x0[model.faces]
    up = np.where(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2] > 0, 1, -1).astype(np.int8)
    layers = Layers(model.face_panel.astype(np.int64), up)  # panel 1 is the outer garment; both face +z
    vertex_layer = layers.vertex_layer(model.faces, model.vertex_count)
    edges = np.unique(np.sort(model.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    rng = np.random.default_rng(0)
    pairs = np.hstack([edges[rng.integers(0, len(edges), 400)], edges[rng.integers(0, len(edges), 400)]])
    out = layers.edge_directions(vertex_layer, model.faces, x0, pairs)
    la, lb = vertex_layer[pairs[:, 0]], vertex_layer[pairs[:, 2]]
    assert (la == lb).any() and (la > lb).any() and (la < lb).any()
    assert not out[la == lb].any()
    assert (out[la > lb, 2] > 0).all() and (out[la < lb, 2] < 0).all()  # the outer edge belongs above
    np.testing.assert_allclose(out[la != lb, :2], 0.0, atol=1e-12)


def test_edge_directions_are_the_inner_edges_summed_outward_normals_and_zero_where_loose():
    """The compiled Layers.edge_directions against numpy's sums of the faces' normals (turned out by
    each face's ``face_out``) on a crumpled two-layer cloth, with part of the outer layer loose."""
    from tailor.collide import Layers
    from tailor.geometry import vertex_normals

    model, x0 = stacked(-0.004, 0.0, offset=0.0, size=0.1, resolution=0.02)
    rng = np.random.default_rng(3)
    x = x0 + rng.normal(0.0, 0.003, x0.shape)
    faces = np.asarray(model.faces)
    out_sign = rng.choice(np.array([-1, 1], np.int8), len(faces))
    vertex_layer = np.zeros(model.vertex_count, np.int64)
    vertex_layer[faces] = np.asarray(model.face_panel, np.int64)[:, None]
    loose = np.where((vertex_layer == 1) & (rng.random(model.vertex_count) < 0.3), 0, -1)
    layers = Layers(model.face_panel.astype(np.int64), out_sign, loose)
    edges = np.unique(np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    pairs = np.hstack([edges[rng.integers(0, len(edges), 600)], edges[rng.integers(0, len(edges), 600)]])
    got = layers.edge_directions(vertex_layer, faces, x, pairs)
    normal = vertex_normals(x, faces, out_sign)
    la, lb = vertex_layer[pairs[:, 0]], vertex_layer[pairs[:, 2]]
    free = (la == lb) | (loose[pairs[:, :2]] == lb[:, None]).any(axis=1) | (loose[pairs[:, 2:]] == la[:, None]).any(axis=1)
    expect = np.where((la > lb)[:, None], normal[pairs[:, 2]] + normal[pairs[:, 3]], -(normal[pairs[:, 0]] + normal[pairs[:, 1]]))
    expect[free] = 0.0
    assert free.any() and (~free).any() and (loose[pairs] >= 0).any()
    np.testing.assert_allclose(got, expect, rtol=1e-12, atol=1e-18)


def test_an_inner_garment_caught_over_an_outer_fold_goes_back_under_it_by_its_own_side():
    """An outer garment's fold turns its faces over (a circle skirt's hem landing on trousers): the
    side an inner vertex belongs on is read from the inner cloth round it (Layers.vertex_triangle_sides),
    so an inner panel caught a millimetre over an outer panel lying face down goes back under it,
    where the outer panel's own side (its winding as placed) put it over, and side memory kept it;
    a triangle standing perpendicular to the vertex's normal leaves the pair its remembered side."""
    from tailor.collide import Layers

    model, x0 = stacked(-0.001, 0.0, offset=0.0, size=0.1, resolution=0.02)  # the outer panel 1 mm under the inner
    outer = panel_vertices(model, 1)
    tri = x0[model.faces]
    up = np.where(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2] > 0, 1, -1).astype(np.int8)
    layers = Layers(model.face_panel.astype(np.int64), up)  # as placed: both panels' windings face out (+z)
    x0[outer, 0] *= -1.0  # the outer panel turned over where it lies: its faces now face the body (−z)
    vertex_layer = layers.vertex_layer(model.faces, model.vertex_count)
    inner_v, outer_t = np.flatnonzero(~outer), np.flatnonzero(model.face_panel == 1)
    vtx, tris = np.repeat(inner_v, len(outer_t)), np.tile(outer_t, len(inner_v))
    assert (layers.vertex_triangle_sides(vertex_layer, model.faces, vtx, tris, x0) == 1).all()  # the winding's side: under
    standing = x0.copy()
    standing[outer, 1], standing[outer, 2] = 0.0, x0[outer, 1]  # the outer panel stood up in the x–z plane
    assert (layers.vertex_triangle_sides(vertex_layer, model.faces, vtx, tris, standing) == 0).all()
    ends = []
    for rule in (None, layers):
        state = model.state(x0.copy())
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on", layers=rule)
        assert collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01) > 0
        ends.append(state.x[~outer, 2].mean() - state.x[outer, 2].mean())
    assert ends[1] < -0.002 < 0.0 < ends[0]


def test_cloth_contact_holds_the_vertices_pinned_now(monkeypatch):
    # pins change without the vertex count changing (attachments at settling, an outfit's garment
    # released after waiting to sew): cloth-cloth contact must not move a pinned vertex, nor keep
    # one that was let go
    from conftest import sheet
    from tailor.contact import ContactPipeline

    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    contacts = ContactPipeline(None, None, thickness=0.003, friction=0.3, self_collision="on")
    seen = []
    monkeypatch.setattr(SelfCollider, "respond", lambda self, inv_mass, state, dt, **kw: seen.append(inv_mass.copy()))
    state = model.state(x0)
    pinned = model.with_pins(np.array([0, 1]))
    for m in (model, pinned, model):
        contacts.respond(m, state, 0.01)
    assert seen[0][:2].all() and not seen[1][:2].any() and seen[2][:2].all()


def test_patches_sharing_a_vertex_are_found_as_by_brute_force():
    from itertools import combinations

    from tailor.collide.regions import _shared_vertex_pairs

    rng = np.random.default_rng(3)
    faces, patch = rng.integers(0, 40, (90, 3)), rng.integers(0, 7, 90)
    by_vertex = {}
    for f, p in zip(faces, patch):
        for v in f:
            by_vertex.setdefault(int(v), set()).add(int(p))
    expected = sorted({i * 7 + j for ps in by_vertex.values() for i, j in combinations(sorted(ps), 2)})
    assert _shared_vertex_pairs(faces.ravel(), np.repeat(patch, 3), 7).tolist() == expected


def test_a_cloth_part_flung_across_the_garment_in_one_step_stops_with_a_clear_error():
    """An exploding state (a panel 1 m away from the rest a step later: 100 m/s) stops before the
    swept query over it, which would run for minutes; a panel falling 1 cm does not, nor 1 cm in a
    step of 0.1 ms (100 m/s, but a body's push or an untangling between two responses can do that)."""
    from tailor.errors import SimulationUnstable

    model, x0 = stacked(0.02, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    inv_mass = 1.0 / np.asarray(model.vertex_mass)
    for jump, fails in ((0.01, False), (1.0, True)):
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on")
        collider.respond(inv_mass, model.state(x0.copy(), np.zeros_like(x0)), 0.01)
        x1 = x0.copy()
        x1[upper, 2] -= jump
        state = model.state(x1, np.zeros_like(x0))
        if fails:
            with pytest.raises(SimulationUnstable, match="moved .* relative to the rest in one step"):
                collider.respond(inv_mass, state, 0.01)
        else:
            collider.respond(inv_mass, state, 0.01)
            collider.respond(inv_mass, model.state(x0.copy(), np.zeros_like(x0)), 1e-4)  # and back up in 0.1 ms



def test_a_narrower_margin_asks_about_fewer_pairs_and_finds_the_same_contacts():
    """The query margin is a cost, not a rule: a panel falling onto another is caught by the same
    contacts at 1 cm and at 6 mm, from fewer candidate pairs at the narrower one."""
    model, x0 = stacked(0.006, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    v0 = np.zeros_like(x0)
    v0[upper, 2] = -0.5
    found = []
    for margin in (0.01, 0.006):
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, margin=margin, mode="on")
        state = model.state(x0.copy(), v0.copy())
        contacts = collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01)
        found.append((contacts, collider.candidate_pairs, state.x.copy()))
    (wide, wide_pairs, x_wide), (narrow, narrow_pairs, x_narrow) = found
    assert narrow_pairs < wide_pairs
    assert wide > 0 and narrow == wide
    np.testing.assert_allclose(x_narrow, x_wide, atol=1e-9)


def test_the_default_margin_follows_the_mesh_so_a_finer_mesh_asks_about_as_many_pairs_a_vertex():
    """The default query margin is 0.65 mean edge lengths up to 1 cm: a 2 cm mesh keeps the full
    centimetre; at 5 mm the margin shrinks with the edges, so a vertex of a panel falling onto
    another meets a few candidates more than on the coarse mesh (the thickness does not shrink)
    where the full centimetre would give it twenty times as many, and the falling panel is caught
    either way."""
    from tailor.collide import SELF_MARGIN

    def falling(resolution, margin=None):
        model, x0 = stacked(0.003, 0.0, offset=0.0, size=0.1, resolution=resolution)
        v0 = np.zeros_like(x0)
        v0[panel_vertices(model, 1), 2] = -0.5
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.001, margin=margin, mode="on")
        contacts = collider.respond(1.0 / np.asarray(model.vertex_mass), model.state(x0.copy(), v0), 0.01)
        edges = np.unique(np.sort(model.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
        mean_edge = np.linalg.norm(x0[edges[:, 0]] - x0[edges[:, 1]], axis=1).mean()
        return collider.margin, mean_edge, collider.candidate_pairs / model.vertex_count, contacts

    coarse_margin, _, coarse, caught = falling(0.02)
    assert coarse_margin == SELF_MARGIN and caught > 0
    fine_margin, edge, fine, caught = falling(0.005)
    assert fine_margin == pytest.approx(0.65 * edge) and caught > 0
    wide = falling(0.005, SELF_MARGIN)[2]
    assert fine < 3.0 * coarse and fine < 0.2 * wide


def test_flat_layers_lying_on_each_other_are_candidates_of_each_other_not_of_themselves():
    """Two flat panels 5 mm apart: ``auto`` asks only about pairs joining the two (a flat patch cannot
    touch itself or its flat neighbours: the normal-cone test, pair by pair), ``on`` about pairs
    within each panel too; the upper panel falling onto the lower is stopped the same way."""
    model, x0 = stacked(0.005, 0.0, offset=0.0, size=0.2, resolution=0.01)
    upper = panel_vertices(model, 1)
    v0 = np.zeros_like(x0)
    v0[upper, 2] = -0.5
    found = {}
    for mode in ("on", "auto"):
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode=mode)
        state = model.state(x0.copy(), v0.copy())
        contacts = collider.respond(1.0 / np.asarray(model.vertex_mass), state, 0.01)
        within = np.count_nonzero(upper[collider._vtx] == upper[model.faces[collider._tri, 0]])
        within += np.count_nonzero(upper[collider._ee[:, 0]] == upper[collider._ee[:, 2]])
        found[mode] = (contacts, within, state.v.copy())
    assert found["auto"][1] == 0 and found["on"][1] > 1000
    assert found["auto"][0] == found["on"][0] > 0
    np.testing.assert_allclose(found["auto"][2], found["on"][2], atol=1e-9)
    assert found["auto"][2][upper, 2].min() > -0.45  # slowed: at 0.5 m/s it would have come within 0 of the lower


def test_the_margin_narrows_while_every_step_asks_again_and_widens_when_the_cloth_is_quiet():
    """:class:`MarginSchedule`: a full query right after the last one takes 0.7 of the margin, down
    to the floor (0.3 of the default, at least the thickness); candidates lasting three steps widen
    it again up to the default; while not adapting (open seams sewing) it is the default."""
    from tailor.collide.margins import MarginSchedule

    schedule = MarginSchedule(0.01, thickness=0.002)
    assert schedule.query(True, adapt=True) == 0.01  # the first query: nothing known yet
    margins = []
    for _ in range(6):
        schedule.stepped()
        margins.append(schedule.query(True, adapt=True))
    assert margins[:3] == pytest.approx([0.007, 0.0049, 0.00343]) and margins[-1] == pytest.approx(0.003)
    for _ in range(3):
        schedule.stepped()
    assert schedule.query(False, adapt=True) == pytest.approx(0.003)  # a partial query keeps it
    for _ in range(3):
        schedule.stepped()
    assert schedule.query(True, adapt=True) == pytest.approx(0.003 / 0.7)
    schedule.stepped()
    assert schedule.query(True, adapt=False) == 0.01
    assert MarginSchedule(0.01, thickness=0.004).floor == 0.004


def test_a_cloth_moving_every_step_is_asked_about_at_a_narrower_margin_and_keeps_every_near_pair():
    """A panel sliding over another 8 mm above it, carried 12 mm a step relative to it: every step asks
    again, so the margin narrows (fewer pairs a step) while every vertex–triangle pair within the
    thickness after each step is among the candidates, and the panel pressed onto the other never
    passes through it."""
    from tailor.collide.cloth_kernels import unique_ints
    from tailor.collide.grid import vertex_triangle_pairs

    model, x0 = stacked(0.008, 0.0, offset=0.0, size=0.3, resolution=0.02)
    upper = panel_vertices(model, 1)
    inv_mass = 1.0 / np.asarray(model.vertex_mass)
    pairs = {}
    for adapt in (True, False):
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on")
        if not adapt:  # open seams keep the default margin
            collider.ignore(np.eye(1, len(x0), 0, dtype=bool)[0])
        state = model.state(x0.copy(), np.zeros_like(x0))
        counts = []
        for step in range(20):
            x = state.x.copy()
            x[upper] += np.array([0.012, 0.0, -0.0005])
            state = model.state(x, (x - state.x) / 0.01)
            collider.respond(inv_mass, state, 0.01)
            counts.append(collider.candidate_pairs)
            rx = state.x - state.x.mean(axis=0)
            near_v, near_t, _ = vertex_triangle_pairs(unique_ints(model.faces.ravel()), np.arange(len(model.faces)), collider.faces,
                                                      rx, rx, rx, 0.003, collider._grid_cell, collider._ring_csr, exact=True)
            near = set(zip(near_v.tolist(), near_t.tolist())) - {(0, t) for t in range(len(model.faces))}
            assert near <= set(zip(collider._vtx.tolist(), collider._tri.tolist())), step
        pairs[adapt] = (np.mean(counts[5:]), collider.stats["min_margin_m"], len(self_intersections(state.x, model.faces)))
    assert pairs[True][1] == pytest.approx(0.003) and pairs[False][1] == 0.01
    assert pairs[True][0] < 0.6 * pairs[False][0]
    assert pairs[True][2] == pairs[False][2] == 0  # pressed down on the lower panel, never through it


@pytest.mark.parametrize("gap, speed", [(0.014, 0.3), (0.0185, 0.4)])
def test_a_panel_pressed_onto_one_held_still_keeps_every_near_pair_with_half_the_reach(gap, speed):
    """An outfit's sewn garment is held still while the next sews over it. A panel pressed down 3–4 mm
    a step onto a panel held still: a pair with a still end approaches only by its moving end's drift,
    so it is searched within the thickness plus half the margin (fewer candidates than the whole
    margin), no pair of two still vertices is a candidate, and still every vertex–triangle pair
    within the thickness after each step is among the candidates (anchored to the still panel: the
    cloth's centroid, dragged down by the moving panel, would let pairs slip past), and the
    pressed panel never passes through."""
    from tailor.collide.cloth_kernels import unique_ints
    from tailor.collide.grid import vertex_triangle_pairs

    model, x0 = stacked(gap, 0.0, offset=0.0, size=0.2, resolution=0.02)
    upper = panel_vertices(model, 1)
    inv_mass = np.where(upper, 1.0 / np.asarray(model.vertex_mass), 0.0)
    faces = np.arange(len(model.faces))
    counts = {}
    for hold in (True, False):
        collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on")
        state = model.state(x0.copy(), np.zeros_like(x0))
        counts[hold] = []
        for step in range(12):
            if hold:
                collider.hold_still(~upper)
            v = np.where(upper[:, None], np.array([0.0, 0.0, -speed]), 0.0)
            state = model.state(state.x + 0.01 * v, v)
            collider.respond(inv_mass, state, 0.01)
            counts[hold].append(collider.candidate_pairs)
            assert np.array_equal(state.x[~upper], x0[~upper])
            held = set(zip(collider._vtx.tolist(), collider._tri.tolist()))
            near_v, near_t, _ = vertex_triangle_pairs(unique_ints(model.faces.ravel()), faces, collider.faces, state.x, state.x,
                                                      state.x, 0.003, collider._grid_cell, collider._ring_csr, exact=True)
            assert set(zip(near_v.tolist(), near_t.tolist())) <= held, (hold, step)
            if hold:
                assert (upper[collider._vtx] | upper[model.faces[collider._tri]].any(axis=1)).all()
        assert len(self_intersections(state.x, model.faces)) == 0
        assert state.x[upper, 2].min() > 0.002  # resting on the still panel
    assert max(counts[True]) > 0
    assert sum(counts[True]) < 0.8 * sum(counts[False])


@pytest.mark.parametrize("mode", ["on", "auto"])
def test_candidates_found_again_only_where_the_cloth_moved_still_hold_every_near_pair(mode):
    """A corner flapping over a still panel: the still panel keeps its candidates (partial queries
    find again only the pairs touching vertices that moved from their anchors, and in ``auto`` the
    pairs of patches that could not touch before and can now), and after every step each
    vertex–triangle pair within the thickness is among them."""
    from tailor.collide.cloth import PARTIAL_SHARE
    from tailor.collide.cloth_kernels import unique_ints
    from tailor.collide.grid import vertex_triangle_pairs

    model, x0 = stacked(0.004, 0.0, offset=0.0, size=0.2, resolution=0.02)
    upper = panel_vertices(model, 1)
    collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode=mode, partial=PARTIAL_SHARE)
    state = model.state(x0.copy(), np.zeros_like(x0))
    inv_mass = 1.0 / np.asarray(model.vertex_mass)
    rng = np.random.default_rng(2)
    corner = upper & (x0[:, 0] > 0.05)  # a corner of the upper panel flaps; the rest lies still
    near_pairs = 0
    for step in range(30):
        v = np.zeros_like(x0)
        v[corner] = rng.normal(0.0, 0.6, 3)
        state = model.state(state.x + 0.01 * v, v)
        collider.respond(inv_mass, state, 0.01)
        rx = state.x - state.x.mean(axis=0)
        faces = np.arange(len(model.faces))
        near_v, near_t, _ = vertex_triangle_pairs(unique_ints(model.faces.ravel()), faces, collider.faces, rx, rx, rx, 0.003,
                                                  collider._grid_cell, collider._ring_csr, exact=True)
        held = set(zip(collider._vtx.tolist(), collider._tri.tolist()))
        assert set(zip(near_v.tolist(), near_t.tolist())) <= held, step
        near_pairs += len(near_v)
    assert collider.stats["partial_queries"] > 0 and near_pairs > 0


@pytest.mark.parametrize("told", [True, False])
def test_a_self_collider_rebuilt_after_a_weld_keeps_the_sides_the_cloth_had_before_the_step(told):
    """After welding (a new numbering) the self-collider is built afresh. Told where the step starts
    (``follow(friction, x)``), it keeps the upper panel above the lower one through a step that
    carries it through; not told, it can only take the crossed end of the step as the sides to keep
    (what every first step after a weld did)."""
    from tailor.contact import ContactPipeline

    model, x0 = stacked(0.01, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    contacts = ContactPipeline(None, None, thickness=0.003, friction=0.3, self_collision="on")
    contacts.follow(0.3, x0 if told else None)
    x1, v = x0.copy(), np.zeros_like(x0)
    x1[upper, 2] -= 0.015  # 5 mm below the lower panel at the end of the step
    v[upper, 2] = -1.5
    state = model.state(x1, v)
    contacts.respond(model, state, 0.01)
    above = state.x[upper, 2].mean() > state.x[~upper, 2].mean()
    assert above == told


@pytest.mark.parametrize("outfit", [True, False])
def test_an_open_seam_passes_through_its_own_garment_but_not_through_another(outfit):
    """While sewing, the vertices of open seams are left free (:meth:`SelfCollider.ignore`) so that
    a seam's two sides meet; in an outfit they still meet the other garments (a skirt's band
    closing over the trousers' must not be drawn through them)."""
    model, x0 = stacked(0.01, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    garment = upper.astype(np.int64) if outfit else np.zeros(model.vertex_count, np.int64)
    collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="on", garment=garment)
    inv_mass = 1.0 / np.asarray(model.vertex_mass)
    collider.respond(inv_mass, model.state(x0.copy(), np.zeros_like(x0)), 0.01)
    collider.ignore(upper)  # the upper panel's seams are open
    x1, v = x0.copy(), np.zeros_like(x0)
    x1[upper, 2] -= 0.015
    v[upper, 2] = -1.5
    state = model.state(x1, v)
    collider.respond(inv_mass, state, 0.01)
    assert (state.x[upper, 2].mean() > state.x[~upper, 2].mean()) == outfit


def test_positions_moved_between_steps_are_the_sides_the_next_step_keeps():
    """Told where the next step starts (``follow(friction, x)``) with the numbering unchanged, the
    self-collider keeps the sides the cloth has there: the upper panel, lifted from below the lower
    one to above it between steps (untangled, attached), stays above through a step that does not
    cross; an unchanged collider would still remember it below and pull it back through."""
    from tailor.contact import ContactPipeline

    model, x0 = stacked(-0.005, 0.0, offset=0.0, size=0.1, resolution=0.02)
    upper = panel_vertices(model, 1)
    contacts = ContactPipeline(None, None, thickness=0.003, friction=0.3, self_collision="on")
    contacts.respond(model, model.state(x0.copy(), np.zeros_like(x0)), 0.01)  # remembers it below
    x_mid = x0.copy()
    x_mid[upper, 2] = 0.01
    contacts.follow(0.3, x_mid)
    x1 = x_mid.copy()
    x1[upper, 2] = 0.008
    state = model.state(x1, np.zeros_like(x1))
    contacts.respond(model, state, 0.01)
    assert state.x[upper, 2].min() > state.x[~upper, 2].max() + 0.002


def test_pairs_kept_across_an_open_seam_stay_candidates_where_their_patches_lie_flat_together():
    """``auto`` keeps a candidate only between patches that can touch, and neighbouring patches
    lying flat together cannot. An open seam's two sides, closing edge to edge, lie flat together,
    yet the pairs kept between their neighbourhoods (:meth:`SelfCollider.ignore`) must stay
    candidates, or the two sides fold through each other as they close (the T-shirt at 1.5 cm
    stopped sewing at an armpit). Here: a sheet under another (so its patches take part), its own
    vertex pairs about a centimetre apart kept."""
    model, x0 = stacked(0.002, 0.0, offset=0.0, size=0.1, resolution=0.005)
    lower = np.flatnonzero(~panel_vertices(model, 1))
    near = np.linalg.norm(x0[lower, None] - x0[None, lower], axis=2)
    a, b = np.nonzero((near > 0.008) & (near < 0.011))
    keep = np.column_stack([lower[a], lower[b]])
    collider = SelfCollider(model.faces, model.face_panel, x0, thickness=0.003, mode="auto")
    collider.ignore(~panel_vertices(model, 1), keep)
    collider.respond(1.0 / np.asarray(model.vertex_mass), model.state(x0.copy()), 0.01)
    corners = model.faces[collider._tri]
    within = ~panel_vertices(model, 1)[collider._vtx] & ~panel_vertices(model, 1)[corners].any(axis=1)
    keys = set((keep[:, 0] * len(x0) + keep[:, 1]).tolist())
    kept = [any(int(v) * len(x0) + int(c) in keys for c in f) for v, f in zip(collider._vtx[within], corners[within])]
    assert len(kept) > 100 and all(kept)  # the sheet's own candidates: every one a kept pair, and there are many


def test_nearly_parallel_edges_whose_common_normal_swings_are_never_read_as_crossed():
    """Two nearly parallel 4 mm edges (a pleat's walls pressed together) stay 0.7 mm apart or more all
    along a step, but their common normal turns by 78°: the side read in the last
    step's normal is no memory, so the pair is a contact by proximity (0.96 mm apart, under the 1 mm
    thickness), not a crossing to push 2 mm back through (a 256² sheet on the sphere was pinched
    3.6× that way)."""
    from tailor.collide.cloth_kernels import detect_ee_serial

    xp = np.array([[0.0, 0.0, 0.0], [0.004, 0.0, 0.0], [0.000672, -0.000823, -0.000207], [0.004667, -0.000638, -0.000171]])
    x = np.array([[0.0, 0.0, 0.0], [0.004, 0.0, 0.0], [0.000919, -0.000971, -0.000619], [0.004831, -0.000962, 0.000216]])
    s = np.linspace(0.0, 1.0, 41)
    apart = min(np.linalg.norm((y[0] + s[:, None] * (y[1] - y[0]))[:, None] - (y[2] + s[:, None] * (y[3] - y[2]))[None], axis=2).min()
                for y in (xp + k * (x - xp) for k in s))
    assert apart > 0.0006  # they never pass through each other
    n_prev, n_now = (np.cross(y[1] - y[0], y[3] - y[2]) for y in (xp, x))
    assert abs(n_prev @ n_now) < 0.3 * np.linalg.norm(n_prev) * np.linalg.norm(n_now)  # the normal swung beyond 72°
    oi, oa, on, oh = np.empty((1, 4), np.int64), np.empty((1, 4)), np.empty((1, 3)), np.empty(1)
    hit = np.zeros(1, bool)
    detect_ee_serial(x, xp, np.zeros((4, 3)), 0.002, np.array([[0, 1, 2, 3]]), np.zeros(1, bool), np.zeros((1, 3)), 0.001, 0.006,
                     oi, oa, on, oh, hit, 0, np.arange(1))
    assert hit[0]
    assert (oa[0][:, None] * x[oi[0]]).sum(axis=0) @ on[0] == pytest.approx(0.00096, abs=2e-5)  # on the side it is on


def _edge_pair_across_layers(memory_with_layers: bool):
    """Two 4 mm edges 0.8 mm apart, one of an outer garment and one of the inner (its layer normal +z),
    nearly parallel: their common normal n̂ stands 63° off the layer normal. The outer edge lies on
    the +n̂ side of the inner one (the side the layers' +z leans it to) or on the −n̂ side."""
    db = np.array([0.003, 0.0001, 0.0002])
    n = np.cross([0.004, 0.0, 0.0], db)
    n /= np.linalg.norm(n)
    pb = np.array([0.002, 0.0, 0.0]) - (1.0 if memory_with_layers else -1.0) * 0.0008 * n
    x = np.array([[0.0, 0.0, 0.0], [0.004, 0.0, 0.0], pb - 0.5 * db, pb + 0.5 * db])
    return x, n


@pytest.mark.parametrize("memory_with_layers", [True, False])
def test_an_edge_pair_standing_off_the_layers_keeps_its_side_only_where_the_layers_agree(memory_with_layers):
    """Layer rule, edge–edge: where two garments' edges have a common normal far from the layers'
    normal (n̂·ẑ = 0.45 here) its sign says nothing of which side of the inner layer the outer edge
    is on; forcing it (the rule before) shoved GarmentCode's skirts on MakeHuman's women sideways
    through their pants step after step until a triangle tore. Such a pair keeps its remembered side
    where that agrees with the layers, and is no contact where it does not (pushed along n̂ it
    would be forced through the other edge)."""
    from tailor.collide.cloth_kernels import detect_ee_serial

    x, n = _edge_pair_across_layers(memory_with_layers)
    assert 0.3 < abs(n[2]) < 0.9
    oi, oa, on, oh = np.empty((1, 4), np.int64), np.empty((1, 4)), np.empty((1, 3)), np.empty(1)
    hit = np.zeros(1, bool)
    toward = np.array([[0.0, 0.0, 1.0]])  # the inner edge's outward normal: the outer edge belongs above it
    detect_ee_serial(x, x, np.zeros((4, 3)), 0.002, np.array([[0, 1, 2, 3]]), np.zeros(1, bool), toward, 0.001, 0.006,
                     oi, oa, on, oh, hit, 0, np.arange(1))
    assert hit[0] == memory_with_layers
    if memory_with_layers:
        np.testing.assert_allclose(on[0], n, atol=1e-9)  # pushed apart the way it already is apart
        assert (oa[0][:, None] * x[oi[0]]).sum(axis=0) @ on[0] == pytest.approx(0.0008, abs=1e-9)


def _two_garment_squares(inner_z, outer_z):
    """A 2 cm square of an inner garment (layer 0) at height ``inner_z`` and one of an outer garment
    (layer 1) at ``outer_z``, both wound and turned out to face +z."""
    from tailor.collide import Layers

    square = np.array([[0.0, 0.0], [0.02, 0.0], [0.02, 0.02], [0.0, 0.02]])
    x = np.vstack([np.column_stack([square, np.full(4, inner_z)]), np.column_stack([square, np.full(4, outer_z)])])
    faces = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    return x, faces, Layers(np.array([0, 0, 1, 1]), np.ones(4, np.int8))


def test_cloth_against_an_inner_garments_rim_keeps_its_side():
    """Beyond an inner garment's open edge (a waistband's top) the outer one has no outside to be put
    on: a skirt's band rising over the top of trousers' band lies on the body there. Against the
    rim's triangles, and for the rim's own vertices against outer triangles, pairs keep their side
    (forcing the skirt over the rim pumped the trousers' band until it tore). Layers.round_body
    marks the rim: the vertices on the cloth's open edges."""
    from tailor.collide import Layers

    x, faces, plain = _two_garment_squares(0.0, 0.002)
    vertex_layer = plain.vertex_layer(faces, len(x))
    rim = np.zeros(len(x), bool)
    rim[[2, 3]] = True  # the inner square's top edge
    layers = Layers(plain.face_layer, plain.face_out, None, rim)
    outer_on_rim = np.array([6, 6, 4]), np.array([0, 1, 1])  # triangle 0 and 1 touch the rim
    inner_vs_outer = np.array([2, 1]), np.array([2, 2])  # a rim vertex and one off it, under outer triangle 2
    for vtx, tri in (outer_on_rim, inner_vs_outer):
        assert (plain.vertex_triangle_sides(vertex_layer, faces, vtx, tri, x) != 0).all()
    assert (layers.vertex_triangle_sides(vertex_layer, faces, *outer_on_rim, x) == 0).all()
    np.testing.assert_array_equal(layers.vertex_triangle_sides(vertex_layer, faces, *inner_vs_outer, x), [0, -1])
    body = np.array([[0.0, 0.0, -0.1], [1.0, 0.0, -0.1], [0.0, 1.0, -0.1]])
    made = Layers.round_body(plain.face_layer, np.array([0, 0, 1, 1]), x, faces, body, np.array([[0, 1, 2]]))
    assert made.rim.all()  # every vertex of two lone squares is on an open edge

