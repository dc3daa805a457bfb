"""A drape as one animation: what every exporter and the preview read.

:class:`Animation` holds the welded garment (a seam is one vertex) over all frames, its faces,
per-panel UVs and groups, the frame rate and optionally the body. It comes either straight from
a :class:`tailor.dress.DrapeResult` (:func:`animation_from_drape`) or from a run folder written
by ``tailor drape`` (:func:`read_run`), so ``tailor export`` works on old runs too.
"""

from __future__ import annotations

import json
import logging
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import TailorError
from .obj import read_obj, read_obj_vertices

__all__ = ["Animation", "animation_from_drape", "read_run", "read_loads", "LOADS_FILE", "welded", "panel_colour", "mtl_text", "PANEL_COLOURS", "BODY_COLOUR"]

log = logging.getLogger(__name__)

DEFAULT_FPS = 25.0

PANEL_COLOURS = ((0.80, 0.25, 0.25), (0.25, 0.45, 0.85), (0.30, 0.70, 0.35), (0.90, 0.75, 0.20),
                 (0.65, 0.30, 0.75), (0.20, 0.75, 0.75), (0.95, 0.55, 0.25), (0.55, 0.55, 0.55))
"""Panel i is drawn in ``PANEL_COLOURS[i % 8]`` in every output (MTL, GLB, USD, previews, drawings)."""

BODY_COLOUR = (0.78, 0.78, 0.80)


def panel_colour(i: int) -> tuple:
    """RGB (0–1) of panel ``i``."""
    return PANEL_COLOURS[i % len(PANEL_COLOURS)]


def mtl_text(names) -> str:
    """A Wavefront material file with one material per panel name, in the panel colours."""
    return "".join(f"newmtl {name}\nKd {r:.3f} {g:.3f} {b:.3f}\n\n"
                   for i, name in enumerate(names) for r, g, b in [panel_colour(i)])


@dataclass(frozen=True)
class Animation:
    """An animated garment (and optionally the body) ready to export or render.

    Attributes
    ----------
    name : str
    positions : (F, N, 3) float
        Garment vertex positions per frame [m].
    faces : (T, 3) int
    uv : (U, 2) float
        Flat pattern coordinates [m] (one set per panel, so seams have two).
    face_uv : (T, 3) int
        UV index of each face corner.
    face_group : (T,) int
        Panel of each face, indexing ``group_names``.
    group_names : tuple of str
    fps : float
    body_positions : (F, M, 3) float or None
    body_faces : (B, 3) int or None
    contact_forces, attachment_forces : (F, N, 3) float or None
        The force the body's contact and the attachments exert on each vertex per frame [N]
        (a run's ``loads.npz``; None when unknown).
    garments : tuple of (name, tuple of group names), optional
        An outfit's garments and their panels (:meth:`split`); empty for one garment.
    """

    name: str
    positions: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    face_uv: np.ndarray
    face_group: np.ndarray
    group_names: tuple
    fps: float = DEFAULT_FPS
    body_positions: np.ndarray | None = None
    body_faces: np.ndarray | None = None
    contact_forces: np.ndarray | None = None
    attachment_forces: np.ndarray | None = None
    garments: tuple = ()

    def split(self) -> list["Animation"]:
        """One animation per garment of an outfit, each with its own vertices, UVs and panels and
        without the body; ``[self]`` for one garment."""
        if len(self.garments) < 2:
            return [self]
        return [self._part(name, [g for g, n in enumerate(self.group_names) if n in set(panels)])
                for name, panels in self.garments]

    def _part(self, name: str, groups: list) -> "Animation":
        """The animation of the faces in ``groups`` only, renumbered."""
        sel = np.isin(self.face_group, groups)
        verts, faces = np.unique(self.faces[sel], return_inverse=True)
        uvs, face_uv = np.unique(self.face_uv[sel], return_inverse=True)
        group_of = np.full(len(self.group_names), -1)
        group_of[groups] = np.arange(len(groups))
        loads = [None if f is None else f[:, verts] for f in (self.contact_forces, self.attachment_forces)]
        return Animation(name=name, positions=self.positions[:, verts], faces=faces.reshape(-1, 3), uv=self.uv[uvs],
                         face_uv=face_uv.reshape(-1, 3), face_group=group_of[self.face_group[sel]],
                         group_names=tuple(self.group_names[g] for g in groups), fps=self.fps,
                         contact_forces=loads[0], attachment_forces=loads[1])

    @property
    def frame_count(self) -> int:
        """Number of frames F."""
        return len(self.positions)

    @property
    def vertex_count(self) -> int:
        """Garment vertices per frame N."""
        return self.positions.shape[1]

    @property
    def has_body(self) -> bool:
        """Whether body frames are included."""
        return self.body_positions is not None

    def check_finite(self) -> None:
        """Raise :class:`TailorError` if any position is NaN or infinite (nothing non-finite is exported)."""
        if not np.all(np.isfinite(self.positions)) or (self.has_body and not np.all(np.isfinite(self.body_positions))):
            raise TailorError(f"{self.name}: refusing to export non-finite vertex positions")


def welded(weld, faces, x):
    """Welded positions (one per merged group, the first member's) and ``faces`` in welded indices."""
    weld = np.asarray(weld)
    n = int(weld.max()) + 1
    first = np.full(n, -1, np.intp)
    first[weld[::-1]] = np.arange(len(weld))[::-1]
    return np.asarray(x)[first], weld[np.asarray(faces)]


