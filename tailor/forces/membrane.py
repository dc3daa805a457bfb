"""Carignan's elastic surface on triangles: stretch (Eq. 4a) and strain-rate damping (Eq. 2, 4b).

Each triangle is a patch of the continuum of Eq. 1 with material coordinates a = (a₁, a₂) along
warp and weft (its grain frame, in metres of rest fabric). Its deformation gradient is
F = [∂r/∂a₁, ∂r/∂a₂] = [x₁ − x₀, x₂ − x₀]·Dm⁻¹, the metric G = FᵀF, and the rest metric G⁰ = I.
With the Lagrangian (Green) strain E = ½(G − G⁰) the stretch energy of a triangle of rest area A is

    W = A · ½ (η₁₁E₁₁² + η₂₂E₂₂² + 2η₁₂E₁₂²)          (Eq. 1 second term, Eq. 4a)

and the Rayleigh dissipation of the strain rate Ė = ½(ḞᵀF + FᵀḞ) (Eq. 2) is

    D = A · ½ (φ₁₁Ė₁₁² + φ₂₂Ė₂₂² + 2φ₁₂Ė₁₂²)          (Eq. 1 third term, Eq. 4b)

whose force −∂D/∂v vanishes for any rigid motion (Ė = 0), as Carignan designed it: a falling
cloth is not slowed down by its own damping. Forces are −∂W/∂x and −∂D/∂v, vectorised over faces.
"""

from __future__ import annotations

import numpy as np

from .kernels import face_stretch_into, green_strain_into

__all__ = [
    "deformation_gradient",
    "green_strain",
    "stretch_energy",
    "stretch_forces",
    "damping_forces",
    "dissipation",
    "membrane_gradients",
    "stretch_stiffness",
]


def _columns(model, x):
    f = model.faces
    x0 = x[f[:, 0]]
    d1 = x[f[:, 1]] - x0
    d2 = x[f[:, 2]] - x0
    dm = model.face_dm_inv
    c1 = d1 * dm[:, 0, 0, None] + d2 * dm[:, 1, 0, None]
    c2 = d1 * dm[:, 0, 1, None] + d2 * dm[:, 1, 1, None]
    return c1, c2


def deformation_gradient(model, x) -> np.ndarray:
    """F = ∂r/∂a of each triangle, shape (F, 3, 2): columns along warp and weft [dimensionless]."""
    c1, c2 = _columns(model, x)
    return np.stack([c1, c2], axis=2)


def face_stretch(model, x) -> np.ndarray:
    """Largest principal stretch of each triangle (1 = rest), shape (F,): the root of the larger
    eigenvalue of the right Cauchy–Green tensor FᵀF (compiled: the implicit step checks it every
    step)."""
    out = np.empty(model.face_count)
    face_stretch_into(np.ascontiguousarray(x, dtype=float), model.faces, model.face_dm_inv, out)
    return out


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def green_strain(model, x):
    """(E₁₁, E₂₂, E₁₂) of each triangle, three arrays of shape (F,) (compiled: the implicit step's
    compression-softened stiffness asks for it every step)."""
    out = np.empty((3, model.face_count))
    green_strain_into(np.ascontiguousarray(x, dtype=float), model.faces, model.face_dm_inv, *out)
    return out[0], out[1], out[2]


def stretch_stiffness(model, e11, e22):
    """(η₁₁, η₂₂, η₁₂) per face [N/m] at strains E₁₁, E₂₂: the model's, softened where compressed.

    With ``model.compression`` = c < 1 a shortened warp or weft (E < 0) resists with c·η: the
    energy ½cηE² joins ½ηE² with equal slope at E = 0, so forces stay continuous and remain its
    exact gradient. Woven cloth shortened along a yarn buckles out of plane (bending takes over)
    long before the yarns compress, which is what lets a gathered seam or an eased waist fold.
    """
    k1, k2, k12 = model.face_stretch_warp, model.face_stretch_weft, model.face_stretch_shear
    if model.compression < 1.0:
        k1 = np.where(e11 < 0.0, model.compression * k1, k1)
        k2 = np.where(e22 < 0.0, model.compression * k2, k2)
    return k1, k2, k12


def stretch_energy(model, state) -> float:
    """Elastic stretch energy Σ A·½(η₁₁E₁₁² + η₂₂E₂₂² + 2η₁₂E₁₂²) [J]."""
    e11, e22, e12 = green_strain(model, state.x)
    k1, k2, k12 = stretch_stiffness(model, e11, e22)
    w = k1 * e11**2 + k2 * e22**2 + 2.0 * k12 * e12**2
    return float(0.5 * np.dot(model.face_rest_area, w))


