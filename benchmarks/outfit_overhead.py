"""An outfit's wall time against the sum of its garments draped alone (issue 32: at most 1.3x).

    python benchmarks/outfit_overhead.py [--garments trousers tshirt] [--frames 50] [--rounds 3] [--cpu]

Each round drapes every garment alone and then the outfit, on the walking mannequin at the same
settings, each in a fresh process after a small compiling drape (so numba's compilation and the body's
loading are outside the timed part) and one after the other, never two at once: this machine is noisy,
so the rounds interleave and the ratio is taken per round and as the ratio of medians. Prints per run
the wall, its phases, CG iterations, penetration and crossings; for the outfit the vertices out of
layer too.

``--cpu`` runs each drape on one thread (``NUMBA_NUM_THREADS=1``) and takes the ratio of the
processes' CPU time instead of the wall: on this machine the wall of one and the same drape moves
by a fifth from run to run, single-threaded CPU time by under a tenth, so a change to the outfit's
overhead shows there first (the wall is what issue 32 asks about; it is printed too). Besides the
medians it prints the ratio of the fastest run of each drape: noise from other work on the machine
only adds time, so the least is the least disturbed.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]

_CHILD = r'''
import json, sys, time
import tailor
names, frames, quality, resolution = sys.argv[1].split("+"), int(sys.argv[2]), sys.argv[3], float(sys.argv[4])
body = tailor.read_body("mannequin-walk")
tailor.drape(tailor.read_pattern(sys.argv[5] + "/panels/tshirt.json"), body, resolution=0.08, frames=1)
patterns = [tailor.read_pattern(sys.argv[5] + "/panels/" + n + ".json") for n in names]
t, cpu = time.perf_counter(), time.process_time()
r = tailor.drape(patterns if len(patterns) > 1 else patterns[0], body, resolution=resolution, frames=frames,
                 quality=quality)
rep = r.report
print(json.dumps(dict(wall=time.perf_counter() - t, cpu=time.process_time() - cpu, phases={k: v.wall_s for k, v in rep.phases.items()},
                      cg=rep.cg_iterations, pen_mm=rep.max_penetration_m * 1e3,
                      crossings=max(rep.crossings_per_frame),
                      out_of_layer=max(rep.out_of_layer_per_frame or [0]))))
'''


def _run(names: str, args) -> dict:
    env = dict(os.environ, NUMBA_NUM_THREADS="1") if args.cpu else None
    out = subprocess.run([sys.executable, "-c", _CHILD, names, str(args.frames), args.quality,
                          str(args.resolution), str(HERE)], capture_output=True, text=True, check=True, env=env)
    run = json.loads(out.stdout.strip().splitlines()[-1])
    run["time"] = run["cpu"] if args.cpu else run["wall"]
    return run


def _line(names: str, run: dict) -> str:
    phases = " ".join(f"{k} {v:.1f}" for k, v in run["phases"].items())
    cpu = f" (CPU {run['cpu']:.1f} s)" if run["time"] == run["cpu"] else ""
    return (f"  {names:<18} {run['wall']:6.1f} s{cpu}  ({phases})  CG {run['cg']}  {run['pen_mm']:.2f} mm  "
            f"crossings {run['crossings']}  out of layer {run['out_of_layer']}")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--garments", nargs="+", default=["trousers", "tshirt"], help="innermost first")
    p.add_argument("--frames", type=int, default=50)
    p.add_argument("--resolution", type=float, default=0.02)
    p.add_argument("--quality", default="draft")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--cpu", action="store_true", help="one thread per drape, the ratio of CPU times")
    args = p.parse_args()
    unit = "s of CPU" if args.cpu else "s"
    outfit = "+".join(args.garments)
    alone, together, ratios, each = [], [], [], {name: [] for name in args.garments}
    for k in range(args.rounds):
        print(f"round {k + 1}", flush=True)
        walls = []
        for name in args.garments:
            run = _run(name, args)
            walls.append(run["time"])
            each[name].append(run["time"])
            print(_line(name, run), flush=True)
        run = _run(outfit, args)
        print(_line(outfit, run), flush=True)
        alone.append(sum(walls))
        together.append(run["time"])
        ratios.append(run["time"] / sum(walls))
        print(f"  outfit / sum alone: {run['time']:.1f} / {sum(walls):.1f} {unit} = {ratios[-1]:.2f}", flush=True)
    print(f"median: outfit {statistics.median(together):.1f} {unit}, garments alone {statistics.median(alone):.1f} {unit}, "
          f"ratio of medians {statistics.median(together) / statistics.median(alone):.2f}, "
          f"per round {', '.join(f'{r:.2f}' for r in ratios)}")
    fastest = sum(min(t) for t in each.values())
    print(f"fastest of each: outfit {min(together):.1f} {unit}, garments alone {fastest:.1f} {unit}, ratio "
          f"{min(together) / fastest:.2f} (a shared machine only ever adds time: the least is the least disturbed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
