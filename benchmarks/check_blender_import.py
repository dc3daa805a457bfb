"""Import tailor's exports into Blender and compare what Blender plays back with the OBJ frames.

    python benchmarks/check_blender_import.py RUN_DIR [--blender-python PY]

Exports RUN_DIR (a folder written by ``tailor drape``) as GLB, PC2 and USD into a temporary
folder, then, in a Python that has ``bpy`` (``pip install bpy``; bpy 5.0 needs Python 3.11),
imports each with Blender's own importer (glTF, OBJ + Mesh Cache modifier, USD), steps the scene
to every frame and prints the largest distance [m] between Blender's evaluated vertices and the
OBJ frame. Blender's scene frame rate is set to the drape's first (glTF stores seconds, and
Blender converts them at the scene's rate, 24 fps by default).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tailor.io.animation import read_run  # noqa: E402
from tailor.io.export import export  # noqa: E402

BLENDER_PART = r"""
import json, sys
import bpy
import numpy as np

folder, name, fps, frames_file = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
frames = np.load(frames_file)

def evaluated(obj, frame):
    bpy.context.scene.frame_set(frame)
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    me = ev.to_mesh()
    x = np.array([(ev.matrix_world @ v.co)[:] for v in me.vertices])
    ev.to_mesh_clear()
    return x

def error(x, k):
    # GLB splits seam vertices: compare each Blender vertex with its nearest OBJ vertex
    d = np.linalg.norm(x[:, None, :] - frames[k][None], axis=2).min(axis=1) if x.shape != frames[k].shape \
        else np.linalg.norm(x - frames[k], axis=1)
    return float(d.max())

def fresh():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps = int(round(fps))

result = {}
fresh()
bpy.ops.import_scene.gltf(filepath=f"{folder}/{name}.glb")
obj = bpy.data.objects[name]
result["glb"] = max(error(evaluated(obj, k), k) for k in range(len(frames)))
fresh()
bpy.ops.wm.obj_import(filepath=f"{folder}/{name}_base.obj", forward_axis="Y", up_axis="Z")
obj = bpy.context.selected_objects[0]
mod = obj.modifiers.new("cache", "MESH_CACHE")
mod.cache_format, mod.filepath, mod.forward_axis, mod.up_axis = "PC2", f"{folder}/{name}.pc2", "POS_Y", "POS_Z"
result["pc2"] = max(error(evaluated(obj, k), k) for k in range(len(frames)))
fresh()
bpy.ops.wm.usd_import(filepath=f"{folder}/{name}.usdc")
obj = [o for o in bpy.context.scene.objects if o.type == "MESH" and "garment" in o.name][0]
result["usd"] = max(error(evaluated(obj, k), k) for k in range(len(frames)))
result["blender"] = bpy.app.version_string
print("RESULT " + json.dumps(result))
"""


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="a folder written by tailor drape")
    parser.add_argument("--blender-python", default=sys.executable, help="a Python with bpy (default: this one)")
    args = parser.parse_args(argv)
    anim = read_run(args.run, with_body=False)
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in ("glb", "pc2", "usd"):
            export(anim, fmt, tmp, with_body=False)
        import numpy as np

        np.save(Path(tmp) / "frames.npy", anim.positions)
        (Path(tmp) / "blender_part.py").write_text(BLENDER_PART)
        done = subprocess.run([args.blender_python, str(Path(tmp) / "blender_part.py"), tmp, anim.name, str(anim.fps),
                               str(Path(tmp) / "frames.npy")], capture_output=True, text=True, timeout=1800)
        lines = [ln for ln in done.stdout.splitlines() if ln.startswith("RESULT ")]
        if done.returncode or not lines:
            sys.exit(f"Blender part failed:\n{done.stderr[-2000:]}")
        result = json.loads(lines[-1][7:])
    print(f"Blender {result.pop('blender')}: {anim.frame_count} frames of {anim.vertex_count} vertices")
    for fmt, err in result.items():
        print(f"  {fmt}: largest distance to the OBJ frames {err:.2e} m")


if __name__ == "__main__":
    main()
