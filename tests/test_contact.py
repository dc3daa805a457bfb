"""The one contact pipeline (`tailor/contact.py`): what each phase setting does, and that a
renumbered cloth is followed."""

import numpy as np
import pytest

from tailor.collide import BodyCollider
from tailor.contact import Attachments, ContactPipeline, ContactSettings, StaticBody, body_margin
from tailor.errors import SimulationError
from tailor.scenes import cloth_model, floor, rectangle

THICKNESS = 0.002


def _resting(speed=(0.0, 0.0, 0.0)):
    """A 20 cm cloth lying on the floor a little inside it, moving at ``speed``, and its pipeline."""
    _, model = cloth_model([rectangle(0.2, 0.2)], "cotton", 0.05)
    x = np.c_[model.rest_uv - 0.1, np.full(model.vertex_count, 0.5 * THICKNESS)]
    state = model.state(x, np.tile(speed, (model.vertex_count, 1)).astype(float))
    bv, bf = floor()
    pipe = ContactPipeline(BodyCollider(bv[None], bf, margin=body_margin(THICKNESS)), StaticBody(bv),
                           thickness=THICKNESS, friction=0.5)
    return model, state, pipe


def test_held_contacts_are_handed_on_only_when_the_phase_holds_them():
    model, state, pipe = _resting((0.0, 0.0, -0.1))
    pipe.respond(model, state, 0.01)
    held = pipe.hold(model)
    assert held is not None and held.valid_for(model) and len(held) == model.vertex_count
    assert np.allclose(state.x[:, 2], THICKNESS) and np.all(state.v[:, 2] >= 0)  # pushed out, approach cancelled
    model, state, pipe = _resting((0.0, 0.0, -0.1))
    pipe.configure(ContactSettings(hold=False))
    pipe.respond(model, state, 0.01)
    assert pipe.hold(model) is None
    assert pipe.predict(model, state, state.x, state.v, 0.01, np.zeros(0, int)) is None


@pytest.mark.parametrize(("scale", "slides"), [(0.0, True), (1.0, False)])
def test_the_friction_scale_of_a_phase_lets_the_cloth_slide_or_holds_it(scale, slides):
    model, state, pipe = _resting((0.05, 0.0, -0.2))  # pressed into the floor while sliding at 5 cm/s
    pipe.configure(ContactSettings(friction_scale=scale))
    pipe.respond(model, state, 0.01)
    # Eq. 14: μ·Δv_n = 0.5 · 0.2 m/s exceeds the 5 cm/s of sliding, which stops; without friction it goes on
    assert np.allclose(state.v[:, 0], 0.05 if slides else 0.0)


def test_forgetting_a_renumbered_cloth_drops_the_contacts_it_held():
    model, state, pipe = _resting((0.0, 0.0, -0.1))
    pipe.respond(model, state, 0.01)
    assert pipe.hold(model) is not None
    pipe.forget()
    assert pipe.hold(model) is None


def test_an_unknown_self_collision_mode_is_one_line():
    with pytest.raises(SimulationError, match="self_collision must be one of"):
        ContactPipeline(None, None, thickness=THICKNESS, friction=0.4, self_collision="sometimes")


def test_attachments_follow_a_renumbering_and_drop_removed_vertices():
    a = Attachments(np.array([0, 3, 5]), np.array([0, 1, 0]), np.full((3, 3), 1 / 3), np.full(3, 0.002),
                    np.array([[0, 1, 2], [1, 2, 3]]))
    inverse = np.array([0, 1, 2, -1, 3, 7])  # vertex 3 was cut away, 5 became 7
    b = a.renumbered(inverse)
    assert b.ids.tolist() == [0, 7] and b.tri.tolist() == [0, 0]


