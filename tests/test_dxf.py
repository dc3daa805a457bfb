"""Patterns from CAD: AAMA / ASTM DXF files from several exporters' dialects import with their
pieces, areas and seams, and drape without hand editing; broken files give one line and exit 2."""

import json

import numpy as np
import pytest

from tailor import drape, read_pattern
from tailor.cli import main
from tailor.io.body_files import read_body

pytest.importorskip("ezdxf")

from dxf_files import FOUR_GORES, gore_outline, write_aama  # noqa: E402

SEWN = {frozenset(("Front Left", "Back Left")), frozenset(("Front Right", "Back Right")),
        frozenset(("Front Left", "Front Right")), frozenset(("Back Left", "Back Right"))}


def _gore_area_cm2():
    p, _ = gore_outline(points=201)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _import(tmp_path, capsys=None, *args, **dialect):
    dxf = write_aama(tmp_path / "skirt.dxf", **dialect)
    out = tmp_path / "skirt.json"
    assert main(["import", str(dxf), "--out", str(out), *args]) == 0
    return read_pattern(out)


def _sewn(pattern):
    return {frozenset((s.a.panel, s.b.panel)) for s in pattern.seams}


@pytest.mark.parametrize("dialect", [
    {}, {"lwpolyline": False}, {"notch_points": True}, {"turn_points": False},
    {"scale": 1 / 2.54, "units_text": "ENGLISH"}, {"scale": 1.0, "units_text": None, "insunits": 5}],
    ids=["lwpolyline-mm", "polyline-r12", "notch-points", "no-turn-points", "inches", "cm-header"])
def test_every_dialect_imports_the_pieces_their_areas_and_seams(tmp_path, dialect):
    pattern = _import(tmp_path, **dialect)
    assert [p.name for p in pattern.panels] == list(FOUR_GORES)
    for panel in pattern.panels:
        assert panel.area * 1e4 == pytest.approx(_gore_area_cm2(), rel=0.01)
        assert panel.grain == pytest.approx(np.pi / 2)
    assert _sewn(pattern) == SEWN and len(pattern.seams) == 4


def test_a_four_gore_skirt_drafted_in_dxf_drapes_in_one_piece(tmp_path):
    pattern = _import(tmp_path)
    assert {a.panel for a in pattern.attachments} == set(FOUR_GORES)  # no waistband: held at the waist
    result = drape(pattern, read_body("mannequin"), frames=2, resolution=0.04)
    welded = int(result.weld.max()) + 1
    assert welded < result.mesh.vertex_count  # the seams were sewn
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = result.weld[result.mesh.faces]
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]]])
    pieces, _ = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(welded, welded)))
    assert pieces == 1
    assert result.report.max_penetration_m <= 0.002 and max(result.report.crossings_per_frame) == 0


def test_a_pair_becomes_two_mirrored_panels(tmp_path):
    pattern = _import(tmp_path, pieces={"Front": ([20.0], [35.0]), "Back": ([35.0], [20.0, 21.0])}, quantity=2)
    names = [p.name for p in pattern.panels]
    assert names == ["Front", "Front_2", "Back", "Back_2"]
    a, b = pattern.panels[0], pattern.panels[1]
    assert b.area == pytest.approx(a.area, rel=1e-6)
    assert len(pattern.seams) == 4  # each front to a back at the side, each piece to its copy at the centre


def test_a_pair_the_file_says_is_not_mirrored_stays_alike(tmp_path):
    pattern = _import(tmp_path, pieces={"Front": ([20.0], [35.0]), "Back": ([35.0], [20.0, 21.0])}, quantity=2,
                      mirror_text="N")
    a, b = pattern.panels[0], pattern.panels[1]
    np.testing.assert_allclose(np.asarray(b.vertices) - np.min(b.vertices, axis=0),
                               np.asarray(a.vertices) - np.min(a.vertices, axis=0), atol=1e-9)


def test_a_graded_file_reads_one_size(tmp_path, capsys):
    medium = _import(tmp_path, sizes=("M", "L"))
    assert len(medium.panels) == 4 and "sizes M, L in the file" in capsys.readouterr().out
    large = _import(tmp_path, None, "--size", "L", sizes=("M", "L"))
    assert large.panels[0].area > 1.02 * medium.panels[0].area
    dxf = tmp_path / "skirt.dxf"
    assert main(["import", str(dxf), "--out", str(tmp_path / "x.json"), "--size", "XL"]) == 2
    assert "--size XL: the file has sizes M, L" in capsys.readouterr().err


