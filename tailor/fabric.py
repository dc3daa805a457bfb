"""Fabric: the three numbers a designer understands, plus friction and thickness.

Carignan et al. (seed 002, §5) derive every simulation parameter from areal density ρ,
the stretch percentage λ a panel shows when suspended under its own weight, and a bending
number c. :class:`Fabric` stores those user numbers in SI; the parameter derivation
(Eq. 21–26) lives in :mod:`tailor.params`.

Examples
--------
>>> f = preset("denim")
>>> f.density  # kg/m²
0.4
>>> fabric_names()[:3]
('chiffon', 'organza', 'silk')
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from .errors import FabricError
from .hanging import hanging_strain

__all__ = ["Fabric", "KawabataCurves", "PRESETS", "KAWABATA_FABRICS", "preset", "fabric_names", "DEFAULT_FABRIC"]


@dataclass(frozen=True, slots=True)
class Fabric:
    """A fabric in SI units.

    Attributes
    ----------
    name : str
        Preset name or a user label.
    density : float
        Areal density ρ [kg/m²] (Eq. 21). Silk ≈ 0.05, denim ≈ 0.4, heavy leather 10 (the
        paper's 1.0 g/cm²).
    stretch_warp, stretch_weft : float
        Elongation λ under own weight as a fraction (0.02 = 2 %), along the warp (grain)
        and the weft (Eq. 22a/b).
    bending : float
        Carignan's bending number c (Eq. 25): the cube of the fabric's Peirce bending length in
        cm (see :mod:`tailor.params`); 0 means no bending resistance. Silk ≈ 1, denim ≈ 60.
    friction : float
        Coulomb friction coefficient μ against bodies (Eq. 14).
    thickness : float
        Cloth thickness [m], used as the collision margin.
    tear_strain : float
        Stretch across a line of the cloth at which it rips (0.25 = 25 %; 0 = never), used when
        tearing is switched on (:mod:`tailor.tearing`).
    wearable_stretch : float
        The largest stretch still comfortable to wear (0.06 = 6 %): the top of a fit map's strain
        scale (CLO's "wearable stretch limit", :mod:`tailor.fit`). Presets: ``docs/fabrics.md``.
    kawabata : KawabataCurves or None
        Measured tensile, shear and bending curves (Bottino et al.); when given they replace the
        stretch and bending numbers in the elastic law (the numbers remain for the time step).
    """

    name: str
    density: float
    stretch_warp: float
    stretch_weft: float
    bending: float
    friction: float = 0.4
    thickness: float = 1.0e-3
    kawabata: "KawabataCurves | None" = None
    tear_strain: float = 0.0
    wearable_stretch: float = 0.10

    def __post_init__(self):
        for f in fields(self):
            if f.name in ("name", "kawabata"):
                continue
            value = getattr(self, f.name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                raise FabricError(f"fabric {self.name!r}: {f.name} must be a finite number, got {value!r}")
        if self.density <= 0:
            raise FabricError(f"fabric {self.name!r}: density must be positive, got {self.density * 1e3:g} g/m²")
        for key in ("stretch_warp", "stretch_weft"):
            v = getattr(self, key)
            if not 0.0 < v <= 1.0:
                raise FabricError(f"fabric {self.name!r}: {key} must be in (0, 100] %, got {v * 100:g} %")
        if self.bending < 0:
            raise FabricError(f"fabric {self.name!r}: bending must be >= 0, got {self.bending:g}")
        if self.friction < 0:
            raise FabricError(f"fabric {self.name!r}: friction must be >= 0, got {self.friction:g}")
        if self.thickness <= 0:
            raise FabricError(f"fabric {self.name!r}: thickness must be positive, got {self.thickness * 1e3:g} mm")
        if not 0.0 < self.wearable_stretch <= 5.0:
            raise FabricError(f"fabric {self.name!r}: wearable_stretch must be in (0, 500] %, got {self.wearable_stretch * 100:g} %")
        if self.tear_strain < 0:
            raise FabricError(f"fabric {self.name!r}: tear_strain must be >= 0 % (0: never tears), got {self.tear_strain * 100:g} %")

    def with_values(self, **values) -> "Fabric":
        """A copy with some fields replaced (validated again)."""
        return replace(self, **values)


@dataclass(frozen=True, slots=True)
class KawabataCurves:
    """Piecewise-linear Kawabata (KES-F) curves through the origin (Bottino et al. §4.1, §5).

    Each curve is a tuple of (deformation, load) breakpoints with increasing deformation and
    non-decreasing load, starting after the origin; beyond the last point the last slope goes on,
    and compression mirrors tension. One segment is the linear approximation (the KES mean slope),
    five segments the accurate one. The simulator uses Bottino's secant stiffness K = f(ε)/ε, so
    the stress of every triangle lies exactly on the curve.

    Attributes
    ----------
    tensile_warp, tensile_weft : tuple of (strain, N/m)
        Force per unit width against strain.
    shear : tuple of (rad, N/m)
        Shear force per unit length against shear angle (mean of warp and weft).
    bending : tuple of (1/m, N·m/m)
        Bending moment per unit width against curvature.
    """

    tensile_warp: tuple
    tensile_weft: tuple
    shear: tuple
    bending: tuple

    def __post_init__(self):
        for name in ("tensile_warp", "tensile_weft", "shear", "bending"):
            pts = getattr(self, name)
            ok = isinstance(pts, tuple) and len(pts) >= 1 and all(
                isinstance(p, tuple) and len(p) == 2 and all(isinstance(v, (int, float)) and math.isfinite(v) for v in p) for p in pts
            )
            if not ok:
                raise FabricError(f"kawabata.{name}: expected a list of [deformation, load] pairs")
            xs = [0.0] + [p[0] for p in pts]
            ys = [0.0] + [p[1] for p in pts]
            if any(b <= a for a, b in zip(xs, xs[1:])):
                raise FabricError(f"kawabata.{name}: deformations must increase from 0")
            if any(b < a for a, b in zip(ys, ys[1:])) or ys[-1] <= 0:
                raise FabricError(f"kawabata.{name}: loads must not decrease and must end above 0")

    @property
    def segments(self) -> int:
        """Segments of the tensile warp curve (1 = linear, 5 = Bottino's accurate variant)."""
        return len(self.tensile_warp)

    @staticmethod
    def initial_slope(curve) -> float:
        """Slope of the first segment (load per unit deformation)."""
        return curve[0][1] / curve[0][0]

    @staticmethod
    def mean_slope(curve) -> float:
        """Secant slope to the last point (the one-segment approximation of a curve)."""
        return curve[-1][1] / curve[-1][0]

    def linearised(self) -> "KawabataCurves":
        """The one-segment version: each curve replaced by its secant to the last point."""
        return KawabataCurves(*(tuple([c[-1]]) for c in (self.tensile_warp, self.tensile_weft, self.shear, self.bending)))


def _p(name, g_m2, stretch_pct, bending, friction=0.4, thickness_mm=1.0, weft_pct=None, tear_pct=25.0, wearable_pct=10.0):
    w = stretch_pct if weft_pct is None else weft_pct
    return Fabric(name, g_m2 * 1e-3, stretch_pct * 1e-2, w * 1e-2, bending, friction, thickness_mm * 1e-3,
                  tear_strain=tear_pct * 1e-2, wearable_stretch=wearable_pct * 1e-2)


PRESETS: dict[str, Fabric] = {
    f.name: f
    for f in (
        # bending c = (bending length in cm)³, typical of the class; drape-tested against published
        # ranges (docs/fabrics.md, tailor.lab.DRAPE_RANGES). Tear strains: elongation at break of the
        # class (order of magnitude); wearable stretch: the comfortable stretch of the class
        _p("chiffon", 35, 3.0, 1.7, 0.3, 0.3, tear_pct=20.0, wearable_pct=8.0),
        _p("organza", 45, 1.5, 12.2, 0.3, 0.3, tear_pct=20.0, wearable_pct=3.0),
        _p("silk", 50, 2.0, 2.7, 0.25, 0.3, tear_pct=20.0, wearable_pct=6.0),
        _p("satin", 100, 1.5, 3.4, 0.25, 0.35, tear_pct=20.0, wearable_pct=5.0),
        _p("crepe", 110, 3.0, 2.2, 0.4, 0.4, tear_pct=25.0, wearable_pct=8.0),
        _p("poplin", 115, 1.0, 12.2, 0.4, 0.3, tear_pct=25.0, wearable_pct=4.0),
        _p("cotton", 120, 1.0, 8.0, 0.4, 0.5, tear_pct=25.0, wearable_pct=5.0),
        _p("linen", 170, 1.0, 17.6, 0.45, 0.5, tear_pct=25.0, wearable_pct=3.0),
        _p("jersey", 180, 8.0, 4.0, 0.5, 0.8, weft_pct=15.0, tear_pct=100.0, wearable_pct=30.0),
        _p("rib_knit", 230, 10.0, 4.1, 0.5, 1.2, weft_pct=25.0, tear_pct=150.0, wearable_pct=50.0),
        _p("twill", 230, 0.8, 24.4, 0.45, 0.6, tear_pct=25.0, wearable_pct=4.0),
        _p("wool", 280, 1.5, 15.0, 0.5, 1.5, tear_pct=30.0, wearable_pct=6.0),
        _p("fleece", 280, 5.0, 10.6, 0.6, 2.5, weft_pct=10.0, tear_pct=80.0, wearable_pct=15.0),
        _p("denim_10oz", 340, 0.6, 32.8, 0.5, 0.8, tear_pct=25.0, wearable_pct=3.0),
        _p("canvas", 400, 0.5, 74.0, 0.5, 1.0, tear_pct=25.0, wearable_pct=2.0),
        _p("denim", 400, 0.5, 60.0, 0.5, 1.0, tear_pct=25.0, wearable_pct=3.0),
        _p("denim_14oz", 475, 0.5, 54.9, 0.5, 1.1, tear_pct=25.0, wearable_pct=3.0),
        _p("melton", 550, 1.5, 32.8, 0.6, 2.5, tear_pct=30.0, wearable_pct=4.0),
        _p("leather", 650, 1.5, 27.0, 0.6, 0.8, tear_pct=50.0, wearable_pct=8.0),
        _p("heavy_leather", 10000, 0.2, 1000.0, 0.6, 3.0, tear_pct=50.0, wearable_pct=5.0),
    )
}
"""Named fabrics, light to heavy: ``denim`` is 12 oz/yd², ``twill`` a chino, ``wool`` a suiting,
``leather`` garment (lamb nappa) leather. ``heavy_leather`` is Carignan's 1.0 g/cm² extreme, kept
for the stability tests and not a garment fabric."""

def _kes(name, g_m2, warp, weft, shear_g, bending_b, friction=0.4, thickness_mm=0.5):
    """A Kawabata fabric from five-segment tensile curves [(strain, N/m)], shear G and bending B.

    Shear is given as KES G (gf/cm/deg) and bending as KES B (gf·cm²/cm), converted to SI; their
    curves are mildly stiffening five-segment lines whose mean slope is G and B.
    """
    g_si = shear_g * 9.80665e-3 / 1e-2 * 180 / math.pi  # N/m per rad
    b_si = bending_b * 9.80665e-3 * 1e-4 / 1e-2  # N·m per m width × m = N·m
    shear = tuple((a, g_si * a * (0.8 + 0.1 * k)) for k, a in enumerate((0.015, 0.03, 0.05, 0.07, 0.087)))
    bend = tuple((kappa, b_si * kappa * (0.8 + 0.1 * k)) for k, kappa in enumerate((30.0, 60.0, 90.0, 120.0, 150.0)))
    curves = KawabataCurves(tuple(warp), tuple(weft), shear, bend)
    rho = g_m2 * 1e-3
    lam_warp = hanging_strain(rho, KawabataCurves.initial_slope(curves.tensile_warp))
    lam_weft = hanging_strain(rho, KawabataCurves.initial_slope(curves.tensile_weft))
    c = b_si / (rho * 9.80665 * 1e-6)
    return Fabric(name, rho, lam_warp, lam_weft, c, friction, thickness_mm * 1e-3, curves, tear_strain=0.25,
                  wearable_stretch=0.05)


KAWABATA_FABRICS: dict[str, Fabric] = {
    f.name: f
    for f in (
        # Representative KES-F data (not the paper's unpublished curves): J-shaped tensile curves
        # f = F_m·(ε/EMT)^p reaching F_m = 500 gf/cm at EMT, with LT = 2/(p + 1).
        _kes("bottino_a", 138,
             warp=[(0.005, 4.1), (0.01, 17.7), (0.02, 73.0), (0.03, 170.0), (0.05, 490.0)],
             weft=[(0.008, 4.1), (0.016, 17.7), (0.032, 73.0), (0.048, 170.0), (0.08, 490.0)],
             shear_g=0.6, bending_b=0.07),
        _kes("bottino_b", 291,
             warp=[(0.006, 2.3), (0.012, 11.6), (0.024, 58.0), (0.036, 149.0), (0.06, 490.0)],
             weft=[(0.009, 2.3), (0.018, 11.6), (0.036, 58.0), (0.054, 149.0), (0.09, 490.0)],
             shear_g=0.5, bending_b=0.12, thickness_mm=0.8),
    )
}
"""Kawabata-described fabrics for Bottino et al.'s experiments: A (cotton-like, 138 g/m²) and
B (wool, 291 g/m²), five-segment curves; ``.linearised()`` gives the one-segment variant."""

DEFAULT_FABRIC = "cotton"
"""Fabric used when a pattern names none."""


def fabric_names() -> tuple[str, ...]:
    """Every fabric name: presets light to heavy, then the Kawabata fabrics."""
    return (*PRESETS, *KAWABATA_FABRICS)


def preset(name: str) -> Fabric:
    """The preset fabric called ``name``; raises :class:`FabricError` naming the choices."""
    try:
        return PRESETS[name] if name in PRESETS else KAWABATA_FABRICS[name]
    except (KeyError, TypeError):
        import difflib

        names = [*PRESETS, *KAWABATA_FABRICS]
        close = difflib.get_close_matches(str(name), names, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise FabricError(f"unknown fabric {name!r}{hint}; choose one of {', '.join(names)}") from None
