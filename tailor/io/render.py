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
    color = np.clip(np.asarray(base_color)[None, :] * lam[:, None], 0, 1)
    depth = p.mean(axis=1) @ view_dir
    return color, depth


def render_views(path, meshes, *, views=("front", "side"), size=(8, 6), title=None, dpi=100, lines=()):
    """Render ``meshes`` [(vertices (N, 3), faces (F, 3), rgb)] seen from the front (−Y) and side (+X) to a PNG.

    ``lines`` [(start (3,), end (3,), rgb)] are drawn over the meshes (landmark cuts, say).
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
        for vertices, faces, rgb in meshes:
            c, z = _shade(np.asarray(vertices), np.asarray(faces), d, rgb)
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
    if title:
        fig.suptitle(title)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
