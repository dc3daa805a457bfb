"""Reference scenes: flat panels dropped on rigid shapes, usable from tests, bench and validate.

A scene is cloth (panels of a :class:`~tailor.pattern.Pattern`, placed flat in space) over a
static rigid body (a sphere, a floor, boxes: any closed or open triangle mesh). :func:`run_scene`
simulates it with body contact (Carignan Eq. 9–14) and, unless switched off, self-collision
(Eq. 5–8), and returns the frames and a report. Nothing here writes files.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
import trimesh

from .collide import BodyCollider
from .contact import ContactPipeline, StaticBody, body_margin, check_self_collision
from .curves import Curve
from .fabric import Fabric, preset
from .forces import total_forces
from .mesh import GarmentMesh, discretise
from .model import build_model
from .pattern import Edge, Panel, Pattern
from .integrators import SolverSettings, make_integrator
from .sim import Guard, simulate

__all__ = ["Setup", "sphere_drop", "two_corner_hang", "SPHERE_FABRIC", "rectangle", "grid", "sphere", "floor", "run_scene", "SceneResult", "cloth_model"]


def rectangle(width: float, height: float, name: str = "panel", *, grain: float = 0.5 * math.pi) -> Panel:
    """A ``width`` × ``height`` [m] rectangular panel with its corner at the origin."""
    pts = ((0.0, 0.0), (width, 0.0), (width, height), (0.0, height))
    edges = tuple(Edge(Curve("straight", (pts[i], pts[(i + 1) % 4])), (i, (i + 1) % 4)) for i in range(4))
    return Panel(name, pts, edges, grain=grain)


def grid(width: float, height: float, nx: int, ny: int | None = None, name: str = "cloth", *,
         grain: float = 0.5 * math.pi) -> GarmentMesh:
    """A regular ``nx`` × ``ny`` vertex grid over a ``width`` × ``height`` [m] panel, as a mesh.

    Each quad is split along alternating diagonals (no preferred shear direction), the layout a
    cloth tool's grid primitive gives, so scenes can be compared vertex for vertex with one.
    """
    ny = nx if ny is None else ny
    if nx < 2 or ny < 2:
        raise ValueError(f"a grid needs at least 2 × 2 vertices, got {nx} × {ny}")
    u, v = np.meshgrid(np.linspace(0.0, width, nx), np.linspace(0.0, height, ny), indexing="xy")
    uv = np.c_[u.ravel(), v.ravel()]
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), indexing="xy")
    a = (j * nx + i).ravel()
    b, c, d = a + 1, a + nx, a + nx + 1
    even = ((i + j) % 2 == 0).ravel()
    first = np.where(even[:, None], np.c_[a, b, d], np.c_[a, b, c])
    second = np.where(even[:, None], np.c_[a, d, c], np.c_[b, d, c])
    faces = np.stack([first, second], axis=1).reshape(-1, 3)
    boundary = 2 * (nx - 1) + 2 * (ny - 1)
    edge_vertices = {(0, None, 0): np.arange(nx), (0, None, 1): np.arange(nx - 1, nx * ny, nx),
                     (0, None, 2): np.arange(nx * ny - 1, nx * (ny - 1) - 1, -1), (0, None, 3): np.arange(nx * (ny - 1), -1, -nx)}
    return GarmentMesh(uv, faces, np.zeros(len(uv), np.intp), np.zeros(len(faces), np.intp),
                       np.tile([math.cos(grain), math.sin(grain)], (len(faces), 1)), np.zeros((0, 2), np.intp),
                       np.zeros(0, np.intp), edge_vertices, (name,), max(width / (nx - 1), height / (ny - 1)), boundary)


def sphere(radius: float, center=(0.0, 0.0, 0.0), *, subdivisions: int = 4):
    """(vertices, faces) of an icosphere [m]."""
    ball = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(ball.vertices) + np.asarray(center, float), np.asarray(ball.faces)


def floor(size: float = 4.0, z: float = 0.0):
    """(vertices, faces) of a square floor of side ``size`` [m] at height ``z``, facing +z."""
    h = 0.5 * size
    v = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]], float)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def cloth_model(panels, fabric: Fabric | str, resolution: float, *, compression: float = 1.0, **model_kwargs):
    """Discretise ``panels`` (no seams) and build their model; returns (mesh, model)."""
    fabric = preset(fabric) if isinstance(fabric, str) else fabric
    pattern = Pattern("scene", tuple(panels), fabric=fabric)
    mesh = discretise(pattern, resolution)
    return mesh, build_model(mesh, fabric, compression=compression, **model_kwargs)


@dataclass
class SceneResult:
    """Frames [m] of a scene run (frame 0 = start), the model and a report."""

    frames: list
    model: object
    report: dict = field(default_factory=dict)


def run_scene(model, x0, *, body=None, duration: float = 1.0, fps: float = 25.0, integrator: str = "implicit",
              dt: float | None = None, thickness: float = 0.003, friction: float = 0.4, self_collision: str = "auto",
              margin: float | None = None, v0=None, guard: Guard | None = None, on_frame=None, hooks=(),
              forces=None, wind=None) -> SceneResult:
    """Simulate cloth ``model`` from positions ``x0`` over a static ``body`` = (vertices, faces).

    ``wind`` (a :class:`~tailor.forces.wind.Wind` or air velocity) blows on a model with air.
    ``self_collision`` is ``auto`` (only regions that can touch), ``on`` or ``off``. Extra
    ``hooks(model, state, dt)`` run after the contact responses. Returns a :class:`SceneResult`
    whose report holds the wall time, steps, penetration and what the self-collision pass did.
    """
    check_self_collision(self_collision)
    t0 = time.perf_counter()
    x0 = np.asarray(x0, float)
    state = model.state(x0.copy(), None if v0 is None else np.asarray(v0, float).copy())
    contacts = scene_contacts(model, x0, body, thickness=thickness, friction=friction, self_collision=self_collision,
                              margin=margin)
    integ = make_integrator(integrator) if isinstance(integrator, str) else integrator
    if wind is not None:
        forces = forces or functools.partial(total_forces, wind=wind)
        integ.configure(replace(integ.settings, wind=wind))  # the solve treats drag relative to this air
    frames = []
    steps_before = integ.counters.steps  # an integrator handed in may have stepped before
    for _, st in simulate(model, state, duration=duration, frame_rate=fps, integrator=integ, dt=dt, contacts=contacts,
                          hooks=hooks, guard=guard or Guard(), forces=forces or total_forces):
        frames.append(st.x.copy())
        if on_frame is not None:
            on_frame(len(frames) - 1, st)
    report = {"wall_s": time.perf_counter() - t0, "steps": integ.counters.steps - steps_before, "vertices": int(model.vertex_count),
              "max_contact_correction_m": contacts.deepest, "self_collision": contacts.self_report(),
              "cg_iterations": integ.counters.iterations, "halved_steps": integ.counters.halved_steps()}
    return SceneResult(frames, model, report)


def scene_contacts(model, x0, body, *, thickness: float, friction: float, self_collision: str, margin: float | None) -> ContactPipeline:
    """The contact pipeline of cloth ``model`` at ``x0`` over a static ``body`` = (vertices, faces) or None."""
    collider, motion = None, None
    if body is not None:
        bv = np.asarray(body[0], float)
        collider = BodyCollider(bv[None], body[1], margin=body_margin(thickness))
        motion = StaticBody(bv)
    contacts = ContactPipeline(collider, motion, thickness=thickness, friction=friction, self_collision=self_collision,
                               self_margin=margin)
    if self_collision != "off":
        contacts.self_collider(model, x0)  # its patches cut from the start positions
    return contacts


@dataclass
class Setup:
    """A reference scene ready to run: cloth model, start positions, rigid body and timing."""

    name: str
    mesh: GarmentMesh
    model: object
    x0: np.ndarray
    body: tuple | None
    duration: float = 2.0
    fps: float = 25.0
    thickness: float = 0.001
    friction: float = 0.4

    def run(self, *, integrator: str = "implicit", dt: float | None = None, tolerance: float | None = None,
            self_collision: str = "off", guard: Guard | None = None, forces=None, v0=None, wind=None) -> SceneResult:
        """Simulate the scene; ``tolerance`` sets the implicit solver's relative residual."""
        integ = make_integrator(integrator)
        if tolerance is not None:
            integ.configure(SolverSettings(tolerance=tolerance))
        return run_scene(self.model, self.x0, body=self.body, duration=self.duration, fps=self.fps, integrator=integ,
                         dt=dt, thickness=self.thickness, friction=self.friction, self_collision=self_collision,
                         guard=guard, forces=forces, v0=v0, wind=wind)


