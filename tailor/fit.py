"""Fit maps: how a draped garment fits, as a designer reads it (strain, pressure, gap and ease).

**Stretch** (per face). The deformation gradient of a face from its flat pattern shape to 3D,
F = Ds·Dm⁻¹ (Dm its edges in the pattern, the OBJ's UVs in metres; Ds the same edges in 3D), is
the map Carignan's membrane energy measures (Eq. 2–3 act on the metric FᵀF). Its largest
singular value λ gives ``stretch_max`` = 100·(λ − 1) %, and the length of F·g for the panel's
grain g (and its normal in the pattern plane) gives ``stretch_warp`` (``stretch_weft``).

**Contact** (per vertex). The force the body's contact exerts on the garment, normal and friction
(Carignan Eq. 9–14 and the implicit solve's held contacts), averaged over the steps of the frame
(:class:`~tailor.contact.ContactLoads`); ``pressure_kpa`` is its part along the body's outward
normal over the vertex's share of the garment's area; ``gap_mm`` the signed distance to the body.

**Ease** (per landmark the garment covers). The girth of the garment cut by the landmark's plane
(the convex hull of the cut: a tape measure round the garment) less the body's girth in the same
plane, in cm: the number a pattern maker works with. The garment's cut points are those nearer the
landmark's own outline than any other part of the body in that plane (a sleeve is not counted in
the bust), and the landmark counts as covered only if they go all round it.

Sources: a :class:`~tailor.dress.DrapeResult` in memory (:meth:`FitSource.of_drape`) or a run folder
written by ``tailor drape`` (:meth:`FitSource.of_run`: its OBJ frames, ``loads.npz`` and
``report.json``). Writing the maps to files is :mod:`tailor.io.fit_files`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .collide import body_gap
from .errors import BodyError, TailorError
from .geometry import face_areas

__all__ = ["FitMap", "FitSource", "Ease", "fit_map", "fit_section", "face_stretch", "body_gap", "landmark_ease",
           "EASE_LANDMARKS", "vertex_field", "VERTEX_FIELDS"]

EASE_LANDMARKS = ("bust", "waist", "hips", "left_upper_arm", "right_upper_arm", "left_thigh", "right_thigh")
"""Landmarks whose ease a fit map reports (where the garment covers them)."""

EASE_REACH = 0.15
"""Garment cut points farther than this [m] from the landmark's outline are not round it."""

EASE_MAX_OPENING = math.radians(60.0)
"""A landmark is covered when the garment's cut round it leaves no opening wider than this angle."""


@dataclass(frozen=True)
class Ease:
    """Girths [m] at one landmark on one frame: the garment's, the body's, and their difference."""

    landmark: str
    garment: float
    body: float
    faces: np.ndarray = field(default_factory=lambda: np.zeros(0, np.intp), compare=False)
    """The garment faces the cut crosses round the landmark (for the stretch and pressure there)."""

    @property
    def ease(self) -> float:
        return self.garment - self.body

    def as_dict(self) -> dict:
        return {"garment_cm": round(self.garment * 100, 2), "body_cm": round(self.body * 100, 2),
                "ease_cm": round(self.ease * 100, 2)}


