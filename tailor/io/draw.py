"""Pattern drawings: the flat panels as a tailor lays them out, to PNG or SVG (matplotlib).

Each panel is drawn in its colour (the same as in the OBJ material, GLB, USD and previews) with
its name, its edge numbers (``edges[i]`` in the file, grey, inside the outline), a grain arrow
(the warp direction) and optionally its triangle mesh. Every seam has one colour and number,
drawn as a thick stroke on both of its sides, with **notches** (short ticks across the edge) at
both ends and an arrowhead at the end its fraction 1 lies: the two arrows of a seam point to the
points that are sewn together, so a twisted seam shows as arrows running opposite ways around
the garment. Attachments are dashed black. Axes are in centimetres.
"""

from __future__ import annotations

import logging

import numpy as np

from ..curves import loop_polyline, sample_curve
from .animation import panel_colour
from .atomic import atomic_write

__all__ = ["draw_pattern", "panel_layout"]

log = logging.getLogger(__name__)

GAP = 0.08
"""Space between panels in the layout [m]."""


def panel_layout(pattern, gap: float = GAP) -> list[np.ndarray]:
    """Offset [m] of each panel's coordinates in a drawing: rows of panels, roughly as wide as tall."""
    boxes = []
    for p in pattern.panels:
        pts = loop_polyline([e.curve for e in p.edges])
        boxes.append((pts.min(axis=0), pts.max(axis=0)))
    widths = np.array([hi[0] - lo[0] for lo, hi in boxes])
    heights = np.array([hi[1] - lo[1] for lo, hi in boxes])
    row_width = max(float(widths.max()), float(np.sqrt((widths + gap) @ (heights + gap)) * 1.4))
    offsets, x, y, row_h = [], 0.0, 0.0, 0.0
    for (lo, hi), w, h in zip(boxes, widths, heights):
        if x > 0 and x + w > row_width:
            x, y, row_h = 0.0, y - row_h - gap, 0.0
        offsets.append(np.array([x, y - h]) - lo)
        x += w + gap
        row_h = max(row_h, h)
    return offsets


def _side_points(pattern, side, n: int = 24) -> np.ndarray:
    edge = pattern.panel(side.panel).loop(side.hole)[side.edge]
    return sample_curve(edge.curve, np.linspace(side.start, side.end, n))


def _inward(panel, pts):
    """Unit normals pointing into the panel for points along its outline (its winding known)."""
    t = np.gradient(pts, axis=0)
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    n = np.stack([-t[:, 1], t[:, 0]], axis=1)  # left of the direction of travel
    return n if panel.signed_area > 0 else -n


def draw_pattern(pattern, path, *, mesh_resolution: float | None = None, dpi: int = 150) -> None:
    """Draw ``pattern`` to ``path`` (``.png`` or ``.svg``), atomically.

    ``mesh_resolution`` [m] also draws the triangle mesh :func:`tailor.mesh.discretise` makes.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..errors import TailorError

    fmt = str(path).rsplit(".", 1)[-1].lower()
    if fmt not in ("png", "svg"):
        raise TailorError(f"{path}: a drawing is .png or .svg")
    offsets = panel_layout(pattern)
    allpts = np.concatenate([loop_polyline([e.curve for e in p.edges]) + o for p, o in zip(pattern.panels, offsets)])
    span = (allpts.max(axis=0) - allpts.min(axis=0)) * CM
    scale = 8.0 / max(span.max(), 1e-9)
    fig, ax = plt.subplots(figsize=(max(span[0] * scale, 3) + 1.5, max(span[1] * scale, 3) + 1.0))
    size = max(span.max(), 10.0)  # cm: notch, arrow and text sizes follow the drawing
    mesh = None
    if mesh_resolution:
        from ..mesh import discretise

        mesh = discretise(pattern, mesh_resolution)
    for i, (panel, off) in enumerate(zip(pattern.panels, offsets)):
        _draw_panel(ax, i, panel, off, mesh, size)
    _draw_seams(ax, pattern, offsets, size, plt.get_cmap("tab20"))
    _draw_attachments(ax, pattern, offsets)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.04)
    ax.set_xlabel("cm")
    ax.set_title(f"{pattern.name}: {len(pattern.panels)} panels, {len(pattern.seams)} seams"
                 + (f", mesh {mesh_resolution * CM:g} cm" if mesh_resolution else ""), fontsize=9)
    ax.tick_params(labelsize=7)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format=fmt, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    log.debug("drew %s -> %s", pattern.name, path)


CM = 100.0
"""Drawings are in cm."""


def _draw_panel(ax, i, panel, off, mesh, size) -> None:
    """One panel: outline, holes, its mesh, edge numbers, name and grain arrow."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import FancyArrowPatch, Polygon as PolygonPatch

    colour = panel_colour(i)
    outline = (loop_polyline([e.curve for e in panel.edges]) + off) * CM
    ax.add_patch(PolygonPatch(outline, closed=True, facecolor=(*colour, 0.18), edgecolor="black", linewidth=0.8))
    for hole in panel.holes:
        ax.add_patch(PolygonPatch((loop_polyline([e.curve for e in hole]) + off) * CM, closed=True,
                                  facecolor="white", edgecolor="black", linewidth=0.8))
    if mesh is not None:
        faces = mesh.faces[mesh.face_panel == i]
        tri = (mesh.uv[faces] + off) * CM
        ax.add_collection(LineCollection(np.concatenate([tri, tri[:, :1]], axis=1), colors=[(*colour, 0.6)],
                                         linewidths=0.3))
    for k, edge in enumerate(panel.edges):  # edge numbers, just inside the outline
        mid = sample_curve(edge.curve, [0.45, 0.5, 0.55])
        inward = _inward(panel, mid)[1]
        ax.text(*((mid[1] + off) * CM + inward * size * 0.025), str(k), fontsize=6, color="0.45",
                ha="center", va="center")
    centre = (outline.min(axis=0) + outline.max(axis=0)) / 2
    ext = outline.max(axis=0) - outline.min(axis=0)
    g = np.array([np.cos(panel.grain), np.sin(panel.grain)]) * min(ext) * 0.3
    ax.add_patch(FancyArrowPatch(centre - g, centre + g, arrowstyle="<|-|>", mutation_scale=8, color="0.25",
                                 linewidth=0.8))
    ax.text(centre[0], centre[1] - min(ext) * 0.05, panel.name, fontsize=8, ha="center", va="top",
            rotation=0, bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.7, "pad": 1})
    _draw_marks(ax, panel, off)


