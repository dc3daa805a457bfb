"""Cloth–body contact (Carignan Eq. 9–14): :class:`BodyCollider`, FCL as its broad phase."""

from __future__ import annotations

import numpy as np

from ..errors import SimulationUnstable
from .broad import BOX_CELL, NearCubes, TriangleBoxes, TriangleGeometry, clustered_query
from .closest import nearest_into
from .contacts import NO_CONTACTS, Contacts
from .drift import BodyDrift
from .inside import InsideTest
from .memory import KeptCandidates, LandingTests, LastResponse, grouped_keys, per_vertex, same_positions

__all__ = ["BodyCollider", "BODY_SPAN"]

BODY_SPAN = 16
"""Body frames one FCL broad phase of the body serves (:meth:`BodyCollider._body`): a walk builds its
boxes, and learns which of them lie near each cube of space, once per span instead of every frame."""

QUERY_CHUNK = 2048
"""Cloth vertices one body query asks about at a time (:meth:`BodyCollider._query`): the pairs a
query finds on the way to its answer take several times the memory of the answer, so a whole
cloth is asked about in parts."""

SPEND = 0.5
"""Share of the margin a cloth vertex may move (relative to the body near it) before it is asked
again (:meth:`BodyCollider.candidates`); the rest, :attr:`BodyCollider.sure`, is where every body
triangle is among its candidates, so a distance found there is exact."""


