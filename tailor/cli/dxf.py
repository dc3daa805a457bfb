"""``tailor import`` and ``tailor export-pattern``: patterns from and to pattern-making CAD (DXF in
the AAMA / ASTM D6673 layout)."""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import TailorError


def _cmd_import(args) -> int:
    from ..io import pattern_from_dict
    from ..io.atomic import write_text_atomic
    from ..io.dxf import read_dxf
    from ..io.dxf_pattern import pieces_to_pattern

    source = Path(args.file)
    out = Path(args.out)
    if out.suffix.lower() != ".json":
        raise TailorError(f"--out {out}: a pattern file ends in .json")
    sidecar = None
    if args.seams not in ("auto", "none"):
        path = Path(args.seams)
        try:
            sidecar = (json.loads(path.read_text()), str(path))
        except OSError as exc:
            raise TailorError(f"--seams {path}: cannot read: {exc.strerror or exc}") from None
        except ValueError as exc:
            raise TailorError(f"{path}: malformed JSON: {exc}") from None
        if not isinstance(sidecar[0], dict):
            raise TailorError(f"{path}: expected an object with 'seams' (and 'placement')")
    pieces, notes = read_dxf(source, units=args.units, size=args.size)
    doc, more = pieces_to_pattern(pieces, out.stem, seams=args.seams, sidecar=sidecar)
    doc["description"] = f"imported from {source.name}"
    pattern = pattern_from_dict(doc, source=str(out))  # what it would read back, checked before writing
    write_text_atomic(out, json.dumps(doc, indent=1))
    area = sum(p.area for p in pattern.panels) * 1e4
    print(f"{source}: {len(pattern.panels)} pieces, {area:.0f} cm² in all, {len(pattern.seams)} seams, "
          f"{len(pattern.attachments)} attachments -> {out}")
    for note in notes + more:
        print(f"  {note}")
    return 0


def _cmd_export_pattern(args) -> int:
    from ..io import read_pattern
    from ..io.dxf_export import write_dxf

    out = Path(args.out)
    if out.suffix.lower() != ".dxf":
        raise TailorError(f"--out {out}: a DXF file ends in .dxf")
    pattern = read_pattern(args.pattern)
    write_dxf(pattern, out)
    print(f"{args.pattern}: {len(pattern.panels)} pieces, {len(pattern.seams)} seams as notches -> {out} (AAMA, mm)")
    return 0


def add_import_command(sub) -> None:
    """import, export-pattern."""
    i = sub.add_parser("import", help="a pattern from CAD: DXF in the AAMA / ASTM D6673 layout (needs ezdxf)")
    i.add_argument("file", metavar="FILE.dxf")
    i.add_argument("--out", required=True, metavar="PATTERN.json", help="the pattern file to write")
    i.add_argument("--units", choices=["mm", "cm", "in", "m"], help="the file's units (default: from the file, else mm)")
    i.add_argument("--size", metavar="S", help="the size to read from a graded file (default: the first)")
    i.add_argument("--seams", default="auto", metavar="auto|none|SEAMS.json",
                   help="auto (default): sew notched sides of equal length and matching notches; none: no seams; "
                        "SEAMS.json: the seams (and placements) listed there (docs/pattern-format.md)")
    i.set_defaults(func=_cmd_import)

    e = sub.add_parser("export-pattern", help="a pattern to CAD: DXF in the AAMA layout, seams as notches (needs ezdxf)")
    e.add_argument("pattern", metavar="PATTERN")
    e.add_argument("--format", choices=["dxf-aama"], default="dxf-aama", help="dxf-aama (the only one)")
    e.add_argument("--out", required=True, metavar="FILE.dxf")
    e.set_defaults(func=_cmd_export_pattern)
