"""The fabric laboratory: the standard fabric tests, simulated, and calibration from them.

A fabric technologist describes cloth by the tests a lab runs on it; tailor runs the same tests on
its own cloth model so that the two can be compared and matched:

* **Cusick drape test** (BS 5058, ISO 9073-9; Cusick 1968): a 30 cm circular specimen clamped
  between 18 cm disks drapes under gravity. The drape coefficient DC = (shadow − disk) /
  (specimen − disk) is measured from the settled shape seen from above, and its folds (nodes) are
  counted around the shadow's outline. :func:`drape_test`.
* **Cantilever test** (ASTM D1388, BS 3356; Peirce 1930): a 2.5 cm strip slides over the edge of
  a platform; its overhang l and the angle θ of the chord from the edge to its tip give the
  bending length C = l·(cos ½θ / (8 tan θ))^⅓ (Peirce's relation, exact enough for θ < 60°).
  tailor's bending number is C³ in cm (Carignan Eq. 25 with ℓ = 1 cm, :mod:`tailor.params`), so a
  measured bending length converts directly, and the simulated test checks the model keeps it.
  :func:`cantilever_test`.
* **Calibration**: the fabric numbers that reproduce a measurement (:func:`calibrate_bending`
  from a drape coefficient, :func:`fabric_from_cantilever`, :func:`fabric_from_kes`).

The specimen is meshed with a ring of vertices exactly on the disk's edge, so the clamp is a
circle and not the jagged set of vertices nearest it. The mesh picks which folds form (three seeds
give one answer), so one specimen's DC moves by up to 0.03 between resolutions; the test averages
three specimens of different triangulations, as the standard averages specimens (docs/fabrics.md).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .fabric import Fabric
from .forces import internal_forces
from .mesh import GarmentMesh, disk_mesh
from .model import build_model
from .units import CM, GRAVITY

__all__ = ["SPECIMEN_RADIUS", "DISK_RADIUS", "DRAPE_RESOLUTION", "DRAPE_RANGES", "DrapeTest", "drape_test", "specimen_mesh",
           "drape_coefficient", "count_nodes", "SPECIMEN_SCALES", "CantileverTest", "cantilever_test", "peirce_bending_length",
           "nominal_bending_length", "fabric_from_cantilever", "calibrate_bending", "fabric_from_kes"]

SPECIMEN_RADIUS, DISK_RADIUS = 0.15, 0.09
"""The Cusick specimen's and the supporting disks' radii [m] (BS 5058: 30 cm on 18 cm)."""

DRAPE_RESOLUTION = 0.01
"""Element size [m] of the drape test by default: three specimens averaged give DC within 0.02 of a
0.75 cm mesh (docs/fabrics.md)."""

LAY_S, SETTLE_S = 2.0, 1.5
"""Simulated seconds over which gravity is raised from zero (the specimen laid down gently), then
held while it settles."""


def specimen_mesh(resolution: float = DRAPE_RESOLUTION, *, radius: float = SPECIMEN_RADIUS,
                  disk: float = DISK_RADIUS) -> tuple[GarmentMesh, np.ndarray, np.ndarray]:
    """(mesh, clamped vertex ids, rim vertex ids in order) of a circular specimen [m].

    Triangle meshes the disk with a ring of vertices on the clamp's edge (radius ``disk``) and the
    rim; everything within the ring is clamped. Warp along x.
    """
    uv, faces, (rim, ring) = disk_mesh((radius, disk), resolution)
    n, f, no = len(uv), len(faces), len(rim)
    mesh = GarmentMesh(uv=uv, faces=faces, vertex_panel=np.zeros(n, np.intp), face_panel=np.zeros(f, np.intp),
                       face_grain=np.tile([1.0, 0.0], (f, 1)), seam_pairs=np.zeros((0, 2), np.intp),
                       seam_pair_seam=np.zeros(0, np.intp), edge_vertices={(0, None, 0): np.r_[np.arange(no), 0]},
                       panel_names=("specimen",), resolution=resolution, boundary_count=no + len(ring))
    clamp = np.flatnonzero(np.hypot(uv[:, 0], uv[:, 1]) <= disk * (1.0 + 1e-9))
    return mesh, clamp, rim


def drape_coefficient(x, faces, *, specimen_radius: float = SPECIMEN_RADIUS, disk_radius: float = DISK_RADIUS):
    """(DC, shadow polygon): the union of the triangles seen from above against the annulus area."""
    from shapely.geometry import Polygon
    from shapely.ops import unary_union

    tri = np.asarray(x)[np.asarray(faces)][:, :, :2]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    keep = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) > 1e-14  # edge-on triangles cast no shadow
    shadow = unary_union([Polygon(t) for t in tri[keep]])
    disk = math.pi * disk_radius**2
    return (shadow.area - disk) / (math.pi * specimen_radius**2 - disk), shadow


def count_nodes(x, boundary, *, prominence: float = 0.005) -> int:
    """Folds of a draped specimen: peaks of the outline's radius around the centre.

    A peak counts when it stands ``prominence`` [m] above the deeper of the two troughs that
    separate it from higher peaks on either side (topographic prominence) — the folds an operator
    counts on the shadow, however wide they are. The outline is periodic, so it is read three
    times over and the middle turn counted.
    """
    from scipy.signal import find_peaks

    p = np.asarray(x)[np.asarray(boundary)]
    order = np.argsort(np.arctan2(p[:, 1], p[:, 0]))
    r = np.hypot(p[order, 0], p[order, 1])
    n = len(r)
    k = max(1, n // 60)  # light circular smoothing
    r = np.convolve(np.r_[r[-k:], r, r[:k]], np.ones(2 * k + 1) / (2 * k + 1), mode="same")[k:-k]
    peaks, _ = find_peaks(np.tile(r, 3), prominence=prominence)
    return int(np.count_nonzero((peaks >= n) & (peaks < 2 * n)))


DRAPE_RANGES = {
    # preset: (DC low, DC high, nodes low, nodes high) of its fabric class (docs/fabrics.md says where from)
    "chiffon": (0.15, 0.35, 7, 12), "organza": (0.55, 0.85, 4, 7), "silk": (0.20, 0.45, 7, 11),
    "satin": (0.25, 0.50, 6, 10), "crepe": (0.20, 0.45, 7, 11), "poplin": (0.50, 0.75, 4, 7),
    "cotton": (0.45, 0.70, 5, 8), "linen": (0.55, 0.80, 4, 7), "jersey": (0.20, 0.45, 6, 10),
    "rib_knit": (0.25, 0.50, 6, 9), "twill": (0.65, 0.88, 3, 6), "wool": (0.45, 0.75, 4, 7),
    "fleece": (0.45, 0.75, 4, 7), "denim_10oz": (0.70, 0.92, 3, 6), "canvas": (0.85, 0.97, 3, 5),
    "denim": (0.80, 0.95, 3, 5), "denim_14oz": (0.80, 0.95, 3, 5), "melton": (0.70, 0.92, 3, 6),
    "leather": (0.60, 0.90, 3, 6),
}
"""Published Cusick drape coefficients and node counts of each preset's fabric class (30 cm on 18 cm)."""


