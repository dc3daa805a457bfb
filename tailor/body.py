"""Bodies: a triangle mesh and its motion, normalised to tailor's frame.

Any standing human comes in: metres or not, Y-up or Z-up, facing any horizontal direction.
:func:`normalise_body` detects units (a standing adult is 1.0–2.5 m tall), the up axis (the
longest extent) and the facing (the feet stick out forward from the ankles), then brings the body
to metres, Z up, facing −Y, feet on z = 0 and centred over the origin. Every choice can be forced,
and every choice is reported.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import BodyError

__all__ = ["Body", "normalise_body", "check_body_arrays", "UNITS", "AXES"]

UNITS = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001}
"""Length units a body file may be in, to metres."""

AXES = {"x": 0, "y": 1, "z": 2}
"""Axis names for ``up`` and ``facing``."""


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


def _rotation_to_z_up(up: int) -> np.ndarray:
    """Rotation taking axis ``up`` to +Z (right-handed; Y-up becomes Z-up as (x, −z, y))."""
    if up == 2:
        return np.eye(3)
    if up == 1:
        return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    return np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


def _foot_offsets(vertices):
    """Horizontal offsets from each planted foot's ankle to the foot's centre (toes pull it forward)."""
    z = vertices[:, 2]
    h = np.ptp(z)
    low = vertices[z < z.min() + 0.03 * h][:, :2]
    ankles = vertices[(z > z.min() + 0.05 * h) & (z < z.min() + 0.08 * h)][:, :2]
    if len(low) < 6 or len(ankles) < 6:
        return []
    # two feet: split the floor slab across its widest gap-free direction (k-means, 2 clusters)
    centres = low[[np.argmin(low[:, 0]), np.argmax(low[:, 0])]].astype(float)
    for _ in range(10):
        label = np.argmin(((low[:, None, :] - centres[None]) ** 2).sum(axis=2), axis=1)
        centres = np.array([low[label == c].mean(axis=0) if np.any(label == c) else centres[c] for c in range(2)])
    if np.linalg.norm(centres[0] - centres[1]) < 0.05 * h:  # one foot (or feet together)
        centres = low.mean(axis=0, keepdims=True)
        label = np.zeros(len(low), int)
    out = []
    for c, centre in enumerate(centres):
        near = ankles[np.linalg.norm(ankles - centre, axis=1) < 0.08 * h]
        if len(near) >= 3 and np.any(label == c):
            out.append(low[label == c].mean(axis=0) - near.mean(axis=0))
    return out


def _forward(frames) -> np.ndarray:
    """Horizontal unit axis the body faces: from each planted foot's ankle towards its toes.

    Offsets of every planted foot in every frame are averaged (a lifted foot is not in the
    floor slab), and the dominant horizontal axis with its sign is the facing.
    """
    offsets = []
    for vertices in np.asarray(frames).reshape(-1, *np.shape(frames)[-2:]):
        offsets.extend(_foot_offsets(vertices))
    default = np.array([0.0, -1.0, 0.0])
    if not offsets:
        return default
    d = np.mean(offsets, axis=0)
    if np.linalg.norm(d) < 0.005 * np.ptp(np.asarray(frames)[..., 2]):
        return default
    k = int(np.argmax(np.abs(d)))
    out = np.zeros(3)
    out[k] = np.sign(d[k])
    return out


def normalise_body(frames, faces, *, units: str = "auto", up: str = "auto", facing: str = "auto", source: str = "body"):
    """Bring a body to metres, Z up, facing −Y, feet on z = 0, centred on the origin.

    Parameters
    ----------
    frames : (T, N, 3) or (N, 3)
    units : "auto" or one of :data:`UNITS`
    up : "auto" or "x", "y", "z"
    facing : "auto" or a signed axis such as "-y", "+z"
        The direction the body faces *in the file's own frame*.

    Returns
    -------
    frames : (T, N, 3) [m]; faces (F, 3); report : dict
    """
    frames, faces = check_body_arrays(frames, faces, source)
    rest = frames[0]
    extent = np.ptp(rest, axis=0)
    if up == "auto":
        up_axis = int(np.argmax(extent))
    elif up in AXES:
        up_axis = AXES[up]
    else:
        raise BodyError(f"{source}: up must be auto, x, y or z, got {up!r}")
    tall = extent[up_axis]
    if units == "auto":
        fits = [(name, s) for name, s in UNITS.items() if 1.0 <= tall * s <= 2.5]
        if not fits:
            raise BodyError(
                f"{source}: cannot tell the units: the body is {tall:g} units tall, which is no standing human "
                f"in m, dm, cm or mm; pass the units explicitly"
            )
        unit_name, scale = fits[0]
    elif units in UNITS:
        unit_name, scale = units, UNITS[units]
    else:
        raise BodyError(f"{source}: units must be auto, {', '.join(UNITS)}, got {units!r}")
    rot = _rotation_to_z_up(up_axis)
    out = np.einsum("ij,tnj->tni", rot, frames * scale)
    if facing == "auto":
        fwd = _forward(out)
        facing_name = "detected"
    else:
        sign = -1.0 if facing.startswith("-") else 1.0
        name = facing.lstrip("+-")
        if name not in AXES:
            raise BodyError(f"{source}: facing must be auto or a signed axis like -y, got {facing!r}")
        fwd = np.zeros(3)
        fwd[AXES[name]] = sign
        fwd = rot @ fwd
        facing_name = facing
    if abs(fwd[2]) > 0.5:
        raise BodyError(f"{source}: the body cannot face its own up axis ({facing})")
    angle = np.arctan2(fwd[0], -fwd[1])  # rotate about z so that fwd → −Y
    c, s = np.cos(angle), np.sin(angle)
    rz = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    out = np.einsum("ij,tnj->tni", rz, out)
    rest = out[0]
    z0 = rest[:, 2].min()
    mid = rest[(rest[:, 2] > z0 + 0.45 * np.ptp(rest[:, 2])) & (rest[:, 2] < z0 + 0.6 * np.ptp(rest[:, 2]))]
    centre = mid[:, :2].mean(axis=0) if len(mid) else rest[:, :2].mean(axis=0)
    out = out - np.array([centre[0], centre[1], z0])
    report = {
        "units": unit_name,
        "up": "xyz"[up_axis],
        "facing": facing_name,
        "forward_in_file": (np.linalg.inv(rz @ rot) @ np.array([0.0, -1.0, 0.0])).round(6).tolist(),
        "height_m": float(np.ptp(out[0][:, 2])),
        "frames": int(len(out)),
        "vertices": int(out.shape[1]),
        "faces": int(len(faces)),
    }
    return out, faces, report