MARK_STYLES = {"notch": {"marker": "^", "markersize": 4, "linestyle": "none", "color": "black"},
               "drill_hole": {"marker": "o", "markersize": 5, "linestyle": "none", "markerfacecolor": "none",
                              "color": "black"},
               "internal_line": {"linestyle": "--", "linewidth": 0.7, "color": "0.3"},
               "mirror_line": {"linestyle": "-.", "linewidth": 0.7, "color": "0.3"}}
"""How a panel's marks from CAD are drawn."""


def _draw_marks(ax, panel, off) -> None:
    for kind, pts in panel.marks:
        p = (np.asarray(pts) + off) * CM
        ax.plot(p[:, 0], p[:, 1], **MARK_STYLES[kind])


def _draw_seams(ax, pattern, offsets, size, cmap) -> None:
    """Every seam's two sides in one colour, with notches at both ends, a direction arrow and its number."""
    from matplotlib.patches import FancyArrowPatch

    for j, seam in enumerate(pattern.seams):
        colour = cmap(j % 20)
        for side in (seam.a, seam.b):
            pi = pattern.panel_index(side.panel)
            panel, off = pattern.panels[pi], offsets[pi]
            pts = (_side_points(pattern, side) + off) * CM
            ax.plot(pts[:, 0], pts[:, 1], color=colour, linewidth=2.5, solid_capstyle="butt")
            inward = _inward(panel, pts) * (-1 if side.reversed else 1)
            length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
            notch = min(size * 0.02, 0.12 * length)  # short darts get short notches
            for end in (0, -1):  # notches across the edge at both ends of the sewn stretch
                n = inward[end] * notch
                ax.plot([pts[end, 0] - n[0], pts[end, 0] + n[0]], [pts[end, 1] - n[1], pts[end, 1] + n[1]],
                        color=colour, linewidth=1.2)
            ax.add_patch(FancyArrowPatch(pts[-5], pts[-1], arrowstyle="-|>", mutation_scale=12, color=colour,
                                         linewidth=1.0, shrinkA=0, shrinkB=0))
            mid = pts[len(pts) // 2] + inward[len(pts) // 2] * size * 0.045
            ax.text(mid[0], mid[1], str(j), fontsize=7, color=colour, ha="center", va="center", fontweight="bold")


def _draw_attachments(ax, pattern, offsets) -> None:
    """Attachments: dashed edges, dotted corners."""
    for att in pattern.attachments:
        pi = pattern.panel_index(att.panel)
        off = offsets[pi]
        if att.edge is not None:
            pts = (_side_points(pattern, att) + off) * CM
            ax.plot(pts[:, 0], pts[:, 1], color="black", linewidth=1.5, linestyle=(0, (3, 2)))
        else:
            v = (np.asarray(pattern.panels[pi].vertices[att.vertex]) + off) * CM
            ax.plot(*v, marker="o", color="black", markersize=4)
