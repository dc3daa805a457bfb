"""The ``tailor`` command: a thin shell over the library.

Every :class:`~tailor.errors.TailorError` becomes one line on stderr and exit status 2; the
CLI is the only module that prints or reads ``argv``.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

from .errors import TailorError

__all__ = ["main"]

log = logging.getLogger("tailor")

UP_CHOICES = ["auto", "x", "y", "z", "-x", "-y", "-z"]
"""Values of ``--up``: detected, or the file's axis that points up (a minus: the body stands on its head)."""


def _pattern_summary(pattern) -> list[str]:
    from .curves import curve_length

    lines = [f"{pattern.source}: {pattern.name}"]
    lines.append(f"  panels      {len(pattern.panels)}  ({', '.join(p.name for p in pattern.panels)})")
    lines.append(f"  area        {pattern.area:.4f} m²")
    seam_len = sum(pattern.side_length(s.a) for s in pattern.seams)
    auto = sum(s.orientation.startswith("auto:same") for s in pattern.seams)
    extra = f", {auto} oriented 'same' from the placement" if auto else ""
    lines.append(f"  seams       {len(pattern.seams)}  ({seam_len * 100:.1f} cm sewn{extra})")
    if pattern.attachments:
        lines.append(f"  attachments {len(pattern.attachments)}")
    outline = sum(curve_length(e.curve) for p in pattern.panels for e in p.edges)
    lines.append(f"  outline     {outline * 100:.1f} cm")
    f = pattern.fabric
    lines.append(
        f"  fabric      {f.name}: {f.density * 1e3:g} g/m², stretch {f.stretch_warp * 100:g}/{f.stretch_weft * 100:g} % "
        f"(warp/weft), bending c={f.bending:g}, friction {f.friction:g}, thickness {f.thickness * 1e3:g} mm"
    )
    placed = sum(p.placement is not None for p in pattern.panels)
    lines.append(f"  placement   {placed}/{len(pattern.panels)} panels placed")
    return lines


def _cmd_check(args) -> int:
    from .io import read_pattern

    for path in args.patterns:
        pattern = read_pattern(path)
        print("\n".join(_pattern_summary(pattern)))
    return 0


def _cmd_mesh(args) -> int:
    from .io import read_pattern
    from .io.obj import write_obj
    from .mesh import discretise

    pattern = read_pattern(args.pattern)
    t0 = time.perf_counter()
    mesh = discretise(pattern, args.resolution * 1e-2)
    ms = (time.perf_counter() - t0) * 1e3
    out = Path(args.out) if args.out else Path("out") / f"{pattern.name}.obj"
    write_obj(
        out,
        mesh.flat_positions(),
        mesh.faces,
        uv=mesh.uv,
        face_group=mesh.face_panel,
        group_names=mesh.panel_names,
        header=f"tailor mesh {pattern.source} at {args.resolution:g} cm",
    )
    area = mesh.face_rest_area.sum()
    print(
        f"{pattern.source}: {mesh.vertex_count} vertices, {mesh.face_count} triangles, "
        f"{len(mesh.seam_pairs)} seam pairs, min angle {mesh.min_angle():.1f}°, "
        f"area {area:.4f} m² ({(area / pattern.area - 1) * 100:+.3f} % of exact), {ms:.0f} ms -> {out}"
    )
    return 0


def _cmd_draw(args) -> int:
    from .io import read_pattern
    from .io.draw import draw_pattern

    pattern = read_pattern(args.pattern)
    out = Path(args.out) if args.out else Path("out") / f"{pattern.name}.png"
    draw_pattern(pattern, out, mesh_resolution=args.mesh * 1e-2 if args.mesh else None)
    print(f"{pattern.source}: {len(pattern.panels)} panels, {len(pattern.seams)} seams -> {out}")
    return 0


def _fabric_from_args(args):
    from .fabric import preset

    fabric = preset(args.fabric)
    values = {}
    if args.density is not None:
        values["density"] = args.density * 1e-3
    if args.stretch is not None:
        values["stretch_warp"] = values["stretch_weft"] = args.stretch * 1e-2
    if args.stretch_weft is not None:
        values["stretch_weft"] = args.stretch_weft * 1e-2
    if args.bending is not None:
        values["bending"] = args.bending
    if not values:
        return fabric
    return fabric.with_values(name=f"{fabric.name} (custom)", **values)


