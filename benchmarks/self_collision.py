"""Per-step cost of self-collision at 1k, 10k and 50k vertices, ``on`` against ``auto``.

Run:  python benchmarks/self_collision.py [--quick]
A square sheet folded in two (the halves 5 mm apart) is the worst case for ``auto`` (every patch
near another); the same sheet lying flat is the best case. For each, one FCL query (patch boxes,
hierarchy rebuild, vertex spheres) and one narrow phase + response are timed side by side.
"""

import argparse
import math
import time

import numpy as np

from tailor.collide import SelfCollider
from tailor.scenes import cloth_model, rectangle


def sheet(vertices):
    h = math.sqrt(1.88 / vertices)  # Triangle's quality mesh: ≈ 1.88/h² vertices per m²
    mesh, model = cloth_model([rectangle(1.0, 1.0, "sheet")], "cotton", h)
    flat = np.column_stack([mesh.uv - 0.5, np.full(model.vertex_count, 0.5)])
    folded = flat.copy()
    right = folded[:, 0] > 0.0
    folded[right, 0] = -folded[right, 0]
    folded[right, 2] += 0.005
    return model, flat, folded


def measure(model, x, mode):
    collider = SelfCollider(model.faces, model.face_panel, x, thickness=0.003, mode=mode)
    state = model.state(x.copy(), np.zeros_like(x))
    state.v[:, 2] = np.where(x[:, 0] < 0, 0.2, -0.2)
    inv_mass = 1.0 / np.asarray(model.vertex_mass)
    collider.respond(inv_mass, model.state(x.copy()), 0.01)  # warm the compiled kernels
    collider = SelfCollider(model.faces, model.face_panel, x, thickness=0.003, mode=mode)
    t0 = time.perf_counter()
    collider.respond(inv_mass, state, 0.01)  # queries (first step), then narrow phase + response
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    contacts = collider.respond(inv_mass, state, 0.01)  # a cached step: narrow phase + response only
    cached = time.perf_counter() - t0
    return first, cached, collider.stats["query_s"], collider.candidate_pairs, contacts


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1k and 10k only")
    args = ap.parse_args()
    sizes = (1_000, 10_000) if args.quick else (1_000, 10_000, 50_000)
    print(f"{'vertices':>9} {'shape':>7} {'mode':>5} {'query ms':>9} {'step ms':>8} {'cached ms':>10} {'pairs':>8} {'contacts':>9}")
    for n in sizes:
        model, flat, folded = sheet(n)
        for shape, x in (("flat", flat), ("folded", folded)):
            for mode in ("on", "auto"):
                first, cached, query, pairs, contacts = measure(model, x, mode)
                print(f"{model.vertex_count:>9} {shape:>7} {mode:>5} {query * 1e3:>9.1f} {first * 1e3:>8.1f} "
                      f"{cached * 1e3:>10.2f} {pairs:>8} {contacts:>9}", flush=True)


if __name__ == "__main__":
    main()
