"""Compiled (numba) kernels for the hot path: the fused membrane and bending force loops and the
implicit step's Jacobian assembly (its linear solve lives with the integrators, :mod:`tailor.integrators.cg`).

They compute exactly what :mod:`.membrane`, :mod:`.bending` and :mod:`.jacobian` compute with
numpy (those remain the readable reference, and give the energies); ``tests/forces/test_kernels.py``
checks that both agree to round-off. ``benchmarks/forces.py`` measures why they exist
(docs/measurements.md). Every threaded sum
has an order fixed by the mesh, not the thread count. Compiled once per machine (``cache=True``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = [
    "green_strain_into",
    "membrane_forces_into",
    "bending_forces_into",
    "membrane_jacobian_into",
    "bending_jacobian_into",
    "membrane_system_into",
    "bending_system_into",
    "element_chunks",
    "ELEMENT_CHUNK",
    "face_stretch_into",
]


@njit(cache=True)
def _membrane_range(x, v, faces, dm, area, k1, k2, k12, p1, p2, p12, damp, out, start, stop):
    for f in range(start, stop):
        i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
        a00, a01, a10, a11 = dm[f, 0, 0], dm[f, 0, 1], dm[f, 1, 0], dm[f, 1, 1]
        d1x, d1y, d1z = x[i1, 0] - x[i0, 0], x[i1, 1] - x[i0, 1], x[i1, 2] - x[i0, 2]
        d2x, d2y, d2z = x[i2, 0] - x[i0, 0], x[i2, 1] - x[i0, 1], x[i2, 2] - x[i0, 2]
        c1x, c1y, c1z = d1x * a00 + d2x * a10, d1y * a00 + d2y * a10, d1z * a00 + d2z * a10
        c2x, c2y, c2z = d1x * a01 + d2x * a11, d1y * a01 + d2y * a11, d1z * a01 + d2z * a11
        s11 = k1[f] * 0.5 * (c1x * c1x + c1y * c1y + c1z * c1z - 1.0)
        s22 = k2[f] * 0.5 * (c2x * c2x + c2y * c2y + c2z * c2z - 1.0)
        s12 = k12[f] * 0.5 * (c1x * c2x + c1y * c2y + c1z * c2z)
        if damp:
            u1x, u1y, u1z = v[i1, 0] - v[i0, 0], v[i1, 1] - v[i0, 1], v[i1, 2] - v[i0, 2]
            u2x, u2y, u2z = v[i2, 0] - v[i0, 0], v[i2, 1] - v[i0, 1], v[i2, 2] - v[i0, 2]
            r1x, r1y, r1z = u1x * a00 + u2x * a10, u1y * a00 + u2y * a10, u1z * a00 + u2z * a10
            r2x, r2y, r2z = u1x * a01 + u2x * a11, u1y * a01 + u2y * a11, u1z * a01 + u2z * a11
            s11 += p1[f] * (c1x * r1x + c1y * r1y + c1z * r1z)
            s22 += p2[f] * (c2x * r2x + c2y * r2y + c2z * r2z)
            s12 += p12[f] * 0.5 * (c1x * r2x + c1y * r2y + c1z * r2z + r1x * c2x + r1y * c2y + r1z * c2z)
        a = area[f]
        q1, q2 = c1x * s11 + c2x * s12, c1x * s12 + c2x * s22
        g1, g2 = a * (q1 * a00 + q2 * a01), a * (q1 * a10 + q2 * a11)
        out[i0, 0] += g1 + g2
        out[i1, 0] -= g1
        out[i2, 0] -= g2
        q1, q2 = c1y * s11 + c2y * s12, c1y * s12 + c2y * s22
        g1, g2 = a * (q1 * a00 + q2 * a01), a * (q1 * a10 + q2 * a11)
        out[i0, 1] += g1 + g2
        out[i1, 1] -= g1
        out[i2, 1] -= g2
        q1, q2 = c1z * s11 + c2z * s12, c1z * s12 + c2z * s22
        g1, g2 = a * (q1 * a00 + q2 * a01), a * (q1 * a10 + q2 * a11)
        out[i0, 2] += g1 + g2
        out[i1, 2] -= g1
        out[i2, 2] -= g2


@njit(cache=True)
def _bending_range(x, hinges, stiffness, rest, out, start, stop):
    for h in range(start, stop):
        j0, j1, j2, j3 = hinges[h, 0], hinges[h, 1], hinges[h, 2], hinges[h, 3]
        ex, ey, ez = x[j1, 0] - x[j0, 0], x[j1, 1] - x[j0, 1], x[j1, 2] - x[j0, 2]
        ax, ay, az = x[j2, 0] - x[j0, 0], x[j2, 1] - x[j0, 1], x[j2, 2] - x[j0, 2]
        bx, by, bz = x[j3, 0] - x[j1, 0], x[j3, 1] - x[j1, 1], x[j3, 2] - x[j1, 2]
        n0x, n0y, n0z = ey * az - ez * ay, ez * ax - ex * az, ex * ay - ey * ax
        n1x, n1y, n1z = by * ez - bz * ey, bz * ex - bx * ez, bx * ey - by * ex
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        nn0 = n0x * n0x + n0y * n0y + n0z * n0z
        nn1 = n1x * n1x + n1y * n1y + n1z * n1z
        if el == 0.0 or nn0 == 0.0 or nn1 == 0.0:
            continue
        cx, cy, cz = n0y * n1z - n0z * n1y, n0z * n1x - n0x * n1z, n0x * n1y - n0y * n1x
        sin = (cx * ex + cy * ey + cz * ez) / el
        cos = n0x * n1x + n0y * n1y + n0z * n1z
        torque = -stiffness[h] * (math.atan2(sin, cos) - rest[h])
        ux, uy, uz = ex / el, ey / el, ez / el
        a0 = ax * ux + ay * uy + az * uz  # (o0 − e0)·ê
        a1 = a0 - el  # (o0 − e1)·ê
        b1 = bx * ux + by * uy + bz * uz  # (o1 − e1)·ê
        b0 = b1 + el  # (o1 − e0)·ê
        w0, w1 = torque / nn0, torque / nn1
        out[j0, 0] += -a1 * w0 * n0x - b1 * w1 * n1x
        out[j0, 1] += -a1 * w0 * n0y - b1 * w1 * n1y
        out[j0, 2] += -a1 * w0 * n0z - b1 * w1 * n1z
        out[j1, 0] += a0 * w0 * n0x + b0 * w1 * n1x
        out[j1, 1] += a0 * w0 * n0y + b0 * w1 * n1y
        out[j1, 2] += a0 * w0 * n0z + b0 * w1 * n1z
        out[j2, 0] -= el * w0 * n0x
        out[j2, 1] -= el * w0 * n0y
        out[j2, 2] -= el * w0 * n0z
        out[j3, 0] -= el * w1 * n1x
        out[j3, 1] -= el * w1 * n1y
        out[j3, 2] -= el * w1 * n1z


_CHUNK = 1024
_MAX_TASKS = 8


def _tasks(n: int) -> int:
    """Tasks for ``n`` elements: fixed by the mesh, not the thread count, so forces are summed in
    the same order (to the bit) on any machine and in any batch worker."""
    # 2 tasks from 4k elements (measured on 2 cores: 32k faces 0.54 ms vs 0.70 serial, 0.84 at 8
    # tasks, whose buffers cost more than they save), one more per 64k elements
    return min(_MAX_TASKS, 2 + n // (16 * _CHUNK)) if n >= _CHUNK else 1


@njit(cache=True, parallel=True)
def _membrane_parallel(x, v, faces, dm, area, k1, k2, k12, p1, p2, p12, damp, out, tasks):
    buf = np.zeros((tasks, out.shape[0], 3))
    n = faces.shape[0]
    for t in prange(tasks):
        _membrane_range(x, v, faces, dm, area, k1, k2, k12, p1, p2, p12, damp, buf[t], n * t // tasks, n * (t + 1) // tasks)
    for t in range(tasks):
        out += buf[t]


@njit(cache=True, parallel=True)
def _bending_parallel(x, hinges, stiffness, rest, out, tasks):
    buf = np.zeros((tasks, out.shape[0], 3))
    n = hinges.shape[0]
    for t in prange(tasks):
        _bending_range(x, hinges, stiffness, rest, buf[t], n * t // tasks, n * (t + 1) // tasks)
    for t in range(tasks):
        out += buf[t]


def membrane_forces_into(model, state, out, *, damping: bool = True, stiffness=None) -> None:
    """Add stretch (and strain-rate damping) forces of every triangle into ``out`` [N].

    ``stiffness`` = (η₁₁, η₂₂, η₁₂) per face overrides the model's (Kawabata secants). Large meshes
    are split over the available cores, each thread summing into its own buffer.
    """
    k1, k2, k12 = stiffness if stiffness is not None else (model.face_stretch_warp, model.face_stretch_weft, model.face_stretch_shear)
    args = (
        state.x, state.v, model.faces, model.face_dm_inv, model.face_rest_area,
        k1, k2, k12,
        model.face_damping_warp, model.face_damping_weft, model.face_damping_shear, damping, out,
    )
    tasks = _tasks(model.face_count)
    if tasks > 1:
        _membrane_parallel(*args, tasks)
    else:
        _membrane_range(*args, 0, model.face_count)


def bending_forces_into(model, state, out, *, stiffness=None) -> None:
    """Add dihedral bending forces of every hinge into ``out`` [N] (``stiffness`` overrides the model's)."""
    k = model.hinge_stiffness if stiffness is None else stiffness
    args = (state.x, model.hinge_vertices, k, model.hinge_rest_angle, out)
    n = len(model.hinge_vertices)
    tasks = _tasks(n)
    if tasks > 1:
        _bending_parallel(*args, tasks)
    else:
        _bending_range(*args, 0, n)


@njit(cache=True, inline="always")
def _membrane_face(f, x, faces, dm, area, k1, k2, k12, p1, p2, p12, g, kf, cf):
    """Face f's 9×9 stiffness (Gauss–Newton + clamped geometric) and damping blocks, into kf, cf."""
    i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
    a00, a01, a10, a11 = dm[f, 0, 0], dm[f, 0, 1], dm[f, 1, 0], dm[f, 1, 1]
    w1 = (-(a00 + a10), a00, a10)
    w2 = (-(a01 + a11), a01, a11)
    c1x = (x[i1, 0] - x[i0, 0]) * a00 + (x[i2, 0] - x[i0, 0]) * a10
    c1y = (x[i1, 1] - x[i0, 1]) * a00 + (x[i2, 1] - x[i0, 1]) * a10
    c1z = (x[i1, 2] - x[i0, 2]) * a00 + (x[i2, 2] - x[i0, 2]) * a10
    c2x = (x[i1, 0] - x[i0, 0]) * a01 + (x[i2, 0] - x[i0, 0]) * a11
    c2y = (x[i1, 1] - x[i0, 1]) * a01 + (x[i2, 1] - x[i0, 1]) * a11
    c2z = (x[i1, 2] - x[i0, 2]) * a01 + (x[i2, 2] - x[i0, 2]) * a11
    c1 = (c1x, c1y, c1z)
    c2 = (c2x, c2y, c2z)
    for a in range(3):
        for k in range(3):
            g[0, 3 * a + k] = w1[a] * c1[k]
            g[1, 3 * a + k] = w2[a] * c2[k]
            g[2, 3 * a + k] = 0.5 * (w1[a] * c2[k] + w2[a] * c1[k])
    s11 = k1[f] * 0.5 * (c1x * c1x + c1y * c1y + c1z * c1z - 1.0)
    s22 = k2[f] * 0.5 * (c2x * c2x + c2y * c2y + c2z * c2z - 1.0)
    s12 = k12[f] * 0.5 * (c1x * c2x + c1y * c2y + c1z * c2z)
    # positive part of the 2×2 stress (closed-form eigen-decomposition)
    half_tr = 0.5 * (s11 + s22)
    rad = math.sqrt(0.25 * (s11 - s22) ** 2 + s12 * s12)
    l1, l2 = half_tr + rad, half_tr - rad
    if rad > 0.0:
        if abs(s12) > 1e-300:
            v1x, v1y = l1 - s22, s12
        elif s11 >= s22:
            v1x, v1y = 1.0, 0.0
        else:
            v1x, v1y = 0.0, 1.0
        nrm = math.sqrt(v1x * v1x + v1y * v1y)
        v1x, v1y = v1x / nrm, v1y / nrm
    else:
        v1x, v1y = 1.0, 0.0
    v2x, v2y = -v1y, v1x
    l1p, l2p = max(l1, 0.0), max(l2, 0.0)
    q11 = l1p * v1x * v1x + l2p * v2x * v2x
    q22 = l1p * v1y * v1y + l2p * v2y * v2y
    q12 = l1p * v1x * v1y + l2p * v2x * v2y
    ar = area[f]
    ck0, ck1, ck2 = k1[f] * ar, k2[f] * ar, 2.0 * k12[f] * ar
    cc0, cc1, cc2 = p1[f] * ar, p2[f] * ar, 2.0 * p12[f] * ar
    for r in range(9):
        for c in range(9):
            kv = ck0 * g[0, r] * g[0, c] + ck1 * g[1, r] * g[1, c] + ck2 * g[2, r] * g[2, c]
            cf[r, c] = cc0 * g[0, r] * g[0, c] + cc1 * g[1, r] * g[1, c] + cc2 * g[2, r] * g[2, c]
            if r % 3 == c % 3:
                ra, cb = r // 3, c // 3
                kv += ar * (w1[ra] * (q11 * w1[cb] + q12 * w2[cb]) + w2[ra] * (q12 * w1[cb] + q22 * w2[cb]))
            kf[r, c] = kv


@njit(cache=True)
def _membrane_jacobian(x, faces, dm, area, k1, k2, k12, p1, p2, p12, pos, kdata, cdata):
    """Scatter each face's 9×9 stiffness and damping blocks into CSR data (the reference layout)."""
    g = np.empty((3, 9))
    kf = np.empty((9, 9))
    cf = np.empty((9, 9))
    for f in range(faces.shape[0]):
        _membrane_face(f, x, faces, dm, area, k1, k2, k12, p1, p2, p12, g, kf, cf)
        for r in range(9):
            for c in range(9):
                p = pos[f, 9 * r + c]
                kdata[p] += kf[r, c]
                cdata[p] += cf[r, c]


@njit(cache=True, inline="always")
def _add_element(e, nodes, slots, kf, cf, v, dt, blocks, kv):
    """blocks += Δt·C_e + Δt²·K_e and kv += K_e·v over element e's vertex pairs."""
    k = nodes.shape[1]
    dt2 = dt * dt
    for a in range(k):
        ia = nodes[e, a]
        for b in range(k):
            ib = nodes[e, b]
            s = slots[e, a, b]
            for r in range(3):
                acc = 0.0
                for c in range(3):
                    kk = kf[3 * a + r, 3 * b + c]
                    blocks[s, r, c] += dt * cf[3 * a + r, 3 * b + c] + dt2 * kk
                    acc += kk * v[ib, c]
                kv[ia, r] += acc


ELEMENT_CHUNK = 128
"""Elements of one parallel task of the assembly (:func:`element_chunks`): neighbours in the mesh,
their blocks a few kilobytes, kept in cache while the chunk adds to them."""


@njit(cache=True, parallel=True)
def _membrane_system(x, v, faces, dm, area, k1, k2, k12, p1, p2, p12, slots, order, tasks, classes, dt, blocks, kv):
    """Faces' Δt·C + Δt²·K into 3×3 blocks and K·v, one colour class of chunks at a time
    (:func:`element_chunks`).

    No two chunks of a class share a vertex, so a class's chunks run in parallel without write
    conflicts, each in its own order, and every block sums its faces in one order on any thread
    count; a chunk's faces share most of their vertices, so their blocks stay in cache.
    """
    for col in range(len(classes) - 1):
        for task in prange(classes[col], classes[col + 1]):
            g = np.empty((3, 9))
            kf = np.empty((9, 9))
            cf = np.empty((9, 9))
            for t in range(tasks[task], tasks[task + 1]):
                f = order[t]
                _membrane_face(f, x, faces, dm, area, k1, k2, k12, p1, p2, p12, g, kf, cf)
                _add_element(f, faces, slots, kf, cf, v, dt, blocks, kv)


@njit(cache=True, inline="always")
def _hinge_gradient(h, x, hinges, g):
    """∇θ of hinge h into g (12,); False for a degenerate hinge (no bending stiffness then)."""
    j0, j1, j2, j3 = hinges[h, 0], hinges[h, 1], hinges[h, 2], hinges[h, 3]
    ex, ey, ez = x[j1, 0] - x[j0, 0], x[j1, 1] - x[j0, 1], x[j1, 2] - x[j0, 2]
    ax, ay, az = x[j2, 0] - x[j0, 0], x[j2, 1] - x[j0, 1], x[j2, 2] - x[j0, 2]
    bx, by, bz = x[j3, 0] - x[j1, 0], x[j3, 1] - x[j1, 1], x[j3, 2] - x[j1, 2]
    n0 = (ey * az - ez * ay, ez * ax - ex * az, ex * ay - ey * ax)
    n1 = (by * ez - bz * ey, bz * ex - bx * ez, bx * ey - by * ex)
    el = math.sqrt(ex * ex + ey * ey + ez * ez)
    nn0 = n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]
    nn1 = n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]
    if el == 0.0 or nn0 == 0.0 or nn1 == 0.0:
        return False
    ux, uy, uz = ex / el, ey / el, ez / el
    a0 = ax * ux + ay * uy + az * uz
    a1 = a0 - el
    b1 = bx * ux + by * uy + bz * uz
    b0 = b1 + el
    for k in range(3):
        q0 = n0[k] / nn0
        q1 = n1[k] / nn1
        g[k] = -a1 * q0 - b1 * q1
        g[3 + k] = a0 * q0 + b0 * q1
        g[6 + k] = -el * q0
        g[9 + k] = -el * q1
    return True