def _cmd_params(args) -> int:
    import json

    from .params import fabric_params

    if args.resolution <= 0:
        from .errors import FabricError

        raise FabricError(f"--resolution must be positive, got {args.resolution:g} cm")
    fabric = _fabric_from_args(args)
    p = fabric_params(fabric, args.resolution * 1e-2)
    if args.json:
        print(json.dumps({"fabric": fabric.name, **p.as_dict()}, indent=2))
        return 0
    rows = [
        ("fabric", fabric.name, ""),
        ("density ρ (Eq. 21)", f"{p.density * 1e3:g}", "g/m²"),
        ("stretch λ warp / weft", f"{fabric.stretch_warp * 100:g} / {fabric.stretch_weft * 100:g}", "%"),
        ("η₁₁ warp (Eq. 22a)", f"{p.stretch_warp:.4g}", "N/m"),
        ("η₂₂ weft (Eq. 22b)", f"{p.stretch_weft:.4g}", "N/m"),
        ("η₁₂ shear (Eq. 22c)", f"{p.stretch_shear:.4g}", "N/m"),
        ("wave speed warp / weft (Eq. 23)", f"{p.wave_speed_warp:.4g} / {p.wave_speed_weft:.4g}", "m/s"),
        ("bending c / B (Eq. 25)", f"{fabric.bending:g} / {p.bending_rigidity:.4g}", "cm³ / N·m"),
        ("bending length (B/ρg)^⅓", f"{(p.bending_rigidity / (p.density * 9.80665)) ** (1 / 3) * 100:.3g}", "cm"),
        ("damping φ₁₁ at h (Eq. 26)", f"{p.damping_warp:.4g}", "N·s/m"),
        ("resolution h", f"{p.resolution * 100:g}", "cm"),
        ("time step Δt (Eq. 24, l = 2)", f"{p.time_step:.4g}", "s"),
        ("steps per second", f"{1 / p.time_step:.0f}", ""),
    ]
    width = max(len(r[0]) for r in rows)
    for name, value, unit in rows:
        print(f"{name:<{width}}  {value} {unit}".rstrip())
    return 0


def _read_body_args(args):
    from .io.body_files import read_body

    return read_body(args.body, units=args.units, up=args.up, facing=args.facing, base=args.base, fps=args.body_fps)


def _cmd_body_info(args) -> int:
    from .measure import measure_body

    body = _read_body_args(args)
    r = body.report
    print(f"{args.body}: {r.get('vertices', body.frames.shape[1])} vertices, {r.get('faces', len(body.faces))} faces, "
          f"{body.frame_count} frame(s) at {body.fps:g} fps")
    for line in _normalisation_lines(r):
        print(f"  {line}")
    print(f"  height {body.height * 100:.1f} cm")
    marks = measure_body(body)
    print(f"  {'landmark':<16}{'height cm':>10}{'girth cm':>10}{'width cm':>10}{'depth cm':>10}")
    for name, lm in marks.items():
        print(f"  {name:<16}{lm.center[2] * 100:>10.1f}{lm.girth * 100:>10.1f}{lm.width * 100:>10.1f}{lm.depth * 100:>10.1f}")
    return 0


def _normalisation_lines(r: dict):
    """What reading a body did, as ``tailor body info`` prints it."""
    if "units" not in r:
        return
    fwd = ", ".join(f"{c:g}" for c in r.get("forward_in_file", ()))
    where = f" ({fwd} in the file)" if fwd else ""
    yield f"units {r['units']}, up axis {r['up']}, facing {r['facing']}{where} -> metres, Z up, facing -Y"
    if "centre_shift_m" in r:
        sx, sy, _ = (100 * c for c in r["centre_shift_m"])
        yield f"moved {sx:+.1f}, {sy:+.1f} cm to put the trunk over the origin, feet on the floor"
    welded = r.get("vertices_in_file", r.get("vertices", 0)) - r.get("vertices", 0)
    if welded or r.get("parts_dropped"):
        yield (f"{r.get('parts_dropped', 0)} small separate part(s) dropped (eyes, teeth, lashes, ...); "
               f"{welded} duplicate or unused vertices removed")


