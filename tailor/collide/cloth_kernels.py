"""Compiled kernels of the self-collision narrow phase and response (:mod:`.cloth` explains them).

Vertex–triangle and edge–edge pairs are judged for contact, predicted contact or crossing
(:func:`detect_vt`, :func:`detect_ee`), and resolved by equal and opposite inelastic impulses
(Carignan Eq. 5–8, :func:`resolve_contacts`); the parallel variants write one slot per pair, so
their result does not depend on the thread count.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .broad import run_starts

__all__ = ["detect_vt", "detect_vt_serial", "detect_ee", "detect_ee_serial", "pair_motion", "resolve_contacts", "present",
           "unique_ints", "touching", "touching_vt", "NEAR_THICKNESS", "PARALLEL_PAIRS"]

LAYER_EDGE_COS2 = 0.9 ** 2
"""cos² of the largest angle (26°) between an edge pair's common normal and an outfit's layer normal
at which the layer rule sets the pair's side (:func:`_ee_pair`); beyond it the normal lies too near
the layers for its sign to say which side of them an edge is on (GarmentCode's garments layered on
MakeHuman's bodies were shoved sideways by such pairs until they tore; docs/outfits.md)."""

NEAR_THICKNESS = 0.25
"""Fraction of the thickness kept between a vertex and a triangle of its 1-ring (or two edges whose
ends are neighbours): enough to stop a tight fold passing through itself, little enough not to
push a sharp seam corner open."""
PARALLEL_PAIRS = 4096
"""Candidate pairs from which the narrow phase runs on every thread (below, waking them costs more)."""


def unique_ints(a):
    """Sorted distinct values of a 1-D integer array, by one sort (NumPy 2's ``np.unique`` hashes,
    far slower on millions of keys: docs/measurements.md)."""
    a = np.sort(a)
    return a[run_starts(a)] if len(a) else a


def present(a, size: int):
    """Sorted distinct values of an integer array ``a`` of values in [0, ``size``), by a mask (as
    :func:`unique_ints`, without a sort: the vertices of an active set of faces)."""
    mask = np.zeros(size, np.bool_)
    mask[a] = True
    return np.flatnonzero(mask)


@njit(cache=True, parallel=True)
def _touching(rows, mask, out):
    for k in prange(rows.shape[0]):
        hit = False
        for j in range(rows.shape[1]):
            hit = hit or mask[rows[k, j]]
        out[k] = hit


def touching(rows, mask):
    """(K,) bool: whether each row of vertex indices ``rows`` (K, m) holds a vertex of ``mask`` (N,)
    bool (one compiled pass: NumPy's fancy index and ``any`` take several over 250 k edge pairs)."""
    rows = np.asarray(rows)
    out = np.empty(len(rows), np.bool_)
    if len(rows):
        _touching(np.ascontiguousarray(rows.reshape(len(rows), -1), dtype=np.int64), np.ascontiguousarray(mask, np.bool_), out)
    return out


@njit(cache=True)
def _classify(gap, closing, travelled, thickness, reach):
    """Whether a pair at signed ``gap`` (positive on the side it was on) is a contact.

    In contact: nearer than ``thickness``. Predicted: ``closing`` [m] (approach over the next step,
    1.5× the current velocity) would bring it nearer. Crossed: behind by no more than it
    ``travelled`` relative to the other side since the previous step (a real passage, not a plane
    sweeping past a distant point), and within ``reach``.
    """
    if gap >= reach or gap < -reach:
        return False
    if gap >= thickness:
        return gap - closing < thickness
    if gap < 0.0:
        return -gap <= travelled + thickness
    return True


@njit(cache=True, inline="always")
def _d(x, i, j):
    """x[i] − x[j] as a tuple (no array allocated in the compiled loops)."""
    return x[i, 0] - x[j, 0], x[i, 1] - x[j, 1], x[i, 2] - x[j, 2]


@njit(cache=True, inline="always")
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _cross(a, b):
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


@njit(cache=True, inline="always")
def _store(k, out_i, out_a, out_n, out_h, i0, i1, i2, i3, a0, a1, a2, a3, n, h):
    out_i[k, 0], out_i[k, 1], out_i[k, 2], out_i[k, 3] = i0, i1, i2, i3
    out_a[k, 0], out_a[k, 1], out_a[k, 2], out_a[k, 3] = a0, a1, a2, a3
    out_n[k, 0], out_n[k, 1], out_n[k, 2] = n[0], n[1], n[2]
    out_h[k] = h


@njit(cache=True, inline="always")
def _vt_pair(k, x, xp, vel, dt, faces, vtx, tri, near, fixed, thickness, reach, out_i, out_a, out_n, out_h, hit):
    """Whether candidate k (vertex ``vtx[k]``, triangle ``tri[k]``) is a contact; if so it fills
    slot k of the outputs and sets ``hit[k]``. Each contact is a stencil of four vertices
    with signed weights α summing to zero, the gap being (Σαᵢxᵢ)·n with ``n`` pointing to the side
    the vertex was on before this step (side memory): vertex p over triangle abc at barycentrics
    (u, v, w) has α = (1, −u, −v, −w). Contacts are in contact, predicted or crossed
    (:func:`_classify`) over ``dt``. Pairs flagged ``near`` (the triangle touches the vertex's
    1-ring) keep only :data:`NEAR_THICKNESS` of the thickness: at a sharp bend or a seam corner they
    are close without touching, but a tight fold can still pass through. Each contact's kept
    distance goes to ``out_h``. ``fixed[k]`` (±1, 0: none) overrides the side memory: the side of
    the triangle's winding normal the vertex belongs on (an outfit's layers, :class:`Layers`): a
    pair that has just passed behind its triangle is put back on that side even if it started the
    step behind it; one deeper behind than it travelled is left to untangling.
    """
    hit[k] = False
    p, t = vtx[k], tri[k]
    a, b, c = faces[t, 0], faces[t, 1], faces[t, 2]
    e1, e2 = _d(x, b, a), _d(x, c, a)
    n = _cross(e1, e2)
    nn = math.sqrt(_dot(n, n))
    if nn <= 1e-300:
        return
    n = (n[0] / nn, n[1] / nn, n[2] / nn)
    d = _d(x, p, a)
    s_prev = _dot(_d(xp, p, a), _cross(_d(xp, b, a), _d(xp, c, a)))
    s_now = _dot(d, n)
    side = (1.0 if s_prev > 0.0 else -1.0) if s_prev != 0.0 else (1.0 if s_now >= 0.0 else -1.0)
    if fixed[k] != 0:
        side = float(fixed[k])
    d11, d12, d22 = _dot(e1, e1), _dot(e1, e2), _dot(e2, e2)
    den = d11 * d22 - d12 * d12
    if den <= 0.0:
        return
    r1, r2 = _dot(d, e1), _dot(d, e2)
    v = (d22 * r1 - d12 * r2) / den
    w = (d11 * r2 - d12 * r1) / den
    u = 1.0 - v - w
    if u < 0.0 or v < 0.0 or w < 0.0:
        return
    rv_n = 0.0
    moved2 = 0.0
    for q in range(3):
        rv_n += (vel[p, q] - (u * vel[a, q] + v * vel[b, q] + w * vel[c, q])) * n[q]
        m = (x[p, q] - xp[p, q]) - (u * (x[a, q] - xp[a, q]) + v * (x[b, q] - xp[b, q]) + w * (x[c, q] - xp[c, q]))
        moved2 += m * m
    h = NEAR_THICKNESS * thickness if near[k] else thickness
    if _classify(side * s_now, -1.5 * dt * side * rv_n, math.sqrt(moved2), h, reach):
        _store(k, out_i, out_a, out_n, out_h, p, a, b, c, 1.0, -u, -v, -w,
               (side * n[0], side * n[1], side * n[2]), h)
        hit[k] = True


@njit(cache=True, parallel=True)
def detect_vt(x, xp, vel, dt, faces, vtx, tri, near, fixed, thickness, reach, out_i, out_a, out_n, out_h, hit, sel):
    """The vertex–triangle candidates ``sel`` through :func:`_vt_pair`, in parallel (one slot each: the
    result does not depend on the thread count)."""
    for j in prange(len(sel)):
        _vt_pair(sel[j], x, xp, vel, dt, faces, vtx, tri, near, fixed, thickness, reach, out_i, out_a, out_n, out_h, hit)


@njit(cache=True)
def detect_vt_serial(x, xp, vel, dt, faces, vtx, tri, near, fixed, thickness, reach, out_i, out_a, out_n, out_h, hit, sel):
    """:func:`detect_vt` on one thread: a few hundred candidates are not worth waking the others."""
    for j in range(len(sel)):
        _vt_pair(sel[j], x, xp, vel, dt, faces, vtx, tri, near, fixed, thickness, reach, out_i, out_a, out_n, out_h, hit)


SWUNG = 0.1
"""cos² of the angle by which an edge pair's common normal may turn in a step and still carry its
side memory (72°). Nearly parallel edges (the two walls of a pleat pressed together, their grid
edges aligned) have a common normal that swings with fractions of a millimetre of motion; the side
read in the last step's normal is then noise, and a pair read as crossed is pushed through by
millimetres (a 256² sheet on the sphere pinched 3.6× at a pleat's foot). Such a pair keeps the side
it is on now: a contact by proximity or approach, never a crossing. It costs halved steps where a
pair had truly crossed (the 64² sheet at ``normal``: 278 against 29); leaving such pairs out instead
stopped a GarmentCode T-shirt at the armpit. docs/measurements.md, thirty-first day."""


@njit(cache=True, inline="always")
def _ee_pair(k, x, xp, vel, dt, pairs, near, toward, thickness, reach, out_i, out_a, out_n, out_h, hit, offset):
    """Whether candidate edge pair k of ``pairs`` (E, 4) = (a0, a1, b0, b1) is a contact; it uses slot
    ``offset + k`` of the outputs and of ``hit``.

    Two edges can pass through each other with no vertex ever near a triangle (sheets sliding
    across each other, a boundary edge cutting through a layer). Their closest points
    pa = (1 − s)·a0 + s·a1 and pb = (1 − t)·b0 + t·b1 give the stencil α = (1 − s, s, −(1 − t), −t)
    and the normal n = (a1 − a0) × (b1 − b0) / |…|, oriented by side memory like the vertex–triangle
    case: the sign of (pa − pb)·n before this step (it flips only when the edges pass through each
    other), unless the normal swung more than :data:`SWUNG` allows. Pairs whose closest points
    fall on an end (a vertex: the vertex–triangle test covers it) or that are parallel within 0.06°
    (the normal is undefined) are left out; ``near`` pairs (ends
    in each other's 1-ring) keep a smaller distance, as in :func:`detect_vt`. A non-zero
    ``toward[k]`` overrides the side memory: edge a belongs on the side of edge b that vector points
    to (an outfit's layers), as ``fixed`` does in :func:`_vt_pair`, where the common normal lies
    within acos(√:data:`LAYER_EDGE_COS2`) of that vector. Off it (edges near parallel, or one rising
    out of its layer) the normal's sign says nothing of the layers and a forced side shoved the
    cloth sideways step after step: such a pair keeps its side memory where that agrees with the
    layers and is no contact where it does not (the vertex–triangle rule puts the cloth back).
    """
    slot = offset + k
    hit[slot] = False
    a0, a1, b0, b1 = pairs[k, 0], pairs[k, 1], pairs[k, 2], pairs[k, 3]
    da, db, r = _d(x, a1, a0), _d(x, b1, b0), _d(x, a0, b0)
    aa, bb, ab = _dot(da, da), _dot(db, db), _dot(da, db)
    den = aa * bb - ab * ab
    if den <= 1e-6 * aa * bb:  # within 0.06° of parallel
        return
    ar, br = _dot(da, r), _dot(db, r)
    s = (ab * br - bb * ar) / den
    t = (aa * br - ab * ar) / den
    if s <= 0.0 or s >= 1.0 or t <= 0.0 or t >= 1.0:
        return
    n = _cross(da, db)
    nn = math.sqrt(_dot(n, n))
    n = (n[0] / nn, n[1] / nn, n[2] / nn)
    g_now = 0.0
    g_prev = 0.0
    rv_n = 0.0
    moved2 = 0.0
    n_prev = _cross(_d(xp, a1, a0), _d(xp, b1, b0))
    for q in range(3):
        g_now += (r[q] + s * da[q] - t * db[q]) * n[q]
        g_prev += ((1.0 - s) * xp[a0, q] + s * xp[a1, q] - (1.0 - t) * xp[b0, q] - t * xp[b1, q]) * n_prev[q]
        rv_n += ((1.0 - s) * vel[a0, q] + s * vel[a1, q] - (1.0 - t) * vel[b0, q] - t * vel[b1, q]) * n[q]
        m = ((1.0 - s) * (x[a0, q] - xp[a0, q]) + s * (x[a1, q] - xp[a1, q])
             - (1.0 - t) * (x[b0, q] - xp[b0, q]) - t * (x[b1, q] - xp[b1, q]))
        moved2 += m * m
    turned = _dot(n_prev, n)
    if turned < 0.0:
        g_prev = -g_prev  # the edges turned over each other: keep the sign in today's normal
    if turned * turned < SWUNG * _dot(n_prev, n_prev):
        g_prev = 0.0  # their common normal swung (nearly parallel edges): the side it gave is no memory
    side = (1.0 if g_prev > 0.0 else -1.0) if g_prev != 0.0 else (1.0 if g_now >= 0.0 else -1.0)
    h = NEAR_THICKNESS * thickness if near[k] else thickness
    lay = (toward[k, 0], toward[k, 1], toward[k, 2])
    lay2 = _dot(lay, lay)
    if lay2 > 0.0:
        pull = _dot(n, lay)
        if pull * pull >= LAYER_EDGE_COS2 * lay2:
            side = 1.0 if pull > 0.0 else -1.0
        elif pull * side < 0.0:  # the common normal stands off the layers: memory, never against them
            return
    if _classify(side * g_now, -1.5 * dt * side * rv_n, math.sqrt(moved2), h, reach):
        _store(slot, out_i, out_a, out_n, out_h, a0, a1, b0, b1, 1.0 - s, s, t - 1.0, -t,
               (side * n[0], side * n[1], side * n[2]), h)
        hit[slot] = True


@njit(cache=True, parallel=True)
def detect_ee(x, xp, vel, dt, pairs, near, toward, thickness, reach, out_i, out_a, out_n, out_h, hit, offset, sel):
    """The edge–edge candidates ``sel`` through :func:`_ee_pair`, in parallel (one slot each)."""
    for j in prange(len(sel)):
        _ee_pair(sel[j], x, xp, vel, dt, pairs, near, toward, thickness, reach, out_i, out_a, out_n, out_h, hit, offset)


@njit(cache=True)
def detect_ee_serial(x, xp, vel, dt, pairs, near, toward, thickness, reach, out_i, out_a, out_n, out_h, hit, offset, sel):
    """:func:`detect_ee` on one thread."""
    for j in range(len(sel)):
        _ee_pair(sel[j], x, xp, vel, dt, pairs, near, toward, thickness, reach, out_i, out_a, out_n, out_h, hit, offset)


@njit(cache=True, parallel=True)
def _touching_vt(vtx, tri, faces, mask, out):
    for k in prange(len(tri)):
        f = faces[tri[k]]
        out[k] = mask[vtx[k]] or mask[f[0]] or mask[f[1]] or mask[f[2]]


def touching_vt(vtx, tri, faces, mask):
    """(K,) bool: whether each vertex–triangle pair (``vtx``, ``tri``) has a vertex of ``mask``."""
    out = np.empty(len(tri), np.bool_)
    if len(tri):
        _touching_vt(vtx, tri, faces, np.ascontiguousarray(mask, np.bool_), out)
    return out


@njit(cache=True)
def pair_motion(motion, vtx, tri, faces, ee):
    """Largest relative motion [m] within any candidate pair: of a vertex against its triangle's
    corners, of an edge's ends against the other's (bounds the motion of the pair's closest points)."""
    worst = 0.0
    for k in range(len(vtx)):
        p = vtx[k]
        for c in range(3):
            q = faces[tri[k], c]
            d = 0.0
            for e in range(3):
                g = motion[p, e] - motion[q, e]
                d += g * g
            worst = max(worst, d)
    for k in range(len(ee)):
        for i in range(2):
            for j in range(2, 4):
                d = 0.0
                for e in range(3):
                    g = motion[ee[k, i], e] - motion[ee[k, j], e]
                    d += g * g
                worst = max(worst, d)
    return math.sqrt(worst)


@njit(cache=True)
def resolve_contacts(x, vel, inv_mass, ci, ca, cn, ch, dt, friction, sweeps):
    """Gauss–Seidel over the contacts: separate to ``thickness``, then Eq. 5–8 on approaching pairs.

    With stencil weights α (Σα = 0) every correction moves vertex i by αᵢ·imᵢ·j for one vector j,
    so Σmᵢ·Δvᵢ = j·Σαᵢ = 0: linear momentum is conserved exactly. Returns the largest remaining
    overlap [m].
    """
    worst = 0.0
    for _ in range(sweeps):
        worst = 0.0
        least = 1e300
        for k in range(len(ci)):
            n = cn[k]
            thickness = ch[k]
            least = min(least, thickness)
            big_w = 0.0
            r_max = 0.0
            gap = 0.0
            for m in range(4):
                i = ci[k, m]
                big_w += ca[k, m] * ca[k, m] * inv_mass[i]
                gap += ca[k, m] * (x[i] @ n)
            if big_w <= 0.0:
                continue
            # a side held mostly by pinned vertices would fling its free one (Δv = rel/α):
            # no vertex changes by more than the whole relative motion
            for m in range(4):
                r_max = max(r_max, abs(ca[k, m]) * inv_mass[ci[k, m]] / big_w)
            big_w *= max(1.0, r_max)
            if gap < thickness:
                worst = max(worst, thickness - gap)
                lam = (thickness - gap) / big_w
                for m in range(4):
                    i = ci[k, m]
                    x[i] += lam * ca[k, m] * inv_mass[i] * n
            rel = np.zeros(3)
            for m in range(4):
                rel += ca[k, m] * vel[ci[k, m]]
            vn = rel @ n
            j = np.zeros(3)
            if gap < thickness * 1.01:
                if vn < 0.0:  # in contact and approaching: the normal velocities meet (Eq. 7 along n) ...
                    tang = rel - vn * n
                    st = math.sqrt(tang @ tang)
                    # ... and sliding loses at most μ times that (Coulomb, as Eq. 14 for the body)
                    keep = max(0.0, 1.0 - friction * (-vn) / st) if st > 0.0 else 0.0
                    j = -(vn * n + (1.0 - keep) * tang) / big_w
            elif vn * dt < thickness - gap:  # would close the gap this step: arrive, do not cross
                j = ((thickness - gap) / dt - vn) / big_w * n
            for m in range(4):
                i = ci[k, m]
                vel[i] += ca[k, m] * inv_mass[i] * j
        if worst < 1e-3 * least:
            break
    return worst
