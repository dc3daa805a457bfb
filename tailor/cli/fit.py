"""``tailor fit``: fit maps of a drape (stretch, pressure, gap, ease), and ``tailor drape --fit``'s half."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import TailorError


def fit_frames(text: str, count: int) -> list[int]:
    """``all``, ``last`` or a frame number (negative: from the end) → frame indices of a ``count``-frame drape."""
    if text == "all":
        return list(range(count))
    if text == "last":
        return [count - 1]
    try:
        k = int(text)
    except ValueError:
        raise TailorError(f"--frame: expected a frame number, 'last' or 'all', got {text!r}") from None
    if not -count <= k < count:
        raise TailorError(f"--frame: {k} is not a frame of this drape (0 to {count - 1})")
    return [k % count]


def check_maximum(value):
    """``--max`` in % (None: each fabric's wearable stretch)."""
    if value is not None and not value > 0:
        raise TailorError(f"--max: expected a stretch above 0 %, got {value:g}")
    return value


def make_fits(source, frames, *, quiet: bool = False) -> list:
    """Fit maps of ``frames`` of ``source``, with a progress bar."""
    from ..fit import fit_map
    from .common import _bar

    bar, update = _bar("fit", "frame", quiet)
    fits = []
    with bar:
        for i, k in enumerate(frames):
            fits.append(fit_map(source, k))
            update(i + 1, len(frames))
    return fits


def describe(fits, out: Path) -> str:
    """One line per map: the worst panel, the largest pressure, the ease at the bust/waist/hips."""
    lines = []
    for f in fits:
        rows = f.panel_rows()
        worst = max(rows, key=lambda r: r["stretch_max_pct"])
        ease = ", ".join(f"{k} {e.ease * 100:+.1f}" for k, e in f.ease.items() if k in ("bust", "waist", "hips"))
        lines.append(f"fit frame {f.frame}: stretch up to {worst['stretch_max_pct']:.1f} % ({worst['panel']}), "
                     f"{max(r['over_wearable_pct'] for r in rows):.1f} % of a panel over its wearable stretch, "
                     f"pressure up to {f.pressure_kpa.max(initial=0):.2f} kPa"
                     + (f", ease cm: {ease}" if ease else "") + f" -> {out}/")
        lines += [f"  note: {n}" for n in f.notes]
    return "\n".join(lines)


def _cmd_fit(args) -> int:
    from ..fit import FitSource, fit_section
    from ..io.atomic import write_text_atomic
    from ..io.body_files import read_body
    from ..io.fit_files import write_fit

    maximum = check_maximum(args.max)
    run = Path(args.run)
    body = read_body(args.body, units=args.units) if args.body else None
    source = FitSource.of_run(run, body=body)
    frames = fit_frames(args.frame, source.anim.frame_count)
    out = Path(args.out) if args.out else run / "fit"
    fits = make_fits(source, frames, quiet=args.quiet)
    write_fit(fits, out, source.bodies, maximum=maximum)
    report = run / "report.json"
    if report.exists():
        info = json.loads(report.read_text())
        info["fit"] = fit_section(fits)
        write_text_atomic(report, json.dumps(info, indent=2))
    print(describe(fits, out))
    return 0


def add_fit_command(sub) -> None:
    """fit."""
    f = sub.add_parser("fit", help="fit maps of a drape: stretch, contact pressure, gap to the body, ease")
    f.add_argument("run", metavar="RUN_DIR", help="a folder written by tailor drape")
    f.add_argument("--frame", default="last", metavar="N|all", help="the frame to map (default: the last; all: every frame)")
    f.add_argument("--out", metavar="DIR", help="output folder (default RUN_DIR/fit)")
    f.add_argument("--max", type=float, metavar="PCT",
                   help="top of the strain scale for every panel, %% (default: each fabric's wearable stretch)")
    f.add_argument("--body", metavar="BODY", help="the body the run was draped on, if the run has no body frames "
                   "(default: the shipped body the report names)")
    f.add_argument("--units", default="auto", choices=["auto", "m", "dm", "cm", "mm"], help="units of --body's file")
    f.set_defaults(func=_cmd_fit)