def _landmark_segments(mark):
    """Two 3D segments across a landmark's cut (its width and its depth), for the body picture."""
    import numpy as np

    c = np.asarray(mark.center)
    axis = np.asarray(mark.axis)
    across = np.cross(axis, [0.0, 1.0, 0.0])
    across = across / np.linalg.norm(across) if np.linalg.norm(across) > 1e-6 else np.array([1.0, 0.0, 0.0])
    depth = np.cross(axis, across)
    color = (0.85, 0.15, 0.1) if abs(axis[2]) > 0.9 else (0.1, 0.35, 0.85)
    return [(c - 0.5 * mark.width * across, c + 0.5 * mark.width * across, color),
            (c - 0.5 * mark.depth * depth, c + 0.5 * mark.depth * depth, color)]


def _cmd_body_make(args) -> int:
    from .io.body_files import make_bodies
    from .mannequin import MEASUREMENT_PRESETS, with_measurements

    base = MEASUREMENT_PRESETS[args.preset]
    m = with_measurements(base, height=args.height, bust=args.bust, waist=args.waist, hips=args.hips,
                          arm_length=args.arm_length, shoulder_width=args.shoulder_width, arm_angle=args.arm_angle,
                          shoulder_slope=args.shoulder_slope, arm_forward=args.arm_forward, leg_spread=args.leg_spread)
    rest, walk = make_bodies(args.out, m, frames=args.frames)
    print(f"wrote {rest} and {walk} ({args.frames} frames, 1 s walk cycle)")
    return 0


def _cmd_body_render(args) -> int:
    from .io.render import render_views

    from .measure import measure_body

    body = _read_body_args(args)
    frame = min(max(args.frame, 0), body.frame_count - 1)
    lines = []
    if not args.no_landmarks:
        for mark in measure_body(body, body.frames[frame]).values():
            lines.extend(_landmark_segments(mark))
    render_views(args.out, [(body.frames[frame], body.faces, (0.78, 0.78, 0.8))], lines=lines,
                 title=f"{args.body} frame {frame}" if body.frame_count > 1 else str(args.body))
    print(f"wrote {args.out}")
    return 0


def _graded(pattern, body, design="mannequin"):
    """``pattern`` graded from the ``design`` body (default: tailor's mannequin, GarmentCode's mean body) to
    ``body``; prints the scales."""
    from .io.body_files import design_landmarks
    from .measure import measure_body
    from .sizing import grade

    graded, scales = grade(pattern, measure_body(body), design_landmarks(design))
    shown = ", ".join(f"{name} {sx:.2f}×{sy:.2f}" for name, (sx, sy) in scales.items())
    print(f"graded {pattern.source} to {body.report.get('source', body.name)} (across × along): {shown}")
    return graded, scales


def _cmd_grade(args) -> int:
    import json

    from .io.atomic import atomic_write
    from .io.pattern_json import pattern_from_dict, reshaped_document
    from .measure import measure_body
    from .sizing import check_loops

    path = Path(args.pattern)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TailorError(f"{path}: cannot read the pattern: {exc}") from None
    pattern = pattern_from_dict(doc, source=path.name, name=path.stem)
    body = _read_body_args(args)
    graded, _ = _graded(pattern, body, args.design_body)
    for loop in check_loops(graded, measure_body(body)):
        print(f"  {loop.landmark:<16} loop {loop.length * 100:6.1f} cm, body {loop.girth * 100:6.1f} cm, ease {loop.ease * 100:+5.1f} cm")
    with atomic_write(args.out) as fh:
        json.dump(reshaped_document(doc, graded), fh, indent=1)
    print(f"wrote {args.out}")
    return 0


