"""Validation against real cloth (quick versions): Bottino's sphere and two-point hanging converge
with resolution, and Cusick drape coefficients order by bending stiffness within (0, 1)."""

from __future__ import annotations

import numpy as np
import pytest

import tailor
from tailor.lab import DrapeTest, count_nodes, drape_coefficient, drape_test
from tailor.validate import _run_patch, _shape_distance, bottino_fabric


def test_bottino_fabric_models():
    kes5, kes1, auto = (bottino_fabric("A", m) for m in ("kes5", "kes1", "auto"))
    assert kes5.kawabata.segments == 5 and kes1.kawabata.segments == 1 and auto.kawabata is None
    assert auto.density == kes5.density == pytest.approx(0.138)
    with pytest.raises(ValueError):
        bottino_fabric("A", "kes3")


def test_two_point_hanging_converges_with_resolution():
    height = {n: np.ptp(_run_patch("hang", bottino_fabric("A", "auto"), n)[1][:, 2]) for n in (11, 21, 31)}
    assert abs(height[31] - height[21]) < abs(height[21] - height[11])
    assert abs(height[31] - height[21]) < 0.002


def test_sphere_quick_resolutions_agree_and_rest_on_the_sphere():
    a = _run_patch("sphere", bottino_fabric("A", "kes5"), 11, duration=1.6)
    b = _run_patch("sphere", bottino_fabric("A", "kes5"), 21, duration=1.6)
    assert _shape_distance(b[:2], a[:2]) < 0.008
    r = np.linalg.norm(b[1], axis=1)
    assert r.min() > 0.045 - 0.001  # nothing inside the 9 cm sphere beyond a millimetre


@pytest.mark.slow
def test_sphere_21_against_31_converges():
    # the issue's own check (a minute): the full 2 s of settling at 11, 21 and 31; CI runs the quick
    # version above
    runs = {n: _run_patch("sphere", bottino_fabric("A", "kes5"), n) for n in (11, 21, 31)}
    d21 = _shape_distance(runs[31][:2], runs[21][:2])
    assert d21 < _shape_distance(runs[31][:2], runs[11][:2])
    # the target: 3.5 mm (measured 2.9 mm; 3.9 mm before a contact read the wrong side of a
    # body edge; the folds are chaotic: 7.5 mm at a 2.5 ms step then)
    assert d21 < 0.0035


def test_patch_meeting_a_cube_edge_lands_without_being_thrown_off():
    # Bottino's 8 cm cube, fabric A, n = 31: the patch's vertices beyond the cube's top edge, level
    # with a side face, read "15 mm inside" from a partial set of cached triangles and were thrown
    # off (stretched 4x at t = 0.04 s); now the run lands: nothing rises above where it started
    from tailor.scenes import run_scene
    from tailor.validate import STEP, patch_scene

    setup = patch_scene("cube80", bottino_fabric("A", "kes5"), 31, duration=0.12)
    result = run_scene(setup.model, setup.x0, body=setup.body, duration=setup.duration, fps=25, integrator="implicit",
                       dt=STEP, thickness=setup.thickness, friction=setup.friction, self_collision="off")
    x = result.frames[-1]
    assert x[:, 2].max() <= setup.x0[:, 2].max() + 1e-6
    top = np.all(np.abs(x[:, :2]) < 0.035, axis=1)  # over the cube's top face: resting on it
    assert top.sum() > 100 and np.all(np.abs(x[top, 2] - 0.04) < 0.002)


def test_drape_coefficient_grows_with_bending_and_lies_in_0_1():
    cotton = tailor.preset("cotton")
    dc = [drape_test(cotton.with_values(bending=c), resolution=0.03, specimens=1).drape_coefficient for c in (1.0, 8.0, 60.0)]
    assert 0.0 < dc[0] < dc[1] < dc[2] < 1.0


def test_drape_coefficient_and_nodes_of_known_shapes():
    # a flat specimen covers everything (DC 1); one hanging straight down covers only the disk (DC 0)
    t = np.linspace(0, 2 * np.pi, 65)[:-1]
    rings = [0.0, 0.09, 0.15]
    x = np.concatenate([[[0.0, 0.0, 0.0]]] + [np.c_[r * np.cos(t), r * np.sin(t), np.zeros_like(t)] for r in rings[1:]])
    fan = [(0, 1 + i, 1 + (i + 1) % 64) for i in range(64)]
    ring = [(1 + i, 65 + i, 65 + (i + 1) % 64) for i in range(64)] + [(1 + i, 65 + (i + 1) % 64, 1 + (i + 1) % 64) for i in range(64)]
    faces = np.array(fan + ring)
    dc, _ = drape_coefficient(x, faces)
    assert dc == pytest.approx(1.0, abs=0.01)
    hanging = x.copy()
    hanging[65:, :2] *= 0.09 / 0.15
    hanging[65:, 2] = -0.06
    assert drape_coefficient(hanging, faces)[0] == pytest.approx(0.0, abs=0.01)
    wavy = x.copy()
    wavy[65:, :2] *= (1 + 0.1 * np.cos(6 * t))[:, None]
    assert count_nodes(wavy, np.arange(65, 129)) == 6


def test_a_run_that_stops_is_reported_and_does_not_cost_the_report(tmp_path, monkeypatch):
    import tailor.validate as V
    from tailor.errors import SimulationUnstable
    from tailor.scenes import grid

    def fake_run(scene, fabric, n, mesh="grid", duration=2.0):
        if "automatic" in fabric.name and n == 21 and scene == "sphere":
            raise SimulationUnstable("simulation unstable at t = 0.04 s")
        m = grid(0.2, 0.2, n)
        return m, np.c_[m.uv, np.full(len(m.uv), 0.05)], 0.0

    def fake_cusick(fabric, **kw):
        if fabric.name == "silk":
            raise SimulationUnstable("simulation unstable at t = 1 s")
        m = grid(0.3, 0.3, 5)
        x = np.c_[m.uv - 0.15, np.zeros(len(m.uv))]
        dc, shadow = drape_coefficient(x, m.faces)
        return DrapeTest(fabric.name, dc, 0, shadow, x, m.faces)

    monkeypatch.setattr(V, "_run_patch", fake_run)
    monkeypatch.setattr(V, "drape_test", fake_cusick)
    text = V.validate(tmp_path, quick=True).read_text()
    assert "## Runs that stopped" in text
    assert "sphere, fabric A, auto, n = 21 (grid): simulation unstable" in text and "Cusick, silk" in text
    assert "| 11 |  | — |" in text  # the auto table's missing cell
    assert "| silk | 2.7 | unstable |" in text and "| cotton |" in text
