"""Bottino et al.'s Kawabata option: stiffness K = f(ε)/ε from measured curves (seed 004, §4.1).

For a fabric described by :class:`~tailor.fabric.KawabataCurves`, the membrane's warp, weft and
shear stiffnesses and the hinges' bending stiffness are replaced, every evaluation, by the secant
slopes of the curves at each element's current deformation. Since our stresses are linear in the
stiffness (S₁₁ = η₁₁E₁₁, …), the resulting stress lies exactly on the measured curve:

* warp/weft: S = f_tensile(E) (Green strain ≈ engineering strain at cloth strains);
* shear: S₁₂ = f_shear(γ) with the shear angle γ = 2E₁₂, so η₁₂ = 2·f_shear(γ)/γ;
* bending: M = f_bending(κ) with the hinge's curvature κ = |θ|·(hinge curvature scale), and the
  hinge stiffness scaled by f(κ)/κ over the linear rigidity it was built with.

Compression mirrors tension (the curves are odd); beyond the last breakpoint the last slope goes on.
"""

from __future__ import annotations

import numpy as np

from ..geometry import hinge_angles
from .membrane import green_strain, stretch_stiffness

__all__ = ["curve_secant", "secant_membrane_stiffness", "secant_hinge_stiffness"]


def curve_secant(curve, deformation) -> np.ndarray:
    """Secant slope f(|d|)/|d| of a piecewise-linear curve through the origin, shape like ``deformation``."""
    xs = np.array([0.0] + [p[0] for p in curve])
    ys = np.array([0.0] + [p[1] for p in curve])
    a = np.abs(np.asarray(deformation, dtype=float))
    last_slope = (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
    f = np.where(a <= xs[-1], np.interp(a, xs, ys), ys[-1] + last_slope * (a - xs[-1]))
    initial = ys[1] / xs[1]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(a > 1e-12, f / np.maximum(a, 1e-300), initial)


def secant_membrane_stiffness(model, x):
    """(η₁₁, η₂₂, η₁₂) per face [N/m] at positions ``x``: the model's own, or from its curves."""
    e11, e22, e12 = green_strain(model, x)
    k1, k2, k12 = (np.array(a, dtype=float) for a in stretch_stiffness(model, e11, e22))
    if not model.has_curves:
        return k1, k2, k12
    for panel, curves in enumerate(model.curves):
        if curves is None:
            continue
        sel = model.face_panel == panel
        k1[sel] = curve_secant(curves.tensile_warp, e11[sel])
        k2[sel] = curve_secant(curves.tensile_weft, e22[sel])
        k12[sel] = 2.0 * curve_secant(curves.shear, 2.0 * e12[sel])
    return k1, k2, k12


def secant_hinge_stiffness(model, x) -> np.ndarray:
    """Hinge stiffness [N·m] at positions ``x``: the model's own, or scaled along its bending curve."""
    k = np.array(model.hinge_stiffness)
    if not model.has_curves or not len(k):
        return k
    kappa = np.abs(hinge_angles(x, model.hinge_vertices)) * model.hinge_curvature_scale
    for panel, curves in enumerate(model.curves):
        if curves is None:
            continue
        sel = model.hinge_panel == panel
        linear = model.params[panel].bending_rigidity
        if linear > 0:
            k[sel] *= curve_secant(curves.bending, kappa[sel]) / linear
    return k
