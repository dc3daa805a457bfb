"""Force Jacobians for implicit integration, assembled into sparse matrices.

K ≈ −∂f/∂x and C = −∂f/∂v, both symmetric positive semi-definite so the implicit system
M + Δt·C + Δt²·K is SPD and conjugate gradients converge:

* membrane stretch: the Gauss–Newton term A·Σ cᵢ∇Eᵢ∇Eᵢᵀ plus the geometric term with the
  stress clamped to its positive part (a compressed triangle adds no negative stiffness);
* strain-rate damping: exactly A·Σ φᵢ∇Ėᵢ∇Ėᵢᵀ (the force is linear in v, and ∂Ė/∂v = ∂E/∂x);
* bending: k·∇θ∇θᵀ; springs: k·d̂d̂ᵀ + k·max(1 − l/|d|, 0)(I − d̂d̂ᵀ), dampers k_d·d̂d̂ᵀ.

:class:`SparsePattern` precomputes where every element block lands in one CSR matrix, so a
step only sums numbers (``np.bincount``) instead of rebuilding the sparsity.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..geometry import hinge_angle_gradients
from .kawabata import secant_hinge_stiffness, secant_membrane_stiffness
from .kernels import bending_jacobian_into, membrane_jacobian_into
from .membrane import membrane_gradients

__all__ = ["SparsePattern", "force_jacobians", "jacobian_data", "jacobian_blocks"]


def _block_indices(elements):
    """Row/column dof indices of every entry of the (3k × 3k) element blocks, shape (E, 3k, 3k)."""
    dof = (3 * elements[:, :, None] + np.arange(3)[None, None, :]).reshape(len(elements), -1)
    rows = np.repeat(dof[:, :, None], dof.shape[1], axis=2)
    cols = np.repeat(dof[:, None, :], dof.shape[1], axis=1)
    return rows, cols


class SparsePattern:
    """The CSR sparsity of a model's Jacobians and the scatter map of every element entry."""

    def __init__(self, model):
        n = 3 * model.vertex_count
        groups = [model.faces]
        if model.elastic == "springs":
            groups = [model.spring_vertices]
        if model.has_bending:
            groups.append(model.hinge_vertices)
        self.has_pairs = len(model.pair_vertices) > 0
        if self.has_pairs:
            groups.append(model.pair_vertices)
        rows, cols, sizes = [], [], []
        for g in groups:
            r, c = _block_indices(np.asarray(g))
            rows.append(r.reshape(-1))
            cols.append(c.reshape(-1))
            sizes.append(r.shape)
        diag = np.arange(n)
        rows.append(diag)
        cols.append(diag)
        r, c = np.concatenate(rows), np.concatenate(cols)
        key = r.astype(np.int64) * n + c
        uniq, self.scatter = np.unique(key, return_inverse=True)
        self.shape = (n, n)
        self.rows, self.cols = (uniq // n).astype(np.int32), (uniq % n).astype(np.int32)
        self.nnz = len(uniq)
        self.entry_count = len(key)
        self.diagonal_offset = len(key) - n  # the identity entries come last
        order_csr = np.lexsort((self.cols, self.rows))
        assert np.all(order_csr == np.arange(self.nnz))  # np.unique already sorts by (row, col)
        starts = np.cumsum([0] + [int(np.prod(s)) for s in sizes])
        self.positions = [
            self.scatter[a:b].reshape(s[0], -1).astype(np.int64) for a, b, s in zip(starts[:-1], starts[1:], sizes)
        ]
        """Per element group (faces or springs, then hinges): CSR slot of each block entry, (E, (3k)²)."""
        self.diagonal_slots = self.scatter[self.diagonal_offset :]
        """CSR slot of each diagonal entry (dof order)."""
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.rows, minlength=n))]).astype(np.int32)
        self._block_slots = None
        self._diag_block = None

    def _blocks_map(self):
        """CSR slot of every entry of the 3×3 block form (−1: structurally zero), built once."""
        if self._block_slots is None:
            n = self.shape[0]
            a = sp.csr_matrix((np.arange(1, self.nnz + 1, dtype=float), self.cols, self.indptr), shape=self.shape).tobsr(
                blocksize=(3, 3))
            a.sort_indices()
            self._block_slots = np.rint(a.data).astype(np.int64).reshape(-1) - 1
            self.block_indptr = a.indptr.astype(np.int32)
            self.block_cols = a.indices.astype(np.int32)
            assert len(self.block_indptr) == n // 3 + 1
        return self._block_slots

    def blocks(self, data) -> np.ndarray:
        """The stored values as 3×3 blocks (B, 3, 3) in the order of ``block_indptr``/``block_cols``."""
        slots = self._blocks_map()
        out = np.where(slots >= 0, np.concatenate([data, [0.0]])[slots], 0.0)
        return out.reshape(-1, 3, 3)

    def diagonal_blocks(self, blocks) -> np.ndarray:
        """(N, 3, 3) diagonal block of every vertex row."""
        self._blocks_map()
        if self._diag_block is None:
            rows = np.repeat(np.arange(len(self.block_indptr) - 1), np.diff(self.block_indptr))
            self._diag_block = np.flatnonzero(rows == self.block_cols)
            assert len(self._diag_block) == len(self.block_indptr) - 1
        return blocks[self._diag_block]

    def matrix(self, entries) -> sp.csr_matrix:
        """CSR matrix from the concatenated element entries (in pattern order, identity slot last)."""
        return self.csr(np.bincount(self.scatter, weights=entries, minlength=self.nnz))

    def csr(self, data) -> sp.csr_matrix:
        """CSR matrix with this pattern and the given stored values."""
        return sp.csr_matrix((data, self.cols, self.indptr), shape=self.shape)