SPECIMEN_SCALES = (1.0, 1.03, 1.06)
"""Element-size factors of the specimens a drape test averages. Like the standard's several
specimens cut from one fabric, each is a different triangulation; the mesh picks which folds form,
so one specimen's DC moves by up to 0.03 between resolutions and three averaged agree within 0.02
(docs/fabrics.md)."""


@dataclass
class DrapeTest:
    """A settled Cusick test: the specimens' mean drape coefficient and median nodes, and the first
    specimen's shadow outline and positions [m] (for pictures)."""

    fabric: str
    drape_coefficient: float
    nodes: int
    shadow: object = field(repr=False)
    x: np.ndarray = field(repr=False)
    faces: np.ndarray = field(repr=False)
    resolution: float = DRAPE_RESOLUTION
    wall_s: float = 0.0
    specimens: tuple = ()
    """(DC, nodes) of each specimen."""

    def as_dict(self) -> dict:
        """The numbers a lab sheet gives (for ``--json``)."""
        return {"fabric": self.fabric, "drape_coefficient": round(self.drape_coefficient, 4), "nodes": self.nodes,
                "specimens": [{"drape_coefficient": round(dc, 4), "nodes": n} for dc, n in self.specimens],
                "resolution_cm": self.resolution / CM, "specimen_cm": 2 * SPECIMEN_RADIUS / CM,
                "disk_cm": 2 * DISK_RADIUS / CM, "wall_s": round(self.wall_s, 2)}


