"""Fit maps (tailor.fit): stretch is the mesh's own, contact forces carry the garment's weight, and a
tighter pattern reads tighter."""

import json
import math

import numpy as np
import pytest

from tailor import drape, read_pattern
from tailor.cli import main
from tailor.fabric import preset
from tailor.fit import FitSource, face_stretch, fit_map
from tailor.geometry import face_areas
from tailor.io import pattern_from_dict
from tailor.io.body_files import read_body
from tailor.io.obj import read_obj
from tailor.units import GRAVITY

RES = 0.04


def read_ply(path):
    """(vertex table, face table) of a binary little-endian PLY as numpy structured arrays (an
    independent reader: the header's own property names and types)."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    elements, current = [], None
    for line in data[:end].decode("ascii").splitlines():
        words = line.split()
        if words[0] == "element":
            current = [words[1], int(words[2]), []]
            elements.append(current)
        elif words[0] == "property" and words[1] == "list":
            current[2] += [("n", "u1"), ("i", "<i4", (3,))]
        elif words[0] == "property":
            current[2].append((words[2], {"float": "<f4", "int": "<i4"}[words[1]]))
    out, offset = {}, end
    for name, count, props in elements:
        dt = np.dtype(props)
        out[name] = np.frombuffer(data, dt, count, offset)
        offset += count * dt.itemsize
    assert offset == len(data)
    return out["vertex"], out["face"]


def metric_stretch(uv, face_uv, x, faces):
    """Largest principal stretch [%] per face from its three edge lengths alone: the metric C (2×2,
    symmetric) with eᵀ·C·e = |edge in 3D|² for each flat edge e, then 100·(√λmax(C) − 1)."""
    out = []
    for fu, f in zip(face_uv, faces):
        rows, rhs = [], []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            e = uv[fu[b]] - uv[fu[a]]
            rows.append([e[0] ** 2, 2 * e[0] * e[1], e[1] ** 2])
            rhs.append(np.sum((x[f[b]] - x[f[a]]) ** 2))
        c11, c12, c22 = np.linalg.solve(rows, rhs)
        out.append(100 * (math.sqrt(np.linalg.eigvalsh([[c11, c12], [c12, c22]]).max()) - 1))
    return np.array(out)


@pytest.fixture(scope="module")
def tshirt_run(tmp_path_factory):
    """The shipped T-shirt on the static mannequin at 4 cm, written by ``tailor drape --fit``."""
    out = tmp_path_factory.mktemp("fit") / "tshirt"
    assert main(["-q", "drape", "panels/tshirt.json", "--resolution", "4", "--frames", "3", "--fit", "--out", str(out)]) == 0
    return out


def test_face_stretch_of_known_deformations():
    uv = np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.1]])
    faces = np.array([[0, 1, 2]])
    stretched = np.column_stack([uv[:, 0] * 1.2, np.zeros(3), uv[:, 1]])  # 20 % along u, stood upright
    s_max, warp, weft = face_stretch(uv, faces, stretched, faces, np.array([0.0]))
    np.testing.assert_allclose([s_max[0], warp[0], weft[0]], [20.0, 20.0, 0.0], atol=1e-9)
    _, warp, weft = face_stretch(uv, faces, stretched, faces, np.array([math.pi / 2]))  # grain along v
    np.testing.assert_allclose([warp[0], weft[0]], [0.0, 20.0], atol=1e-9)
    c, s = math.cos(0.7), math.sin(0.7)
    rigid = np.column_stack([uv, np.zeros(3)]) @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) + 3.0
    np.testing.assert_allclose(np.concatenate(face_stretch(uv, faces, rigid, faces, np.array([0.3]))), 0.0, atol=1e-9)


def test_stretch_is_the_written_meshs_own_deformation(tshirt_run):
    run = tshirt_run
    obj = read_obj(run / "garment_0002.obj")
    vert, face = read_ply(run / "fit" / "fit_0002.ply")
    np.testing.assert_allclose(np.column_stack([vert["x"], vert["y"], vert["z"]]), obj.vertices, atol=1e-6)
    np.testing.assert_array_equal(face["i"], obj.faces)
    recomputed = metric_stretch(obj.uv, obj.face_uv, obj.vertices, obj.faces)
    assert np.abs(face["stretch_max"] - recomputed).max() < 0.2
    assert face["stretch_max"].max() > 5.0  # a T-shirt hangs from its shoulders: the check compares real stretch
    for table, names in ((vert, ("contact_fx", "contact_fy", "contact_fz", "pressure_kpa", "gap_mm")),
                         (face, ("stretch_max", "stretch_warp", "stretch_weft"))):
        for name in names:
            assert np.all(np.isfinite(table[name])), name
    assert vert["gap_mm"].min() > 0.0  # nothing inside the body


def _weight(obj, density):
    return face_areas(obj.uv, obj.face_uv).sum() * density * GRAVITY


def test_a_tshirt_without_attachments_rests_its_weight_on_the_body(tshirt_run):
    report = json.loads((tshirt_run / "report.json").read_text())
    fit = report["fit"]["frames"][0]
    weight = _weight(read_obj(tshirt_run / "garment_0002.obj"), preset("jersey").density)
    assert fit["contact_force_n"][2] == pytest.approx(weight, rel=0.10)
    assert np.abs(fit["contact_force_n"][:2]).max() < 0.05 * weight  # at rest: no net sideways push
    assert fit["attachment_force_n"] == [0.0, 0.0, 0.0]
    assert {"bust", "waist"} <= set(fit["ease"])
    rows = (tshirt_run / "fit" / "fit.csv").read_text().splitlines()
    assert rows[0].startswith("frame,panel,stretch_max_pct") and len(rows) == 5


def test_a_skirt_hangs_on_its_waistband_and_the_body_together():
    pattern = read_pattern("panels/skirt.json")
    result = drape(pattern, read_body("mannequin"), frames=2, resolution=RES)
    fit = fit_map(result, ease=False)
    held, resting = fit.attachment_force.sum(axis=0)[2], fit.contact_force.sum(axis=0)[2]
    mesh = result.mesh
    area = face_areas(mesh.uv, mesh.faces)
    density = np.array([(pn.fabric or pattern.fabric).density for pn in pattern.panels])[mesh.face_panel]
    weight = float((area * density).sum() * GRAVITY)
    assert held + resting == pytest.approx(weight, rel=0.10)
    assert held > 0.5 * weight  # the waistband carries it


def _tshirt(width: float):
    """The shipped T-shirt with its body panels ``width`` times as wide (sleeves unchanged)."""
    d = json.loads(open("panels/tshirt.json").read())
    for panel in d["pattern"]["panels"].values():
        if panel.get("label") == "body":
            panel["vertices"] = [[x * width, y] for x, y in panel["vertices"]]
            a = panel["placement"]["anchor"]
            panel["placement"]["anchor"] = [a[0] * width, a[1]]
    return pattern_from_dict(d, source=f"tshirt ×{width}")


def test_a_narrower_tshirt_is_tighter_at_the_bust_and_a_wider_one_looser():
    body = read_body("mannequin")
    bust = {w: fit_map(drape(_tshirt(w), body, frames=2, resolution=RES)).at_landmark("bust") for w in (0.9, 1.0, 1.1)}
    # the tight one presses the bust far harder; the two loose ones rest on it by their own weight
    # alike (1.2 Pa each to the rounding), the wider one no harder than the plain one beyond their folds' noise
    assert bust[0.9]["pressure_kpa"] > 2.0 * max(bust[1.0]["pressure_kpa"], bust[1.1]["pressure_kpa"]), bust
    assert bust[1.1]["pressure_kpa"] <= 1.25 * bust[1.0]["pressure_kpa"], bust
    # the tight one (1.2 cm of ease) is stretched round the bust beyond either loose one; the two loose
    # ones only by their own weight, alike within a point (their folds differ: 5.9 and 6.6 %)
    assert bust[0.9]["stretch_pct"] > max(bust[1.0]["stretch_pct"], bust[1.1]["stretch_pct"]) + 0.5, bust
    assert bust[1.1]["stretch_pct"] < bust[1.0]["stretch_pct"] + 1.0, bust
    # a loose one hangs in folds its section's hull does not follow in full: more ease, not 10 % more
    assert bust[0.9]["ease_cm"] < bust[1.0]["ease_cm"] - 3 < bust[1.1]["ease_cm"] - 3, bust


def test_tailor_fit_maps_a_run_and_says_what_is_wrong(tshirt_run, tmp_path, capsys):
    out = tmp_path / "maps"
    assert main(["-q", "fit", str(tshirt_run), "--frame", "all", "--out", str(out), "--max", "20"]) == 0
    names = {p.name for p in out.iterdir()}
    assert names == {"ease.csv", "fit.csv", "fit.json"} | {f"{k}_{i:04d}.{e}" for i in range(3) for k, e in
                                                           (("fit", "ply"), ("fit", "png"), ("pressure", "png"))}
    assert len(json.loads((out / "fit.json").read_text())["frames"]) == 3
    capsys.readouterr()
    for args, words in ((["--frame", "7"], "--frame: 7"), (["--max", "-1"], "--max"), (["--frame", "x"], "--frame")):
        assert main(["fit", str(tshirt_run), "--out", str(tmp_path / "bad"), *args]) == 2
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert main(["fit", str(tmp_path)]) == 2
    assert "garment_0000.obj" in capsys.readouterr().err


def test_a_run_without_body_frames_reads_the_body_its_report_names(tshirt_run):
    source = FitSource.of_run(tshirt_run)
    fit = fit_map(source, -1, ease=False)
    assert fit.gap_mm.min() > 0.0 and fit.pressure_kpa.max() > 0.0
    assert source.wearable.tolist() == [preset("jersey").wearable_stretch * 100] * 4


def test_wearable_stretch_is_a_fabric_field_in_pattern_files():
    d = json.loads(open("panels/tshirt.json").read())
    d["fabric"] = {"preset": "cotton", "wearable_stretch": 12}
    assert pattern_from_dict(d, source="t").fabric.wearable_stretch == pytest.approx(0.12)
    d["fabric"]["wearable_stretch"] = -1
    with pytest.raises(Exception, match="wearable_stretch"):
        pattern_from_dict(d, source="t")


def test_exports_and_previews_carry_the_fit(tshirt_run, tmp_path):
    pygltflib = pytest.importorskip("pygltflib")
    from tailor.io.export import export, read_run
    from tailor.io.preview import PreviewSettings, preview

    anim = read_run(tshirt_run)
    assert anim.contact_forces is not None and anim.contact_forces.shape == anim.positions.shape
    (glb,) = export(anim, "glb", tmp_path)
    doc = pygltflib.GLTF2().load(str(glb))
    attributes = doc.meshes[0].primitives[0].attributes
    stretch = doc.accessors[attributes._STRETCH]
    _, faces = read_ply(tshirt_run / "fit" / "fit_0002.ply")
    assert 1.0 < stretch.max[0] <= faces["stretch_max"].max() + 1e-3  # a vertex's is the mean of its faces'
    assert doc.accessors[attributes._PRESSURE].max[0] > 0.0
    (usd,) = export(anim, "usda", tmp_path)
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(usd))
    mesh = stage.GetPrimAtPath("/tailor/garment")
    for name in ("stretch", "pressure"):
        primvar = UsdGeom.PrimvarsAPI(mesh).GetPrimvar(name)
        assert primvar.GetAttr().GetTimeSamples() == [0.0, 1.0, 2.0]
        assert np.all(np.isfinite(primvar.Get(2.0)))
    files = preview(anim, tmp_path / "pv", settings=PreviewSettings(colour="stretch", every=2), gif=False)
    assert [f.name for f in files] == ["frame_0000.png", "frame_0002.png"]
    with pytest.raises(Exception, match="gap"):
        preview(anim, tmp_path / "pv2", settings=PreviewSettings(colour="gap"), gif=False)  # no body frames in this run
