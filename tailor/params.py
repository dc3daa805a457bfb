"""Automatic parameters: everything the simulator needs from a designer's three numbers.

Carignan et al. (seed 002, §5) derive mass, stretch stiffness, time step, bending stiffness and
damping from the areal density ρ, the stretch λ of a panel hanging under its own weight, and a
bending number c. Their formulas are written for a finite-difference grid of spacing h; here they
carry over to triangles and are made independent of the discretisation where the paper says so:

* **Mass** (Eq. 21) m = ρ·da: each triangle's mass ρA is lumped a third to each corner.
* **Stretch** (Eq. 22) η₁₁, η₂₂ [N/m]: the membrane stiffness (tension per unit width per unit
  Green strain) along warp and weft. Eq. 22 ties it to the elongation λ of a *panel hanging from
  its top edge*; so that the number belongs to the fabric and not to the panel or the grid, the
  hanging height is fixed at ``REFERENCE_HEIGHT`` = 1 m. Precisely: **λ is the mean strain
  (ΔH/H) of a 1 m tall strip hanging under its own weight**, solved exactly for our Green-strain
  membrane (so 50 % means 50 %, not a linearised guess). For small λ, η = ρgH/(2λ).
  Shear η₁₂ = √(η₁₁η₂₂) (Eq. 22c: "the mean value" — the geometric mean, which keeps units).
* **Wave speed** (Eq. 23) v = √(η/ρ) [m/s] and **time step** (Eq. 24) Δt = min(h/v)/l with l = 2:
  on triangles h is the smallest triangle altitude, where a wave crosses an element fastest.
  A bending wave (v_b ∝ √(B/ρ)/h) bounds Δt too for stiff fabrics on fine meshes.
* **Bending** (Eq. 25) ξ = c·m·g·h⁴ on the grid; with m = ρh² the continuum flexural rigidity is
  B = c·ρ·g·ℓ³ with the grid length replaced by a fixed ℓ = 1 cm, so **c is the cube of Peirce's
  bending length in cm** (B/(ρg) = C³): silk ≈ 1, cotton ≈ 8, denim ≈ 60. c = 0: no bending.
* **Damping** (Eq. 26) γ = 2h√(mη): critical damping of the strain rate for one element of size h
  ("the ideal case of a single mass"); per triangle, h is its characteristic length √(2A).

Examples
--------
>>> from tailor.fabric import preset
>>> p = fabric_params(preset("cotton"), 0.015)
>>> round(p.stretch_warp, 1)  # N/m: a 1 m strip of 120 g/m² cotton stretching 1 %
57.7
>>> round(p.bending_rigidity * 1e6, 2)  # µN·m
9.41
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from scipy.optimize import brentq

from .fabric import Fabric
from .units import CM, GRAVITY

__all__ = [
    "Params",
    "fabric_params",
    "stretch_stiffness",
    "hanging_strain",
    "bending_rigidity",
    "critical_damping",
    "stable_time_step",
    "REFERENCE_HEIGHT",
    "BENDING_LENGTH_UNIT",
    "SAFETY",
]

REFERENCE_HEIGHT = 1.0
"""Height [m] of the hanging strip that defines the stretch percentage (Eq. 22)."""

BENDING_LENGTH_UNIT = 1.0 * CM
"""The fixed length ℓ [m] replacing Eq. 25's grid spacing: B = c·ρ·g·ℓ³."""

SAFETY = 2.0
"""Eq. 24's l: a wave crosses at most 1/l of an element per step (the paper suggests 2 or 3)."""


def _mean_strain_of_hanging_strip(top_stretch: float) -> float:
    """Mean strain of a Green-strain strip whose top stretch ratio is S, per unit τ = ρgH/η.

    Tension at rest height y above the free end: η·½(s²−1)·s = ρ·g·y, i.e. s³ − s = 2t with
    t = ρgy/η. Integrating s dt from s = 1 to S in closed form gives the mean stretch.
    """
    s = top_stretch
    tau = 0.5 * (s**3 - s)
    integral = (3.0 * s**4 / 8.0 - s**2 / 4.0) - (3.0 / 8.0 - 1.0 / 4.0)
    return integral / tau - 1.0


def hanging_strain(density: float, stiffness: float, height: float = REFERENCE_HEIGHT) -> float:
    """Mean strain ΔH/H of a strip of ``height`` [m] hanging under its own weight.

    Parameters: ``density`` ρ [kg/m²], ``stiffness`` η [N/m] of the Green-strain membrane.
    """
    tau = density * GRAVITY * height / stiffness
    top = brentq(lambda s: s**3 - s - 2.0 * tau, 1.0, 2.0 + 2.0 * tau)
    return _mean_strain_of_hanging_strip(top)


