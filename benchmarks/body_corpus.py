"""Body × garment over the body corpus: landmarks found, wall time, penetration, crossings, the
most stretched triangle, one piece, garment where it belongs. Prints a Markdown table (the issue
note's); ``--quick`` drapes at 6 cm. A garment is a pattern of ``panels/`` or, with
``--garmentcode DIR``, GarmentCode's (``DIR/NAME_specification.json``, placed by its rigid
transforms: its T-shirt, pants, skirts and dress on MakeHuman's bodies, docs/measurements.md).

    python benchmarks/body_corpus.py [--quick] [--resolution CM] [--frames N] [--garments NAME ...]
                                     [--garmentcode ../shared/garmentcode] [--makehuman]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from tailor.body import Body, normalise_body
from tailor.corpus import garment_pieces, makehuman_bodies, mannequin_variants, misplaced, perturbations
from tailor.dress import drape
from tailor.errors import TailorError
from tailor.io import read_pattern
from tailor.io.body_files import read_body
from tailor.measure import measure_body
from tailor.sizing import FitError, check_loops, grade

PANELS = Path(__file__).resolve().parents[1] / "panels"


def pattern_path(garment: str, garmentcode: Path | None) -> Path:
    """GarmentCode's ``GARMENT_specification.json`` in ``garmentcode`` if given, else ``panels/GARMENT.json``."""
    return PANELS / f"{garment}.json" if garmentcode is None else garmentcode / f"{garment}_specification.json"


def run(body, garment, resolution, frames, garmentcode=None):
    t = time.perf_counter()
    frames_, faces, report = normalise_body(body.vertices, body.faces, source=body.name)
    b = Body(frames_, faces, 25.0, body.name, report)
    marks = measure_body(b)
    pattern, note = read_pattern(pattern_path(garment, garmentcode)), ""
    try:
        check_loops(pattern, marks)
    except FitError as exc:  # the one-line error a user sees; then the pattern graded to the body
        note = f"graded ({str(exc).split(': ', 2)[1].split(' (')[0]} too small)"
        pattern, _ = grade(pattern, marks, measure_body(read_body("mannequin")))
    result = drape(pattern, b, frames=frames, resolution=resolution, quality="draft")
    x = result.frames[-1]
    return {"landmarks": len(marks), "wall": time.perf_counter() - t, "pen": 1000 * result.report.max_penetration_m,
            "crossings": max(result.report.crossings_per_frame), "stretch": result.report.max_triangle_stretch_dressed,
            "pieces": garment_pieces(result.weld[result.mesh.faces], int(result.weld.max()) + 1),
            "where": " ".join(filter(None, [misplaced(garment, x, marks) or "ok", note]))}


def corpus(quick: bool, makehuman_only: bool = False):
    people = makehuman_bodies(None if not quick else ["woman", "man", "girl-child", "heavy-woman"])
    if makehuman_only:
        return people
    bodies = mannequin_variants(["child-105", "bmi-40", "t-pose", "arms-60", "thighs-touching", "man"])
    bodies += perturbations(mannequin_variants(["arms-20"])[0], ["dense-fingers", "turned-37", "mm"])
    return bodies + people


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--resolution", type=float, default=4.0, help="cm")
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--garments", nargs="+", default=["tshirt", "skirt"])
    ap.add_argument("--garmentcode", type=Path, help="folder of GarmentCode's NAME_specification.json files")
    ap.add_argument("--makehuman", action="store_true", help="MakeHuman's bodies only")
    args = ap.parse_args()
    res = 0.06 if args.quick else args.resolution / 100
    print("| body | garment | landmarks | wall [s] | penetration [mm] | crossings | stretch | pieces | where |\n"
          "|---|---|---|---|---|---|---|---|---|")
    for body in corpus(args.quick, args.makehuman):
        for garment in args.garments:
            try:
                row = run(body, garment, res, args.frames, args.garmentcode)
                print(f"| {body.name} | {garment} | {row['landmarks']} | {row['wall']:.1f} | {row['pen']:.1f} | {row['crossings']} | "
                      f"{row['stretch']:.2f} | {row['pieces']} | {row['where']} |", flush=True)
            except TailorError as exc:
                print(f"| {body.name} | {garment} | — | — | — | — | — | — | {exc} |", flush=True)


if __name__ == "__main__":
    main()
