"""Physical validation: Bottino et al.'s drape experiments and the Cusick drape test.

Bottino et al. (seed ``004_…``, §6) drape a 20 × 20 cm patch of fabric A (cotton-like, 138 g/m²)
and B (wool-like, 291 g/m²) on a sphere of 9 cm diameter, on cubes of 8, 12.8 and 5.5 cm, and
hang it from two corners 15.5 cm apart, and compare shapes by the **mean distance between
corresponding points of two rest states** — here every vertex of one run against the other run's
surface at the same rest (uv) point (:func:`tailor.bench.rest_error`), so grids of 11, 21 and 31
vertices and Triangle meshes of matching size compare. Models: the five-segment Kawabata curves,
their one-segment (linear) version, and our automatic parameters from the three numbers (Carignan
Eq. 21–26 with the fabric's density, hanging stretch and bending).

The **Cusick drape test** (BS 5058 / ISO 9073-9): a 30 cm circular specimen clamped on an 18 cm
disk drapes under gravity; its drape coefficient is DC = (shadow area − disk area) / (specimen
area − disk area) from the settled shape seen from above, with the number of folds (nodes).

:func:`validate` runs everything (``quick``: fewer, coarser cases) and writes a markdown report
with tables and PNG pictures.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .bench import rest_error
from .lab import drape_test
from .errors import SimulationUnstable
from .fabric import PRESETS, Fabric, preset
from .mesh import discretise
from .model import build_model
from .scenes import Setup, grid, sphere

__all__ = ["bottino_fabric", "patch_scene", "validate", "BOTTINO_SCENES"]

log = logging.getLogger(__name__)

PATCH = 0.20  # m
STEP = 0.005  # s: the implicit step of every validation scene (sphere 21 vs 31, fabric A kes5: 2.8 mm)
BOTTINO_SCENES = {"sphere": 0.09, "cube80": 0.08, "cube128": 0.128, "cube55": 0.055, "hang": 0.155}
"""Bottino's scenes: sphere diameter, cube sides, distance of the two hanging corners [m]."""
MODELS = ("kes5", "kes1", "auto")
"""Fabric models of Bottino's scenes (:func:`bottino_fabric`)."""


def bottino_fabric(which: str, model: str) -> Fabric:
    """Fabric A or B as ``kes5`` (five-segment Kawabata), ``kes1`` (one segment) or ``auto`` (three numbers)."""
    base = preset({"A": "bottino_a", "B": "bottino_b"}[which])
    if model == "kes5":
        return base
    if model == "kes1":
        return base.with_values(name=f"{base.name} 1-segment", kawabata=base.kawabata.linearised())
    if model == "auto":
        return base.with_values(name=f"{base.name} automatic", kawabata=None)
    raise ValueError(f"model must be kes5, kes1 or auto, got {model!r}")


def _patch_mesh(n: int, mesh_kind: str):
    if mesh_kind == "grid":
        return grid(PATCH, PATCH, n)
    from .pattern import Pattern
    from .scenes import rectangle

    return discretise(Pattern("patch", (rectangle(PATCH, PATCH, "patch"),)), PATCH / (n - 1))


def patch_scene(scene: str, fabric: Fabric, n: int = 21, *, mesh: str = "grid", duration: float = 2.0) -> Setup:
    """One of :data:`BOTTINO_SCENES` with the 20 cm patch at ``n`` vertices a side (grid or Triangle mesh)."""
    m = _patch_mesh(n, mesh)
    uv = m.uv - 0.5 * PATCH
    import trimesh

    if scene == "hang":
        model = build_model(m, fabric)
        top = np.flatnonzero(np.isclose(m.uv[:, 1], PATCH))
        corners = top[[np.argmin(m.uv[top, 0]), np.argmax(m.uv[top, 0])]]
        model = model.with_pins(corners)
        x0 = np.c_[uv[:, 0], np.zeros(m.vertex_count), uv[:, 1] + 0.3]
        s = Setup(f"hang{n}", m, model, x0, None, duration, thickness=fabric.thickness, friction=fabric.friction)
        s.pins = corners
        return s
    model = build_model(m, fabric)
    if scene == "sphere":
        r = 0.5 * BOTTINO_SCENES["sphere"]
        body, top = sphere(r, subdivisions=4), r
    else:
        side = BOTTINO_SCENES[scene]
        box = trimesh.creation.box(extents=(side, side, side))
        box = box.subdivide().subdivide()  # the contact query wants triangles smaller than the cloth
        body, top = (np.asarray(box.vertices), np.asarray(box.faces)), 0.5 * side
    x0 = np.c_[uv, np.full(m.vertex_count, top + 0.01)]
    return Setup(f"{scene}{n}", m, model, x0, body, duration, thickness=fabric.thickness, friction=fabric.friction)