def _cmd_drape(args) -> int:
    from .drape import drape
    from .io import read_pattern
    from .io.body_files import read_body
    from .io.garment import write_drape

    formats = _formats(args.format)  # checked before a long run, not after
    wind = _wind(args.wind, args.turbulence)
    cuts = []
    if args.cuts:
        from .io.cuts import read_cuts

        cuts = read_cuts(args.cuts)
    if (args.cuts or args.tear) and (args.preview or any(f != "obj" for f in formats)):
        raise TailorError("--cuts/--tear change the garment's mesh during the run: only the OBJ sequence can hold "
                          "that (leave out --format and --preview)")
    pattern = read_pattern(args.pattern)
    out = Path(args.out) if args.out else Path("out") / pattern.name
    if out.exists() and not args.overwrite:
        raise TailorError(f"{out}: already exists; choose another --out or pass --overwrite")
    body = read_body(args.body, units=args.units, up=args.up, facing=args.facing, base=args.base, fps=args.body_fps)
    if args.grade == "auto":
        pattern, _ = _graded(pattern, body, args.design_body)
    fabric = None
    if args.fabric:
        from .fabric import preset

        fabric = preset(args.fabric)
    bars = PhaseBars(disable=args.quiet)
    t0 = time.perf_counter()
    try:
        result = drape(pattern, body, fabric, frames=args.frames, fps=args.fps, resolution=args.resolution * 1e-2,
                       integrator=args.integrator, sew_timeout=args.sew_timeout, record_sewing=args.record_sewing,
                       self_collision=args.self_collision, quality=args.quality, wind=wind, cuts=cuts,
                       tear=args.tear, progress=bars)
    finally:
        bars.close()
    write_drape(result, out, overwrite=args.overwrite, with_body=args.with_body)
    if any(f != "obj" for f in formats) or args.preview:
        from .io.animation import animation_from_drape
        from .io.export import export

        anim = animation_from_drape(result, with_body=args.with_body)
        for fmt in formats:
            if fmt != "obj":
                export(anim, fmt, out, with_body=args.with_body)
        if args.preview:
            _preview(anim, out / "preview", args)
    r = result.report
    print(f"{pattern.source} on {args.body}: {r['vertices']} vertices ({r['welded_vertices']} after sewing), "
          f"{len(result.frames)} frames, max penetration {r['max_penetration_m'] * 1000:.1f} mm, "
          f"seam gap at merge {r['phases']['sewing']['max_gap_at_merge_m'] * 1000:.1f} mm, "
          f"self-intersections {max(r['self_intersections_per_frame'], default=0)}, "
          + (f"{len(cuts)} cuts and {r['tearing']['edges_torn']} edges torn, " if "tearing" in r else "")
          + f"{time.perf_counter() - t0:.1f} s -> {out}/")
    return 0


def _bar(desc: str, unit: str, quiet: bool):
    """A tqdm bar on stderr and ``update(done, total, text="")`` moving it to ``done`` of ``total``."""
    from tqdm import tqdm

    bar = tqdm(desc=desc, unit=unit, file=sys.stderr, disable=quiet, dynamic_ncols=True)

    def update(done, total, text=""):
        if bar.total != total:
            bar.reset(total=total)
        bar.update(done - bar.n)
        if text:
            bar.set_postfix_str(text)

    return bar, update


class PhaseBars:
    """Progress of a drape on stderr: one tqdm bar per phase, with simulated time, steps/s and ETA."""

    def __init__(self, disable: bool = False):
        self.disable, self.bar, self.phase = disable, None, None
        self.steps0, self.wall0 = 0, time.perf_counter()

    def __call__(self, event) -> None:
        from tqdm import tqdm

        if event.phase != self.phase:
            self.close()
            self.phase, self.steps0, self.wall0 = event.phase, event.steps, time.perf_counter()
            self.bar = tqdm(total=event.total, desc=f"{event.phase:<10}", unit="pair" if event.phase == "sewing" else "frame",
                            file=sys.stderr, disable=self.disable, dynamic_ncols=True, leave=True)
        rate = (event.steps - self.steps0) / max(time.perf_counter() - self.wall0, 1e-9)
        self.bar.n = event.done
        self.bar.set_postfix_str(f"t={event.simulated_s:.2f} s, {rate:.0f} steps/s", refresh=False)
        self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _preview_settings(args):
    from .io.preview import PreviewSettings

    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        raise TailorError(f"--size: expected WIDTHxHEIGHT in pixels, got {args.size!r}") from None
    return PreviewSettings(azimuth=args.azimuth, elevation=args.elevation, width=width, height=height, every=args.every)


def _preview(anim, out, args) -> list:
    from .io.preview import preview

    settings = _preview_settings(args)
    bar, update = _bar("preview", "frame", args.quiet)
    with bar:
        files = preview(anim, out, settings=settings, gif=not args.no_gif, progress=update)
    gifs = [f for f in files if f.suffix == ".gif"]
    print(f"preview: {len(files) - len(gifs)} frames -> {out}/" + (f", {gifs[0]}" if gifs else ""))
    return files


