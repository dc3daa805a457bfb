"""The hanging strip that defines a fabric's stretch number (Carignan Eq. 22).

A strip of height H and areal density ρ hangs from its top edge; at rest height y above its free
end it carries its own weight below, ρ·g·y per unit width. For tailor's Green-strain membrane of
stiffness η the local stretch s solves η·½(s² − 1)·s = ρ·g·y, and the strip's mean strain follows
in closed form. Pure functions, no state.
"""

from __future__ import annotations

from scipy.optimize import brentq

from .units import GRAVITY

__all__ = ["hanging_strain", "mean_strain_of_hanging_strip", "REFERENCE_HEIGHT"]

REFERENCE_HEIGHT = 1.0
"""Height [m] of the hanging strip that defines the stretch percentage (Eq. 22)."""


def mean_strain_of_hanging_strip(top_stretch: float) -> float:
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
    return mean_strain_of_hanging_strip(top)
