"""Export a drape in the formats artists use: OBJ sequence, PC2 point cache, GLB, USD.

=========  ===========================================  ============================================
format     files                                         opens in
=========  ===========================================  ============================================
``obj``    ``garment_0000.obj`` … (+ ``garment.mtl``)     everything (one file per frame)
``pc2``    ``<name>.pc2`` + ``<name>_base.obj``           Blender (Mesh Cache modifier), 3ds Max
``glb``    ``<name>.glb`` (morph-target animation)        Blender, three.js, Unreal, online viewers
``usd``    ``<name>.usdc`` (``usda``: text)               Blender, Houdini, Maya, usdview, Omniverse
=========  ===========================================  ============================================

An outfit's garments are one mesh each: a PC2 cache and base mesh per garment (named after it), a
GLB mesh and node per garment, a USD prim ``/tailor/<garment>`` per garment.

:func:`export` takes a :class:`~tailor.dress.DrapeResult`, an
:class:`~tailor.io.animation.Animation` or a run folder written by ``tailor drape``.
"""

from __future__ import annotations

import logging
from pathlib import Path

from ..errors import TailorError
from .animation import Animation, animation_from_drape, mtl_text, read_run
from .atomic import write_text_atomic
from .obj import write_obj
from .pc2 import write_pc2

__all__ = ["export", "FORMATS", "as_animation", "read_run"]

log = logging.getLogger(__name__)

FORMATS = ("obj", "pc2", "glb", "usd", "usda")
"""Export formats; ``usd`` is the binary crate (.usdc), ``usda`` the text form."""


def as_animation(source, *, with_body: bool = True) -> Animation:
    """An :class:`Animation` from a DrapeResult, an Animation or a run folder."""
    if isinstance(source, Animation):
        return source
    if isinstance(source, (str, Path)):
        return read_run(source, with_body=with_body)
    if hasattr(source, "frames") and hasattr(source, "weld"):
        return animation_from_drape(source, with_body=with_body)
    raise TailorError(f"cannot export a {type(source).__name__}; give a drape result, an Animation or a run folder")


def _write_garment_obj(path, anim: Animation, k: int, header: str, mtl: str | None = None) -> Path:
    write_obj(path, anim.positions[k], anim.faces, uv=anim.uv, face_uv=anim.face_uv, face_group=anim.face_group,
              group_names=anim.group_names, header=header, mtl=mtl)
    return Path(path)


def export(source, fmt: str, out, *, with_body: bool = True) -> list[Path]:
    """Write ``source`` in format ``fmt`` (one of :data:`FORMATS`) into folder ``out``; returns the files.

    Every file is written atomically; non-finite positions are refused. ``with_body`` also
    exports the body when the source has it.
    """
    if fmt not in FORMATS:
        raise TailorError(f"unknown export format {fmt!r}; choose from {', '.join(FORMATS)}")
    anim = as_animation(source, with_body=with_body)
    anim.check_finite()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    body = with_body and anim.has_body
    name = anim.name
    written: list[Path] = []
    if fmt == "obj":
        write_text_atomic(out / "garment.mtl", mtl_text(anim.group_names))
        written.append(out / "garment.mtl")
        for k in range(anim.frame_count):
            written.append(_write_garment_obj(out / f"garment_{k:04d}.obj", anim, k, f"tailor drape of {name}, frame {k}",
                                              mtl="garment.mtl"))
            if body:
                write_obj(out / f"body_{k:04d}.obj", anim.body_positions[k], anim.body_faces)
                written.append(out / f"body_{k:04d}.obj")
    elif fmt == "pc2":
        parts = anim.split()  # an outfit: a cache per garment
        for part in parts:
            stem = name if len(parts) == 1 else part.name
            written.append(_write_garment_obj(out / f"{stem}_base.obj", part, 0, f"tailor: base mesh of {stem}.pc2"))
            write_pc2(out / f"{stem}.pc2", part.positions)
            written.append(out / f"{stem}.pc2")
        if body:
            write_obj(out / "body_base.obj", anim.body_positions[0], anim.body_faces)
            write_pc2(out / "body.pc2", anim.body_positions)
            written += [out / "body_base.obj", out / "body.pc2"]
    elif fmt == "glb":
        from .gltf import write_glb

        write_glb(out / f"{name}.glb", anim, with_body=body)
        written.append(out / f"{name}.glb")
    else:
        from .usd import write_usd

        p = out / f"{name}.{'usda' if fmt == 'usda' else 'usdc'}"
        write_usd(p, anim, with_body=body)
        written.append(p)
    log.debug("exported %s: %s", fmt, ", ".join(p.name for p in written[:3]) + (" …" if len(written) > 3 else ""))
    return written

