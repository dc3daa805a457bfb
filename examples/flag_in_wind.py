"""A flag on a pole in a rising gale, tearing: wind, tearing and a mesh that really splits.

Run:  python examples/flag_in_wind.py      (writes out/flag_in_wind/frame_0000.obj …, torn.png)

The 1 m × 0.6 m cotton flag is held along its pole edge. The wind is a turbulent Perlin-noise
air velocity (tailor.forces.wind.Wind), acting on each triangle along its normal, so the flag
flaps; it rises from calm to a gale (its ``ramp``). Where the cloth is stretched across a line by more than
the fabric's tear strain (30 %) the mesh splits there: every frame's OBJ has the
topology of that moment, rips and all.
"""

import os
import time
from pathlib import Path

import numpy as np

import tailor
from tailor.forces.wind import Wind
from tailor.io.obj import write_obj
from tailor.io.render import render_views
from tailor.model import AIR_DENSITY, build_model
from tailor.scenes import grid
from tailor.tearing import TearableCloth, simulate_tearing

quick = os.environ.get("TAILOR_QUICK") == "1"
fabric = tailor.preset("cotton").with_values(name="flag cotton", tear_strain=0.3)
n = 16 if quick else 41
mesh = grid(1.0, 0.6, n, round(0.6 * (n - 1)) + 1, name="flag")
pole = np.flatnonzero(mesh.uv[:, 0] < 1e-9)
x0 = np.c_[mesh.uv[:, 0], np.zeros(mesh.vertex_count), mesh.uv[:, 1] + 1.4]  # in the x–z plane, pole at x = 0


def build(m, pinned):
    return build_model(m, fabric, air_density=AIR_DENSITY, pinned=pinned)


# a gale rising from calm to 30 m/s
wind = Wind(speed=30.0, direction=(1.0, 0.3, 0.0), turbulence=0.3, gust_size=0.5, ramp=1.0 if quick else 3.0)
cloth = TearableCloth(mesh, build, tear_strain=fabric.tear_strain, pinned=pole)
out = Path("out") / "flag_in_wind"
t0 = time.perf_counter()
picture = None
for frame, state in simulate_tearing(cloth, cloth.model.state(x0), duration=1.2 if quick else 4.0, fps=25,
                                     integrator="implicit", dt=0.0025, wind=wind):
    write_obj(out / f"frame_{frame:04d}.obj", state.x, cloth.mesh.faces, uv=cloth.mesh.uv)
    if picture is None and cloth.tears >= 15:  # the rip running
        picture = (frame, state.x.copy(), cloth.mesh.faces.copy(), cloth.tears)
        render_views(out / "torn.png", [(picture[1], picture[2], (0.8, 0.25, 0.25))], views=("front",), size=(6, 4),
                     title=f"frame {frame}: {cloth.tears} edges torn")
if picture is None:
    render_views(out / "torn.png", [(state.x, cloth.mesh.faces, (0.8, 0.25, 0.25))], views=("front",), size=(6, 4),
                 title=f"frame {frame}: {cloth.tears} edges torn")
print(f"{frame + 1} frames in {out}/ ({time.perf_counter() - t0:.1f} s): {cloth.tears} edges torn, "
      f"{cloth.mesh.vertex_count - mesh.vertex_count} vertices split off, first tear at "
      f"{cloth.events[0][0]:.2f} s" if cloth.events else "no tear")