class BodyCollider:
    """Cloth–body contact (Carignan Eq. 9–14) with FCL as the broad phase.

    FCL finds the body triangles within ``margin`` of every cloth vertex, by clusters: boxes
    round nearby cloth vertices against boxes round nearby body triangles
    (:func:`clustered_query`, built once per :data:`BODY_SPAN` body frames). Those candidates
    are kept while no cloth vertex has moved more than its budget (a share of the margin, :data:`SPEND`)
    relative to the body near it; each step a compiled narrow phase finds, on the body as it is at that instant, the
    closest point, its barycentric coordinates and the outward normal.

    Parameters
    ----------
    frames : (T, N, 3) body positions [m]; faces : (F, 3)
    margin : float
        Query radius [m]; must exceed the distance a cloth vertex moves between queries.
    spend : float
        Share of the margin a vertex may move before it is asked again (:data:`SPEND`).

    Attributes
    ----------
    budget : float
        How far [m] a vertex may move relative to the body near it before it is asked again.
    sure : float
        The margin less the budget [m]: every body triangle within it of a vertex is a candidate,
        so distances (and sides) found within it are exact. A step must not carry the body further
        than this through the cloth (:class:`~tailor.dress.timeline.Timeline`): a vertex that crossed
        the surface is then found inside within it, and seen to have crossed.
    """

    def __init__(self, frames, faces, *, margin: float = 0.02, spend: float = SPEND):
        if not 0.0 < spend < 1.0:
            raise ValueError(f"spend must lie strictly between 0 and 1 (a share of the margin), got {spend!r}")
        self.frames = np.asarray(frames, float)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self.margin = float(margin)
        self.budget = spend * self.margin
        self.sure = self.margin - self.budget
        self._boxes = {}  # span of body frames (frame // BODY_SPAN) → its broad phase
        self._geometry = {}  # body frame → its triangles (TriangleGeometry)
        self._cache: KeptCandidates | None = None  # each vertex's candidates and what is left of its budget
        self._drifts = {}  # (frame, frame) → the body's BodyDrift between them
        self._previous = None  # signed distance of every vertex after the last response
        self._seen: LastResponse | None = None  # where the cloth and the body were at the last response
        self._inside_test = None  # (body positions, their InsideTest)
        self._tested: LandingTests | None = None  # the landing tests against the body where it stands now
        self.deepest = 0.0  # deepest penetration any response found [m]
        self.queries = 0
        self.queried_points = 0

    def forget(self) -> None:
        """Drop what is remembered per cloth vertex (the cloth's vertices were renumbered: a cut or a tear)."""
        self._cache = None
        self._previous = None
        self._seen = None
        self._tested = None

    def checkpoint(self) -> tuple:
        """What a step's response changes of what the collider remembers per vertex (the distances and
        sides after the last response, the deepest penetration), for :meth:`restore`. The kept
        candidates need no restoring: each vertex's stay valid at any position it is asked about
        (:meth:`candidates` re-counts them)."""
        return self._previous, self._seen, self.deepest

    def restore(self, mark: tuple) -> None:
        """What the collider remembered at :meth:`checkpoint` ``mark`` (a step undone)."""
        self._previous, self._seen, self.deepest = mark

    def _body(self, frame):
        """(broad phase, triangles) of the body at ``frame``: the margin's FCL broad phase of its span of
        :data:`BODY_SPAN` frames (built round where each triangle is over them, so that the cubes it
        learns serve the whole span) and the frame's own triangles, which the query tests exactly
        (the last two of each kept: a walk moves on frame by frame)."""
        span = frame // BODY_SPAN
        return (_recent(self._boxes, span, 2, lambda: self._span_boxes(span)),
                _recent(self._geometry, frame, 2, lambda: TriangleGeometry(self.frames[frame], self.faces)))

    def _span_boxes(self, span: int) -> NearCubes:
        """The margin's FCL broad phase of the body over frames ``span · BODY_SPAN`` onwards."""
        f = self.frames[span * BODY_SPAN:(span + 1) * BODY_SPAN]
        return NearCubes(TriangleBoxes(f[0], self.faces, BOX_CELL, vertex_boxes=(f.min(axis=0), f.max(axis=0))), self.margin)

    def candidates(self, x, frame: int, *, cache: bool = True, rows=None):
        """(lo, hi, tri): the body triangles within ``margin`` of vertex i are ``tri[lo[i]:hi[i]]`` (FCL broad phase).

        With ``cache`` each vertex keeps its answer while it is certain to hold every triangle
        within :attr:`sure`: a vertex asked about has :attr:`budget` to spend, and spends what
        it moves and, when the body frame changes, how much closer the body near it came relative
        to it (:class:`~tailor.collide.drift.BodyDrift`; the trunk under a shirt moves with the
        shirt, a swinging arm does not). Only the vertices that spent it are asked again (sewing
        moves a few fast, settling and walking move most slowly). With ``rows`` (sorted vertex ids)
        only their answers are brought up to date (the others may be stale: not to be read).
        """
        if not np.all(np.isfinite(x)):  # FCL would crash on NaN; the guard reports instabilities
            raise SimulationUnstable("cloth positions became NaN or infinite before the body collision query; "
                                     "try a smaller time step or the implicit integrator")
        c = self._cache
        if not cache or c is None or c.ref.shape != x.shape:
            every = np.arange(len(x))
            keys = self._query(x, frame, every)
            if not cache:
                return self._spans(keys, len(x))
            c = self._cache = KeptCandidates(frame, x)
            c.renew(every, x, keys, len(self.faces), self.budget)
            return c.spans()
        if c.frame != frame:
            c.spend(self._drift(c.frame, frame).relative(x, x - c.ref), x, frame)
        ids = np.arange(len(x)) if rows is None else np.asarray(rows, np.int64)
        step = x[ids] - c.ref[ids]
        travel, budget = np.einsum("ij,ij->i", step, step), np.maximum(c.slack[ids], 0.0) ** 2
        if (travel >= budget).any():  # a query is made: those three quarters through their budget too (they would be next)
            moved = ids[travel >= 0.5625 * budget]
            c.renew(moved, x, self._query(x[moved], frame, moved), len(self.faces), self.budget)
        return c.spans()

    def _drift(self, a: int, b: int):
        """The body's :class:`BodyDrift` from frame ``a`` to ``b`` within the margin (the last few kept)."""
        return _recent(self._drifts, (a, b), 4, lambda: BodyDrift(self.frames[a], self.frames[b], self.faces, self.margin))

    def _inside(self, points, body_x) -> np.ndarray:
        """Whether each point lies inside the closed body at ``body_x`` (:class:`InsideTest`, binned once
        per body position: a still body is asked many times over)."""
        kept = self._inside_test
        if kept is None or not same_positions(kept[0], body_x):
            kept = self._inside_test = (np.array(body_x, float), InsideTest(body_x, self.faces))
        return kept[1](points)

    def _spans(self, keys, n):
        """(lo, hi, tri) of sorted keys ``vertex · F + triangle`` over ``n`` vertices: vertex i's
        triangles are ``tri[lo[i]:hi[i]]``."""
        ptr = np.concatenate([[0], np.cumsum(np.bincount(keys // len(self.faces), minlength=n))]).astype(np.int64)
        return ptr[:-1], ptr[1:], keys % len(self.faces)

    def _closest(self, x, spans, body_x, rows=None):
        """Narrow phase: signed distance, triangle (−1: none), barycentrics and normal per point
        (of the points ``rows`` only, if given: the others get none)."""
        n = len(x)
        dist, tri_out, bary, normal = np.full(n, np.inf), np.full(n, -1, np.int64), np.zeros((n, 3)), np.zeros((n, 3))
        rows = np.arange(n, dtype=np.int64) if rows is None else np.asarray(rows, np.int64)
        nearest_into(np.ascontiguousarray(x), *spans, np.ascontiguousarray(body_x), self.faces, dist, tri_out, bary, normal, rows)
        dist[tri_out < 0] = np.inf
        return dist, tri_out, bary, normal

    def _query(self, points, frame, ids, radius=None):
        """Sorted keys ``vertex · F + triangle`` of body triangles within the margin (or ``radius``) of
        ``points`` (``ids`` their vertices), :data:`QUERY_CHUNK` points at a time."""
        self.queries += 1
        self.queried_points += len(points)
        ids = np.asarray(ids, np.int64)
        keys = np.concatenate([self._query_part(points[k:k + QUERY_CHUNK], frame, ids[k:k + QUERY_CHUNK], radius)
                               for k in range(0, len(points), QUERY_CHUNK)] or [np.zeros(0, np.int64)])
        if len(points) > QUERY_CHUNK and np.any(np.diff(ids) < 0):  # parts in order of their vertices are sorted already
            keys.sort()
        return keys

    def _query_part(self, points, frame, ids, radius):
        near, geometry = self._body(frame)
        point, tri = (near.query(points, geometry) if radius is None
                      else clustered_query(points, radius, near.target, geometry=geometry))
        keys = grouped_keys(point, tri, ids, len(self.faces))  # sorted when ``ids`` is: all the CSR needs
        if len(ids) > 1 and np.any(np.diff(ids) < 0):  # asked out of vertex order: grouped in that order
            keys.sort()
        return keys

    def nearest(self, x, body_x, frame: int, *, cache: bool = True, rows=None):
        """Signed distance [m] (positive outside), triangle, barycentrics and normal per vertex (of
        the vertices ``rows`` only, if given (cached only): the others get none).

        Vertices with no body triangle within the margin get triangle −1 and distance +inf.
        """
        found = self._closest(x, self.candidates(x, frame, cache=cache, rows=rows), body_x, rows)
        return self._confirm_deep(x, found, body_x) if cache else found  # uncached: complete within the margin

    def depth(self, x, body_x, frame: int) -> float:
        """How deep [m] the deepest of the points ``x`` (the cloth's vertices) is inside the body at
        ``body_x`` (0: none). Those surely outside since the last response (:meth:`_surely_outside`:
        resting on the body at the thickness, most of them) are not looked at."""
        dist, tri, _, _ = self.nearest(x, body_x, frame, rows=np.flatnonzero(~self._surely_outside(x, body_x)))
        inside = dist[tri >= 0]
        return float(max(0.0, -inside.min())) if len(inside) else 0.0

    def _confirm_deep(self, x, found, body_x):
        """``found`` with the vertices read deeper than :attr:`sure` checked against the closed surface.

        The cached candidates hold every triangle within :attr:`sure` of a vertex, but only
        some of those farther off. Beyond it the closest of them is still farther than
        :attr:`sure` (the true distance is too), but its side is the vote of whichever faces
        happened to be cached (a vertex outside a cube's corner, level with one face, can read
        inside from that face alone and be thrown off). Such vertices are tested
        against the closed surface (:func:`points_inside`, as :meth:`rescue` does: the body must be
        watertight for either); those outside are out of reach.
        """
        dist, tri, bary, normal = found
        deep = np.flatnonzero((tri >= 0) & (dist < -self.sure))
        if len(deep):
            out = deep[~self._inside(x[deep], body_x)]
            tri[out], dist[out] = -1, np.inf
        return dist, tri, bary, normal

    def rescue(self, model, state, body_x, body_v, frame: int, *, thickness, reach: float = 0.15, keep=None) -> int:
        """Return cloth vertices trapped inside the body to its surface; how many were moved.

        :meth:`respond` trusts only contacts within :attr:`sure`, or vertices it saw cross,
        so a vertex that arrives deep inside without crossing (a merged seam vertex at the
        centroid of its partners round a shoulder, or one squeezed through a crease) stays
        there. Here every vertex not surely outside (:meth:`_surely_outside`) is tested against the
        closed surface (:func:`points_inside`);
        those inside, and confirmed by the closest triangle within ``reach`` facing away, are
        put ``thickness`` outside it at the body's velocity (inelastic, as Eq. 9–10). ``keep(ids, out)``,
        optional, says which of those moves to make ((K,) bool); the others stay inside for now.
        """
        ids, tri, bary, out = self.push_out(state.x, body_x, frame, clearance=thickness, reach=reach,
                                            skip=model.vertex_pinned | self._surely_outside(state.x, body_x))
        if keep is not None and len(ids):
            ok = keep(ids, out)
            ids, tri, bary, out = ids[ok], tri[ok], bary[ok], out[ok]
        if not len(ids):
            return 0
        state.x[ids] = out
        state.v[ids] = (body_v[self.faces[tri]] * bary[:, :, None]).sum(axis=1)
        if self._previous is not None and len(self._previous) == len(state.x):
            self._previous[ids] = per_vertex(thickness, ids)
        return len(ids)

    def push_out(self, points, body_x, frame: int, *, clearance: float, reach: float = 0.15, skip=None):
        """The ``points`` inside the closed body surface (:func:`points_inside`; not ``skip``, (N,) bool)
        whose closest triangle within ``reach`` faces away from them, put ``clearance`` outside it.

        Returns (ids, their closest triangles, barycentrics, the points moved out (K, 3))."""
        test = np.arange(len(points)) if skip is None else np.flatnonzero(~np.asarray(skip, bool))
        inside = test[self._inside(points[test], body_x)]
        if not len(inside):
            return inside, inside, np.zeros((0, 3)), np.zeros((0, 3))
        keys = self._query(points[inside], frame, np.arange(len(inside)), radius=reach)
        dist, tri, bary, normal = self._closest(points[inside], self._spans(keys, len(inside)), body_x)
        ok = (tri >= 0) & (dist < 0.0)
        out = points[inside[ok]] + (per_vertex(clearance, inside[ok]) - dist[ok])[:, None] * normal[ok]
        return inside[ok], tri[ok], bary[ok], out

    def landing(self, model, x_end, v_end, dt, body_x, body_v, frame: int, *, thickness, skip=None):
        """The vertices a step would bring within ``thickness`` of the body, as :class:`Contacts` to hold.

        ``skip``: ids not to test (the contacts the solve already holds: most of a resting cloth's).

        ``x_end``, ``v_end`` are where a solved step would leave the cloth. A vertex that started
        the step outside (or just inside) the thickness and would end closer gets the normal
        velocity that makes it land exactly at the thickness, relative to the body; an implicit
        solve holding that (:class:`tailor.integrators.ImplicitEuler` ``predict``) lands the cloth
        within the step instead of having it pushed out afterwards.
        """
        test = ~model.vertex_pinned
        if skip is not None and len(skip):
            test[skip] = False
        rows = np.flatnonzero(test & ~self._out_of_reach(x_end, body_x, thickness))
        tested = self._tested
        if tested is None or len(tested.x) != len(x_end) or not same_positions(tested.body_x, body_x):
            tested = self._tested = LandingTests(body_x, len(x_end))
        rows = tested.unclear(rows, x_end, thickness)
        dist, tri, bary, normal = self._confirm_deep(x_end, self._closest(x_end, self.candidates(x_end, frame, rows=rows), body_x, rows),
                                                     body_x)
        tested.found(rows, x_end, dist, tri, self.sure)
        close = np.flatnonzero((tri >= 0) & (dist < thickness) & ~model.vertex_pinned)
        if not len(close):
            return Contacts(np.zeros(0, np.intp), np.zeros((0, 3)), np.zeros(0), model.vertex_count)
        n = normal[close]
        vb = np.einsum("kij,ki->kj", body_v[self.faces[tri[close]]], bary[close])
        vn = np.einsum("ij,ij->i", v_end[close] - vb, n)
        start = dist[close] - dt * vn  # where it started, relative to the body
        ok = (vn < 0) & (start > -self.sure)
        close, n, vb, start = close[ok], n[ok], vb[ok], start[ok]
        return Contacts(close, n, np.einsum("ij,ij->i", vb, n) - np.maximum(start - per_vertex(thickness, close), 0.0) / dt,
                        model.vertex_count)

    def _out_of_reach(self, x, body_x, thickness) -> np.ndarray:
        """Vertices at ``x`` that cannot be within ``thickness`` of the body at ``body_x``: their distance
        at the last response, less how much closer the body near them has come since (their motion
        relative to it, :class:`~tailor.collide.drift.BodyDrift`), still exceeds it."""
        far = self._far(x, body_x, thickness)[0]
        return np.zeros(len(x), bool) if far is None else far

    def _far(self, x, body_x, beyond):
        """(far, bound, outside): the vertices at ``x`` surely farther than ``beyond`` from the body at
        ``body_x`` (what the last response knew of them, less how much closer the body near them
        came relative to them since; ``beyond`` [m] one for all or (N,) each vertex's own) and those
        two lower bounds for every vertex, as :class:`LastResponse` keeps them; (None, None, None)
        before a response of this numbering."""
        seen = self._seen
        if seen is None or len(seen.x) != len(x):
            return None, None, None
        closer = seen.drift(body_x, self.faces).relative(x, x - seen.x)
        bound = seen.bound - closer
        return bound > beyond, bound, seen.outside - closer

    def _surely_outside(self, x, body_x) -> np.ndarray:
        """Vertices at ``x`` that cannot have entered the body at ``body_x``: found outside at the last
        response, within :attr:`sure` (where the side is certain), by more than they have moved
        relative to the body near them since (to reach its inside they must cross its surface)."""
        outside = self._far(x, body_x, 0.0)[2]
        return np.zeros(len(x), bool) if outside is None else outside > 0.0

    def _hits(self, x, body_x, frame, thickness):
        """The vertices to respond to: (hit ids, dist, tri, bary, normal) of all vertices.

        A vertex found deeper than :attr:`sure` either crossed the surface this step (it was
        outside before: push it back) or lies near the far side of a thin or concave part (armpit,
        crotch) where the closest triangle is not the one it entered by: those are left. A resting
        band above the thickness keeps resting contact from flickering on and off. Vertices surely
        farther off than 1.5 thicknesses (:meth:`_far`: most of a hanging garment) are not looked
        at: they get none, and keep what the last response knew of them, less their drift since.
        """
        far, bound, outside = self._far(x, body_x, 1.5 * np.max(thickness))
        dist, tri, bary, normal = self.nearest(x, body_x, frame, rows=None if far is None else np.flatnonzero(~far))
        # the cached candidates hold every triangle within ``sure``: a distance found is exact up to
        # there, and none found (or a farther one) means at least that
        sure = self.sure
        near_bound = np.minimum(np.where(tri >= 0, dist, np.inf), sure)
        near_outside = np.where((tri >= 0) & (dist > 0.0) & (dist < sure), dist, 0.0)
        if far is not None:  # not looked at: what the last response knew, less how much closer they may have come
            near_bound[far], near_outside[far] = bound[far], np.maximum(outside[far], 0.0)
        self._seen = LastResponse(x.copy(), near_bound, body_x, near_outside, sure)
        prev = self._previous if self._previous is not None and len(self._previous) == len(dist) else None
        crossed = (prev >= 0.0) & (dist < 0.0) if prev is not None else np.zeros(len(dist), bool)
        plausible = (dist > -sure) | crossed
        hit = np.flatnonzero((tri >= 0) & (dist < 1.5 * thickness) & plausible)
        previous = np.where(tri >= 0, dist, np.inf)
        if far is not None and prev is not None:
            previous[far] = prev[far]
        self._previous = previous
        self._previous[hit] = per_vertex(thickness, hit)  # pushed back out by the response
        return hit, dist, tri, bary, normal

    def respond(self, model, state, dt, body_x, body_v, frame: int, *, thickness, friction,
                impulse=None) -> Contacts:
        """Eq. 9–14 on ``state`` in place: push out to ``thickness``, cancel approach, apply friction.

        ``thickness`` [m] is one for every vertex or (N,) each vertex's own (as for :meth:`rescue`
        and :meth:`landing`: an outfit's garments kept each its layers out).

        ``impulse`` (N,) [N·s], optional: the normal impulse the integrator's solve already gave
        each vertex it held on the body (the contacts this returned last step); it counts towards
        the friction budget of Eq. 14 like the approach cancelled here. Returns the vertices
        resting on the body and not being pulled into it, for the next implicit step to hold, each
        with the normal force the body gave it over this step (the solve's and this response's):
        the next step's friction budget.
        :attr:`deepest` keeps the deepest penetration any response found.
        """
        hit, dist, tri, bary, normal = self._hits(state.x, body_x, frame, thickness)
        if not len(hit):
            return NO_CONTACTS
        self.deepest = max(self.deepest, float(max(0.0, -dist[hit].min())))
        vb = (body_v[self.faces[tri[hit]]] * bary[hit][:, :, None]).sum(axis=1)  # body velocity at the contact (Eq. 9)
        n = normal[hit]
        movable = ~model.vertex_pinned[hit]
        hit, n, vb = hit[movable], n[movable], vb[movable]
        thickness = per_vertex(thickness, hit)
        rel = state.v[hit] - vb  # Eq. 9
        vn = np.einsum("ij,ij->i", rel, n)  # Eq. 10
        # a vertex that started the step above the thickness falls until it lands on it (its
        # position moves with the approach up to there), then rests: normal velocity cancelled
        start_gap = dist[hit] - dt * vn
        land = np.where(vn < 0, np.maximum(vn, -np.maximum(start_gap - thickness, 0.0) / dt), vn)
        dv_n = -np.minimum(vn, 0.0)  # the approach cancelled here
        # contacts the solve held had their friction there (stuck, or sliding at the Coulomb limit)
        held = np.zeros(len(hit)) if impulse is None else np.asarray(impulse)[hit] / model.vertex_mass[hit]
        tangential = rel - vn[:, None] * n  # Eq. 11
        speed_t = np.linalg.norm(tangential, axis=1)
        mu = np.asarray(friction)[hit] if np.ndim(friction) else float(friction)
        # Eq. 14: friction removes at most μ·(normal velocity change); beyond that it stops sliding
        keep = np.where(speed_t > 0, np.maximum(0.0, 1.0 - mu * dv_n / np.maximum(speed_t, 1e-300)), 0.0)
        pressed = ((vn < 0) | (held > 0))[:, None]
        new_rel = np.where(pressed, tangential * keep[:, None] + np.maximum(vn, 0.0)[:, None] * n, rel)
        v_new = vb + new_rel
        # the step already moved the vertex with its old velocity: move it as the new one would
        # (with the landing approach), then out to the thickness if it started closer. Friction
        # acts from the landing on: its change of the tangential velocity moves the vertex only
        # for the part of the step after it reached the thickness (none for one landing at its end)
        after = np.where(vn < 0, np.clip(dt - np.maximum(start_gap - thickness, 0.0) / np.maximum(-vn, 1e-300), 0.0, dt), dt)
        dv = v_new - state.v[hit]
        dv_normal = np.einsum("ij,ij->i", dv, n)
        shift = after[:, None] * (dv - dv_normal[:, None] * n) + dt * (dv_normal + np.where(pressed[:, 0], np.minimum(land, 0.0), 0.0))[:, None] * n
        gap = dist[hit] + np.einsum("ij,ij->i", shift, n)
        state.x[hit] += shift + np.maximum(thickness - gap, 0.0)[:, None] * n
        state.v[hit] = v_new
        # resting (not leaving) and not held by a pull last step: held during the next one
        rest = (np.einsum("ij,ij->i", new_rel, n) <= 1e-9) & (held >= 0)
        mu = np.broadcast_to(mu, hit.shape)
        pressing = (model.vertex_mass[hit] * (np.maximum(held, 0.0) + dv_n) / dt)[rest]  # [N]: the solve's and this response's
        return Contacts(hit[rest], n[rest], np.einsum("ij,ij->i", vb[rest], n[rest]), model.vertex_count,
                        body_velocity=vb[rest], friction=mu[rest], normal_force=pressing)


def _recent(store: dict, key, keep: int, make):
    """``store[key]``, made by ``make()`` if missing; the store keeps the ``keep`` made last (a walk
    moves on frame by frame: what it left behind is not asked again)."""
    if key not in store:
        if len(store) >= keep:
            store.pop(next(iter(store)))
        store[key] = make()
    return store[key]
