"""Bodies: a triangle mesh and its motion, normalised to tailor's frame.

Any standing human comes in: metres or not, Y-up or Z-up, facing any horizontal direction, with
eyes and teeth as separate parts, from wherever its file put it. :func:`normalise_body` welds
duplicate vertices, drops small separate parts, detects the up axis, units and facing and the
trunk's centre (:mod:`tailor.orient`), then brings the body to metres, Z up, facing −Y, feet on
z = 0 and the trunk over the origin. Every choice can be forced, and every choice is reported.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import BodyError
from .orient import AXES, UNITS, body_parts, detect_units, forward, up_rotation, weld

__all__ = ["Body", "normalise_body", "check_body_arrays", "UNITS", "AXES"]


@dataclass(frozen=True, eq=False)
class Body:
    """A body mesh in tailor's frame: metres, Z up, facing −Y, feet on z = 0.

    Attributes
    ----------
    frames : ndarray, shape (T, N, 3)
        Vertex positions of every frame [m] (T = 1 for a static body).
    faces : ndarray, shape (F, 3)
    fps : float
        Frames per second of the motion.
    name : str
    report : dict
        What normalisation detected or was told (units, up axis, facing, height).
    rest : ndarray, shape (N, 3), optional
        A neutral pose of the same mesh (arms and legs apart, standing still) in which a garment
        is dressed before the motion starts; the shipped walk carries the static mannequin's.
    """

    frames: np.ndarray
    faces: np.ndarray
    fps: float = 25.0
    name: str = "body"
    report: dict = field(default_factory=dict)
    rest: np.ndarray | None = None

    @property
    def vertices(self) -> np.ndarray:
        """Rest (first-frame) positions [m], shape (N, 3)."""
        return self.frames[0]

    @property
    def frame_count(self) -> int:
        """T."""
        return len(self.frames)

    @property
    def height(self) -> float:
        """Height of the first frame [m]."""
        return float(np.ptp(self.frames[0][:, 2]))

    @property
    def duration(self) -> float:
        """Length of the motion [s] (0 for a static body)."""
        return (self.frame_count - 1) / self.fps if self.frame_count > 1 else 0.0

    def at(self, t: float, *, loop: bool = True):
        """Positions [m] and velocities [m/s] at time ``t``, linearly interpolated between frames."""
        if self.frame_count == 1:
            return self.frames[0], np.zeros_like(self.frames[0])
        period = self.frame_count / self.fps if loop else self.duration
        s = (t % period) * self.fps if loop else min(max(t, 0.0), self.duration) * self.fps
        i = int(np.floor(s))
        a = s - i
        i0 = i % self.frame_count
        i1 = (i + 1) % self.frame_count if loop else min(i + 1, self.frame_count - 1)
        x = (1 - a) * self.frames[i0] + a * self.frames[i1]
        v = (self.frames[i1] - self.frames[i0]) * self.fps
        return x, v


def check_body_arrays(frames, faces, source: str = "body"):
    """Validate frames (T, N, 3) and faces (F, 3); raise :class:`BodyError` naming ``source``."""
    frames = np.asarray(frames, dtype=float)
    faces = np.asarray(faces)
    if frames.ndim == 2:
        frames = frames[None]
    if frames.ndim != 3 or frames.shape[-1] != 3 or frames.shape[1] == 0:
        raise BodyError(f"{source}: the mesh has no vertices")
    if faces.ndim != 2 or len(faces) == 0:
        raise BodyError(f"{source}: the mesh has no faces (a point cloud cannot be a body)")
    if faces.shape[1] != 3:
        raise BodyError(f"{source}: faces must be triangles, got {faces.shape[1]} corners")
    if not np.all(np.isfinite(frames)):
        bad = np.argwhere(~np.isfinite(frames))[0]
        raise BodyError(f"{source}: vertex {bad[1]} of frame {bad[0]} is NaN or infinite")
    if faces.min() < 0 or faces.max() >= frames.shape[1]:
        raise BodyError(f"{source}: a face refers to vertex {int(faces.max())}, but there are {frames.shape[1]}")
    return frames, faces.astype(np.intp)


def normalise_body(frames, faces, *, units: str = "auto", up: str = "auto", facing: str = "auto", source: str = "body"):
    """Bring a body to metres, Z up, facing −Y, feet on z = 0, the trunk over the origin.

    Detection (:mod:`tailor.orient`) reads the shape of the first frame (the feet of every frame
    for the facing); the same transform moves every frame, so a walk that travels keeps travelling.

    Parameters
    ----------
    frames : (T, N, 3) or (N, 3)
    units : "auto" or one of :data:`UNITS`
    up : "auto" or a signed axis such as "y", "-z"
    facing : "auto" or a signed axis such as "-y", "+z"
        The direction the body faces *in the file's own frame*.

    Returns
    -------
    frames : (T, M, 3) [m]; faces (F, 3); report : dict
        M ≤ N: duplicate vertices are welded and small separate parts dropped (``report`` says how many).
    """
    frames, faces = check_body_arrays(frames, faces, source)
    count_in = frames.shape[1]
    frames, faces = weld(frames, faces)
    frames, faces, dropped = body_parts(frames, faces, source)
    rot, up_name = up_rotation(frames[0], faces, up, source)
    out = np.einsum("ij,tnj->tni", rot, frames)
    scale, unit_name = detect_units(float(np.ptp(out[0][:, 2])), units, source)
    out = out * scale
    out[..., 2] -= out[0][:, 2].min()
    fwd, centre = _facing(out, faces, rot, facing, source)
    angle = np.arctan2(fwd[0], -fwd[1])  # rotate about z so that fwd → −Y
    c, s = np.cos(angle), np.sin(angle)
    rz = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    shift = rz[:2, :2] @ centre
    out = np.einsum("ij,tnj->tni", rz, out) - np.array([shift[0], shift[1], 0.0])
    report = {
        "units": unit_name,
        "up": up_name,
        "facing": "detected" if facing == "auto" else facing,
        "forward_in_file": (np.linalg.inv(rz @ rot) @ np.array([0.0, -1.0, 0.0])).round(6).tolist(),
        "centre_shift_m": (-np.append(shift, 0.0)).round(6).tolist(),
        "height_m": float(np.ptp(out[0][:, 2])),
        "frames": int(len(out)),
        "vertices": int(out.shape[1]),
        "faces": int(len(faces)),
        "vertices_in_file": int(count_in),
        "parts_dropped": dropped,
    }
    return out, faces, report


def _facing(frames, faces, rot, facing, source):
    """(forward (3,), trunk centre (2,)) of Z-up ``frames``; ``facing`` names it in the file's frame."""
    try:
        fwd, centre = forward(frames, faces)
    except BodyError as exc:
        raise BodyError(f"{source}: {exc}") from None
    if facing == "auto":
        return fwd, centre
    name = facing.lstrip("+-")
    if name not in AXES:
        raise BodyError(f"{source}: facing must be auto or a signed axis like -y, got {facing!r}")
    given = np.zeros(3)
    given[AXES[name]] = -1.0 if facing.startswith("-") else 1.0
    given = rot @ given
    if abs(given[2]) > 0.5:
        raise BodyError(f"{source}: the body cannot face its own up axis ({facing})")
    given[2] = 0.0
    return given / np.linalg.norm(given), centre