def _run_patch(scene: str, fabric: Fabric, n: int, mesh: str = "grid", duration: float = 2.0):
    setup = patch_scene(scene, fabric, n, mesh=mesh, duration=duration)
    hooks = ()
    if scene == "hang":
        # the two corners start 20 cm apart and are brought to 15.5 cm in the first half second
        pins, gap = setup.pins, 0.5 * (PATCH - BOTTINO_SCENES["hang"])
        start = setup.x0[pins].copy()

        def move(model, state, dt):
            s = min(1.0, state.t / 0.5)
            state.x[pins] = start + np.array([[gap, 0, 0], [-gap, 0, 0]]) * s
            state.v[pins] = 0.0

        hooks = (move,)
    from .scenes import run_scene

    t0 = time.perf_counter()
    result = run_scene(setup.model, setup.x0, body=setup.body, duration=setup.duration, fps=25, integrator="implicit",
                       dt=STEP, thickness=setup.thickness, friction=setup.friction, self_collision="off", hooks=hooks)
    return setup.mesh, result.frames[-1], time.perf_counter() - t0


def _shape_distance(a, b) -> float:
    """Bottino's metric [m]: mean distance of ``b``'s points to ``a``'s surface at the same rest points."""
    (mesh_a, xa), (mesh_b, xb) = a, b
    return rest_error(mesh_a.uv, xa, mesh_b.uv, xb)[0]


def _mm(a, b):
    """Bottino's metric between two runs [mm]; NaN if either stopped."""
    return math.nan if a is None or b is None else _shape_distance(a[:2], b[:2]) * 1e3


def _cell(v) -> str:
    """A distance [mm] to one decimal; — for a run that stopped (NaN)."""
    return "—" if math.isnan(v) else f"{v:.1f}"


def _table(title, labels, matrix) -> str:
    head = "| " + title + " | " + " | ".join(labels) + " |\n|---|" + "---|" * len(labels) + "\n"
    return head + "".join("| " + a + " | " + " | ".join("" if v is None else _cell(v) for v in row) + " |\n"
                          for a, row in zip(labels, matrix))


@dataclass(frozen=True)
class _Plan:
    """What one ``tailor validate`` runs."""

    quick: bool
    sizes: tuple
    scenes: tuple
    fabrics: tuple
    models: tuple
    default_models: tuple
    duration: float
    cusick_fabrics: tuple

    @classmethod
    def of(cls, quick: bool, models) -> "_Plan":
        default = ("kes5", "auto") if quick else MODELS
        models = default if models is None else tuple(models)
        for m in models:
            bottino_fabric("A", m)  # an unknown model is an error before anything runs
        return cls(quick, (11, 21) if quick else (11, 21, 31),
                   ("sphere", "hang") if quick else ("sphere", "cube80", "cube128", "cube55", "hang"),
                   ("A",) if quick else ("A", "B"), models, default, 1.2 if quick else 2.0,
                   ("silk", "cotton", "denim") if quick else tuple(PRESETS))

    @property
    def jobs(self) -> list:
        """(scene, fabric, model, n, mesh kind) of every patch run."""
        jobs = [(s, f, mo, n, "grid") for s in self.scenes for f in self.fabrics for mo in self.models for n in self.sizes]
        return jobs + [(s, f, "kes5", n, "triangle") for s in self.scenes[:1] for f in self.fabrics for n in self.sizes]


class _Tally:
    """Runs done of a total, told to ``progress(done, total, text)``."""

    def __init__(self, progress, total: int):
        self.progress, self.total, self.done = progress, total, 0

    def __call__(self, text: str) -> None:
        self.done += 1
        if self.progress:
            self.progress(self.done, self.total, text)


def validate(out, *, quick: bool = False, progress=None, models=None) -> Path:
    """Run the validation scenes and write ``out/validation.md`` and its pictures; returns the report path."""
    from .io.atomic import write_text_atomic

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    plan = _Plan.of(quick, models)
    tally = _Tally(progress, len(plan.jobs) + len(plan.cusick_fabrics))
    t_all = time.perf_counter()
    failed = []
    runs = {}
    for key in plan.jobs:
        scene, fab, model, n, mesh_kind = key
        try:
            runs[key] = _run_patch(scene, bottino_fabric(fab, model), n, mesh_kind, plan.duration)
        except SimulationUnstable as exc:  # one case must not cost the report: it says so instead
            runs[key] = None
            failed.append(f"{scene}, fabric {fab}, {model}, n = {n} ({mesh_kind}): {exc}")
        tally(f"{scene} {fab} {model} n={n} {mesh_kind}")
    models_arg = '' if plan.models == plan.default_models else ' --models ' + ','.join(plan.models)
    lines = ["# Validation: Bottino et al.'s drape experiments and the Cusick drape test\n",
             f"Written by `tailor validate{' --quick' if quick else ''}{models_arg}`. Bottino's metric: the mean distance [mm] "
             "between corresponding points (same rest position on the patch) of two settled shapes. "
             f"Patch 20 × 20 cm, {plan.duration:g} s of settling, implicit Euler at 5 ms.\n"]
    for scene in plan.scenes:
        lines.append(f"\n## {scene}\n")
        for fab in plan.fabrics:
            lines += _scene_section(out, plan, scene, fab, runs)
    lines += _cusick_section(out, plan, failed, tally)
    if failed:
        lines.append("\n## Runs that stopped\n\nEach stopped with `SimulationUnstable` (its table cells read —):\n\n"
                     + "".join(f"- {f}\n" for f in failed))
    lines.append(f"\nTotal wall time {time.perf_counter() - t_all:.0f} s.\n")
    report = out / "validation.md"
    write_text_atomic(report, "".join(lines))
    return report


