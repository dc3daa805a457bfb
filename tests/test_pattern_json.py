"""Loading pattern files: conversion to SI, and one clear error per kind of bad input."""

import copy
import json
import math

import numpy as np
import pytest

from conftest import PANELS, doc_with, gc_skirt_doc, rect_panel
from tailor.errors import PatternError, SeamError
from tailor.io import pattern_from_dict, read_pattern


def load(doc, source="p.json"):
    return pattern_from_dict(doc, source=source)


def error_of(doc) -> str:
    with pytest.raises(PatternError) as info:
        load(doc)
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith("p.json: ")
    return msg


# -- conversion ---------------------------------------------------------------------------------
def test_units_become_metres_and_area_is_exact(square_doc):
    p = load(square_doc)
    assert p.panels[0].vertices[2] == pytest.approx((0.2, 0.2))
    assert p.area == pytest.approx(0.04)
    square_doc["properties"]["units_in_meter"] = 1000  # millimetres
    assert load(square_doc).area == pytest.approx(0.0004)


def test_garmentcode_transform_becomes_z_up_facing_minus_y():
    # GarmentCode: Y up, body facing +Z. A panel 30 cm in front (z = 30) at height 100 cm.
    panel = rect_panel(10, 10, translation=[0, 100, 30], rotation=[0, 0, 0])
    p = load(doc_with({"front": panel}))
    world = p.panels[0].placement.apply(np.array([[0.0, 0.0], [0.1, 0.1]]))
    assert world[0] == pytest.approx([0.0, -0.3, 1.0])  # in front = −Y, height = +Z
    assert world[1] == pytest.approx([0.1, -0.3, 1.1])


def test_garmentcode_rotation_is_euler_xyz_degrees():
    panel = rect_panel(10, 10, rotation=[0, 90, 0])  # about GarmentCode's vertical (y) axis
    p = load(doc_with({"side": panel}))
    world = p.panels[0].placement.apply(np.array([[0.1, 0.0]]))[0]
    # R_y(90°)·(0.1, 0, 0) = (0, 0, −0.1) in GarmentCode → (0, 0.1, 0) in tailor's frame
    assert world == pytest.approx([0.0, 0.1, 0.0], abs=1e-12)


def test_relative_curvature_control_point():
    panel = rect_panel(20, 10)
    panel["edges"][0]["curvature"] = {"type": "quadratic", "params": [[0.5, -0.5]]}
    p = load(doc_with({"a": panel}))
    # control = start + 0.5·(20, 0) − 0.5·(0, 20) = (10, −10) cm
    assert p.panels[0].edges[0].curve.points[1] == pytest.approx((0.10, -0.10))


def test_fabric_numbers_convert_from_designer_units():
    doc = doc_with({"a": rect_panel(10, 10)}, fabric={"preset": "silk", "density": 60, "stretch": 5, "thickness": 0.4})
    f = load(doc).fabric
    assert (f.density, f.stretch_warp, f.stretch_weft, f.thickness) == pytest.approx((0.06, 0.05, 0.05, 0.0004))


def test_seam_orientation_default_is_half_edge(two_panel_doc):
    seam = load(two_panel_doc).seams[0]
    assert seam.orientation == "auto:opposite"
    assert (seam.b.start, seam.b.end) == (1.0, 0.0)


def test_seam_orientation_from_placement_when_decisive():
    # Two panels side by side, both facing −Y: front's right edge (going up) lies on the
    # other's left edge (going down): 'opposite'. Mirror the second so its edge goes up: 'same'.
    a = rect_panel(10, 10, translation=[0, 0, 0])
    b = rect_panel(10, 10, translation=[10, 0, 0])
    doc = doc_with({"a": a, "b": b}, [[{"panel": "a", "edge": 1}, {"panel": "b", "edge": 3}]])
    assert load(doc).seams[0].orientation == "auto:opposite"
    b2 = {"vertices": [[0, 0], [0, 10], [10, 10], [10, 0]], "edges": [{"endpoints": [i, (i + 1) % 4]} for i in range(4)],
          "translation": [10, 0, 0]}
    doc = doc_with({"a": a, "b": b2}, [[{"panel": "a", "edge": 1}, {"panel": "b", "edge": 0}]])
    assert load(doc).seams[0].orientation == "auto:same"


def test_read_pattern_names_file_and_reports_json_position(tmp_path):
    f = tmp_path / "broken.json"
    f.write_text('{"pattern": {\n  "panels": {,}\n}}')
    with pytest.raises(PatternError, match=r"^broken\.json: line 2 column 14: malformed JSON"):
        read_pattern(f)
    with pytest.raises(PatternError, match="no such pattern file"):
        read_pattern(tmp_path / "missing.json")


