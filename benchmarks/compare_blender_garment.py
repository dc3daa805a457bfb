"""A whole garment drape in tailor against Blender's cloth on the walk alone, side by side in one run.

    python benchmarks/compare_blender_garment.py [--blender-python PY] [--garment tshirt] [--frames 50]
                                                 [--resolution 0.02] [--rounds 3] [--presets draft normal final]

tailor dresses the walking mannequin in ``panels/GARMENT.json`` at each preset (sew, settle, walk
``--frames`` frames: the whole ``tailor drape``), timed. Blender's cloth (in a Python that has
``bpy``: ``pip install bpy`` in a Python 3.11 venv; skipped with a message when there is none) is
given tailor's dressed frame 0 (the default preset's, from the first round) and simulates only the
walk; the rounds interleave (each preset once, then Blender once), so a machine that speeds up or
slows down during the run does so for both: the
welded garment mesh, quality 5, self-collision on, Blender's Cotton stiffness (tension and
compression 15, shear 5, bending 0.5), the physical vertex mass (garment mass / vertices), air
damping 1, the body a collider following the walk through a Mesh Cache modifier (a PC2 file
written by :func:`tailor.io.pc2.write_pc2`). Timed is Blender's stepping through the frames only.

Printed per run: wall time (median of ``--rounds``), its ratio to Blender's (> 1: tailor's whole
drape is quicker than Blender's walk), the deepest penetration into the body of the last frame
and the edge–triangle crossings of the last frame (:func:`tailor.collide.edge_crossings`, the
check a renderer trips on), the same independent checks for both simulators.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import tailor  # noqa: E402
from tailor.collide import BodyCollider, edge_crossings  # noqa: E402
from tailor.io.pc2 import write_pc2  # noqa: E402
from tailor.sim import DEFAULT_QUALITY, QUALITY  # noqa: E402

HERE = Path(__file__).resolve().parents[1]

BLENDER_PART = r"""
import json, sys, time
import bpy
import numpy as np

data = np.load(sys.argv[1])
out, pc2, frames = sys.argv[2], sys.argv[3], int(sys.argv[4])
bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
sc.render.fps = 25
sc.frame_start, sc.frame_end = 1, frames

def mesh_object(name, verts, faces):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts.tolist(), [], faces.tolist())
    me.update()
    ob = bpy.data.objects.new(name, me)
    sc.collection.objects.link(ob)
    return ob

body = mesh_object("body", data["body0"], data["body_faces"])
cache = body.modifiers.new("walk", "MESH_CACHE")
cache.cache_format = "PC2"
cache.filepath = pc2
cache.frame_start = 1.0  # scene frame 1 = the cache's first sample = tailor's frame 0
body.modifiers.new("collision", "COLLISION")
body.collision.thickness_outer = 0.002
cloth = mesh_object("garment", data["cloth0"], data["cloth_faces"])
m = cloth.modifiers.new("cloth", "CLOTH")
s = m.settings
s.quality = 5
s.mass = float(data["vertex_mass"])
s.tension_stiffness = s.compression_stiffness = 15.0
s.shear_stiffness, s.bending_stiffness = 5.0, 0.5
s.air_damping = 1.0
c = m.collision_settings
c.use_self_collision = True
c.distance_min = 0.002
c.self_distance_min = 0.002
m.point_cache.frame_start, m.point_cache.frame_end = 1, frames
t = time.perf_counter()
for f in range(1, frames + 1):
    sc.frame_set(f)
wall = time.perf_counter() - t
ev = cloth.evaluated_get(bpy.context.evaluated_depsgraph_get())
x = np.array([ev.matrix_world @ v.co for v in ev.data.vertices])
np.save(out, x)
print(json.dumps({"wall_s": wall}))
"""


def welded(result, frame):
    """(positions, faces) of ``frame`` on the welded garment (merged seam vertices are one)."""
    x = np.zeros((int(result.weld.max()) + 1, 3))
    x[result.weld] = result.frames[frame]
    return x, result.weld[np.asarray(result.mesh.faces)]


def checks(x, faces, body_x, body_faces):
    """(deepest penetration into the body [mm], edge–triangle crossings) of a garment at ``x``."""
    collider = BodyCollider(body_x[None], body_faces, margin=0.03)
    dist, tri, _, _ = collider.nearest(x, body_x, 0, cache=False)
    inside = dist[(tri >= 0)]
    return 1e3 * float(max(0.0, -inside.min())) if len(inside) else 0.0, len(edge_crossings(x, faces))


def garment_mass(result) -> float:
    """Total mass [kg] of the garment: the rest area of every panel's triangles times its density."""
    params = result.report.params
    uv, faces = np.asarray(result.mesh.uv), np.asarray(result.mesh.faces)
    a, b = uv[faces[:, 1]] - uv[faces[:, 0]], uv[faces[:, 2]] - uv[faces[:, 0]]
    area = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    names = [p.name for p in result.pattern.panels]
    panel = np.asarray(result.mesh.vertex_panel)[faces[:, 0]]
    density = np.array([params[names[k]]["density"] for k in panel])
    return float((area * density).sum())