@dataclass(frozen=True)
class _GentleLoad:
    """The forces with gravity raised linearly from zero over ``ramp`` s (quasi-static loading)."""

    ramp: float

    def __call__(self, model, state):
        out = internal_forces(model, state)
        out += min(1.0, state.t / self.ramp) * model.vertex_mass[:, None] * model.gravity[None, :]
        return out


def drape_test(fabric: Fabric, *, resolution: float = DRAPE_RESOLUTION, specimens: int = len(SPECIMEN_SCALES),
               lay: float = LAY_S, settle: float = SETTLE_S, compression: float = 1.0, seed: int = 0) -> DrapeTest:
    """Drape ``specimens`` 30 cm specimens clamped on the 18 cm disk; their mean DC and median nodes.

    Each specimen is meshed at ``resolution`` times one of :data:`SPECIMEN_SCALES` (a different
    triangulation, as the standard tests several specimens of one fabric), starts flat with a
    0.1 mm random ripple outside the disk (it dies away while gravity is small: the folds are the
    mesh's, whatever the seed), and is draped by :func:`_drape_specimen`.
    """
    if not 1 <= specimens <= len(SPECIMEN_SCALES):
        raise ValueError(f"specimens must be 1 to {len(SPECIMEN_SCALES)}, got {specimens}")
    t0 = time.perf_counter()
    runs = [_drape_specimen(fabric, resolution * k, lay, settle, compression, seed) for k in SPECIMEN_SCALES[:specimens]]
    dc = float(np.mean([r[0] for r in runs]))
    nodes = int(np.median([r[1] for r in runs]))
    _, _, shadow, x, faces = runs[0]
    return DrapeTest(fabric.name, dc, nodes, shadow, x, faces, resolution, time.perf_counter() - t0,
                     tuple((float(r[0]), int(r[1])) for r in runs))


def _drape_specimen(fabric: Fabric, resolution: float, lay: float, settle: float, compression: float, seed: int):
    """(DC, nodes, shadow, x, faces) of one specimen laid down gently.

    Gravity rises from zero over ``lay`` s, as when an operator lays the specimen down, and is held
    ``settle`` s more. Dropped at full gravity instead, the falling ring buckles into more,
    shallower folds than the laid-down one and keeps them: the energy differences between fold
    counts are small and the fall picks its fastest growing mode, not the one the fabric settles
    into at rest (docs/fabrics.md).
    """
    from .scenes import run_scene

    mesh, clamp, rim = specimen_mesh(resolution)
    model = build_model(mesh, fabric, pinned=clamp, compression=compression)
    uv = mesh.uv
    x0 = np.c_[uv, np.full(mesh.vertex_count, 0.5)]
    free = np.hypot(uv[:, 0], uv[:, 1]) > DISK_RADIUS * (1.0 + 1e-9)
    x0[:, 2] += 1e-4 * np.random.default_rng(seed).standard_normal(mesh.vertex_count) * free
    result = run_scene(model, x0, duration=lay + settle, fps=25, integrator="implicit", dt=0.005, self_collision="off",
                       forces=_GentleLoad(lay))
    x = result.frames[-1]
    dc, shadow = drape_coefficient(x, mesh.faces)
    return dc, count_nodes(x, rim), shadow, x, mesh.faces


STRIP_WIDTH = 2.5 * CM
"""The cantilever strip's width [m] (ASTM D1388)."""


