"""Cost per vertex-step on the sphere from 32² to 256², the step following the mesh (issue 29).

    python benchmarks/sphere_scaling.py [--presets draft normal] [--sizes 32 64 128 256] [--fixed]

Each preset drops the 1 m cotton square onto the sphere (:func:`tailor.scenes.sphere_drop`, 2 s,
self-collision ``auto``) at its own solver tolerance and at the step a garment of that mesh takes,
``Quality.garment_step(1 / (n − 1))``: a step carries no vertex farther, in its own triangles, on
a fine grid than on a coarse one. ``--fixed`` runs each preset's fixed step instead, as ``tailor
bench`` runs the scene (a 40 ms step on a 3.9 mm grid moves a flap ten edge lengths: more CG
iterations a step and more self-contact pairs a vertex the finer the grid). Prints wall time,
integrator steps, µs per vertex-step, CG iterations a step, the self-contact's query and response
seconds and the steps halved; one run each, in this process, after an untimed warm-up.
"""

from __future__ import annotations

import argparse
import sys
import time

from tailor.scenes import sphere_drop
from tailor.sim import QUALITY


def run(n: int, preset: str, fixed: bool) -> str:
    """One drop: a Markdown table row."""
    q = QUALITY[preset]
    dt = q.step if fixed else q.garment_step(1.0 / (n - 1))
    scene = sphere_drop(n)
    t0 = time.perf_counter()
    result = scene.run(dt=dt, tolerance=q.tolerance, self_collision="auto")
    wall = time.perf_counter() - t0
    rep = result.report
    steps, selfc = rep["steps"], rep["self_collision"]
    halved = sum(rep["halved_steps"].values())
    return (f"| {n}² | {preset} | {dt * 1e3:.1f} ms | {wall:.1f} s | {steps} | {wall / steps / (n * n) * 1e6:.1f} | "
            f"{rep['cg_iterations'] / steps:.0f} | {selfc.get('query_s', 0.0):.1f} s | {selfc.get('response_s', 0.0):.1f} s | {halved} |")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--presets", nargs="+", default=["draft", "normal"], choices=list(QUALITY))
    p.add_argument("--sizes", nargs="+", type=int, default=[32, 64, 128, 256])
    p.add_argument("--fixed", action="store_true", help="each preset's fixed step (tailor bench's), not the mesh's")
    args = p.parse_args(argv)
    sphere_drop(8).run(dt=0.04, tolerance=1e-2)  # untimed warm-up: the compiled kernels load
    print("| grid | preset | step | wall | steps | µs a vertex-step | CG a step | self-contact queries | responses | halved |\n"
          "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|", flush=True)
    for preset in args.presets:
        for n in args.sizes:
            print(run(n, preset, args.fixed), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
