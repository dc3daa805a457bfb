"""A pattern of one size on a body of another: loops checked up front, grading to the body with seams matched."""

import json

import numpy as np
import pytest

from conftest import PANELS
from tailor.body import Body, normalise_body
from tailor.cli import main
from tailor.corpus import mannequin_variants
from tailor.dress import drape
from tailor.io import read_pattern
from tailor.io.body_files import read_body
from tailor.io.obj import write_obj
from tailor.io.pattern_json import pattern_from_dict, reshaped_document
from tailor.measure import measure_body
from tailor.sizing import REGIONS, FitError, check_loops, grade, pattern_loops


@pytest.fixture(scope="module")
def design():
    return measure_body(read_body("mannequin"))


@pytest.fixture(scope="module")
def heavy():
    """The BMI-40 mannequin (waist 118 cm, bust 128 cm) as a Body, and its landmarks."""
    b = mannequin_variants(["bmi-40"])[0]
    frames, faces, report = normalise_body(b.vertices, b.faces)
    body = Body(frames, faces, 25.0, "bmi-40", {**report, "source": "bmi-40.obj"})
    return body, measure_body(body)


def test_loops_are_the_sewn_widths_round_each_landmark():
    skirt = {lp.landmark: lp for lp in pattern_loops(read_pattern(PANELS / "skirt.json"))}
    assert set(skirt) == {"waist"} and skirt["waist"].length == pytest.approx(0.88, abs=1e-6)  # two 44 cm bands
    tshirt = {lp.landmark: lp for lp in pattern_loops(read_pattern(PANELS / "tshirt.json"))}
    assert set(tshirt) == {"chest", "left_upper_arm", "right_upper_arm"}
    doc = json.loads((PANELS / "tshirt.json").read_text())
    front = np.array(doc["pattern"]["panels"]["front"]["vertices"])
    assert tshirt["chest"].length == pytest.approx(2 * np.ptp(front[:, 0]) / 100, rel=0.02)


def test_a_loop_smaller_than_the_body_is_one_line_up_front(heavy):
    body, marks = heavy
    with pytest.raises(FitError) as info:
        check_loops(read_pattern(PANELS / "skirt.json"), marks)
    msg = str(info.value)
    assert "\n" not in msg and "skirt.json: the waist loop" in msg and "88.0 cm" in msg and "--grade auto" in msg
    assert f"{marks['waist'].girth * 100:.1f} cm" in msg
    with pytest.raises(FitError, match="chest loop"):
        drape(read_pattern(PANELS / "tshirt.json"), body, frames=1, resolution=0.1)


@pytest.mark.parametrize("name", ["skirt", "tshirt", "trousers"])
def test_grading_keeps_the_design_ease_and_the_seams_matched(heavy, design, name):
    body, marks = heavy
    pattern = read_pattern(PANELS / f"{name}.json")
    graded, scales = grade(pattern, marks, design)
    before = {lp.landmark: lp for lp in check_loops(pattern, design)}
    for loop in check_loops(graded, marks):  # no FitError now
        relative = loop.length / loop.girth
        if loop.landmark in REGIONS["arm"] + REGIONS["leg"]:  # a limb panel gives way to its seam to the trunk
            assert loop.ease > 0, loop.landmark
        else:
            assert relative == pytest.approx(before[loop.landmark].length / before[loop.landmark].girth, rel=0.03), loop.landmark
    for a, b in zip(pattern.seams, graded.seams):
        ratio0 = pattern.side_length(a.a) / pattern.side_length(a.b)
        ratio1 = graded.side_length(b.a) / graded.side_length(b.b)
        assert ratio1 == pytest.approx(ratio0, rel=0.03), f"seam {a.index}"
    assert all(sx > 1.05 for sx, _ in scales.values())  # every panel got wider for this body


def test_the_graded_file_reads_back_as_the_graded_pattern(heavy, design):
    body, marks = heavy
    doc = json.loads((PANELS / "trousers.json").read_text())
    graded, _ = grade(pattern_from_dict(doc), marks, design)
    back = pattern_from_dict(reshaped_document(doc, graded))
    for p, q in zip(graded.panels, back.panels):
        assert np.abs(np.subtract(p.vertices, q.vertices)).max() < 1e-9
    for s, t in zip(graded.seams, back.seams):
        assert graded.side_length(s.a) == pytest.approx(back.side_length(t.a), abs=1e-9)


def test_cli_grade_writes_a_pattern_that_drapes_and_drape_grade_auto(tmp_path, heavy, capsys):
    body, _ = heavy
    path = tmp_path / "heavy.obj"
    write_obj(path, body.vertices * 100.0, body.faces)  # in cm, as a user's file
    out = tmp_path / "skirt_graded.json"
    assert main(["drape", str(PANELS / "skirt.json"), "--body", str(path), "--out", str(tmp_path / "no"), "--frames", "1",
                 "--resolution", "10"]) == 2
    assert "waist loop" in capsys.readouterr().err
    assert main(["grade", str(PANELS / "skirt.json"), "--body", str(path), "--out", str(out)]) == 0
    assert "ease" in capsys.readouterr().out
    graded = read_pattern(out)
    loops = check_loops(graded, measure_body(read_body(path)))
    assert loops[0].ease > 0
    run = tmp_path / "run"
    assert main(["-q", "drape", str(PANELS / "skirt.json"), "--body", str(path), "--grade", "auto", "--out", str(run),
                 "--frames", "1", "--resolution", "10", "--quality", "draft"]) == 0
    report = json.loads((run / "report.json").read_text())
    assert report["loops"]["waist"]["ease_cm"] > 0 and report["max_penetration_m"] <= 0.002


def test_grading_from_the_design_body_it_was_drafted_for(tmp_path, heavy, design):
    """A GarmentCode measurement YAML names the design body: the default's measurements grade like the default
    mannequin, and a pattern graded from the target's own measurements hardly changes."""
    from tailor.corpus import VARIANTS
    from tailor.io.body_files import GARMENTCODE_BODY, design_landmarks
    from tailor.units import CM, DEG

    body, marks = heavy
    m = VARIANTS["bmi-40"]
    yaml_text = "body:\n" + "".join(
        f"  {gc}: {getattr(m, ours) / (DEG if ours in ('arm_angle', 'shoulder_slope') else CM):.6g}\n"
        for gc, ours in GARMENTCODE_BODY.items())
    (tmp_path / "own.yaml").write_text(yaml_text)
    pattern = read_pattern(PANELS / "skirt.json")
    _, scales = grade(pattern, marks, design_landmarks(tmp_path / "own.yaml"))
    for name, (sx, sy) in scales.items():
        assert sx == pytest.approx(1.0, abs=0.04) and sy == pytest.approx(1.0, abs=0.04), name
    (tmp_path / "bad.yaml").write_text("body:\n  waist: lots\n")
    assert main(["grade", str(PANELS / "skirt.json"), "--body", "mannequin", "--design-body", str(tmp_path / "bad.yaml"),
                 "--out", str(tmp_path / "x.json")]) == 2
    assert not (tmp_path / "x.json").exists()
