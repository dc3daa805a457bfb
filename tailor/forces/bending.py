"""Bending from the change of curvature (Carignan Eq. 1 fourth term, Eq. 4c, Eq. 25).

On a triangle mesh the curvature lives on the edges: the dihedral angle θ between the two
triangles of each hinge. The energy Σ ½·k·(θ − θ₀)² with k ∝ B|e|²/(A₀ + A₁) approximates the
continuum ½∫B·κ² dA (discrete shells; the constant is calibrated per panel, see
:func:`tailor.model.build_model`); the gradient of θ is the classical closed form
(Bridson et al. 2003). With B = 0 there is no bending force at all (and the pass can be skipped).
"""

from __future__ import annotations

import numpy as np

from ..geometry import hinge_angle_gradients, hinge_angles

__all__ = ["bending_energy", "bending_forces"]


def bending_energy(model, state) -> float:
    """Σ ½·k·(θ − θ₀)² [J]."""
    if not len(model.hinge_vertices):
        return 0.0
    d = hinge_angles(state.x, model.hinge_vertices) - model.hinge_rest_angle
    return float(0.5 * np.dot(model.hinge_stiffness, d * d))


def bending_forces(model, state, out=None) -> np.ndarray:
    """−∂(bending energy)/∂x [N], shape (N, 3); added into ``out`` when given."""
    out = np.zeros_like(state.x) if out is None else out
    hv = model.hinge_vertices
    if not len(hv):
        return out
    torque = model.hinge_stiffness * (hinge_angles(state.x, hv) - model.hinge_rest_angle)
    g = hinge_angle_gradients(state.x, hv) * (-torque)[:, None, None]
    n = len(out)
    for k in range(3):
        out[:, k] += np.bincount(hv.reshape(-1), g[:, :, k].reshape(-1), minlength=n)
    return out
