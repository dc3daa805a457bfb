"""Compiled (numba) kernels of the implicit step's linear solve: 3×3 block-CSR products and the
filtered block-Jacobi preconditioned CG (Baraff & Witkin 1998, §5.3).

Every threaded sum runs over chunks fixed by the vertex count, not the thread count, so a solve is
deterministic on any machine. Compiled once per machine (``cache=True``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = ["bsr_rows", "block_pcg", "inverse_3x3"]

_CHUNK = 1024
"""Vertices per chunk of a threaded reduction (the order of every sum is fixed by it)."""

@njit(cache=True, inline="always")
def _block_row(bptr, bcol, blocks, x, i):
    """Row ``i`` of A·x for A in 3×3 block-CSR form: (a0, a1, a2)."""
    a0 = a1 = a2 = 0.0
    for p in range(bptr[i], bptr[i + 1]):
        j = 3 * bcol[p]
        x0, x1, x2 = x[j], x[j + 1], x[j + 2]
        a0 += blocks[p, 0, 0] * x0 + blocks[p, 0, 1] * x1 + blocks[p, 0, 2] * x2
        a1 += blocks[p, 1, 0] * x0 + blocks[p, 1, 1] * x1 + blocks[p, 1, 2] * x2
        a2 += blocks[p, 2, 0] * x0 + blocks[p, 2, 1] * x1 + blocks[p, 2, 2] * x2
    return a0, a1, a2



@njit(cache=True, parallel=True)
def bsr_rows(bptr, bcol, blocks, x, rows, out):
    """out[k] = row ``rows[k]`` of A·x, (K, 3), for A in 3×3 block-CSR form (a few rows of the product)."""
    for k in prange(len(rows)):
        out[k, 0], out[k, 1], out[k, 2] = _block_row(bptr, bcol, blocks, x, rows[k])



@njit(cache=True, inline="always")
def _held_part(v0, v1, v2, c, normals):
    """(v0, v1, v2) without its held part if the vertex is held contact ``c`` (−1: not held): the
    normal component."""
    if c < 0:
        return v0, v1, v2
    d = v0 * normals[c, 0] + v1 * normals[c, 1] + v2 * normals[c, 2]
    return v0 - d * normals[c, 0], v1 - d * normals[c, 1], v2 - d * normals[c, 2]


@njit(cache=True, parallel=True)
def _cg_product(bptr, bcol, blocks, p, q, held, normals, part):
    """q = filter(A·p) and the chunks' partial sums of p·q, in one pass."""
    n = len(bptr) - 1
    for ch in prange((n + _CHUNK - 1) // _CHUNK):
        acc = 0.0
        for i in range(ch * _CHUNK, min(n, (ch + 1) * _CHUNK)):
            a0, a1, a2 = _block_row(bptr, bcol, blocks, p, i)
            a0, a1, a2 = _held_part(a0, a1, a2, held[i], normals)
            q[3 * i], q[3 * i + 1], q[3 * i + 2] = a0, a1, a2
            acc += p[3 * i] * a0 + p[3 * i + 1] * a1 + p[3 * i + 2] * a2
        part[ch] = acc


@njit(cache=True, parallel=True)
def _cg_update(alpha, x, r, p, q, z, pinv, held, normals, part_rz, part_rr):
    """x += α·p, r −= α·q, z = filter(P·r) and the chunks' partial sums of r·z and r·r, in one pass."""
    n = len(pinv)
    for ch in prange((n + _CHUNK - 1) // _CHUNK):
        rz = 0.0
        rr = 0.0
        for i in range(ch * _CHUNK, min(n, (ch + 1) * _CHUNK)):
            for e in range(3 * i, 3 * i + 3):
                x[e] += alpha * p[e]
                r[e] -= alpha * q[e]
            r0, r1, r2 = r[3 * i], r[3 * i + 1], r[3 * i + 2]
            z0 = pinv[i, 0, 0] * r0 + pinv[i, 0, 1] * r1 + pinv[i, 0, 2] * r2
            z1 = pinv[i, 1, 0] * r0 + pinv[i, 1, 1] * r1 + pinv[i, 1, 2] * r2
            z2 = pinv[i, 2, 0] * r0 + pinv[i, 2, 1] * r1 + pinv[i, 2, 2] * r2
            z0, z1, z2 = _held_part(z0, z1, z2, held[i], normals)
            z[3 * i], z[3 * i + 1], z[3 * i + 2] = z0, z1, z2
            rz += r0 * z0 + r1 * z1 + r2 * z2
            rr += r0 * r0 + r1 * r1 + r2 * r2
        part_rz[ch] = rz
        part_rr[ch] = rr


@njit(cache=True, parallel=True)
def _cg_direction(beta, p, z):
    for i in prange(len(p)):
        p[i] = z[i] + beta * p[i]


@njit(cache=True, parallel=True)
def _cg_residual(b, q, r, held, normals, part):
    """r = S·b − q (q = S·A·x: the filtered residual) in one pass; returns b·b (summed over fixed chunks)."""
    n = len(held)
    for ch in prange((n + _CHUNK - 1) // _CHUNK):
        acc = 0.0
        for i in range(ch * _CHUNK, min(n, (ch + 1) * _CHUNK)):
            b0, b1, b2 = b[3 * i], b[3 * i + 1], b[3 * i + 2]
            acc += b0 * b0 + b1 * b1 + b2 * b2
            f0, f1, f2 = _held_part(b0, b1, b2, held[i], normals)
            r[3 * i], r[3 * i + 1], r[3 * i + 2] = f0 - q[3 * i], f1 - q[3 * i + 1], f2 - q[3 * i + 2]
        part[ch] = acc
    return _total(part)


@njit(cache=True, inline="always")
def _total(part):
    s = 0.0
    for c in range(len(part)):
        s += part[c]
    return s


@njit(cache=True)
def block_pcg(bptr, bcol, blocks, b, x, pinv, rtol, max_iterations, ids, normals):
    """Block-Jacobi preconditioned CG on a 3×3 block-CSR matrix, filtered by contacts, in place.

    Baraff & Witkin's modified PCG (1998, §5.3): vertex ``ids[k]`` may not change its velocity
    along ``normals[k]`` from the value ``x`` holds on entry (the caller sets it to the prescribed
    one) but moves freely in the tangent plane (friction is a drag in the matrix); no constraints
    if ``ids`` is empty. Residual and search directions are
    projected ("filtered") onto the free subspace, so A·x − b on exit is the constraints' reaction.
    Block storage has one column index per 3×3 block; each vertex's own 3×3 diagonal block,
    inverted, is the preconditioner (``pinv``, (N, 3, 3)). An iteration is three threaded passes
    over the vertices (product with its filter and p·q; update, preconditioner, filter, r·z and r·r;
    new direction) instead of eight separate loops. Returns (iterations, converged); stops when |filtered r| ≤ rtol·|b|.

    Cheaper per solve here than the multigrid and Gauss–Seidel preconditioners tried against it
    (docs/measurements.md): one product is cheap and the contact passes restart CG often.
    """
    nv = len(bptr) - 1
    n = len(b)
    held = np.full(nv, -1, np.int64)
    for k in range(len(ids)):
        held[ids[k]] = k
    part = np.zeros((nv + _CHUNK - 1) // _CHUNK)
    part2 = np.zeros_like(part)
    r = np.empty(n)
    q = np.empty(n)
    z = np.empty(n)
    _cg_product(bptr, bcol, blocks, x, q, held, normals, part)  # q = S·A·x
    bnorm = math.sqrt(_cg_residual(b, q, r, held, normals, part))  # r = S·b − q
    if bnorm == 0.0:
        if len(ids) == 0:
            x[:] = 0.0
        return 0, True
    q[:] = 0.0
    _cg_update(0.0, x, r, q, q, z, pinv, held, normals, part, part2)  # z = filter(P·r)
    rz = _total(part)
    rr = _total(part2)
    p = z.copy()
    target = rtol * bnorm
    for it in range(max_iterations):
        if math.sqrt(rr) <= target:
            return it, True
        _cg_product(bptr, bcol, blocks, p, q, held, normals, part)
        pq = _total(part)
        if pq <= 0.0:
            return it, False
        alpha = rz / pq
        _cg_update(alpha, x, r, p, q, z, pinv, held, normals, part, part2)
        rz_new = _total(part)
        rr = _total(part2)
        beta = rz_new / rz
        rz = rz_new
        _cg_direction(beta, p, z)
    return max_iterations, math.sqrt(rr) <= target


@njit(cache=True, parallel=True)
def inverse_3x3(a):
    """Inverses of (N, 3, 3) matrices by their adjugates (the block-Jacobi preconditioner's blocks).

    The diagonal blocks are mass plus Δt²·stiffness, symmetric positive definite; LAPACK's batched
    ``np.linalg.inv`` spends longer dispatching 3 × 3 problems than solving them.
    """
    out = np.empty_like(a)
    for k in prange(a.shape[0]):
        m = a[k]
        c00 = m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]
        c01 = m[1, 2] * m[2, 0] - m[1, 0] * m[2, 2]
        c02 = m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]
        inv_det = 1.0 / (m[0, 0] * c00 + m[0, 1] * c01 + m[0, 2] * c02)
        out[k, 0, 0] = c00 * inv_det
        out[k, 0, 1] = (m[0, 2] * m[2, 1] - m[0, 1] * m[2, 2]) * inv_det
        out[k, 0, 2] = (m[0, 1] * m[1, 2] - m[0, 2] * m[1, 1]) * inv_det
        out[k, 1, 0] = c01 * inv_det
        out[k, 1, 1] = (m[0, 0] * m[2, 2] - m[0, 2] * m[2, 0]) * inv_det
        out[k, 1, 2] = (m[0, 2] * m[1, 0] - m[0, 0] * m[1, 2]) * inv_det
        out[k, 2, 0] = c02 * inv_det
        out[k, 2, 1] = (m[0, 1] * m[2, 0] - m[0, 0] * m[2, 1]) * inv_det
        out[k, 2, 2] = (m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]) * inv_det
    return out
