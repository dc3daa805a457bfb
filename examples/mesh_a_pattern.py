"""Read a pattern, check it, and triangulate its panels: the first step of every drape.

Run:  python examples/mesh_a_pattern.py [PATTERN]      (writes out/<name>_flat.obj)
"""

import os
import sys
from pathlib import Path

import tailor
from tailor.io.obj import write_obj

here = Path(__file__).resolve().parent
path = Path(sys.argv[1]) if len(sys.argv) > 1 else here.parent / "panels" / "tshirt.json"
quick = os.environ.get("TAILOR_QUICK") == "1"

pattern = tailor.read_pattern(path)  # validated, in metres
print(f"{pattern.name}: {len(pattern.panels)} panels, {pattern.area:.3f} m² of {pattern.fabric.name}")

mesh = tailor.discretise(pattern, resolution=0.03 if quick else 0.015)
print(f"{mesh.vertex_count} vertices, {mesh.face_count} triangles, min angle {mesh.min_angle():.1f}°")
for si, seam in enumerate(pattern.seams):
    n = int((mesh.seam_pair_seam == si).sum())
    print(f"  seam {si}: {seam.a.panel}[{seam.a.edge}] ↔ {seam.b.panel}[{seam.b.edge}]  {n} vertex pairs ({seam.orientation})")

out = Path("out") / f"{pattern.name}_flat.obj"
write_obj(out, mesh.flat_positions(), mesh.faces, uv=mesh.uv, face_group=mesh.face_panel, group_names=mesh.panel_names)
print(f"wrote {out}")
