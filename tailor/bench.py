"""Speed versus accuracy, measured: the sweep behind ``tailor bench`` and the stability map.

For each reference scene (:mod:`tailor.scenes`) the sweep runs integrator × time step ×
resolution (and the implicit solver tolerance of the quality presets), and records wall time,
steps, CG iterations, peak resident memory of the process during the run, whether the run stayed stable, and its error against a
converged reference run (finest mesh, small step, tight tolerance): the mean and max distance
[mm] between final positions at the same **rest (uv) points**, so different resolutions compare.
Time steps are also given as multiples of the model's Eq. 24 step.

The stability map runs a small scene for every cell of a matrix over density, stretch,
bending, resolution, wind and body speed, per integrator at its chosen step; a cell either completes with
finite, bounded frames or stops with :class:`~tailor.errors.SimulationUnstable` — anything else
(a NaN frame, another exception) is a defect and is reported as ``FAILED``.

Nothing here is a unit test: the numbers are measured side by side in one run on one machine.
"""

from __future__ import annotations

import csv
import io
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

from .errors import SimulationUnstable
from .fabric import Fabric
from .forces.wind import Wind
from .model import build_model
from .scenes import SPHERE_FABRIC, Setup, grid, sphere, sphere_drop, two_corner_hang
from .sim import QUALITY

__all__ = ["savings", "Run", "SCENES", "QUICK_SCENES", "GarmentScene", "sweep", "rest_error", "pareto", "write_results", "stability_map", "STABILITY_AXES"]


@dataclass
class Run:
    """One measured run of the sweep."""

    scene: str
    integrator: str
    resolution: int
    dt: float
    eq24_multiple: float
    tolerance: float | None
    label: str = ""
    wall_s: float = math.nan
    steps: int = 0
    cg_iterations: int = 0
    peak_mb: float = math.nan
    stable: bool = True
    error_mean_mm: float = math.nan
    error_max_mm: float = math.nan
    note: str = ""
    final: np.ndarray | None = field(default=None, repr=False)
    uv: np.ndarray | None = field(default=None, repr=False)

    def row(self) -> dict:
        return {k: getattr(self, k) for k in ("scene", "integrator", "resolution", "dt", "eq24_multiple", "tolerance", "label",
                                              "wall_s", "steps", "cg_iterations", "peak_mb", "stable", "error_mean_mm",
                                              "error_max_mm", "note")}


@dataclass(frozen=True)
class BenchScene:
    """A scene family: ``make(n)`` builds it at ``n`` × ``n`` vertices."""

    name: str
    make: object
    resolutions: tuple
    quick_resolutions: tuple
    description: str


@dataclass(frozen=True)
class GarmentScene:
    """A garment on the walking mannequin (``tailor drape``); levels are resolutions in mm."""

    name: str
    pattern: str
    resolutions: tuple
    quick_resolutions: tuple
    description: str
    frames: int = 25
    quick_frames: int = 5

    def run(self, resolution_mm, quality, frames):
        """(final positions, rest uv, panel per vertex, report) of one drape."""
        from .dress import drape
        from .io import read_pattern
        from .io.body_files import read_body

        pattern = read_pattern(Path(__file__).resolve().parents[1] / "panels" / self.pattern)
        result = drape(pattern, read_body("mannequin-walk"), frames=frames, resolution=resolution_mm * 1e-3,
                       quality=quality)
        return result.frames[-1], result.mesh.uv, result.mesh.vertex_panel, result.report


SCENES = {
    "sphere": BenchScene("sphere", sphere_drop, (32, 48, 64), (16, 24),
                         "1 m cotton (150 g/m²) dropped onto a sphere r = 0.25 m, 2 s"),
    "hang": BenchScene("hang", two_corner_hang, (24, 32, 48), (12, 16),
                       "1 m cotton pinned at two corners, falling and swinging, 2 s"),
    "tshirt": GarmentScene("tshirt", "tshirt.json", (40, 30), (50,), "the T-shirt on the walking mannequin, 1 s of walk"),
    "skirt": GarmentScene("skirt", "skirt.json", (40, 30), (50,), "the skirt on the walking mannequin, 1 s of walk"),
}
"""Reference scenes of the sweep by name (grid scenes by vertices per side, garments by mm)."""

QUICK_SCENES = ("sphere", "hang")
"""What ``tailor bench --quick`` runs by default (the garment scenes take minutes each)."""


