"""Writing a drape: an OBJ per frame (welded seams, per-panel UVs and groups), a material file,
optionally the body, the loads and ``report.json`` — all into a fresh folder that appears only when complete.

:class:`DrapeWriter` writes frames as the simulation hands them over (``tailor drape`` streams
them: a long animation takes no more memory than a short one); :func:`write_drape` writes a
finished :class:`~tailor.dress.DrapeResult` through it.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from ..dress.report import DrapeFrame
from ..errors import TailorError
from .animation import LOADS_FILE, mtl_text, welded
from .obj import obj_text

__all__ = ["write_drape", "DrapeWriter"]


class DrapeWriter:
    """Writes a drape's frames into ``out_dir`` as they come: ``writer(frame)`` for each
    :class:`~tailor.dress.DrapeFrame` (a ``sink`` of :func:`~tailor.dress.drape`), then
    :meth:`finish` with the report.

    Files: ``garment_0000.obj`` … (``v`` welded so a seam is one vertex, ``vt`` the flat pattern in
    metres, one ``g`` per panel; an outfit's garments one ``o`` each, panels ``GARMENT/PANEL``),
    ``garment.mtl``, optionally ``body_0000.obj`` …, ``loads.npz`` (per frame the body's contact and
    the attachments' forces on each OBJ vertex, N: ``contact_0000``, ``attachment_0000`` …, what
    :mod:`tailor.fit` reads; each array stored as it comes) and ``report.json``. A garment cut or torn
    during the run is written with each frame's own mesh.

    Everything goes into a temporary folder beside ``out_dir``, renamed into place by :meth:`finish`;
    an existing ``out_dir`` is refused unless ``overwrite`` (then replaced only at the end). Used as a
    context manager, a run that fails before :meth:`finish` leaves nothing behind.
    """

    def __init__(self, out_dir, pattern, *, overwrite: bool = False, body_faces=None):
        out = Path(out_dir)
        if out.exists() and not overwrite:
            raise TailorError(f"{out}: already exists; choose another --out or pass --overwrite")
        out.parent.mkdir(parents=True, exist_ok=True)
        self.out, self.pattern = out, pattern
        # an outfit's garments one ``o`` each: the garment of every panel
        self._objects = [pattern.piece_of(i).name for i in range(len(pattern.panels))] if pattern.pieces else None
        self.body_faces = None if body_faces is None else np.asarray(body_faces)
        self.count = 0
        self._tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
        self._loads: zipfile.ZipFile | None = None

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        if kind is not None:
            self.abort()
        return False

    def __call__(self, frame: DrapeFrame) -> None:
        """Write one frame (frames must come in order: 0, 1, …)."""
        if self._tmp is None:
            raise RuntimeError("DrapeWriter: already finished")
        if frame.index != self.count:
            raise ValueError(f"DrapeWriter: frame {frame.index} given where frame {self.count} was due")
        mesh, k = frame.mesh, self.count
        names = mesh.panel_names
        if k == 0:
            (self._tmp / "garment.mtl").write_text(mtl_text(names))
        xw, faces = welded(frame.weld, mesh.faces, frame.x)
        text = obj_text(xw, faces, uv=mesh.uv, face_uv=mesh.faces, face_group=mesh.face_panel, group_names=names,
                        group_objects=self._objects, mtl="garment.mtl",
                        header=f"tailor drape of {self.pattern.name}, frame {k}")
        (self._tmp / f"garment_{k:04d}.obj").write_text(text)
        if self.body_faces is not None:
            (self._tmp / f"body_{k:04d}.obj").write_text(obj_text(frame.body_x, self.body_faces))
        if frame.contact_force is not None:
            self._store(f"contact_{k:04d}", frame.contact_force)
            self._store(f"attachment_{k:04d}", frame.attachment_force)
        self.count += 1

    def _store(self, name: str, array) -> None:
        """One array into ``loads.npz`` (NumPy's ``savez_compressed`` layout, written member by member)."""
        if self._loads is None:
            self._loads = zipfile.ZipFile(self._tmp / LOADS_FILE, "w", compression=zipfile.ZIP_DEFLATED)
        with self._loads.open(f"{name}.npy", "w", force_zip64=True) as f:
            np.lib.format.write_array(f, np.asanyarray(array), allow_pickle=False)

    def finish(self, report) -> Path:
        """``report.json`` (``report``: the drape's :class:`~tailor.dress.DrapeReport`) and the folder
        renamed into place; returns ``out_dir``."""
        if self._tmp is None:
            raise RuntimeError("DrapeWriter: already finished")
        if self._loads is not None:
            self._loads.close()
        out = report.to_json()
        out["pattern"] = self.pattern.source
        out["name"] = self.pattern.name
        out["frames_written"] = self.count
        (self._tmp / "report.json").write_text(json.dumps(out, indent=2, default=_jsonable))
        _replace(self._tmp, self.out)
        self._tmp = None
        return self.out

    def abort(self) -> None:
        """Remove everything written so far (the run failed)."""
        if self._loads is not None:
            self._loads.close()
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None


def _replace(tmp: Path, out: Path) -> None:
    """``tmp`` renamed to ``out``, an existing ``out`` moved aside first and removed after."""
    if out.exists():
        trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old.", dir=out.parent))
        out.rename(trash / out.name)
        tmp.rename(out)
        shutil.rmtree(trash, ignore_errors=True)
    else:
        tmp.rename(out)


def write_drape(result, out_dir, *, overwrite: bool = False, with_body: bool = False) -> Path:
    """Write ``result`` (:class:`tailor.dress.DrapeResult`, its frames kept) into ``out_dir`` with a
    :class:`DrapeWriter`: the same files, appearing only when complete."""
    if not result.frames:
        raise TailorError("write_drape: the result holds no frames (draped with keep_frames=False: give a "
                          "DrapeWriter as its sink instead)")
    loads = bool(result.contact_forces)
    with DrapeWriter(out_dir, result.pattern, overwrite=overwrite,
                     body_faces=result.body_faces if with_body else None) as writer:
        for k, x in enumerate(result.frames):
            mesh, weld = result.topology_at(k)  # a cut or a tear changes the mesh from its frame on
            writer(DrapeFrame(k, x, result.body_frames[k], result.contact_forces[k] if loads else None,
                              result.attachment_forces[k] if loads else None, mesh, weld))
        return writer.finish(result.report)


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