@dataclass(frozen=True)
class FitMap:
    """The fit of one frame: per face stretch [%], per vertex loads [N], pressure [kPa] and gap [mm].

    ``wearable`` is each panel's fabric's wearable stretch [%]; ``ease`` maps landmark names to
    :class:`Ease` (the landmarks the garment covers); ``notes`` say what could not be measured.
    """

    frame: int
    positions: np.ndarray
    faces: np.ndarray
    face_group: np.ndarray
    group_names: tuple
    rest_area: np.ndarray
    stretch_max: np.ndarray
    stretch_warp: np.ndarray
    stretch_weft: np.ndarray
    contact_force: np.ndarray
    attachment_force: np.ndarray
    pressure_kpa: np.ndarray
    gap_mm: np.ndarray
    wearable: np.ndarray
    ease: dict = field(default_factory=dict)
    notes: tuple = ()

    def panel_rows(self) -> list[dict]:
        """Per panel: max and 95th-percentile stretch [%], share of its area over its fabric's
        wearable stretch [%], and the largest pressure on its vertices [kPa]."""
        rows = []
        for g, name in enumerate(self.group_names):
            sel = self.face_group == g
            if not sel.any():
                continue
            s, area = self.stretch_max[sel], self.rest_area[sel]
            over = float(area[s > self.wearable[g]].sum() / max(area.sum(), 1e-300))
            verts = np.unique(self.faces[sel])
            rows.append({"panel": name, "stretch_max_pct": round(float(s.max()), 2),
                         "stretch_p95_pct": round(float(np.percentile(s, 95)), 2),
                         "wearable_stretch_pct": round(float(self.wearable[g]), 2),
                         "over_wearable_pct": round(100 * over, 2),
                         "max_pressure_kpa": round(float(self.pressure_kpa[verts].max()), 3)})
        return rows

    def at_landmark(self, name: str) -> dict:
        """Ease [cm] at a landmark the garment covers, with the mean stretch [%] of the garment faces
        its cut crosses and the mean contact pressure [kPa] on their vertices."""
        e = self.ease[name]
        verts = np.unique(self.faces[e.faces])
        return {**e.as_dict(), "stretch_pct": round(float(self.stretch_max[e.faces].mean()), 2),
                "pressure_kpa": round(float(self.pressure_kpa[verts].mean()), 4)}

    def summary(self) -> dict:
        """The frame's fit as report.json holds it."""
        return {"frame": self.frame, "panels": self.panel_rows(),
                "ease": {k: self.at_landmark(k) for k in self.ease},
                "contact_force_n": [round(float(v), 4) for v in self.contact_force.sum(axis=0)],
                "attachment_force_n": [round(float(v), 4) for v in self.attachment_force.sum(axis=0)],
                "max_pressure_kpa": round(float(self.pressure_kpa.max(initial=0.0)), 3),
                **({"notes": list(self.notes)} if self.notes else {})}


class BodyFrames:
    """Where the body is at each frame of a drape: its written frames, or a body re-read.

    ``frames`` (F, M, 3) with ``faces``; or ``body`` (:class:`~tailor.body.Body`) sampled at
    ``(k − offset) / fps`` for frame k (frames before ``offset``, sewing and settling, in its rest pose).
    """

    def __init__(self, frames=None, faces=None, body=None, offset: int = 0, fps: float = 25.0):
        self.frames, self.faces, self.body, self.offset, self.fps = frames, faces, body, offset, fps

    def at(self, k: int):
        """(vertices, faces) of the body at frame ``k``; None if no body is known."""
        if self.frames is not None:
            return np.asarray(self.frames[k]), np.asarray(self.faces)
        if self.body is None:
            return None
        b = self.body
        if k < self.offset or b.frame_count == 1:
            return (b.rest if b.rest is not None else b.frames[0]), np.asarray(b.faces)
        return b.at((k - self.offset) / self.fps)[0], np.asarray(b.faces)


