"""Body contacts held inside the implicit solve (Baraff & Witkin's filtered CG)."""

import numpy as np
import pytest

from tailor.fabric import preset
from tailor.integrators import Contacts, ImplicitEuler
from tailor.model import build_model
from tailor.scenes import floor, grid, run_scene, sphere
from tailor.sim import max_stretch
from tailor.units import GRAVITY


def _cloth(n, fabric="cotton", **kw):
    mesh = grid(0.5, 0.5, n)
    return mesh, build_model(mesh, preset(fabric), **kw)


def _moving_cloth_with_contacts():
    """(model, state, ids, normals, target): a rumpled moving 8 × 8 cloth, five contacts in random directions."""
    mesh, model = _cloth(8)
    rng = np.random.default_rng(1)
    x = np.c_[mesh.uv, np.zeros(len(mesh.uv))] + 0.003 * rng.standard_normal((len(mesh.uv), 3))
    state = model.state(x, 0.2 * rng.standard_normal((len(x), 3)))
    ids = np.array([3, 10, 20, 41, 50])
    normals = rng.standard_normal((len(ids), 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    return model, state, ids, normals, np.array([0.0, 0.1, -0.05, 0.0, 0.2])


def test_held_vertices_end_the_step_at_their_prescribed_normal_velocity():
    model, state, ids, normals, target = _moving_cloth_with_contacts()
    integ = ImplicitEuler(tolerance=1e-10)
    from tailor.forces import total_forces
    result = integ.step(model, state, 0.01, total_forces, contacts=Contacts(ids, normals, target, model.vertex_count))
    new = result.state
    vn = np.einsum("ij,ij->i", new.v[ids], normals)
    # a contact is unilateral: held ones end at their normal velocity, pushed (impulse ≥ 0); one the
    # body would have had to pull on is let go and leaves
    held = result.impulses[ids] != 0.0
    assert held.sum() >= 2 and integ.counters.released == (~held).sum()
    assert np.allclose(vn[held], target[held], atol=1e-12)
    assert np.all(result.impulses >= 0.0)
    # (not exactly: after the release the neighbours move too, and one may drift back at a few mm/s,
    # which the collider's next response catches: 2.9 mm/s here, against 0.2 m/s of motion)
    assert np.all(vn[~held] > target[~held] - 0.01)
    free = np.setdiff1d(np.arange(model.vertex_count), ids)
    assert np.abs(new.v[free] - state.v[free]).max() > 1e-3  # the others moved as the solve says


def test_a_contact_let_go_is_not_predicted_back_and_held_ones_are_not_asked_about():
    # a prediction that keeps naming every contact (as the landing query did for a contact let go
    # while its neighbours settled) must not bring back one let go within the step: that cycled,
    # a solve each pass; and predict is told which vertices are held, so it need not test them
    model, state, ids, normals, target = _moving_cloth_with_contacts()
    told = []

    def predict(model_, st, x_end, v_end, dt, held_ids):
        told.append(np.sort(held_ids))
        return Contacts(ids, normals, target, model_.vertex_count)

    integ = ImplicitEuler(tolerance=1e-10)
    from tailor.forces import total_forces
    result = integ.step(model, state, 0.01, total_forces, contacts=Contacts(ids, normals, target, model.vertex_count),
                        predict=predict)
    assert integ.counters.released >= 1  # as in the test above: some are pulled on
    let_go = ids[result.impulses[ids] == 0.0]
    assert len(let_go) == integ.counters.released and integ.counters.predicted == 0
    assert len(told) >= 1 and all(np.isin(t, ids).all() for t in told)
    assert not np.isin(let_go, told[-1]).any()  # the last call was told the current held set


def test_cloth_resting_on_the_floor_stays_exactly_at_rest_and_its_support_is_its_weight():
    mesh, model = _cloth(12)
    thickness = 0.002
    x0 = np.c_[mesh.uv, np.full(len(mesh.uv), thickness)]
    impulses = []

    class Recording(ImplicitEuler):
        def step(self, *args, **kwargs):
            result = super().step(*args, **kwargs)
            impulses.append(0.0 if result.impulses is None else result.impulses.sum())
            return result

    run = run_scene(model, x0, body=floor(), duration=0.2, integrator=Recording(tolerance=1e-10), dt=0.01,
                    thickness=thickness, self_collision="off")
    last = run.frames[-1]
    assert np.abs(last - x0).max() < 1e-9  # no flicker between held and falling steps
    # every step from the second on, the floor's reaction is exactly the weight over the step
    assert np.allclose(impulses[2:], model.total_mass * GRAVITY * 0.01, rtol=1e-6)


def test_a_sheet_falling_onto_a_sphere_at_a_large_step_is_not_torn_apart():
    # before the contacts were held in the solve, the post-step response fought the solve and a
    # triangle on top of the sphere reached 3.8x its rest size at this step
    mesh = grid(1.0, 1.0, 24)
    model = build_model(mesh, preset("cotton"))
    x0 = np.c_[mesh.uv - 0.5, np.full(len(mesh.uv), 0.27)]
    worst = [1.0]
    run = run_scene(model, x0, body=sphere(0.25, subdivisions=3), duration=0.6, dt=0.01, thickness=0.001,
                    self_collision="off", hooks=[lambda m, s, dt: worst.__setitem__(0, max(worst[0], max_stretch(m, s.x)))])
    assert worst[0] < 1.35
    d = np.linalg.norm(run.frames[-1], axis=1)
    assert d.min() > 0.25 * np.cos(np.pi / 40) - 1e-3  # nothing inside the (faceted) sphere


@pytest.mark.parametrize("n, duration", [(64, 0.3), pytest.param(128, 2.0, marks=pytest.mark.slow)])
def test_the_draft_preset_drops_a_fine_sheet_onto_the_sphere_without_tearing_it(n, duration):
    # draft's 0.04 s step: vertices that landed at the end of a step were dragged by
    # friction over the whole step, up to 1.4 cm (a 64² sheet reached 2.2×, a 128² one the guard's 3×)
    from tailor.scenes import sphere_drop
    from tailor.sim import QUALITY, Guard

    draft = QUALITY["draft"]
    scene = sphere_drop(n, duration=duration)
    run = scene.run(dt=draft.step, tolerance=draft.tolerance, guard=Guard(strain_every=1))
    assert max(max_stretch(scene.model, x) for x in run.frames) < 1.5
    assert run.report["max_contact_correction_m"] < 2e-3
    assert np.linalg.norm(run.frames[-1], axis=1).min() > 0.25 * np.cos(np.pi / 40)  # outside the faceted sphere


@pytest.mark.parametrize("speed, mu", [(0.05, 0.5), (0.5, 0.5), (0.5, 0.2), (0.02, 0.3)])
def test_a_sheet_sliding_on_a_floor_ends_its_step_where_coulomb_friction_stops_it(speed, mu):
    # a flat sheet sliding at ``speed`` on a floor that pushed it with its weight: Eq. 14 takes at
    # most μ·g·Δt off its speed in a step, and stops it where that is enough. The friction is a drag
    # inside the solve: it must end each vertex there, never reversed, and the contact's impulse
    # (what the loads report) must balance the sheet's change of momentum.
    from tailor.forces import total_forces
    mesh, model = _cloth(6)
    n, dt = model.vertex_count, 0.01
    direction = np.array([0.6, 0.8, 0.0])
    state = model.state(np.c_[mesh.uv, np.zeros(n)], np.tile(speed * direction, (n, 1)))
    weight = model.vertex_mass * GRAVITY
    contacts = Contacts(np.arange(n), np.tile([0.0, 0.0, 1.0], (n, 1)), np.zeros(n), n, body_velocity=np.zeros((n, 3)),
                        friction=np.full(n, mu), normal_force=weight)
    integ = ImplicitEuler(tolerance=1e-12)
    result = integ.step(model, state, dt, total_forces, contacts=contacts)
    expected = max(speed - mu * GRAVITY * dt, 0.0)
    v = result.state.v
    assert np.abs(v[:, 2]).max() < 1e-9  # held on the floor
    along = v @ direction
    assert np.all(along >= 0.0)  # never reversed
    assert np.allclose(along, expected, atol=integ.stick_speed)
    assert np.abs(v - along[:, None] * direction).max() < 1e-9  # no sideways push
    # the floor's whole impulse (normal and friction) is the sheet's change of momentum less gravity's
    gravity = np.zeros((n, 3))
    gravity[:, 2] = -weight * dt
    assert np.allclose(result.support, model.vertex_mass[:, None] * (v - state.v) - gravity, atol=1e-9)
    assert np.allclose(result.impulses, weight * dt, rtol=1e-6)


def _incline(theta):
    """A 4 m square plane through the origin, tilted by ``theta`` about x (downhill = −y)."""
    c, s = np.cos(theta), np.sin(theta)
    v = np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], float)
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return v @ rot.T, np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize("degrees, mu", [(20.0, 0.5), (30.0, 0.2)])
def test_coulomb_friction_on_an_incline_holds_or_slides_at_the_right_acceleration(degrees, mu):
    theta = np.radians(degrees)
    mesh = grid(0.1, 0.1, 6)
    model = build_model(mesh, preset("denim"))
    thickness = 0.002
    normal = np.array([0.0, -np.sin(theta), np.cos(theta)])
    rot = np.array([[1, 0, 0], [0, np.cos(theta), -np.sin(theta)], [0, np.sin(theta), np.cos(theta)]])
    x0 = np.c_[mesh.uv - 0.05, np.zeros(len(mesh.uv))] @ rot.T + thickness * normal
    run = run_scene(model, x0, body=_incline(theta), duration=0.5, dt=0.01, thickness=thickness, friction=mu,
                    self_collision="off")
    travelled = np.linalg.norm(run.frames[-1] - x0, axis=1).mean()
    expected = 0.5 * GRAVITY * max(np.sin(theta) - mu * np.cos(theta), 0.0) * 0.5**2
    if expected == 0.0:
        assert travelled < 1e-3  # static friction holds: no creep
    else:
        assert travelled == pytest.approx(expected, rel=0.1)


def test_a_patch_dropped_centred_on_a_sphere_keeps_its_mirror_symmetry():
    # Bottino's 20 cm patch on the 9 cm sphere: nothing in the scene prefers a side, so the patch
    # must not drift. (The centre vertex lands on the sphere's top vertex and is pulled on; its
    # tangential reaction is round-off, and friction used to drag it a full μ|rn| that way.)
    n = 31
    mesh = grid(0.2, 0.2, n)
    model = build_model(mesh, preset("bottino_a"))
    x0 = np.c_[mesh.uv - 0.1, np.full(n * n, 0.055)]
    result = run_scene(model, x0, body=sphere(0.045), duration=0.12, fps=50, integrator="implicit", dt=0.005,
                       thickness=0.001, friction=0.4, self_collision="off")
    g = result.frames[-1].reshape(n, n, 3)
    mirrored = g[:, ::-1].copy()
    mirrored[..., 0] *= -1
    assert g[..., 2].min() < 0.04  # it has draped over the sphere
    assert abs(g[..., 0].mean()) < 1e-5  # was 1 mm after 0.12 s
    assert np.abs(mirrored - g).max() < 1e-4
