"""Model (fixed) and State (moving): the simulator's data, as struct-of-arrays numpy."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["Model", "State", "ELASTIC_MODELS", "AIR_DENSITY"]

ELASTIC_MODELS = ("membrane", "springs")
"""``membrane``: Carignan's elastic surface (Eq. 1–4) on triangles; ``springs``: Walker's mass-spring net."""

AIR_DENSITY = 1.2
"""Density of air [kg/m³] used for drag and wind."""


def _frozen(a):
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Model:
    """Everything about a cloth that does not change during a run (SI units).

    Attributes
    ----------
    rest_uv : (N, 2) [m]
        Rest position of each vertex in its panel plane (also the UVs).
    faces : (F, 3) int
        Triangles.
    face_panel : (F,) int
        Panel index of each triangle.
    vertex_mass : (N,) [kg]
        Lumped mass, a third of each adjacent triangle's ρA (Eq. 21).
    vertex_pinned : (N,) bool
        Vertices held in place (infinite mass): integrators never move them.
    face_rest_area : (F,) [m²]
    face_dm_inv : (F, 2, 2) [1/m]
        Inverse of the rest edge matrix in the grain frame (columns: warp, weft), so the
        deformation gradient is ``[x1 − x0, x2 − x0] @ face_dm_inv``.
    face_stretch_warp, face_stretch_weft, face_stretch_shear : (F,) [N/m]
        η₁₁, η₂₂, η₁₂ (Eq. 22).
    face_damping_warp, face_damping_weft, face_damping_shear : (F,) [N·s/m]
        φ₁₁, φ₂₂, φ₁₂: strain-rate damping (Eq. 26), φ = 2η/ω_e, critical for each element's
        fastest mode (Carignan's γ = 2h√(mη) is 2η/ω with the single-mass ω = √(η/m)/h; here ω_e
        is the element's exact fastest frequency, so the mesh's noisiest mode is exactly critical).
    hinge_vertices : (B, 4) int
        ``[e0, e1, o0, o1]``: a shared edge and the two opposite vertices.
    hinge_rest_angle : (B,) [rad]
    hinge_panel : (B,) int
        Panel of each hinge's first triangle.
    hinge_curvature_scale : (B,) [1/m]
        κ = scale·|θ|: the curvature a hinge angle stands for (so that ½kθ² = ½Bκ²A).
    hinge_stiffness : (B,) [N·m]
        k = c·B·|e|²/(A₀ + A₁), c calibrated per panel so Σ ½k(θ − θ₀)² equals ½∫B·κ² dA on
        cylinders (Eq. 25).
    spring_vertices : (S, 2) int; spring_rest_length (S,) [m]; spring_stiffness (S,) [N/m];
    spring_damping : (S,) [N·s/m]
        Walker's structural, shear and flexion springs (built and used when ``elastic == "springs"``;
        none otherwise), stiffness calibrated to the membrane's energy, dampers critical for the
        net's fastest mode.
    gravity : (3,) [m/s²]
    pair_vertices : (P, 2) int; pair_stiffness (P,) [N/m]; pair_damping (P,) [N·s/m]
        Zero-length springs between vertex pairs (seams being closed), integrated implicitly.
    air_density : float [kg/m³]
        0 = vacuum (no drag, no wind).
    drag_coefficient : float
        Normal drag coefficient C_d of a cloth face.
    time_step : float [s]
        The explicit step of Eq. 24 for this mesh (smallest altitude, stiffest fabric), capped at 0.9×
        the exact symplectic-Euler stability bound of the fastest damped element mode.
    elastic : str
        One of :data:`ELASTIC_MODELS`.
    params : tuple of Params
        Derived parameters of each panel's fabric (for reports).
    curves : tuple of KawabataCurves or None
        Per panel, measured curves that replace the linear law (:mod:`tailor.forces.kawabata`).
    compression : float
        Fraction of the warp/weft stretch stiffness that resists compression (1 = Carignan's
        symmetric law; woven cloth buckles instead of shortening, so draping uses less).
    """

    rest_uv: np.ndarray
    faces: np.ndarray
    face_panel: np.ndarray
    vertex_mass: np.ndarray
    vertex_pinned: np.ndarray
    face_rest_area: np.ndarray
    face_dm_inv: np.ndarray
    face_stretch_warp: np.ndarray
    face_stretch_weft: np.ndarray
    face_stretch_shear: np.ndarray
    face_damping_warp: np.ndarray
    face_damping_weft: np.ndarray
    face_damping_shear: np.ndarray
    hinge_vertices: np.ndarray
    hinge_rest_angle: np.ndarray
    hinge_stiffness: np.ndarray
    hinge_panel: np.ndarray
    hinge_curvature_scale: np.ndarray
    spring_vertices: np.ndarray
    spring_rest_length: np.ndarray
    spring_stiffness: np.ndarray
    spring_damping: np.ndarray
    gravity: np.ndarray
    pair_vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.intp))
    pair_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    pair_damping: np.ndarray = field(default_factory=lambda: np.zeros(0))
    air_density: float = 0.0
    drag_coefficient: float = 1.0
    time_step: float = 1e-3
    elastic: str = "membrane"
    params: tuple = field(default=(), repr=False)
    curves: tuple = field(default=(), repr=False)
    compression: float = 1.0

    @property
    def vertex_count(self) -> int:
        """N."""
        return len(self.vertex_mass)

    @property
    def face_count(self) -> int:
        """F."""
        return len(self.faces)

    @property
    def has_bending(self) -> bool:
        """Whether any hinge resists bending (skip the pass when not)."""
        return bool(len(self.hinge_stiffness)) and bool(np.any(self.hinge_stiffness > 0))

    @property
    def has_curves(self) -> bool:
        """Whether any panel follows measured Kawabata curves."""
        return any(c is not None for c in self.curves)

    @property
    def strain_dependent(self) -> bool:
        """Whether the membrane stiffness depends on the strain (Kawabata curves or softer compression)."""
        return self.has_curves or self.compression < 1.0

    @property
    def total_mass(self) -> float:
        """[kg]."""
        return float(self.vertex_mass.sum())

    def with_pairs(self, pairs, stiffness, damping) -> "Model":
        """A copy with zero-length pair springs (``pairs`` (P, 2), stiffness [N/m], damping [N·s/m])."""
        return replace(self, pair_vertices=_frozen(np.asarray(pairs, np.intp).reshape(-1, 2)),
                       pair_stiffness=_frozen(np.asarray(stiffness, float)), pair_damping=_frozen(np.asarray(damping, float)))

    def with_pins(self, pinned) -> "Model":
        """A copy with ``pinned`` (bool mask or indices) held in place."""
        mask = np.zeros(self.vertex_count, bool)
        mask[np.asarray(pinned)] = True
        return replace(self, vertex_pinned=_frozen(mask))

    def prefix(self, count: int) -> "Model":
        """The model of its first ``count`` vertices: every triangle, hinge, spring and pair among
        them, nothing joining them to the rest (an outfit's garments inside the one sewing, its
        outer garments left out until their stage). A triangle joining the two parts may only join
        pinned vertices of the first to the rest (the forces it drops move nothing)."""
        count = int(count)
        if count >= self.vertex_count:
            return self
        faces = np.all(self.faces < count, axis=1)
        hinges = np.all(self.hinge_vertices < count, axis=1)
        springs = np.all(self.spring_vertices < count, axis=1)
        pairs = np.all(self.pair_vertices < count, axis=1)
        joining = self.faces[~faces & np.any(self.faces < count, axis=1)]
        if not self.vertex_pinned[joining[joining < count]].all():
            raise ValueError(f"a triangle joins the first {count} vertices to the rest: they cannot be simulated apart")
        fields = {name: getattr(self, name)[faces] for name in (
            "faces", "face_panel", "face_rest_area", "face_dm_inv", "face_stretch_warp", "face_stretch_weft",
            "face_stretch_shear", "face_damping_warp", "face_damping_weft", "face_damping_shear")}
        fields.update({name: getattr(self, name)[hinges] for name in (
            "hinge_vertices", "hinge_rest_angle", "hinge_stiffness", "hinge_panel", "hinge_curvature_scale")})
        fields.update({name: getattr(self, name)[springs] for name in (
            "spring_vertices", "spring_rest_length", "spring_stiffness", "spring_damping")})
        fields.update({name: getattr(self, name)[pairs] for name in ("pair_vertices", "pair_stiffness", "pair_damping")})
        fields.update({name: getattr(self, name)[:count] for name in ("rest_uv", "vertex_mass", "vertex_pinned")})
        return replace(self, **{name: _frozen(a) for name, a in fields.items()})

    def state(self, x, v=None, t: float = 0.0) -> "State":
        """A State of this model at positions ``x`` [m] (velocities default to rest)."""
        x = np.array(x, dtype=float)
        if x.shape != (self.vertex_count, 3):
            raise ValueError(f"positions must have shape ({self.vertex_count}, 3), got {x.shape}")
        v = np.zeros_like(x) if v is None else np.array(v, dtype=float)
        return State(x, v, float(t))


@dataclass(slots=True)
class State:
    """What moves: positions ``x`` (N, 3) [m], velocities ``v`` (N, 3) [m/s], time ``t`` [s]."""

    x: np.ndarray
    v: np.ndarray
    t: float = 0.0

    def copy(self) -> "State":
        """An independent copy."""
        return State(self.x.copy(), self.v.copy(), self.t)
