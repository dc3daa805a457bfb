"""The main job in a dozen lines: sew the A-line skirt onto the walking mannequin.

Run:  python examples/skirt_walk.py          (writes out/skirt_walk/garment_0000.obj …, report.json)

TAILOR_QUICK=1 uses a coarse 4 cm mesh, half a second of settling and 5 frames (about 15 s); the
default is 2 cm, a second of settling and one second of walking (25 frames).
"""

import os
from pathlib import Path

import tailor
from tailor import drape
from tailor.io.body_files import read_body
from tailor.io.garment import write_drape

quick = os.environ.get("TAILOR_QUICK") == "1"
pattern = tailor.read_pattern(Path(__file__).resolve().parent.parent / "panels" / "skirt.json")
body = read_body("mannequin-walk")  # tailor's own mannequin, 1 s walk cycle at 25 fps

result = drape(pattern, body, frames=5 if quick else 25, resolution=0.04 if quick else 0.02, settle=0.5 if quick else 1.0)
out = write_drape(result, Path("out") / "skirt_walk", overwrite=True, with_body=True)

r = result.report
print(f"{r.vertices} vertices, sewn in {r.phases['sewing'].simulated_s:.2f} s of simulated time, "
      f"max penetration {r.max_penetration_m * 1000:.1f} mm, {len(result.frames)} frames in {out}/ "
      f"({r.wall_s:.1f} s)")
