"""Previews of a drape: shaded frames rendered off-screen (matplotlib Agg) and an animated GIF.

The same painter's algorithm as :mod:`tailor.io.render` (flat-shaded triangles sorted back to
front), seen by an orthographic camera at any azimuth and elevation: the body in grey, each panel
of the garment in its colour (:data:`tailor.io.animation.PANEL_COLOURS`). The frame's extent is
fixed over the whole animation, so the garment moves and the camera does not. The body is closed,
so its faces turned away from the camera are culled; the garment is two-sided.
"""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from ..errors import TailorError
from .animation import BODY_COLOUR, Animation, panel_colour
from .atomic import atomic_write

__all__ = ["camera", "preview", "PreviewSettings"]

GARMENT_DEPTH_BIAS = 0.02
"""Metres by which garment faces are moved toward the camera when sorting against the body."""

log = logging.getLogger(__name__)


def camera(azimuth: float, elevation: float):
    """Orthonormal (right, up, view) of a camera at ``azimuth`` (rad; 0 = in front, at −Y, π/2 = at
    the body's left, +X) and ``elevation`` (rad above the horizon), looking at the origin."""
    eye = np.array([np.sin(azimuth) * np.cos(elevation), -np.cos(azimuth) * np.cos(elevation), np.sin(elevation)])
    view = -eye
    right = np.cross(view, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    return right, np.cross(right, view), view


class PreviewSettings:
    """How previews look: camera angles in degrees (as in files), picture size in pixels."""

    def __init__(self, azimuth: float = -30.0, elevation: float = 10.0, width: int = 360, height: int = 480,
                 every: int = 1, colour: str = "panel"):
        from ..fit import VERTEX_FIELDS

        if width < 16 or height < 16:
            raise TailorError("preview size: width and height must be at least 16 pixels")
        if every < 1:
            raise TailorError("preview --every must be at least 1")
        if colour not in ("panel", *VERTEX_FIELDS):
            raise TailorError(f"preview --color: choose panel or one of {', '.join(VERTEX_FIELDS)}, got {colour!r}")
        self.azimuth, self.elevation = np.radians(azimuth), np.radians(elevation)
        self.width, self.height, self.every = int(width), int(height), int(every)
        self.colour = colour


def _shaded(x, faces, rgb, basis, cull: bool):
    """Projected triangles (T, 3, 2), shaded colours (T, 3) and depths of a mesh; ``rgb`` per face."""
    right, up, view = basis
    p = x[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-15)
    rgb = np.asarray(rgb, float)
    if cull:
        keep = n @ view < 0  # facing the camera
        p, n, rgb = p[keep], n[keep], rgb[keep]
    light = -view + 0.6 * up + 0.3 * right
    light /= np.linalg.norm(light)
    lam = 0.3 + 0.7 * np.abs(n @ light)
    colours = np.clip(rgb * lam[:, None], 0, 1)
    xy = np.stack([p @ right, p @ up], axis=-1)
    return xy, colours, p.mean(axis=1) @ view


UNITS = {"stretch": "%", "pressure": "kPa", "gap": "mm"}


def _fit_colours(anim: Animation, frames, field: str):
    """Per frame rendered, the garment's face colours by a fit field (the mean of its vertices', in
    8 bands from 0 to one top for the whole animation: :func:`~tailor.io.fit_files.nice_top`), and
    the legend's text."""
    from ..fit import vertex_field
    from .fit_files import band_colours, nice_top

    values = {k: vertex_field(anim, k, field)[anim.faces].mean(axis=1) for k in frames}
    top = nice_top(np.concatenate(list(values.values())))
    return {k: band_colours(v, top) for k, v in values.items()}, f"{field} 0-{top:g} {UNITS[field]}, blue to red"


def _meshes(anim: Animation, k: int, garment_rgb=None):
    if garment_rgb is None:
        garment_rgb = np.array([panel_colour(g) for g in range(len(anim.group_names))])[anim.face_group]
    out = []
    if anim.has_body:
        out.append((anim.body_positions[k], anim.body_faces, np.tile(BODY_COLOUR, (len(anim.body_faces), 1)), True))
    out.append((anim.positions[k], anim.faces, garment_rgb, False))
    return out


def preview(anim: Animation, out_dir, *, settings: PreviewSettings | None = None, gif: bool = True,
            progress=None) -> list[Path]:
    """Render every ``settings.every``-th frame of ``anim`` to ``out_dir/frame_0000.png`` … and,
    if ``gif``, ``out_dir/<name>.gif`` playing at the drape's rate. Returns the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from PIL import Image

    s = settings or PreviewSettings()
    anim.check_finite()
    basis = camera(s.azimuth, s.elevation)
    frames = list(range(0, anim.frame_count, s.every))
    # fixed extent: every projected vertex of every frame shown
    clouds = [anim.positions[frames]] + ([anim.body_positions[frames]] if anim.has_body else [])
    pts = np.concatenate([c.reshape(-1, 3) for c in clouds])
    lo = np.array([(pts @ basis[0]).min(), (pts @ basis[1]).min()])
    hi = np.array([(pts @ basis[0]).max(), (pts @ basis[1]).max()])
    centre, half = (lo + hi) / 2, (hi - lo) / 2 * 1.05 + 0.01
    aspect = s.width / s.height
    half = np.array([max(half[0], half[1] * aspect), max(half[1], half[0] / aspect)])
    dpi = 100
    fig = plt.figure(figsize=(s.width / dpi, s.height / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(centre[0] - half[0], centre[0] + half[0])
    ax.set_ylim(centre[1] - half[1], centre[1] + half[1])
    ax.axis("off")
    fig.patch.set_facecolor("white")
    poly = PolyCollection([], linewidths=0.3, antialiased=True)
    ax.add_collection(poly)
    colours_of, legend = ({}, None) if s.colour == "panel" else _fit_colours(anim, frames, s.colour)
    if legend:
        ax.text(0.02, 0.02, legend, transform=ax.transAxes, fontsize=7)
    out = Path(out_dir)
    written, images = [], []
    try:
        for i, k in enumerate(frames):
            xy, colours, depth = zip(*(_shaded(np.asarray(x), np.asarray(f), rgb, basis, cull)
                                       for x, f, rgb, cull in _meshes(anim, k, colours_of.get(k))))
            # the garment lies on the body: sorting by centroid alone lets small body triangles
            # under a large cloth triangle win; a garment face is drawn over body faces within 2 cm
            depth = depth[:-1] + (depth[-1] - GARMENT_DEPTH_BIAS,)
            xy, colours, depth = np.concatenate(xy), np.concatenate(colours), np.concatenate(depth)
            order = np.argsort(-depth)  # far first
            poly.set_verts(xy[order])
            poly.set_facecolor(colours[order])
            poly.set_edgecolor(colours[order])  # hides the hairline gaps between triangles
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi)
            path = out / f"frame_{k:04d}.png"
            with atomic_write(path, "wb") as fh:
                fh.write(buf.getvalue())
            written.append(path)
            if gif:
                images.append(Image.open(io.BytesIO(buf.getvalue())).convert("RGB"))
            if progress:
                progress(i + 1, len(frames))
    finally:
        plt.close(fig)
    if gif and images:
        path = out / f"{anim.name}.gif"
        palette = images[len(images) // 2].quantize(colors=128, method=Image.Quantize.MEDIANCUT)
        frames_p = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
        duration = int(round(1000 * s.every / anim.fps))
        with atomic_write(path, "wb") as fh:
            frames_p[0].save(fh, format="GIF", save_all=True, append_images=frames_p[1:], duration=duration, loop=0,
                             optimize=True)
        written.append(path)
    log.debug("preview: %d frames -> %s", len(frames), out)
    return written