def _broken(tmp_path, kind):
    import ezdxf

    path = tmp_path / f"{kind}.dxf"
    if kind == "empty":
        path.write_text("")
    elif kind == "truncated":
        write_aama(path)
        path.write_bytes(path.read_bytes()[:2000])
    else:
        doc = ezdxf.new("R2000")
        block = doc.blocks.new("P0")
        if kind == "no-boundary":
            block.add_line((0, 0), (100, 0), dxfattribs={"layer": "1"})
        elif kind == "bow-tie":  # two equal lobes: no area
            block.add_lwpolyline([(0, 0), (100, 100), (100, 0), (0, 100)], close=True, dxfattribs={"layer": "1"})
        else:  # a figure eight with unequal lobes
            block.add_lwpolyline([(0, 0), (300, 200), (300, 0), (0, 100)], close=True, dxfattribs={"layer": "1"})
        doc.modelspace().add_blockref("P0", (0, 0))
        doc.saveas(path)
    return path


@pytest.mark.parametrize("kind, words", [("empty", "no pattern pieces"), ("truncated", ""),
                                         ("no-boundary", "no boundary on layer 1"), ("bow-tie", "P0"),
                                         ("figure-eight", "piece 'P0': the layer 1 boundary crosses itself near (")])
def test_a_broken_file_gives_one_line_and_exit_2(tmp_path, capsys, kind, words):
    path = _broken(tmp_path, kind)
    out = tmp_path / "out.json"
    assert main(["import", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("tailor: error: ") and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert words in err and not out.exists()


def test_without_ezdxf_import_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    import sys

    dxf = write_aama(tmp_path / "skirt.dxf")
    monkeypatch.setitem(sys.modules, "ezdxf", None)
    assert main(["import", str(dxf), "--out", str(tmp_path / "s.json")]) == 2
    assert 'pip install -e ".[dxf]"' in capsys.readouterr().err


def _centroid(panel):
    from tailor.curves import loop_polyline

    p = loop_polyline([e.curve for e in panel.edges])
    x, y = p[:, 0], p[:, 1]
    c = x * np.roll(y, -1) - np.roll(x, -1) * y
    return np.array([((x + np.roll(x, -1)) * c).sum(), ((y + np.roll(y, -1)) * c).sum()]) / (3.0 * c.sum())


def _seam_ends(pattern):
    """Each seam as the two pairs of points sewn together at its ends, in each panel's own frame
    about its centroid [m]: independent of edge numbering, side direction and panel origin."""
    from tailor.curves import sample_curve

    def point(side, s):
        panel = pattern.panels[pattern.panel_index(side.panel)]
        f = side.start + s * (side.end - side.start)
        return side.panel, sample_curve(panel.loop(side.hole)[side.edge].curve, [f])[0] - _centroid(panel)

    # a seam's sides run so that the points at equal fractions meet (the orientation is in them)
    return [[(point(seam.a, s), point(seam.b, s)) for s in (0.0, 1.0)] for seam in pattern.seams]


def _same_seam(x, y, tol=3e-3) -> bool:
    """Whether two seams (from :func:`_seam_ends`) sew the same points together, within ``tol`` [m]."""
    def same_pair(p, q):
        return any(all(a[0] == b[0] and np.linalg.norm(a[1] - b[1]) < tol for a, b in zip(p, qq)) for qq in (q, q[::-1]))
    return any(all(same_pair(p, q) for p, q in zip(x, yy)) for yy in (y, y[::-1]))


SHIPPED = sorted(p.stem for p in (__import__("pathlib").Path(__file__).parents[1] / "panels").glob("*.json"))


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_pattern_round_trips_through_dxf(tmp_path, name):
    original = read_pattern(f"panels/{name}.json")
    dxf, back = tmp_path / f"{name}.dxf", tmp_path / f"{name}.json"
    assert main(["export-pattern", f"panels/{name}.json", "--out", str(dxf)]) == 0
    assert main(["import", str(dxf), "--out", str(back)]) == 0
    again = read_pattern(back)
    assert [p.name for p in again.panels] == [p.name for p in original.panels]
    for a, b in zip(original.panels, again.panels):
        assert b.area == pytest.approx(a.area, rel=0.005), a.name
    assert len(again.seams) == len(original.seams)
    found = _seam_ends(again)
    for seam in _seam_ends(original):  # the same points sewn together
        assert any(_same_seam(seam, other) for other in found), seam


def test_a_seams_sidecar_names_sides_by_edge_or_notch_and_overrides_placement(tmp_path, capsys):
    dxf = write_aama(tmp_path / "skirt.dxf")
    sidecar = tmp_path / "seams.json"
    sidecar.write_text(json.dumps({
        "seams": [{"between": [{"piece": "Front Left", "notch": 1}, {"piece": "Back Left", "edge": 3}]},
                  {"between": [{"piece": "Front Left", "edge": 3}, {"piece": "Front Right", "notch": 1}]}],
        "placement": {"Back Left": {"landmark": "hips", "angle": 135}}}))
    out = tmp_path / "skirt.json"
    assert main(["import", str(dxf), "--out", str(out), "--seams", str(sidecar)]) == 0
    pattern = read_pattern(out)
    assert _sewn(pattern) == {frozenset(("Front Left", "Back Left")), frozenset(("Front Left", "Front Right"))}
    assert all(s.orientation == "opposite" for s in pattern.seams)  # as their notches say
    assert pattern.panels[2].placement.landmark == "hips"
    for bad, words in (({"seams": [{"between": [{"piece": "Nope", "edge": 0}, {"piece": "Back Left", "edge": 3}]}]},
                        "seams[0].between[0]"),
                       ({"seams": [{"between": [{"piece": "Front Left", "notch": 9}, {"piece": "Back Left", "edge": 3}]}]},
                        "seams[0].between[0].notch: piece 'Front Left' has notches 1 to 2"),
                       ({"placement": {"Nope": {}}}, "placement.Nope: no such piece")):
        sidecar.write_text(json.dumps(bad))
        capsys.readouterr()
        assert main(["import", str(dxf), "--out", str(tmp_path / "bad.json"), "--seams", str(sidecar)]) == 2
        err = capsys.readouterr().err
        assert words in err and str(sidecar) in err and len(err.strip().splitlines()) == 1


def test_notches_drill_holes_and_lines_are_kept_as_panel_marks(tmp_path):
    pattern = _import(tmp_path)
    kinds = [k for k, _ in pattern.panels[0].marks]
    assert kinds.count("notch") == 2 and kinds.count("drill_hole") == 1
    hole = np.asarray(dict(pattern.panels[0].marks)["drill_hole"][0]) - _centroid(pattern.panels[0])
    # (0, 30 cm) of the gore's own frame, whose centroid lies on x = 0
    assert hole[0] == pytest.approx(0.0, abs=1e-3)
    again = tmp_path / "again.dxf"
    assert main(["export-pattern", str(tmp_path / "skirt.json"), "--out", str(again)]) == 0
    assert main(["import", str(again), "--out", str(tmp_path / "again.json")]) == 0
    back = read_pattern(tmp_path / "again.json").panels[0]
    moved = np.asarray(dict(back.marks)["drill_hole"][0]) - _centroid(back)
    assert np.linalg.norm(moved - hole) < 1e-3
    from tailor.io.draw import draw_pattern

    draw_pattern(read_pattern(tmp_path / "again.json"), tmp_path / "marks.png")
    assert (tmp_path / "marks.png").stat().st_size > 1000


def test_a_round_tripped_pattern_drapes_as_the_original(tmp_path):
    """What a round trip must keep for the drape: which points meet (a seam's orientation is in its
    sides), the placements (tailor writes its own as a text other readers ignore), the waist hold."""
    assert main(["export-pattern", "panels/trousers.json", "--out", str(tmp_path / "t.dxf")]) == 0
    assert main(["import", str(tmp_path / "t.dxf"), "--out", str(tmp_path / "t.json")]) == 0
    pattern = read_pattern(tmp_path / "t.json")
    original = read_pattern("panels/trousers.json")
    assert [p.placement.landmark for p in pattern.panels] == [p.placement.landmark for p in original.panels]
    assert {a.panel for a in pattern.attachments} == {a.panel for a in original.attachments}
    result = drape(pattern, read_body("mannequin"), frames=1, resolution=0.04, fabric="denim")
    assert result.report.phases["sewing"].extra["max_gap_at_merge_m"] < 0.04
    assert max(result.report.crossings_per_frame) == 0 and result.report.max_penetration_m <= 0.002