def peirce_bending_length(overhang: float, angle: float) -> float:
    """Bending length C = l·(cos ½θ / (8 tan θ))^⅓ of a strip overhanging ``overhang`` whose tip
    chord falls ``angle`` [rad] below the horizontal (Peirce 1930; ASTM D1388 eq. 1)."""
    if not 0.0 < angle < 0.5 * math.pi:
        raise ValueError(f"the cantilever's tip angle must be between 0 and 90°, got {math.degrees(angle):.1f}°")
    return overhang * (math.cos(0.5 * angle) / (8.0 * math.tan(angle))) ** (1.0 / 3.0)


def nominal_bending_length(fabric: Fabric) -> float:
    """The bending length [m] the fabric's bending number stands for: C = c^⅓ cm (:mod:`tailor.params`)."""
    return fabric.bending ** (1.0 / 3.0) * CM


@dataclass
class CantileverTest:
    """A simulated cantilever: overhang l, tip chord angle θ, and the bending length C they give [m]."""

    fabric: str
    direction: str
    overhang: float
    angle: float
    bending_length: float
    nominal: float
    wall_s: float = 0.0

    def as_dict(self) -> dict:
        """The numbers a lab sheet gives (for ``--json``), in cm and degrees."""
        return {"fabric": self.fabric, "direction": self.direction, "bending_length_cm": round(self.bending_length / CM, 3),
                "nominal_cm": round(self.nominal / CM, 3), "overhang_cm": round(self.overhang / CM, 3),
                "tip_angle_deg": round(math.degrees(self.angle), 2), "wall_s": round(self.wall_s, 2)}


def cantilever_test(fabric: Fabric, *, direction: str = "warp", overhang: float | None = None,
                    resolution: float | None = None) -> CantileverTest:
    """Hang a 2.5 cm strip over a platform's edge and read its bending length from Peirce's relation.

    The overhang defaults to twice the nominal bending length, where the standard's tip would sit on
    the 41.5° line; 1 cm of strip lies clamped on the platform. The strip is loaded gently like
    the drape specimen, and the chord from the edge to the tip's mid-point gives θ.
    """
    from .scenes import grid, run_scene

    if fabric.bending <= 0:
        raise ValueError(f"fabric {fabric.name!r} has no bending stiffness: it has no bending length")
    if direction not in ("warp", "weft"):
        raise ValueError(f"direction must be warp or weft, got {direction!r}")
    nominal = nominal_bending_length(fabric)
    l = 2.0 * nominal if overhang is None else float(overhang)
    h = min(l / 16.0, 0.5 * CM) if resolution is None else float(resolution)
    held = 1.0 * CM
    nx, ny = int(math.ceil((l + held) / h)) + 1, max(3, int(math.ceil(STRIP_WIDTH / h)) + 1)
    mesh = grid(l + held, STRIP_WIDTH, nx, ny, "strip", grain=0.0 if direction == "warp" else 0.5 * math.pi)
    x0 = np.c_[mesh.uv[:, 0] - held, mesh.uv[:, 1], np.zeros(mesh.vertex_count)]
    model = build_model(mesh, fabric, pinned=np.flatnonzero(x0[:, 0] <= 1e-9))
    t0 = time.perf_counter()
    result = run_scene(model, x0, duration=LAY_S + SETTLE_S, fps=25, integrator="implicit", dt=0.005,
                       self_collision="off", forces=_GentleLoad(LAY_S))
    x = result.frames[-1]
    tip = x[np.isclose(x0[:, 0], l)].mean(axis=0)
    angle = math.atan2(-tip[2], tip[0])
    return CantileverTest(fabric.name, direction, l, angle, peirce_bending_length(l, angle), nominal,
                          time.perf_counter() - t0)