@dataclass(frozen=True)
class FitSource:
    """What fit maps are made of: the drape as an :class:`~tailor.io.animation.Animation` (with its
    loads), each panel's grain [rad] and wearable stretch [%], and the body per frame."""

    anim: object
    grain: np.ndarray
    wearable: np.ndarray
    bodies: BodyFrames
    notes: tuple = ()

    @classmethod
    def of_drape(cls, result) -> "FitSource":
        """The fit source of a :class:`~tailor.dress.DrapeResult`."""
        from .io.animation import animation_from_drape

        anim = animation_from_drape(result, with_body=True)
        grain, wearable = _panel_values(result.report.panels, anim.group_names)
        return cls(_with_loads(anim, []), grain, wearable, BodyFrames(anim.body_positions, anim.body_faces))

    @classmethod
    def of_run(cls, run_dir, body=None) -> "FitSource":
        """The fit source of a run folder (``body``: a :class:`~tailor.body.Body` for runs written
        without ``--with-body``, default the shipped body its report names; the body's frames are
        taken from the folder when it has them)."""
        from .io.animation import read_run

        folder = Path(run_dir)
        anim = read_run(folder, with_body=True)
        report = _read_json(folder / "report.json")
        notes = []
        grain, wearable = _panel_values(report.get("panels"), anim.group_names)
        if "panels" not in report:
            notes.append("report.json has no panel grains or wearable stretch (a run of an older tailor): "
                         "grain 90°, wearable stretch 10 %")
        anim = _with_loads(anim, notes)
        if anim.has_body:
            bodies = BodyFrames(anim.body_positions, anim.body_faces)
        else:
            body = body if body is not None else _named_body(report)
            motion = report.get("phases", {}).get("motion", {}).get("frames", anim.frame_count)
            bodies = BodyFrames(body=body, offset=max(0, anim.frame_count - int(motion)), fps=anim.fps)
        return cls(anim, grain, wearable, bodies, tuple(notes))


def _with_loads(anim, notes: list):
    """``anim`` with zero loads (and a note) where it has none."""
    if anim.contact_forces is not None:
        return anim
    from dataclasses import replace

    notes.append("no contact forces recorded (a run of an older tailor): contact forces and pressure are 0")
    zero = np.zeros_like(anim.positions)
    return replace(anim, contact_forces=zero, attachment_forces=zero)


def _named_body(report: dict):
    """The shipped body a run was draped on (report.json's body name), or None."""
    from .io.body_files import NAMED_BODIES, read_body

    name = str(report.get("body", {}).get("name", "")).replace("_", "-")
    return read_body(name) if name in NAMED_BODIES else None


def _read_json(path: Path) -> dict:
    if not path.exists():
        return {}
    try:
        return json.loads(path.read_text())
    except ValueError as exc:
        raise TailorError(f"{path}: malformed JSON: {exc}") from None


def _panel_values(panels, names):
    """(grain [rad], wearable stretch [%]) per panel name, from report.json's ``panels``."""
    panels = panels or {}
    grain = np.array([math.radians(float(panels.get(n, {}).get("grain_deg", 90.0))) for n in names])
    wearable = np.array([float(panels.get(n, {}).get("wearable_stretch_pct", 10.0)) for n in names])
    return grain, wearable


def face_stretch(uv, face_uv, x, faces, grain):
    """(max, warp, weft) stretch [%] per face: 100·(λ − 1) of the deformation gradient from the flat
    pattern ``uv`` [m] to ``x`` (module docstring); ``grain`` (T,) [rad] per face, in the uv plane."""
    uv, x = np.asarray(uv, float), np.asarray(x, float)
    dm = np.stack([uv[face_uv[:, 1]] - uv[face_uv[:, 0]], uv[face_uv[:, 2]] - uv[face_uv[:, 0]]], axis=2)
    ds = np.stack([x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]]], axis=2)
    det = dm[:, 0, 0] * dm[:, 1, 1] - dm[:, 0, 1] * dm[:, 1, 0]
    ok = np.abs(det) > 1e-14
    inv = np.zeros_like(dm)
    inv[ok, 0, 0], inv[ok, 1, 1] = dm[ok, 1, 1] / det[ok], dm[ok, 0, 0] / det[ok]
    inv[ok, 0, 1], inv[ok, 1, 0] = -dm[ok, 0, 1] / det[ok], -dm[ok, 1, 0] / det[ok]
    f = ds @ inv  # (T, 3, 2)
    c = np.einsum("tki,tkj->tij", f, f)
    half_trace, half_diff = 0.5 * (c[:, 0, 0] + c[:, 1, 1]), 0.5 * (c[:, 0, 0] - c[:, 1, 1])
    top = half_trace + np.sqrt(half_diff ** 2 + c[:, 0, 1] ** 2)
    g = np.column_stack([np.cos(grain), np.sin(grain)])
    across = np.column_stack([-g[:, 1], g[:, 0]])
    warp = np.linalg.norm(np.einsum("tij,tj->ti", f, g), axis=1)
    weft = np.linalg.norm(np.einsum("tij,tj->ti", f, across), axis=1)
    out = [100.0 * (np.sqrt(np.maximum(top, 0.0)) - 1.0), 100.0 * (warp - 1.0), 100.0 * (weft - 1.0)]
    return tuple(np.where(ok, s, 0.0) for s in out)