# -- one error per mistake -----------------------------------------------------------------------
def test_unknown_key_suggests_the_right_one(square_doc):
    square_doc["pattern"]["panels"]["sq"]["vertice"] = []
    msg = error_of(square_doc)
    assert "pattern.panels.sq.vertice" in msg and "did you mean 'vertices'" in msg


def test_missing_field(square_doc):
    del square_doc["pattern"]["panels"]["sq"]["edges"]
    assert "pattern.panels.sq: missing field 'edges'" in error_of(square_doc)


def test_non_numeric_coordinate(square_doc):
    square_doc["pattern"]["panels"]["sq"]["vertices"][1][0] = "20cm"
    assert "pattern.panels.sq.vertices[1][0]: expected a number, got a string" in error_of(square_doc)


@pytest.mark.parametrize(
    "field,value,needle",
    [
        (("fabric",), {"density": -5}, "fabric.density: must be positive"),
        (("fabric",), {"stretch": 0}, "fabric.stretch: must be positive"),
        (("fabric",), {"bending": -1}, "fabric.bending: must be >= 0"),
        (("properties", "units_in_meter"), -100, "properties.units_in_meter: must be positive"),
        (("fabric",), "brocade", "unknown fabric 'brocade'"),
    ],
)
def test_bad_numbers(square_doc, field, value, needle):
    node = square_doc
    for k in field[:-1]:
        node = node[k]
    node[field[-1]] = value
    assert needle in error_of(square_doc)


def test_a_curve_beyond_what_a_float_can_place_names_its_edge():
    """A curvature of 1e169 (a mutated file, found by the fuzz test) overflows the curve's sampling:
    a one-line error naming the edge, not shapely's exception on NaN coordinates."""
    doc = json.loads((PANELS / "circle_skirt.json").read_text())
    doc["pattern"]["panels"]["skirt_front"]["edges"][1]["curvature"]["params"][0] = 1e169
    assert "pattern.panels.skirt_front.edges[1]: curve is out of range" in error_of(doc)


def test_fewer_than_three_vertices(square_doc):
    square_doc["pattern"]["panels"]["sq"]["vertices"] = [[0, 0], [1, 0]]
    assert "pattern.panels.sq.vertices: expected at least 3 items, got 2" in error_of(square_doc)


def test_edge_vertex_index_out_of_range(square_doc):
    square_doc["pattern"]["panels"]["sq"]["edges"][2]["endpoints"] = [2, 7]
    assert "pattern.panels.sq.edges[2].endpoints[1]: vertex index 7 does not exist" in error_of(square_doc)


def test_edges_must_form_a_closed_loop(square_doc):
    square_doc["pattern"]["panels"]["sq"]["edges"][1]["endpoints"] = [2, 1]
    assert "do not form a closed loop" in error_of(square_doc)


