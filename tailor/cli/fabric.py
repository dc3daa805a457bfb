"""``tailor fabric``: the standard fabric tests, simulated, and calibration from measurements.

``drape-test`` (Cusick, BS 5058 / ISO 9073-9), ``cantilever-test`` (Peirce, ASTM D1388 / BS 3356)
and ``calibrate`` (the fabric numbers that reproduce a cantilever bending length, a drape
coefficient or Kawabata measurements); :mod:`tailor.lab` does the work.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import FabricError, TailorError
from .common import fabric_from_args, fabric_options


def _positive(value, flag: str, unit: str):
    if value is not None and not value > 0:
        raise FabricError(f"{flag}: expected a number above 0 {unit}, got {value:g}")
    return value


def _test_fabric(args):
    from ..fabric import DEFAULT_FABRIC

    if args.name is None and args.density is None:
        raise TailorError("name a fabric preset, or give its numbers with --density (and --stretch, --bending)")
    return fabric_from_args(args, args.name or DEFAULT_FABRIC)


def _cmd_drape_test(args) -> int:
    from ..io.plots import shadow_plot
    from ..lab import drape_test

    _positive(args.resolution, "--resolution", "cm")
    fabric = _test_fabric(args)
    test = drape_test(fabric, resolution=args.resolution * 1e-2, specimens=args.specimens)
    picture = Path(args.picture or f"out/drape_test_{fabric.name.split()[0]}.png")
    picture.parent.mkdir(parents=True, exist_ok=True)
    shadow_plot(picture, [test])
    if args.json:
        print(json.dumps({**test.as_dict(), "picture": str(picture)}, indent=2))
    else:
        each = ", ".join(f"{dc:.3f}/{n}" for dc, n in test.specimens)
        print(f"{fabric.name}: drape coefficient {test.drape_coefficient:.3f}, {test.nodes} nodes "
              f"(specimens {each}; {args.resolution:g} cm mesh, {test.wall_s:.1f} s); shadow: {picture}")
    return 0


def _cmd_cantilever_test(args) -> int:
    from ..lab import cantilever_test

    _positive(args.overhang, "--overhang", "cm")
    fabric = _test_fabric(args)
    if fabric.bending <= 0:
        raise FabricError(f"fabric {fabric.name!r}: bending is 0, so it has no bending length to measure")
    test = cantilever_test(fabric, direction=args.direction, overhang=None if args.overhang is None else args.overhang * 1e-2)
    if args.json:
        print(json.dumps(test.as_dict(), indent=2))
    else:
        d = test.as_dict()
        print(f"{fabric.name} ({args.direction}): bending length {d['bending_length_cm']:.2f} cm "
              f"(overhang {d['overhang_cm']:.2f} cm, tip {d['tip_angle_deg']:.1f}° below the edge; "
              f"the fabric's bending number stands for {d['nominal_cm']:.2f} cm)")
    return 0


def _kes_number(path: str, key: str, value, unit: str) -> float:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0:
        raise TailorError(f"{path}: {key}: expected a number above 0 ({unit}), got {value!r}")
    return float(value)


def _kes_pair(path: str, key: str, value, unit: str) -> tuple[float, float]:
    """(warp, weft) of a KES field given as one number or as ``{"warp": …, "weft": …}``."""
    if isinstance(value, dict):
        return tuple(_kes_number(path, f"{key}.{d}", value.get(d), unit) for d in ("warp", "weft"))
    v = _kes_number(path, key, value, unit)
    return v, v


def _read_kes(path: str) -> dict:
    """W [g/m²], B [gf·cm²/cm] (the mean of warp and weft) and EMT [%] per direction from a JSON file."""
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise TailorError(f"{path}: cannot read: {exc.strerror}") from None
    except json.JSONDecodeError as exc:
        raise TailorError(f"{path}: not JSON: {exc.msg} at line {exc.lineno}") from None
    if not isinstance(data, dict):
        raise TailorError(f'{path}: expected an object {{"W": …, "B": …, "EMT": …}}')
    bending = _kes_pair(path, "B", data.get("B"), "gf·cm²/cm")
    emt = _kes_pair(path, "EMT", data.get("EMT"), "%")
    return {"W": _kes_number(path, "W", data.get("W"), "g/m²"), "B": 0.5 * sum(bending), "EMT": emt[0], "EMT_weft": emt[1]}


def _calibrated(args, base):
    """(fabric, what checks it) for the measurement given."""
    from ..lab import calibrate_bending, drape_test, fabric_from_cantilever, fabric_from_kes

    if args.cantilever_cm is not None:
        _positive(args.cantilever_cm, "--cantilever-cm", "cm")
        fabric, test = fabric_from_cantilever(base, args.cantilever_cm * 1e-2)
        return fabric, {"cantilever": test.as_dict()}
    if args.drape_coefficient is not None:
        if not 0.0 < args.drape_coefficient < 1.0:
            raise FabricError(f"--drape-coefficient: expected a number between 0 and 1, got {args.drape_coefficient:g}")
        fabric, test = calibrate_bending(base, args.drape_coefficient, resolution=args.resolution * 1e-2)
        return fabric, {"drape_test": test.as_dict()}
    kes = _read_kes(args.kes)
    fabric = fabric_from_kes(base, density_g_m2=kes["W"], bending_gf_cm=kes["B"], emt_pct=kes["EMT"],
                             emt_weft_pct=kes["EMT_weft"])
    return fabric, {"drape_test": drape_test(fabric, resolution=args.resolution * 1e-2).as_dict()}


def _cmd_calibrate(args) -> int:
    from ..fabric import DEFAULT_FABRIC

    _positive(args.resolution, "--resolution", "cm")
    base = fabric_from_args(args, args.like or DEFAULT_FABRIC)
    fabric, check = _calibrated(args, base)
    numbers = {"density": round(fabric.density * 1e3, 4), "stretch": round(fabric.stretch_warp * 100, 5),
               "stretch_weft": round(fabric.stretch_weft * 100, 5), "bending": round(fabric.bending, 4)}
    block = {"fabric": {"preset": base.name.split()[0], **numbers}}
    if args.json:
        print(json.dumps({**numbers, "check": check, "pattern_fabric": block["fabric"]}, indent=2))
        return 0
    print(f"density {numbers['density']:g} g/m², stretch {numbers['stretch']:g} % (weft {numbers['stretch_weft']:g} %), "
          f"bending {numbers['bending']:g}")
    for name, result in check.items():
        print(f"simulated {name.replace('_', ' ')}: " + ", ".join(f"{k} {v}" for k, v in result.items() if k != "fabric"))
    print("for a pattern file:\n  " + json.dumps(block)[1:-1])
    return 0


def add_fabric_commands(sub) -> None:
    """fabric drape-test | cantilever-test | calibrate."""
    from ..fabric import fabric_names
    from ..lab import DRAPE_RESOLUTION, SPECIMEN_SCALES

    f = sub.add_parser("fabric", help="fabric tests (Cusick drape, cantilever) simulated, and calibration from measurements")
    fsub = f.add_subparsers(dest="fabric_command", required=True, metavar="TEST")
    res = DRAPE_RESOLUTION * 100
    d = fsub.add_parser("drape-test", help="the Cusick drape test: drape coefficient, nodes and a shadow picture")
    c = fsub.add_parser("cantilever-test", help="the cantilever test: bending length from Peirce's relation")
    for p in (d, c):
        p.add_argument("name", nargs="?", choices=fabric_names(), metavar="NAME", help="fabric preset (" + ", ".join(fabric_names()) + ")")
        fabric_options(p)
        p.add_argument("--json", action="store_true", help="machine-readable output")
    d.add_argument("--resolution", type=float, default=res, metavar="CM", help=f"element size (cm, default {res:g}: where the node count has converged)")
    d.add_argument("--specimens", type=int, default=len(SPECIMEN_SCALES), choices=range(1, len(SPECIMEN_SCALES) + 1),
                   help=f"specimens averaged, each a different triangulation (default {len(SPECIMEN_SCALES)})")
    d.add_argument("--picture", metavar="PNG", help="the shadow picture (default out/drape_test_NAME.png)")
    d.set_defaults(func=_cmd_drape_test)
    c.add_argument("--direction", default="warp", choices=["warp", "weft"], help="the strip's length along (default warp)")
    c.add_argument("--overhang", type=float, metavar="CM", help="overhang (default: twice the nominal bending length)")
    c.set_defaults(func=_cmd_cantilever_test)

    k = fsub.add_parser("calibrate", help="the fabric numbers that reproduce a measurement, and a block for a pattern file")
    k.add_argument("--like", choices=fabric_names(), metavar="NAME", help="preset giving the numbers not measured (default cotton)")
    fabric_options(k, bending=False)
    how = k.add_mutually_exclusive_group(required=True)
    how.add_argument("--cantilever-cm", type=float, metavar="L", help="measured bending length (ASTM D1388), cm")
    how.add_argument("--drape-coefficient", type=float, metavar="DC", help="measured Cusick drape coefficient, 0 to 1")
    how.add_argument("--kes", metavar="FILE.json", help='Kawabata numbers: {"W": g/m², "B": gf·cm²/cm, "EMT": %%} '
                     '(B and EMT may be {"warp": …, "weft": …})')
    k.add_argument("--resolution", type=float, default=res, metavar="CM", help=f"drape-test element size (cm, default {res:g})")
    k.add_argument("--json", action="store_true", help="machine-readable output")
    k.set_defaults(func=_cmd_calibrate, bending=None)
