"""Wavefront OBJ output: positions, per-panel UVs, one group per panel, written atomically.

The OBJ is the garment format every tool reads. We write ``v`` (metres), ``vt`` (rest panel
coordinates in metres, so a texture's scale is physical), ``g`` per panel and ``f v/vt``.
A NaN or inf position is refused: nothing non-finite ever reaches a file.
"""

from __future__ import annotations

import io as _io
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import TailorError
from .atomic import atomic_write

__all__ = ["write_obj", "obj_text", "read_obj", "read_obj_vertices", "ObjMesh"]


def obj_text(x, faces, *, uv=None, face_uv=None, face_group=None, group_names=None, group_objects=None, mtl=None,
             header="") -> str:
    """The OBJ text of a mesh.

    Parameters
    ----------
    x : array_like, shape (N, 3)
        Vertex positions [m].
    faces : array_like, shape (F, 3)
        Triangles (0-based).
    uv : array_like, shape (T, 2), optional
        Texture coordinates.
    face_uv : array_like, shape (F, 3), optional
        UV index per face corner; defaults to ``faces`` (one uv per vertex).
    face_group, group_names : optional
        Group index per face and the group names (one ``g`` per group).
    group_objects : sequence of str, optional
        The object each group belongs to (an outfit's garment): an ``o`` line starts each.
    """
    x = np.asarray(x, dtype=float)
    faces = np.asarray(faces)
    if not np.all(np.isfinite(x)):
        raise TailorError("refusing to write non-finite vertex positions to OBJ")
    out = _io.StringIO()
    if header:
        out.write("".join(f"# {line}\n" for line in header.splitlines()))
    if mtl:
        out.write(f"mtllib {mtl}\n")
    out.write(_rows("v %.7g %.7g %.7g", x))
    if uv is not None:
        out.write(_rows("vt %.7g %.7g", np.asarray(uv, dtype=float)))
        fuv = faces if face_uv is None else np.asarray(face_uv)
        corners = np.stack([faces + 1, fuv + 1], axis=2).reshape(len(faces), 6)
        fmt = "f %d/%d %d/%d %d/%d"
    else:
        corners = faces + 1
        fmt = "f %d %d %d"
    if face_group is None:
        out.write(_rows(fmt, corners))
    else:
        face_group = np.asarray(face_group)
        current = None
        for gi, name in enumerate(group_names):
            sel = face_group == gi
            if sel.any():
                if group_objects is not None and group_objects[gi] != current:
                    current = group_objects[gi]
                    out.write(f"o {current}\n")
                out.write(f"g {name}\n")
                if mtl:
                    out.write(f"usemtl {name}\n")
                out.write(_rows(fmt, corners[sel]))
    return out.getvalue()


def _rows(fmt: str, rows: np.ndarray) -> str:
    """``rows`` formatted one line each, as ``np.savetxt(fmt=fmt)`` writes them, in one string
    operation instead of savetxt's line by line."""
    rows = np.asarray(rows)
    return ((fmt + "\n") * len(rows)) % tuple(rows.ravel().tolist()) if len(rows) else ""


def write_obj(path, x, faces, **kwargs) -> None:
    """Write :func:`obj_text` to ``path`` atomically."""
    text = obj_text(x, faces, **kwargs)
    with atomic_write(path) as fh:
        fh.write(text)


class ObjMesh(NamedTuple):
    """A triangle mesh read from an OBJ, in file order (nothing merged or reordered).

    Attributes
    ----------
    vertices : (N, 3) float
    faces : (F, 3) int
        Triangles, 0-based; polygons are split into fans.
    uv : (T, 2) float
        Texture coordinates (empty if none).
    face_uv : (F, 3) int or None
        UV index of each face corner.
    face_group : (F,) int
        Group of each face (0 when the file has no ``g``).
    group_names : tuple of str
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    face_uv: np.ndarray | None
    face_group: np.ndarray
    group_names: tuple


def read_obj_vertices(path) -> np.ndarray:
    """Only the ``v`` lines of an OBJ, shape (N, 3): fast, for the frames of a sequence."""
    path = Path(path)
    try:
        lines = [ln[2:] for ln in path.read_text().splitlines() if ln.startswith("v ")]
        v = np.array(" ".join(lines).split(), dtype=float)
    except (OSError, ValueError) as exc:
        raise TailorError(f"{path}: cannot read vertices: {exc}") from None
    if v.size % 3:
        raise TailorError(f"{path}: v lines must have 3 coordinates")
    return v.reshape(-1, 3)


def read_obj(path) -> ObjMesh:
    """Read a Wavefront OBJ (``v``, ``vt``, ``f`` with ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``, ``g``)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise TailorError(f"{path}: cannot read: {exc.strerror or exc}") from None
    v, vt, faces, fuv, fgroup, names = [], [], [], [], [], ["default"]
    group = 0
    for number, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        try:
            if parts[0] == "v":
                v.append([float(a) for a in parts[1:4]])
            elif parts[0] == "vt":
                vt.append([float(a) for a in parts[1:3]])
            elif parts[0] == "g":
                name = " ".join(parts[1:]) or "default"
                if name not in names:
                    names.append(name)
                group = names.index(name)
            elif parts[0] == "f":
                corners = [c.split("/") for c in parts[1:]]
                vi = [_obj_index(c[0], len(v)) for c in corners]
                ti = [_obj_index(c[1], len(vt)) if len(c) > 1 and c[1] else -1 for c in corners]
                for k in range(1, len(vi) - 1):
                    faces.append((vi[0], vi[k], vi[k + 1]))
                    fuv.append((ti[0], ti[k], ti[k + 1]))
                    fgroup.append(group)
        except (ValueError, IndexError):
            raise TailorError(f"{path}: line {number}: cannot parse {line.strip()[:40]!r}") from None
    vertices = np.array(v, dtype=float).reshape(-1, 3)
    faces = np.array(faces, dtype=np.intp).reshape(-1, 3)
    if len(faces) and (faces.max() >= len(vertices) or faces.min() < 0):
        raise TailorError(f"{path}: a face refers to a vertex that does not exist")
    fuv = np.array(fuv, dtype=np.intp).reshape(-1, 3)
    face_uv = fuv if len(fuv) and (fuv >= 0).all() else None
    used = sorted(set(fgroup)) if fgroup else [0]
    remap = np.zeros(len(names), np.intp)
    remap[used] = np.arange(len(used))
    return ObjMesh(vertices, faces, np.array(vt, dtype=float).reshape(-1, 2), face_uv,
                   remap[np.array(fgroup, dtype=np.intp)] if fgroup else np.zeros(0, np.intp),
                   tuple(names[g] for g in used))


def _obj_index(token: str, count: int) -> int:
    i = int(token)
    return i - 1 if i > 0 else count + i
