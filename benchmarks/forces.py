"""Force-evaluation and integrator step times at 1k, 10k and 100k vertices.

Run:  python benchmarks/forces.py [--quick]
Everything is measured side by side in one run (this machine is noisy): the compiled kernels
against the numpy reference of the same forces, the implicit step's Jacobian assembly in 3×3
blocks by element colour classes against the CSR scatter it replaced, then one step of every
integrator.
"""

import argparse
import math
import statistics
import time

import numpy as np

from tailor.fabric import preset
from tailor.forces import bending_forces, damping_forces, internal_forces, stretch_forces, total_forces
from tailor.forces.jacobian import SparsePattern, implicit_blocks, jacobian_data
from tailor.integrators import make_integrator
from tailor.io import pattern_from_dict
from tailor.mesh import discretise
from tailor.model import build_model


def square_model(vertices):
    h = math.sqrt(1.88 / vertices)  # Triangle's quality mesh: ≈ 1.88/h² vertices per m²
    doc = {"pattern": {"panels": {"sq": {"vertices": [[0, 0], [100, 0], [100, 100], [0, 100]],
                                         "edges": [{"endpoints": [i, (i + 1) % 4]} for i in range(4)]}}}}
    model = build_model(discretise(pattern_from_dict(doc), h), preset("cotton"))
    rng = np.random.default_rng(0)
    x = np.column_stack([model.rest_uv, np.zeros(model.vertex_count)]) + rng.normal(0, 1e-3, (model.vertex_count, 3))
    return model, model.state(x, rng.normal(0, 0.1, x.shape))


def timed(fn, repeat):
    fn()  # warm (compiles on first use)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e3


def numpy_internal(model, state):
    return stretch_forces(model, state) + damping_forces(model, state) + bending_forces(model, state)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="1k and 10k only, fewer repeats")
    args = ap.parse_args()
    sizes = (1_000, 10_000) if args.quick else (1_000, 10_000, 100_000)
    print("Force evaluation (stretch + strain-rate damping + bending), median ms")
    print(f"{'vertices':>9} {'faces':>8} {'compiled':>9} {'numpy':>9} {'ratio':>6} {'total incl. gravity':>20}")
    models = {}
    for n in sizes:
        model, state = square_model(n)
        models[n] = (model, state)
        rep = 5 if n >= 100_000 else 20
        fast = timed(lambda: internal_forces(model, state), rep)
        slow = timed(lambda: numpy_internal(model, state), max(3, rep // 4))
        total = timed(lambda: total_forces(model, state), rep)
        print(f"{model.vertex_count:>9} {model.face_count:>8} {fast:>9.2f} {slow:>9.2f} {slow / fast:>6.1f} {total:>20.2f}")
    print("\nImplicit-step Jacobians (Δt·C + Δt²·K and K·v), median ms")
    print(f"{'vertices':>9} {'blocks':>9} {'CSR scatter':>12} {'colour classes':>15} {'ratio':>6}")
    for n in sizes:
        model, state = models[n]
        pattern = SparsePattern(model)
        dt = 0.01

        def csr_scatter():  # the assembly before implicit_blocks: CSR data, block gather, CSR product
            kdata, cdata = jacobian_data(model, state, pattern)
            kv = pattern.csr(kdata) @ state.v.reshape(-1)
            return pattern.blocks(dt * cdata + dt * dt * kdata), kv

        rep = 5 if n >= 100_000 else 20
        old = timed(csr_scatter, rep)
        new = timed(lambda: implicit_blocks(model, state, pattern, dt), rep)
        print(f"{model.vertex_count:>9} {len(pattern.block_cols):>9} {old:>12.2f} {new:>15.2f} {old / new:>6.1f}")
    n = 10_000
    model, state = models[n]
    print(f"\nOne integrator step at {model.vertex_count} vertices (Δt = Eq. 24 = {model.time_step:.3g} s; implicit at 0.01 s), median ms")
    for name in ("forward", "symplectic", "verlet", "rk4", "implicit"):
        integ = make_integrator(name)
        dt = 0.01 if name == "implicit" else model.time_step
        s = state.copy()
        iterations = []

        def one_step():
            integ.reset()  # no warm start or history: every timed step is a first step
            iterations.append(integ.step(model, s, dt, total_forces).iterations)

        ms = timed(one_step, 5 if name == "implicit" else 20)
        extra = f"  ({iterations[-1]} CG iterations)" if name == "implicit" else ""
        per_second = ms / dt / 1e3
        print(f"  {name:<11} {ms:8.2f} ms/step   {per_second:8.2f} s of compute per simulated second{extra}")


if __name__ == "__main__":
    main()
