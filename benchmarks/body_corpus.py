"""Body × garment over the body corpus: landmarks found, wall time, penetration, one piece, garment
where it belongs. Prints a Markdown table (the issue note's); ``--quick`` drapes at 6 cm.

    python benchmarks/body_corpus.py [--quick] [--resolution CM] [--frames N]
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


def run(body, garment, resolution, frames):
    t = time.perf_counter()
    frames_, faces, report = normalise_body(body.vertices, body.faces, source=body.name)
    b = Body(frames_, faces, 25.0, body.name, report)
    marks = measure_body(b)
    pattern, note = read_pattern(PANELS / f"{garment}.json"), ""
    try:
        check_loops(pattern, marks)
    except FitError as exc:  # the one-line error a user sees; then the pattern graded to the body
        note = f"graded ({str(exc).split(': ', 2)[1].split(' (')[0]} too small)"
        pattern, _ = grade(pattern, marks, measure_body(read_body("mannequin")))
    result = drape(pattern, b, frames=frames, resolution=resolution, quality="draft")
    x = result.frames[-1]
    return {"landmarks": len(marks), "wall": time.perf_counter() - t, "pen": 1000 * result.report.max_penetration_m,
            "pieces": garment_pieces(result.weld[result.mesh.faces], int(result.weld.max()) + 1),
            "where": " ".join(filter(None, [misplaced(garment, x, marks) or "ok", note]))}


def corpus(quick: bool):
    bodies = mannequin_variants(["child-105", "bmi-40", "t-pose", "arms-60", "thighs-touching", "man"])
    bodies += perturbations(mannequin_variants(["arms-20"])[0], ["dense-fingers", "turned-37", "mm"])
    bodies += makehuman_bodies(None if not quick else ["woman", "man", "girl-child", "heavy-woman"])
    return bodies


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--resolution", type=float, default=4.0, help="cm")
    ap.add_argument("--frames", type=int, default=3)
    args = ap.parse_args()
    res = 0.06 if args.quick else args.resolution / 100
    print("| body | garment | landmarks | wall [s] | penetration [mm] | pieces | where |\n|---|---|---|---|---|---|---|")
    for body in corpus(args.quick):
        for garment in ("tshirt", "skirt"):
            try:
                row = run(body, garment, res, args.frames)
                print(f"| {body.name} | {garment} | {row['landmarks']} | {row['wall']:.1f} | {row['pen']:.1f} | {row['pieces']} | {row['where']} |", flush=True)
            except TailorError as exc:
                print(f"| {body.name} | {garment} | — | — | — | — | {exc} |", flush=True)


if __name__ == "__main__":
    main()