def _cmd_preview(args) -> int:
    from .io.animation import read_run

    _preview_settings(args)  # bad options fail before reading the run
    anim = read_run(args.run, with_body=not args.no_body)
    _preview(anim, Path(args.out) if args.out else Path(args.run) / "preview", args)
    return 0


def _wind(text, turbulence):
    """``--wind SPEED[,DX,DY,DZ]`` (m/s; direction default +x) → a Wind, or None."""
    if text is None:
        return None
    from .forces.wind import Wind

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise TailorError(f"--wind: expected SPEED or SPEED,DX,DY,DZ (m/s), got {text!r}") from None
    if len(values) not in (1, 4) or values[0] < 0 or (len(values) == 4 and not any(values[1:])):
        raise TailorError(f"--wind: expected SPEED >= 0, or SPEED,DX,DY,DZ with a non-zero direction, got {text!r}")
    if not 0 <= turbulence <= 2:
        raise TailorError(f"--turbulence: expected 0 to 2, got {turbulence:g}")
    return Wind(speed=values[0], direction=tuple(values[1:]) if len(values) == 4 else (1.0, 0.0, 0.0),
                turbulence=turbulence)


def _formats(values) -> list[str]:
    """``--format glb --format usd`` or ``--format glb,usd`` → ['glb', 'usd'], each checked."""
    from .io.export import FORMATS

    names = [f.strip().lower() for v in values or () for f in v.split(",") if f.strip()]
    for f in names:
        if f not in FORMATS:
            raise TailorError(f"--format: unknown format {f!r}; choose from {', '.join(FORMATS)}")
    return list(dict.fromkeys(names))


def _cmd_export(args) -> int:
    from .io.export import export, read_run

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

    from . import batch

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
    from .validate import MODELS

    models = tuple(m.strip() for m in text.split(",") if m.strip())
    bad = [m for m in models if m not in MODELS]
    if bad or not models:
        raise argparse.ArgumentTypeError(f"unknown model {bad[0] if bad else text!r}; choose among {', '.join(MODELS)}")
    return models


def _cmd_validate(args) -> int:
    from .validate import validate

    bar, update = _bar("validate", "run", args.quiet)
    with bar:
        report = validate(args.out, quick=args.quick, progress=update, models=args.models)
    print(f"wrote {report}")
    return 0


def _cmd_bench(args) -> int:
    from . import bench

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


