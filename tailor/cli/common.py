"""What several commands share: axis choices, export formats, progress bars, preview options."""

from __future__ import annotations

import sys

from ..errors import TailorError


UP_CHOICES = ["auto", "x", "y", "z", "-x", "-y", "-z"]
"""Values of ``--up``: detected, or the file's axis that points up (a minus: the body stands on its head)."""


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


def _formats(values) -> list[str]:
    """``--format glb --format usd`` or ``--format glb,usd`` → ['glb', 'usd'], each checked."""
    from ..io.export import FORMATS

    names = [f.strip().lower() for v in values or () for f in v.split(",") if f.strip()]
    for f in names:
        if f not in FORMATS:
            raise TailorError(f"--format: unknown format {f!r}; choose from {', '.join(FORMATS)}")
    return list(dict.fromkeys(names))


def _preview_settings(args):
    from ..io.preview import PreviewSettings

    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        raise TailorError(f"--size: expected WIDTHxHEIGHT in pixels, got {args.size!r}") from None
    return PreviewSettings(azimuth=args.azimuth, elevation=args.elevation, width=width, height=height, every=args.every,
                           colour=args.color)


def _preview(anim, out, args) -> list:
    from ..io.preview import preview

    settings = _preview_settings(args)
    bar, update = _bar("preview", "frame", args.quiet)
    with bar:
        files = preview(anim, out, settings=settings, gif=not args.no_gif, progress=update)
    gifs = [f for f in files if f.suffix == ".gif"]
    print(f"preview: {len(files) - len(gifs)} frames -> {out}/" + (f", {gifs[0]}" if gifs else ""))
    return files


def preview_options(parser) -> None:
    """Camera and picture options shared by ``preview`` and ``drape --preview``."""
    parser.add_argument("--azimuth", type=float, default=-30.0, metavar="DEG",
                        help="camera angle around the body (0 = front, 90 = its left; default -30)")
    parser.add_argument("--elevation", type=float, default=10.0, metavar="DEG", help="camera height angle (default 10)")
    parser.add_argument("--size", default="360x480", metavar="WxH", help="picture size in pixels (default 360x480)")
    parser.add_argument("--every", type=int, default=1, metavar="N", help="render every N-th frame (default 1)")
    parser.add_argument("--no-gif", action="store_true", help="only the PNG frames")
    parser.add_argument("--color", default="panel", choices=["panel", "stretch", "pressure", "gap"],
                        help="colour the garment by panel (default) or by its fit: stretch %%, contact pressure, "
                             "gap to the body (gap needs the body: drape --with-body)")


def fabric_options(parser, *, bending: bool = True) -> None:
    """``--density``, ``--stretch``, ``--stretch-weft`` (and ``--bending``): a preset's numbers overridden."""
    parser.add_argument("--density", type=float, metavar="G_M2", help="areal density, g/m²")
    parser.add_argument("--stretch", type=float, metavar="PCT", help="stretch under own weight (warp and weft), %%")
    parser.add_argument("--stretch-weft", type=float, metavar="PCT", help="a different stretch across the grain, %%")
    if bending:
        parser.add_argument("--bending", type=float, metavar="C", help="bending number c (cube of the bending length in cm)")


def fabric_from_args(args, name: str | None = None):
    """The preset ``args.fabric`` (or ``name``) with the numbers given by :func:`fabric_options`."""
    from ..fabric import preset

    fabric = preset(name or args.fabric)
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