@njit(cache=True)
def _bending_jacobian(x, hinges, stiffness, pos, kdata):
    """Scatter each hinge's 12×12 Gauss–Newton block k·∇θ∇θᵀ into CSR data (the reference layout)."""
    g = np.empty(12)
    for h in range(hinges.shape[0]):
        if not _hinge_gradient(h, x, hinges, g):
            continue
        kh = stiffness[h]
        for r in range(12):
            for c in range(12):
                kdata[pos[h, 12 * r + c]] += kh * g[r] * g[c]


@njit(cache=True, parallel=True)
def _bending_system(x, v, hinges, stiffness, slots, order, tasks, classes, dt, blocks, kv):
    """Hinges' Δt²·k·∇θ∇θᵀ into 3×3 blocks and K·v = k·∇θ·(∇θ·v), one colour class of chunks at a
    time (as :func:`_membrane_system`)."""
    dt2 = dt * dt
    for col in range(len(classes) - 1):
        for task in prange(classes[col], classes[col + 1]):
            g = np.empty(12)
            for t in range(tasks[task], tasks[task + 1]):
                h = order[t]
                if not _hinge_gradient(h, x, hinges, g):
                    continue
                kh = stiffness[h]
                gv = 0.0
                for a in range(4):
                    j = hinges[h, a]
                    gv += g[3 * a] * v[j, 0] + g[3 * a + 1] * v[j, 1] + g[3 * a + 2] * v[j, 2]
                for a in range(4):
                    ia = hinges[h, a]
                    for r in range(3):
                        kv[ia, r] += kh * g[3 * a + r] * gv
                        w = dt2 * kh * g[3 * a + r]
                        for b in range(4):
                            s = slots[h, a, b]
                            for c in range(3):
                                blocks[s, r, c] += w * g[3 * b + c]


