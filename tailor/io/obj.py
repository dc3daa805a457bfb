"""Wavefront OBJ output: positions, per-panel UVs, one group per panel, written atomically.

The OBJ is the garment format every tool reads. We write ``v`` (metres), ``vt`` (rest panel
coordinates in metres, so a texture's scale is physical), ``g`` per panel and ``f v/vt``.
A NaN or inf position is refused: nothing non-finite ever reaches a file.
"""

from __future__ import annotations

import io as _io

import numpy as np

from ..errors import TailorError
from .atomic import atomic_write

__all__ = ["write_obj", "obj_text"]


def obj_text(x, faces, *, uv=None, face_uv=None, face_group=None, group_names=None, mtl=None, header="") -> str:
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
    np.savetxt(out, x, fmt="v %.7g %.7g %.7g")
    if uv is not None:
        np.savetxt(out, np.asarray(uv, dtype=float), fmt="vt %.7g %.7g")
        fuv = faces if face_uv is None else np.asarray(face_uv)
        corners = np.stack([faces + 1, fuv + 1], axis=2).reshape(len(faces), 6)
        fmt = "f %d/%d %d/%d %d/%d"
    else:
        corners = faces + 1
        fmt = "f %d %d %d"
    if face_group is None:
        np.savetxt(out, corners, fmt=fmt)
    else:
        face_group = np.asarray(face_group)
        for gi, name in enumerate(group_names):
            sel = face_group == gi
            if sel.any():
                out.write(f"g {name}\n")
                if mtl:
                    out.write(f"usemtl {name}\n")
                np.savetxt(out, corners[sel], fmt=fmt)
    return out.getvalue()


def write_obj(path, x, faces, **kwargs) -> None:
    """Write :func:`obj_text` to ``path`` atomically."""
    text = obj_text(x, faces, **kwargs)
    with atomic_write(path) as fh:
        fh.write(text)