def rest_error(ref_uv, ref_x, uv, x, ref_panel=None, panel=None):
    """(mean, max) distance [m] between ``x`` and the reference surface at the same rest points ``uv``.

    With ``ref_panel``/``panel`` (panel index per vertex) the rest points are matched panel by
    panel: every panel has its own uv plane.
    """
    ref_panel = np.zeros(len(ref_uv), int) if ref_panel is None else np.asarray(ref_panel)
    panel = np.zeros(len(uv), int) if panel is None else np.asarray(panel)
    d = np.empty(len(uv))
    for p in np.unique(panel):
        r, c = ref_panel == p, panel == p
        at = LinearNDInterpolator(ref_uv[r], ref_x[r])(uv[c])
        missing = ~np.isfinite(at).all(axis=1)
        if missing.any():  # on the boundary, rounding can fall outside the hull
            at[missing] = NearestNDInterpolator(ref_uv[r], ref_x[r])(uv[c][missing])
        d[c] = np.linalg.norm(x[c] - at, axis=1)
    return float(d.mean()), float(d.max())


class PeakMemory:
    """Peak resident memory [MB] of the process while a block of code ran, from the kernel's high-water mark.

    Linux: ``/proc/self/clear_refs`` resets VmHWM to the current resident set on entry; ``mb`` is
    VmHWM on exit (interpreter and libraries included: what running it takes), ``added`` that
    minus the resident set on entry (0 when the run fit in memory the process already held).
    It costs nothing while the code runs (``tracemalloc`` slowed Python-heavy runs about 2×, so the
    bench's wall times were not the real ones) and counts what numba and the libraries allocate
    too. Elsewhere both stay NaN.
    """

    def __init__(self):
        self.mb = self.added = math.nan
        self._start = None

    @staticmethod
    def _status(key):
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])  # kB
        raise OSError(key)

    def __enter__(self):
        try:
            with open("/proc/self/clear_refs", "w") as f:
                f.write("5")
            self._start = self._status("VmRSS")
        except OSError:
            self._start = None
        return self

    def __exit__(self, *exc):
        if self._start is not None:
            try:
                peak = self._status("VmHWM")
            except OSError:
                return False
            self.mb = peak / 1024
            self.added = max(0.0, (peak - self._start) / 1024)
        return False


def _measure(setup: Setup, run: Run) -> Run:
    with PeakMemory() as memory:
        t0 = time.perf_counter()
        try:
            result = setup.run(integrator=run.integrator, dt=run.dt, tolerance=run.tolerance)
        except SimulationUnstable as exc:
            run.stable, run.note = False, str(exc).split(":")[0]
            run.wall_s = time.perf_counter() - t0
        else:
            run.wall_s = time.perf_counter() - t0
            run.steps, run.cg_iterations = result.report["steps"], result.report.get("cg_iterations", 0)
            run.final, run.uv = result.frames[-1], setup.mesh.uv
            if not np.isfinite(run.final).all():  # the guard must make this impossible
                run.stable, run.note = False, "FAILED: non-finite frame"
    run.peak_mb = memory.mb
    return run


