"""Building a :class:`~.data.Model` from a discretised pattern and its fabric(s), once.

Rest geometry in each triangle's grain frame, lumped masses (Carignan Eq. 21), per-face stretch
and damping coefficients (Eq. 22, 26), bending hinges (Eq. 25), springs for Walker's alternative
model, the stable explicit step (Eq. 24), gravity and air; seams welded (Eq. 16–18).
"""

from __future__ import annotations

import numpy as np

from ..errors import FabricError
from ..fabric import Fabric
from ..geometry import face_areas, hinge_angle_gradients, hinge_angles, unique_edges
from ..mesh import GarmentMesh
from ..params import SAFETY, element_frequencies, fabric_params, stable_time_step, symplectic_limit
from ..topology import hinges
from ..units import GRAVITY
from .data import ELASTIC_MODELS, Model, _frozen

__all__ = ["build_model"]


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
    """
    _check_options(elastic, compression, damping)
    panel_count = len(mesh.panel_names)
    fabrics = fabric if isinstance(fabric, dict) else {i: fabric for i in range(panel_count)}
    uv, faces = np.asarray(mesh.uv, float), np.asarray(mesh.faces, np.intp)
    area = face_areas(uv, faces)
    params = tuple(fabric_params(fabrics[i], mesh.resolution, safety=safety) for i in range(panel_count))
    fp = mesh.face_panel
    curves = tuple(fabrics[i].kawabata for i in range(panel_count))
    rho, rigidity, (k1, k2, k12), k_fast = _face_stiffness(params, curves, fp)
    mass = np.bincount(faces.reshape(-1), weights=np.repeat(rho * area / 3.0, 3), minlength=len(uv))
    hv, hf, e_len2, hinge_b, hinge_k, curvature_scale = _hinge_stiffness(uv, faces, area, rigidity, fp)
    springs, ks, rest, kd, omega_springs = _springs(uv, faces, fp, hv, hf, area, k1, k2, rigidity, mass, damping, elastic)
    dm_inv = _grain_frame_dm_inv(uv, faces, np.asarray(mesh.face_grain, float))
    omega_face = element_frequencies(dm_inv, area, rho, *k_fast)
    dt = _stable_step(uv, faces, area, params, safety, damping, omega_springs if elastic == "springs" else
                      float(np.max(omega_face, initial=0.0)), _bending_frequency(uv, hv, hinge_k, mass), mesh.resolution)
    faces_out, uv_out, mass_out = faces, uv, mass
    if weld is not None:
        weld = np.asarray(weld, np.intp)
        factor = _hinge_factors(panel_count, fp, hf, hinge_b, e_len2, area, hinge_k)
        faces_out, uv_out, mass_out, hv, hf, hinge_k, curvature_scale, springs, ks, rest, kd = _welded(
            weld, uv, faces, fp, mass, area, rigidity, factor, springs, ks, rest, kd
        )
    pin_mask = np.zeros(len(mass_out), bool)
    if pinned is not None:
        pin_mask[np.asarray(pinned)] = True
    arrays = dict(rest_uv=uv_out, faces=faces_out, face_panel=fp, vertex_mass=mass_out, vertex_pinned=pin_mask,
                  face_rest_area=area, face_dm_inv=dm_inv, face_stretch_warp=k1, face_stretch_weft=k2,
                  face_stretch_shear=k12, face_damping_warp=damping * 2.0 * k1 / omega_face,
                  face_damping_weft=damping * 2.0 * k2 / omega_face, face_damping_shear=damping * 2.0 * k12 / omega_face,
                  hinge_vertices=hv, hinge_rest_angle=np.zeros(len(hv)), hinge_stiffness=hinge_k,
                  hinge_panel=fp[hf[:, 0]] if len(hf) else np.zeros(0, np.intp), hinge_curvature_scale=curvature_scale,
                  spring_vertices=springs, spring_rest_length=rest, spring_stiffness=ks, spring_damping=kd,
                  gravity=np.asarray(gravity, float))
    return Model(**{k: _frozen(v) for k, v in arrays.items()}, air_density=float(air_density),
                 drag_coefficient=float(drag_coefficient), time_step=float(dt), elastic=elastic, params=params,
                 curves=curves, compression=float(compression))


def _bending_frequency(uv, hv, hinge_k, mass):
    """Gershgorin bound on the fastest bending frequency [rad/s] of the flat rest mesh."""
    if not len(hv) or not np.any(hinge_k > 0):
        return 0.0
    x = np.column_stack([uv, np.zeros(len(uv))])
    g = np.abs(hinge_angle_gradients(x, hv)[:, :, 2]) / np.sqrt(mass[hv])  # out-of-plane, mass-scaled
    row = g * (hinge_k * g.sum(axis=1))[:, None]
    bound = np.bincount(hv.reshape(-1), row.reshape(-1), minlength=len(uv))
    return float(np.sqrt(bound.max()))


def _check_options(elastic, compression, damping) -> None:
    if elastic not in ELASTIC_MODELS:
        raise ValueError(f"elastic model must be one of {ELASTIC_MODELS}, got {elastic!r}")
    if not 0.0 < compression <= 1.0:
        raise ValueError(f"compression must be in (0, 1], got {compression!r}")
    if not damping >= 0:
        raise FabricError(f"damping must be >= 0, got {damping!r}")


def _face_stiffness(params, curves, fp):
    """Per face: density, bending rigidity, (warp, weft, shear) stiffness at rest and the stiffest
    slopes of a Kawabata curve (for damping and the time step)."""

    def per_face(name):
        return np.array([getattr(p, name) for p in params])[fp]

    k1, k2, k12 = per_face("stretch_warp"), per_face("stretch_weft"), per_face("stretch_shear")
    k_fast = [k1.copy(), k2.copy(), k12.copy()]
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
    return per_face("density"), per_face("bending_rigidity"), (k1, k2, k12), k_fast


def _hinge_stiffness(uv, faces, area, rigidity, fp):
    """Hinges (vertices, faces), their squared rest lengths, mean rigidity, calibrated stiffness and
    curvature scale (Eq. 3–4 on the discrete surface)."""
    hv, hf = hinges(faces)
    e_len2 = np.sum((uv[hv[:, 0]] - uv[hv[:, 1]]) ** 2, axis=1)
    hinge_b = 0.5 * (rigidity[hf[:, 0]] + rigidity[hf[:, 1]])  # panels may differ across a seam
    hinge_k = _calibrated_hinge_stiffness(uv, faces, hv, hf, hinge_b * e_len2 / (area[hf[:, 0]] + area[hf[:, 1]]), rigidity, area, fp)
    pair_area = area[hf[:, 0]] + area[hf[:, 1]]
    with np.errstate(invalid="ignore", divide="ignore"):
        curvature_scale = np.where(hinge_b > 0, np.sqrt(3.0 * hinge_k / np.maximum(hinge_b, 1e-300) / pair_area), 3.0 * np.sqrt(e_len2) / pair_area)
    return hv, hf, e_len2, hinge_b, hinge_k, curvature_scale


def _springs(uv, faces, fp, hv, hf, area, k1, k2, rigidity, mass, damping, elastic):
    """Walker's net (springs, stiffness, rest length), its dampers critical for its fastest frequency
    (Eq. 26) and that frequency; none for the membrane (``elastic``), which never reads it (it took
    a fifth of a garment model's memory)."""
    if elastic != "springs":
        return np.zeros((0, 2), np.intp), np.zeros(0), np.zeros(0), np.zeros(0), 0.0
    n = len(uv)
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
    return springs, ks, rest, kd, omega_springs


def _stable_step(uv, faces, area, params, safety, damping, omega_elastic, omega_bend, resolution) -> float:
    """Eq. 24's step on the mesh's smallest altitude, never above the exact stability bound of
    symplectic Euler for the fastest damped mode."""
    tri = uv[faces]
    longest = np.max(np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2), axis=1)
    altitude = float(np.min(2.0 * area / longest)) if len(faces) else resolution
    dt = min(
        stable_time_step(p.density, max(p.stretch_warp, p.stretch_weft), p.bending_rigidity, altitude, safety=safety)
        for p in params
    )
    omega_max = float(np.sqrt(omega_elastic**2 + omega_bend**2))
    if omega_max > 0:
        dt = min(dt, 0.9 * symplectic_limit(damping) / omega_max)
    return dt


def _hinge_factors(panel_count, fp, hf, hinge_b, e_len2, area, hinge_k):
    """Per panel, the median calibration of its hinges (new hinges across a weld get their panel's)."""
    factor = np.ones(panel_count)
    base = hinge_b * e_len2 / (area[hf[:, 0]] + area[hf[:, 1]])
    for pi in range(panel_count):
        sel = (fp[hf[:, 0]] == pi) & (base > 0)
        if sel.any():
            factor[pi] = float(np.median(hinge_k[sel] / base[sel]))
    return factor
