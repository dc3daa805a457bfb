"""The dressing driver (`tailor/dress/`): options checked once, each phase alone on a small scene,
every integrator through cuts and tearing."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from tailor import read_body, read_pattern
from tailor.body import Body
from tailor.cli import main
from tailor.dress import DrapeOptions, drape, prepare
from tailor.dress.options import REST_FRAMES, REST_SPEED, SETTLE_RAMP, TRANSITION_SPEED, settle_step
from tailor.dress.phases import _open_seams, _sew_frame, animate, rms_speed, settle, sew, transition
from tailor.errors import SimulationError, SimulationUnstable
from tailor.integrators import INTEGRATORS
from tailor.tearing import Cut

PANELS = Path(__file__).resolve().parents[1] / "panels"
HOLE = (0.0, -0.15, 0.75)  # on the skirt's front, in the body's frame [m]


@pytest.mark.parametrize(("field", "value"), [("frames", 0), ("frames", 2.5), ("fps", -25.0), ("resolution", float("nan")),
                                              ("sew_timeout", 0.0), ("settle", -1.0), ("integrator", "euler"),
                                              ("self_collision", "maybe"), ("quality", "best"), ("cuts", ("here",))])
def test_options_are_checked_once_with_a_one_line_error_naming_the_field(field, value):
    with pytest.raises(SimulationError) as err:
        DrapeOptions(**{field: value})
    assert field in str(err.value) and "\n" not in str(err.value)


def test_frames_0_on_the_command_line_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["drape", str(PANELS / "skirt.json"), "--frames", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "frames" in err[0] and not out.exists()


@pytest.fixture(scope="module")
def skirt_dressing(mannequin):
    """A skirt at 8 cm placed round the mannequin, ready to sew."""
    pattern = read_pattern(PANELS / "skirt.json")
    return pattern, prepare(pattern, mannequin, DrapeOptions(resolution=0.08, frames=2, settle=0.2))


@pytest.fixture(scope="module")
def sewn(skirt_dressing):
    pattern, (d, _, x0) = skirt_dressing
    return sew(d, x0)


@pytest.fixture(scope="module")
def settled(skirt_dressing, sewn):
    pattern, (d, _, _) = skirt_dressing
    return sewn[0].x.copy(), settle(d, sewn[0])


def test_an_instability_while_seams_have_stopped_closing_names_the_widest_of_them(mannequin, monkeypatch):
    """A garment too small for the body stalls with seams open and is torn by their pull: the error
    keeps the instability's own words and adds the widest stalled stitch and the likely cause;
    with no pair stalled it is the instability's alone."""
    d, _, x0 = prepare(read_pattern(PANELS / "skirt.json"), mannequin, DrapeOptions(resolution=0.08))
    state = d.garment.model.state(x0)

    def unstable(*args, **kwargs):
        raise SimulationUnstable("simulation unstable at t = 1.0 s: a triangle is stretched 10x")

    monkeypatch.setattr(d, "advance", unstable)
    with pytest.raises(SimulationUnstable) as plain:
        _sew_frame(d, state)
    assert str(plain.value) == "simulation unstable at t = 1.0 s: a triangle is stretched 10x"
    sewing = d.garment.sewing
    sewing.stalled[:3] = True
    with pytest.raises(SimulationUnstable) as told:
        _sew_frame(d, state)
    message = str(told.value)
    assert message.startswith("simulation unstable at t = 1.0 s") and "\n" not in message
    assert "skirt.json: by then 3 seam vertex pairs had stopped closing" in message and "too small for this body" in message
    widest = int(np.argmax(sewing.gaps(d.garment.frame(state))[:3]))
    assert f"pattern.stitches[{d.garment.pattern.seams[sewing.seam[widest]].index}]" in message


