"""The linear systems of split4's G1 conditions and their minimum-norm solutions.

Every twist is the minimum-norm change of its target that solves its vertex system
(:func:`_min_norm`, one pseudo-inverse per system size: :func:`_operator`): the ring cycles at the
mesh vertices (:func:`_cycle`), the four equations at an edge midpoint (:data:`_MIDPOINT`), the
C1 parallelogram rule at a face centre. Interior vertices of even valence ≥ 6 need whole
midpoints moved first (:func:`_even_vertex_shifts`, one sparse solve).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import spsolve

from ...errors import ConstructionError
from ...mesh import QuadTopology

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: systems per block in :func:`_min_norm`
_GROUPS = 32768
#: the four equations at an edge midpoint over its twists (LX, RX, LY, RY): ``G_LX + G_RX = A_X``,
#: ``G_LY + G_RY = A_Y``, ``G_LX + G_LY = 2 e_L``, ``G_RX + G_RY = 2 e_R``
_MIDPOINT = np.array([[1.0, 1, 0, 0], [0, 0, 1, 1], [1, 0, 1, 0], [0, 1, 0, 1]])


def _even_vertex_shifts(
    topology: QuadTopology, lam: FloatArray, curve: FloatArray, mu: FloatArray, v_pos: FloatArray
) -> tuple[IntArray, FloatArray]:
    """Midpoint shifts s_e (min-norm) so that every interior vertex of even valence n ≥ 6 satisfies
    ``Σ_j (−1)^j (P2_j + s_{e_j}) = Σ_j (−1)^j m_j t_j / (6 λ_v)``, ``t_j = 3 (P1_j − v)``.

    (P1, P2) of ring half-edge h from its origin are read from ``curve`` (E, 5, 3), and
    m = λ(M → origin) = ±μ_e. With the sign matrix A (vertices × edges), ``s = Aᵀ (A Aᵀ)⁻¹ r``: one
    sparse solve, block-diagonal over clusters of adjacent even vertices. Returns the moved edges
    and their shifts.
    """
    even = ~topology.is_boundary_vertex & (topology.valence >= 6) & (topology.valence % 2 == 0)
    vs = np.flatnonzero(even)
    if not vs.size:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3))
    counts = topology.face_count[vs]
    starts = topology.ring_offsets[vs]
    slot = np.repeat(starts - np.cumsum(np.r_[0, counts[:-1]]), counts) + np.arange(counts.sum())
    ring = topology.ring_halfedges[slot]
    row = np.repeat(np.arange(vs.size), counts)
    alternating = 1.0 - 2.0 * ((slot - topology.ring_offsets[vs][row]) % 2)
    origin = v_pos[vs][row]
    edge = topology.halfedge_edge[ring]
    canonical = topology.edge_halfedges[edge, 0] == ring
    p1, p2 = curve[edge, np.where(canonical, 0, 4)], curve[edge, np.where(canonical, 1, 3)]
    slope = np.where(canonical, mu[edge], -mu[edge])
    terms = alternating[:, None] * (
        slope[:, None] * 3.0 * (p1 - origin) / (6.0 * lam[vs][row, None]) - p2
    )
    residual = np.add.reduceat(terms, np.r_[0, np.cumsum(counts[:-1])])
    moved, column = np.unique(edge, return_inverse=True)
    a = csc_matrix((alternating, (row, column)), shape=(vs.size, moved.size))
    normal = (a @ a.T).tocsc()
    y = np.asarray(spsolve(normal, residual)).reshape(vs.size, 3)
    shift = np.asarray(a.T @ y)
    if not np.isfinite(shift).all() or np.abs(a @ shift - residual).max() > 1e-9 * (
        1.0 + np.abs(residual).max()
    ):
        raise ConstructionError(
            f"split4: the even-valence midpoint system of {vs.size} vertices (valence ≥ 6) is "
            "singular: a cluster of adjacent even-valence vertices has no neighbour outside it"
        )
    return moved, shift


def _operator(matrix: FloatArray) -> FloatArray:
    """``[I − B⁺B, B⁺]`` (n, n + m) of B (m, n): the min-norm change of a target τ onto ``B x = b``
    is this matrix times ``[τ; b]``."""
    inverse = np.linalg.pinv(matrix)
    return np.concatenate([np.eye(matrix.shape[1]) - inverse @ matrix, inverse], axis=1)


def _min_norm(matrix: FloatArray, rhs: FloatArray, target: FloatArray) -> FloatArray:
    """``τ + B⁺ (b − B τ) = [I − B⁺B, B⁺] [τ; b]`` for batches: target (g, n, 3), rhs (g, m, 3),
    B (m, n); one matrix product over all coordinates of the batch."""
    operator = _operator(matrix)
    out = np.empty(target.shape)
    for g0 in range(0, len(target), _GROUPS):  # in blocks of groups: the temporaries stay in cache
        g1 = g0 + _GROUPS
        stacked = np.concatenate([target[g0:g1], rhs[g0:g1]], axis=1).transpose(
            0, 2, 1
        )  # (g, 3, n + m)
        out[g0:g1] = (stacked @ operator.T).transpose(0, 2, 1)
    return out


def _cycle(n: int, closed: bool) -> FloatArray:
    """Equations ``F_{j−1} + F_j`` (rows j = 0..n−1 closed; j = 1..n−1 open) over n unknowns."""
    rows = np.arange(n) if closed else np.arange(1, n)
    matrix = np.zeros((len(rows), n))
    matrix[np.arange(len(rows)), rows] = 1.0
    matrix[np.arange(len(rows)), (rows - 1) % n] += 1.0
    return matrix
