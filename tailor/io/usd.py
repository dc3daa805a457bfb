"""USD export (``usd-core``): time-sampled points, UVs as a face-varying primvar, panels as subsets.

The stage is Z up in metres (``upAxis = "Z"``, ``metersPerUnit = 1``), one time code per frame at
the drape's frame rate. ``/tailor/garment`` is one ``UsdGeom.Mesh`` (welded, so seams are shared
points) with ``points`` and ``extent`` sampled at every frame, ``primvars:st`` (the flat pattern
in metres, indexed per face corner), ``primvars:displayColor`` per face (the panel's colour), and
one ``GeomSubset`` per panel (family ``materialBind``). ``/tailor/body`` is the body, animated the
same way when it moves. ``.usda`` writes text, ``.usdc`` (or ``.usd``) the binary crate.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import TailorError
from .animation import BODY_COLOUR, panel_colour
from .atomic import atomic_path

__all__ = ["write_usd", "usd_available"]


def usd_available() -> bool:
    """Whether ``pxr`` (pip install usd-core) can be imported."""
    try:
        import pxr  # noqa: F401
    except ImportError:
        return False
    return True


def _identifier(name: str, taken: set) -> str:
    ident = re.sub(r"[^A-Za-z0-9_]", "_", name) or "panel"
    if ident[0].isdigit():
        ident = "_" + ident
    base, k = ident, 1
    while ident in taken:
        k += 1
        ident = f"{base}_{k}"
    taken.add(ident)
    return ident


def _mesh(stage, path, frames, faces, colour_per_face):
    from pxr import Gf, UsdGeom, Vt

    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(faces, np.int32).ravel()))
    mesh.CreateDoubleSidedAttr(True)
    points, extent = mesh.CreatePointsAttr(), mesh.CreateExtentAttr()
    samples = [frames[0]] if np.all(frames == frames[0]) else frames
    for k, x in enumerate(samples):
        time = 0.0 if len(samples) == 1 else float(k)
        x = np.ascontiguousarray(x, dtype=np.float32)
        points.Set(Vt.Vec3fArray.FromNumpy(x), time)
        extent.Set(Vt.Vec3fArray([Gf.Vec3f(*map(float, x.min(axis=0))), Gf.Vec3f(*map(float, x.max(axis=0)))]), time)
    colours = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("displayColor", _types().Color3fArray, UsdGeom.Tokens.uniform)
    colours.Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(colour_per_face, dtype=np.float32)))
    return mesh


def _types():
    from pxr import Sdf

    return Sdf.ValueTypeNames


def _fit_primvars(mesh, anim) -> None:
    """``primvars:stretch`` [%] and, when the drape recorded its loads, ``primvars:pressure`` [kPa]
    per vertex, sampled at every frame (:func:`tailor.fit.vertex_field`)."""
    from pxr import UsdGeom, Vt

    from ..fit import vertex_field

    names = ("stretch", "pressure") if anim.contact_forces is not None else ("stretch",)
    for name in names:
        primvar = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(name, _types().FloatArray, UsdGeom.Tokens.vertex)
        for k in range(anim.frame_count):
            values = np.ascontiguousarray(vertex_field(anim, k, name), dtype=np.float32)
            primvar.Set(Vt.FloatArray.FromNumpy(values), float(k))


def _garment_prim(stage, path: str, anim, first_colour: int) -> None:
    """One garment's animated mesh at ``path``: UVs, fit primvars and a face subset per panel
    (colours numbered from ``first_colour``)."""
    from pxr import UsdGeom, Vt

    colours = np.array([panel_colour(first_colour + g) for g in anim.face_group]).reshape(-1, 3)
    garment = _mesh(stage, path, anim.positions, anim.faces, colours)
    st = UsdGeom.PrimvarsAPI(garment).CreatePrimvar("st", _types().TexCoord2fArray, UsdGeom.Tokens.faceVarying)
    st.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(anim.uv, dtype=np.float32)))
    st.SetIndices(Vt.IntArray.FromNumpy(np.ascontiguousarray(anim.face_uv, np.int32).ravel()))
    _fit_primvars(garment, anim)
    taken: set = set()
    for g, name in enumerate(anim.group_names):
        faces = np.flatnonzero(anim.face_group == g).astype(np.int32)
        if len(faces):
            subset = UsdGeom.Subset.CreateGeomSubset(garment, _identifier(name, taken), UsdGeom.Tokens.face,
                                                     Vt.IntArray.FromNumpy(faces), "materialBind")
            subset.GetPrim().SetCustomDataByKey("panel", name)


def write_usd(path, anim, *, with_body: bool = True) -> None:
    """Write ``anim`` (:class:`~tailor.io.animation.Animation`) as a USD stage, atomically.

    Needs ``usd-core`` (``pip install usd-core``); a clear error says so when it is missing.
    """
    if not usd_available():
        raise TailorError(f"{path}: USD export needs usd-core (pip install usd-core)")
    from pxr import Usd, UsdGeom

    anim.check_finite()
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(max(anim.frame_count - 1, 0))
    stage.SetTimeCodesPerSecond(anim.fps)
    stage.SetFramesPerSecond(anim.fps)
    root = UsdGeom.Xform.Define(stage, "/tailor")
    stage.SetDefaultPrim(root.GetPrim())
    stage.SetMetadata("comment", f"tailor drape of {anim.name}")
    parts = anim.split()  # an outfit: one prim per garment
    taken: set = {"body"}
    first = 0
    for part in parts:
        prim = "/tailor/garment" if len(parts) == 1 else f"/tailor/{_identifier(part.name, taken)}"
        _garment_prim(stage, prim, part, first)
        first += len(part.group_names)
    if with_body and anim.has_body:
        _mesh(stage, "/tailor/body", anim.body_positions, anim.body_faces,
              np.tile(BODY_COLOUR, (len(anim.body_faces), 1)))
    with atomic_path(path) as tmp:
        if not stage.GetRootLayer().Export(str(tmp)):
            raise TailorError(f"{path}: USD could not write the stage")