@njit(cache=True)
def element_chunks(nodes, vertex_count, chunk):
    """(order, tasks, classes): the elements (rows of vertex ids) sorted by their lowest vertex and
    cut into chunks of ``chunk``, the chunks coloured so that none of a class shares a vertex with
    another of it. Chunk k's elements are ``order[tasks[k]:tasks[k+1]]``; class c's chunks are
    ``classes[c]`` to ``classes[c+1]``. A mesh numbers its vertices panel by panel, row by row, so a
    chunk is a patch of neighbours: an assembly adding a chunk at a time touches a few kilobytes of
    blocks instead of sweeping the whole matrix once per colour class of single elements.
    Greedy over at most 64 classes (vertex bit masks); a chunk that would need a 65th gets a class
    of its own."""
    n, k = nodes.shape[0], nodes.shape[1]
    low = np.empty(n, np.int64)
    for e in range(n):
        m = nodes[e, 0]
        for a in range(1, k):
            m = min(m, nodes[e, a])
        low[e] = m
    by_vertex = np.argsort(low, kind="mergesort")
    chunks = (n + chunk - 1) // chunk
    masks = np.zeros(vertex_count, np.uint64)
    color = np.empty(chunks, np.int64)
    one, extra = np.uint64(1), 64
    for c in range(chunks):
        used = np.uint64(0)
        for t in range(c * chunk, min(n, (c + 1) * chunk)):
            for a in range(k):
                used |= masks[nodes[by_vertex[t], a]]
        col = 0
        while col < 64 and (used >> np.uint64(col)) & one:
            col += 1
        if col == 64:
            color[c] = extra
            extra += 1
            continue
        color[c] = col
        for t in range(c * chunk, min(n, (c + 1) * chunk)):
            for a in range(k):
                masks[nodes[by_vertex[t], a]] |= one << np.uint64(col)
    sequence = np.argsort(color, kind="mergesort")
    order = np.empty(n, np.int64)
    tasks = np.zeros(chunks + 1, np.int64)
    counts = np.bincount(color) if chunks else np.zeros(0, np.int64)
    classes = np.zeros(len(counts) + 1, np.int64)
    at = 0
    for j in range(chunks):
        c = sequence[j]
        for t in range(c * chunk, min(n, (c + 1) * chunk)):
            order[at] = by_vertex[t]
            at += 1
        tasks[j + 1] = at
    m = 0
    for c in range(len(counts)):
        if counts[c]:
            m += 1
            classes[m] = classes[m - 1] + counts[c]
    return order, tasks, classes[: m + 1]


