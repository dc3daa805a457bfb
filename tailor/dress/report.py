"""What a drape produced: :class:`DrapeResult` (frames and the meshes to write them with), its typed
:class:`DrapeReport` (what report.json holds) and the :class:`DrapeProgress` told after each frame."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

__all__ = ["DrapeResult", "DrapeReport", "DrapeProgress", "DrapeFrame", "PhaseReport"]


@dataclass(frozen=True)
class DrapeFrame:
    """One frame as it leaves the simulation, for a ``sink`` of :func:`~tailor.dress.drape` (a writer
    streaming frames to disk: :class:`tailor.io.garment.DrapeWriter`).

    Attributes
    ----------
    index : int
        0, 1, … in the order written (with ``record_sewing`` the sewing's frames come first).
    x : (N, 3) float
        Every mesh vertex [m] (seam copies included), in ``mesh``'s numbering.
    body_x : (M, 3) float
        The body at the same instant [m].
    contact_force, attachment_force : (W, 3) float32
        The body's contact and the attachments' force on each welded vertex [N], averaged over the frame.
    mesh, weld
        The garment's mesh and its weld (mesh vertex → welded vertex) at this frame: a cut or a tear
        changes them.
    """

    index: int
    x: np.ndarray
    body_x: np.ndarray
    contact_force: np.ndarray
    attachment_force: np.ndarray
    mesh: object
    weld: np.ndarray


@dataclass(frozen=True)
class DrapeProgress:
    """What :func:`~tailor.dress.drape` reports to its ``progress`` callback after every frame.

    Attributes
    ----------
    phase : str
        ``sewing``, ``settling``, ``transition`` (into the motion's first pose) or ``motion``.
    done, total : int
        Seam vertex pairs welded (sewing) or frames simulated (other phases) of this phase.
    simulated_s : float
        Simulated time so far, all phases [s].
    steps : int
        Integrator steps so far, all phases.
    """

    phase: str
    done: int
    total: int
    simulated_s: float
    steps: int


@dataclass
class PhaseReport:
    """One phase: simulated and wall time, frames, and what only that phase measures (``extra``)."""

    simulated_s: float
    wall_s: float
    frames: int | None = None
    extra: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        out = {"simulated_s": self.simulated_s, "wall_s": self.wall_s}
        if self.frames is not None:
            out["frames"] = self.frames
        return {**out, **self.extra}


@dataclass
class DrapeReport:
    """Inputs, derived parameters, cost and quality of a drape (report.json: :meth:`to_json`).

    Lengths in metres, times in seconds, as the attribute names say.
    """

    vertices: int
    faces: int
    resolution_m: float
    fps: float
    integrator: str
    time_step_eq24_s: float
    seam_pairs: int
    loops: dict
    fabrics: dict
    panels: dict  # name → {"grain_deg", "wearable_stretch_pct"}: what a fit map reads per panel
    body: dict
    params: dict
    quality: dict
    active: dict
    skipped: list
    phases: dict = field(default_factory=dict)  # name → PhaseReport
    max_triangle_stretch_dressed: float = 0.0  # largest principal stretch of any triangle once settled (frame 0's state)
    max_penetration_m_per_frame: list = field(default_factory=list)
    max_penetration_m: float = 0.0
    crossings_per_frame: list = field(default_factory=list)  # edges through a triangle of the garment (tailor.collide.edge_crossings)
    placement_crossings: int = 0  # ... of the placed panels, before sewing
    wall_s: float = 0.0
    steps: int = 0
    cg_iterations: int = 0
    halved_steps: dict = field(default_factory=dict)  # steps taken as halves, by cause (the solve's; the contacts overstretching)
    body_bvh_queries: int = 0
    max_contact_correction_m: float = 0.0  # deepest penetration any step had to undo
    vertices_rescued_from_inside_body: int = 0
    welded_vertices: int = 0
    self_collision: dict = field(default_factory=dict)
    tearing: dict | None = None
    fit: dict | None = None  # tailor.fit.fit_section of the frames mapped (tailor drape --fit)
    garments: dict | None = None  # an outfit's garments, innermost first: name → {"layer", "panels", "vertices", ...}
    out_of_layer_per_frame: list | None = None  # an outfit's vertices inside a garment they should be over (tailor.outfit.out_of_order)

    def to_json(self) -> dict:
        """The report as report.json holds it (plain numbers, lists and dicts)."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "phases":
                value = {k: p.to_json() for k, p in value.items()}
            if value is not None:
                out[f.name] = value
        return out


@dataclass
class DrapeResult:
    """Frames of a drape and everything needed to write them.

    Attributes
    ----------
    frames : list of (N, 3) arrays [m]
        Garment vertex positions, frame 0 = dressed and settled.
    body_frames : list of (M, 3) arrays [m]
        The body at the same instants.
    mesh : GarmentMesh
    weld : (N,) int
        Index of each vertex in the welded garment (merged seam vertices share one).
    body_faces : (F, 3) int
        Triangles of the body frames.
    pattern : Pattern
    report : DrapeReport
    topology : list of (frame, GarmentMesh, weld)
        Where a cut or a tear changed the garment's mesh: from that frame on, frames hold the
        vertices of that mesh (``mesh`` and ``weld`` above are frame 0's). Empty if it never changed.
    contact_forces, attachment_forces : list of (W, 3) float32 arrays [N]
        Per frame, the force the body's contact (normal and friction) and the attachments exert
        on each welded vertex (the OBJ's vertex order), averaged over the steps of the frame
        (:class:`~tailor.contact.ContactLoads`).
    """

    frames: list
    body_frames: list
    mesh: object
    weld: np.ndarray
    body_faces: np.ndarray
    pattern: object
    report: DrapeReport
    topology: list = field(default_factory=list)
    contact_forces: list = field(default_factory=list)
    attachment_forces: list = field(default_factory=list)

    def topology_at(self, frame: int):
        """``(mesh, weld)`` of frame ``frame``."""
        mesh, weld = self.mesh, self.weld
        for first, m, w in self.topology:
            if first <= frame:
                mesh, weld = m, w
        return mesh, weld


