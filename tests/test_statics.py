"""Cloth at rest under gravity: the automatic parameters mean what they say (Carignan §5)."""

import numpy as np
import pytest

from conftest import sheet
from tailor.fabric import preset
from tailor.sim import simulate


def settle(model, x0, duration, frame_rate=10, dt=None):
    """Run the implicit integrator; return the states of the last second (for time averages)."""
    states = [s for _, s in simulate(model, model.state(x0), duration=duration, frame_rate=frame_rate,
                                     integrator="implicit", dt=dt)]
    return states[-frame_rate:]


@pytest.mark.parametrize("resolution", [0.05, 0.0333])
@pytest.mark.parametrize("fabric", ["silk", "cotton", "jersey", "denim"])
def test_hanging_panel_stretches_the_requested_percentage(fabric, resolution):
    # Eq. 22 as defined in tailor.params: λ is the mean strain of a 1 m strip hanging from its top
    model, x0 = sheet(100, 100, resolution, fabric)  # warp vertical
    model = model.with_pins(np.flatnonzero(x0[:, 2] > 1 - 1e-9))
    bottom = np.flatnonzero(x0[:, 2] < 1e-9)
    last = settle(model, x0, duration=4.0)
    stretch = np.mean([-s.x[bottom, 2].mean() for s in last])  # time-averaged over the last second
    assert stretch == pytest.approx(preset(fabric).stretch_warp, rel=0.10)


def two_corner_sag(resolution, size_cm=50):
    model, x0 = sheet(size_cm, size_cm, resolution, "cotton")
    s = size_cm / 100
    top = np.flatnonzero(x0[:, 2] > s - 1e-9)
    corners = top[(x0[top, 0] < 1e-9) | (x0[top, 0] > s - 1e-9)]
    model = model.with_pins(corners)
    state = settle(model, x0, duration=3.0)[-1]
    order = np.argsort(x0[top, 0])
    mid = np.interp(s / 2, x0[top, 0][order], state.x[top, 2][order])  # top edge between the pins
    return s - mid, s - state.x[:, 2].min()


def test_two_corner_sag_is_independent_of_resolution_quick():
    coarse, fine = two_corner_sag(0.04), two_corner_sag(0.02)
    assert abs(coarse[0] - fine[0]) < 0.005 and abs(coarse[1] - fine[1]) < 0.005
    assert fine[0] > 0.005  # it does sag: the top edge hangs visibly below the pins (≈ 1 cm for cotton)


@pytest.mark.slow
def test_two_corner_sag_is_independent_of_resolution_2cm_vs_1cm():
    coarse, fine = two_corner_sag(0.02), two_corner_sag(0.01)
    assert abs(coarse[0] - fine[0]) < 0.005 and abs(coarse[1] - fine[1]) < 0.005


def cantilever(c, overhang_cm, clamp_cm=1.0, width_cm=2.0, resolution=0.004):
    """Peirce's cantilever: a strip clamped at one end droops under its own weight."""
    fabric = preset("cotton").with_values(bending=c)
    model, x0 = sheet(clamp_cm + overhang_cm, width_cm, resolution, fabric, vertical=False, grain=0)
    model = model.with_pins(np.flatnonzero(x0[:, 0] <= clamp_cm / 100 + 1e-9))
    state = settle(model, x0, duration=2.0, dt=0.005)[-1]
    tip = np.flatnonzero(x0[:, 0] >= (clamp_cm + overhang_cm) / 100 - 1e-9)
    drop = -state.x[tip, 2].mean()
    reach = state.x[tip, 0].mean() - clamp_cm / 100
    return drop, np.arctan2(drop, reach)


def test_cantilever_droop_decreases_monotonically_with_c():
    drops = [cantilever(c, 5.0, resolution=0.006)[0] for c in (0.0, 1.0, 8.0, 60.0)]
    assert all(a > b for a, b in zip(drops, drops[1:])), drops
    assert drops[0] > 0.045  # c = 0: nothing holds the strip up, it hangs nearly straight down


def test_bending_number_is_the_cube_of_peirce_bending_length():
    # overhang 2C droops to θ ≈ 41.5°; Peirce: C = l·(cos(θ/2) / (8·tan θ))^(1/3)
    c = 8.0  # C = 2 cm
    _, theta = cantilever(c, 4.0)
    bending_length = 0.04 * (np.cos(theta / 2) / (8 * np.tan(theta))) ** (1 / 3)
    assert bending_length == pytest.approx(0.02, rel=0.10)
