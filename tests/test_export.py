"""Exports round-trip: each format read back by an independent, well-kept reader (pxr, pygltflib,
trimesh) gives the OBJ frames' vertex count, frame count and positions within 1e-6 m."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tailor.cli import main
from tailor.errors import TailorError
from tailor.io.animation import Animation, read_run
from tailor.io.export import FORMATS, export
from tailor.io.gltf import from_y_up
from tailor.io.obj import read_obj, read_obj_vertices
from tailor.io.pc2 import read_pc2

TOL = 1e-6  # m: float32 storage of positions within 2 m of the origin


def _obj_frames(run, stem="garment"):
    files = sorted(run.glob(f"{stem}_*.obj"))
    return np.stack([read_obj_vertices(f) for f in files])


def test_run_folder_reads_back_as_the_drape(walk_run):
    result, run = walk_run
    anim = read_run(run)
    assert anim.frame_count == len(result.frames) == 3
    assert anim.vertex_count == result.report.welded_vertices
    assert anim.fps == result.report.fps == 25
    assert anim.group_names == tuple(result.mesh.panel_names)
    assert anim.has_body and anim.body_positions.shape[0] == 3
    assert not np.allclose(anim.body_positions[0], anim.body_positions[-1])  # the walk moves
    np.testing.assert_allclose(anim.positions, _obj_frames(run), atol=0)


def test_pc2_round_trip(walk_run, tmp_path):
    _, run = walk_run
    frames = _obj_frames(run)
    files = export(run, "pc2", tmp_path)
    names = {f.name for f in files}
    assert {"skirt.pc2", "skirt_base.obj", "body.pc2", "body_base.obj"} <= names
    cache = read_pc2(tmp_path / "skirt.pc2")
    base = read_obj(tmp_path / "skirt_base.obj")
    assert cache.shape == frames.shape and len(base.vertices) == cache.shape[1]
    np.testing.assert_allclose(cache[[0, -1]], frames[[0, -1]], atol=TOL)
    np.testing.assert_allclose(base.vertices, frames[0], atol=TOL)
    body = read_pc2(tmp_path / "body.pc2", len(read_obj(tmp_path / "body_base.obj").vertices))
    np.testing.assert_allclose(body[-1], _obj_frames(run, "body")[-1], atol=TOL)


def _accessor(gltf, blob, index):
    acc = gltf.accessors[index]
    view = gltf.bufferViews[acc.bufferView]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[acc.type]
    dtype = {5126: "<f4", 5125: "<u4"}[acc.componentType]
    start = view.byteOffset + (acc.byteOffset or 0)
    return np.frombuffer(blob, dtype, acc.count * width, start).reshape(acc.count, width) if width > 1 else \
        np.frombuffer(blob, dtype, acc.count, start)


def test_glb_round_trip_with_pygltflib_and_trimesh(walk_run, tmp_path):
    pygltflib = pytest.importorskip("pygltflib")
    trimesh = pytest.importorskip("trimesh")
    _, run = walk_run
    frames = _obj_frames(run)
    anim = read_run(run)
    (path,) = export(run, "glb", tmp_path)
    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()
    mesh = gltf.meshes[gltf.nodes[0].mesh]
    assert [gltf.materials[p.material].name for p in mesh.primitives] == list(anim.group_names)
    prim = mesh.primitives[0]
    base = from_y_up(_accessor(gltf, blob, prim.attributes.POSITION))
    targets = [from_y_up(_accessor(gltf, blob, t["POSITION"])) for t in prim.targets]
    assert len(targets) == frames.shape[0] - 1
    # every welded vertex appears (split only at seams) and every copy sits where the OBJ has it
    assert len({tuple(p) for p in np.round(base, 6)}) == anim.vertex_count
    nearest = np.argmin(((base[:, None, :] - frames[0][None]) ** 2).sum(-1), axis=1)
    assert len(np.unique(nearest)) == anim.vertex_count
    np.testing.assert_allclose(base, frames[0][nearest], atol=TOL)
    np.testing.assert_allclose(base + targets[-1], frames[-1][nearest], atol=TOL)
    # the animation: weights at frame k select target k-1, at the frame times
    anim_ = gltf.animations[0]
    times = _accessor(gltf, blob, anim_.samplers[0].input)
    weights = _accessor(gltf, blob, anim_.samplers[0].output).reshape(len(times), -1)
    np.testing.assert_allclose(times, np.arange(3) / 25.0)
    np.testing.assert_array_equal(weights, np.eye(3)[:, 1:])
    assert len(gltf.meshes) == 2 and len(gltf.animations[0].channels) == 2  # the walking body too
    # trimesh reads the same base mesh (no animation)
    scene = trimesh.load(path, process=False)
    assert sum(len(g.faces) for name, g in scene.geometry.items() if "body" not in name) == len(anim.faces)


def test_usd_round_trip_with_pxr(walk_run, tmp_path):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    _, run = walk_run
    frames = _obj_frames(run)
    anim = read_run(run)
    for fmt in ("usd", "usda"):
        (path,) = export(run, fmt, tmp_path)
        stage = Usd.Stage.Open(str(path))
        assert UsdGeom.GetStageUpAxis(stage) == "Z" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
        assert stage.GetTimeCodesPerSecond() == 25 and stage.GetEndTimeCode() == 2
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/tailor/garment"))
        points = mesh.GetPointsAttr()
        assert len(points.GetTimeSamples()) == 3
        for k in (0, 2):
            np.testing.assert_allclose(np.array(points.Get(k)), frames[k], atol=TOL)
        np.testing.assert_array_equal(np.array(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3), anim.faces)
        st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
        np.testing.assert_allclose(np.array(st.ComputeFlattened()).reshape(-1, 3, 2), anim.uv[anim.face_uv], atol=1e-6)
        subsets = UsdGeom.Subset.GetAllGeomSubsets(mesh)
        assert sorted(s.GetPrim().GetCustomDataByKey("panel") for s in subsets) == sorted(anim.group_names)
        body = UsdGeom.Mesh(stage.GetPrimAtPath("/tailor/body")).GetPointsAttr()
        np.testing.assert_allclose(np.array(body.Get(2)), _obj_frames(run, "body")[2], atol=TOL)


def test_obj_export_reproduces_the_frames(walk_run, tmp_path):
    _, run = walk_run
    export(run, "obj", tmp_path, with_body=False)
    np.testing.assert_array_equal(_obj_frames(tmp_path), _obj_frames(run))
    assert (tmp_path / "garment.mtl").exists() and not list(tmp_path.glob("body_*.obj"))


def test_exports_refuse_non_finite_positions_and_write_nothing(walk_run, tmp_path):
    anim = read_run(walk_run[1])
    positions = anim.positions.copy()
    positions[1, 5, 2] = np.nan
    bad = Animation(**{**anim.__dict__, "positions": positions})
    for fmt in FORMATS:
        with pytest.raises(TailorError, match="non-finite"):
            export(bad, fmt, tmp_path / fmt)
        assert not (tmp_path / fmt).exists() or not any((tmp_path / fmt).iterdir())


def test_cli_export_and_its_errors(walk_run, tmp_path, capsys):
    _, run = walk_run
    assert main(["export", str(run), "--format", "glb,pc2", "--out", str(tmp_path / "x")]) == 0
    assert (tmp_path / "x" / "skirt.glb").exists() and (tmp_path / "x" / "skirt.pc2").exists()
    assert main(["export", str(run), "--format", "fbx"]) == 2
    assert "--format" in capsys.readouterr().err
    assert main(["export", str(tmp_path / "nothing"), "--format", "glb"]) == 2
    err = capsys.readouterr().err
    assert "nothing" in err and "Traceback" not in err
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "garment_0000.obj").write_text("v 0 0 0\nf 1 2 x\n")
    assert main(["export", str(tmp_path / "broken"), "--format", "glb"]) == 2
    assert "garment_0000.obj" in capsys.readouterr().err
    json.loads((run / "report.json").read_text())  # the run itself is untouched
