"""glTF binary (GLB) export of an :class:`~tailor.io.animation.Animation`, written by hand.

Animation as **morph targets**: the garment mesh holds frame 0, one morph target per later frame
(position offsets from frame 0), and an animation channel on the node's ``weights`` with linear
interpolation that raises target k to 1 at frame k. Blender's glTF importer turns this into shape
keys with keyed values and plays it back as it was simulated; three.js and other viewers play it
too (only two weights are ever non-zero). We chose it over one node per frame (visibility
flipping by scale) because the topology and UVs are stored once and importers keep it one object.

glTF is Y-up, tailor Z-up: positions are stored as (x, z, −y), which importers turn back into
tailor's frame. Vertices are split where a seam joins two panels (glTF has one UV per vertex);
the copies share positions in every frame, so the seam stays closed. UV v is stored as 1 − v so
that importers that flip it (Blender) show the OBJ's coordinates. One primitive per panel, each
with its own material colour. Optionally the body is a second mesh animated the same way.
"""

from __future__ import annotations

import json
import struct

import numpy as np

from ..errors import TailorError
from .animation import BODY_COLOUR, panel_colour
from .atomic import atomic_write

__all__ = ["write_glb", "to_y_up", "from_y_up"]

_FLOAT, _UINT = 5126, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


def to_y_up(x):
    """tailor (Z up) → glTF (Y up): (x, y, z) ↦ (x, z, −y)."""
    x = np.asarray(x)
    return np.stack([x[..., 0], x[..., 2], -x[..., 1]], axis=-1)


def from_y_up(x):
    """glTF (Y up) → tailor (Z up): the inverse of :func:`to_y_up`."""
    x = np.asarray(x)
    return np.stack([x[..., 0], -x[..., 2], x[..., 1]], axis=-1)


