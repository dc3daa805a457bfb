"""The main job: ``tailor drape``."""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

from ..errors import TailorError
from ..outfit import outfit
from .common import UP_CHOICES, _formats, _preview, preview_options
from .fit import check_maximum, describe, fit_frames, make_fits
from .pattern import _graded


def _options(args):
    """The drape's options from the command line, checked before any file is read."""
    from ..dress import DrapeOptions

    cuts = ()
    if args.cuts:
        from ..io.cuts import read_cuts

        cuts = tuple(read_cuts(args.cuts))
    return DrapeOptions(frames=args.frames, fps=args.fps, resolution=args.resolution * 1e-2, integrator=args.integrator,
                        sew_timeout=args.sew_timeout, record_sewing=args.record_sewing,
                        self_collision=args.self_collision, quality=args.quality,
                        wind=_wind(args.wind, args.turbulence), cuts=cuts, tear=args.tear, fabric=args.fabric)


def _cmd_drape(args) -> int:
    from ..io import read_pattern
    from ..io.body_files import read_body
    from ..io.garment import DrapeWriter

    formats = _formats(args.format)  # checked before a long run, not after
    exports = [f for f in formats if f != "obj"]
    every_frame = bool(args.fit or args.preview or exports)  # what needs the frames kept; the OBJs stream
    options = _options(args)
    if (args.cuts or args.tear) and every_frame:
        raise TailorError("--cuts/--tear change the garment's mesh during the run: only the OBJ sequence can hold "
                          "that (leave out --format, --preview and --fit)")
    check_maximum(args.fit_max)
    patterns = [read_pattern(path) for path in args.pattern]
    out = Path(args.out) if args.out else Path("out") / "+".join(p.name for p in patterns)
    if out.exists() and not args.overwrite:
        raise TailorError(f"{out}: already exists; choose another --out or pass --overwrite")
    body = read_body(args.body, units=args.units, up=args.up, facing=args.facing, base=args.base, fps=args.body_fps)
    if args.grade == "auto":
        patterns = [_graded(p, body, args.design_body)[0] for p in patterns]
    if args.tuck and len(patterns) < 2:
        raise TailorError("--tuck tucks a top into a bottom's waistband: give both patterns")
    pattern = outfit(patterns, tuck=args.tuck)
    t0 = time.perf_counter()
    with DrapeWriter(out, pattern, overwrite=args.overwrite, body_faces=body.faces if args.with_body else None) as writer:
        result = _run(pattern, body, replace(options, keep_frames=every_frame), writer, args.quiet)
        fits = None
        if args.fit:
            from ..fit import FitSource, fit_section

            source = FitSource.of_drape(result)
            fits = make_fits(source, fit_frames(args.fit, len(result.frames)), quiet=args.quiet)
            result.report.fit = fit_section(fits)
        writer.finish(result.report)
    if fits:
        from ..io.fit_files import write_fit

        write_fit(fits, out / "fit", source.bodies, maximum=args.fit_max)
    if exports or args.preview:
        from ..io.animation import animation_from_drape
        from ..io.export import export

        anim = animation_from_drape(result, with_body=args.with_body)
        for fmt in exports:
            export(anim, fmt, out, with_body=args.with_body)
        if args.preview:
            _preview(anim, out / "preview", args)
    r = result.report
    print(f"{pattern.source} on {args.body}: {r.vertices} vertices ({r.welded_vertices} after sewing), "
          f"{writer.count} frames, max penetration {r.max_penetration_m * 1000:.1f} mm, "
          f"seam gap at merge {r.phases['sewing'].extra['max_gap_at_merge_m'] * 1000:.1f} mm, "
          f"crossings {max(r.crossings_per_frame, default=0)}, "
          + (f"{len(options.cuts)} cuts and {r.tearing['edges_torn']} edges torn, " if r.tearing is not None else "")
          + f"{time.perf_counter() - t0:.1f} s -> {out}/")
    if fits:
        print(describe(fits, out / "fit"))
    warning = crossing_warning(r.crossings_per_frame, args.self_collision)
    if warning:
        print(warning, file=sys.stderr)
    if max(r.out_of_layer_per_frame or [0]):
        print(f"tailor: warning: garments out of their layer order: up to {max(r.out_of_layer_per_frame)} vertices "
              f"inside a garment they should be over (report.json out_of_layer_per_frame)", file=sys.stderr)
    return 0


