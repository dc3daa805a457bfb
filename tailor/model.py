"""Model (fixed) and State (moving): the simulator's data, as struct-of-arrays numpy.

:func:`build_model` turns a discretised pattern and its fabric(s) into a :class:`Model` once:
rest geometry in each triangle's grain frame, lumped masses (Carignan Eq. 21), per-face
stretch and damping coefficients (Eq. 22, 26), bending hinges (Eq. 25), springs for Walker's
alternative model, gravity and air. A :class:`State` holds positions, velocities and time.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .errors import FabricError
from .fabric import Fabric
from .geometry import face_areas, hinge_angle_gradients, hinge_angles, unique_edges
from .mesh import GarmentMesh
from .params import SAFETY, element_frequencies, fabric_params, stable_time_step, symplectic_limit
from .topology import hinges
from .units import GRAVITY

__all__ = ["Model", "State", "build_model", "ELASTIC_MODELS", "AIR_DENSITY"]

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
        Walker's structural, shear and flexion springs (used when ``elastic == "springs"``),
        stiffness calibrated to the membrane's energy, dampers critical for the net's fastest mode.
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


def _grain_frame_dm_inv(uv, faces, grain):
    """Inverse rest edge matrices in each face's (warp, weft) frame, shape (F, 2, 2)."""
    weft = np.column_stack([-grain[:, 1], grain[:, 0]])
    p = uv[faces]  # (F, 3, 2)
    d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    dm = np.empty((len(faces), 2, 2))
    dm[:, 0, 0] = np.einsum("ij,ij->i", d1, grain)
    dm[:, 1, 0] = np.einsum("ij,ij->i", d1, weft)
    dm[:, 0, 1] = np.einsum("ij,ij->i", d2, grain)
    dm[:, 1, 1] = np.einsum("ij,ij->i", d2, weft)
    return np.linalg.inv(dm)


def _walker_springs(uv, faces, hv, hf, face_stretch, face_rigidity):
    """Walker's springs on a triangle mesh, each pair once (Walker §3.4–3.6).

    Structural and shear springs are the mesh edges (a triangle mesh has no separate diagonals);
    flexion springs join the two far corners of every hinge (two elements apart), and only exist
    where the fabric resists bending. Stiffness: Walker Eq. 1 with k = η for a spring carrying a
    strip as wide as it is long (so the net stretches like the membrane of Eq. 22).

    Returns (pairs (S, 2), stiffness (S,) [N/m], rest length (S,) [m]).
    """
    structural = unique_edges(faces)
    n = len(uv)
    incident = np.bincount(faces.reshape(-1), minlength=n)
    k_vertex = np.bincount(faces.reshape(-1), weights=np.repeat(face_stretch, 3), minlength=n) / np.maximum(incident, 1)
    k_struct = 0.5 * (k_vertex[structural[:, 0]] + k_vertex[structural[:, 1]])
    bend = face_rigidity[hf[:, 0]] + face_rigidity[hf[:, 1]] > 0 if len(hf) else np.zeros(0, bool)
    flex = np.unique(np.sort(hv[bend][:, 2:4], axis=1), axis=0).reshape(-1, 2)
    k_flex = 0.5 * (k_vertex[flex[:, 0]] + k_vertex[flex[:, 1]])
    pairs = np.concatenate([structural, flex]).astype(np.intp)
    stiffness = np.concatenate([k_struct, k_flex])
    rest = np.linalg.norm(uv[pairs[:, 0]] - uv[pairs[:, 1]], axis=1)
    return pairs, stiffness, rest


def _max_slope(curve) -> float:
    xs = [0.0] + [p[0] for p in curve]
    ys = [0.0] + [p[1] for p in curve]
    return max((b - a) / (d - c) for a, b, c, d in zip(ys, ys[1:], xs, xs[1:]))


