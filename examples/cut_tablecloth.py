"""A tablecloth settles on a table, then a scripted brush cuts a hole and a slit in it.

Run:  python examples/cut_tablecloth.py    (writes out/cut_tablecloth/frame_0000.obj …, cut.png)

The brush (tailor.tearing.Cut) removes the cloth within a radius of a point (a round hole in
the middle of the table) or of a polyline (a slit down the front overhang), or cuts it apart
along a polyline without removing any (``separate=True``: scissors up the left overhang); the
mesh gets new boundary loops there and the freed flaps fall. The table is a box the cloth collides with
(Carignan Eq. 9–14, friction 0.4).
"""

import os
import time
from pathlib import Path

import numpy as np
import trimesh

import tailor
from tailor.io.obj import write_obj
from tailor.io.render import render_views
from tailor.model import AIR_DENSITY, build_model
from tailor.scenes import grid
from tailor.tearing import Cut, TearableCloth, boundary_loops, simulate_tearing

quick = os.environ.get("TAILOR_QUICK") == "1"
fabric = tailor.preset("cotton")
n = 25 if quick else 61
mesh = grid(1.4, 1.4, n, name="tablecloth")
x0 = np.c_[mesh.uv - 0.7, np.full(mesh.vertex_count, 0.78)]  # 3 cm above the table top
table = trimesh.creation.box(extents=(0.8, 0.8, 0.75))
table.apply_translation((0.0, 0.0, 0.375))
cuts = [
    Cut(1.0, [(0.0, 0.0, 0.75)], 0.15),  # a hole in the middle of the top
    Cut(1.2, [(0.2, -0.4, 0.75), (0.2, -0.41, 0.5), (0.2, -0.42, 0.3)], 0.03),  # a slit down the front overhang
    # scissors up the left overhang: nothing removed, the cloth parted along the line
    Cut(1.3, [(-0.42, 0.1, 0.2), (-0.41, 0.1, 0.5), (-0.4, 0.1, 0.72)], 0.08, separate=True),
]
cloth = TearableCloth(mesh, lambda m, pinned: build_model(m, fabric, air_density=AIR_DENSITY, pinned=pinned),
                      tear_strain=0.0)
out = Path("out") / "cut_tablecloth"
t0 = time.perf_counter()
loops = []
for frame, state in simulate_tearing(cloth, cloth.model.state(x0), duration=1.6 if quick else 3.0, fps=25,
                                     dt=0.005, body=(table.vertices, table.faces), thickness=fabric.thickness,
                                     friction=fabric.friction, cuts=cuts):
    write_obj(out / f"frame_{frame:04d}.obj", state.x, cloth.mesh.faces, uv=cloth.mesh.uv)
    loops.append(boundary_loops(cloth.mesh.faces))
render_views(out / "cut.png", [(table.vertices, table.faces, (0.6, 0.45, 0.3)),
                               (state.x, cloth.mesh.faces, (0.85, 0.85, 0.95))], views=("front", "side"),
             title=f"frame {frame}: {loops[-1]} boundary loops")
print(f"{frame + 1} frames in {out}/ ({time.perf_counter() - t0:.1f} s): boundary loops {loops[0]} -> {loops[-1]}, "
      f"{mesh.face_count - cloth.mesh.face_count} triangles cut away")
