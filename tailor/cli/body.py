"""Body commands: body info, make, render."""

from __future__ import annotations

from .common import UP_CHOICES


def _read_body_args(args):
    from ..io.body_files import read_body

    return read_body(args.body, units=args.units, up=args.up, facing=args.facing, base=args.base, fps=args.body_fps)


def _cmd_body_info(args) -> int:
    from ..measure import measure_body

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
    from ..io.body_files import make_bodies
    from ..mannequin import MEASUREMENT_PRESETS, with_measurements

    base = MEASUREMENT_PRESETS[args.preset]
    m = with_measurements(base, height=args.height, bust=args.bust, waist=args.waist, hips=args.hips,
                          arm_length=args.arm_length, shoulder_width=args.shoulder_width, arm_angle=args.arm_angle,
                          shoulder_slope=args.shoulder_slope, arm_forward=args.arm_forward, leg_spread=args.leg_spread)
    rest, walk = make_bodies(args.out, m, frames=args.frames)
    print(f"wrote {rest} and {walk} ({args.frames} frames, 1 s walk cycle)")
    return 0


def _cmd_body_render(args) -> int:
    from ..io.render import render_views

    from ..measure import measure_body

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


def add_body_commands(sub) -> None:
    """body info, body make, body render."""
    b = sub.add_parser("body", help="bodies: information and landmarks, the mannequin, pictures")
    bsub = b.add_subparsers(dest="body_command", required=True, metavar="ACTION")

    bi = bsub.add_parser("info", help="units and axes detected, height, landmarks")
    body_source(bi)
    bi.set_defaults(func=_cmd_body_info)

    from ..mannequin import MEASUREMENT_PRESETS

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