def vertex_areas(x, faces, n: int) -> np.ndarray:
    """Each vertex's third of the area [m²] of the faces round it."""
    return np.bincount(faces.reshape(-1), weights=np.repeat(face_areas(x, faces) / 3.0, 3), minlength=n)


def _pressure(normal_force, x, faces) -> np.ndarray:
    """Pressure [kPa] of a normal force per vertex [N] over the vertex's share of the area at ``x``."""
    return normal_force / np.maximum(vertex_areas(x, faces, len(x)), 1e-12) * 1e-3


def landmark_ease(garment, body_mesh, landmark) -> Ease | None:
    """The :class:`Ease` at ``landmark`` of the trimesh ``garment`` on the trimesh ``body_mesh``
    (None where the garment does not go round it)."""
    import shapely
    import trimesh
    from shapely.geometry import MultiPoint, Point

    from .sections import cut_outlines, plane_frame

    centre, axis = np.asarray(landmark.center, float), np.asarray(landmark.axis, float)
    outlines = cut_outlines(body_mesh, centre, axis)
    if not outlines:
        return None
    own = int(np.argmin([o.distance(Point(0.0, 0.0)) for o in outlines]))
    if outlines[own].distance(Point(0.0, 0.0)) > 0.02:
        return None
    segments, faces = trimesh.intersections.mesh_plane(garment, axis, centre, return_faces=True)
    if not len(segments):
        return None
    u, w = plane_frame(axis)
    rel = segments.reshape(-1, 3) - centre
    pts = np.column_stack([rel @ u, rel @ w])
    d = np.stack([shapely.distance(o, shapely.points(pts)) for o in outlines])
    mine = ((d.argmin(axis=0) == own) & (d[own] < EASE_REACH)).reshape(-1, 2).all(axis=1)
    pts, faces = pts.reshape(-1, 2, 2)[mine].reshape(-1, 2), faces[mine]
    c = np.asarray(outlines[own].centroid.coords[0])
    if len(pts) < 3:
        return None
    ang = np.sort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))
    if np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi])).max() > EASE_MAX_OPENING:
        return None
    return Ease(landmark.name, float(MultiPoint(pts).convex_hull.length), float(outlines[own].convex_hull.length),
                np.asarray(faces, np.intp))


def garment_ease(x, faces, body_x, body_faces, names=EASE_LANDMARKS) -> dict:
    """{landmark: :class:`Ease`} of the garment at ``x`` on the body at ``body_x`` (landmarks found on
    that body, :func:`tailor.measure.find_landmarks`; raises BodyError where they cannot be)."""
    import trimesh

    from .measure import find_landmarks

    landmarks = find_landmarks(body_x, body_faces)
    garment = trimesh.Trimesh(np.asarray(x), np.asarray(faces), process=False)
    body_mesh = trimesh.Trimesh(np.asarray(body_x), np.asarray(body_faces), process=False)
    out = {}
    for name in names:
        e = landmark_ease(garment, body_mesh, landmarks[name])
        if e is not None:
            out[name] = e
    return out


