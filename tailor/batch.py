"""Batch draping on Dask: patterns × bodies × fabrics → a folder of drapes and a manifest.

A **job** is one drape: a pattern file, a body (a name such as ``mannequin-walk`` or a file), a
fabric (a preset name, or the pattern's own) and options (frames, resolution, quality, …). Jobs
come from a JSON or CSV job file (:func:`read_jobs`), which can also give a grid: every pattern
in a folder × these bodies × these fabrics. :func:`drape_many` runs them on a
``dask.distributed`` cluster — a LocalCluster sized to the machine by default (one
single-threaded worker process per core, numba pinned to its share of the cores, so workers do
not oversubscribe), or any running cluster through its ``Client`` / scheduler address.

Each job writes ``OUT/<job id>/`` (the OBJ frames and ``report.json``, exactly what
``tailor drape`` writes) atomically, from its worker — on a multi-machine cluster ``OUT`` must be
a shared file system. ``OUT/manifest.csv`` gets one row per job (status, wall time, vertices,
max penetration, seam gap, failure reason) and is rewritten atomically as jobs finish. A job
that fails (a bad pattern, an unstable run, its time-out) is recorded and the batch goes on.
Job ids hash the job's inputs, so re-running a batch skips every job whose folder is complete
(a killed batch loses only the jobs that were running) and redoes a job whose inputs changed.
"""

from __future__ import annotations

import csv
import glob
import hashlib
import io
import json
import logging
import os
import re
import shutil
import time
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from .errors import TailorError
from .sim import DEFAULT_QUALITY

__all__ = ["Job", "JobTimeout", "read_jobs", "make_jobs", "run_job", "drape_many", "BatchSummary", "MANIFEST_FIELDS",
           "read_manifest", "OPTIONS", "connect", "local_cluster"]

log = logging.getLogger(__name__)

OPTIONS = {
    "frames": int, "fps": float, "resolution": float, "quality": str, "integrator": str, "self_collision": str,
    "sew_timeout": float, "with_body": bool, "timeout": float, "tuck": bool,
}
"""Per-job options and their types; ``resolution`` is in cm (as on the command line), ``timeout``
in seconds of wall time for the whole job."""

DEFAULTS = {"frames": 25, "fps": 25.0, "resolution": 2.0, "quality": DEFAULT_QUALITY, "integrator": "implicit",
            "self_collision": "auto", "sew_timeout": 4.0, "with_body": False, "timeout": 0.0,
            "tuck": False}

MANIFEST_FIELDS = ("id", "status", "pattern", "body", "fabric", "wall_s", "cpu_s", "vertices", "welded_vertices", "frames",
                   "max_penetration_mm", "crossings", "seam_gap_mm", "reason", "options")


class JobTimeout(TailorError):
    """A job ran longer than its ``timeout``."""


@dataclass(frozen=True)
class Job:
    """One drape of a batch.

    Attributes
    ----------
    pattern : str or tuple of str
        Pattern file (absolute once read from a job file); several dress an outfit (:mod:`tailor.outfit`).
    body : str
        A named body (``mannequin``, ``mannequin-walk``) or a body file/folder.
    fabric : str
        Fabric preset, or ``""`` for the pattern's own.
    options : dict
        Keys of :data:`OPTIONS` that differ from :data:`DEFAULTS`.
    """

    pattern: str | tuple
    body: str = "mannequin"
    fabric: str = ""
    options: dict = field(default_factory=dict)

    @property
    def id(self) -> str:
        """Folder name: readable stems and a hash of every input that shapes the result (so changed
        inputs are redone; the time-out is not one of them)."""
        shaping = sorted((k, v) for k, v in self.options.items() if k != "timeout")
        key = json.dumps([self.pattern, self.body, self.fabric, shaping], sort_keys=True)
        digest = hashlib.sha1(key.encode()).hexdigest()[:8]
        parts = ["+".join(Path(p).stem for p in self.patterns), Path(self.body).stem if self.body not in ("mannequin", "mannequin-walk")
                 else self.body, self.fabric or "own"]
        return re.sub(r"[^A-Za-z0-9_.+-]+", "_", "-".join(parts)) + "-" + digest

    @property
    def patterns(self) -> tuple:
        """The job's pattern files (one, or an outfit's)."""
        return (self.pattern,) if isinstance(self.pattern, str) else tuple(self.pattern)

    def option(self, name: str):
        """The job's value of option ``name`` (its own, else the default)."""
        return self.options.get(name, DEFAULTS[name])