def _scatter_stress(model, c1, c2, s11, s22, s12, out):
    """Add the nodal forces −A·P·Dm⁻ᵀ of stresses S (second Piola–Kirchhoff) into ``out``."""
    a = model.face_rest_area[:, None]
    p1 = c1 * s11[:, None] + c2 * s12[:, None]
    p2 = c1 * s12[:, None] + c2 * s22[:, None]
    dm = model.face_dm_inv
    g1 = a * (p1 * dm[:, 0, 0, None] + p2 * dm[:, 0, 1, None])
    g2 = a * (p1 * dm[:, 1, 0, None] + p2 * dm[:, 1, 1, None])
    f = model.faces
    n = len(out)
    for k in range(3):
        w0 = g1[:, k] + g2[:, k]
        out[:, k] += (
            np.bincount(f[:, 0], w0, minlength=n)
            - np.bincount(f[:, 1], g1[:, k], minlength=n)
            - np.bincount(f[:, 2], g2[:, k], minlength=n)
        )
    return out


def stretch_forces(model, state, out=None) -> np.ndarray:
    """−∂W/∂x [N], shape (N, 3); added into ``out`` when given."""
    out = np.zeros_like(state.x) if out is None else out
    c1, c2 = _columns(model, state.x)
    e11 = 0.5 * (_dot(c1, c1) - 1.0)
    e22 = 0.5 * (_dot(c2, c2) - 1.0)
    e12 = 0.5 * _dot(c1, c2)
    k1, k2, k12 = stretch_stiffness(model, e11, e22)
    return _scatter_stress(model, c1, c2, k1 * e11, k2 * e22, k12 * e12, out)


def _strain_rate(model, c1, c2, v):
    r1, r2 = _columns(model, v)
    return _dot(c1, r1), _dot(c2, r2), 0.5 * (_dot(c1, r2) + _dot(r1, c2))


def dissipation(model, state) -> float:
    """Rayleigh dissipation function D = Σ A·½(φ₁₁Ė₁₁² + φ₂₂Ė₂₂² + 2φ₁₂Ė₁₂²) [W]; 2D is the power lost."""
    c1, c2 = _columns(model, state.x)
    r11, r22, r12 = _strain_rate(model, c1, c2, state.v)
    w = model.face_damping_warp * r11**2 + model.face_damping_weft * r22**2 + 2.0 * model.face_damping_shear * r12**2
    return float(0.5 * np.dot(model.face_rest_area, w))


def damping_forces(model, state, out=None) -> np.ndarray:
    """−∂D/∂v [N], shape (N, 3): zero for rigid motion; added into ``out`` when given."""
    out = np.zeros_like(state.x) if out is None else out
    c1, c2 = _columns(model, state.x)
    r11, r22, r12 = _strain_rate(model, c1, c2, state.v)
    return _scatter_stress(
        model, c1, c2, model.face_damping_warp * r11, model.face_damping_weft * r22, model.face_damping_shear * r12, out
    )


def membrane_gradients(model, x):
    """Per-face gradients of (E₁₁, E₂₂, E₁₂) w.r.t. the 9 corner coordinates, and the stresses.

    Returns ``grads`` (F, 3, 9), ``weights`` (F, 3, 2) (corner weights of the two material
    directions, for the geometric stiffness) and ``stress`` (F, 2, 2) (S of Eq. 4a). Used by the
    implicit integrator to assemble a positive semi-definite stiffness (Gauss–Newton material
    term plus the geometric term with compressive stress clamped to zero).
    """
    c1, c2 = _columns(model, x)
    dm = model.face_dm_inv
    w1 = np.stack([-(dm[:, 0, 0] + dm[:, 1, 0]), dm[:, 0, 0], dm[:, 1, 0]], axis=1)  # (F, 3)
    w2 = np.stack([-(dm[:, 0, 1] + dm[:, 1, 1]), dm[:, 0, 1], dm[:, 1, 1]], axis=1)
    g11 = w1[:, :, None] * c1[:, None, :]
    g22 = w2[:, :, None] * c2[:, None, :]
    g12 = 0.5 * (w1[:, :, None] * c2[:, None, :] + w2[:, :, None] * c1[:, None, :])
    grads = np.stack([g11.reshape(-1, 9), g22.reshape(-1, 9), g12.reshape(-1, 9)], axis=1)
    e11 = 0.5 * (_dot(c1, c1) - 1.0)
    e22 = 0.5 * (_dot(c2, c2) - 1.0)
    e12 = 0.5 * _dot(c1, c2)
    k1, k2, k12 = stretch_stiffness(model, e11, e22)
    stress = np.empty((len(c1), 2, 2))
    stress[:, 0, 0] = k1 * e11
    stress[:, 1, 1] = k2 * e22
    stress[:, 0, 1] = stress[:, 1, 0] = k12 * e12
    return grads, np.stack([w1, w2], axis=2), stress
