"""The command line: exit 0 on good input, 2 and one line (no traceback) on bad input."""

import json
import subprocess
import sys

import pytest

from conftest import PANELS
from tailor.cli import main

SHIPPED = sorted(PANELS.glob("*.json"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_check_accepts_every_shipped_pattern(path, capsys):
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "area" in out and "fabric" in out


@pytest.mark.parametrize(
    "text,needle",
    [
        ("{not json", "line 1 column 2: malformed JSON"),
        ('{"pattern": {"panels": {}}}', "pattern.panels: a pattern needs at least one panel"),
        ('{"pattern": {"panels": {"a": {"vertices": [[0,0],[1,0],[0,1]], "edges": [{"endpoints": [0, 5]}]}}}}',
         "vertex index 5 does not exist"),
    ],
)
def test_check_bad_file_exits_2_with_one_line(tmp_path, capsys, text, needle):
    f = tmp_path / "bad.json"
    f.write_text(text)
    assert main(["check", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "bad.json" in err and needle in err


def test_mesh_writes_obj_with_groups_and_uvs(tmp_path, capsys):
    out = tmp_path / "skirt.obj"
    assert main(["mesh", str(PANELS / "skirt.json"), "--resolution", "3", "--out", str(out)]) == 0
    text = out.read_text()
    lines = text.splitlines()
    v = sum(line.startswith("v ") for line in lines)
    vt = sum(line.startswith("vt ") for line in lines)
    groups = [line[2:] for line in lines if line.startswith("g ")]
    assert v == vt > 0 and groups == ["skirt_front", "skirt_back", "wb_front", "wb_back"]
    assert all(float(line.split()[3]) == 0.0 for line in lines if line.startswith("v "))  # flat in z = 0
    assert "min angle" in capsys.readouterr().out
    assert not list(tmp_path.glob(".*tmp"))  # nothing half-written left behind


def test_console_script_exit_status_and_no_traceback(tmp_path):
    bad = tmp_path / "neg.json"
    bad.write_text(json.dumps({"fabric": {"density": -3}, "pattern": {"panels": {}}}))
    proc = subprocess.run([sys.executable, "-m", "tailor", "check", str(bad)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip() == "tailor: error: neg.json: fabric.density: must be positive, got -3"


def test_garmentcode_patterns_check_and_mesh(garmentcode_dir, tmp_path):
    for f in sorted(garmentcode_dir.glob("*_specification.json")):
        assert main(["check", str(f)]) == 0
        assert main(["mesh", str(f), "--out", str(tmp_path / f"{f.stem}.obj")]) == 0


def test_validate_rejects_an_unknown_fabric_model_before_running(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["validate", "--models", "kes5,kes3", "--out", str(tmp_path / "v")])
    assert exc.value.code == 2
    assert "unknown model 'kes3'" in capsys.readouterr().err
    assert not (tmp_path / "v").exists()


def test_drape_warns_of_frames_where_cloth_passes_through_cloth():
    # no shipped garment keeps a crossing any more (tests/test_dress.py): the warning's text alone
    from tailor.cli.drape import crossing_warning

    assert crossing_warning([0, 0, 0], "auto") is None
    text = crossing_warning([0, 3, 7, 0], "auto")
    assert text.startswith("tailor: warning: cloth passes through cloth: 2 of 4 frames")
    assert "most: 7 in frame 2" in text and "untangling could not undo" in text and "\n" not in text
    assert "self-collision is off" in crossing_warning([1], "off")