def _welded(weld, uv, faces, face_panel, mass, area, rigidity, factor, springs, ks, rest, kd):
    """Topology, masses, hinges and springs of the garment with welded vertices."""
    n = int(weld.max()) + 1
    faces_w = weld[faces]
    mass_w = np.bincount(weld, mass, minlength=n)
    first = np.full(n, -1, np.intp)
    first[weld[::-1]] = np.arange(len(weld))[::-1]
    uv_w = uv[first]
    hv, hf = hinges(faces_w)
    f0 = hf[:, 0]
    c0 = np.argmax(faces_w[f0] == hv[:, :1], axis=1)
    c1 = np.argmax(faces_w[f0] == hv[:, 1:2], axis=1)
    e_len2 = np.sum((uv[faces[f0, c0]] - uv[faces[f0, c1]]) ** 2, axis=1)  # rest length in its own panel
    pair_area = area[hf[:, 0]] + area[hf[:, 1]]
    hinge_b = 0.5 * (rigidity[hf[:, 0]] + rigidity[hf[:, 1]])
    hinge_k = factor[face_panel[f0]] * hinge_b * e_len2 / pair_area
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(hinge_b > 0, np.sqrt(3.0 * hinge_k / np.maximum(hinge_b, 1e-300) / pair_area), 3.0 * np.sqrt(e_len2) / pair_area)
    sp = weld[springs]
    keep = sp[:, 0] != sp[:, 1]
    sp, ks, rest, kd = sp[keep], ks[keep], rest[keep], kd[keep]
    sp = np.sort(sp, axis=1)
    _, unique = np.unique(sp, axis=0, return_index=True)
    return faces_w, uv_w, mass_w, hv, hf, hinge_k, scale, sp[unique], ks[unique], rest[unique], kd[unique]


def _calibrated_springs(uv, faces, face_panel, springs, ks, rest, area, face_stretch):
    """Scale each panel's springs so the net stores the membrane's energy under uniform stretch.

    Walker sets one spring strength by hand; here it follows from the fabric: a 1 % stretch of a
    panel along x and along y costs the net what it costs Carignan's membrane (Eq. 22), so the
    two elastic models hang alike.
    """
    ks = ks.copy()
    vertex_panel = np.zeros(len(uv), np.intp)
    vertex_panel[faces.reshape(-1)] = np.repeat(face_panel, 3)
    spring_panel = vertex_panel[springs[:, 0]]
    for pi in np.unique(face_panel):
        sel = spring_panel == pi
        faces_p = face_panel == pi
        membrane = net = 0.0
        for axis in (0, 1):
            strained = uv.copy()
            strained[:, axis] *= 1.01
            length = np.linalg.norm(strained[springs[sel, 0]] - strained[springs[sel, 1]], axis=1)
            net += 0.5 * np.dot(ks[sel], (length - rest[sel]) ** 2)
            green = 0.5 * (1.01**2 - 1.0)
            membrane += 0.5 * np.dot(face_stretch[faces_p], area[faces_p]) * green**2
        if net > 0:
            ks[sel] *= membrane / net
    return ks


def _calibrated_hinge_stiffness(uv, faces, hv, hf, base, rigidity, area, face_panel):
    """Hinge stiffness k = c·B|e|²/(A₀ + A₁), with c chosen per panel on its own rest mesh.

    The discrete-shell weight 3B|e|²/(A₀+A₁) is exact only for particular triangle shapes (it
    is off by a factor ≈ 1.8 on quality Delaunay meshes). So each panel's flat mesh is rolled onto
    a cylinder about its warp and about its weft, and c is set so that Σ½kθ² equals the continuum
    ½∫Bκ² dA of those bends. The bending stiffness then no longer depends on the mesher.
    """
    k = base.copy()
    if not len(hv):
        return k
    hinge_panel = face_panel[hf[:, 0]]
    for pi in np.unique(hinge_panel):
        sel = hinge_panel == pi
        faces_p = face_panel == pi
        if not np.any(rigidity[faces_p] > 0):
            continue
        size = float(np.ptp(uv[faces[faces_p]].reshape(-1, 2), axis=0).max())
        radius = 10.0 * max(size, 1e-6)
        discrete = continuum = 0.0
        for axis in (np.array([1.0, 0.0]), np.array([0.0, 1.0])):
            a, b = uv @ axis, uv @ np.array([-axis[1], axis[0]])
            x = np.column_stack([radius * np.sin(a / radius), b, radius * (1.0 - np.cos(a / radius))])
            theta = hinge_angles(x, hv[sel])
            discrete += 0.5 * np.dot(base[sel], theta**2)
            continuum += 0.5 * np.dot(rigidity[faces_p], area[faces_p]) / radius**2
        if discrete > 0:
            k[sel] *= continuum / discrete
    return k