def _plan(scene: BenchScene, quick: bool):
    """(integrator, n, dt or None, tolerance, label) of every run of a scene."""
    ns = scene.quick_resolutions if quick else scene.resolutions
    plan = []
    for n in ns:
        for q in QUALITY.values():  # the presets' own step and tolerance
            plan.append(("implicit", n, q.step, q.tolerance, q.name))
    n_mid = ns[len(ns) // 2]
    for dt in ((0.01, 0.04) if quick else (0.005, 0.01, 0.02, 0.04, 0.08)):
        if not any(p[1] == n_mid and p[2] == dt and p[3] == 1e-3 for p in plan):
            plan.append(("implicit", n_mid, dt, 1e-3, ""))
    # explicit integrators at multiples of their Eq. 24 step, on the coarsest mesh (they take ~10⁴ steps)
    for integ in ("symplectic",) if quick else ("symplectic", "verlet", "rk4"):
        for mult in ((1.0, 4.0) if quick else (0.25, 1.0, 2.0, 4.0, 8.0)):
            plan.append((integ, ns[0], -mult, None, ""))
    return plan


def sweep(names=QUICK_SCENES, *, quick: bool = False, progress=None) -> list[Run]:
    """Run the sweep over the named scenes; ``progress(i, total, run)`` after each run."""
    runs: list[Run] = []
    todo = []
    garments = [SCENES[n] for n in names if isinstance(SCENES[n], GarmentScene)]
    for name in names:
        scene = SCENES[name]
        if isinstance(scene, GarmentScene):
            continue
        ns = scene.quick_resolutions if quick else scene.resolutions
        ref_n = ns[-1] * 2 if not quick else ns[-1] + 8
        todo.append((scene, ("implicit", ref_n, 0.005, 1e-6, "reference")))
        todo += [(scene, p) for p in _plan(scene, quick)]
    total = len(todo) + sum(1 + len(g.quick_resolutions if quick else g.resolutions) * len(QUALITY) for g in garments)
    setups = {}
    refs = {}
    for i, (scene, (integ, n, dt, tol, label)) in enumerate(todo):
        key = (scene.name, n)
        if key not in setups:
            setups[key] = scene.make(n)
        setup = setups[key]
        eq24 = setup.model.time_step
        step = -dt * eq24 if dt < 0 else dt
        run = _measure(setup, Run(scene.name, integ, n, step, step / eq24, tol, label))
        if label == "reference":
            refs[scene.name] = run
        ref = refs.get(scene.name)
        if run.final is not None and ref is not None and ref.final is not None:
            mean, worst = rest_error(ref.uv, ref.final, run.uv, run.final)
            run.error_mean_mm, run.error_max_mm = 1e3 * mean, 1e3 * worst
        runs.append(run)
        if progress is not None:
            progress(i + 1, total, run)
    for scene in garments:
        runs += _garment_sweep(scene, quick, progress, len(runs), total)
    return runs


def _garment_sweep(scene: GarmentScene, quick: bool, progress, start: int, total: int) -> list[Run]:
    levels = scene.quick_resolutions if quick else scene.resolutions
    frames = scene.quick_frames if quick else scene.frames
    ref_level = levels[-1] - 10
    plan = [(ref_level, "final")] + [(lv, q) for lv in levels for q in QUALITY]
    runs, ref = [], None
    for k, (level, q) in enumerate(plan):
        preset_q = QUALITY[q]
        run = Run(scene.name, "implicit", level, preset_q.step, math.nan, preset_q.tolerance,
                  "reference" if k == 0 else q)
        with PeakMemory() as memory:
            t0 = time.perf_counter()
            try:
                x, uv, panel, report = scene.run(level, q, frames)
            except SimulationUnstable as exc:
                run.stable, run.note = False, str(exc).split(":")[0]
            else:
                run.final, run.uv = x, uv
                run.steps, run.cg_iterations = report.steps, report.cg_iterations
                run.eq24_multiple = preset_q.step / report.time_step_eq24_s
                if k == 0:
                    ref = (uv, x, panel)
                else:
                    mean, worst = rest_error(ref[0], ref[1], uv, x, ref[2], panel)
                    run.error_mean_mm, run.error_max_mm = 1e3 * mean, 1e3 * worst
            run.wall_s = time.perf_counter() - t0
        run.peak_mb = memory.mb
        runs.append(run)
        if progress is not None:
            progress(start + k + 1, total, run)
    return runs


def savings(*, quick: bool = False, progress=None) -> list[tuple[str, str, float, str]]:
    """What skipping unneeded models saves on the sphere scene: rows (what, variant, wall s, detail).

    * bending: a fabric with c = 0 builds no hinges at all, against the same fabric with a
      negligible c (hinges computed, forces ~0);
    * self-collision: ``off`` (nothing can meet: one sheet over a ball), ``auto`` (only regions
      that can touch are checked) and ``on`` (every vertex every step).
    """
    n = 24 if quick else 48
    rows = []
    cases = [("bending", "c = 0 (skipped)", dict(bending=0.0), "off"), ("bending", "c = 1e-9 (computed)", dict(bending=1e-9), "off"),
             ("self-collision", "off", {}, "off"), ("self-collision", "auto", {}, "auto"), ("self-collision", "on", {}, "on")]
    for k, (what, variant, change, selfc) in enumerate(cases):
        fabric = Fabric(**{**{f: getattr(SPHERE_FABRIC, f) for f in ("name", "density", "stretch_warp", "stretch_weft",
                                                                       "bending", "friction", "thickness")}, **change})
        setup = sphere_drop(n, fabric=fabric)
        t0 = time.perf_counter()
        detail = (f"{setup.model.vertex_count} vertices, bending pass "
                  f"{'run over ' + str(len(setup.model.hinge_vertices)) + ' hinges' if setup.model.has_bending else 'skipped'}")
        try:
            result = setup.run(dt=QUALITY["normal"].step, tolerance=QUALITY["normal"].tolerance, self_collision=selfc)
        except SimulationUnstable as exc:  # recorded like a sweep's run: one row must not cost the bench
            detail += f"; stopped: {exc}"
            outcome = "unstable"
        else:
            if selfc != "off":
                sc = result.report["self_collision"]
                detail += (f", self-collision active in {sc['active_steps']} of {sc['steps']} steps, "
                           f"at most {sc['max_active_vertices']} vertices checked, {sc['query_s']:.2f} s in queries")
            outcome = "ok"
        rows.append((what, variant, time.perf_counter() - t0, detail))
        if progress is not None:
            progress(k + 1, len(cases), (what, variant, 0.0, outcome))
    return rows


def pareto(runs):
    """The runs no other run beats in both wall time and mean error (stable runs with an error)."""
    ok = [r for r in runs if r.stable and math.isfinite(r.error_mean_mm) and r.label != "reference"]
    front = [r for r in ok if not any((o.wall_s <= r.wall_s and o.error_mean_mm < r.error_mean_mm) or
                                      (o.wall_s < r.wall_s and o.error_mean_mm <= r.error_mean_mm) for o in ok)]
    return sorted(front, key=lambda r: r.wall_s)


def _table(runs) -> str:
    head = "| scene | integrator | n or mm | Δt [s] | × Eq. 24 | tol | preset | wall [s] | steps | CG its | peak RSS MB | stable | mean err [mm] | max err [mm] |"
    lines = [head, "|" + "---|" * 14]
    for r in runs:
        lines.append(
            f"| {r.scene} | {r.integrator} | {r.resolution} | {r.dt:.3g} | {r.eq24_multiple:.3g} | "
            f"{'' if r.tolerance is None else f'{r.tolerance:.0e}'} | {r.label} | {r.wall_s:.2f} | {r.steps} | {r.cg_iterations} | "
            f"{'—' if math.isnan(r.peak_mb) else f'{r.peak_mb:.0f}'} | {'yes' if r.stable else 'no: ' + r.note} | {r.error_mean_mm:.2f} | {r.error_max_mm:.2f} |")
    return "\n".join(lines)


def write_results(runs, out: Path, saved=()) -> list[Path]:
    """``results.csv``, ``results.md`` and one ``pareto_<scene>.png`` per scene in ``out``; the paths."""
    from .io.atomic import write_text_atomic as atomic_write_text
    from .io.plots import pareto_plot

    out.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(runs[0].row()))
    w.writeheader()
    for r in runs:
        w.writerow(r.row())
    paths = [out / "results.csv", out / "results.md"]
    atomic_write_text(paths[0], buf.getvalue())
    md = ["# tailor bench", "", f"{time.strftime('%Y-%m-%d %H:%M')}, one run, side by side on this machine.", ""]
    for name in dict.fromkeys(r.scene for r in runs):
        mine = [r for r in runs if r.scene == name]
        md += [f"## {name}: {SCENES[name].description}", "", _table(mine), "", "Pareto frontier (time vs mean error):", ""]
        md += [f"- {r.integrator} n={r.resolution} Δt={r.dt:.3g} s tol={r.tolerance} {r.label}: {r.wall_s:.2f} s, "
               f"{r.error_mean_mm:.2f} mm" for r in pareto(mine)]
        md.append("")
        png = out / f"pareto_{name}.png"
        pareto_plot(mine, pareto(mine), png, title=f"{name}: {SCENES[name].description}")
        paths.append(png)
    if saved:
        md += ["## Modelling only what the scene needs (sphere scene, normal preset)", "",
               "| model | variant | wall [s] | detail |", "|---|---|---|---|"]
        md += [f"| {w} | {v} | {t:.2f} | {d} |" for w, v, t, d in saved]
        md.append("")
    atomic_write_text(paths[1], "\n".join(md) + "\n")
    return paths