def membrane_jacobian_into(model, x, positions, kdata, cdata, *, stiffness=None) -> None:
    """Add the membrane stiffness and damping Jacobian entries into CSR data arrays."""
    k1, k2, k12 = stiffness if stiffness is not None else (model.face_stretch_warp, model.face_stretch_weft, model.face_stretch_shear)
    _membrane_jacobian(
        x, model.faces, model.face_dm_inv, model.face_rest_area,
        k1, k2, k12,
        model.face_damping_warp, model.face_damping_weft, model.face_damping_shear, positions, kdata, cdata,
    )


def membrane_system_into(model, state, slots, colors, dt, blocks, kv, *, stiffness=None) -> None:
    """Add the faces' Δt·C + Δt²·K into 3×3 ``blocks`` (element ``slots`` (F, 3, 3)) and K·v into ``kv`` (N, 3)."""
    k1, k2, k12 = stiffness if stiffness is not None else (model.face_stretch_warp, model.face_stretch_weft, model.face_stretch_shear)
    _membrane_system(state.x, state.v, model.faces, model.face_dm_inv, model.face_rest_area, k1, k2, k12,
                     model.face_damping_warp, model.face_damping_weft, model.face_damping_shear, slots, *colors, dt, blocks, kv)


def bending_system_into(model, state, slots, colors, dt, blocks, kv, *, stiffness=None) -> None:
    """Add the hinges' Δt²·K into 3×3 ``blocks`` (element ``slots`` (H, 4, 4)) and K·v into ``kv`` (N, 3)."""
    _bending_system(state.x, state.v, model.hinge_vertices, model.hinge_stiffness if stiffness is None else stiffness,
                    slots, *colors, dt, blocks, kv)


