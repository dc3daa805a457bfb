"""Walker's mass-spring cloth (seed 000, Eq. 1–3): Hooke springs with dampers along their axis.

F_ij = k_s(l − |x_i − x_j|)·d̂ (Eq. 1) and F_ij^d = −k_d((v_i − v_j)·d̂)·d̂ (Eq. 2), with d̂ the unit
vector from j to i; every spring is listed once (Walker checks for duplicates; so does the model).
"""

from __future__ import annotations

import numpy as np

__all__ = ["spring_energy", "spring_forces"]


def _axis(model, x):
    s = model.spring_vertices
    d = x[s[:, 0]] - x[s[:, 1]]
    length = np.linalg.norm(d, axis=1)
    return s, d / np.maximum(length, 1e-300)[:, None], length


def spring_energy(model, state) -> float:
    """Σ ½·k_s·(|x_i − x_j| − l)² [J]."""
    _, _, length = _axis(model, state.x)
    return float(0.5 * np.dot(model.spring_stiffness, (length - model.spring_rest_length) ** 2))


def spring_forces(model, state, out=None) -> np.ndarray:
    """Eq. 1 + Eq. 2 summed per vertex [N], shape (N, 3); added into ``out`` when given."""
    out = np.zeros_like(state.x) if out is None else out
    s, u, length = _axis(model, state.x)
    rel_v = np.einsum("ij,ij->i", state.v[s[:, 0]] - state.v[s[:, 1]], u)
    mag = model.spring_stiffness * (model.spring_rest_length - length) - model.spring_damping * rel_v
    f = u * mag[:, None]  # on vertex i; −f on j
    n = len(out)
    for k in range(3):
        out[:, k] += np.bincount(s[:, 0], f[:, k], minlength=n) - np.bincount(s[:, 1], f[:, k], minlength=n)
    return out