def _run(pattern, body, options, writer, quiet: bool):
    """The drape, its frames handed to ``writer`` as they come, with progress bars on stderr."""
    from ..dress import drape

    bars = PhaseBars(disable=quiet)
    try:
        return drape(pattern, body, options=options, progress=bars, sink=writer)
    finally:
        bars.close()


def crossing_warning(crossings, self_collision: str) -> str | None:
    """The warning for frames whose cloth passes through itself (None: no frame does)."""
    if not max(crossings, default=0):
        return None
    worst = max(range(len(crossings)), key=crossings.__getitem__)
    why = "self-collision is off" if self_collision == "off" else "untangling could not undo them"
    return (f"tailor: warning: cloth passes through cloth: {sum(c > 0 for c in crossings)} of {len(crossings)} frames "
            f"have edges through triangles ({why}; most: {crossings[worst]} in frame {worst}; "
            f"report.json crossings_per_frame)")


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


def _wind(text, turbulence):
    """``--wind SPEED[,DX,DY,DZ]`` (m/s; direction default +x) → a Wind, or None."""
    if text is None:
        return None
    from ..forces.wind import Wind

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


def add_drape_command(sub) -> None:
    """drape."""
    from ..fabric import fabric_names
    from ..integrators import INTEGRATORS
    from ..sim import DEFAULT_QUALITY, QUALITY

    d = sub.add_parser("drape", help="place, sew and drape a pattern (or an outfit of several) on a body; writes an OBJ per frame")
    d.add_argument("pattern", metavar="PATTERN", nargs="+",
                   help="pattern file; several dress an outfit, the first innermost (or by each file's \"layer\")")
    d.add_argument("--body", default="mannequin", help="mannequin (default), mannequin-walk, or a body file/folder")
    d.add_argument("--units", default="auto", choices=["auto", "m", "dm", "cm", "mm"])
    d.add_argument("--up", default="auto", choices=UP_CHOICES, help="the file's axis that points up (a negative one as --up=-y)")
    d.add_argument("--facing", default="auto")
    d.add_argument("--base", help="base mesh of a PC2 body")
    d.add_argument("--body-fps", type=float, metavar="FPS", help="frame rate of a moving body (default: the file's, else 25)")
    d.add_argument("--grade", choices=["none", "auto"], default="none",
                   help="auto: resize the pattern to the body first (its girths across, its lengths along)")
    d.add_argument("--design-body", default="mannequin", metavar="BODY|YAML", help="the body the pattern was drafted for: a body file or name, or a GarmentCode measurement YAML (default: mannequin, GarmentCode's mean body)")
    d.add_argument("--tuck", action="store_true",
                   help="an outfit's top tucked into its trousers' or skirt's waistband instead of over it")
    d.add_argument("--fabric", choices=fabric_names(), help="override the pattern's fabric")
    d.add_argument("--frames", type=int, default=25, help="frames after dressing (default 25)")
    d.add_argument("--fps", type=float, default=25.0)
    d.add_argument("--resolution", type=float, default=2.0, metavar="CM", help="mesh edge length (cm, default 2)")
    d.add_argument("--integrator", default="implicit", choices=list(INTEGRATORS))
    d.add_argument("--quality", default=DEFAULT_QUALITY, choices=list(QUALITY),
                   help="speed/accuracy of the implicit step: draft (default: the T-shirt, skirt, trousers and dress "
                        "walking 50 frames at 2 cm, 7-18 s each, end 8-10 mm from final on average; final lands 2-7 mm "
                        "from itself on a mesh 1%% coarser), normal (1.0-1.3x draft's time, 4.6-7.2 mm) or final "
                        "(2.1-2.5x draft's time)")
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
    d.add_argument("--fit", nargs="?", const="last", metavar="N|all",
                   help="fit maps (stretch, pressure, gap, ease) of the last frame, frame N or all, into OUT/fit")
    d.add_argument("--fit-max", type=float, metavar="PCT",
                   help="top of the strain scale, %% (default: each fabric's wearable stretch)")
    preview_options(d)
    d.set_defaults(func=_cmd_drape)