def bending_jacobian_into(model, x, positions, kdata, *, stiffness=None) -> None:
    """Add the bending stiffness Jacobian entries into a CSR data array."""
    _bending_jacobian(x, model.hinge_vertices, model.hinge_stiffness if stiffness is None else stiffness, positions, kdata)


@njit(cache=True, inline="always")
def _metric(x, faces, dm, f):
    """(c₁·c₁, c₂·c₂, c₁·c₂): the metric FᵀF of triangle ``f``, F's columns c₁, c₂ = [x₁ − x₀, x₂ − x₀]·Dm⁻¹."""
    i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
    a = b = c = 0.0
    for k in range(3):
        d1 = x[i1, k] - x[i0, k]
        d2 = x[i2, k] - x[i0, k]
        c1 = d1 * dm[f, 0, 0] + d2 * dm[f, 1, 0]
        c2 = d1 * dm[f, 0, 1] + d2 * dm[f, 1, 1]
        a += c1 * c1
        b += c2 * c2
        c += c1 * c2
    return a, b, c


@njit(cache=True, parallel=True)
def face_stretch_into(x, faces, dm, out):
    """Largest principal stretch of each triangle into ``out`` (F,): √ of FᵀF's larger eigenvalue."""
    for f in prange(len(faces)):
        a, b, c = _metric(x, faces, dm, f)
        half = 0.5 * (a + b)
        out[f] = math.sqrt(half + math.sqrt(max(half * half - (a * b - c * c), 0.0)))


@njit(cache=True, parallel=True)
def green_strain_into(x, faces, dm, e11, e22, e12):
    """Green strain (E₁₁, E₂₂, E₁₂) of each triangle into the three (F,) arrays: ½(FᵀF − I) with F's
    columns c₁, c₂ as :func:`face_stretch_into` forms them."""
    for f in prange(len(faces)):
        a, b, c = _metric(x, faces, dm, f)
        e11[f], e22[f], e12[f] = 0.5 * (a - 1.0), 0.5 * (b - 1.0), 0.5 * c
