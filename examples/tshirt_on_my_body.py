"""Dress your own body: any OBJ/PLY/STL/GLB, in any units and up axis, wears the T-shirt.

Run:  python examples/tshirt_on_my_body.py [BODY.obj]     (writes out/tshirt_on_my_body/…)

Without an argument the script first exports tailor's mannequin the way other tools would give
it to you — centimetres, Y up, facing +Z — to ``out/my_body.obj``, then loads that file back:
tailor detects the units, the up axis and the facing, finds the landmarks by slicing, and wraps
the pattern's panels around them. TAILOR_QUICK=1 uses a 4 cm mesh and 3 frames.
"""

import os
import sys
from pathlib import Path

import numpy as np

import tailor
from tailor import drape
from tailor.io.body_files import read_body
from tailor.io.garment import write_drape
from tailor.io.obj import write_obj

quick = os.environ.get("TAILOR_QUICK") == "1"
if len(sys.argv) > 1:
    body_path = Path(sys.argv[1])
else:
    m = read_body("mannequin")
    x = m.vertices
    body_path = Path("out") / "my_body.obj"
    write_obj(body_path, np.column_stack([x[:, 0], x[:, 2], -x[:, 1]]) * 100.0, m.faces)  # cm, Y up, facing +Z

body = read_body(body_path)
print(f"{body_path}: detected units {body.report['units']}, up {body.report['up']}, height {body.height * 100:.0f} cm")

pattern = tailor.read_pattern(Path(__file__).resolve().parent.parent / "panels" / "tshirt.json")
result = drape(pattern, body, frames=3 if quick else 25, resolution=0.04 if quick else 0.02)
out = write_drape(result, Path("out") / "tshirt_on_my_body", overwrite=True)
r = result.report
print(f"{r.vertices} vertices, max penetration {r.max_penetration_m * 1000:.1f} mm, {len(result.frames)} frames in {out}/")