def test_a_held_edge_keeps_its_height_and_its_panel_stays_below_it():
    """While sewing, an attached edge keeps its height but slides across; the rest of its panel may
    not rise above it (a skirt drawn up to its band must not fold the band up over its top)."""
    from tailor.contact import HeightHold
    from tailor.model import State

    x = np.array([[0.0, 0, 1.0], [0.1, 0, 1.0], [0.0, 0, 0.95], [0.1, 0, 0.95], [0.0, 0, 0.5]])
    moved = x + [[0.02, 0.01, -0.03], [0.0, 0.0, 0.01], [0.0, 0.0, 0.08], [0.0, 0.0, -0.01], [0.0, 0.0, 0.7]]
    weld = np.array([0, 1, 2, 3, 4])
    hold = HeightHold([0, 1], [1.0, 1.0], weld, under=[0, 1, 2, 3], ceilings=[1.0] * 4)
    state = State(moved.copy(), np.tile([0.0, 0.0, 1.0], (5, 1)), 0.0)
    hold.apply(state, None, None)
    assert np.allclose(state.x[:2, 2], 1.0) and np.allclose(state.x[:2, :2], moved[:2, :2])  # height only
    assert state.x[2, 2] == 1.0 and state.v[2, 2] == 0.0  # folded up over the edge: back under it
    assert state.x[3, 2] == moved[3, 2] and state.v[3, 2] == 1.0  # below: free
    assert state.x[4, 2] == moved[4, 2]  # another panel (the skirt): free



def test_an_outfits_garments_are_kept_each_its_layers_out_from_the_body():
    """Two garments lying on the floor (the body) at one height: the body keeps the inner one a
    thickness out and the outer one two, so its response does not press them into one another."""
    mesh, model = cloth_model([rectangle(0.2, 0.2, "inner"), rectangle(0.2, 0.2, "outer")], "cotton", 0.05)
    x = np.c_[model.rest_uv - 0.1, np.full(model.vertex_count, 0.5 * THICKNESS)]
    state = model.state(x, np.tile((0.0, 0.0, -0.1), (model.vertex_count, 1)))
    bv, bf = floor()
    pipe = ContactPipeline(BodyCollider(bv[None], bf, margin=body_margin(THICKNESS)), StaticBody(bv),
                           thickness=THICKNESS, friction=0.5, panel_layer=np.array([0, 1]))
    pipe.configure(ContactSettings(self_collision=False))
    pipe.respond(model, state, 0.01)
    outer = np.isin(np.arange(model.vertex_count), mesh.panel_vertices(1))
    assert np.allclose(state.x[~outer, 2], THICKNESS) and np.allclose(state.x[outer, 2], 2 * THICKNESS)


def test_a_rescue_that_would_tear_a_triangle_apart_leaves_its_corners_inside_for_now():
    """Two neighbours trapped mid-way through a 6 cm slab, one nearer its top and one its bottom: put
    out each to its nearest face, they would end 6 cm apart (1 cm at rest). They stay; a vertex trapped
    just under the top, whose triangles the move leaves near their rest size, goes out."""
    import trimesh

    from tailor.sim import max_stretch

    slab = trimesh.creation.box(extents=(0.4, 0.4, 0.06))
    bv, bf = np.asarray(slab.vertices), np.asarray(slab.faces)
    _, model = cloth_model([rectangle(0.1, 0.1)], "cotton", 0.01)
    x = np.c_[model.rest_uv - 0.05, np.full(model.vertex_count, 0.04)]
    ring = {tuple(e) for f in model.faces for e in zip(f, np.roll(f, 1))}
    v = int(np.argmin(np.linalg.norm(x[:, :2] - [-0.02, 0.0], axis=1)))
    w = next(b for a, b in ring if a == v)
    u = int(np.argmin(np.linalg.norm(x[:, :2] - [0.03, 0.03], axis=1)))
    x[v, 2], x[w, 2], x[u, 2] = 0.001, -0.001, 0.025
    pipe = ContactPipeline(BodyCollider(bv[None], bf, margin=body_margin(THICKNESS)), StaticBody(bv), thickness=THICKNESS,
                           friction=0.5)
    pipe.limit_rescues(5.0)  # the step guard's
    state = model.state(x.copy(), np.zeros_like(x))
    assert pipe.rescue(model, state) == 1
    assert np.array_equal(state.x[[v, w]], x[[v, w]]) and state.x[u, 2] > 0.03
    alone = model.state(x.copy(), np.zeros_like(x))  # the collider alone puts all three out, and tears
    BodyCollider(bv[None], bf, margin=body_margin(THICKNESS)).rescue(model, alone, bv, np.zeros_like(bv), 0, thickness=THICKNESS)
    start = max_stretch(model, x)  # the trapped pair's triangles, pulled down through the slab
    assert max_stretch(model, state.x) <= start < max_stretch(model, alone.x) and max_stretch(model, alone.x) > 5.0
