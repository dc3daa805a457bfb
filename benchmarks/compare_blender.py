"""The sphere scene in tailor and in Blender's cloth simulator, side by side in one run.

    python benchmarks/compare_blender.py [--blender-python PY] [--n 64] [--rounds 3] [--skip-blender]

Blender's part runs in a Python that has ``bpy`` (``pip install bpy``; bpy 5.0 needs Python
3.11), by default this one, in a subprocess: the same 1 m grid of n × n vertices, 5 cm above an
icosphere of r = 0.25 m (5 120 triangles), areal density 0.15 kg/m² (mass per vertex
0.15 / n² kg), air damping 0 (with real cloth mass Blender's air damping dominates), quality 5
(steps per frame), 50 frames at 25 fps. At that vertex mass Blender's spring damping acts as a
drag too (a free fall stalls at ~0.3 m/s), so it is switched off as well. Blender's cloth runs
slower than real time (×1.25 measured), so its speed multiplier is calibrated first (untimed)
with a free fall of 10 frames at Blender's default vertex mass (at the real one even an undamped
cloth stalls: the script prints how far it falls). tailor runs the
same scene at its quality presets. Printed for each: wall time, ratio to Blender, final mean
height, deepest penetration into the sphere, and clearance (median distance above the sphere of
the vertices over its top cap).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tailor.scenes import sphere_drop  # noqa: E402
from tailor.sim import QUALITY  # noqa: E402

BLENDER_PART = r"""
import json, sys, time
import bpy
import numpy as np

n, out = int(sys.argv[1]), sys.argv[2]

def scene(time_scale, frames, with_sphere, mass=None):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps = 25
    sc.frame_start, sc.frame_end = 1, frames + 1
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n - 1, y_subdivisions=n - 1, size=1.0, location=(0, 0, 0.30))
    cloth = bpy.context.object
    if with_sphere:
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=0.25, location=(0, 0, 0))
        bpy.context.object.modifiers.new("collision", "COLLISION")
    m = cloth.modifiers.new("cloth", "CLOTH")
    s = m.settings
    s.quality = 5
    s.mass = 0.15 / (n * n) if mass is None else mass
    s.air_damping = 0.0
    # at a real cloth's vertex mass (~40 mg) Blender's spring damping also acts as a drag on
    # uniform motion (a free fall reaches a terminal speed of ~0.3 m/s): switch it off too
    for name in ("tension_damping", "compression_damping", "shear_damping", "bending_damping"):
        setattr(s, name, 0.0)
    s.time_scale = time_scale
    m.point_cache.frame_start, m.point_cache.frame_end = 1, frames + 1
    return sc, cloth

def positions(sc, cloth, frames):
    for f in range(1, frames + 2):
        sc.frame_set(f)
    dg = bpy.context.evaluated_depsgraph_get()
    ev = cloth.evaluated_get(dg)
    co = np.array([ev.matrix_world @ v.co for v in ev.data.vertices])
    return co

# calibrate: a free fall of 10 frames (0.4 s) must drop g t^2 / 2; Blender's default vertex
# mass (0.3 kg) falls freely, the real one (~40 mg) reaches a terminal speed: report that too
def fall(mass, scale=1.0):
    sc, cloth = scene(scale, 10, False, mass)
    return 0.30 - positions(sc, cloth, 10)[:, 2].mean()
