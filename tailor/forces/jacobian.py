"""Force Jacobians for implicit integration, assembled into sparse matrices.

K ≈ −∂f/∂x and C = −∂f/∂v, both symmetric positive semi-definite so the implicit system
M + Δt·C + Δt²·K is SPD and conjugate gradients converge:

* membrane stretch: the Gauss–Newton term A·Σ cᵢ∇Eᵢ∇Eᵢᵀ plus the geometric term with the
  stress clamped to its positive part (a compressed triangle adds no negative stiffness);
* strain-rate damping: exactly A·Σ φᵢ∇Ėᵢ∇Ėᵢᵀ (the force is linear in v, and ∂Ė/∂v = ∂E/∂x);
* bending: k·∇θ∇θᵀ; springs: k·d̂d̂ᵀ + k·max(1 − l/|d|, 0)(I − d̂d̂ᵀ), dampers k_d·d̂d̂ᵀ.

:class:`SparsePattern` precomputes where every element block lands, once per topology, so a
step only sums numbers instead of rebuilding the sparsity. The implicit step takes
:func:`implicit_blocks` (Δt·C + Δt²·K straight into 3 × 3 vertex blocks, and K·v, by compiled
kernels over element colour classes); :func:`force_jacobians` gives K and C as CSR matrices and
:func:`jacobian_blocks` the same from numpy alone (the reference both are tested against).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..geometry import hinge_angle_gradients
from .kawabata import secant_hinge_stiffness, secant_membrane_stiffness
from .kernels import ELEMENT_CHUNK, bending_jacobian_into, bending_system_into, element_chunks, membrane_jacobian_into, membrane_system_into
from .membrane import membrane_gradients

__all__ = ["SparsePattern", "BlockPart", "force_jacobians", "jacobian_data", "jacobian_blocks", "implicit_blocks",
           "MIN_PART_VERTICES"]

MIN_PART_VERTICES = 256
"""Fewest vertices a :class:`BlockPart` is solved alone with; smaller runs join a neighbour's part."""


