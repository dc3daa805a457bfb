"""Discretisation: quality, scaling, exact area, seam pairing, reproducibility."""

import math

import numpy as np
import pytest

from conftest import PANELS, doc_with, rect_panel
from tailor.curves import sample_curve
from tailor.errors import MeshingError
from tailor.geometry import face_signed_areas_2d
from tailor.io import pattern_from_dict, read_pattern
from tailor.mesh import MIN_ANGLE_DEG, discretise

SHIPPED = sorted(PANELS.glob("*.json"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_patterns_mesh_with_quality_and_exact_area(path):
    pattern = read_pattern(path)
    mesh = discretise(pattern)  # default 1.5 cm
    assert mesh.min_angle() >= MIN_ANGLE_DEG
    # every triangle's area is positive in its panel's winding (outward normals)
    for pi, panel in enumerate(pattern.panels):
        sign = np.sign(face_signed_areas_2d(mesh.uv, mesh.faces[mesh.face_panel == pi]))
        assert np.all(sign == np.sign(panel.signed_area))
        # area within 0.5 % of the exact panel area, curved edges included
        area = mesh.face_rest_area[mesh.face_panel == pi].sum()
        assert area == pytest.approx(panel.area, rel=5e-3)


def test_vertex_count_scales_as_inverse_square_of_resolution():
    pattern = read_pattern(PANELS / "tshirt.json")
    counts = [discretise(pattern, h).vertex_count for h in (0.04, 0.02, 0.01)]
    ratios = np.array(counts[1:]) / np.array(counts[:-1])
    assert np.all((ratios > 3.3) & (ratios < 4.7)), ratios  # ~4 per halving; boundary adds ~1/h


def test_edges_close_to_target_length():
    mesh = discretise(read_pattern(PANELS / "flag.json"), 0.02)
    e = np.concatenate([mesh.faces[:, [0, 1]], mesh.faces[:, [1, 2]], mesh.faces[:, [2, 0]]])
    lengths = np.linalg.norm(mesh.uv[e[:, 0]] - mesh.uv[e[:, 1]], axis=1)
    assert 0.6 * 0.02 < np.median(lengths) < 1.2 * 0.02


def test_seam_sides_pair_one_to_one_at_equal_arc_length(two_panel_doc):
    two_panel_doc["pattern"]["panels"]["back"] = rect_panel(30, 36)  # 10 % ease on the back sides
    pattern = pattern_from_dict(two_panel_doc)
    mesh = discretise(pattern, 0.015)
    for si in range(len(pattern.seams)):
        pairs = mesh.seam_pairs[mesh.seam_pair_seam == si]
        assert len(pairs) == 28  # the longer side's round(40 / 1.5) = 27 segments, on both sides
        ya, yb = mesh.uv[pairs[:, 0], 1], mesh.uv[pairs[:, 1], 1]
        # same fraction of each side's length, running opposite ways along the edges (half-edge rule)
        fa, fb = ya / 0.40, yb / 0.36
        assert np.allclose(fa, fb, atol=1e-9)
        assert len(np.unique(pairs[:, 0])) == len(pairs)


def test_tube_from_one_panel_pairs_bottom_with_bottom(tube_doc):
    pattern = pattern_from_dict(tube_doc)
    mesh = discretise(pattern, 0.02)
    a, b = mesh.seam_pairs.T
    assert np.allclose(mesh.uv[a, 1], mesh.uv[b, 1])  # no twist: each height meets itself
    assert np.allclose(mesh.uv[a, 0], 0.30) and np.allclose(mesh.uv[b, 0], 0.0)


def test_sub_range_seams_share_the_edge_split():
    pattern = read_pattern(PANELS / "trousers.json")
    mesh = discretise(pattern, 0.015)
    wb = pattern.panel_index("wb_front")
    band = mesh.edge_vertices[(wb, None, 0)]
    halves = [mesh.seam_pairs[mesh.seam_pair_seam == s.index] for s in pattern.seams if s.a.panel == "wb_front" and s.a.edge == 0]
    assert len(halves) == 2
    together = np.concatenate([h[:, 0] for h in halves])
    assert set(together) == set(band)  # the two halves cover the band's edge, meeting in one vertex
    assert len(together) == len(band) + 1


def test_curved_seam_points_lie_on_their_curves():
    pattern = read_pattern(PANELS / "tshirt.json")
    mesh = discretise(pattern, 0.015)
    front = pattern.panel_index("front")
    ids = mesh.edge_vertices[(front, None, 2)]  # the armhole, a cubic
    curve = pattern.panels[front].edges[2].curve
    dense = sample_curve(curve, np.linspace(0, 1, 4001))
    d = np.min(np.linalg.norm(mesh.uv[ids][:, None] - dense[None], axis=2), axis=1)
    assert d.max() < 1e-4
    step = np.linalg.norm(np.diff(mesh.uv[ids], axis=0), axis=1)
    assert step.std() / step.mean() < 0.02  # even spacing by arc length


def test_meshes_are_reproducible():
    pattern = read_pattern(PANELS / "dress.json")
    m1, m2 = discretise(pattern, 0.02), discretise(pattern, 0.02)
    assert np.array_equal(m1.uv, m2.uv) and np.array_equal(m1.faces, m2.faces)
    assert np.array_equal(m1.seam_pairs, m2.seam_pairs)


def test_holes_stay_empty_and_darts_pair_across_the_hole():
    pattern = read_pattern(PANELS / "dress.json")
    mesh = discretise(pattern, 0.015)
    back = pattern.panel_index("back")
    assert mesh.face_rest_area[mesh.face_panel == back].sum() == pytest.approx(pattern.panels[back].area, rel=5e-3)
    dart = [s.index for s in pattern.seams if s.a.hole == 0]
    pairs = mesh.seam_pairs[np.isin(mesh.seam_pair_seam, dart)]
    ya, yb = mesh.uv[pairs[:, 0], 1], mesh.uv[pairs[:, 1], 1]
    assert np.allclose(ya, yb, atol=1e-9)  # a dart's two legs meet at equal heights


def test_grain_frame_per_face():
    doc = doc_with({"a": rect_panel(10, 10, grain=0), "b": rect_panel(10, 10, grain=45)})
    mesh = discretise(pattern_from_dict(doc), 0.02)
    assert np.allclose(mesh.face_grain[mesh.face_panel == 0], [1, 0])
    assert np.allclose(mesh.face_grain[mesh.face_panel == 1], [math.sqrt(0.5)] * 2)


def test_bad_resolution_is_an_error(square_doc):
    with pytest.raises(MeshingError, match="resolution must be a positive length"):
        discretise(pattern_from_dict(square_doc), -1.0)