def test_zero_area_outline():
    panel = {"vertices": [[0, 0], [10, 0], [20, 0]], "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 0]}]}
    assert "pattern.panels.flat: outline has zero area" in error_of(doc_with({"flat": panel}))


def test_self_intersecting_outline_is_located_in_cm():
    bowtie = {"vertices": [[0, 0], [10, 10], [10, 0], [0, 10]], "edges": [{"endpoints": [i, (i + 1) % 4]} for i in range(4)]}
    msg = error_of(doc_with({"bow": bowtie}))
    assert "pattern.panels.bow: outline crosses itself" in msg and "(5.0, 5.0) cm" in msg


def test_curve_that_makes_the_outline_cross_itself(square_doc):
    square_doc["pattern"]["panels"]["sq"]["edges"][0]["curvature"] = {"type": "quadratic", "params": [[0.5, 3.0]]}
    assert "outline crosses itself" in error_of(square_doc)


def test_hole_outside_its_panel(square_doc):
    hole = {"vertices": [[30, 30], [35, 30], [35, 35]], "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 0]}]}
    square_doc["pattern"]["panels"]["sq"]["holes"] = [hole]
    assert "pattern.panels.sq.holes[0]: hole is not inside the panel outline" in error_of(square_doc)


def test_circle_radius_too_small(square_doc):
    square_doc["pattern"]["panels"]["sq"]["edges"][0]["curvature"] = {"type": "circle", "params": [5, 0, 1]}
    assert "edges[0].curvature.params[0]: arc radius 5 is smaller than half the chord 10" in error_of(square_doc)


def test_seam_to_missing_panel(two_panel_doc):
    two_panel_doc["pattern"]["stitches"][0][1]["panel"] = "bak"
    msg = error_of(two_panel_doc)
    assert "pattern.stitches[0][1].panel: unknown value 'bak'" in msg and "did you mean 'back'" in msg


def test_seam_to_missing_edge(two_panel_doc):
    two_panel_doc["pattern"]["stitches"][1][0]["edge"] = 4
    assert "pattern.stitches[1][0].edge: edge index 4 does not exist (there are 4)" in error_of(two_panel_doc)


def test_edge_sewn_twice(two_panel_doc):
    two_panel_doc["pattern"]["stitches"].append([{"panel": "front", "edge": 1}, {"panel": "back", "edge": 0}])
    with pytest.raises(SeamError, match=r"stitches\[2\]\[0\]: edge 1 of panel 'front' is already sewn by pattern.stitches\[0\]"):
        load(two_panel_doc)


def test_disjoint_ranges_of_one_edge_may_be_sewn_separately(two_panel_doc):
    two_panel_doc["pattern"]["panels"]["extra"] = rect_panel(15, 40)
    two_panel_doc["pattern"]["stitches"] = [
        [{"panel": "front", "edge": 0, "range": [0, 0.5]}, {"panel": "extra", "edge": 0}],
        [{"panel": "front", "edge": 0, "range": [0.5, 1]}, {"panel": "extra", "edge": 2}],
    ]
    assert len(load(two_panel_doc).seams) == 2


def test_seam_lengths_too_different(two_panel_doc):
    two_panel_doc["pattern"]["panels"]["back"] = rect_panel(30, 25)  # 25 cm side sewn to 40 cm side
    with pytest.raises(SeamError, match=r"stitches\[0\]: sewn lengths differ too much: 40.0 cm .* vs 25.0 cm .* 38% > the 25% ease limit"):
        load(two_panel_doc)


def test_unknown_landmark(square_doc):
    square_doc["pattern"]["panels"]["sq"]["placement"] = {"landmark": "wasit"}
    msg = error_of(square_doc)
    assert "pattern.panels.sq.placement.landmark: unknown value 'wasit'" in msg and "did you mean 'waist'" in msg


def test_placement_and_transform_are_exclusive(square_doc):
    square_doc["pattern"]["panels"]["sq"].update(placement={"landmark": "waist"}, translation=[0, 0, 0])
    assert "either 'placement' or 'translation'" in error_of(square_doc)


def test_attachment_target_and_vertex(square_doc):
    square_doc["pattern"]["attachments"] = [{"panel": "sq", "vertex": 9, "to": "pin"}]
    assert "pattern.attachments[0].vertex: vertex index 9 does not exist" in error_of(square_doc)
    square_doc["pattern"]["attachments"] = [{"panel": "sq", "edge": 2, "to": "nek"}]
    assert "did you mean 'neck'" in error_of(square_doc)


def test_a_free_lower_interface_edge_is_held_at_the_waist():
    """GarmentCode labels a lower garment's waist ``lower_interface``; its files have no attachments.
    A free edge so labelled is attached to the waist; a sewn one (a dress's bodice to its skirt) is
    not, and a file's own ``attachments``, even empty, are kept as they are."""
    doc = gc_skirt_doc()
    held = load(doc).attachments
    assert {(a.panel, a.edge, a.target) for a in held} == {("wb_front", 2, "waist"), ("wb_back", 1, "waist")}
    sewn = copy.deepcopy(doc)
    sewn["pattern"]["panels"]["skirt_front"]["edges"][2]["label"] = "lower_interface"  # sewn to the band
    assert len(load(sewn).attachments) == 2
    doc["pattern"]["attachments"] = []
    assert load(doc).attachments == ()


def test_garmentcode_files_load_unchanged(garmentcode_dir):
    for f in sorted(garmentcode_dir.glob("*_specification.json")):
        p = read_pattern(f)
        assert len(p.panels) >= 4 and len(p.seams) >= 6
        total = sum(panel.area for panel in p.panels)
        assert 0.3 < total < 2.0  # m² of fabric in a garment


def test_document_is_not_modified(square_doc):
    before = copy.deepcopy(square_doc)
    load(square_doc)
    assert json.dumps(before, sort_keys=True) == json.dumps(square_doc, sort_keys=True)
    assert math.isclose(load(square_doc).area, 0.04)