def _coerce(name: str, value, where: str):
    kind = OPTIONS[name]
    try:
        if kind is bool:
            if isinstance(value, str):
                if value.strip().lower() not in ("1", "0", "true", "false", "yes", "no", ""):
                    raise ValueError(value)
                return value.strip().lower() in ("1", "true", "yes")
            return bool(value)
        if kind is int and isinstance(value, float) and not value.is_integer():
            raise ValueError(value)
        out = kind(float(value)) if kind is int else kind(value)
    except (TypeError, ValueError):
        raise TailorError(f"{where}: expected {kind.__name__}, got {value!r}") from None
    if kind in (int, float) and out < 0:
        raise TailorError(f"{where}: must not be negative, got {value!r}")
    return out


def _job(entry: dict, base: Path, source: str, where: str, defaults: dict) -> Job:
    entry = {**defaults, **{k: v for k, v in entry.items() if v not in (None, "")}}
    unknown = set(entry) - {"pattern", "body", "fabric"} - set(OPTIONS)
    if unknown:
        raise TailorError(f"{source}: {where}.{sorted(unknown)[0]}: unknown job field; "
                          f"use pattern, body, fabric, {', '.join(OPTIONS)}")
    if "pattern" not in entry:
        raise TailorError(f"{source}: {where}.pattern: missing")
    given = entry["pattern"]
    if isinstance(given, list) and not given:
        raise TailorError(f"{source}: {where}.pattern: an empty list (give a file, or a list of files for an outfit)")
    files = [Path(str(f)) for f in (given if isinstance(given, list) else [given])]
    files = [str((f if f.is_absolute() else base / f).resolve()) for f in files]
    body = str(entry.get("body") or "mannequin")
    if body not in ("mannequin", "mannequin-walk") and not Path(body).is_absolute():
        body = str(base / body)
    options = {k: _coerce(k, v, f"{source}: {where}.{k}") for k, v in entry.items() if k in OPTIONS}
    options = {k: v for k, v in options.items() if v != DEFAULTS[k]}
    if options.get("tuck") and len(files) < 2:
        raise TailorError(f"{source}: {where}.tuck: applies to a list of patterns (a top and a bottom)")
    return Job(files[0] if len(files) == 1 else tuple(files), body, str(entry.get("fabric") or ""), options)


def _grid(grid: dict, base: Path, source: str, defaults: dict) -> list[Job]:
    unknown = set(grid) - {"patterns", "bodies", "fabrics"}
    if unknown:
        raise TailorError(f"{source}: grid.{sorted(unknown)[0]}: unknown grid field; use patterns, bodies, fabrics")
    patterns = grid.get("patterns")
    if patterns is None:
        raise TailorError(f"{source}: grid.patterns: missing (a folder, a glob, or a list of files)")
    files: list[str] = []
    for item in [patterns] if isinstance(patterns, str) else patterns:
        p = Path(item) if Path(item).is_absolute() else base / item
        if p.is_dir():
            found = sorted(str(f) for f in p.glob("*.json"))
        elif any(c in str(item) for c in "*?["):
            found = sorted(glob.glob(str(p)))
        else:
            found = [str(p)]
        if not found:
            raise TailorError(f"{source}: grid.patterns: {item!r} matches no pattern file")
        files += found
    bodies = grid.get("bodies") or [defaults.get("body", "mannequin")]
    fabrics = grid.get("fabrics") or [defaults.get("fabric", "")]
    return [_job({"pattern": f, "body": b, "fabric": fab}, base, source, f"grid[{i}]", defaults)
            for i, (f, b, fab) in enumerate((f, b, fab) for f in files for b in bodies for fab in fabrics)]