# ---------------------------------------------------------------- stability at the extremes

STABILITY_BASE = {"density_g_m2": 150.0, "stretch_pct": 1.0, "bending": 8.0, "resolution_cm": 4.0, "wind_m_s": 0.0,
                  "body_speed_m_s": 0.0}
STABILITY_AXES = {
    "density_g_m2": (5.0, 50.0, 1000.0, 10000.0),
    "stretch_pct": (0.1, 1.0, 10.0, 50.0),
    "bending": (0.0, 1.0, 60.0, 1000.0),
    "resolution_cm": (0.5, 2.0, 5.0, 10.0),
    "wind_m_s": (0.0, 5.0, 15.0, 30.0),
    "body_speed_m_s": (0.0, 1.4, 2.8, 4.2),
}
"""One-factor-at-a-time axes around :data:`STABILITY_BASE`. Body speed runs to 3× walking (1.4 m/s)."""

STABILITY_STEPS = {"implicit": QUALITY["normal"].step, "symplectic": None, "rk4": None}
"""Each integrator at its chosen step (None: the model's Eq. 24 step)."""


def _stability_cell(integrator, params, *, size, duration):
    fabric = Fabric("cell", params["density_g_m2"] * 1e-3, params["stretch_pct"] * 1e-2, params["stretch_pct"] * 1e-2,
                    params["bending"], 0.4, 0.001)
    n = max(3, int(round(size / (params["resolution_cm"] * 1e-2))) + 1)
    mesh = grid(size, size, n)
    wind = params["wind_m_s"]
    model = build_model(mesh, fabric, pinned=[n * (n - 1), n * n - 1], air_density=1.2 if wind else 0.0)
    x0 = np.c_[mesh.uv - 0.5 * size, np.full(mesh.vertex_count, 1.0)]
    # a body moving at speed u through the hanging cloth, seen from the body (Galilean: gravity and
    # the cloth's forces are the same in that frame; the cell has no air unless it has wind): a ball
    # in the cloth's way, and cloth and pins coming at it with −u
    speed = params["body_speed_m_s"]
    body = sphere(0.12, center=(-0.2 - 0.25 * size, 0.0, 1.0 - 0.4 * size), subdivisions=3) if speed else None
    v0 = np.tile([-speed, 0.0, 0.0], (mesh.vertex_count, 1)) if speed else None
    setup = Setup("cell", mesh, model, x0, body, duration)
    air = Wind(speed=wind, direction=(1.0, 0.0, 0.0), turbulence=0.3) if wind else None
    t0 = time.perf_counter()
    try:
        result = setup.run(integrator=integrator, dt=STABILITY_STEPS.get(integrator), wind=air, v0=v0)
    except SimulationUnstable as exc:
        return "unstable", time.perf_counter() - t0, str(exc)
    frames = np.asarray(result.frames)
    if not np.isfinite(frames).all():
        return "FAILED", time.perf_counter() - t0, "a non-finite frame left the simulator"
    return "ok", time.perf_counter() - t0, f"{len(frames)} frames, n={n}, {model.vertex_count} vertices"


