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


def test_a_span_is_covered_in_equal_steps_and_ends_exactly_on_time():
    model, x0 = sheet(10, 10, 0.05, "cotton", vertical=False)
    contacts = _Recorder()
    order = []
    stepper = Stepper(make_integrator("implicit"), contacts=contacts, hooks=[lambda m, s, dt: order.append(dt)])
    state = stepper.advance(model, model.state(x0), 0.04, 0.015)  # 0.04 s in steps of at most 15 ms: 3 of 13.3 ms
    assert state.t == 0.04 and order == [pytest.approx(0.04 / 3)] * 3 and stepper.steps == 3
    assert contacts.calls == ["hold", "respond"] * 3  # each step holds, then the contacts respond


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