def preview_options(parser) -> None:
    """Camera and picture options shared by ``preview`` and ``drape --preview``."""
    parser.add_argument("--azimuth", type=float, default=-30.0, metavar="DEG",
                        help="camera angle around the body (0 = front, 90 = its left; default -30)")
    parser.add_argument("--elevation", type=float, default=10.0, metavar="DEG", help="camera height angle (default 10)")
    parser.add_argument("--size", default="360x480", metavar="WxH", help="picture size in pixels (default 360x480)")
    parser.add_argument("--every", type=int, default=1, metavar="N", help="render every N-th frame (default 1)")
    parser.add_argument("--no-gif", action="store_true", help="only the PNG frames")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``tailor`` command."""
    p = argparse.ArgumentParser(prog="tailor", description="Sewing patterns in, simulated garments out.")
    p.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    p.add_argument("-q", "--quiet", action="store_true", help="only errors")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    c = sub.add_parser("check", help="validate pattern files and summarise them")
    c.add_argument("patterns", nargs="+", metavar="PATTERN")
    c.set_defaults(func=_cmd_check)

    m = sub.add_parser("mesh", help="triangulate a pattern's panels flat, as an OBJ")
    m.add_argument("pattern", metavar="PATTERN")
    m.add_argument("--resolution", type=float, default=1.5, metavar="CM", help="target edge length (cm, default 1.5)")
    m.add_argument("--out", metavar="FILE.obj", help="output OBJ (default out/<pattern>.obj)")
    m.set_defaults(func=_cmd_mesh)

    dr = sub.add_parser("draw", help="draw a pattern's flat panels with seams, notches and grain (PNG or SVG)")
    dr.add_argument("pattern", metavar="PATTERN")
    dr.add_argument("--out", metavar="FILE", help="a .png or .svg (default out/<pattern>.png)")
    dr.add_argument("--mesh", type=float, nargs="?", const=2.0, metavar="CM",
                    help="also draw the triangle mesh (edge length in cm, default 2)")
    dr.set_defaults(func=_cmd_draw)

    from .fabric import DEFAULT_FABRIC, fabric_names

    q = sub.add_parser("params", help="the simulation parameters derived from a fabric (Carignan Eq. 21-26)")
    q.add_argument("--fabric", default=DEFAULT_FABRIC, choices=fabric_names(), help=f"preset (default {DEFAULT_FABRIC})")
    q.add_argument("--density", type=float, metavar="G_M2", help="areal density, g/m²")
    q.add_argument("--stretch", type=float, metavar="PCT", help="stretch under own weight (warp and weft), %%")
    q.add_argument("--stretch-weft", type=float, metavar="PCT", help="a different stretch across the grain, %%")
    q.add_argument("--bending", type=float, metavar="C", help="bending number c (cube of the bending length in cm)")
    q.add_argument("--resolution", type=float, default=1.5, metavar="CM", help="element size (cm, default 1.5)")
    q.add_argument("--json", action="store_true", help="machine-readable output")
    q.set_defaults(func=_cmd_params)

    b = sub.add_parser("body", help="bodies: information and landmarks, the mannequin, pictures")
    bsub = b.add_subparsers(dest="body_command", required=True, metavar="ACTION")

    def body_source(parser, option=False):
        if option:
            parser.add_argument("--body", required=True, help="mesh file, frame folder, npz, PC2, or mannequin / mannequin-walk")
        else:
            parser.add_argument("body", metavar="BODY", help="mesh file, frame folder, npz, PC2, or mannequin / mannequin-walk")
        parser.add_argument("--units", default="auto", choices=["auto", "m", "dm", "cm", "mm"])
        parser.add_argument("--up", default="auto", choices=UP_CHOICES,
                            help="the file's axis that points up (a negative one as --up=-y)")
        parser.add_argument("--facing", default="auto", help="direction the body faces in its file: auto, -y, +z, ...")
        parser.add_argument("--base", help="base mesh of a PC2 point cache")
        parser.add_argument("--body-fps", type=float, metavar="FPS", help="frame rate of a moving body (default: the file's, else 25)")

    bi = bsub.add_parser("info", help="units and axes detected, height, landmarks")
    body_source(bi)
    bi.set_defaults(func=_cmd_body_info)

    from .mannequin import MEASUREMENT_PRESETS

    bm = bsub.add_parser("make", help="generate the parametric mannequin and its walk cycle")
    bm.add_argument("--preset", default="default", choices=list(MEASUREMENT_PRESETS))
    for name in ("height", "bust", "waist", "hips", "arm-length", "shoulder-width"):
        bm.add_argument(f"--{name}", type=float, metavar="CM")
    bm.add_argument("--arm-angle", type=float, metavar="DEG", help="arms below horizontal (default 45.5; 0: T-pose)")
    bm.add_argument("--arm-forward", type=float, metavar="DEG", help="arms swung forward (+) or back (-) (default 0)")
    bm.add_argument("--leg-spread", type=float, metavar="DEG", help="each leg out from vertical (default 0; -5: knees together)")
    bm.add_argument("--shoulder-slope", type=float, metavar="DEG",
                    help="fall of the shoulder line from the neck to the shoulder tip (default 21.7)")
    bm.add_argument("--frames", type=int, default=25, help="frames of the 1 s walk (25 fps)")
    bm.add_argument("--out", default="bodies", metavar="DIR")
    bm.set_defaults(func=_cmd_body_make)

    br = bsub.add_parser("render", help="front and side views as a PNG")
    body_source(br)
    br.add_argument("--frame", type=int, default=0)
    br.add_argument("--no-landmarks", action="store_true", help="leave the landmark cuts off the picture")
    br.add_argument("--out", required=True, metavar="PNG")
    br.set_defaults(func=_cmd_body_render)

    gr = sub.add_parser("grade", help="resize a pattern to a body (its girths across, its lengths along); writes a pattern file")
    gr.add_argument("pattern", metavar="PATTERN")
    body_source(gr, option=True)
    gr.add_argument("--out", required=True, metavar="PATTERN.json")
    gr.add_argument("--design-body", default="mannequin", metavar="BODY|YAML", help="the body the pattern was drafted for: a body file or name, or a GarmentCode measurement YAML (default: mannequin, GarmentCode's mean body)")
    gr.set_defaults(func=_cmd_grade)

    from .integrators import INTEGRATORS

    d = sub.add_parser("drape", help="place, sew and drape a pattern on a body; writes an OBJ per frame")
    d.add_argument("pattern", metavar="PATTERN")
    d.add_argument("--body", default="mannequin", help="mannequin (default), mannequin-walk, or a body file/folder")
    d.add_argument("--units", default="auto", choices=["auto", "m", "dm", "cm", "mm"])
    d.add_argument("--up", default="auto", choices=UP_CHOICES, help="the file's axis that points up (a negative one as --up=-y)")
    d.add_argument("--facing", default="auto")
    d.add_argument("--base", help="base mesh of a PC2 body")
    d.add_argument("--body-fps", type=float, metavar="FPS", help="frame rate of a moving body (default: the file's, else 25)")
    d.add_argument("--grade", choices=["none", "auto"], default="none",
                   help="auto: resize the pattern to the body first (its girths across, its lengths along)")
    d.add_argument("--design-body", default="mannequin", metavar="BODY|YAML", help="the body the pattern was drafted for: a body file or name, or a GarmentCode measurement YAML (default: mannequin, GarmentCode's mean body)")
    d.add_argument("--fabric", choices=fabric_names(), help="override the pattern's fabric")
    d.add_argument("--frames", type=int, default=25, help="frames after dressing (default 25)")
    d.add_argument("--fps", type=float, default=25.0)
    d.add_argument("--resolution", type=float, default=2.0, metavar="CM", help="mesh edge length (cm, default 2)")
    d.add_argument("--integrator", default="implicit", choices=list(INTEGRATORS))
    d.add_argument("--quality", default="final", choices=["draft", "normal", "final"],
                   help="speed/accuracy of the implicit step (default final; see `tailor bench`)")
    d.add_argument("--sew-timeout", type=float, default=4.0, metavar="S", help="seconds of sewing before giving up")
    d.add_argument("--self-collision", default="auto", choices=["auto", "on", "off"],
                   help="cloth-cloth contact once the garment is sewn: auto (default) = only where it can "
                        "touch itself, on = everywhere, off = none")
    d.add_argument("--wind", metavar="SPEED[,DX,DY,DZ]",
                   help="wind on the sewn garment, m/s (direction default +x; a breeze 3, a gale 20)")
    d.add_argument("--turbulence", type=float, default=0.3, help="gust strength relative to the wind speed (default 0.3)")
    d.add_argument("--cuts", metavar="FILE", help="a cuts file: the brush cuts holes or slits at given times "
                   "(JSON, cm; see docs/pattern-format.md)")
    d.add_argument("--tear", action="store_true", help="let the garment tear beyond its fabric's tear_strain")
    d.add_argument("--record-sewing", action="store_true", help="also write the sewing and settling frames")
    d.add_argument("--with-body", action="store_true", help="also write the body of every frame")
    d.add_argument("--out", metavar="DIR", help="output folder (default out/<pattern name>)")
    d.add_argument("--overwrite", action="store_true", help="replace an existing output folder")
    d.add_argument("--format", action="append", metavar="FMT",
                   help="also export as pc2, glb, usd or usda (repeat or comma-separate; the OBJ frames are always written)")
    d.add_argument("--preview", action="store_true", help="render preview frames and a GIF into OUT/preview")
    preview_options(d)
    d.set_defaults(func=_cmd_drape)

    from .io.export import FORMATS

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
    return p


def main(argv=None) -> int:
    """Run the ``tailor`` command; returns the exit status (0 ok, 2 bad input or failure)."""
    args = build_parser().parse_args(argv)
    level = logging.ERROR if args.quiet else logging.DEBUG if args.verbose else logging.INFO
    logging.basicConfig(level=level, format="%(message)s")
    try:
        return args.func(args)
    except TailorError as exc:
        print(f"tailor: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tailor: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (| head): nothing more to say, and no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
