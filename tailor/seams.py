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


STALL = 0.02
"""A seam pair whose gap shrinks by less than this fraction from one frame's :meth:`Sewing.close`
to the next is stuck: pressed against the body by the straight pull."""


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
    seam : (S,) int or None
        The pattern seam of each pair (given per pair of ``pairs`` as passed in; kept in step with
        the pairs kept).
    meeting : callable or None
        Where the pairs whose midpoint lies inside the body meet instead (:meth:`route_around`).
    stuck : (S,) bool
        Pairs that once closed by less than :data:`STALL` of their gap from one :meth:`close` to the next.
    stalled : (S,) bool
        The open pairs that closed by less than that at the last :meth:`close`.
    anchored : (A,) int
        Mesh vertices of the panels held while sewing (:meth:`anchor`); none at first.
    blocked : (S,) bool
        Pairs whose straight way to each other ran through the body when their stage began
        (:meth:`block`): routed round it from the start.
    step : float or None
        The step [s] the pull is integrated at, when longer than the plain implicit step (None: that
        one). Its damping is taken from the step's start velocities, explicitly even in an implicit
        step: at c = 2√(2k) (89 /s at k = 1000) a step near 2/c (22 ms) would ring instead of damping,
        so a longer step removes the share 1 − e^(−c·step) of the closing velocity a step (exact for
        the damping alone) instead of c·step.
    """

    pairs: np.ndarray
    rate: float = 1000.0
    max_acceleration: float = 50.0
    step: float | None = None
    merge_distance: float = 0.004
    merged: np.ndarray = field(default=None)
    max_gap_at_merge: float = 0.0
    active: np.ndarray = field(default=None)
    seam: np.ndarray = field(default=None)
    meeting: object = field(default=None, repr=False)
    meeting_beyond: float = 0.0

    def __post_init__(self):
        pairs = np.asarray(self.pairs, dtype=np.intp).reshape(-1, 2)
        keep = pairs[:, 0] != pairs[:, 1]
        self.pairs = pairs[keep]
        if self.seam is not None:
            self.seam = np.asarray(self.seam, np.intp)[keep]
        self.stuck = np.zeros(len(self.pairs), bool)
        self.stalled = np.zeros(len(self.pairs), bool)
        self.anchored = np.zeros(0, np.intp)
        self.blocked = np.zeros(len(self.pairs), bool)
        self.routes_stuck = False
        self._last_gap = np.full(len(self.pairs), np.inf)
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

    @property
    def all_stalled(self) -> bool:
        """Whether there are pairs sewing now and every one of them stalled at the last :meth:`close`."""
        now = ~self.merged & self.active
        return bool(now.any() and self.stalled[now].all())

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

    def route_around(self, meeting, beyond: float = 0.0, *, stuck: bool = True) -> None:
        """Pairs :attr:`blocked`, and with ``stuck`` those :attr:`stuck`, farther apart than ``beyond``
        [m] whose midpoint lies inside the body meet at ``meeting(midpoints) -> (ids, points)``
        instead, points clear of the body (None: every pair meets at its midpoint). Nearer pairs are
        the implicit springs' (:meth:`near_stiffness`); pairs still closing are left to the straight
        pull, which slides round the body well enough."""
        self.meeting, self.meeting_beyond = meeting, beyond
        self.routes_stuck = meeting is not None and stuck

    def block(self, x, inside, *, over: float, samples: int = 19) -> int:
        """Mark the open pairs sewing now whose straight way between their ends at ``x`` passes
        through the body (``inside(points) -> bool``, probed at ``samples`` points) and whose
        midpoint lies less than ``over`` [m] under its top :attr:`blocked`; return how many are.

        A sleeveless dress placed flat in front of and behind the body has its straps' ends either
        side of the shoulder, just below its top: pulled straight, they stop on its faces and are
        routed over it only once stuck (:data:`~tailor.dress.options.ROUTE_AFTER`), by when the
        bodice has closed round the chest and holds them down (GarmentCode's dress; docs/measurements.md,
        "Sixth day"). Known from the placement, they are routed from the start. Pairs deep in the
        body (a sleeve's underarm corner through the armpit) are left to the straight pull.
        """
        now = np.flatnonzero(~self.merged & self.active)
        p = self.pairs[now]
        t = np.linspace(0.05, 0.95, samples)[None, :, None]
        along = x[p[:, 0]][:, None] * (1.0 - t) + x[p[:, 1]][:, None] * t
        through = np.asarray(inside(along.reshape(-1, 3)), bool).reshape(len(p), samples).any(axis=1)
        mid = 0.5 * (x[p[through, 0]] + x[p[through, 1]])
        up = np.linspace(0.0, over, samples)
        above = mid[:, None] + up[None, :, None] * np.array([0.0, 0.0, 1.0])
        clear = ~np.asarray(inside(above.reshape(-1, 3)), bool).reshape(len(mid), samples)
        self.blocked[:] = False
        self.blocked[now[np.flatnonzero(through)[clear.any(axis=1)]]] = True
        return int(self.blocked.sum())

    def forces(self, model, state, weld, out):
        """Add Eq. 15 forces of the open pairs sewing now into ``out`` [N] (welded model and state).

        Each end is drawn to the pair's meeting point, the midpoint, critically damped. A strap's
        two ends in front of and behind a shoulder would be drawn straight through it and stop on
        its surface; with :meth:`route_around` they are drawn to a point over it instead."""
        now = ~self.merged & self.active
        i, j = weld[self.pairs[now, 0]], weld[self.pairs[now, 1]]
        keep = i != j
        i, j = i[keep], j[keep]
        if not len(i):
            return out
        d = state.x[j] - state.x[i]
        to_i, to_j = d.copy(), -d  # twice the way to the meeting point
        if self.meeting is not None:
            self._route(state.x, i, j, d, (self.blocked | (self.stuck & self.routes_stuck))[now][keep], to_i, to_j)
        c = 2.0 * np.sqrt(2.0 * self.rate)  # critically damped closing
        if self.step is not None:
            c = -np.expm1(-c * self.step) / self.step
        damp = c * (state.v[j] - state.v[i])
        m = model.vertex_mass
        for ends, accel in ((i, self.rate * to_i + damp), (j, self.rate * to_j - damp)):
            norm = np.linalg.norm(accel, axis=1)
            accel *= np.minimum(1.0, self.max_acceleration / np.maximum(norm, 1e-300))[:, None]
            for k in range(3):
                out[:, k] += np.bincount(ends, m[ends] * accel[:, k], minlength=len(out))
        return out

    def _route(self, x, i, j, d, routed, to_i, to_j) -> None:
        """Point the ``routed`` far pairs (ends ``i``, ``j``, gaps ``d``) whose midpoint is inside the
        body at their :attr:`meeting` point, in place in ``to_i``, ``to_j``."""
        far = np.flatnonzero(routed & (np.einsum("ij,ij->i", d, d) > self.meeting_beyond ** 2))
        if not len(far):
            return
        ids, met = self.meeting(0.5 * (x[i[far]] + x[j[far]]))
        ids = far[ids]
        to_i[ids], to_j[ids] = 2.0 * (met - x[i[ids]]), 2.0 * (met - x[j[ids]])

    def open_pairs(self, weld) -> np.ndarray:
        """Open pairs sewing now, in welded indices (a pair already joined through others is dropped), (P, 2)."""
        p = weld[self.pairs[~self.merged & self.active]]
        return p[p[:, 0] != p[:, 1]]

    def anchor(self, ids) -> None:
        """The mesh vertices ``ids`` belong to panels held while sewing (a waistband whose attached
        edge keeps its height, :class:`~tailor.contact.HeightHold`): a pair with one end among them
        is stiffened only once near (:meth:`near_stiffness`'s ``anchored_near``)."""
        self.anchored = np.unique(np.asarray(ids, np.intp))

    def near_stiffness(self, x, pairs, mass, *, near: float, rate: float, weld=None, anchored_near: float = 0.0):
        """Stiffness [N/m] and damping [N·s/m] of implicit springs on the ``pairs`` closer than ``near``.

        A zero-length spring of stiffness m·k (Eq. 15's k·m, m the pair's mean mass) is far too
        stiff to integrate explicitly once k is large enough to stretch cloth into place; the
        implicit solver takes it in its stride. Pairs farther than ``near`` get none (the gentle
        explicit pull of :meth:`forces` brings them closer first).

        A pair joining a held panel to a free one (one end :meth:`anchor`-ed; ``weld`` numbers the
        simulated vertices) is stiffened only within ``anchored_near``: such a spring pulls the held
        panel as hard as the free one, and a band held by its top edge was stretched down to the
        skirt or trousers placed a hand's breadth below it (GarmentCode's placements), past the
        stability limit at 2 cm meshes. The capped explicit pull, which cloth follows as a whole,
        brings them near.
        """
        gap = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
        if weld is not None and len(self.anchored):
            held = np.zeros(max(len(x), int(weld.max()) + 1), bool)  # welded vertices out of the model numbered last
            held[weld[self.anchored]] = True
            near = np.where(held[pairs[:, 0]] != held[pairs[:, 1]], anchored_near, near)
        m = 0.5 * (mass[pairs[:, 0]] + mass[pairs[:, 1]])
        k = np.where(gap < near, m * rate, 0.0)
        return k, 2.0 * np.sqrt(k * m)

    def close(self, x) -> int:
        """Mark the open pairs sewing now closer than d (Eq. 16) at unwelded positions ``x``; return how many."""
        open_ = np.flatnonzero(~self.merged & self.active)
        if not len(open_):
            return 0
        gap = self.gaps(x)[open_]
        # a pair that closed less than STALL of its gap since the last call is stuck (for good)
        self.stalled[:] = False
        self.stalled[open_] = gap > (1.0 - STALL) * self._last_gap[open_]
        self.stuck |= self.stalled
        self._last_gap[open_] = gap
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
