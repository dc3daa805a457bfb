"""Pattern commands: check, mesh, draw, params, grade."""

from __future__ import annotations

import time
from pathlib import Path

from ..errors import TailorError
from .body import _read_body_args, body_source
from .common import fabric_from_args, fabric_options


def _pattern_summary(pattern) -> list[str]:
    from ..curves import curve_length

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
    from ..io import read_pattern

    for path in args.patterns:
        pattern = read_pattern(path)
        print("\n".join(_pattern_summary(pattern)))
    return 0


def _cmd_mesh(args) -> int:
    from ..io import read_pattern
    from ..io.obj import write_obj
    from ..mesh import discretise

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
    from ..io import read_pattern
    from ..io.draw import draw_pattern

    pattern = read_pattern(args.pattern)
    out = Path(args.out) if args.out else Path("out") / f"{pattern.name}.png"
    draw_pattern(pattern, out, mesh_resolution=args.mesh * 1e-2 if args.mesh else None)
    print(f"{pattern.source}: {len(pattern.panels)} panels, {len(pattern.seams)} seams -> {out}")
    return 0


def _cmd_params(args) -> int:
    import json

    from ..params import fabric_params

    if args.resolution <= 0:
        from ..errors import FabricError

        raise FabricError(f"--resolution must be positive, got {args.resolution:g} cm")
    fabric = fabric_from_args(args)
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


def _graded(pattern, body, design="mannequin"):
    """``pattern`` graded from the ``design`` body (default: tailor's mannequin, GarmentCode's mean body) to
    ``body``; prints the scales."""
    from ..io.body_files import design_landmarks
    from ..measure import measure_body
    from ..sizing import grade

    graded, scales = grade(pattern, measure_body(body), design_landmarks(design))
    shown = ", ".join(f"{name} {sx:.2f}×{sy:.2f}" for name, (sx, sy) in scales.items())
    print(f"graded {pattern.source} to {body.report.get('source', body.name)} (across × along): {shown}")
    return graded, scales


def _cmd_grade(args) -> int:
    import json

    from ..io.atomic import atomic_write
    from ..io.pattern_json import pattern_from_dict, reshaped_document
    from ..measure import measure_body
    from ..sizing import check_loops

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


def add_pattern_commands(sub) -> None:
    """check, mesh, draw, params, grade."""
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

    from ..fabric import DEFAULT_FABRIC, fabric_names

    q = sub.add_parser("params", help="the simulation parameters derived from a fabric (Carignan Eq. 21-26)")
    q.add_argument("--fabric", default=DEFAULT_FABRIC, choices=fabric_names(), help=f"preset (default {DEFAULT_FABRIC})")
    fabric_options(q)
    q.add_argument("--resolution", type=float, default=1.5, metavar="CM", help="element size (cm, default 1.5)")
    q.add_argument("--json", action="store_true", help="machine-readable output")
    q.set_defaults(func=_cmd_params)

    gr = sub.add_parser("grade", help="resize a pattern to a body (its girths across, its lengths along); writes a pattern file")
    gr.add_argument("pattern", metavar="PATTERN")
    body_source(gr, option=True)
    gr.add_argument("--out", required=True, metavar="PATTERN.json")
    gr.add_argument("--design-body", default="mannequin", metavar="BODY|YAML", help="the body the pattern was drafted for: a body file or name, or a GarmentCode measurement YAML (default: mannequin, GarmentCode's mean body)")
    gr.set_defaults(func=_cmd_grade)