def make_jobs(spec: dict, *, base=".", source: str = "<jobs>") -> list[Job]:
    """Jobs from a job document: ``{"defaults": {...}, "jobs": [{...}, ...], "grid": {...}}``."""
    if not isinstance(spec, dict):
        raise TailorError(f"{source}: expected an object with jobs, grid and/or defaults")
    unknown = set(spec) - {"defaults", "jobs", "grid"}
    if unknown:
        raise TailorError(f"{source}: {sorted(unknown)[0]}: unknown top-level field; use defaults, jobs, grid")
    base = Path(base)
    defaults = dict(spec.get("defaults") or {})
    jobs = [_job(e, base, source, f"jobs[{i}]", defaults) for i, e in enumerate(spec.get("jobs") or [])]
    if spec.get("grid"):
        jobs += _grid(spec["grid"], base, source, defaults)
    if not jobs:
        raise TailorError(f"{source}: no jobs (give jobs: [...] or grid: {{patterns: ...}})")
    ids = [j.id for j in jobs]
    dup = next((i for i in ids if ids.count(i) > 1), None)
    if dup:
        raise TailorError(f"{source}: job {dup} appears twice")
    return jobs


def read_jobs(path) -> list[Job]:
    """Jobs from a ``.json`` job document or a ``.csv`` with a header (pattern, body, fabric, options…).

    Relative paths are relative to the job file.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise TailorError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if path.suffix.lower() == ".csv":
        rows = list(csv.DictReader(io.StringIO(text)))
        if not rows:
            raise TailorError(f"{path}: no jobs (a header line and one row per job)")
        spec = {"jobs": [{k.strip(): (v or "").strip() for k, v in row.items() if k} for row in rows]}
        return make_jobs(spec, base=path.parent, source=str(path))
    try:
        spec = json.loads(text)
    except json.JSONDecodeError as exc:
        raise TailorError(f"{path}: malformed JSON at line {exc.lineno}: {exc.msg}") from None
    return make_jobs(spec, base=path.parent, source=str(path))


@lru_cache(maxsize=4)
def _body(source: str):
    from .io.body_files import read_body

    return read_body(source)


def _row(job: Job, status: str, **fields) -> dict:
    """A manifest row of ``job``: its inputs, ``status`` and ``fields``."""
    return {"id": job.id, "status": status, "pattern": " + ".join(job.patterns), "body": job.body, "fabric": job.fabric,
            "options": json.dumps(job.options, sort_keys=True), "reason": "", **fields}


def _measures(report: dict, frames) -> dict:
    """The manifest's numbers from a drape's report (``DrapeResult.report`` or its ``report.json``)."""
    return {"vertices": report.get("vertices", ""), "welded_vertices": report.get("welded_vertices", ""),
            "frames": frames, "max_penetration_mm": round(report.get("max_penetration_m", 0.0) * 1e3, 3),
            "crossings": max(report.get("crossings_per_frame", []), default=""),
            "seam_gap_mm": round(report["phases"]["sewing"]["max_gap_at_merge_m"] * 1e3, 3)}


def run_job(job: Job, out) -> dict:
    """Run one job and write ``out/<job.id>/``; never raises: returns its manifest row."""
    from .dress import drape
    from .io import read_pattern
    from .io.garment import DrapeWriter
    from .outfit import outfit

    t0, cpu0 = time.perf_counter(), time.process_time()
    row = _row(job, "failed")
    timeout = job.option("timeout")

    def progress(event):
        if timeout and time.perf_counter() - t0 > timeout:
            raise JobTimeout(f"time-out after {timeout:g} s ({event.phase}, simulated {event.simulated_s:.2f} s)")

    try:
        pattern = outfit([read_pattern(p) for p in job.patterns], tuck=job.option("tuck"))
        body = _body(job.body)
        with DrapeWriter(Path(out) / job.id, pattern, overwrite=True,
                         body_faces=body.faces if job.option("with_body") else None) as writer:  # frames stream to disk
            result = drape(pattern, body, job.fabric or None, frames=job.option("frames"), fps=job.option("fps"),
                           resolution=job.option("resolution") * 1e-2, integrator=job.option("integrator"),
                           quality=job.option("quality"), self_collision=job.option("self_collision"),
                           sew_timeout=job.option("sew_timeout"), progress=progress, sink=writer, keep_frames=False)
            writer.finish(result.report)
        row.update(status="done", **_measures(result.report.to_json(), writer.count))
    except TailorError as exc:
        row["reason"] = str(exc).splitlines()[0]
    except Exception as exc:  # a bug in one job must not stop the batch; the row keeps what it was
        row["reason"] = f"{type(exc).__name__}: {exc}".splitlines()[0]
        log.exception("job %s failed unexpectedly", job.id)
    row["wall_s"] = round(time.perf_counter() - t0, 3)
    row["cpu_s"] = round(time.process_time() - cpu0, 3)  # all threads of the process (a worker's own included)
    return row


def read_manifest(out) -> dict:
    """Rows of ``out/manifest.csv`` by job id (empty if there is none)."""
    path = Path(out) / "manifest.csv"
    if not path.exists():
        return {}
    with open(path, newline="") as fh:
        return {row["id"]: row for row in csv.DictReader(fh)}


def _write_manifest(out: Path, rows: list[dict]) -> None:
    from .io.atomic import atomic_write

    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=MANIFEST_FIELDS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    with atomic_write(out / "manifest.csv") as fh:
        fh.write(text.getvalue())


def _done_row(job: Job, out: Path, previous: dict) -> dict | None:
    """The manifest row of a job whose folder is complete, or None (to be run)."""
    report = out / job.id / "report.json"
    if not report.exists():
        return None
    row = previous.get(job.id)
    if row and row.get("status") == "done":
        return row
    try:  # the folder is complete but the manifest was not updated (killed in between)
        r = json.loads(report.read_text())
    except ValueError:
        return None
    return _row(job, "done", wall_s=r.get("wall_s", ""), **_measures(r, r.get("frames_written", "")))


@dataclass
class BatchSummary:
    """What a batch did: manifest rows in job order and the counts."""

    rows: list
    done: int = 0
    failed: int = 0
    skipped: int = 0
    wall_s: float = 0.0
    workers: int = 0

    @property
    def throughput_per_min(self) -> float:
        """Garments draped per minute of wall time (skipped ones not counted)."""
        return 60.0 * self.done / self.wall_s if self.wall_s > 0 else 0.0

    def text(self) -> str:
        """One line for people."""
        return (f"{self.done} done, {self.failed} failed, {self.skipped} skipped in {self.wall_s:.1f} s on "
                f"{self.workers} worker(s): {self.throughput_per_min:.2f} garments/min")


def connect(address: str):
    """A ``distributed.Client`` connected to the scheduler at ``address`` (``tcp://host:8786``)."""
    try:
        from distributed import Client
    except ImportError:
        raise TailorError("tailor batch needs dask.distributed: pip install 'dask[distributed]'") from None
    try:
        return Client(address, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise TailorError(f"--scheduler {address}: cannot connect ({exc})") from None


def local_cluster(workers: int | None = None):
    """A LocalCluster of single-threaded worker processes, numba given each worker's share of the cores."""
    try:
        from distributed import LocalCluster
    except ImportError:
        raise TailorError("tailor batch needs dask.distributed: pip install 'dask[distributed]'") from None
    cores = os.cpu_count() or 1
    workers = workers or cores
    if workers < 1:
        raise TailorError(f"--workers must be at least 1, got {workers}")
    threads = str(max(1, cores // workers))
    env = {"NUMBA_NUM_THREADS": threads, "OMP_NUM_THREADS": "1"}
    if threads == "1":
        # measured: GNU OpenMP's spin-waiting (numba's omp layer) in two single-threaded workers on
        # 2 cores burned 5-8x the CPU of a job (41 s instead of 5 s); passive waiting fixes it, but
        # slows a worker that does run 2 numba threads (parallel regions wait for a wake-up)
        env["OMP_WAIT_POLICY"] = "PASSIVE"
    for name in ("distributed", "dask"):  # the cluster's own chatter is not the user's business
        logging.getLogger(name).setLevel(logging.ERROR)
    import dask

    # the workers' statistical profiler samples every 10 ms and takes the GIL from the job's thread
    dask.config.set({"distributed.worker.profile.enabled": False})
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, scheduler_kwargs={"dashboard": False},
                        dashboard_address=None, env=env,
                        silence_logs=logging.ERROR)


def drape_many(jobs, out, *, client=None, workers: int | None = None, progress=None) -> BatchSummary:
    """Run ``jobs`` (Job objects, dicts, or a job file path) into folder ``out`` on Dask.

    ``client``: a ``distributed.Client`` to use (a notebook's, or one connected to a cluster);
    default: a LocalCluster of ``workers`` processes (default: one per core) for this call.
    ``progress(row, finished, total)`` is called as each job finishes. Jobs whose folder is
    complete are skipped. Returns a :class:`BatchSummary`; the manifest is ``out/manifest.csv``.
    """
    if isinstance(jobs, (str, Path)):
        jobs = read_jobs(jobs)
    jobs = [j if isinstance(j, Job) else make_jobs({"jobs": [j]})[0] for j in jobs]
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    previous = read_manifest(out)
    rows: dict[str, dict] = {}
    todo = []
    for job in jobs:
        row = _done_row(job, out, previous)
        if row is None:
            for leftover in out.glob(f".{job.id}.*"):  # a write killed half-way: never a result
                shutil.rmtree(leftover, ignore_errors=True)
            todo.append(job)
        else:
            rows[job.id] = row
    summary = BatchSummary(rows=[], skipped=len(jobs) - len(todo))
    t0 = time.perf_counter()
    own = None
    if todo:
        if client is None:
            from distributed import Client

            cluster = local_cluster(workers)
            own = (cluster, Client(cluster))
            client = own[1]
        try:
            summary.workers = len(client.scheduler_info().get("workers", {}))
            _run_on(client, todo, out, rows, jobs, progress)
        finally:
            if own:
                own[1].close()
                own[0].close()
    summary.rows = [rows[j.id] for j in jobs if j.id in rows]
    summary.done = sum(1 for j in todo if rows.get(j.id, {}).get("status") == "done")
    summary.failed = len(todo) - summary.done
    summary.wall_s = time.perf_counter() - t0
    _write_manifest(out, summary.rows)
    return summary


def _run_on(client, todo, out, rows, jobs, progress) -> None:
    from distributed import as_completed

    futures = {client.submit(run_job, job, str(out), key=f"tailor-{job.id}", pure=False, retries=0): job for job in todo}
    for finished, future in enumerate(as_completed(futures), 1):
        job = futures[future]
        try:
            row = future.result()
        except Exception as exc:  # the worker died (memory, signal): record it, keep going
            row = _row(job, "failed", reason=f"worker lost: {type(exc).__name__}: {exc}".splitlines()[0])
        rows[job.id] = row
        _write_manifest(out, [rows[j.id] for j in jobs if j.id in rows])
        if progress:
            progress(row, finished, len(todo))