def _scene_section(out, plan: _Plan, scene: str, fab: str, runs) -> list:
    """Tables of one scene and fabric (resolution against resolution, model against model) and its picture."""
    from .io.render import render_views

    sizes, models, lines = plan.sizes, plan.models, []
    labels = [str(n) for n in sizes]
    for model in models:
        m = [[None if i == j else _mm(runs[(scene, fab, model, a, "grid")], runs[(scene, fab, model, b, "grid")])
              for j, b in enumerate(sizes)] for i, a in enumerate(sizes)]
        lines.append(f"\nFabric {fab}, {model}: grid resolution against resolution (mm)\n\n")
        lines.append(_table("n", labels, m))
    n = sizes[-1]
    m = [[None if i == j else _mm(runs[(scene, fab, a, n, "grid")], runs[(scene, fab, b, n, "grid")])
          for j, b in enumerate(models)] for i, a in enumerate(models)]
    lines.append(f"\nFabric {fab}, n = {n}: model against model (mm)\n\n")
    lines.append(_table("model", list(models), m))
    if scene == plan.scenes[0]:
        tri = [_mm(runs[(scene, fab, "kes5", k, "grid")], runs[(scene, fab, "kes5", k, "triangle")]) for k in sizes]
        lines.append(f"\nFabric {fab}, kes5: grid against Triangle mesh of the same size (mm): "
                     + ", ".join(f"n = {k}: {_cell(v)}" for k, v in zip(sizes, tri)) + "\n")
    if runs[(scene, fab, "kes5", n, "grid")] is None:
        return lines
    mesh, x, _ = runs[(scene, fab, "kes5", n, "grid")]
    meshes = [(x, mesh.faces, (0.8, 0.3, 0.3))]
    if scene != "hang":
        setup = patch_scene(scene, bottino_fabric(fab, "kes5"), 3)
        meshes.insert(0, (setup.body[0], setup.body[1], (0.7, 0.7, 0.75)))
    else:
        sag = np.ptp(x[:, 2]) * 1e3
        lines.append(f"\nFabric {fab}: height of the hanging patch {sag:.1f} mm at n = {n}; by resolution: "
                     + ", ".join(f"{k}: {np.ptp(runs[(scene, fab, 'kes5', k, 'grid')][1][:, 2]) * 1e3:.1f}"
                                 for k in sizes if runs[(scene, fab, 'kes5', k, 'grid')] is not None) + "\n")
    pic = out / f"validation_{scene}_{fab}.png"
    render_views(pic, meshes, size=(6, 3), title=f"{scene}, fabric {fab}, n = {n}")
    lines.append(f"\n![{scene} fabric {fab}]({pic.name})\n")
    return lines


def _cusick_section(out, plan: _Plan, failed: list, tally: _Tally) -> list:
    """The Cusick drape test of every fabric: a table and the shadows' picture."""
    from .io.plots import shadow_plot

    lines = ["\n## Cusick drape test\n\n30 cm specimen clamped on an 18 cm disk, laid down gently (`tailor fabric drape-test`); "
             "DC = (shadow − disk) / (specimen − disk).\n\n| fabric | bending c | DC | nodes | wall s |\n|---|---|---|---|---|\n"]
    results = []
    for name in plan.cusick_fabrics:
        try:
            r = drape_test(preset(name), resolution=0.02 if plan.quick else 0.01, specimens=1 if plan.quick else 3)
        except SimulationUnstable as exc:
            failed.append(f"Cusick, {name}: {exc}")
            lines.append(f"| {name} | {preset(name).bending:g} | unstable | | |\n")
            continue
        finally:
            tally(f"cusick {name}")
        results.append(r)
        lines.append(f"| {name} | {preset(name).bending:g} | {r.drape_coefficient:.3f} | {r.nodes} | {r.wall_s:.1f} |\n")
    pic = out / "validation_cusick.png"
    shadow_plot(pic, results)
    lines.append(f"\n![drape shadows]({pic.name})\n")
    return lines