def animation_from_drape(result, *, with_body: bool = True) -> Animation:
    """The :class:`Animation` of a :class:`tailor.dress.DrapeResult` (welded, as the OBJ files are)."""
    if getattr(result, "topology", None):
        first = result.topology[0][0]
        raise TailorError(f"the garment's mesh changes at frame {first} (a cut or a tear): only the OBJ sequence "
                          "can hold that; export without --format pc2/glb/usd")
    mesh = result.mesh
    positions = np.stack([welded(result.weld, mesh.faces, x)[0] for x in result.frames])
    faces = result.weld[mesh.faces]
    body = np.stack(result.body_frames) if with_body and result.body_frames else None
    loads = len(result.contact_forces) == len(result.frames) and len(result.frames) > 0
    return Animation(name=result.pattern.name, positions=positions, faces=faces, uv=np.asarray(mesh.uv),
                     face_uv=np.asarray(mesh.faces), face_group=np.asarray(mesh.face_panel),
                     group_names=tuple(mesh.panel_names), fps=float(result.report.fps),
                     body_positions=body, body_faces=np.asarray(result.body_faces) if body is not None else None,
                     contact_forces=np.stack(result.contact_forces) if loads else None,
                     attachment_forces=np.stack(result.attachment_forces) if loads else None,
                     garments=_garments(result.report.garments))


def _garments(section) -> tuple:
    """An outfit's (garment, panels) from a report's ``garments`` section (empty: one garment)."""
    return tuple((str(name), tuple(g["panels"])) for name, g in (section or {}).items())


LOADS_FILE = "loads.npz"
"""A run folder's per-frame contact and attachment forces (``contact_NNNN``, ``attachment_NNNN``, N)."""


def read_loads(folder: Path, frames: int, vertices: int):
    """(contact, attachment) forces, each (frames, vertices, 3) [N], of a run folder; (None, None)
    if it has no :data:`LOADS_FILE` (a run of an older tailor)."""
    path = folder / LOADS_FILE
    if not path.exists():
        return None, None
    try:
        with np.load(path) as data:
            contact = np.stack([data[f"contact_{k:04d}"] for k in range(frames)]).astype(float)
            attached = np.stack([data[f"attachment_{k:04d}"] for k in range(frames)]).astype(float)
    except (KeyError, ValueError, OSError) as exc:
        raise TailorError(f"{path}: unreadable or incomplete ({exc})") from None
    if contact.shape != (frames, vertices, 3) or attached.shape != contact.shape:
        raise TailorError(f"{path}: forces of shape {contact.shape}, but the run has {frames} frames of {vertices} vertices")
    return contact, attached


def _numbered(folder: Path, stem: str) -> list[Path]:
    pattern = re.compile(rf"{stem}_(\d+)\.obj$")
    found = sorted((int(m.group(1)), p) for p in folder.iterdir() if (m := pattern.match(p.name)))
    return [p for _, p in found]


def read_run(run_dir, *, with_body: bool = True) -> Animation:
    """Read a run folder written by ``tailor drape`` (``garment_0000.obj`` …, ``report.json``).

    Body frames (``body_0000.obj`` …) are read when present and ``with_body``. The frame rate comes
    from ``report.json`` (25 fps if it is missing).
    """
    folder = Path(run_dir)
    if not folder.is_dir():
        raise TailorError(f"{folder}: not a run folder (expected garment_0000.obj … written by tailor drape)")
    files = _numbered(folder, "garment")
    if not files:
        raise TailorError(f"{folder}: no garment_0000.obj frames in this folder")
    first = read_obj(files[0])
    if first.face_uv is None:
        raise TailorError(f"{files[0]}: faces have no texture coordinates (v/vt); not a tailor garment frame")
    positions = [first.vertices] + [read_obj_vertices(p) for p in files[1:]]
    for p, x in zip(files, positions):
        if x.shape != first.vertices.shape:
            raise TailorError(f"{p}: {len(x)} vertices, but {files[0].name} has {len(first.vertices)}")
    fps, name, garments = DEFAULT_FPS, folder.name, ()
    report = folder / "report.json"
    if report.exists():
        try:
            info = json.loads(report.read_text())
        except ValueError as exc:
            raise TailorError(f"{report}: malformed JSON: {exc}") from None
        fps = float(info.get("fps", DEFAULT_FPS))
        name = str(info.get("name", name))
        garments = _garments(info.get("garments"))
    body = body_faces = None
    body_files = _numbered(folder, "body") if with_body else []
    if body_files:
        if len(body_files) != len(files):
            raise TailorError(f"{folder}: {len(body_files)} body frames for {len(files)} garment frames")
        b0 = read_obj(body_files[0])
        frames = [b0.vertices] + [read_obj_vertices(p) for p in body_files[1:]]
        for p, x in zip(body_files, frames):
            if x.shape != b0.vertices.shape:
                raise TailorError(f"{p}: {len(x)} vertices, but {body_files[0].name} has {len(b0.vertices)}")
        body = np.stack(frames)
        body_faces = b0.faces
    log.debug("read %s: %d frames, %d vertices, body %s", folder, len(files), len(first.vertices), body is not None)
    contact, attached = read_loads(folder, len(files), len(first.vertices))
    return Animation(name=name, positions=np.stack(positions), faces=first.faces, uv=first.uv, face_uv=first.face_uv,
                     face_group=first.face_group, group_names=first.group_names, fps=fps,
                     body_positions=body, body_faces=body_faces, contact_forces=contact, attachment_forces=attached,
                     garments=garments)
