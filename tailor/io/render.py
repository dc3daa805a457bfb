"""Off-screen pictures of bodies and garments (matplotlib, Agg): front and side views.

Flat-shaded triangles sorted back to front (painter's algorithm) with a fixed light: enough for a
person to check a body or a drape at a glance, with no display and no GPU.
"""

from __future__ import annotations

import numpy as np

from .atomic import atomic_write

__all__ = ["render_views"]


def _shade(vertices, faces, view_dir, base_color):
    p = vertices[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    light = np.array([0.3, -0.6, 0.75])
    light /= np.linalg.norm(light)
    lam = np.clip(np.abs(n @ light), 0, 1) * 0.75 + 0.25
    base = np.asarray(base_color, float)
    color = np.clip((base if base.ndim == 2 else base[None, :]) * lam[:, None], 0, 1)
    depth = p.mean(axis=1) @ view_dir
    return color, depth


def render_views(path, meshes, *, views=("front", "side"), size=(8, 6), title=None, dpi=100, lines=(), colorbar=None):
    """Render ``meshes`` [(vertices (N, 3), faces (F, 3), rgb[, bias])] seen from the front (−Y) and
    side (+X) (or back) to a PNG.

    ``rgb`` is one colour or one per face; ``bias`` [m] moves a mesh's faces towards the camera when
    sorting (a garment lying on a body is drawn over the body faces within that distance).
    ``lines`` [(start (3,), end (3,), rgb)] are drawn over the meshes (landmark cuts, say).
    ``colorbar``: (matplotlib ScalarMappable, label) drawn beside the views.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    directions = {"front": (np.array([0.0, 1.0, 0.0]), (0, 2)), "side": (np.array([-1.0, 0.0, 0.0]), (1, 2)),
                  "back": (np.array([0.0, -1.0, 0.0]), (0, 2))}
    fig, axes = plt.subplots(1, len(views), figsize=size)
    axes = np.atleast_1d(axes)
    for ax, view in zip(axes, views):
        d, (i, j) = directions[view]
        polys, colors, depths = [], [], []
        for vertices, faces, rgb, *bias in meshes:
            c, z = _shade(np.asarray(vertices), np.asarray(faces), d, rgb)
            z = z - (bias[0] if bias else 0.0)
            xy = np.asarray(vertices)[:, [i, j]].copy()
            if view == "back":
                xy[:, 0] *= -1
            polys.append(xy[np.asarray(faces)])
            colors.append(c)
            depths.append(z)
        polys, colors, depths = np.concatenate(polys), np.concatenate(colors), np.concatenate(depths)
        order = np.argsort(-depths)  # far first
        ax.add_collection(PolyCollection(polys[order], facecolors=colors[order], edgecolors="none"))
        for start, end, rgb in lines:
            seg = np.array([start, end])[:, [i, j]] * ([-1.0, 1.0] if view == "back" else 1.0)
            ax.plot(seg[:, 0], seg[:, 1], color=rgb, linewidth=1.2)
        allxy = polys.reshape(-1, 2)
        ax.set_xlim(allxy[:, 0].min() - 0.05, allxy[:, 0].max() + 0.05)
        ax.set_ylim(allxy[:, 1].min() - 0.05, allxy[:, 1].max() + 0.05)
        ax.set_aspect("equal")
        ax.set_title(view)
        ax.axis("off")
    if colorbar is not None:
        mappable, label = colorbar
        fig.colorbar(mappable, ax=list(axes), label=label, shrink=0.8)
    if title:
        fig.suptitle(title)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