def test_a_sewing_time_out_says_whether_more_time_would_help(mannequin):
    """The time-out names the widest open stitch; if that pair had stopped closing, more time will
    not close it and the message says the garment may be too small instead of asking for more."""
    d, _, x0 = prepare(read_pattern(PANELS / "skirt.json"), mannequin, DrapeOptions(resolution=0.08))
    state = d.garment.model.state(x0)
    sewing = d.garment.sewing
    message = _open_seams(d.garment, state, 4.0)
    assert "still open after 4 s of sewing" in message and "allow more time (--sew-timeout)" in message
    sewing.stalled[int(np.argmax(sewing.gaps(d.garment.frame(state))))] = True
    message = _open_seams(d.garment, state, 4.0)
    assert "they had stopped closing: the garment may be too small for this body" in message
    assert "--sew-timeout" not in message and "\n" not in message


def test_sewing_alone_closes_every_seam_and_welds(skirt_dressing, sewn):
    pattern, (d, _, x0) = skirt_dressing
    state, report = sewn
    g = d.garment
    assert g.sewing.open_count == 0 and g.model.vertex_count < g.mesh.vertex_count
    # sewn by pulling and welding, not left for the stragglers' rule at ¾ of the time-out
    assert report.simulated_s < 0.75 * d.options.sew_timeout and report.extra["max_gap_at_merge_m"] <= 0.6 * 0.08
    assert 1 <= report.extra["rebuilds"] <= report.frames  # welded in batches, at most once a frame
    assert np.isfinite(state.x).all()


def test_settling_alone_hangs_the_sewn_garment_under_gravity(skirt_dressing, settled):
    pattern, (d, _, _) = skirt_dressing
    before, (state, report) = settled
    g = d.garment
    assert g.model.gravity[2] < 0 and d.contacts.settings.hold and d.contacts.settings.friction_scale == 1.0
    assert report.simulated_s == pytest.approx(0.2)
    # held up by the hips: it has not fallen as a free body would (½·g·t² = 20 cm, g·t = 2 m/s)
    assert abs(np.mean(state.v[:, 2])) < 0.2 and np.mean(before[:, 2] - state.x[:, 2]) < 0.05
    assert d.motion_limit >= 5.0


def test_settling_ends_once_the_garment_is_at_rest(mannequin):
    """Given 3 s, a sewn skirt settles until it is still (its rms speed under REST_SPEED for
    REST_FRAMES frames in a row) and stops there, not at 3 s."""
    pattern = read_pattern(PANELS / "skirt.json")
    d, _, x0 = prepare(pattern, mannequin, DrapeOptions(resolution=0.08, frames=1, settle=3.0))
    state, report = settle(d, sew(d, x0)[0])
    assert REST_FRAMES <= report.frames < 3.0 * d.options.fps
    assert report.simulated_s == pytest.approx(report.frames / d.options.fps)
    assert rms_speed(d.garment.model, state) < REST_SPEED
    m = d.garment.model.vertex_mass
    kinetic = 0.5 * (m * (state.v ** 2).sum(axis=1)).sum()
    assert rms_speed(d.garment.model, state) == pytest.approx(np.sqrt(2 * kinetic / m.sum()))


def test_every_preset_settles_to_the_same_rest_and_final_gets_there_still(mannequin):
    """Settling is quasi-static: its end is a static equilibrium, the same whatever the step, so
    every preset settles at the coarse step. `final` then dresses the same garment as `draft`,
    at rest, instead of still swinging after its whole settling time."""
    pattern = read_pattern(PANELS / "tshirt.json")
    ends = []
    for quality in ("draft", "final"):
        d, _, x0 = prepare(pattern, mannequin, DrapeOptions(resolution=0.04, frames=1, settle=1.0, quality=quality))
        state, report = settle(d, sew(d, x0)[0])
        assert report.frames < d.options.fps and rms_speed(d.garment.model, state) < REST_SPEED
        ends.append(state.x)
    assert np.linalg.norm(ends[0] - ends[1], axis=1).max() < 1e-3