def fit_map(source, frame: int = -1, *, ease: bool = True) -> FitMap:
    """The :class:`FitMap` of ``frame`` (negative: from the end) of ``source``: a :class:`FitSource`
    or a :class:`~tailor.dress.DrapeResult`. ``ease``: measure the body's landmarks on that frame
    (about a second) and the garment's girths there."""
    src = source if isinstance(source, FitSource) else FitSource.of_drape(source)
    anim = src.anim
    k = frame % anim.frame_count if -anim.frame_count <= frame < anim.frame_count else None
    if k is None:
        raise TailorError(f"frame {frame}: the drape has frames 0 to {anim.frame_count - 1}")
    x, faces = anim.positions[k], np.asarray(anim.faces)
    group = np.asarray(anim.face_group)
    s_max, s_warp, s_weft = face_stretch(anim.uv, anim.face_uv, x, faces, src.grain[group])
    rest = face_areas(anim.uv, anim.face_uv)
    contact = np.asarray(anim.contact_forces[k], float)
    notes = list(src.notes)
    body = src.bodies.at(k)
    if body is None:
        raise TailorError(f"{anim.name}: the run has no body frames (drape with --with-body) and no body was given "
                          "(--body): gap, pressure and ease need the body")
    dist, normal = body_gap(x, *body)
    pressure = _pressure(np.maximum(np.einsum("ij,ij->i", contact, normal), 0.0), x, faces)
    found = {}
    if ease:
        try:
            found = garment_ease(x, faces, *body)
        except BodyError as exc:
            notes.append(f"ease not measured on frame {k}: {exc}")
    return FitMap(k, x, faces, group, tuple(anim.group_names), rest, s_max, s_warp, s_weft, contact,
                  np.asarray(anim.attachment_forces[k], float), pressure, dist * 1e3, src.wearable, found, tuple(notes))


def fit_section(fits) -> dict:
    """The fit section of report.json: ``{"frames": [FitMap.summary(), …]}``."""
    return {"frames": [f.summary() for f in fits]}


VERTEX_FIELDS = ("stretch", "pressure", "gap")
"""Per-vertex fit quantities of :func:`vertex_field` (what exports and previews colour by)."""


def vertex_field(anim, k: int, name: str) -> np.ndarray:
    """One of :data:`VERTEX_FIELDS` per vertex of frame ``k`` of an Animation, from it alone.

    ``stretch`` [%]: the mean ``stretch_max`` of the faces round the vertex, weighted by their
    pattern area; ``pressure`` [kPa]: the contact force along the garment's own normal over the
    vertex's area (the fit map's uses the body's normal; where the cloth lies on the body they
    agree), 0 when the animation has no loads; ``gap`` [mm]: :func:`body_gap` (needs the body).
    """
    x, faces = anim.positions[k], np.asarray(anim.faces)
    n = len(x)
    if name == "stretch":
        s = face_stretch(anim.uv, anim.face_uv, x, faces, np.zeros(len(faces)))[0]
        w = np.repeat(face_areas(anim.uv, anim.face_uv), 3)
        total = np.bincount(faces.reshape(-1), weights=w, minlength=n)
        return np.bincount(faces.reshape(-1), weights=np.repeat(s, 3) * w, minlength=n) / np.maximum(total, 1e-300)
    if name == "pressure":
        if anim.contact_forces is None:
            return np.zeros(n)
        p = x[faces]
        fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        normal = np.stack([np.bincount(faces.reshape(-1), weights=np.repeat(fn[:, i], 3), minlength=n) for i in range(3)], 1)
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        return _pressure(np.abs(np.einsum("ij,ij->i", anim.contact_forces[k], normal)), x, faces)
    if name == "gap":
        if not anim.has_body:
            raise TailorError(f"{anim.name}: colouring by gap needs the body (drape with --with-body)")
        return body_gap(x, anim.body_positions[k], anim.body_faces)[0] * 1e3
    raise TailorError(f"unknown fit field {name!r}; choose from {', '.join(VERTEX_FIELDS)}")
