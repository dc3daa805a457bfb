"""Each quality preset on whole garments walking: cost against accuracy, to put the default on the knee.

    python benchmarks/garment_presets.py [--garments tshirt skirt] [--resolution 0.02] [--frames 50]

Every garment drapes on the walking mannequin at each preset (``tailor drape --quality``), all in
this one process, one after the other. Prints per preset the wall time (whole drape and motion), CG
iterations, the deepest penetration and the most self-intersecting triangle pairs of any frame, and
the distance of its last frame from ``final``'s (mean and worst over corresponding rest points:
``tailor bench``'s metric). The default should be the cheapest preset within a few mm of ``final``.

A walk is chaotic: ``final`` itself lands elsewhere when nothing a designer would notice changes.
With ``--floor`` each garment also drapes at ``final`` on a mesh 1 % coarser, and its row ("final,
mesh +1 %") gives that spread: a preset within a few mm of it is as close to ``final`` as ``final``
is to itself.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import tailor
from tailor.bench import rest_error
from tailor.sim import QUALITY

HERE = Path(__file__).resolve().parents[1]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--garments", nargs="+", default=["tshirt", "skirt"])
    p.add_argument("--resolution", type=float, default=0.02)
    p.add_argument("--frames", type=int, default=50)
    p.add_argument("--floor", action="store_true", help="also final on a mesh 1 %% coarser: final's own spread")
    args = p.parse_args()
    body = tailor.read_body("mannequin-walk")
    tailor.drape(tailor.read_pattern(HERE / "panels" / "tshirt.json"), body, resolution=0.08, frames=1)  # compile
    print("| garment | preset | wall s | motion s | CG iterations | max penetration mm | max crossings | "
          "last frame vs final: mean mm | worst mm |\n|---|---|---|---|---|---|---|---|---|")
    for garment in args.garments:
        pattern = tailor.read_pattern(HERE / "panels" / f"{garment}.json")
        results = {}
        for name in reversed(list(QUALITY)):  # final first: the others are compared with it
            t = time.perf_counter()
            r = tailor.drape(pattern, body, resolution=args.resolution, frames=args.frames, quality=name)
            results[name] = (r, time.perf_counter() - t)
        if args.floor:
            t = time.perf_counter()
            r = tailor.drape(pattern, body, resolution=args.resolution * 1.01, frames=args.frames, quality="final")
            results["final, mesh +1 %"] = (r, time.perf_counter() - t)
        ref = results["final"][0]
        for name in [*QUALITY, *(n for n in results if n not in QUALITY)]:
            r, wall = results[name]
            mean, worst = rest_error(ref.mesh.uv, ref.frames[-1], r.mesh.uv, r.frames[-1], ref.mesh.vertex_panel,
                                     r.mesh.vertex_panel)
            rep = r.report
            print(f"| {garment} | {name} | {wall:.1f} | {rep.phases['motion'].wall_s:.1f} | {rep.cg_iterations} | "
                  f"{rep.max_penetration_m * 1e3:.2f} | {max(rep.crossings_per_frame)} | {mean * 1e3:.1f} | "
                  f"{worst * 1e3:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
