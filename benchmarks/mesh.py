"""Discretisation time of the shipped T-shirt (and any pattern given) at 2, 1 and 0.5 cm.

Run:  python benchmarks/mesh.py [PATTERN ...]
Prints the median of 5 runs per resolution, with vertex and triangle counts.
"""

import statistics
import sys
import time
from pathlib import Path

import tailor

paths = sys.argv[1:] or [Path(__file__).resolve().parents[1] / "panels" / "tshirt.json"]
print(f"{'pattern':<22}{'h [cm]':>8}{'vertices':>10}{'triangles':>11}{'min angle':>11}{'ms (median of 5)':>18}")
for path in paths:
    pattern = tailor.read_pattern(path)
    for h_cm in (2.0, 1.0, 0.5):
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            mesh = tailor.discretise(pattern, h_cm * 1e-2)
            times.append((time.perf_counter() - t0) * 1e3)
        print(f"{pattern.name:<22}{h_cm:>8.1f}{mesh.vertex_count:>10}{mesh.face_count:>11}"
              f"{mesh.min_angle():>10.1f}°{statistics.median(times):>18.1f}")