def stretch_stiffness(density: float, stretch: float) -> float:
    """Membrane stiffness η [N/m] giving mean strain ``stretch`` to a 1 m hanging strip (Eq. 22).

    Exact for the Green-strain membrane; η = ρgH/(2λ) in the small-strain limit.
    """
    top = brentq(lambda s: _mean_strain_of_hanging_strip(s) - stretch, 1.0 + 1e-12, 10.0)
    tau = 0.5 * (top**3 - top)
    return density * GRAVITY * REFERENCE_HEIGHT / tau


def bending_rigidity(density: float, c: float) -> float:
    """Flexural rigidity B = c·ρ·g·ℓ³ [N·m] (Eq. 25 with a fixed ℓ = 1 cm); c = 0 gives 0."""
    return c * density * GRAVITY * BENDING_LENGTH_UNIT**3


def critical_damping(density: float, stiffness: float, length: float) -> float:
    """Strain-rate damping coefficient φ = 2·h·√(ρη) [N·s/m] (Eq. 26) for elements of size ``length``.

    A single element of mass ρh² on a spring η returns to rest without oscillating.
    """
    return 2.0 * length * math.sqrt(density * stiffness)


def stable_time_step(density, stiffness, rigidity, altitude, *, safety: float = SAFETY) -> float:
    """Eq. 24: Δt = (h / v) / l with v = √(η/ρ) (Eq. 23), bounded by the bending wave too [s].

    ``altitude`` is the smallest triangle altitude [m]. Flexural waves travel at
    ω/k = √(B/ρ)·k; on a mesh the fastest has k ≈ π/h, so Δt_b = h² / (π·√(B/ρ)) / l.
    """
    dt = altitude / math.sqrt(stiffness / density) / safety
    if rigidity > 0:
        dt = min(dt, altitude**2 / (math.pi * math.sqrt(rigidity / density)) / safety)
    return dt


@dataclass(frozen=True, slots=True)
class Params:
    """Derived simulation parameters of one fabric at one resolution (all SI).

    Attributes
    ----------
    density : float
        ρ [kg/m²] (Eq. 21).
    stretch_warp, stretch_weft, stretch_shear : float
        η₁₁, η₂₂, η₁₂ [N/m] (Eq. 22).
    wave_speed_warp, wave_speed_weft : float
        [m/s] (Eq. 23).
    bending_rigidity : float
        B [N·m] (Eq. 25).
    damping_warp, damping_weft, damping_shear : float
        φ [N·s/m] for elements of the given resolution (Eq. 26).
    resolution : float
        Element size h [m] these were derived for.
    time_step : float
        Δt [s] (Eq. 24) for an element altitude of ``resolution · √3/2``.
    """

    density: float
    stretch_warp: float
    stretch_weft: float
    stretch_shear: float
    wave_speed_warp: float
    wave_speed_weft: float
    bending_rigidity: float
    damping_warp: float
    damping_weft: float
    damping_shear: float
    resolution: float
    time_step: float

    def as_dict(self) -> dict:
        """Plain dict (for reports)."""
        return asdict(self)


def fabric_params(fabric: Fabric, resolution: float, *, safety: float = SAFETY) -> Params:
    """All of Carignan's derived parameters (Eq. 21–26) for ``fabric`` at element size ``resolution`` [m]."""
    rho = fabric.density
    k1 = stretch_stiffness(rho, fabric.stretch_warp)
    k2 = stretch_stiffness(rho, fabric.stretch_weft)
    k12 = math.sqrt(k1 * k2)
    bend = bending_rigidity(rho, fabric.bending)
    altitude = resolution * math.sqrt(3.0) / 2.0
    return Params(
        density=rho,
        stretch_warp=k1,
        stretch_weft=k2,
        stretch_shear=k12,
        wave_speed_warp=math.sqrt(k1 / rho),
        wave_speed_weft=math.sqrt(k2 / rho),
        bending_rigidity=bend,
        damping_warp=critical_damping(rho, k1, resolution),
        damping_weft=critical_damping(rho, k2, resolution),
        damping_shear=critical_damping(rho, k12, resolution),
        resolution=resolution,
        time_step=stable_time_step(rho, max(k1, k2), bend, altitude, safety=safety),
    )