def stability_map(*, integrators=("implicit", "symplectic"), axes=None, size: float = 0.5, duration: float = 0.4,
                  progress=None):
    """Rows (integrator, axis, value, outcome, wall s, detail) over one-factor-at-a-time extremes."""
    axes = STABILITY_AXES if axes is None else axes
    cells = [(i, a, v) for i in integrators for a, vals in axes.items() for v in vals]
    rows = []
    for k, (integ, axis, value) in enumerate(cells):
        params = dict(STABILITY_BASE, **{axis: value})
        # explicit integrators at 0.5 cm take ~10⁵ steps: they run that cell on a smaller cloth
        outcome, wall, detail = _stability_cell(integ, params, size=size, duration=duration)
        rows.append((integ, axis, value, outcome, wall, detail))
        if progress is not None:
            progress(k + 1, len(cells), rows[-1])
    return rows


def write_stability(rows, out: Path) -> list[Path]:
    """``stability.md`` and ``stability.png`` in ``out``; the paths."""
    from .io.atomic import write_text_atomic as atomic_write_text
    from .io.plots import stability_plot

    out.mkdir(parents=True, exist_ok=True)
    lines = ["# Stability at the extremes", "", f"Base cell: {STABILITY_BASE}; one factor varied at a time.", "",
             "| integrator | axis | value | outcome | wall [s] | detail |", "|---|---|---|---|---|---|"]
    lines += [f"| {i} | {a} | {v:g} | {o} | {w:.2f} | {d} |" for i, a, v, o, w, d in rows]
    paths = [out / "stability.md", out / "stability.png"]
    atomic_write_text(paths[0], "\n".join(lines) + "\n")
    stability_plot(rows, paths[1])
    return paths


def stability_text(rows) -> str:
    """The map as text: one line per integrator and axis, one symbol per value (. ok, U unstable, F failed)."""
    out = []
    for integ in dict.fromkeys(r[0] for r in rows):
        for axis in dict.fromkeys(r[1] for r in rows if r[0] == integ):
            cells = [r for r in rows if r[0] == integ and r[1] == axis]
            marks = " ".join(f"{v:g}:{ {'ok': '.', 'unstable': 'U'}.get(o, 'F') }" for _, _, v, o, _, _ in cells)
            out.append(f"{integ:<11} {axis:<14} {marks}")
    return "\n".join(out)
