"""Benchmark plots (matplotlib, Agg): the time–error Pareto frontier and the stability map."""

from __future__ import annotations

import math

import numpy as np

from .atomic import atomic_write

__all__ = ["pareto_plot", "stability_plot", "shadow_plot"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def pareto_plot(runs, front, path, *, title: str = "") -> None:
    """Wall time vs mean error of every stable run (one marker per integrator), the frontier as a line."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    markers = {"implicit": "o", "symplectic": "s", "verlet": "^", "rk4": "D", "forward": "v"}
    for integ in dict.fromkeys(r.integrator for r in runs):
        mine = [r for r in runs if r.integrator == integ and r.stable and math.isfinite(r.error_mean_mm) and r.label != "reference"]
        if mine:
            ax.scatter([r.wall_s for r in mine], [max(r.error_mean_mm, 1e-3) for r in mine], marker=markers.get(integ, "o"),
                       label=integ, alpha=0.8)
            for r in mine:
                ax.annotate(f"n{r.resolution} {r.dt:.2g}s {r.label}", (r.wall_s, max(r.error_mean_mm, 1e-3)), fontsize=6,
                            xytext=(3, 3), textcoords="offset points")
    if front:
        ax.plot([r.wall_s for r in front], [max(r.error_mean_mm, 1e-3) for r in front], "k--", lw=1, label="Pareto frontier")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("mean error vs reference [mm]")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)


def stability_plot(rows, path) -> None:
    """A grid per integrator: axes × values, green ok, orange unstable (stopped cleanly), red failed."""
    plt = _pyplot()
    integrators = list(dict.fromkeys(r[0] for r in rows))
    axes_names = list(dict.fromkeys(r[1] for r in rows))
    width = max(sum(1 for r in rows if r[0] == integrators[0] and r[1] == a) for a in axes_names)
    fig, axs = plt.subplots(1, len(integrators), figsize=(4.5 * len(integrators), 0.6 * len(axes_names) + 1.5), squeeze=False)
    colour = {"ok": (0.3, 0.75, 0.35), "unstable": (0.95, 0.6, 0.2)}
    for col, (ax, integ) in enumerate(zip(axs[0], integrators)):
        img = np.ones((len(axes_names), width, 3))
        for i, a in enumerate(axes_names):
            cells = [r for r in rows if r[0] == integ and r[1] == a]
            for j, r in enumerate(cells):
                img[i, j] = colour.get(r[3], (0.85, 0.15, 0.15))
                ax.text(j, i, f"{r[2]:g}", ha="center", va="center", fontsize=7)
        ax.imshow(img, aspect="auto")
        ax.set_yticks(range(len(axes_names)), axes_names if col == 0 else [], fontsize=8)
        ax.set_xticks([])
        ax.set_title(integ, fontsize=9)
    fig.suptitle("green: finished; orange: stopped with SimulationUnstable; red: failed", fontsize=9, y=1.04)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)


def shadow_plot(path, results):
    """Cusick drape shadows seen from above, one panel per result (DC and nodes in the title)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(5, len(results))
    rows = math.ceil(len(results) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(2.2 * cols, 2.4 * rows), squeeze=False)
    for ax, r in zip(axes.ravel(), results):
        geoms = getattr(r.shadow, "geoms", [r.shadow])
        for g in geoms:
            xs, ys = g.exterior.xy
            ax.fill(np.asarray(xs) * 100, np.asarray(ys) * 100, color=(0.3, 0.3, 0.35))
        t = np.linspace(0, 2 * np.pi, 100)
        ax.plot(15 * np.cos(t), 15 * np.sin(t), lw=0.5, color="0.6")
        ax.plot(9 * np.cos(t), 9 * np.sin(t), lw=0.8, color="white")
        ax.set_title(f"{r.fabric}: DC {r.drape_coefficient:.2f}, {r.nodes} nodes", fontsize=7)
        ax.set_aspect("equal")
        ax.axis("off")
    for ax in axes.ravel()[len(results):]:
        ax.axis("off")
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