def drape_once(pattern, body, args, name):
    """(wall [s], DrapeResult) of one whole drape at preset ``name``."""
    t = time.perf_counter()
    result = tailor.drape(pattern, body, resolution=args.resolution, frames=args.frames, quality=name)
    return time.perf_counter() - t, result


class BlenderRun:
    """Blender's cloth on the walk from a drape's frame 0, set up once in ``tmp``; each call is one timed round."""

    def __init__(self, python, result, args, tmp: Path):
        x0, self.faces = welded(result, 0)
        np.savez(tmp / "scene.npz", cloth0=x0, cloth_faces=self.faces, body0=result.body_frames[0],
                 body_faces=result.body_faces, vertex_mass=garment_mass(result) / len(x0))
        write_pc2(tmp / "walk.pc2", np.asarray(result.body_frames, np.float32))
        (tmp / "part.py").write_text(BLENDER_PART)
        self.cmd = [python, str(tmp / "part.py"), str(tmp / "scene.npz"), str(tmp / "last.npy"), str(tmp / "walk.pc2"),
                    str(args.frames)]
        self.last = tmp / "last.npy"

    def __call__(self) -> float:
        done = subprocess.run(self.cmd, capture_output=True, text=True, check=True)
        return json.loads(done.stdout.strip().splitlines()[-1])["wall_s"]


def rounds(pattern, body, args, tmp: Path):
    """({preset: (median wall, DrapeResult)}, (median wall, last positions, faces) or None): round by
    round each preset once, then Blender once, so the machine's drift over the run hits both alike."""
    walls, results, blender_walls, blender = {n: [] for n in args.presets}, {}, [], None
    bpy = has_bpy(args.blender_python)
    for _ in range(args.rounds):
        for name in args.presets:
            wall, results[name] = drape_once(pattern, body, args, name)
            walls[name].append(wall)
            print(f"tailor {name}: {wall:.1f} s", file=sys.stderr, flush=True)
        if bpy:
            blender = blender or BlenderRun(args.blender_python, results.get(DEFAULT_QUALITY, next(iter(results.values()))),
                                            args, tmp)
            blender_walls.append(blender())
            print(f"blender: {blender_walls[-1]:.1f} s", file=sys.stderr, flush=True)
    runs = {n: (statistics.median(walls[n]), results[n]) for n in args.presets}
    return runs, (statistics.median(blender_walls), np.load(blender.last), blender.faces) if bpy else None


def has_bpy(python) -> bool:
    return subprocess.run([python, "-c", "import bpy"], capture_output=True).returncode == 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--blender-python", default=sys.executable, help="a Python with bpy (default: this one)")
    p.add_argument("--garment", default="tshirt")
    p.add_argument("--frames", type=int, default=50, help="frames of the walk, frame 0 (dressed) included")
    p.add_argument("--resolution", type=float, default=0.02)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--presets", nargs="+", default=list(QUALITY), choices=list(QUALITY))
    args = p.parse_args()
    body = tailor.read_body("mannequin-walk")
    pattern = tailor.read_pattern(HERE / "panels" / f"{args.garment}.json")
    tailor.drape(pattern, body, resolution=0.08, frames=1)  # compile the kernels before timing
    with tempfile.TemporaryDirectory() as tmp:
        runs, blender = rounds(pattern, body, args, Path(tmp))
    reference = runs.get(DEFAULT_QUALITY, next(iter(runs.values())))[1]
    last_body = reference.body_frames[-1]
    if blender is None:
        print(f"{args.blender_python} has no bpy: Blender's part skipped (pip install bpy in a Python 3.11 venv)")
    print(f"\n{args.garment}, walking mannequin, {args.frames} frames, {args.resolution * 100:g} cm mesh "
          f"({len(welded(reference, 0)[0])} welded vertices)\n")
    print("| run | wall s | Blender ÷ run | penetration mm (last frame) | crossings (last frame) |\n|---|---|---|---|---|")
    for name, (wall, result) in runs.items():
        pen, cross = checks(*welded(result, -1), last_body, result.body_faces)
        ratio = f"{blender[0] / wall:.2f}" if blender else "–"
        print(f"| tailor {name} (whole drape) | {wall:.1f} | {ratio} | {pen:.1f} | {cross} |")
    if blender:
        pen, cross = checks(blender[1], blender[2], last_body, reference.body_faces)
        print(f"| Blender (walk only) | {blender[0]:.1f} | 1.00 | {pen:.1f} | {cross} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