def _membrane_blocks(model, x, coeff11, coeff22, coeff12, geometric):
    grads, weights, stress = membrane_gradients(model, x)
    a = model.face_rest_area
    c = np.stack([coeff11, coeff22, 2.0 * coeff12], axis=1) * a[:, None]
    blocks = np.einsum("fi,fia,fib->fab", c, grads, grads)
    if geometric:
        w, v = np.linalg.eigh(stress)
        s_pos = np.einsum("fij,fj,fkj->fik", v, np.maximum(w, 0.0), v)
        m3 = a[:, None, None] * np.einsum("fai,fij,fbj->fab", weights, s_pos, weights)  # (F, 3, 3)
        blocks += np.einsum("fab,ij->faibj", m3, np.eye(3)).reshape(-1, 9, 9)
    return blocks


def _spring_blocks(model, x, stiffness_part: bool):
    s = model.spring_vertices
    d = x[s[:, 0]] - x[s[:, 1]]
    length = np.linalg.norm(d, axis=1)
    u = d / np.maximum(length, 1e-300)[:, None]
    uu = u[:, :, None] * u[:, None, :]
    if stiffness_part:
        k = model.spring_stiffness
        geo = np.maximum(1.0 - model.spring_rest_length / np.maximum(length, 1e-300), 0.0)
        b3 = k[:, None, None] * (uu + geo[:, None, None] * (np.eye(3) - uu))
    else:
        b3 = model.spring_damping[:, None, None] * uu
    sign = np.array([[1.0, -1.0], [-1.0, 1.0]])
    return np.einsum("ab,fij->faibj", sign, b3).reshape(-1, 6, 6)


def jacobian_data(model, state, pattern: SparsePattern):
    """Stored values (in ``pattern``'s CSR order) of K = −∂f/∂x and C = −∂f/∂v."""
    if model.elastic == "springs":
        k, c = jacobian_blocks(model, state, pattern)
        return k.data, c.data
    kdata = np.zeros(pattern.nnz)
    cdata = np.zeros(pattern.nnz)
    curves = model.has_curves  # Kawabata: secant stiffness in the Newton step too
    membrane_jacobian_into(model, state.x, pattern.positions[0], kdata, cdata,
                           stiffness=secant_membrane_stiffness(model, state.x) if model.strain_dependent else None)
    if model.has_bending:
        bending_jacobian_into(model, state.x, pattern.positions[1], kdata,
                              stiffness=secant_hinge_stiffness(model, state.x) if curves else None)
    if pattern.has_pairs:
        _add_pair_blocks(model, pattern.positions[-1], kdata, cdata)
    return kdata, cdata


def _add_pair_blocks(model, positions, kdata, cdata):
    """K·[[I, −I], [−I, I]] and C·[[I, −I], [−I, I]] of the pair springs into CSR data."""
    block = np.einsum("ab,ij->aibj", np.array([[1.0, -1.0], [-1.0, 1.0]]), np.eye(3)).reshape(36)
    np.add.at(kdata, positions.reshape(-1), (model.pair_stiffness[:, None] * block).reshape(-1))
    np.add.at(cdata, positions.reshape(-1), (model.pair_damping[:, None] * block).reshape(-1))


def force_jacobians(model, state, pattern: SparsePattern):
    """(K, C): stiffness −∂f/∂x and damping −∂f/∂v as CSR matrices, shape (3N, 3N).

    The membrane and bending blocks are scattered straight into CSR storage by compiled kernels
    (:mod:`.kernels`); springs use the numpy blocks of this module. :func:`jacobian_blocks` gives
    the same matrices from numpy alone (the reference the kernels are tested against).
    """
    kdata, cdata = jacobian_data(model, state, pattern)
    return pattern.csr(kdata), pattern.csr(cdata)


def jacobian_blocks(model, state, pattern: SparsePattern):
    """(K, C) assembled from numpy element blocks (reference implementation)."""
    x = state.x
    n = 3 * model.vertex_count
    if model.elastic == "springs":
        k_parts = [_spring_blocks(model, x, True).reshape(-1)]
        c_parts = [_spring_blocks(model, x, False).reshape(-1)]
    else:
        k_parts = [_membrane_blocks(model, x, *secant_membrane_stiffness(model, x), True).reshape(-1)]
        c_parts = [
            _membrane_blocks(model, x, model.face_damping_warp, model.face_damping_weft, model.face_damping_shear, False).reshape(-1)
        ]
    if model.has_bending:
        g = hinge_angle_gradients(x, model.hinge_vertices).reshape(-1, 12)
        k_parts.append((model.hinge_stiffness[:, None, None] * g[:, :, None] * g[:, None, :]).reshape(-1))
        c_parts.append(np.zeros(len(g) * 144))
    zeros = np.zeros(n)
    k = pattern.matrix(np.concatenate(k_parts + [zeros]))
    c = pattern.matrix(np.concatenate(c_parts + [zeros]))
    return k, c
