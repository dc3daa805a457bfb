"""Batch throughput on this machine: garments per minute with 1 and 2 Dask workers, side by side,
and the same jobs one after another in this process (numba using every core) as the baseline.

    python benchmarks/batch_throughput.py [--jobs N] [--resolution CM] [--frames F]

Jobs are the shipped skirt, T-shirt and dress on the static mannequin in cotton, denim, silk, wool
(draft quality). Each run writes into a fresh temporary folder; the first job of every run
includes its workers' start-up (imports, numba's cached kernels), as a real batch does.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tailor.batch import Job, drape_many, run_job  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=8)
    parser.add_argument("--resolution", type=float, default=4.0)
    parser.add_argument("--frames", type=int, default=10)
    args = parser.parse_args(argv)
    combos = [(p, f) for f in ("cotton", "denim", "silk", "wool") for p in ("skirt", "tshirt", "dress")]
    if not 1 <= args.jobs <= len(combos):
        parser.error(f"--jobs: 1 to {len(combos)} (distinct pattern × fabric pairs)")
    jobs = [Job(str(ROOT / "panels" / f"{p}.json"), "mannequin", f,
                {"frames": args.frames, "resolution": args.resolution, "quality": "draft"}) for p, f in combos[: args.jobs]]
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        rows = [run_job(j, Path(tmp) / "seq") for j in jobs]
        wall = time.perf_counter() - t0
        results.append(("in-process, one after another", wall, sum(r["status"] == "done" for r in rows)))
        for workers in (1, 2):
            s = drape_many(jobs, Path(tmp) / f"w{workers}", workers=workers)
            for r in s.rows:
                print(f"    {workers} worker(s): {r['id']:<40} wall {r['wall_s']:7.2f} s  cpu {r.get('cpu_s', 0):7.2f} s")
            results.append((f"Dask LocalCluster, {workers} worker(s)", s.wall_s, s.done))
    base = results[0][1]
    print(f"{len(jobs)} jobs ({args.resolution:g} cm, {args.frames} frames, draft):")
    for name, wall, done in results:
        print(f"  {name:<34} {wall:6.1f} s  {60 * done / wall:5.2f} garments/min  ({base / wall:.2f}x, {done} done)")


if __name__ == "__main__":
    main()