SPHERE_FABRIC = Fabric("cotton-150", 0.15, 0.01, 0.01, 8.0, 0.4, 0.001)
"""The sphere scene's cloth: cotton at 150 g/m² (the areal density of the Blender comparison)."""


def sphere_drop(n: int = 64, *, fabric: Fabric = SPHERE_FABRIC, size: float = 1.0, radius: float = 0.25,
                drop: float = 0.05, duration: float = 2.0) -> Setup:
    """A ``size`` m square cloth of ``n`` × ``n`` vertices dropped centred onto a sphere of ``radius``.

    The cloth starts flat ``drop`` m above the sphere's top; the sphere is an icosphere of 5 120
    triangles centred at the origin.
    """
    mesh = grid(size, size, n)
    model = build_model(mesh, fabric)
    x0 = np.c_[mesh.uv - 0.5 * size, np.full(mesh.vertex_count, radius + drop)]
    return Setup(f"sphere{n}", mesh, model, x0, sphere(radius), duration, thickness=fabric.thickness, friction=fabric.friction)


def two_corner_hang(n: int = 32, *, fabric: Fabric | str = "cotton", size: float = 1.0, duration: float = 2.0) -> Setup:
    """A ``size`` m square cloth of ``n`` × ``n`` vertices, flat, pinned at its two far corners: it falls and swings."""
    fabric = preset(fabric) if isinstance(fabric, str) else fabric
    mesh = grid(size, size, n)
    corners = [n * (n - 1), n * n - 1]
    model = build_model(mesh, fabric, pinned=corners)
    x0 = np.c_[mesh.uv - 0.5 * size, np.full(mesh.vertex_count, 1.5)]
    return Setup(f"hang{n}", mesh, model, x0, None, duration, thickness=fabric.thickness, friction=fabric.friction)
