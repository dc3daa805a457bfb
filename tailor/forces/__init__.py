"""Forces: pure functions of (model, state), each adding into an (N, 3) array [N].

:func:`total_forces` sums what the model needs and nothing more: bending only where it has
stiffness, air only when the model has air, and the elastic model the model names.
"""

from __future__ import annotations

import numpy as np

from .bending import bending_energy, bending_forces
from .kawabata import secant_hinge_stiffness, secant_membrane_stiffness
from .kernels import bending_forces_into, membrane_forces_into
from .external import air_forces, gravity_energy, gravity_forces
from .membrane import damping_forces, dissipation, stretch_energy, stretch_forces
from .springs import spring_energy, spring_forces

__all__ = [
    "total_forces",
    "internal_forces",
    "potential_energy",
    "kinetic_energy",
    "stretch_energy",
    "stretch_forces",
    "damping_forces",
    "dissipation",
    "bending_energy",
    "bending_forces",
    "spring_energy",
    "spring_forces",
    "pair_forces",
    "gravity_forces",
    "gravity_energy",
    "air_forces",
]


def internal_forces(model, state, out=None) -> np.ndarray:
    """Stretch, damping and bending (membrane) or springs (Walker) [N], shape (N, 3).

    The membrane and bending passes run as compiled kernels (:mod:`.kernels`), equal to the
    numpy reference functions of :mod:`.membrane` and :mod:`.bending` to round-off.
    """
    out = np.zeros_like(state.x) if out is None else out
    curves = model.has_curves
    if model.elastic == "springs":
        spring_forces(model, state, out)
    else:
        membrane_forces_into(model, state, out,
                             stiffness=secant_membrane_stiffness(model, state.x) if model.strain_dependent else None)
    if model.has_bending:
        bending_forces_into(model, state, out, stiffness=secant_hinge_stiffness(model, state.x) if curves else None)
    if len(model.pair_vertices):
        pair_forces(model, state, out)
    return out


def pair_forces(model, state, out=None) -> np.ndarray:
    """Zero-length pair springs with dampers: f_i = K(x_j − x_i) + C(v_j − v_i), and the opposite on j [N]."""
    out = np.zeros_like(state.x) if out is None else out
    p = model.pair_vertices
    i, j = p[:, 0], p[:, 1]
    f = model.pair_stiffness[:, None] * (state.x[j] - state.x[i]) + model.pair_damping[:, None] * (state.v[j] - state.v[i])
    n = len(out)
    for k in range(3):
        out[:, k] += np.bincount(i, f[:, k], minlength=n) - np.bincount(j, f[:, k], minlength=n)
    return out


def total_forces(model, state, *, wind=None) -> np.ndarray:
    """All forces on every vertex [N], shape (N, 3): internal, gravity and air."""
    out = internal_forces(model, state)
    gravity_forces(model, state, out)
    air_forces(model, state, wind, out)
    return out


def potential_energy(model, state) -> float:
    """Elastic + bending + gravitational potential energy [J]."""
    elastic = spring_energy(model, state) if model.elastic == "springs" else stretch_energy(model, state)
    return elastic + bending_energy(model, state) + gravity_energy(model, state)


def kinetic_energy(model, state) -> float:
    """½Σm|v|² [J]."""
    return float(0.5 * np.dot(model.vertex_mass, np.einsum("ij,ij->i", state.v, state.v)))
