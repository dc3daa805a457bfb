"""Commands on runs and many runs: export, preview, batch, validate, bench."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import TailorError
from .common import _bar, _formats, _preview, _preview_settings, preview_options


def _cmd_preview(args) -> int:
    from ..io.animation import read_run

    _preview_settings(args)  # bad options fail before reading the run
    anim = read_run(args.run, with_body=not args.no_body)
    _preview(anim, Path(args.out) if args.out else Path(args.run) / "preview", args)
    return 0


def _cmd_export(args) -> int:
    from ..io.export import export, read_run

    formats = _formats(args.format)
    if not formats:
        raise TailorError("--format: give at least one of obj, pc2, glb, usd, usda")
    anim = read_run(args.run, with_body=not args.no_body)
    out = Path(args.out) if args.out else Path(args.run)
    for fmt in formats:
        files = export(anim, fmt, out, with_body=not args.no_body)
        print(f"{fmt}: {anim.frame_count} frames, {anim.vertex_count} vertices"
              f"{' + body' if anim.has_body and not args.no_body else ''} -> "
              + (", ".join(str(f) for f in files) if len(files) <= 4 else f"{out}/ ({len(files)} files)"))
    return 0


def _cmd_batch(args) -> int:
    from dataclasses import replace as _replace

    from .. import batch

    jobs = batch.read_jobs(args.jobs)
    if args.timeout is not None:
        if args.timeout <= 0:
            raise TailorError(f"--timeout must be positive, got {args.timeout:g}")
        jobs = [j if "timeout" in j.options else _replace(j, options={**j.options, "timeout": args.timeout}) for j in jobs]
    client = batch.connect(args.scheduler) if args.scheduler else None
    bar, update = _bar("batch", "job", args.quiet)
    counts = {"done": 0, "failed": 0}

    def progress(row, finished, total):
        counts[row["status"]] = counts.get(row["status"], 0) + 1
        update(finished, total, f"done {counts['done']}, failed {counts['failed']}: {row['id']}")

    try:
        summary = batch.drape_many(jobs, args.out, client=client, workers=args.workers, progress=progress)
    finally:
        bar.close()
        if client is not None:
            client.close()
    for row in summary.rows:
        if row["status"] != "done":
            print(f"failed: {row['id']}: {row['reason']}", file=sys.stderr)
    print(f"{summary.text()} -> {Path(args.out) / 'manifest.csv'}")
    return 0


def _models(text: str) -> tuple:
    """``--models``: comma-separated Bottino fabric models."""
    from ..validate import MODELS

    models = tuple(m.strip() for m in text.split(",") if m.strip())
    bad = [m for m in models if m not in MODELS]
    if bad or not models:
        raise argparse.ArgumentTypeError(f"unknown model {bad[0] if bad else text!r}; choose among {', '.join(MODELS)}")
    return models


def _cmd_validate(args) -> int:
    from ..validate import validate

    bar, update = _bar("validate", "run", args.quiet)
    with bar:
        report = validate(args.out, quick=args.quick, progress=update, models=args.models)
    print(f"wrote {report}")
    return 0


def _cmd_bench(args) -> int:
    from .. import bench

    out = Path(args.out)
    bar, update = _bar("bench", "run", args.quiet)

    def progress(i, total, item):
        update(i, total, f"{item.scene} {item.integrator} n={item.resolution} dt={item.dt:.3g} {item.wall_s:.1f}s"
               if isinstance(item, bench.Run) else f"{item[0]} {item[1]}={item[2]:g} {item[3]}")

    if args.stability:
        rows = bench.stability_map(integrators=("implicit", "symplectic") if args.quick else ("implicit", "symplectic", "rk4"),
                                   progress=progress)
        bar.close()
        print(bench.stability_text(rows))
        paths = bench.write_stability(rows, out)
        failed = [r for r in rows if r[3] not in ("ok", "unstable")]
    else:
        names = args.scenes or (list(bench.QUICK_SCENES) if args.quick else list(bench.SCENES))
        unknown = [n for n in names if n not in bench.SCENES]
        if unknown:
            raise TailorError(f"unknown bench scene {unknown[0]!r}; choose from {', '.join(bench.SCENES)}")
        runs = bench.sweep(names, quick=args.quick, progress=progress)
        saved = bench.savings(quick=args.quick, progress=progress) if "sphere" in names else ()
        bar.close()
        paths = bench.write_results(runs, out, saved)
        for what, variant, wall, _ in saved:
            print(f"{what}: {variant} {wall:.2f} s")
        for name in names:
            front = bench.pareto([r for r in runs if r.scene == name])
            print(f"{name}: frontier " + ", ".join(f"{r.label or r.integrator} n{r.resolution} {r.dt:.3g}s "
                                                   f"{r.wall_s:.1f}s/{r.error_mean_mm:.1f}mm" for r in front))
        failed = [r for r in runs if r.note.startswith("FAILED")]
    print("wrote " + ", ".join(str(p) for p in paths))
    if failed:
        print(f"tailor: error: {len(failed)} run(s) wrote a non-finite frame or failed otherwise", file=sys.stderr)
        return 2
    return 0


def add_output_commands(sub) -> None:
    """export, preview, batch, validate, bench."""
    from ..io.export import FORMATS

    ex = sub.add_parser("export", help="export a drape folder as OBJ sequence, PC2, GLB or USD")
    ex.add_argument("run", metavar="RUN_DIR", help="a folder written by tailor drape")
    ex.add_argument("--format", action="append", required=True, metavar="FMT",
                    help=f"one of {', '.join(FORMATS)} (repeat or comma-separate for several)")
    ex.add_argument("--out", metavar="DIR", help="output folder (default: RUN_DIR)")
    ex.add_argument("--no-body", action="store_true", help="leave the body out even if the run has it")
    ex.set_defaults(func=_cmd_export)

    pv = sub.add_parser("preview", help="render a drape folder to PNG frames and an animated GIF")
    pv.add_argument("run", metavar="RUN_DIR", help="a folder written by tailor drape (--with-body shows the body)")
    pv.add_argument("--out", metavar="DIR", help="output folder (default: RUN_DIR/preview)")
    pv.add_argument("--no-body", action="store_true", help="leave the body out")
    preview_options(pv)
    pv.set_defaults(func=_cmd_preview)

    ba = sub.add_parser("batch", help="drape many jobs (patterns × bodies × fabrics) on Dask; resumable")
    ba.add_argument("jobs", metavar="JOBS", help="a .json or .csv job file")
    ba.add_argument("--out", required=True, metavar="DIR", help="output folder: one folder per job and manifest.csv")
    ba.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: one per core)")
    ba.add_argument("--scheduler", metavar="ADDRESS", help="run on an existing Dask cluster (tcp://host:8786)")
    ba.add_argument("--timeout", type=float, metavar="S", help="wall-time limit per job, seconds (jobs may set their own)")
    ba.set_defaults(func=_cmd_batch)

    va = sub.add_parser("validate", help="Bottino's drape experiments and the Cusick drape test: a markdown report")
    va.add_argument("--quick", action="store_true", help="sphere and hanging scenes of fabric A, coarse, 3 Cusick fabrics")
    va.add_argument("--out", default="out/validation", metavar="DIR", help="output folder (default out/validation)")
    va.add_argument("--models", metavar="LIST", type=_models, help="comma-separated fabric models of Bottino's scenes among kes5, kes1, "
                    "auto (default: all three; with --quick kes5,auto)")
    va.set_defaults(func=_cmd_validate)

    be = sub.add_parser("bench", help="measure speed versus accuracy (or stability at the extremes)")
    be.add_argument("scenes", nargs="*", metavar="SCENE",
                    help="sphere, hang, tshirt, skirt (default: all; with --quick: sphere and hang)")
    be.add_argument("--quick", action="store_true", help="small meshes and few steps (under 3 minutes)")
    be.add_argument("--stability", action="store_true", help="the stability map instead of the sweep")
    be.add_argument("--out", default="out/bench", metavar="DIR", help="output folder (default out/bench)")
    be.set_defaults(func=_cmd_bench)