scale = float(np.sqrt(0.5 * 9.80665 * 0.4**2 / fall(0.3)))
light = fall(None, scale) / (0.5 * 9.80665 * 0.4**2)
sc, cloth = scene(scale, 50, True)
t0 = time.perf_counter()
x = positions(sc, cloth, 50)
wall = time.perf_counter() - t0
np.save(out, x)
print(json.dumps({"wall_s": wall, "time_scale": scale, "free_fall": light, "vertices": len(x), "version": bpy.app.version_string}))
"""


def metrics(x, radius=0.25):
    d = np.linalg.norm(x, axis=1)
    cap = np.linalg.norm(x[:, :2], axis=1) < 0.5 * radius
    return {"mean_height_m": float(x[:, 2].mean()), "penetration_mm": 1e3 * max(0.0, radius - d.min()),
            "clearance_mm": 1e3 * float(np.median(d[cap] - radius)) if cap.any() else float("nan")}


def blender_run(python, n):
    """(wall [s], final positions, info) of one Blender run, or None with the reason printed."""
    with tempfile.TemporaryDirectory() as tmp:
        script, out = Path(tmp) / "blender_part.py", Path(tmp) / "x.npy"
        script.write_text(BLENDER_PART)
        env = dict(os.environ, PYTHONPATH="")
        done = subprocess.run([python, str(script), str(n), str(out)], capture_output=True, text=True, env=env)
        if done.returncode != 0:
            tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or ["?"]
            print(f"Blender part failed ({tail[0]}); install bpy in --blender-python, or pass --skip-blender")
            return None
        info = json.loads(done.stdout.strip().splitlines()[-1])
        return info["wall_s"], np.load(out), info


def tailor_run(name, n):
    """(wall [s], final positions) of the sphere scene at quality preset ``name``."""
    q = QUALITY[name]
    setup = sphere_drop(n)
    t0 = time.perf_counter()
    result = setup.run(dt=q.step, tolerance=q.tolerance)
    return time.perf_counter() - t0, result.frames[-1]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--blender-python", default=sys.executable, help="a Python with bpy (default: this one)")
    p.add_argument("--n", type=int, default=64, help="vertices per side (default 64)")
    p.add_argument("--rounds", type=int, default=3,
                   help="rounds of Blender, draft and normal back to back (default 3); the ratios are per round, "
                        "their median is reported (this machine is noisy); final runs once")
    p.add_argument("--skip-blender", action="store_true")
    args = p.parse_args(argv)
    sphere_drop(8).run(dt=0.04, tolerance=1e-2)  # untimed warm-up (compiled kernels load), as Blender's calibration is
    walls = {}  # row name → wall per round
    last = {}  # row name → final positions of its last run
    info = None
    for _ in range(max(1, args.rounds)):
        if not args.skip_blender:
            got = blender_run(args.blender_python, args.n)
            if got is None:
                args.skip_blender = True
            else:
                wall, x, info = got
                walls.setdefault("blender", []).append(wall)
                last["blender"] = x
        for name in ("draft", "normal"):
            wall, x = tailor_run(name, args.n)
            walls.setdefault(name, []).append(wall)
            last[name] = x
    wall, last["final"] = tailor_run("final", args.n)
    walls["final"] = [wall]
    if info is not None:
        print(f"Blender free fall of the real-mass cloth over 0.4 s: {100 * info['free_fall']:.0f} % of g t²/2 "
              f"(its implicit step drags light cloth)")
    blender = walls.get("blender")
    rounds = len(walls["draft"])
    print(f"sphere scene, {args.n} × {args.n} vertices, 2 s, 50 frames; {rounds} round(s) of Blender, draft, normal back "
          f"to back in one run on this machine (median wall; ratio = median over rounds of Blender / tailor)")
    print(f"{'':<58} {'wall [s]':>9} {'vs Blender':>10} {'mean z [m]':>10} {'pen [mm]':>9} {'clear [mm]':>10}")
    for key in ("blender", "draft", "normal", "final"):
        if key not in walls:
            continue
        if key == "blender":
            name = f"Blender {info['version']} cloth, quality 5 (speed ×{info['time_scale']:.3f})"
        else:
            q = QUALITY[key]
            name = f"tailor {key} (Δt {q.step:g} s, tol {q.tolerance:.0e})"
        ratio = "-"
        if blender and key != "blender":
            per = [b / w for b, w in zip(blender, walls[key])] if key != "final" else [float(np.median(blender)) / walls[key][0]]
            ratio = f"{np.median(per):.2f}×"
            if len(per) > 1:
                name += " [" + ", ".join(f"{r:.2f}" for r in per) + "]"
        m = metrics(last[key])
        print(f"{name:<58} {np.median(walls[key]):9.2f} {ratio:>10} {m['mean_height_m']:10.4f} {m['penetration_mm']:9.2f} "
              f"{m['clearance_mm']:10.2f}")


if __name__ == "__main__":
    main()
