"""Any body in: units, up axis and facing detected; motion formats; one-line errors."""

import struct

import numpy as np
import pytest
from conftest import PANELS

from tailor.body import normalise_body
from tailor.cli import main
from tailor.errors import BodyError
from tailor.io.body_files import read_body
from tailor.io.obj import write_obj
from tailor.measure import find_landmarks


@pytest.fixture(scope="module")
def reference(mannequin):
    return find_landmarks(mannequin.vertices, mannequin.faces)


def garmentcode_frame(x):
    """tailor (Z up, facing −Y) → GarmentCode's (Y up, facing +Z): (x, y, z) → (x, z, −y)."""
    return np.column_stack([x[:, 0], x[:, 2], -x[:, 1]])


@pytest.mark.parametrize("units,scale", [("mm", 1000.0), ("cm", 100.0), ("dm", 10.0), ("m", 1.0)])
def test_same_landmarks_in_any_units_and_y_up(tmp_path, mannequin, reference, units, scale):
    f = tmp_path / "body.obj"
    write_obj(f, garmentcode_frame(mannequin.vertices) * scale, mannequin.faces)
    body = read_body(f)
    assert body.report["units"] == units and body.report["up"] == "y"
    marks = find_landmarks(body.vertices, body.faces)
    for name in ("crotch", "waist", "bust", "hips", "left_knee", "right_elbow"):
        assert np.allclose(marks[name].center, reference[name].center, atol=0.003), name
        assert marks[name].girth == pytest.approx(reference[name].girth, abs=0.003)


def test_facing_is_detected_from_the_feet_and_can_be_forced(mannequin):
    turned = mannequin.vertices @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]).T  # faces +X now
    frames, _, report = normalise_body(turned, mannequin.faces)
    assert report["forward_in_file"] == pytest.approx([1.0, 0.0, 0.0], abs=1e-9)
    assert np.abs(frames[0] - mannequin.vertices).max() < 1e-6
    _, _, forced = normalise_body(turned, mannequin.faces, facing="-y")
    assert forced["forward_in_file"] == pytest.approx([0.0, -1.0, 0.0], abs=1e-9)


def test_feet_on_the_floor_and_centred(mannequin):
    frames, _, _ = normalise_body(mannequin.vertices + [3.0, -2.0, 0.7], mannequin.faces)
    assert frames[0][:, 2].min() == pytest.approx(0.0, abs=1e-12)
    assert np.abs(frames[0] - mannequin.vertices).max() < 1e-9


def test_frame_folder_npz_and_pc2(tmp_path, mannequin):
    walk = read_body("mannequin-walk")
    folder = tmp_path / "frames"
    for i in range(3):
        write_obj(folder / f"f{i:03d}.obj", walk.frames[i] * 100.0, walk.faces)  # centimetres
    body = read_body(folder, fps=25)
    assert body.frame_count == 3 and body.report["units"] == "cm"
    shift = (body.frames - walk.frames[:3]).mean(axis=(0, 1))  # re-centred on its own first frame
    assert abs(shift[2]) < 1e-6 and np.linalg.norm(shift) < 0.02
    assert np.abs(body.frames - shift - walk.frames[:3]).max() < 2e-5
    pc2 = tmp_path / "walk.pc2"
    n = walk.frames.shape[1]
    with open(pc2, "wb") as fh:
        fh.write(b"POINTCACHE2\0" + struct.pack("<iiffi", 1, n, 0.0, 1.0, 3))
        fh.write(walk.frames[:3].astype("<f4").tobytes())
    write_obj(tmp_path / "base.obj", walk.frames[0], walk.faces)
    cached = read_body(pc2, base=tmp_path / "base.obj")
    assert cached.frame_count == 3 and np.abs(cached.frames - shift - walk.frames[:3]).max() < 1e-5


def test_interpolation_in_time():
    walk = read_body("mannequin-walk")
    x, v = walk.at(0.5 / walk.fps)
    assert np.allclose(x, 0.5 * (walk.frames[0] + walk.frames[1]))
    assert np.allclose(v, (walk.frames[1] - walk.frames[0]) * walk.fps)
    assert np.allclose(walk.at(walk.frame_count / walk.fps)[0], walk.frames[0])  # loops


