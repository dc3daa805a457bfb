"""The parametric mannequin: measured like the tape it was made from, watertight, walking on the floor."""

import numpy as np
import pytest

from tailor.collide import self_intersections
from tailor.io.body_files import BODIES_DIR, make_bodies, read_body
from tailor.mannequin import MEASUREMENT_PRESETS, make_mannequin, walk_cycle
from tailor.measure import find_landmarks

DEFAULT = MEASUREMENT_PRESETS["default"]


@pytest.fixture(scope="module")
def landmarks(mannequin):
    return find_landmarks(mannequin.vertices, mannequin.faces)


@pytest.mark.parametrize("name,girth", [("bust", DEFAULT.bust), ("waist", DEFAULT.waist), ("hips", DEFAULT.hips),
                                        ("underbust", DEFAULT.underbust)])
def test_girths_match_the_tape_within_2cm(landmarks, name, girth):
    assert landmarks[name].girth == pytest.approx(girth, abs=0.02)


@pytest.mark.parametrize("name,height", [("crotch", DEFAULT.crotch_z), ("hips", DEFAULT.hips_z), ("waist", DEFAULT.waist_z),
                                         ("bust", DEFAULT.bust_z), ("shoulders", DEFAULT.shoulder_z)])
def test_landmark_heights_within_2cm(landmarks, name, height):
    assert landmarks[name].height == pytest.approx(height, abs=0.02)


def test_height_and_arm_pose(mannequin, landmarks):
    assert mannequin.height == pytest.approx(DEFAULT.height, abs=0.02)
    for side, sign in (("left", 1), ("right", -1)):
        axis = np.array(landmarks[f"{side}_elbow"].axis)  # towards the shoulder
        down = np.degrees(np.arcsin(axis[2]))
        assert down == pytest.approx(np.degrees(DEFAULT.arm_angle), abs=3.0)
        assert sign * landmarks[f"{side}_wrist"].center[0] > 0.4


def test_watertight_and_not_self_intersecting(mannequin):
    import trimesh

    mesh = trimesh.Trimesh(mannequin.vertices, mannequin.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0.05  # m³, outward normals
    assert 5_000 <= len(mannequin.faces) <= 20_000
    assert len(self_intersections(mannequin.vertices, mannequin.faces)) == 0


def test_walk_keeps_topology_and_feet_on_or_above_the_floor():
    walk = read_body("mannequin-walk")
    assert walk.frame_count == 25 and walk.fps == 25.0
    rest = read_body("mannequin")
    assert walk.frames.shape[1] == rest.vertices.shape[0] and np.array_equal(walk.faces, rest.faces)
    lows = walk.frames[:, :, 2].min(axis=1)
    assert np.all(lows >= -1e-4) and np.all(lows <= 1e-4)  # standing on the floor, never below it
    feet = walk.frames[:, walk.frames[0][:, 2] < 0.05]
    assert np.ptp(feet[:, :, 1], axis=0).max() > 0.2  # the feet really stride (> 20 cm)
    x, v = walk.at(0.02)
    assert np.isfinite(v).all() and np.abs(v).max() < 5.0  # m/s, a walk


def test_shipped_bodies_are_what_the_code_makes(tmp_path):
    rest, walk = make_bodies(tmp_path)
    for name in ("mannequin.obj", "mannequin_walk.npz"):
        shipped, fresh = read_body(BODIES_DIR / name), read_body(tmp_path / name)
        assert shipped.frames.shape == fresh.frames.shape
        assert np.abs(shipped.frames - fresh.frames).max() < 1e-4


def test_other_measurements_make_another_body():
    man = make_mannequin(MEASUREMENT_PRESETS["man"], resolution=0.025, calibrate=2)
    marks = find_landmarks(man.vertices, man.faces)
    assert marks["waist"].girth == pytest.approx(MEASUREMENT_PRESETS["man"].waist, abs=0.02)
    assert np.ptp(man.vertices[:, 2]) == pytest.approx(1.78, abs=0.02)
    assert walk_cycle(man, frames=5).shape == (5, len(man.vertices), 3)


def test_shoulders_fall_from_the_neck_at_the_shoulder_slope(mannequin):
    """The top of the trunk falls tan(slope) per metre outwards from the neck (a flat 'coat-hanger'
    top held GarmentCode's T-shirt 4 cm too low and it slid off)."""
    v = mannequin.vertices

    def top(x):
        near = (np.abs(v[:, 0] - x) < 0.008) & (np.abs(v[:, 1]) < 0.03) & (v[:, 2] > 1.3) & (v[:, 2] < 1.52)
        return v[near, 2].max()

    inner, outer = 0.5 * DEFAULT.neck_width + 0.01, 0.5 * DEFAULT.shoulder_width - 0.02
    fall = top(inner) - top(outer)
    assert fall == pytest.approx(np.tan(DEFAULT.shoulder_slope) * (outer - inner), abs=0.005)  # flat top: 6 mm