def _block_keys(groups, nv: int) -> np.ndarray:
    """Sorted keys i·nv + j of the 3×3 blocks of :class:`SparsePattern`: every vertex's own, and
    every two vertices of an element both ways. Found from each element's unordered pairs (3 a
    triangle, 6 a hinge) rather than its k² ordered ones, a third of the keys to sort."""
    parts = [np.arange(nv, dtype=np.int64) * (nv + 1)]
    for g in groups:
        a, b = np.triu_indices(g.shape[1], 1)
        pair = np.unique((np.minimum(g[:, a], g[:, b]) * nv + np.maximum(g[:, a], g[:, b])).reshape(-1))
        parts += [pair, (pair % nv) * nv + pair // nv]
    return np.unique(np.concatenate(parts))


@dataclass(frozen=True, slots=True)
class BlockPart:
    """Vertices ``lo:hi`` of a block-CSR matrix coupled to no vertex outside them: the rows' own
    block pointers (``bptr``, from 0) and columns (``bcol``, from ``lo``) over blocks ``first:last``."""

    lo: int
    hi: int
    bptr: np.ndarray
    bcol: np.ndarray
    first: int
    last: int


def block_parts(bptr, bcol, min_vertices: int = MIN_PART_VERTICES) -> list[BlockPart]:
    """The independent diagonal parts of a structurally symmetric block-CSR matrix: cut before every
    vertex ``i`` that no block of a row before it reaches (the column a row reaches farthest, its
    running maximum, is below ``i``), each part at least ``min_vertices`` long (the last joins the
    one before if shorter). An outfit's garments are one part each; a garment is one part."""
    nv = len(bptr) - 1
    if nv == 0:
        return []
    reach = np.maximum.accumulate(np.maximum.reduceat(bcol, bptr[:-1]) if len(bcol) else np.arange(nv))
    cuts, lo = [], 0
    for i in np.flatnonzero(reach[:-1] < np.arange(1, nv)) + 1:
        if i - lo >= min_vertices and nv - i >= min_vertices:
            cuts.append(int(i))
            lo = int(i)
    edges = [0, *cuts, nv]
    return [BlockPart(a, b, (bptr[a:b + 1] - bptr[a]).astype(bptr.dtype), (bcol[bptr[a]:bptr[b]] - a).astype(bcol.dtype),
                      int(bptr[a]), int(bptr[b])) for a, b in zip(edges[:-1], edges[1:])]


class SparsePattern:
    """The CSR sparsity of a model's Jacobians and the scatter map of every element entry.

    Built at the level of vertex pairs (one 3×3 block each, ~9× fewer keys to sort than dofs),
    so the same layout serves as scalar CSR (``indptr``, ``cols``) and as 3×3 block CSR
    (``block_indptr``, ``block_cols``): row 3i+a holds, for each neighbour j of vertex i in
    increasing order, the three entries (3i+a, 3j+b).
    """

    def __init__(self, model):
        nv = model.vertex_count
        groups = [np.asarray(model.faces if model.elastic != "springs" else model.spring_vertices, np.int64)]
        if model.has_bending:
            groups.append(np.asarray(model.hinge_vertices, np.int64))
        self.has_pairs = len(model.pair_vertices) > 0
        if self.has_pairs:
            groups.append(np.asarray(model.pair_vertices, np.int64))
        keys = _block_keys(groups, nv)
        self.shape = (3 * nv, 3 * nv)
        self.nnz = 9 * len(keys)
        self.block_rows = keys // nv
        """Row (vertex) of every 3×3 block, in :meth:`blocks` order."""
        self.block_cols = (keys % nv).astype(np.int32)
        self.block_indptr = np.concatenate([[0], np.cumsum(np.bincount(self.block_rows, minlength=nv))]).astype(np.int32)
        self._diag_block = np.searchsorted(keys, np.arange(nv, dtype=np.int64) * (nv + 1))
        index = np.int32 if len(keys) < 2**31 else np.int64
        self.element_blocks = [np.searchsorted(keys, (g[:, :, None] * nv + g[:, None, :]).reshape(-1)).astype(index).reshape(g.shape[0], g.shape[1], g.shape[1])
                               for g in groups]  # block of every vertex pair of every element
        """Per element group (faces or springs, then hinges, then pairs): block index of each of its
        vertex pairs, (E, k, k) (32-bit where they fit: the largest array of the pattern)."""
        self._groups = groups
        self._colors = [None] * len(groups)
        self._moving = [None] * len(groups)  # (still mask, its classes) last asked of colors_moving

    @cached_property
    def parts(self) -> list[BlockPart]:
        """The matrix's independent diagonal parts (:func:`block_parts`): garments not sewn together
        (an outfit's), each solved on its own (made on first use)."""
        return block_parts(self.block_indptr, self.block_cols)

    @cached_property
    def _block_slots(self) -> np.ndarray:
        """Scalar CSR slot of every entry of every block, (B·9,) in block order (row a, column b):
        row 3i+a holds, for each neighbour j of vertex i in increasing order, the entries (3i+a, 3j+b).
        Made on first use, as the rest of the scalar layout: the implicit step works on blocks."""
        start = self.block_indptr.astype(np.int64)
        deg = np.diff(start)
        rows = self.block_rows
        base = 9 * start[rows] + 3 * (np.arange(len(rows)) - start[rows])  # slot of entry (a=0, b=0) of each block
        stride = 3 * deg[rows]  # from one row of a block to the next
        a3 = np.arange(3)
        return (base[:, None, None] + a3[None, :, None] * stride[:, None, None] + a3[None, None, :]).reshape(-1)

    @cached_property
    def cols(self) -> np.ndarray:
        """Scalar CSR column of every stored entry."""
        cols = np.empty(self.nnz, np.int32)
        a3 = np.arange(3)
        cols[self._block_slots] = (3 * self.block_cols[:, None, None] + a3[None, None, :]).astype(np.int32).repeat(3, axis=1).reshape(-1)
        return cols

    @cached_property
    def indptr(self) -> np.ndarray:
        """Scalar CSR row pointers (three rows per vertex, each as long as its block row)."""
        start = self.block_indptr[:-1].astype(np.int64)
        deg = np.diff(self.block_indptr.astype(np.int64))
        a3 = np.arange(3)
        rows = 9 * np.repeat(start, 3) + np.tile(a3, len(start)) * np.repeat(3 * deg, 3)
        return np.append(rows, self.nnz).astype(np.int32)

    @cached_property
    def diagonal_slots(self) -> np.ndarray:
        """CSR slot of each diagonal entry (dof order)."""
        a3 = np.arange(3)
        return self._block_slots.reshape(-1, 3, 3)[self._diag_block][:, a3, a3].reshape(-1)

    @cached_property
    def positions(self) -> list:
        """Per element group: CSR slot of each entry of each element's (3k × 3k) block, (E, (3k)²).
        Made on first use: the implicit step assembles blocks and never needs them (the largest
        arrays of the pattern)."""
        slots = self._block_slots.reshape(-1, 3, 3)
        return [slots[p].transpose(0, 1, 3, 2, 4).reshape(len(p), -1).astype(np.int64) for p in self.element_blocks]

    @cached_property
    def scatter(self) -> np.ndarray:
        """CSR slot of every concatenated element entry, the diagonal identity slots last (:meth:`matrix`)."""
        return np.concatenate([pos.reshape(-1) for pos in self.positions] + [self.diagonal_slots])

    def colors(self, group: int):
        """(order, tasks, classes) of element group ``group`` in chunks of neighbours, coloured in classes
        whose chunks share no vertex (:func:`element_chunks`), made once."""
        if self._colors[group] is None:
            self._colors[group] = element_chunks(np.ascontiguousarray(self._groups[group], np.int64), self.shape[0] // 3,
                                                 ELEMENT_CHUNK)
        return self._colors[group]

    def colors_moving(self, group: int, still):
        """:meth:`colors` less the elements whose every vertex is ``still`` ((N,) bool: pinned and at
        rest, as an outfit's inner garments held while the next one sews): such an element adds
        nothing to K·v and only to blocks of pinned rows and columns, which the solve replaces by
        the identity, so leaving it out of the assembly changes nothing. Remembered for the last
        mask asked."""
        order, tasks, classes = self.colors(group)
        if not still.any():
            return order, tasks, classes
        last = self._moving[group]
        if last is None or not np.array_equal(last[0], still):
            keep = ~still[self._groups[group][order]].all(axis=1)
            counts = np.bincount(np.repeat(np.arange(len(tasks) - 1), np.diff(tasks))[keep], minlength=len(tasks) - 1)
            self._moving[group] = last = (still.copy(), (order[keep], np.concatenate([[0], np.cumsum(counts)]).astype(tasks.dtype),
                                                         classes))
        return last[1]

    def blocks(self, data) -> np.ndarray:
        """The stored values as 3×3 blocks (B, 3, 3) in the order of ``block_indptr``/``block_cols``."""
        return data[self._block_slots].reshape(-1, 3, 3)

    @property
    def diagonal_block_index(self) -> np.ndarray:
        """(N,) index, in :meth:`blocks` order, of every vertex's own block."""
        return self._diag_block

    def diagonal_blocks(self, blocks) -> np.ndarray:
        """(N, 3, 3) diagonal block of every vertex row."""
        return blocks[self._diag_block]

    def add_to_diagonal(self, blocks, values) -> None:
        """``blocks`` (from :meth:`blocks`) += ``values`` (N, 3, 3) on every vertex's diagonal block, in place."""
        blocks[self._diag_block] += values

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


def implicit_blocks(model, state, pattern: SparsePattern, dt: float):
    """(Δt·C + Δt²·K as 3×3 blocks (B, 3, 3) in ``pattern``'s block order, K·v (N, 3)).

    What an implicit step needs of the Jacobians, assembled straight into block form: faces and
    hinges by compiled kernels, one colour class of elements at a time in parallel (the sums in
    the same order on any thread count), seam pairs by numpy; Walker's springs through
    :func:`jacobian_data`. Equals that function's K and C to round-off (the order of the sums differs).
    """
    v = state.v
    if model.elastic == "springs":
        kdata, cdata = jacobian_data(model, state, pattern)
        return pattern.blocks(dt * cdata + (dt * dt) * kdata), (pattern.csr(kdata) @ v.reshape(-1)).reshape(-1, 3)
    blocks = np.zeros((len(pattern.block_cols), 3, 3))
    kv = np.zeros((model.vertex_count, 3))
    still = np.asarray(model.vertex_pinned) & ~v.any(axis=1)  # pinned at rest: their elements add nothing kept
    membrane_system_into(model, state, pattern.element_blocks[0], pattern.colors_moving(0, still), dt, blocks, kv,
                         stiffness=secant_membrane_stiffness(model, state.x) if model.strain_dependent else None)
    if model.has_bending:
        bending_system_into(model, state, pattern.element_blocks[1], pattern.colors_moving(1, still), dt, blocks, kv,
                            stiffness=secant_hinge_stiffness(model, state.x) if model.has_curves else None)
    if pattern.has_pairs:
        i, j = np.asarray(model.pair_vertices).T
        k, c = np.asarray(model.pair_stiffness, float), np.asarray(model.pair_damping, float)
        slots = pattern.element_blocks[-1]  # (P, 2, 2)
        eye = np.eye(3)
        w = (dt * c + dt * dt * k)[:, None, None] * eye
        for a, b, sign in ((0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 1.0)):
            np.add.at(blocks, slots[:, a, b], sign * w)
        pull = k[:, None] * (v[i] - v[j])
        np.add.at(kv, i, pull)
        np.add.at(kv, j, -pull)
    return blocks, kv


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
