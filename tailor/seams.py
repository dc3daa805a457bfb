"""Sewing: seaming forces that close seams (Carignan Eq. 15), then merging (Eq. 16–18).

While a seam pair is apart, each of its vertices is pulled towards the other by
f_i = k·m_i·(r_j − r_i) (Eq. 15 with the paper's k·η folded into one rate k [1/s²]), damped along
the pair and capped in acceleration so the first frames never explode. As soon as a pair is closer
than d it is merged: the two vertices become one particle of the summed mass, at the
mass-weighted position (Eq. 18) with the momentum-conserving velocity (Eq. 17). Merging is a
*weld* of the mesh (:func:`tailor.model.build_model` with ``weld``): the implicit solver then sees
one particle, not two copies held together, and the sewn garment is one connected mesh.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["Sewing", "merge_state"]


@dataclass
class Sewing:
    """The seam pairs of a garment and which of them are merged (indices of the unwelded mesh).

    Attributes
    ----------
    pairs : (S, 2) int
        Vertex pairs to sew (pairs of a vertex with itself are dropped).
    rate : float
        k of Eq. 15 [1/s²]: pull per metre of gap, per unit mass.
    max_acceleration : float
        Cap on the seaming acceleration [m/s²].
    merge_distance : float
        d of Eq. 16 [m].
    merged : (S,) bool
    max_gap_at_merge : float
        Widest gap [m] any pair had when it was merged.
    active : (S,) bool
        The pairs sewing now (an outfit sews one garment at a time: :meth:`sew_only`); all at first.
    """

    pairs: np.ndarray
    rate: float = 1000.0
    max_acceleration: float = 50.0
    merge_distance: float = 0.004
    merged: np.ndarray = field(default=None)
    max_gap_at_merge: float = 0.0
    active: np.ndarray = field(default=None)

    def __post_init__(self):
        pairs = np.asarray(self.pairs, dtype=np.intp).reshape(-1, 2)
        keep = pairs[:, 0] != pairs[:, 1]
        self.pairs = pairs[keep]
        if self.merged is None:
            self.merged = np.zeros(len(self.pairs), bool)
        self.active = np.ones(len(self.pairs), bool) if self.active is None else np.asarray(self.active, bool)[keep]

    @property
    def open_count(self) -> int:
        """Pairs not yet merged."""
        return int((~self.merged).sum())

    @property
    def sewing_count(self) -> int:
        """Pairs sewing now and not yet merged."""
        return int((~self.merged & self.active).sum())

    def sew_only(self, active) -> None:
        """From now on only the pairs where ``active`` (S,) is true pull and merge."""
        self.active = np.asarray(active, bool).copy()

    def gaps(self, x) -> np.ndarray:
        """Distance of every pair [m] at unwelded positions ``x``, shape (S,)."""
        return np.linalg.norm(x[self.pairs[:, 0]] - x[self.pairs[:, 1]], axis=1)

    def weld_map(self, n: int) -> np.ndarray:
        """Index of each of the ``n`` vertices in the welded mesh (merged pairs share one)."""
        p = self.pairs[self.merged]
        graph = coo_matrix((np.ones(len(p)), (p[:, 0], p[:, 1])), shape=(n, n))
        labels = connected_components(graph, directed=False)[1]
        _, first = np.unique(labels, return_index=True)
        order = np.argsort(first)
        index = np.empty(len(first), np.intp)
        index[order] = np.arange(len(first))
        return index[labels]

    def forces(self, model, state, weld, out):
        """Add Eq. 15 forces of the open pairs sewing now into ``out`` [N] (welded model and state)."""
        now = ~self.merged & self.active
        i, j = weld[self.pairs[now, 0]], weld[self.pairs[now, 1]]
        keep = i != j
        i, j = i[keep], j[keep]
        if not len(i):
            return out
        d = state.x[j] - state.x[i]
        rel_v = state.v[j] - state.v[i]
        accel = self.rate * d + 2.0 * np.sqrt(2.0 * self.rate) * rel_v  # critically damped closing
        norm = np.linalg.norm(accel, axis=1)
        accel *= np.minimum(1.0, self.max_acceleration / np.maximum(norm, 1e-300))[:, None]
        m = model.vertex_mass
        for k in range(3):
            out[:, k] += np.bincount(i, m[i] * accel[:, k], minlength=len(out))
            out[:, k] -= np.bincount(j, m[j] * accel[:, k], minlength=len(out))
        return out

    def open_pairs(self, weld) -> np.ndarray:
        """Open pairs sewing now, in welded indices (a pair already joined through others is dropped), (P, 2)."""
        p = weld[self.pairs[~self.merged & self.active]]
        return p[p[:, 0] != p[:, 1]]

    def near_stiffness(self, x, pairs, mass, *, near: float, rate: float):
        """Stiffness [N/m] and damping [N·s/m] of implicit springs on the ``pairs`` closer than ``near``.

        A zero-length spring of stiffness m·k (Eq. 15's k·m, m the pair's mean mass) is far too
        stiff to integrate explicitly once k is large enough to stretch cloth into place; the
        implicit solver takes it in its stride. Pairs farther than ``near`` get none (the gentle
        explicit pull of :meth:`forces` brings them closer first).
        """
        gap = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
        m = 0.5 * (mass[pairs[:, 0]] + mass[pairs[:, 1]])
        k = np.where(gap < near, m * rate, 0.0)
        return k, 2.0 * np.sqrt(k * m)

    def close(self, x) -> int:
        """Mark the open pairs sewing now closer than d (Eq. 16) at unwelded positions ``x``; return how many."""
        open_ = np.flatnonzero(~self.merged & self.active)
        if not len(open_):
            return 0
        gap = self.gaps(x)[open_]
        close = gap < self.merge_distance
        if close.any():
            self.max_gap_at_merge = max(self.max_gap_at_merge, float(gap[close].max()))
            self.merged[open_[close]] = True
        return int(close.sum())


def merge_state(x, v, mass, weld):
    """Positions and velocities of the welded particles: Eq. 18 and Eq. 17 for whole groups.

    ``x``, ``v`` (N, 3) and ``mass`` (N,) are per unwelded vertex; returns (x_w, v_w) of shape
    (max(weld) + 1, 3): mass-weighted positions and momentum-conserving velocities.
    """
    n = int(weld.max()) + 1
    total = np.bincount(weld, mass, minlength=n)
    xw = np.column_stack([np.bincount(weld, mass * x[:, k], minlength=n) for k in range(3)]) / total[:, None]
    vw = np.column_stack([np.bincount(weld, mass * v[:, k], minlength=n) for k in range(3)]) / total[:, None]
    return xw, vw
