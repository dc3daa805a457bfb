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
* **Damping** (Eq. 26) γ = 2h√(mη) is critical damping for "the ideal case of a single mass": it
  equals 2η/ω with the single-mass frequency ω = √(η/m)/h. On triangles we use each element's exact
  fastest frequency ω_e instead, φ = 2η/ω_e, so the mesh's noisiest mode is exactly critically
  damped and nothing slower is (rigid motion, swinging and draping are untouched).
* The explicit step is also kept at 0.9× the exact stability bound of symplectic Euler for that
  critically damped fastest mode.

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

import numpy as np
from scipy.optimize import brentq

from .fabric import Fabric
from .hanging import REFERENCE_HEIGHT, mean_strain_of_hanging_strip, hanging_strain
from .units import CM, GRAVITY

__all__ = [
    "Params",
    "fabric_params",
    "stretch_stiffness",
    "hanging_strain",
    "bending_rigidity",
    "element_frequencies",
    "symplectic_limit",
    "stable_time_step",
    "REFERENCE_HEIGHT",
    "BENDING_LENGTH_UNIT",
    "SAFETY",
]

BENDING_LENGTH_UNIT = 1.0 * CM
"""The fixed length ℓ [m] replacing Eq. 25's grid spacing: B = c·ρ·g·ℓ³."""

SAFETY = 2.0
"""Eq. 24's l: a wave crosses at most 1/l of an element per step (the paper suggests 2 or 3)."""


def stretch_stiffness(density: float, stretch: float) -> float:
    """Membrane stiffness η [N/m] giving mean strain ``stretch`` to a 1 m hanging strip (Eq. 22).

    Exact for the Green-strain membrane; η = ρgH/(2λ) in the small-strain limit.
    """
    top = brentq(lambda s: mean_strain_of_hanging_strip(s) - stretch, 1.0 + 1e-12, 10.0)
    tau = 0.5 * (top**3 - top)
    return density * GRAVITY * REFERENCE_HEIGHT / tau


def bending_rigidity(density: float, c: float) -> float:
    """Flexural rigidity B = c·ρ·g·ℓ³ [N·m] (Eq. 25 with a fixed ℓ = 1 cm); c = 0 gives 0."""
    return c * density * GRAVITY * BENDING_LENGTH_UNIT**3


def stable_time_step(density, stiffness, rigidity, altitude, *, safety: float = SAFETY) -> float:
    """Eq. 24: Δt = (h / v) / l with v = √(η/ρ) (Eq. 23), bounded by the bending wave too [s].

    ``altitude`` is the smallest triangle altitude [m]. Flexural waves travel at
    ω/k = √(B/ρ)·k; on a mesh the fastest has k ≈ π/h, so Δt_b = h² / (π·√(B/ρ)) / l.
    """
    dt = altitude / math.sqrt(stiffness / density) / safety
    if rigidity > 0:
        dt = min(dt, altitude**2 / (math.pi * math.sqrt(rigidity / density)) / safety)
    return dt


def element_frequencies(dm_inv, area, rho, k1, k2, k12):
    """Fastest natural frequency ω_e [rad/s] of each free triangle with lumped corner masses.

    K_e = A·Σ cᵢ∇Eᵢ∇Eᵢᵀ at rest and M_e = (ρA/3)·I, so ω_e² = 3·λ_max(K_e)/(ρA). Over the whole
    mesh, ω_max ≤ max_e ω_e (lumped masses partition by element), a safe bound for Δt.
    """
    if not len(area):
        return np.zeros(0)
    w1 = np.stack([-(dm_inv[:, 0, 0] + dm_inv[:, 1, 0]), dm_inv[:, 0, 0], dm_inv[:, 1, 0]], axis=1)
    w2 = np.stack([-(dm_inv[:, 0, 1] + dm_inv[:, 1, 1]), dm_inv[:, 0, 1], dm_inv[:, 1, 1]], axis=1)
    e1, e2 = np.array([1.0, 0.0]), np.array([0.0, 1.0])  # rest F = I in the panel plane
    g11 = (w1[:, :, None] * e1).reshape(-1, 6)
    g22 = (w2[:, :, None] * e2).reshape(-1, 6)
    g12 = 0.5 * (w1[:, :, None] * e2 + w2[:, :, None] * e1).reshape(-1, 6)
    k = (
        k1[:, None, None] * g11[:, :, None] * g11[:, None, :]
        + k2[:, None, None] * g22[:, :, None] * g22[:, None, :]
        + 2.0 * k12[:, None, None] * g12[:, :, None] * g12[:, None, :]
    )
    lam = np.linalg.eigvalsh(k)[:, -1]  # out-of-plane dofs have no stiffness at rest
    return np.sqrt(3.0 * lam / rho)


def symplectic_limit(zeta: float) -> float:
    """Largest ω·Δt for which symplectic Euler is stable on ẍ + 2ζωẋ + ω²x = 0 (Jury criterion)."""
    return min(2.0 * (np.sqrt(zeta * zeta + 1.0) - zeta), 1.0 / zeta if zeta > 0 else np.inf)


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
        φ [N·s/m] for equilateral elements of the given resolution (Eq. 26).
    resolution : float
        Element size h [m] these were derived for.
    time_step : float
        Δt [s] (Eq. 24) for equilateral elements of side ``resolution``.
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
    # an equilateral element of side h, warp along one edge: its fastest frequency sets Eq. 26
    dm_inv = np.linalg.inv(np.array([[[resolution, 0.5 * resolution], [0.0, altitude]]]))
    area = np.array([0.5 * resolution * altitude])
    omega = float(element_frequencies(dm_inv, area, np.array([rho]), np.array([k1]), np.array([k2]), np.array([k12]))[0])
    dt = stable_time_step(rho, max(k1, k2), bend, altitude, safety=safety)
    return Params(
        density=rho,
        stretch_warp=k1,
        stretch_weft=k2,
        stretch_shear=k12,
        wave_speed_warp=math.sqrt(k1 / rho),
        wave_speed_weft=math.sqrt(k2 / rho),
        bending_rigidity=bend,
        damping_warp=2.0 * k1 / omega,
        damping_weft=2.0 * k2 / omega,
        damping_shear=2.0 * k12 / omega,
        resolution=resolution,
        time_step=min(dt, 0.9 * symplectic_limit(1.0) / omega),
    )
