"""What the body collider remembers per cloth vertex between steps (:class:`~.body.BodyCollider`):
its cached candidates and budget, the landing tests of a step, and the cloth at the last response."""

from __future__ import annotations

import numpy as np
from numba import njit

from .drift import BodyDrift

__all__ = ["KeptCandidates", "LandingTests", "LastResponse", "grouped_keys", "same_positions", "same_optional", "per_vertex"]


def same_positions(a, b) -> bool:
    """Whether two arrays of body positions are the same (a still body is handed over again and again)."""
    return a is b or np.array_equal(a, b)


def same_optional(a, b) -> bool:
    """Whether two optional arrays (None: none) are the same."""
    return (a is None and b is None) or (a is not None and b is not None and np.array_equal(a, b))


class KeptCandidates:
    """The body collider's cached candidates: per vertex the triangles found within the margin (the
    first ``count[i]`` slots of its row in ``slots``), where the vertex was when its budget was last
    counted (``ref``) and how much of its budget (:attr:`BodyCollider.budget`) it has left there
    (``slack`` [m]), and the body frame they were counted on.

    The rows share one array, each with room for its count rounded up to :attr:`ROW_ROOM` slots: a
    vertex asked again rewrites its own row where it fits and moves to the end where it does not;
    when the array is full the rows in use are packed together again. (Rows as wide as the widest
    vertex's took 82 slots a vertex on a T-shirt whose vertices hold 33 on average.)"""

    ROW_ROOM = 4

    def __init__(self, frame, x):
        n = len(x)
        self.frame, self.ref, self.slack = frame, x.copy(), np.zeros(n)
        self.slots = np.zeros(0, np.int32)
        self.count = np.zeros(n, np.int64)
        self._lo = np.zeros(n, np.int64)
        self._room = np.zeros(n, np.int64)  # slots of each row
        self._end = 0  # slots handed out so far (rows in use and rows abandoned)

    def spans(self):
        """(lo, hi, tri): vertex i's candidate triangles are ``tri[lo[i]:hi[i]]``."""
        return self._lo, self._lo + self.count, self.slots

    def spend(self, drift, x, frame) -> None:
        """The body frame changed to ``frame`` with the vertices at ``x``: ``drift`` (per vertex) is spent."""
        self.slack = self.slack - drift
        self.ref = x.copy()
        self.frame = frame

    def renew(self, ids, x, keys, face_count: int, slack) -> None:
        """Vertices ``ids`` (sorted) were asked about again at ``x``: their whole budget ``slack`` back,
        and as their candidates the triangles of ``keys`` (sorted ``vertex · F + triangle``)."""
        self.ref[ids] = x[ids]
        self.slack[ids] = slack
        vertex, tri = keys // face_count, keys % face_count
        start = np.searchsorted(vertex, ids)
        count = np.searchsorted(vertex, ids, side="right") - start
        grow = count > self._room[ids]
        if grow.any():
            self._make_room(ids[grow], count[grow])
        self.count[ids] = count
        self.slots[self._lo[vertex] + np.arange(len(keys)) - np.repeat(start, count)] = tri

    def _make_room(self, rows, need) -> None:
        """Rows ``rows`` moved to the end with room for ``need`` slots each (their old rows abandoned);
        out of slots, the rows in use are packed first, with an eighth to spare."""
        self.count[rows], self._room[rows] = 0, 0
        room = -(-need // self.ROW_ROOM) * self.ROW_ROOM
        total = int(room.sum())
        if self._end + total > len(self.slots):
            in_use = int(self._room.sum())
            self._pack(total + (in_use + total) // 8)
        first = self._end + np.concatenate([[0], np.cumsum(room)[:-1]])
        self._end += total
        self._lo[rows], self._room[rows] = first, room

    def _pack(self, spare: int) -> None:
        """Every row moved next to the one before it, in vertex order, keeping its room; ``spare``
        slots free after them."""
        packed = np.zeros(int(self._room.sum()) + spare, np.int32)
        self._end = _pack_rows(self.slots, self._lo, self.count, self._room, packed)
        self.slots = packed


def grouped_keys(point, tri, ids, face_count: int):
    """Keys ``ids[point] · F + tri`` of (point, triangle) pairs grouped by point in the order of
    ``ids``, each point's triangles ascending: with ``ids`` sorted, the keys sorted, by one counting
    pass and a sort of each point's few triangles instead of a sort of them all (a body query's keys,
    every query)."""
    point = np.ascontiguousarray(point, np.int64)
    out = np.empty(len(point), np.int64)
    _group(point, np.ascontiguousarray(tri, np.int64), np.ascontiguousarray(ids, np.int64), face_count, out)
    return out


@njit(cache=True)
def _group(point, tri, ids, face_count, out):
    start = np.zeros(len(ids) + 1, np.int64)
    for k in range(len(point)):
        start[point[k] + 1] += 1
    for i in range(len(ids)):
        start[i + 1] += start[i]
    for k in range(len(point)):
        p = point[k]
        out[start[p]] = ids[p] * face_count + tri[k]
        start[p] += 1
    first = 0
    for i in range(len(ids)):  # each point's keys (start[i] is now where its group ends) by insertion
        for k in range(first + 1, start[i]):
            key = out[k]
            j = k - 1
            while j >= first and out[j] > key:
                out[j + 1] = out[j]
                j -= 1
            out[j + 1] = key
        first = start[i]


@njit(cache=True)
def _pack_rows(slots, lo, count, room, out):
    """Rows ``slots[lo[i]:lo[i] + count[i]]`` copied one after another into ``out``, each keeping
    ``room[i]`` slots; ``lo`` updated in place. Returns the slots used (no temporaries: a packing
    with index arrays raised a drape's peak by 0.5 KB a vertex)."""
    at = 0
    for i in range(len(lo)):
        for k in range(count[i]):
            out[at + k] = slots[lo[i] + k]
        lo[i] = at
        at += room[i]
    return at


class LandingTests:
    """The landing tests against the body standing at ``body_x`` (a step's end, the same for each of
    the step's contact passes): per vertex where it was last tested and a lower bound of its distance
    from the body there (−inf: never tested). A vertex at least ``bound`` away cannot have come within
    the thickness unless it has moved more than ``bound`` less the thickness since."""

    def __init__(self, body_x, n: int):
        self.body_x = body_x
        self.x = np.zeros((n, 3))
        self.bound = np.full(n, -np.inf)

    def unclear(self, rows, x, thickness) -> np.ndarray:
        """Those of ``rows`` that may be within ``thickness`` at ``x``."""
        moved = np.linalg.norm(x[rows] - self.x[rows], axis=1)
        return rows[self.bound[rows] - moved <= per_vertex(thickness, rows)]

    def found(self, rows, x, dist, tri, sure) -> None:
        """``rows`` tested at ``x``: ``dist``, ``tri`` as :meth:`BodyCollider._closest` gives them (a
        distance is exact within ``sure`` [m], where every triangle is a candidate; none found or a
        farther one means at least that)."""
        self.x[rows] = x[rows]
        self.bound[rows] = np.minimum(np.where(tri[rows] >= 0, dist[rows], np.inf), sure)


class LastResponse:
    """The cloth at the last response: positions ``x``, lower bounds of their distances from the body
    (``bound`` [m], at most ``reach``; negative inside), of how far outside it they surely were
    (``outside`` [m], 0 where the side is not certain), and the body's positions then; the body's
    drift since within ``reach``, for the last body asked about."""

    def __init__(self, x, bound, body, outside, reach: float):
        self.x, self.bound, self.body, self.outside, self.reach = x, bound, body, outside, reach
        self._drift = None  # (body positions, BodyDrift to them)

    def drift(self, body_x, faces) -> BodyDrift:
        """The body's :class:`BodyDrift` from then to ``body_x`` (the same positions asked again: the same one)."""
        d = self._drift
        if d is None or not same_positions(d[0], body_x):
            d = self._drift = (body_x.copy(), BodyDrift(self.body, body_x, faces, self.reach))
        return d[1]


def per_vertex(thickness, ids):
    """``thickness`` [m] of the vertices ``ids``: one for all, or each vertex's own ((N,) array: an
    outfit's garments, each kept its layers out)."""
    return thickness if np.ndim(thickness) == 0 else np.asarray(thickness)[ids]
