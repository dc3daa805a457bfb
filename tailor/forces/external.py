"""External forces (Carignan Eq. 1 right-hand side; Walker Eq. 3): gravity and air.

Air acts on each triangle along its normal, against the normal component of the velocity
relative to the wind: f = −½·ρ_air·C_d·A·(v_rel·n)|v_rel·n|·n, shared equally by its corners.
That is drag when the air is still and wind when it moves, and it is why a flag flaps: the
force follows the cloth's orientation. A cloth in vacuum (ρ_air = 0) feels only gravity.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["gravity_forces", "gravity_energy", "air_forces"]


def gravity_forces(model, state, out=None) -> np.ndarray:
    """m·g per vertex [N], shape (N, 3); added into ``out`` when given."""
    out = np.zeros_like(state.x) if out is None else out
    out += model.vertex_mass[:, None] * model.gravity[None, :]
    return out


def gravity_energy(model, state) -> float:
    """Potential energy −Σ m·g·x [J] (zero at the origin)."""
    return float(-np.dot(model.vertex_mass, state.x @ model.gravity))


def air_damping(model, state, wind=None) -> np.ndarray:
    """−∂f/∂v of :func:`air_forces`, lumped on each vertex: (N, 3, 3), positive semi-definite.

    A face's force −½ρC_d·A·v_n|v_n|·n has the velocity derivative −ρC_d·A·|v_n|·n nᵀ; its corners
    share it (a third of the force each, the face velocity the mean of theirs), which summed over
    a row gives ρC_d·A·|v_n|/3·n nᵀ per corner. The implicit integrator adds it to its system so
    drag and wind stay stable at any step: explicitly, light cloth in an 8 m/s wind (ρ_cloth /
    (ρ_air·C_d·|v_n|) ≈ 0.02 s) blows up at draft's 0.04 s.
    """
    out = np.zeros((model.vertex_count, 3, 3))
    if model.air_density > 0.0 and model.face_count:
        _air(state.x, state.v, model.faces, _face_wind(model, state, wind), model.air_density * model.drag_coefficient,
             np.zeros((0, 3)), out)
    return out


def air_forces(model, state, wind=None, out=None) -> np.ndarray:
    """Normal air force on every face, spread to its corners [N], shape (N, 3).

    Parameters
    ----------
    wind : callable or array_like, optional
        Air velocity [m/s]: a (3,) vector, a (F, 3) array per face, or ``wind(points, t)``
        returning (F, 3) at the face centres. ``None`` = still air.
    """
    out = np.zeros_like(state.x) if out is None else out
    if model.air_density > 0.0 and model.face_count:
        air = np.zeros_like(out)
        _air(state.x, state.v, model.faces, _face_wind(model, state, wind), -0.5 * model.air_density * model.drag_coefficient,
             air, np.zeros((0, 3, 3)))
        out += air
    return out


def _face_wind(model, state, wind) -> np.ndarray:
    """The air's velocity [m/s] at each face, (F, 3), or (1, 3) where it is one for all."""
    if wind is None:
        return np.zeros((1, 3))
    if callable(wind):
        f = model.faces
        return np.ascontiguousarray(wind((state.x[f[:, 0]] + state.x[f[:, 1]] + state.x[f[:, 2]]) / 3.0, state.t), np.float64)
    return np.ascontiguousarray(np.asarray(wind, np.float64).reshape(-1, 3))


@njit(cache=True)
def _air(x, v, faces, wind, coefficient, force, damping):
    """Each face's air force (into ``force``, (N, 3), unless empty; ``coefficient`` −½ρC_d) or its
    velocity derivative (into ``damping``, (N, 3, 3), unless empty; ``coefficient`` ρC_d), a third
    to each corner, face by face: no per-face temporaries (the arrays of a vectorised version took a
    tenth of a drape's memory). The products are taken in the order the vectorised version took them."""
    one = wind.shape[0] == 1
    for t in range(faces.shape[0]):
        a, b, c = faces[t, 0], faces[t, 1], faces[t, 2]
        e1 = x[b] - x[a]
        e2 = x[c] - x[a]
        n0 = e1[1] * e2[2] - e1[2] * e2[1]
        n1 = e1[2] * e2[0] - e1[0] * e2[2]
        n2 = e1[0] * e2[1] - e1[1] * e2[0]
        area2 = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        if area2 == 0.0:
            continue
        n0, n1, n2 = n0 / area2, n1 / area2, n2 / area2
        w = wind[0] if one else wind[t]
        vn = (((v[a, 0] + v[b, 0] + v[c, 0]) / 3.0 - w[0]) * n0 + ((v[a, 2] + v[b, 2] + v[c, 2]) / 3.0 - w[2]) * n2
              + ((v[a, 1] + v[b, 1] + v[c, 1]) / 3.0 - w[1]) * n1)  # in the order NumPy's einsum sums them
        n = (n0, n1, n2)
        if force.shape[0]:
            mag = coefficient * (0.5 * area2) * vn * abs(vn) / 3.0
            for k in range(3):
                for i in range(3):
                    force[faces[t, k], i] += n[i] * mag
        if damping.shape[0]:
            drag = coefficient * (0.5 * area2) * abs(vn) / 3.0
            for k in range(3):
                for i in range(3):
                    for j in range(3):
                        damping[faces[t, k], i, j] += drag * n[i] * n[j]