class _Buffer:
    """Binary chunk and the bufferViews/accessors describing it."""

    def __init__(self):
        self.chunks, self.offset = [], 0
        self.views, self.accessors = [], []

    def add(self, array, kind: str, target: int | None = None, bounds: bool = False) -> int:
        array = np.ascontiguousarray(array)
        data = array.tobytes()
        view = {"buffer": 0, "byteOffset": self.offset, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        self.chunks.append(data)
        self.offset += len(data)  # every component is 4 bytes, so views stay 4-byte aligned
        acc = {"bufferView": len(self.views) - 1, "componentType": _UINT if array.dtype == np.uint32 else _FLOAT,
               "count": len(array), "type": kind}
        if bounds:
            flat = array.reshape(len(array), -1)
            acc["min"] = flat.min(axis=0).tolist()
            acc["max"] = flat.max(axis=0).tolist()
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def blob(self) -> bytes:
        return b"".join(self.chunks)


def _morph_mesh(buf, frames, split, groups, uv=None, colour_of=None, name="mesh", scalars=None):
    """Add a mesh whose glTF vertex j is ``frames[:, split[j]]``; returns (mesh dict, target count).
    ``scalars``: {attribute name: (N,) per original vertex} added as SCALAR float attributes."""
    base = to_y_up(frames[0][split]).astype(np.float32)
    attributes = {"POSITION": buf.add(base, "VEC3", _ARRAY_BUFFER, bounds=True)}
    if uv is not None:
        attributes["TEXCOORD_0"] = buf.add(uv.astype(np.float32), "VEC2", _ARRAY_BUFFER)
    for key, values in (scalars or {}).items():
        attributes[key] = buf.add(np.asarray(values, np.float32)[split], "SCALAR", _ARRAY_BUFFER, bounds=True)
    targets = []
    for frame in frames[1:]:
        delta = to_y_up(frame[split]).astype(np.float32) - base
        targets.append({"POSITION": buf.add(delta, "VEC3", _ARRAY_BUFFER, bounds=True)})
    primitives = []
    for g, (material, tri) in enumerate(groups):
        prim = {"attributes": attributes, "indices": buf.add(tri.astype(np.uint32).ravel(), "SCALAR",
                                                             _ELEMENT_ARRAY_BUFFER, bounds=True),
                "mode": 4, "material": material}
        if targets:
            prim["targets"] = targets
        primitives.append(prim)
    mesh = {"name": name, "primitives": primitives}
    if targets:
        mesh["weights"] = [0.0] * len(targets)
        mesh["extras"] = {"targetNames": [f"frame_{k:04d}" for k in range(1, len(frames))]}
    return mesh, len(targets)


def _weights_animation(buf, frame_count: int, fps: float, node: int):
    """Sampler and channel raising morph target k−1 to weight 1 at frame k (frame 0: all zero)."""
    times = (np.arange(frame_count) / fps).astype(np.float32)
    weights = np.zeros((frame_count, frame_count - 1), np.float32)
    weights[np.arange(1, frame_count), np.arange(frame_count - 1)] = 1.0
    sampler = {"input": buf.add(times, "SCALAR", bounds=True), "output": buf.add(weights.ravel(), "SCALAR"),
               "interpolation": "LINEAR"}
    return sampler, {"target": {"node": node, "path": "weights"}}


def _fit_attributes(anim) -> dict:
    """The garment's fit of its last frame as glTF application attributes: ``_STRETCH`` [%] and, when the
    drape recorded its loads, ``_PRESSURE`` [kPa] (:func:`tailor.fit.vertex_field`). glTF animates only
    positions by morph targets, so these are the last frame's (the mesh's ``extras.fit_frame``)."""
    from ..fit import vertex_field

    k = anim.frame_count - 1
    out = {"_STRETCH": vertex_field(anim, k, "stretch")}
    if anim.contact_forces is not None:
        out["_PRESSURE"] = vertex_field(anim, k, "pressure")
    return out


def _garment_mesh(buf, anim, first_material: int):
    """(glTF mesh, morph targets) of one garment: a vertex per distinct (position, uv) corner, a
    primitive per panel (materials numbered from ``first_material``), its last frame's fit."""
    corners = np.stack([anim.faces.ravel(), anim.face_uv.ravel()], axis=1)
    unique, inverse = np.unique(corners, axis=0, return_inverse=True)
    tri = inverse.reshape(-1, 3)
    uv = anim.uv[unique[:, 1]] * np.array([1.0, -1.0]) + np.array([0.0, 1.0])
    groups = [(first_material + g, tri[anim.face_group == g]) for g in range(len(anim.group_names))
              if np.any(anim.face_group == g)]
    mesh, n_targets = _morph_mesh(buf, anim.positions, unique[:, 0], groups, uv=uv, name=anim.name,
                                  scalars=_fit_attributes(anim))
    mesh.setdefault("extras", {})["fit_frame"] = anim.frame_count - 1
    return mesh, n_targets


def write_glb(path, anim, *, with_body: bool = True) -> None:
    """Write ``anim`` (:class:`~tailor.io.animation.Animation`) as a GLB file, atomically.

    The garment (an outfit: a mesh per garment) and the body if ``with_body`` and the animation has
    one animate by morph targets at ``anim.fps``; a garment carries its last frame's fit
    (:func:`_fit_attributes`).
    Non-finite positions are refused.
    """
    anim.check_finite()
    buf = _Buffer()
    materials, meshes, nodes, samplers, channels = [], [], [], [], []
    for part in anim.split():  # an outfit: one mesh per garment
        mesh, n_targets = _garment_mesh(buf, part, len(materials))
        materials += [{"name": name, "pbrMetallicRoughness": {"baseColorFactor": [*panel_colour(len(materials) + i), 1.0],
                                                              "metallicFactor": 0.0, "roughnessFactor": 0.9},
                       "doubleSided": True} for i, name in enumerate(part.group_names)]
        meshes.append(mesh)
        nodes.append({"name": part.name, "mesh": len(meshes) - 1})
        if n_targets:
            s, c = _weights_animation(buf, anim.frame_count, anim.fps, len(nodes) - 1)
            samplers.append(s)
            channels.append({**c, "sampler": len(samplers) - 1})
    if with_body and anim.has_body:
        body_frames = anim.body_positions
        moving = not np.all(body_frames == body_frames[0])
        materials.append({"name": "body", "pbrMetallicRoughness": {"baseColorFactor": [*BODY_COLOUR, 1.0],
                                                                     "metallicFactor": 0.0, "roughnessFactor": 1.0}})
        body, body_targets = _morph_mesh(buf, body_frames if moving else body_frames[:1],
                                         np.arange(body_frames.shape[1]), [(len(materials) - 1, anim.body_faces)],
                                         name="body")
        meshes.append(body)
        nodes.append({"name": "body", "mesh": len(meshes) - 1})
        if body_targets:
            s, c = _weights_animation(buf, anim.frame_count, anim.fps, len(nodes) - 1)
            samplers.append(s)
            channels.append({**c, "sampler": len(samplers) - 1})
    blob = buf.blob()
    doc = {"asset": {"version": "2.0", "generator": "tailor"}, "scene": 0,
           "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
           "materials": materials, "buffers": [{"byteLength": len(blob)}], "bufferViews": buf.views,
           "accessors": buf.accessors}
    if samplers:
        doc["animations"] = [{"name": "drape", "samplers": samplers, "channels": channels}]
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    if total >= 2**32:
        raise TailorError(f"{path}: the animation is {total / 2**30:.1f} GiB, beyond GLB's 4 GiB; export fewer frames")
    with atomic_write(path, "wb") as fh:
        fh.write(struct.pack("<4sII", b"glTF", 2, total))
        fh.write(struct.pack("<I4s", len(text), b"JSON") + text)
        fh.write(struct.pack("<I4s", len(blob), b"BIN\0") + blob)
