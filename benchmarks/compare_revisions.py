"""The main job at two revisions of tailor, side by side: wall time and whether the frames are identical.

    python benchmarks/compare_revisions.py BASE [--garments tshirt skirt] [--resolution 0.02]
                                                [--frames 50] [--rounds 2]

BASE (a commit, tag or branch) is checked out into a temporary git worktree; this checkout is the
other side. Each garment drapes on the walking mannequin, each round running BASE then this
checkout in fresh processes (alternating, so the machine's drift falls on both), after one small
warm-up drape each (numba compiles its kernels once per checkout). Prints the median wall time of
each side, their ratio, the time of the motion phase, and whether every frame is bit-identical:
the check a refactoring must pass ("results unchanged where nothing was meant to change").
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]

RUNNER = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import tailor
body = tailor.read_body("mannequin-walk")
pattern = tailor.read_pattern(sys.argv[2])
t = time.perf_counter()
result = tailor.drape(pattern, body, resolution=float(sys.argv[3]), frames=int(sys.argv[4]))
wall = time.perf_counter() - t
report = result.report if isinstance(result.report, dict) else result.report.to_json()
np.save(sys.argv[5], np.stack(result.frames))
print(json.dumps({"wall_s": wall, "motion_s": report["phases"]["motion"]["wall_s"], "steps": report["steps"]}))
"""


def _drape(repo: Path, garment: str, resolution: float, frames: int, out: Path) -> dict:
    pattern = HERE / "panels" / f"{garment}.json"
    done = subprocess.run([sys.executable, "-c", RUNNER, str(repo), str(pattern), str(resolution), str(frames), str(out)],
                          capture_output=True, text=True, check=True, cwd=tempfile.gettempdir())
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("base", help="the revision to compare this checkout with")
    p.add_argument("--garments", nargs="+", default=["tshirt", "skirt"])
    p.add_argument("--resolution", type=float, default=0.02, help="mesh edge length [m] (default the drape's 2 cm)")
    p.add_argument("--frames", type=int, default=50)
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        subprocess.run(["git", "-C", str(HERE), "worktree", "add", "--detach", "-q", str(base), args.base], check=True)
        try:
            sides = {"base": base, "this": HERE}
            for repo in sides.values():  # compile the kernels of each checkout before timing it
                for garment in args.garments:
                    _drape(repo, garment, 0.04, 2, Path(tmp) / "warm.npy")
            for garment in args.garments:
                times = {k: [] for k in sides}
                for _ in range(args.rounds):
                    for name, repo in sides.items():
                        times[name].append(_drape(repo, garment, args.resolution, args.frames, Path(tmp) / f"{name}.npy"))
                same = np.array_equal(np.load(Path(tmp) / "base.npy"), np.load(Path(tmp) / "this.npy"))
                med = {k: statistics.median(r["wall_s"] for r in v) for k, v in times.items()}
                motion = {k: statistics.median(r["motion_s"] for r in v) for k, v in times.items()}
                print(f"{garment:<8} {args.base}: {med['base']:6.1f} s (motion {motion['base']:5.1f} s)   this: "
                      f"{med['this']:6.1f} s (motion {motion['this']:5.1f} s)   this/base {med['this'] / med['base']:.3f}   "
                      f"frames {'bit-identical' if same else 'DIFFER'}   ({args.rounds} rounds, {args.frames} frames, "
                      f"{args.resolution * 100:g} cm)", flush=True)
        finally:
            subprocess.run(["git", "-C", str(HERE), "worktree", "remove", "--force", str(base)], check=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