def test_settling_steps_at_the_garment_step_first_then_coarser(mannequin):
    """Settling's step (quasi-static, alike in every preset): draft's garment step for its first
    SETTLE_RAMP s (gravity comes on: the fastest fall), then 2 s/m of mesh (40 ms at 2 cm)."""
    d, _, _ = prepare(read_pattern(PANELS / "tshirt.json"), mannequin, DrapeOptions(resolution=0.02, quality="final"))
    tl = d.timeline
    assert tl.still_step == pytest.approx(0.005)
    tl.start_settling(1.0)
    assert tl.settling_step(1.0) == pytest.approx(0.02)
    assert tl.settling_step(1.0 + SETTLE_RAMP - 0.04) == pytest.approx(0.02)
    assert tl.settling_step(1.0 + SETTLE_RAMP) == pytest.approx(0.04)
    assert settle_step(0.01) == pytest.approx(0.02) and settle_step(0.08) == pytest.approx(0.04)


def test_transition_and_motion_alone_on_a_still_body(skirt_dressing, settled):
    pattern, (d, _, _) = skirt_dressing
    state, report = transition(d, settled[1][0])
    assert report is None  # a still body has no transition
    state, motion, penetration, crossings = animate(d, state)
    assert len(d.frames) == 2 and motion.frames == 2
    assert max(penetration) <= 0.002 and len(crossings) == 2


def test_a_walking_body_is_eased_from_its_rest_pose_into_its_first_frame():
    body = read_body("mannequin-walk")
    pattern = read_pattern(PANELS / "skirt.json")
    d, _, _ = prepare(pattern, body, DrapeOptions(resolution=0.08))
    tl = d.timeline
    assert tl.keys and np.array_equal(tl.at(0.0)[0], body.rest)  # dressed in the rest pose
    tl.start_transition(1.0)
    assert np.allclose(tl.at(1.0 + 0.5 * tl.transition_s)[0], 0.5 * (body.rest + body.frames[0]))
    # the point that moves farthest (a hand, 27 cm) does so at the transition's speed, not faster
    farthest = float(np.linalg.norm(body.frames[0] - body.rest, axis=1).max())
    assert np.isclose(np.linalg.norm(tl.at(1.1)[1], axis=1).max(), farthest / tl.transition_s)
    assert farthest / tl.transition_s <= TRANSITION_SPEED + 1e-9 and 0.2 <= tl.transition_s <= 1.0
    tl.start_motion(2.0)
    x, v, k = tl.at(2.0)
    assert np.allclose(x, body.frames[0]) and k == tl.keys + 1  # collider frame of the motion's first pose
    assert len(tl.collider_frames) == 1 + tl.keys + body.frame_count


@pytest.mark.parametrize("integrator", [pytest.param(name, marks=pytest.mark.slow) if name in ("symplectic", "verlet") else name
                                        for name in sorted(INTEGRATORS)])
def test_every_integrator_survives_cuts_and_tearing_on_a_garment(integrator, mannequin):
    """A hole is cut in a sewn skirt of a weak fabric, which may then tear on: the mesh changes under
    every integrator (the integrator forgets its history, the contacts their per-vertex memory). CI
    runs the implicit, forward Euler and RK4 steps; symplectic Euler and Verlet, between them, are slow tests."""
    pattern = read_pattern(PANELS / "skirt.json")
    # 5 %: at 3–4 % the torn garment shreds under RK4 (explicit, at Eq. 24's step): the guard stops it
    weak = dataclasses.replace(pattern.fabric, tear_strain=0.05)
    result = drape(pattern, mannequin, weak, integrator=integrator, resolution=0.08, frames=3, settle=0.2, tear=True,
                   cuts=[Cut(0.04, (HOLE,), 0.05)])
    assert result.topology and all(np.isfinite(f).all() for f in result.frames)
    mesh, weld = result.topology_at(2)
    assert result.frames[2].shape == (mesh.vertex_count, 3) and mesh.face_count < result.mesh.face_count
    assert result.report.max_penetration_m <= 0.002


def test_the_issue_command_symplectic_with_cuts_completes(tmp_path):
    cuts = tmp_path / "cuts.json"
    cuts.write_text(json.dumps({"cuts": [{"time": 0.04, "points": [[100 * c for c in HOLE]], "radius": 5}]}))
    out = tmp_path / "run"
    assert main(["-q", "drape", str(PANELS / "skirt.json"), "--integrator", "symplectic", "--resolution", "8",
                 "--frames", "3", "--cuts", str(cuts), "--out", str(out)]) == 0
    assert len(list(out.glob("*.obj"))) == 3


