"""A square of cloth hanging from two corners: the fabric physics on its own.

Run:  python examples/hanging_cloth.py [FABRIC]     (writes out/hanging_cloth/frame_0000.obj …)

The cloth's parameters come from the fabric's three numbers (density, stretch, bending) by
Carignan's Eq. 21–26; the implicit integrator takes 10 ms steps.
"""

import os
import sys
from pathlib import Path

import numpy as np

import tailor
from tailor.io.obj import write_obj
from tailor.model import build_model
from tailor.sim import simulate

quick = os.environ.get("TAILOR_QUICK") == "1"
fabric = tailor.preset(sys.argv[1] if len(sys.argv) > 1 else "cotton")

pattern = tailor.read_pattern(Path(__file__).resolve().parent.parent / "panels" / "flag.json")
mesh = tailor.discretise(pattern, resolution=0.05 if quick else 0.02)
model = build_model(mesh, fabric)

# stand the 1 m square up in the x–z plane and hold it by its two top corners
x0 = np.column_stack([mesh.uv[:, 0] - 0.5, np.zeros(mesh.vertex_count), mesh.uv[:, 1] + 0.5])
top = x0[:, 2] > 1.5 - 1e-9
corners = np.flatnonzero(top & ((x0[:, 0] < -0.5 + 1e-9) | (x0[:, 0] > 0.5 - 1e-9)))
model = model.with_pins(corners)

out = Path("out") / "hanging_cloth"
duration = 0.5 if quick else 3.0
for frame, state in simulate(model, model.state(x0), duration=duration, frame_rate=25, integrator="implicit"):
    write_obj(out / f"frame_{frame:04d}.obj", state.x, mesh.faces, uv=mesh.uv)
sag = 1.5 - state.x[:, 2].min()
print(f"{fabric.name}: {model.vertex_count} vertices, {frame + 1} frames in {out}/, lowest point {sag * 100:.1f} cm below the pins")