@pytest.mark.parametrize(
    "content,needle",
    [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "has no faces"),
        ("", "empty"),
        ("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", "NaN or infinite"),
        ("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nf 1 2 3\n", "cannot tell the units"),
    ],
)
def test_bad_bodies_give_one_line_errors(tmp_path, content, needle):
    f = tmp_path / "bad.obj"
    f.write_text(content)
    with pytest.raises(BodyError, match=needle) as info:
        read_body(f)
    assert "\n" not in str(info.value) and "bad.obj" in str(info.value)


def test_frames_with_different_topology(tmp_path, mannequin):
    folder = tmp_path / "frames"
    write_obj(folder / "a.obj", mannequin.vertices, mannequin.faces)
    write_obj(folder / "b.obj", mannequin.vertices, mannequin.faces[:-2])
    with pytest.raises(BodyError, match="b.obj: frame topology differs from a.obj"):
        read_body(folder)


def test_cli_body_info_and_errors(tmp_path, capsys):
    assert main(["body", "info", "mannequin"]) == 0
    out = capsys.readouterr().out
    assert "waist" in out and "left_elbow" in out and "units m" in out
    f = tmp_path / "points.obj"
    f.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    assert main(["body", "info", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "points.obj: the mesh has no faces" in err
    png = tmp_path / "m.png"
    assert main(["body", "render", "mannequin", "--out", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("turn", [0, 1, 2, 3])
def test_facing_of_every_walk_frame_alone(turn):
    from tailor.orient import forward

    walk = read_body("mannequin-walk")
    c, s = np.cos(turn * np.pi / 2), np.sin(turn * np.pi / 2)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    expected = rot @ [0.0, -1.0, 0.0]
    for frame in walk.frames:
        assert forward((frame @ rot.T)[None], walk.faces)[0] == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("suffix", [".ply", ".stl", ".off", ".glb"])
def test_common_mesh_formats(tmp_path, mannequin, reference, suffix):
    import trimesh

    f = tmp_path / f"body{suffix}"
    trimesh.Trimesh(garmentcode_frame(mannequin.vertices) * 100.0, mannequin.faces, process=False).export(f)
    body = read_body(f)
    assert body.report["units"] == "cm" and body.report["up"] == "y"
    assert find_landmarks(body.vertices, body.faces)["waist"].girth == pytest.approx(reference["waist"].girth, abs=0.003)


def test_a_walk_from_another_tool_travels_and_the_garment_follows(tmp_path, capsys):
    """OBJ frames in cm, Y up, off-centre, walking forward at 1.2 m/s, at 30 fps: read with --body-fps, not
    re-centred per frame; the skirt goes along with it, outside it."""
    import json

    walk = read_body("mannequin-walk")
    folder = tmp_path / "walk"
    for i in range(12):
        x = walk.frames[i % walk.frame_count] + [0.5, 2.0 - 1.2 * i / 30.0, 0.0]
        write_obj(folder / f"f{i:03d}.obj", garmentcode_frame(x) * 100.0, walk.faces)
    body = read_body(folder, fps=30)
    assert body.fps == 30 and body.report["units"] == "cm" and body.report["up"] == "y"
    travel = body.frames[-1].mean(axis=0) - body.frames[0].mean(axis=0)
    assert travel[1] == pytest.approx(-1.2 * 11 / 30, abs=0.02) and abs(travel[0]) < 0.01
    run = tmp_path / "run"
    assert main(["-q", "drape", str(PANELS / "skirt.json"), "--body", str(folder), "--body-fps", "30", "--frames", "8",
                 "--resolution", "10", "--quality", "draft", "--out", str(run)]) == 0
    report = json.loads((run / "report.json").read_text())
    assert report["body"]["fps"] == 30 and report["max_penetration_m"] <= 0.002
    from tailor.io.obj import read_obj_vertices

    first, last = (read_obj_vertices(run / f"garment_{k:04d}.obj") for k in (0, 7))
    moved = last.mean(axis=0) - first.mean(axis=0)
    assert moved[1] == pytest.approx(-1.2 * 7 / 25, abs=0.05)  # 7 frames at 25 fps of a 1.2 m/s walk
