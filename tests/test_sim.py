"""The one step loop (`tailor/sim.py`): a span covered exactly, contacts after every step and before the
hooks, the guard stopping an unstable run with frame, step and a remedy."""

import numpy as np
import pytest

from conftest import sheet
from tailor.errors import SimulationUnstable
from tailor.integrators import make_integrator
from tailor.sim import Guard, Stepper, simulate


class _Recorder:
    """A stand-in contact pipeline that records what the step loop asks of it."""

    def __init__(self):
        self.calls = []

    def hold(self, model):
        self.calls.append("hold")
        return None

    def predict(self, *args):
        return None

    def respond(self, model, state, dt, impulses, support):
        self.calls.append("respond")

    def checkpoint(self):
        self.calls.append("checkpoint")

    def restore(self, mark, x):
        self.calls.append("restore")


def test_a_span_is_covered_in_equal_steps_and_ends_exactly_on_time():
    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    contacts = _Recorder()
    order = []
    stepper = Stepper(make_integrator("implicit"), contacts=contacts, hooks=[lambda m, s, dt: order.append(dt)])
    state = stepper.advance(model, model.state(x0), 0.04, 0.015)  # 0.04 s in steps of at most 15 ms: 3 of 13.3 ms
    assert state.t == 0.04 and order == [pytest.approx(0.04 / 3)] * 3 and stepper.steps == 3
    assert contacts.calls == ["checkpoint", "hold", "respond"] * 3  # each step marks, holds, then the contacts respond


def test_frames_fall_on_multiples_of_the_frame_time_with_the_explicit_eq24_step():
    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    times = [s.t for _, s in simulate(model, model.state(x0), duration=0.2, frame_rate=25, integrator="symplectic")]
    assert times == pytest.approx([0.04 * k for k in range(6)], abs=1e-12)


def test_an_unstable_run_stops_naming_frame_step_and_a_remedy():
    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    state = model.state(x0, np.random.default_rng(0).normal(0, 1.0, x0.shape))
    with pytest.raises(SimulationUnstable) as err:
        for _ in simulate(model, state, duration=0.2, integrator="forward", dt=0.01, guard=Guard(max_speed=5.0)):
            pass
    text = str(err.value)
    assert "frame" in text and "step" in text and "try a smaller time step" in text and "\n" not in text


class _Pinching(_Recorder):
    """A contact response that puts vertex 0 ``speed`` × the step from ``x``: a long step
    overstretches its triangles (as a self-contact response catching a flap), a short one does not."""

    def __init__(self, speed, x):
        super().__init__()
        self.speed, self.x, self.restored_to = speed, x[0, 0], []

    def respond(self, model, state, dt, impulses, support):
        super().respond(model, state, dt, impulses, support)
        state.x[0, 0] = self.x - self.speed * dt

    def restore(self, mark, x):
        super().restore(mark, x)
        self.restored_to.append(x.copy())


def test_a_step_its_contacts_overstretch_is_taken_again_in_halves():
    from tailor.sim import max_stretch

    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    start = model.state(x0)
    pipe, kept = _Pinching(3.0, x0), []  # 12 cm in 40 ms out of 5 cm triangles: 4.2×; 6 cm in 20 ms: 2.6×
    stepper = Stepper(make_integrator("implicit"), contacts=pipe, hooks=[lambda m, s, dt: kept.append(dt)])
    end = stepper.advance(model, start, 0.04, 0.04)
    assert stepper.retried == 1 and kept == [0.02, 0.02] and end.t == pytest.approx(0.04)
    assert max_stretch(model, end.x) < 3.0 and pipe.calls.count("restore") == 1
    np.testing.assert_array_equal(pipe.restored_to[0], x0)  # undone back to where it began

    never = Stepper(make_integrator("implicit"), contacts=_Pinching(400.0, x0), guard=Guard(retries=2))
    with pytest.raises(SimulationUnstable, match="stretched"):
        never.advance(model, model.state(x0), 0.04, 0.04)
    assert never.retried == 2  # Δt/2, then Δt/4: no smaller step helped


class _Refusing(_Recorder):
    """A contact response that stops a step longer than ``longest`` as unstable (as the self-contact's
    guard stops cloth moving too fast for its candidates)."""

    def __init__(self, longest):
        super().__init__()
        self.longest = longest

    def respond(self, model, state, dt, impulses, support):
        super().respond(model, state, dt, impulses, support)
        if dt > self.longest:
            raise SimulationUnstable("too fast for the contacts")


def test_a_step_its_contacts_call_unstable_is_taken_again_in_halves():
    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    kept = []
    stepper = Stepper(make_integrator("implicit"), contacts=_Refusing(0.015), hooks=[lambda m, s, dt: kept.append(dt)])
    end = stepper.advance(model, model.state(x0), 0.04, 0.04)
    assert stepper.retried == 3 and kept == [0.01] * 4 and end.t == pytest.approx(0.04)  # 40 → 20 → 10 ms, twice
    never = Stepper(make_integrator("implicit"), contacts=_Refusing(0.001), guard=Guard(retries=2))
    with pytest.raises(SimulationUnstable, match="too fast"):
        never.advance(model, model.state(x0), 0.04, 0.04)


def test_a_step_undone_and_taken_again_ends_where_it_did():
    """The contacts' checkpoint holds all a step changes: a cloth folding on a sphere (body and
    self-contact, held contacts, loads), a step taken, undone and taken again, ends bit for bit the same."""
    from tailor.scenes import scene_contacts, sphere_drop

    scene = sphere_drop(16)
    pipe = scene_contacts(scene.model, scene.x0, scene.body, thickness=scene.thickness, friction=scene.friction,
                          self_collision="auto", margin=None)
    integrator = make_integrator("implicit")
    stepper = Stepper(integrator, contacts=pipe)
    state = stepper.advance(scene.model, scene.model.state(scene.x0), 0.6, 0.02)  # draped over it, folding
    assert pipe.hold(scene.model) is not None

    def once():
        integrator.reset()
        new = stepper.step(scene.model, state, 0.02)
        return new, pipe.hold(scene.model), pipe.loads.take(scene.model.vertex_count)

    mark = pipe.checkpoint()
    first = once()
    pipe.restore(mark, state.x)
    again = once()
    np.testing.assert_array_equal(first[0].x, again[0].x)
    np.testing.assert_array_equal(first[0].v, again[0].v)
    np.testing.assert_array_equal(first[1].ids, again[1].ids)
    np.testing.assert_array_equal(first[2][0], again[2][0])