def fabric_from_cantilever(base: Fabric, bending_length: float, *, check: bool = True) -> tuple[Fabric, CantileverTest | None]:
    """The fabric ``base`` with the bending number of a measured bending length [m], and its check.

    Peirce's relation makes the bending number c = C³ (C in cm). The simulated cantilever of the
    result is then run; a narrow strip of tailor's cloth curls sideways a little as it bends (the
    dihedral bending energy couples the two curvatures like a Poisson ratio of ⅓), so where the
    simulated bending length misses the measurement by more than 2 %, c is corrected once by the
    ratio's cube and the test run again. The test returned is the last one.
    """
    fabric = base.with_values(bending=(bending_length / CM) ** 3)
    if not check:
        return fabric, None
    test = cantilever_test(fabric)
    if abs(test.bending_length / bending_length - 1.0) > 0.02:
        fabric = fabric.with_values(bending=fabric.bending * (bending_length / test.bending_length) ** 3)
        test = cantilever_test(fabric, overhang=2.0 * bending_length)
    return fabric, test


def calibrate_bending(base: Fabric, drape_coefficient: float, *, resolution: float = DRAPE_RESOLUTION,
                      specimens: int = len(SPECIMEN_SCALES), tolerance: float = 0.005, progress=None) -> tuple[Fabric, DrapeTest]:
    """The fabric ``base`` with the bending number whose simulated drape test gives ``drape_coefficient``.

    DC grows with bending; the search brackets the target in log c between 0.05 and 3000 and
    narrows it by regula falsi on (log c, DC) until the test is within ``tolerance`` (about six
    drape tests). ``progress(c, test)`` is called after each.
    """
    if not 0.0 < drape_coefficient < 1.0:
        raise ValueError(f"a drape coefficient lies between 0 and 1, got {drape_coefficient:g}")

    def run(log_c):
        test = drape_test(base.with_values(bending=math.exp(log_c)), resolution=resolution, specimens=specimens)
        if progress is not None:
            progress(math.exp(log_c), test)
        return test

    a, b = math.log(0.05), math.log(3000.0)
    fa = fb = None  # DC − target at the bracket's ends, once tested
    best_c, best = None, None
    m = math.log(max(base.bending, 0.05))
    for _ in range(14):
        t = run(m)
        miss = t.drape_coefficient - drape_coefficient
        if best is None or abs(miss) < abs(best.drape_coefficient - drape_coefficient):
            best_c, best = math.exp(m), t
        if abs(miss) <= tolerance:
            break
        if miss > 0:
            b, fb = m, miss
        else:
            a, fa = m, miss
        if fa is None or fb is None:  # open bracket: halve it in log c
            m = 0.5 * (a + b)
        else:  # regula falsi, kept away from the ends
            m = a + (b - a) * min(max(fa / (fa - fb), 0.1), 0.9)
    return base.with_values(bending=best_c), best


KES_LOAD = 500 * 9.80665e-3 / 1e-2
"""KES-F's tensile test load [N/m]: 500 gf/cm, at which EMT is read."""


def fabric_from_kes(base: Fabric, *, density_g_m2: float, bending_gf_cm: float, emt_pct: float,
                    emt_weft_pct: float | None = None) -> Fabric:
    """The fabric ``base`` from Kawabata (KES-F) numbers: W [g/m²], B [gf·cm²/cm], EMT [%].

    B over the weight per area gives the bending length cubed (c = B/(W·ℓ³), B and W in SI); the
    tensile curve's secant to 500 gf/cm (EMT) gives the membrane stiffness, and with it the stretch
    a 1 m strip shows under its own weight (Carignan Eq. 22, :func:`tailor.hanging.hanging_strain`).
    """
    from .hanging import hanging_strain

    rho = density_g_m2 * 1e-3
    b_si = bending_gf_cm * 9.80665e-3 * 1e-4 / 1e-2  # gf·cm²/cm → N·m
    c = b_si / (rho * GRAVITY * CM**3)
    warp = hanging_strain(rho, KES_LOAD / (emt_pct * 1e-2))
    weft = warp if emt_weft_pct is None else hanging_strain(rho, KES_LOAD / (emt_weft_pct * 1e-2))
    return base.with_values(density=rho, bending=c, stretch_warp=warp, stretch_weft=weft)
