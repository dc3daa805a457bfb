"""Memory a garment drape takes per vertex of cloth, apart from the body (issue 29 asks ≤ 1 KB).

Each resolution runs in a fresh process (no allocator reuse between runs): one compiling drape at
3 cm, then the measured one, its frames streamed to disk as ``tailor drape`` does (``--keep-frames``:
kept in memory, as the library's ``drape`` does by default), under ``tracemalloc`` (numpy and Python allocations; numba's and
FCL's own are not seen, the resident set's high-water mark counts them). The body's share (its
frames, its broad phase, its candidates) does not grow with the cloth, so the memory per vertex
of cloth is the slope between two resolutions: (peak at the finer − peak at the coarser) /
(vertices at the finer − vertices at the coarser).

    python benchmarks/garment_memory.py [--pattern panels/tshirt.json] [--frames 10]
                                        [--resolutions 0.03 0.02 0.015] [--keep-frames]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

_CHILD = """
import json, sys, tempfile, tracemalloc
from pathlib import Path
import tailor
from tailor.bench import PeakMemory
from tailor.io.garment import DrapeWriter
pattern, res, frames, keep = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), sys.argv[4] == "keep"
body = tailor.read_body("mannequin-walk")
garment = tailor.read_pattern(pattern)
tailor.drape(garment, body, resolution=0.03, frames=1)  # compile the kernels
tracemalloc.start()
base = tracemalloc.get_traced_memory()[0]
with PeakMemory() as rss, tempfile.TemporaryDirectory() as tmp:
    if keep:
        result = tailor.drape(garment, body, resolution=res, frames=frames)
    else:  # as tailor drape does: the frames stream to disk
        with DrapeWriter(Path(tmp) / "run", garment) as writer:
            result = tailor.drape(garment, body, resolution=res, frames=frames, sink=writer, keep_frames=False)
            writer.finish(result.report)
peak = tracemalloc.get_traced_memory()[1] - base
print(json.dumps({"resolution": res, "vertices": result.report.welded_vertices,
                  "traced_mb": peak / 2**20, "rss_added_mb": rss.added}))
"""


def measure(pattern: str, resolution: float, frames: int, keep: bool = False) -> dict:
    """One drape in a fresh process: vertices, traced peak [MB] and resident set added [MB]."""
    out = subprocess.run([sys.executable, "-c", _CHILD, pattern, str(resolution), str(frames), "keep" if keep else "stream"],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pattern", default="panels/tshirt.json")
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.03, 0.02, 0.015])
    parser.add_argument("--keep-frames", action="store_true",
                        help="keep every frame in memory (the library's default) instead of streaming them to disk")
    args = parser.parse_args(argv)
    rows = [measure(args.pattern, r, args.frames, args.keep_frames) for r in args.resolutions]
    print(f"{'mesh':>6} {'vertices':>8} {'traced MB':>10} {'RSS added MB':>13} {'KB/vertex (slope)':>18}")
    for prev, row in zip([None] + rows[:-1], rows):
        slope = ""
        if prev is not None and row["vertices"] != prev["vertices"]:
            slope = f"{(row['traced_mb'] - prev['traced_mb']) * 1024 / (row['vertices'] - prev['vertices']):.2f}"
        print(f"{row['resolution'] * 100:5.1f}cm {row['vertices']:8d} {row['traced_mb']:10.1f} {row['rss_added_mb']:13.1f} {slope:>18}")


if __name__ == "__main__":
    main()