def test_only_body_points_that_can_reach_the_cloth_limit_the_moving_step_by_their_speed_relative_to_it():
    from tailor.dress.timeline import NearBodySpeed as _NearBodySpeed

    # two boxes: a still one near the cloth and one 1 m away moving at 2 m/s
    still = np.array([[x, y, z] for x in (0.0, 0.1) for y in (0.0, 0.1) for z in (0.0, 0.1)])
    frames = np.stack([np.concatenate([still, still + [1.0 + 0.08 * k, 0.0, 0.0]]) for k in range(3)])
    cube = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                     [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    body = Body(frames, np.concatenate([cube, cube + 8]), fps=25.0)
    speed = _NearBodySpeed(body, None, 0.03)
    cloth = np.array([[0.05, 0.05, 0.12], [0.06, 0.05, 0.12]])
    at_rest = np.zeros_like(cloth)
    assert speed(cloth, at_rest, frames[0], 0.04, (0.0, 0.04)) == 0.0  # the moving box is out of reach
    assert speed(cloth + [1.0, 0.0, 0.0], at_rest, frames[0], 0.04, (0.0, 0.04)) == pytest.approx(2.0)
    with_it = np.tile([2.0, 0.0, 0.0], (len(cloth), 1))  # cloth carried along with the moving box
    assert speed(cloth + [1.0, 0.0, 0.0], with_it, frames[0], 0.04, (0.0, 0.04)) == pytest.approx(0.0)
    # fast cloth reaches both boxes; the still one meets it at its whole speed
    assert speed(cloth, np.full_like(cloth, 30.0), frames[0], 0.04, (0.0, 0.04)) == pytest.approx(30.0 * np.sqrt(3.0))


def test_the_transition_steps_at_the_settling_step_unless_the_body_near_the_cloth_is_fast():
    """The body's way from its rest pose into the motion's first frame is quasi-static (only its end is
    kept): stepped as settling is, where the near-body rule allows; the motion keeps the preset's step."""
    from tailor.dress.timeline import Timeline
    from tailor.model import State

    cube = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                     [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    rest = np.array([[x, y, z] for x in (0.0, 0.1) for y in (0.0, 0.1) for z in (0.0, 0.1)])
    frames = np.stack([rest + [0.05 + 0.01 * k, 0.0, 0.0] for k in range(3)])  # 5 cm from the rest pose
    body = Body(frames, cube, fps=25.0, rest=rest)
    cloth = np.array([[0.05, 0.05, 0.12], [0.06, 0.05, 0.12]])

    def steps(travel):
        timeline = Timeline(body, 0.02, settle_step=0.04)
        timeline.follow_collider(0.03, travel)
        timeline.start_transition(0.0)
        during = timeline.moving_step(State(cloth, np.zeros_like(cloth), 0.0), 0.04)
        timeline.start_motion(timeline.transition_s)
        return during, timeline.moving_step(State(cloth, np.zeros_like(cloth), timeline.transition_s), 0.04)

    assert steps(0.015) == (0.04, 0.02)  # the box eases in at 0.25 m/s: 4 cm steps carry it 1 cm
    during, moving = steps(0.005)  # a step may carry the body only 5 mm through the cloth
    assert during == pytest.approx(0.005 / 0.25) and moving == pytest.approx(0.02)


@pytest.mark.parametrize("garment, resolution, frames", [
    ("dress", 0.04, 3), ("circle_skirt", 0.04, 3),
    pytest.param("dress", 0.02, 50, marks=pytest.mark.slow), pytest.param("tshirt", 0.02, 50, marks=pytest.mark.slow),
    pytest.param("skirt", 0.02, 50, marks=pytest.mark.slow), pytest.param("trousers", 0.02, 50, marks=pytest.mark.slow),
    pytest.param("circle_skirt", 0.02, 50, marks=pytest.mark.slow)])
def test_walking_garments_do_not_pass_through_themselves(garment, resolution, frames):
    """Every frame written is free of edges through the garment's own triangles (the check a renderer
    trips on), untangled where sewing or the walk made some, and nothing enters the body. Without
    untangling the 2 cm dress kept 96 crossings and the T-shirt 11 (at the armholes), the 4 cm
    circle skirt 155–164 (a fold at the hem); with untangling but without self-collision while
    sewing (the flare folding as its waist is drawn in) the circle skirt kept a knot of 4–7."""
    result = drape(read_pattern(PANELS / f"{garment}.json"), read_body("mannequin-walk"), frames=frames,
                   resolution=resolution)
    assert max(result.report.crossings_per_frame) == 0
    assert result.report.max_penetration_m <= 0.001


def test_a_skirt_sews_to_its_bodice_after_the_bodice_closes():
    """GarmentCode labels a dress's skirt waist ``lower_interface``: the seams joining it to the
    bodice form a second sewing stage, so the bodice closes over the shoulders before the heavier
    skirt can draw it down. A skirt's band (its labelled edge free) needs no second stage."""
    from conftest import doc_with, gc_skirt_doc, rect_panel
    from tailor.dress.garment import Garment
    from tailor.io import pattern_from_dict
    from tailor.mesh import discretise

    def plan(doc):
        pattern = pattern_from_dict(doc, source="dress.json")
        mesh = discretise(pattern, 0.05)
        garment = Garment(pattern, mesh, {i: pattern.fabric for i in range(len(pattern.panels))}, 0.01)
        return pattern, mesh, garment

    skirt = rect_panel(40, 30)
    skirt["edges"][2]["label"] = "lower_interface"
    doc = doc_with({"front": rect_panel(40, 40), "back": rect_panel(40, 40), "skirt": skirt},
                   [[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}],
                    [{"panel": "front", "edge": 0}, {"panel": "skirt", "edge": 2}]])
    pattern, mesh, garment = plan(doc)
    assert garment.stages == 2
    stages = garment.stage_plan()
    first = stages[0].sewing
    assert [(st.garment, st.dresses) for st in stages] == [(0, True), (0, False)]  # one garment: dressed once
    seam_of_pair = garment.sewing.seam
    assert set(seam_of_pair[first]) == {0} and set(seam_of_pair[~first]) == {1}
    assert plan(gc_skirt_doc())[2].stages == 1


def test_cloth_crossed_while_sewing_is_untangled_that_frame_not_at_the_next_weld(mannequin):
    """A vertex of the placed skirt pushed through a neighbouring panel: the self-collision keeps
    the side it finds, so only untangling undoes it. Sewing untangles every frame (a dress's skirt
    top slid over its bodice's bottom by the hundred between two welds), so the first sewing frame
    written, before any weld, already has no crossing."""
    from tailor.collide import edge_crossings
    from tailor.dress.phases import sew

    pattern = read_pattern(PANELS / "skirt.json")
    frames = []
    d, _, x0 = prepare(pattern, mannequin, DrapeOptions(resolution=0.08, frames=1, record_sewing=True),
                       on_frame=lambda i, x, bx: frames.append((x.copy(), d.garment.rebuilds)))
    mesh, x0 = d.garment.mesh, x0.copy()
    seam = np.zeros(mesh.vertex_count, bool)
    seam[np.asarray(mesh.seam_pairs).ravel()] = True
    faces, panel = np.asarray(mesh.faces), np.asarray(mesh.vertex_panel)
    v = np.flatnonzero(~seam & (panel == 0))[0]  # inside the first panel, on no seam
    other = faces[panel[faces[:, 0]] != 0]
    centre = x0[other].mean(axis=1)
    t = int(np.argmin(np.linalg.norm(centre - x0[v], axis=1)))
    a, b, c = x0[other[t]]
    normal = np.cross(b - a, c - a) / np.linalg.norm(np.cross(b - a, c - a))
    side = np.sign((x0[v] - centre[t]) @ normal)
    x0[v] = centre[t] - side * 0.005 * normal  # 5 mm past the nearest other panel
    assert len(edge_crossings(x0, faces)) > 0
    sew(d, x0)
    x, rebuilds = frames[0]
    assert rebuilds == 0  # written before the first weld
    assert len(edge_crossings(x, faces)) == 0
