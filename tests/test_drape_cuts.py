"""The brush and tearing on a sewn garment: `tailor drape --cuts FILE --tear` (issue 10)."""

import json
from dataclasses import replace

import numpy as np
import pytest

from conftest import PANELS

from tailor.cli import main
from tailor.dress import drape
from tailor.io import read_pattern
from tailor.io.body_files import read_body
from tailor.io.obj import read_obj
from tailor.tearing import Cut, boundary_loops

HOLE = (0.0, -0.15, 0.75)  # on the skirt's front, in the body's frame [m]


def _frames(out):
    return [read_obj(p) for p in sorted(out.glob("garment_*.obj"))]


def test_a_cuts_file_cuts_the_draped_skirt_and_each_obj_frame_has_its_own_mesh(tmp_path, capsys):
    cuts = tmp_path / "cuts.json"
    cuts.write_text(json.dumps({"cuts": [
        {"time": 0.04, "points": [[100 * c for c in HOLE]], "radius": 5},
        {"time": 0.08, "points": [[10, -15, 50], [10, -15, 70]], "radius": 6, "separate": True},
    ]}))
    out = tmp_path / "cut"
    assert main(["--quiet", "drape", str(PANELS / "skirt.json"), "--resolution", "4", "--frames", "4", "--cuts",
                 str(cuts), "--out", str(out)]) == 0
    assert "2 cuts and 0 edges torn" in capsys.readouterr().out
    frames = _frames(out)
    assert len(frames) == 4
    loops = [boundary_loops(f.faces) for f in frames]
    faces = [len(f.faces) for f in frames]
    verts = [len(f.vertices) for f in frames]
    assert loops[0] == 2 and loops[1] == 3  # waist and hem, then the hole
    assert faces[1] < faces[0] and faces[2] == faces[1]  # the hole removes cloth, the scissors none
    assert verts[2] > verts[1]  # ... but split the vertices along their line
    centroids = frames[1].vertices[frames[1].faces].mean(axis=1)
    assert np.linalg.norm(centroids - HOLE, axis=1).min() > 0.04  # the disc is gone (it moved < 1 cm since)
    for f in frames:
        assert np.isfinite(f.vertices).all()
        directed = np.stack([f.faces, np.roll(f.faces, -1, axis=1)], axis=2).reshape(-1, 2)
        assert len(np.unique(directed, axis=0)) == len(directed)  # consistently oriented, no duplicates
    report = json.loads((out / "report.json").read_text())
    assert report["tearing"]["topology_changes"] == 2 and report["max_penetration_m"] <= 0.002


def test_a_separating_cut_on_a_sewn_skirt_keeps_its_mass_and_unpicks_a_seam():
    """A cut along a side seam opens the seam: the welded vertices on it split, no triangle goes."""
    pattern = read_pattern(PANELS / "skirt.json")
    body = read_body("mannequin")
    base = drape(pattern, body, frames=1, resolution=0.04, settle=0.2, quality="normal")
    seam = base.frames[0][base.mesh.seam_pairs[base.mesh.seam_pair_seam == 0, 0]]  # the first side seam
    seam = seam[np.argsort(seam[:, 2])]
    cut = Cut(0.0, [seam[0] - (0, 0, 0.05), *seam[: len(seam) // 2]], 0.05, separate=True)  # from the hem up
    result = drape(pattern, body, frames=2, resolution=0.04, settle=0.2, cuts=[cut], quality="normal")
    mesh, weld = result.topology_at(0)
    assert mesh.face_count == base.mesh.face_count and int(weld.max()) > int(base.weld.max())
    assert result.report.tearing["events"][0]["edges"] >= len(seam) // 2 - 1
    assert boundary_loops(weld[mesh.faces]) == 2  # the slit from the hem opened the hem loop up the seam
    from tailor.model import build_model
    fabrics = {i: p.fabric or pattern.fabric for i, p in enumerate(pattern.panels)}
    m0 = build_model(base.mesh, fabrics, weld=base.weld).vertex_mass.sum()
    m1 = build_model(mesh, fabrics, weld=weld).vertex_mass.sum()
    assert m1 == pytest.approx(m0, rel=1e-12)


def test_the_skirt_tears_only_when_its_fabric_is_weak():
    pattern = read_pattern(PANELS / "skirt.json")
    body = read_body("mannequin")
    cotton = pattern.fabric
    strong = drape(pattern, body, replace(cotton, tear_strain=0.25), frames=3, resolution=0.04, settle=0.2, tear=True,
                   quality="normal")
    assert strong.report.tearing["edges_torn"] == 0 and not strong.topology
    weak = drape(pattern, body, replace(cotton, tear_strain=0.005), frames=3, resolution=0.04, settle=0.2, tear=True,
                 quality="normal")
    assert weak.report.tearing["edges_torn"] > 0 and weak.topology
    assert all(np.isfinite(f).all() for f in weak.frames)


@pytest.mark.parametrize("doc,field", [
    ("{", "malformed JSON"),
    ({"cuts": [{"time": 0.1, "points": [[0, 0, 0]], "radius": -1}]}, "cuts[0].radius: must be positive"),
    ({"cuts": [{"time": 0.1, "points": [[0, 0, 0]], "radius": 2, "separate": True}]}, "cuts[0].points: a separating"),
    ({"cuts": [{"time": 0.1, "points": [[0, 0]], "radius": 2}]}, "cuts[0].points[0]: expected 3 items"),
    ({"cuts": [{"tim": 0.1}]}, "did you mean 'time'"),
])
def test_bad_cuts_files_give_one_line_and_exit_2(tmp_path, capsys, doc, field):
    cuts = tmp_path / "cuts.json"
    cuts.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    out = tmp_path / "out"
    assert main(["drape", str(PANELS / "skirt.json"), "--cuts", str(cuts), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cuts.json" in err[0] and field in err[0] and not out.exists()


def test_cuts_refuse_formats_that_need_one_mesh(tmp_path, capsys):
    cuts = tmp_path / "cuts.json"
    cuts.write_text(json.dumps({"cuts": []}))
    out = tmp_path / "out"
    assert main(["drape", str(PANELS / "skirt.json"), "--cuts", str(cuts), "--format", "glb", "--out", str(out)]) == 2
    assert "only the OBJ sequence" in capsys.readouterr().err and not out.exists()