def build_model(
    mesh: GarmentMesh,
    fabric: Fabric | dict,
    *,
    elastic: str = "membrane",
    gravity=(0.0, 0.0, -GRAVITY),
    air_density: float = 0.0,
    drag_coefficient: float = 1.0,
    damping: float = 1.0,
    safety: float = SAFETY,
    pinned=None,
    weld=None,
    compression: float = 1.0,
) -> Model:
    """Build the fixed simulation model of a discretised garment.

    Parameters
    ----------
    mesh : GarmentMesh
        Panels from :func:`tailor.mesh.discretise`.
    fabric : Fabric or dict
        One fabric, or ``{panel index: Fabric}`` for every panel.
    elastic : {"membrane", "springs"}
        Carignan's elastic surface (default) or Walker's mass-spring model. Springs on an
        irregular triangulation are locally soft where triangles are thin (near boundaries): the
        membrane is the accurate model, the net the classic fast one.
    gravity : (3,) [m/s²]
    pair_vertices : (P, 2) int; pair_stiffness (P,) [N/m]; pair_damping (P,) [N·s/m]
        Zero-length springs between vertex pairs (seams being closed), integrated implicitly.
    air_density : float [kg/m³]
        0 (default) = vacuum; :data:`AIR_DENSITY` for air drag.
    damping : float
        Multiple of Eq. 26's critical strain-rate damping (1 = critical per element, 0 = none).
    safety : float
        Eq. 24's l.
    pinned : bool mask or indices, optional
    weld : (N,) int, optional
        Index of each mesh vertex in a welded garment (sewn seams: Carignan Eq. 16–18). Welded
        vertices are one particle with the summed mass; each triangle keeps its panel's rest shape,
        and triangles that now meet across a seam get bending hinges there too.
    compression : float
        Fraction of the warp/weft stiffness acting in compression, in (0, 1].

    Returns
    -------
    Model
    """
    if elastic not in ELASTIC_MODELS:
        raise ValueError(f"elastic model must be one of {ELASTIC_MODELS}, got {elastic!r}")
    if not 0.0 < compression <= 1.0:
        raise ValueError(f"compression must be in (0, 1], got {compression!r}")
    if not damping >= 0:
        raise FabricError(f"damping must be >= 0, got {damping!r}")
    panel_count = len(mesh.panel_names)
    fabrics = fabric if isinstance(fabric, dict) else {i: fabric for i in range(panel_count)}
    uv, faces = np.asarray(mesh.uv, float), np.asarray(mesh.faces, np.intp)
    area = face_areas(uv, faces)
    params = tuple(fabric_params(fabrics[i], mesh.resolution, safety=safety) for i in range(panel_count))
    fp = mesh.face_panel

    def per_face(name):
        return np.array([getattr(p, name) for p in params])[fp]

    rho = per_face("density")
    k1, k2, k12 = per_face("stretch_warp"), per_face("stretch_weft"), per_face("stretch_shear")
    curves = tuple(fabrics[i].kawabata for i in range(panel_count))
    k_fast = [k1.copy(), k2.copy(), k12.copy()]  # stiffest slopes, for damping and the time step
    for pi, c in enumerate(curves):
        if c is None:
            continue
        sel = fp == pi
        k1[sel] = c.initial_slope(c.tensile_warp)
        k2[sel] = c.initial_slope(c.tensile_weft)
        k12[sel] = 2.0 * c.initial_slope(c.shear)
        k_fast[0][sel] = _max_slope(c.tensile_warp)
        k_fast[1][sel] = _max_slope(c.tensile_weft)
        k_fast[2][sel] = 2.0 * _max_slope(c.shear)
    n = len(uv)
    mass = np.bincount(faces.reshape(-1), weights=np.repeat(rho * area / 3.0, 3), minlength=n)

    hv, hf = hinges(faces)
    rigidity = per_face("bending_rigidity")
    e_len2 = np.sum((uv[hv[:, 0]] - uv[hv[:, 1]]) ** 2, axis=1)
    hinge_b = 0.5 * (rigidity[hf[:, 0]] + rigidity[hf[:, 1]])  # panels may differ across a seam
    hinge_k = _calibrated_hinge_stiffness(uv, faces, hv, hf, hinge_b * e_len2 / (area[hf[:, 0]] + area[hf[:, 1]]), rigidity, area, fp)
    pair_area = area[hf[:, 0]] + area[hf[:, 1]]
    with np.errstate(invalid="ignore", divide="ignore"):
        curvature_scale = np.where(hinge_b > 0, np.sqrt(3.0 * hinge_k / np.maximum(hinge_b, 1e-300) / pair_area), 3.0 * np.sqrt(e_len2) / pair_area)

    springs, ks, rest = _walker_springs(uv, faces, hv, hf, np.maximum(k1, k2), rigidity)
    ks = _calibrated_springs(uv, faces, fp, springs, ks, rest, area, k1)
    # Gershgorin bound on the net's fastest frequency; Rayleigh dampers critical for it (Eq. 26)
    # rows of M^-1/2·K·M^-1/2: Σ k·(1/m_v + 1/√(m_v·m_u)) over the springs at v
    cross = ks / np.sqrt(mass[springs[:, 0]] * mass[springs[:, 1]])
    row = np.bincount(springs[:, 0], ks / mass[springs[:, 0]] + cross, minlength=n) + np.bincount(
        springs[:, 1], ks / mass[springs[:, 1]] + cross, minlength=n
    )
    omega_springs = float(np.sqrt(np.max(row, initial=0.0)))
    kd = damping * 2.0 * ks / max(omega_springs, 1e-300)

    dm_inv = _grain_frame_dm_inv(uv, faces, np.asarray(mesh.face_grain, float))
    omega_face = element_frequencies(dm_inv, area, rho, *k_fast)
    omega_bend = _bending_frequency(uv, hv, hinge_k, mass)
    tri = uv[faces]
    longest = np.max(np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2), axis=1)
    altitude = float(np.min(2.0 * area / longest)) if len(faces) else mesh.resolution
    dt = min(
        stable_time_step(p.density, max(p.stretch_warp, p.stretch_weft), p.bending_rigidity, altitude, safety=safety)
        for p in params
    )
    # never above the exact stability bound of symplectic Euler for the fastest damped mode
    omega_elastic = omega_springs if elastic == "springs" else float(np.max(omega_face, initial=0.0))
    omega_max = float(np.sqrt(omega_elastic**2 + omega_bend**2))
    if omega_max > 0:
        dt = min(dt, 0.9 * symplectic_limit(damping) / omega_max)
    faces_out, uv_out, mass_out = faces, uv, mass
    if weld is not None:
        weld = np.asarray(weld, np.intp)
        factor = np.ones(panel_count)
        base = hinge_b * e_len2 / (area[hf[:, 0]] + area[hf[:, 1]])
        for pi in range(panel_count):
            sel = (fp[hf[:, 0]] == pi) & (base > 0)
            if sel.any():
                factor[pi] = float(np.median(hinge_k[sel] / base[sel]))
        faces_out, uv_out, mass_out, hv, hf, hinge_k, curvature_scale, springs, ks, rest, kd = _welded(
            weld, uv, faces, fp, mass, area, rigidity, factor, springs, ks, rest, kd
        )
        n = len(mass_out)
    pin_mask = np.zeros(n, bool)
    if pinned is not None:
        pin_mask[np.asarray(pinned)] = True
    return Model(
        rest_uv=_frozen(uv_out),
        faces=_frozen(faces_out),
        face_panel=_frozen(fp),
        vertex_mass=_frozen(mass_out),
        vertex_pinned=_frozen(pin_mask),
        face_rest_area=_frozen(area),
        face_dm_inv=_frozen(dm_inv),
        face_stretch_warp=_frozen(k1),
        face_stretch_weft=_frozen(k2),
        face_stretch_shear=_frozen(k12),
        face_damping_warp=_frozen(damping * 2.0 * k1 / omega_face),
        face_damping_weft=_frozen(damping * 2.0 * k2 / omega_face),
        face_damping_shear=_frozen(damping * 2.0 * k12 / omega_face),
        hinge_vertices=_frozen(hv),
        hinge_rest_angle=_frozen(np.zeros(len(hv))),
        hinge_stiffness=_frozen(hinge_k),
        hinge_panel=_frozen(fp[hf[:, 0]] if len(hf) else np.zeros(0, np.intp)),
        hinge_curvature_scale=_frozen(curvature_scale),
        spring_vertices=_frozen(springs),
        spring_rest_length=_frozen(rest),
        spring_stiffness=_frozen(ks),
        spring_damping=_frozen(kd),
        gravity=_frozen(np.asarray(gravity, float)),
        air_density=float(air_density),
        drag_coefficient=float(drag_coefficient),
        time_step=float(dt),
        elastic=elastic,
        params=params,
        curves=curves,
        compression=float(compression),
    )


def _bending_frequency(uv, hv, hinge_k, mass):
    """Gershgorin bound on the fastest bending frequency [rad/s] of the flat rest mesh."""
    if not len(hv) or not np.any(hinge_k > 0):
        return 0.0
    x = np.column_stack([uv, np.zeros(len(uv))])
    g = np.abs(hinge_angle_gradients(x, hv)[:, :, 2]) / np.sqrt(mass[hv])  # out-of-plane, mass-scaled
    row = g * (hinge_k * g.sum(axis=1))[:, None]
    bound = np.bincount(hv.reshape(-1), row.reshape(-1), minlength=len(uv))
    return float(np.sqrt(bound.max()))
