"""Batch draping on Dask: failures recorded and never stopping the batch, resume after a kill,
results identical to one-by-one runs, and job files checked like every other input."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import PANELS
from tailor.batch import DEFAULTS, Job, drape_many, make_jobs, read_jobs, read_manifest, run_job
from tailor.cli import main
from tailor.errors import TailorError
from tailor.io.obj import read_obj_vertices

distributed = pytest.importorskip("distributed")

QUICK = {"frames": 2, "resolution": 12, "quality": "draft"}


def _jobs(tmp_path):
    (tmp_path / "broken.json").write_text('{"pattern": {"panels": {"a": {"vertices": [[0, 0]], "edges": []}}}}')
    spec = {"defaults": QUICK,
            "jobs": [{"pattern": str(PANELS / "skirt.json")},
                     {"pattern": "broken.json"},
                     {"pattern": str(PANELS / "flag.json"), "resolution": 10}],
            "grid": {"patterns": [str(PANELS / "tshirt.json"), str(PANELS / "skirt.json")], "fabrics": ["silk"],
                     "bodies": ["mannequin"]}}
    spec["jobs"].append({"pattern": str(PANELS / "tshirt.json"), "fabric": "denim"})
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps(spec))
    return path


@pytest.fixture(scope="module")
def client():
    from tailor.batch import local_cluster

    cluster = local_cluster(2)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_job_files_json_grid_and_csv(tmp_path):
    jobs = read_jobs(_jobs(tmp_path))
    assert len(jobs) == 6 and len({j.id for j in jobs}) == 6
    assert jobs[1].pattern == str((tmp_path / "broken.json").resolve())  # relative to the job file
    assert jobs[2].options == {"frames": 2, "resolution": 10.0}  # "draft" is the default: not kept
    assert jobs[2].option("quality") == "draft"
    assert jobs[3].fabric == "denim" and [j.fabric for j in jobs[4:]] == ["silk", "silk"]  # jobs, then the grid
    csv_file = tmp_path / "jobs.csv"
    csv_file.write_text(f"pattern,body,fabric,frames,with_body\n{PANELS / 'skirt.json'},mannequin-walk,denim,3,yes\n"
                        f"{PANELS / 'flag.json'},,,,\n")
    a, b = read_jobs(csv_file)
    assert (a.body, a.fabric, a.options) == ("mannequin-walk", "denim", {"frames": 3, "with_body": True})
    assert (b.body, b.fabric, b.options) == ("mannequin", "", {})
    # the id hashes what shapes the result, not the time-out
    assert Job("p.json", options={"frames": 3}).id != Job("p.json", options={"frames": 4}).id
    assert Job("p.json", options={"timeout": 5.0}).id == Job("p.json").id


@pytest.mark.parametrize("spec, field", [
    ({"jobs": [{"pattern": "a.json", "colour": "red"}]}, "jobs[0].colour"),
    ({"jobs": [{"pattern": "a.json", "frames": "many"}]}, "jobs[0].frames"),
    ({"jobs": [{"pattern": "a.json", "resolution": -2}]}, "jobs[0].resolution"),
    ({"jobs": [{"body": "mannequin"}]}, "jobs[0].pattern"),
    ({"grid": {"patterns": "nowhere/*.json"}}, "grid.patterns"),
    ({"jobs": [{"pattern": "a.json"}, {"pattern": "a.json"}]}, "appears twice"),
    ({"job": []}, "job"),
])
def test_bad_job_documents_name_the_field(spec, field):
    with pytest.raises(TailorError, match=r"jobs\.json: .*" + field.replace("[", r"\[").replace("]", r"\]")):
        make_jobs(spec, source="jobs.json")


def test_cli_refuses_a_malformed_job_file_in_one_line(tmp_path, capsys):
    bad = tmp_path / "jobs.json"
    bad.write_text('{"jobs": [')
    assert main(["batch", str(bad), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "jobs.json" in err and "malformed JSON" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_a_job_over_its_time_out_fails_and_writes_nothing(tmp_path):
    row = run_job(Job(str(PANELS / "skirt.json"), options={**QUICK, "timeout": 1e-3}), tmp_path)
    assert row["status"] == "failed" and "time-out" in row["reason"]
    assert not any(tmp_path.iterdir())


def test_batch_records_the_broken_job_resumes_and_matches_one_by_one(tmp_path, client):
    jobs = read_jobs(_jobs(tmp_path))
    out = tmp_path / "out"
    summary = drape_many(jobs, out, client=client)
    assert (summary.done, summary.failed, summary.skipped) == (5, 1, 0)
    manifest = read_manifest(out)
    assert len(manifest) == 6
    broken = manifest[jobs[1].id]
    assert broken["status"] == "failed" and "broken.json" in broken["reason"] and "pattern.panels.a" in broken["reason"]
    for job in jobs[:1] + jobs[2:]:
        row = manifest[job.id]
        assert row["status"] == "done" and int(row["vertices"]) > 0 and float(row["max_penetration_mm"]) <= 2.0
        assert (out / job.id / "garment_0001.obj").exists()
    assert not (out / jobs[1].id).exists()

    # identical to running the job alone, here, on this process's threads
    from tailor.dress import drape
    from tailor.io import read_pattern
    from tailor.io.body_files import read_body
    from tailor.io.garment import write_drape

    job = jobs[3]
    alone = drape(read_pattern(job.pattern), read_body(job.body), job.fabric, frames=job.option("frames"),
                  resolution=job.option("resolution") * 1e-2, quality=job.option("quality"))
    write_drape(alone, tmp_path / "alone")
    for k in range(job.option("frames")):
        np.testing.assert_array_equal(read_obj_vertices(out / job.id / f"garment_{k:04d}.obj"),
                                      read_obj_vertices(tmp_path / "alone" / f"garment_{k:04d}.obj"))

    # a kill mid-batch: one job's folder never appeared (its write left a temporary folder), the
    # manifest did not get its row; the rest must not be redone
    lost = jobs[4]
    stamps = {j.id: (out / j.id / "report.json").stat().st_mtime_ns for j in jobs if j is not lost and j is not jobs[1]}
    (out / lost.id).rename(out / f".{lost.id}.half")
    rows = [r for r in read_manifest(out).values() if r["id"] != lost.id]
    (out / "manifest.csv").write_text(",".join(rows[0]) + "\n" + "".join(
        ",".join(f'"{v}"' for v in r.values()) + "\n" for r in rows))
    again = drape_many(jobs, out, client=client)
    assert (again.done, again.failed, again.skipped) == (1, 1, 4)
    assert all((out / i / "report.json").stat().st_mtime_ns == t for i, t in stamps.items())
    assert (out / lost.id / "report.json").exists() and not (out / f".{lost.id}.half").exists()
    assert read_manifest(out)[lost.id]["status"] == "done" and len(read_manifest(out)) == 6


def test_killing_the_batch_command_and_rerunning_loses_only_running_jobs(tmp_path):
    # a small first job finishes while the second runs; the kill lands in the second
    spec = {"defaults": QUICK, "jobs": [{"pattern": str(PANELS / "flag.json"), "resolution": 25},
                                        {"pattern": str(PANELS / "skirt.json"), "resolution": 12},
                                        {"pattern": str(PANELS / "flag.json"), "resolution": 20}]}
    (tmp_path / "jobs.json").write_text(json.dumps(spec))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "tailor", "-q", "batch", str(tmp_path / "jobs.json"), "--out", str(out), "--workers", "1"]
    proc = subprocess.Popen(cmd, start_new_session=True)
    deadline = time.time() + 240
    while time.time() < deadline and not any(r["status"] == "done" for r in read_manifest(out).values()):
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    first = {i: r for i, r in read_manifest(out).items() if r["status"] == "done"}
    assert first, "no job finished before the deadline"
    stamps = {i: (out / i / "report.json").stat().st_mtime_ns for i in first}
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"{len(first)} skipped" in done.stdout
    assert all(r["status"] == "done" for r in read_manifest(out).values()) and len(read_manifest(out)) == 3
    assert all((out / i / "report.json").stat().st_mtime_ns == t for i, t in stamps.items())


def test_a_job_may_tuck_an_outfits_top_into_its_bottom(tmp_path, monkeypatch):
    import tailor.dress

    pair = [str(PANELS / "trousers.json"), str(PANELS / "tshirt.json")]
    tucked, plain = make_jobs({"jobs": [{"pattern": pair, "tuck": True}, {"pattern": pair}]}, base=tmp_path)
    assert tucked.option("tuck") and not plain.option("tuck") and tucked.id != plain.id
    with pytest.raises(TailorError, match=r"jobs\[0\]\.tuck: applies to a list of patterns"):
        make_jobs({"jobs": [{"pattern": pair[1], "tuck": True}]}, base=tmp_path)
    seen = []

    def drape(pattern, *args, **kwargs):  # the outfit the job would drape, then stop
        seen.append([piece.tucks for piece in pattern.pieces])
        raise TailorError("stopped")

    monkeypatch.setattr(tailor.dress, "drape", drape)
    for job in (tucked, plain):
        assert run_job(job, tmp_path / "out")["reason"] == "stopped"
    assert seen == [[False, True], [False, False]]  # the trousers tuck the T-shirt in


def test_defaults_are_what_tailor_drape_uses():
    from tailor.cli import build_parser

    args = build_parser().parse_args(["drape", "x.json"])
    assert DEFAULTS["frames"] == args.frames and DEFAULTS["resolution"] == args.resolution
    assert DEFAULTS["quality"] == args.quality and DEFAULTS["sew_timeout"] == args.sew_timeout


def test_a_job_may_dress_an_outfit_of_several_patterns(tmp_path):
    spec = {"jobs": [{"pattern": [str(PANELS / "trousers.json"), str(PANELS / "tshirt.json")], "frames": 1},
                     {"pattern": str(PANELS / "tshirt.json")}]}
    outfit_job, single = make_jobs(spec, base=tmp_path)
    assert outfit_job.patterns == (str(PANELS / "trousers.json"), str(PANELS / "tshirt.json"))
    assert outfit_job.id.startswith("trousers+tshirt-mannequin-own-") and single.patterns == (str(PANELS / "tshirt.json"),)
    with pytest.raises(TailorError, match=r"jobs\[0\]\.pattern: an empty list"):
        make_jobs({"jobs": [{"pattern": []}]}, base=tmp_path)
