"""Fit maps to files: a PLY per frame with the fit on its faces and vertices, strain and pressure
pictures in the CLO convention, and the per-panel and ease tables (:mod:`tailor.fit`).

Strain pictures divide the range from no stretch to the top of the scale into 8 bands, blue to
red: the top is each panel's fabric's wearable stretch (CLO's "fabric" mode; the colour bar then
reads in that fabric's % when every panel shares it, else in % of each fabric's limit), or one
``maximum`` for all (CLO's "global" mode).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..errors import TailorError
from .animation import BODY_COLOUR
from .atomic import atomic_write, write_text_atomic

__all__ = ["write_ply", "write_fit", "strain_picture", "pressure_picture", "nice_top", "band_colours", "BANDS",
           "BAND_COLOURS"]

BANDS = 8
"""Colour bands of a strain or pressure picture."""

BAND_COLOURS = ((0.00, 0.20, 0.90), (0.00, 0.55, 1.00), (0.00, 0.80, 0.80), (0.10, 0.75, 0.25),
                (0.60, 0.85, 0.10), (1.00, 0.85, 0.00), (1.00, 0.50, 0.00), (0.90, 0.05, 0.05))
"""Blue (no strain) to red (the top of the scale), one colour per band."""

GARMENT_BIAS = 0.02
"""Garment faces are sorted this much [m] nearer the camera than the body they lie on."""


def write_ply(path, vertices, faces, *, vertex_props=None, face_props=None) -> None:
    """A binary little-endian PLY of a triangle mesh with float32 properties per vertex and per face."""
    vertex_props, face_props = dict(vertex_props or {}), dict(face_props or {})
    v, f = np.asarray(vertices, float), np.asarray(faces)
    for name, values in (*vertex_props.items(), *face_props.items()):
        if not np.all(np.isfinite(values)):
            raise TailorError(f"{path}: refusing to write non-finite values of {name}")
    vdt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4")] + [(k, "<f4") for k in vertex_props])
    fdt = np.dtype([("n", "u1"), ("i", "<i4", (3,))] + [(k, "<f4") for k in face_props])
    va = np.empty(len(v), vdt)
    va["x"], va["y"], va["z"] = v.T
    for k, values in vertex_props.items():
        va[k] = values
    fa = np.empty(len(f), fdt)
    fa["n"], fa["i"] = 3, f
    for k, values in face_props.items():
        fa[k] = values
    header = ["ply", "format binary_little_endian 1.0", "comment tailor fit map", f"element vertex {len(v)}",
              "property float x", "property float y", "property float z",
              *(f"property float {k}" for k in vertex_props), f"element face {len(f)}",
              "property list uchar int vertex_indices", *(f"property float {k}" for k in face_props), "end_header"]
    with atomic_write(path, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        fh.write(va.tobytes())
        fh.write(fa.tobytes())


def band_colours(values, top):
    """RGB per value: its band of :data:`BANDS` between 0 and ``top`` (per value or one), clipped."""
    t = np.clip(np.asarray(values, float) / np.maximum(top, 1e-12), 0.0, 1.0 - 1e-9)
    return np.asarray(BAND_COLOURS)[(t * BANDS).astype(int)]


def _bar(top: float, label: str):
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import BoundaryNorm, ListedColormap

    bounds = np.linspace(0.0, top, BANDS + 1)
    return ScalarMappable(norm=BoundaryNorm(bounds, BANDS), cmap=ListedColormap(BAND_COLOURS)), label


def _picture(path, fit, body, face_rgb, colorbar, title) -> None:
    from .render import render_views

    meshes = []
    if body is not None:
        meshes.append((body[0], body[1], BODY_COLOUR))
    meshes.append((fit.positions, fit.faces, face_rgb, GARMENT_BIAS))
    render_views(path, meshes, views=("front", "back"), size=(9, 6), title=title, colorbar=colorbar)


def strain_picture(path, fit, body=None, maximum: float | None = None) -> None:
    """The strain map of a :class:`~tailor.fit.FitMap`, front and back, with its colour bar."""
    wearable = fit.wearable[fit.face_group]
    if maximum is not None:
        top, label = np.full(len(wearable), maximum), f"stretch % (scale 0-{maximum:g} %)"
        bar_top = maximum
    elif np.ptp(fit.wearable) == 0:
        top, bar_top, label = wearable, float(fit.wearable[0]), "stretch % (scale: the fabric's wearable stretch)"
    else:
        top, bar_top, label = wearable, 100.0, "stretch, % of each fabric's wearable stretch"
    _picture(path, fit, body, band_colours(fit.stretch_max, top), _bar(bar_top, label),
             f"strain map, frame {fit.frame}")


def nice_top(values, floor: float = 0.01) -> float:
    """Top of a colour scale: the 99th percentile of the positive ``values`` rounded up to a round
    number (1, 1.5, 2, 3, 4, 5, 6 or 8 × a power of ten; at least ``floor``)."""
    v = np.asarray(values, float)
    v = v[v > 0]
    top = max(float(np.percentile(v, 99)) if len(v) else floor, floor)
    e = 10.0 ** np.floor(np.log10(top))
    return float(next(m * e for m in (1, 1.5, 2, 3, 4, 5, 6, 8, 10) if m * e >= top * (1 - 1e-12)))




def pressure_picture(path, fit, body=None) -> None:
    """The pressure map (per face, the mean of its vertices' pressure), front and back."""
    top = nice_top(fit.pressure_kpa)
    face = fit.pressure_kpa[fit.faces].mean(axis=1)
    _picture(path, fit, body, band_colours(face, top), _bar(top, "contact pressure, kPa"),
             f"pressure map, frame {fit.frame}")


def _ply(path, fit) -> None:
    f = fit.contact_force
    write_ply(path, fit.positions, fit.faces,
              vertex_props={"contact_fx": f[:, 0], "contact_fy": f[:, 1], "contact_fz": f[:, 2],
                            "pressure_kpa": fit.pressure_kpa, "gap_mm": fit.gap_mm},
              face_props={"stretch_max": fit.stretch_max, "stretch_warp": fit.stretch_warp,
                          "stretch_weft": fit.stretch_weft, "panel": fit.face_group})


def _csv_text(rows: list[dict]) -> str:
    buf = io.StringIO()
    if rows:
        writer = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return buf.getvalue()


def write_fit(fits, out_dir, bodies=None, *, maximum: float | None = None, pictures: bool = True) -> list[Path]:
    """Write fit maps into ``out_dir``: ``fit_NNNN.ply``, ``fit_NNNN.png``, ``pressure_NNNN.png`` per
    map, ``fit.csv`` (per frame and panel), ``ease.csv`` (per frame and landmark) and ``fit.json``
    (:func:`tailor.fit.fit_section`). ``bodies``: a :class:`~tailor.fit.BodyFrames` to draw the body
    in the pictures. Returns the files written."""
    from ..fit import fit_section

    out = Path(out_dir)
    rows, ease_rows = [], []
    for fit in fits:
        name = f"{fit.frame:04d}"
        _ply(out / f"fit_{name}.ply", fit)
        if pictures:
            body = bodies.at(fit.frame) if bodies is not None else None
            strain_picture(out / f"fit_{name}.png", fit, body, maximum)
            pressure_picture(out / f"pressure_{name}.png", fit, body)
        rows += [{"frame": fit.frame, **r} for r in fit.panel_rows()]
        ease_rows += [{"frame": fit.frame, "landmark": k, **fit.at_landmark(k)} for k in fit.ease]
    write_text_atomic(out / "fit.csv", _csv_text(rows))
    write_text_atomic(out / "ease.csv", _csv_text(ease_rows))
    write_text_atomic(out / "fit.json", json.dumps(fit_section(fits), indent=2))
    return sorted(out.iterdir())
