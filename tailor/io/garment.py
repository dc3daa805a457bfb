"""Writing a drape: an OBJ per frame (welded seams, per-panel UVs and groups), a material file,
optionally the body, and ``report.json`` — all into a fresh folder that appears only when complete.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..errors import TailorError
from .animation import LOADS_FILE, mtl_text, welded
from .obj import obj_text

__all__ = ["write_drape"]

def write_drape(result, out_dir, *, overwrite: bool = False, with_body: bool = False) -> Path:
    """Write ``result`` (:class:`tailor.dress.DrapeResult`) into ``out_dir``.

    Files: ``garment_0000.obj`` … (``v`` welded so a seam is one vertex, ``vt`` the flat pattern in
    metres, one ``g`` per panel; an outfit's garments one ``o`` each, panels ``GARMENT/PANEL``), ``garment.mtl``, optionally ``body_0000.obj`` …, ``loads.npz``
    (per frame the body's contact and the attachments' forces on each OBJ vertex, N:
    ``contact_0000``, ``attachment_0000`` …, what :mod:`tailor.fit` reads) and ``report.json``. A garment cut or torn during the run is written with each frame's own mesh.
    Everything is written into a temporary folder beside ``out_dir`` and renamed
    into place at the end; an existing ``out_dir`` is refused unless ``overwrite``.
    """
    out = Path(out_dir)
    if out.exists() and not overwrite:
        raise TailorError(f"{out}: already exists; choose another --out or pass --overwrite")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        names = result.mesh.panel_names
        pieces = result.pattern.pieces
        objects = [result.pattern.piece_of(i).name for i in range(len(names))] if pieces else None
        (tmp / "garment.mtl").write_text(mtl_text(names))
        for k, x in enumerate(result.frames):
            mesh, weld = result.topology_at(k)  # a cut or a tear changes the mesh from its frame on
            xw, faces = welded(weld, mesh.faces, x)
            text = obj_text(xw, faces, uv=mesh.uv, face_uv=mesh.faces, face_group=mesh.face_panel, group_names=names,
                            group_objects=objects, mtl="garment.mtl", header=f"tailor drape of {result.pattern.name}, frame {k}")
            (tmp / f"garment_{k:04d}.obj").write_text(text)
            if with_body:
                (tmp / f"body_{k:04d}.obj").write_text(obj_text(result.body_frames[k], result.body_faces))
        if result.contact_forces:
            loads = {f"contact_{k:04d}": c for k, c in enumerate(result.contact_forces)}
            loads.update({f"attachment_{k:04d}": a for k, a in enumerate(result.attachment_forces)})
            np.savez_compressed(tmp / LOADS_FILE, **loads)
        report = result.report.to_json()
        report["pattern"] = result.pattern.source
        report["name"] = result.pattern.name
        report["frames_written"] = len(result.frames)
        (tmp / "report.json").write_text(json.dumps(report, indent=2, default=_jsonable))
        if out.exists():
            trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old.", dir=out.parent))
            out.rename(trash / out.name)
            tmp.rename(out)
            shutil.rmtree(trash, ignore_errors=True)
        else:
            tmp.rename(out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
