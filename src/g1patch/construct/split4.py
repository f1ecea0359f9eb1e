"""Exact G1 with polynomial patches only: the 2×2-split bicubic network (polynomial-g1.md).

Every quad f is split at its edge midpoints M and its centre C into four bicubic Bézier
sub-patches; sub-patch ``4 f + k`` sits at corner k. Inside the quad the four pieces join C1,
so each quad is one bicubic B-spline patch with knots ``[0,0,0,0,½,½,1,1,1,1]`` in u and v
(:func:`bspline_nets`). On every refined edge (half mesh edge V–M or seam M–C) from S to E with
sub-patches P, Q on either side the symmetric G1 form

    D_P(t) + D_Q(t) = Φ(t) c'(t),   Φ(0) = λ_S,  Φ(1) = −λ_E                          (G1)

holds, λ being the star coefficient of the end vertex for that edge (``t_left + t_right = λ t``).
In Bézier coefficients (``δ_k`` cross row − curve point, ``d_k`` curve differences) it is

    δP_0 + δQ_0 = λ_S d_0,   δP_1 + δQ_1 = (2 Φ0 d_1 + Φ1 d_0)/3,   and the mirror at E,

so G1 is a star plus a twist system at every refined vertex:

* original vertex v: a star ``t_{j−1} + t_{j+1} = λ_j t_j`` per slot (λ_j = 2 c_j), half-edge points
  ``P1 = v + T/6``; twists ``F_{j−1} + F_j = R_j`` with
  ``R_j = 2 P1_j + (2 λ_j (P2_j − P1_j) − m_j (P1_j − v))/3``, ``m_j = λ(M_j → v)``. Where that
  twist system has compatibility conditions (even valence: valence 4 and ≥ 6 below) the star is
  regular (one λ_v); on the boundary and at odd valence any fan whose sectors have equal areas
  will do (the re-assembly of a Gregory network takes the nearest to its fan,
  :func:`_equal_area_fans`; a build the regular star);
* midpoint M of edge X → Y: sheared star ``t_L + t_R = μ t_X`` (μ = λ(M → X), λ(M → Y) = −μ),
  compatible iff ``D (5 μ + c_X − c_Y) = 2 μ (P1 − P5)`` for ``D = P2 − P4`` (:func:`_edge_curves`);
* centre C: a plain cross (λ = 0), so every seam is C1.

Even-valence twist cycles are singular: at valence 4 they need equal λ from opposite ring
edges, so μ is carried along grid lines (:func:`_chain_shears`); at even valence ≥ 6 they need
``Σ_j (−1)^j P2_j = Σ_j (−1)^j m_j t_j / (6 λ_v)``, met by moving whole midpoints
(:func:`_even_vertex_shifts`). Every twist is the minimum-norm change of its target (below)
that solves its vertex system (a pseudo-inverse per system size). Work is done in centred,
unit-scaled coordinates and mapped back.

Shape: the assembly moves the targets only as far as G1 requires (DESIGN §1). Each face's targets
are one bicubic (corners, slot tangents, :attr:`~g1patch.targets.Targets.corner_interior`,
:func:`target_nets`), subdivided at ½ into a 7×7 net (or a ``guide`` net instead). The free
choices take that net's *detail over what its boundary predicts*, added to what the split curves
predict (:data:`_QUANTITIES`): the centre ``ΣM/2 − ΣV/4 + (C° − ΣM°/2 + ΣV/4)``, the cross arms
over ``(M_k − M_{k+2})/6``, the seam tangents at M over ``C − M`` (their star gap ``t_L + t_R − μ
t_X`` split equally), and every twist target the parallelogram of its three neighbours plus the
net's twist offset. So where the star, the shear or an even-valence shift moves a curve point, the
interior moves with it and keeps the targets' shape; where the split curves are the targets' own (a
C1 bicubic B-spline with μ = 0: a regular torus under ``limit``) the targets are reproduced, the
min-norm twist changes vanish and each quad is one bicubic. The star length safeguard stays
everywhere: a star longer than it allows (B-spline tangents on a strongly graded cage, a 1 : 4 box)
is shrunk, and a face with a shrunk corner takes the net's detail scaled by the smallest factor (its
curves are that much shorter than the net's).

From :data:`KERNEL_FACES` faces on, the stars, the grid-line shears, the assembly and the network's
connectivity run in numba kernels (:func:`_compiled_patches`: the curves edge by edge, the net's
quantities and the centre face by face, the midpoint stars and twists edge by edge, the ring twists
vertex by vertex, the centre twists face by face, each writing straight into the controls; ranges
side by side, :func:`~g1patch.kernels.in_chunks`), so a large build makes no (4F, ·, 3) temporaries.
The NumPy code is the reference: the same formulas, batched; the two agree to rounding
(tests/test_split4_kernels.py: points within 16 ε · max|x|).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix, csc_matrix
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import spsolve

from ..errors import ConstructionError, InputError
from ..frame import Frame
from ..mesh import QuadMesh, QuadTopology
from ..network import PatchNetwork
from ..patches import PatchSet
from ..targets import Targets, halfedge_slots

__all__ = [
    "BSPLINE_KNOTS",
    "STAR_LENGTH_LIMIT",
    "FanWalk",
    "SplitStar",
    "bspline_nets",
    "fan_walk",
    "macro_nets",
    "split4_network_from_parts",
    "split4_network_from_targets",
    "split4_patches",
    "split4_provenance",
    "split4_star",
    "target_nets",
]

#: knots of each quad's B-spline patch, in u and in v
BSPLINE_KNOTS = np.array([0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0])

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# Frame of corner k: point (p, q) of the 7×7 macro net, p along edge k, q back along edge k − 1.
# _LOCAL[k, p, q] = (i, j) in sub-patch k's own 4×4 Bézier net, for p, q ∈ 0..3.
_P, _Q = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
_LOCAL = np.stack(
    [
        np.stack([_P, _Q], -1),
        np.stack([3 - _Q, _P], -1),
        np.stack([3 - _P, 3 - _Q], -1),
        np.stack([_Q, 3 - _P], -1),
    ]
)
_SUB_ORIGIN = np.array(
    [[0, 0], [3, 0], [3, 3], [0, 3]]
)  # (s, t)·3: where sub-patch k sits in the 7×7 net


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.einsum("...d,...d->...", a, b)


def _chain_shears(
    topology: QuadTopology, ends: FloatArray, *, compiled: bool = False
) -> FloatArray:
    """μ_e = λ(M_e → X_e) per edge, constant in size and alternating in sign along grid lines.

    Nodes ``2e + s`` are the ends of interior edge e (s = 0 at X, 1 at Y) and carry
    λ(M_e → that end). A node pair inside an edge has opposite λ; the two nodes of a grid line at
    an interior valence-4 vertex (ring edges j and j + 2) have equal λ. Signs come from the
    connected components of the signed double cover (copy n carries +, copy n + 2E carries −; an
    equal link joins like copies, an opposite link unlike ones), which also labels the lines in
    linear time. The size is set at a line's dominant end, the end with the largest
    ``|c_end − c_next|``, to λ = −(c_end − c_next), making δ = ½ there and δ ∈ [⅓, ½] everywhere;
    ``ends`` (E, 2) holds each edge's c at X and at Y (:func:`edge_end_cosines`).
    Closed lines (all valence 4) get μ = 0. ``compiled``: by walking the lines
    (:func:`_chain_kernel`, the same values bit for bit).
    """
    n_edges = topology.n_edges
    nodes = 2 * n_edges
    interior = ~topology.is_boundary_edge
    through = ~topology.is_boundary_vertex & (topology.valence == 4)
    h = topology.edge_halfedges[:, 0]
    x_of, y_of = topology.origin(h), topology.target(h)
    node_cosine = np.ascontiguousarray(ends, dtype=np.float64).reshape(
        -1
    )  # c of node 2e + s at its own end
    if compiled:
        from ..kernels import jit_kernel

        lam = np.zeros(nodes)
        jit_kernel(_chain_kernel)(
            node_cosine,
            x_of,
            y_of,
            interior,
            through,
            topology.ring_offsets,
            topology.ring_halfedges,
            topology.halfedge_edge,
            topology.edge_halfedges,
            lam,
        )
        return lam[0::2]
    ring = topology.ring_halfedges
    ring_edge = topology.halfedge_edge[ring]
    ring_node = 2 * ring_edge + (topology.edge_halfedges[ring_edge, 0] != ring)
    at_through = ring_node.reshape(-1)[np.repeat(through, topology.face_count)].reshape(-1, 4)
    same = np.concatenate([at_through[:, [0, 2]], at_through[:, [1, 3]]])
    inner = np.flatnonzero(interior)
    flip = np.stack([2 * inner, 2 * inner + 1], axis=1)
    rows = np.concatenate([same[:, 0], same[:, 0] + nodes, flip[:, 0], flip[:, 0] + nodes])
    cols = np.concatenate([same[:, 1], same[:, 1] + nodes, flip[:, 1] + nodes, flip[:, 1]])
    graph = coo_matrix(
        (np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(2 * nodes, 2 * nodes)
    )
    _, cover = connected_components(graph, directed=False)
    chain = np.minimum(cover[:nodes], cover[nodes:])

    vertex = np.stack([x_of, y_of], axis=1).reshape(-1)  # vertex of node 2e + s
    ends = np.flatnonzero(np.repeat(interior, 2) & ~through[vertex])
    gap = node_cosine[ends] - node_cosine[ends ^ 1]
    order = np.lexsort((ends, -np.abs(gap), chain[ends]))
    _, first = np.unique(chain[ends[order]], return_index=True)
    dominant = ends[order[first]]
    value = np.zeros(nodes)
    head_of_chain = np.full(nodes, -1, dtype=np.int64)
    head_of_chain[chain[dominant]] = dominant
    value[dominant] = -gap[order[first]]
    head = head_of_chain[chain]
    on_path = head >= 0
    anchor = np.where(on_path, head, 0)
    sign = np.where(cover[:nodes] == cover[anchor], 1.0, -1.0)
    lam = np.where(on_path, sign * value[anchor], 0.0)
    return lam[0::2]


def _edge_curves(
    x: FloatArray,
    y: FloatArray,
    t_xy: FloatArray,
    t_yx: FloatArray,
    mu: FloatArray,
    c_x: FloatArray,
    c_y: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Edge points ``(P1, P2, M, P4, P5)`` of each edge X → Y.

    The full cubic ``X, X + T_XY/3, Y + T_YX/3, Y`` is halved at its de Casteljau midpoint M,
    ``P1 = X + T_XY/6``, ``P5 = Y + T_YX/6``; then ``P2 = M + D/2``, ``P4 = M − D/2`` with
    ``D = δ (P1 − P5)``, ``δ = 2 μ / (5 μ + c_X − c_Y)`` (½ where μ = 0, the plain halving).
    """
    p1 = x + t_xy / 6.0
    p5 = y + t_yx / 6.0
    m = 0.5 * (x + y) + (t_xy + t_yx) / 8.0
    sheared = mu != 0.0
    delta = np.full(len(mu), 0.5)
    delta[sheared] = 2.0 * mu[sheared] / (5.0 * mu[sheared] + c_x[sheared] - c_y[sheared])
    half = 0.5 * delta[:, None] * (p1 - p5)
    return p1, m + half, m, m - half, p5


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
            "singular: "
            "a cluster of adjacent even-valence vertices has no neighbour outside it"
        )
    return moved, shift


_GROUPS = 32768  # systems per block in _min_norm
# : faces from which :func:`split4_patches` runs its numba kernels (below, loading them costs more
# than they save)
KERNEL_FACES = 20_000


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


_MIDPOINT = np.array([[1.0, 1, 0, 0], [0, 0, 1, 1], [1, 0, 1, 0], [0, 1, 0, 1]])  # (LX, RX, LY, RY)

# de Casteljau halving of a cubic at ½: the 7 × 4 matrix from Bézier points to the two halves'
_HALVE = (
    np.array(
        [
            [8.0, 0, 0, 0],
            [4, 4, 0, 0],
            [2, 4, 2, 0],
            [1, 3, 3, 1],
            [0, 2, 4, 2],
            [0, 0, 4, 4],
            [0, 0, 0, 8],
        ]
    )
    / 8.0
)
# What the assembly takes over from a face's macro net (the targets' bicubic subdivided at ½, or a
# guide), per half-edge h = 4f + k in the frame of corner k (points (p, q) of :func:`_macro_index`),
# each as the net's detail over what its own boundary predicts, so that where G1 moves a curve
# point the interior moves with it:
# * the centre over the bilinear Coons centre ``ΣM/2 − ΣV/4``: ``(3,3) − 2 (3,0) + (0,0)`` (its mean
# over k);
# * the cross arm ``b_k − C`` over ``(M_k − M_{k+2})/6``: ``(3,2) − (3,0)/3`` (taken as ``(a_k −
# a_{k+2})/2``);
# * the seam tangent ``3 (e − M)`` at M_k into the face over ``C − M``: ``3 (3,1) − 2 (3,0) −
# (3,3)``;
# * the twist offsets, each twist point minus the parallelogram of its three neighbours, at
#   MID[k] (2,1), MID[k−1] (1,2), C (2,2) and V (1,1).
_CENTRE, _CROSS, _SEAM, _TWIST_MID, _TWIST_PREV, _TWIST_CENTRE, _TWIST_VERTEX = range(7)
_QUANTITIES: tuple[dict[tuple[int, int], float], ...] = (
    {(3, 3): 1.0, (3, 0): -2.0, (0, 0): 1.0},
    {(3, 2): 1.0, (3, 0): -1.0 / 3.0},
    {(3, 1): 3.0, (3, 0): -2.0, (3, 3): -1.0},
    {(2, 1): 1.0, (2, 0): -1.0, (3, 1): -1.0, (3, 0): 1.0},
    {(1, 2): 1.0, (0, 2): -1.0, (1, 3): -1.0, (0, 3): 1.0},
    {(2, 2): 1.0, (3, 2): -1.0, (2, 3): -1.0, (3, 3): 1.0},
    {(1, 1): 1.0, (1, 0): -1.0, (0, 1): -1.0, (0, 0): 1.0},
)


def _macro_index(k: int, p: int, q: int) -> tuple[int, int]:
    """Index (i, j) in the 7×7 macro net of point (p, q) in the frame of corner k (as
    :data:`_LOCAL`, on 0..6)."""
    return [(p, q), (6 - q, p), (6 - p, 6 - q), (q, 6 - p)][k]


def _quantity_weights() -> FloatArray:
    """[k, quantity, 7 i + j]: weights of :data:`_QUANTITIES` over the 7×7 macro net, frame of
    corner k."""
    weights = np.zeros((4, len(_QUANTITIES), 49))
    for k in range(4):
        for c, terms in enumerate(_QUANTITIES):
            for (p, q), weight in terms.items():
                i, j = _macro_index(k, p, q)
                weights[k, c, 7 * i + j] += weight
    return weights


#: [k, quantity, 7 i + j] over the macro net and [k, quantity, 4 i + j] over a bicubic's 4×4 net
#: (its de Casteljau halves at ½ in u and v)
_MACRO_WEIGHTS = _quantity_weights()
_NET_WEIGHTS = _MACRO_WEIGHTS @ np.kron(_HALVE, _HALVE)


def target_nets(targets: Targets) -> FloatArray:
    """The (F, 4, 4, 3) Bézier nets of the targets' own bicubic per face: corners, edge points
    ``x + t/3`` from the slot tangents, interior points :attr:`Targets.corner_interior`
    (``net[i, j]``, i along edge 0, j along edge 3 reversed)."""
    from ..gregory import INTERIOR_INDEX

    topology = targets.topology
    slot_out, slot_in = halfedge_slots(topology)
    h = 4 * np.arange(topology.n_faces)[:, None] + np.arange(4)
    corner = targets.positions[topology.faces]
    net = np.empty((topology.n_faces, 4, 4, 3))
    net[:, [0, 3, 3, 0], [0, 0, 3, 3]] = corner
    net[:, [1, 3, 2, 0], [0, 1, 3, 2]] = (
        corner + targets.tangents[slot_out[h]] / 3.0
    )  # edge k, next to corner k
    net[:, [2, 3, 1, 0], [0, 2, 3, 1]] = (
        np.roll(corner, -1, axis=1) + targets.tangents[slot_in[h]] / 3.0
    )  # next to k + 1
    net[:, INTERIOR_INDEX[:, 0], INTERIOR_INDEX[:, 1]] = targets.corner_interior
    return net


def _own_quantities(targets: Targets, guide: FloatArray | None) -> FloatArray:
    """Per half-edge h = 4f + k the (4F, 7, 3) :data:`_QUANTITIES` of face f's macro net: the
    ``guide`` (F, 7, 7, 3), or the targets' bicubic (:func:`target_nets`) subdivided at ½."""
    nets, weights = (
        (target_nets(targets).reshape(-1, 16, 3), _NET_WEIGHTS)
        if guide is None
        else (guide.reshape(-1, 49, 3), _MACRO_WEIGHTS)
    )
    return np.matmul(weights.reshape(-1, weights.shape[-1]), nets).reshape(
        -1, len(_QUANTITIES), 3
    )  # (F, 4·7, 3)


# Sources of the assembly, per half-edge h = 4f + k: 0 V, 1..7 the points of _assemble's
# ``points`` (P1, P2 and M from the origin, P1 and P2 from the target, the seam point into f, b),
# 8 C, 9..12 the twists at V, MID[k], MID[k−1], C. _FRAME[p, q] = (source, from prev(h)).
_FRAME = {
    (0, 0): (0, False),
    (1, 0): (1, False),
    (2, 0): (2, False),
    (3, 0): (3, False),
    (0, 1): (4, True),
    (0, 2): (5, True),
    (0, 3): (3, True),
    (3, 1): (6, False),
    (3, 2): (7, False),
    (3, 3): (8, False),
    (1, 3): (6, True),
    (2, 3): (7, True),
    (1, 1): (9, False),
    (2, 1): (10, False),
    (1, 2): (11, False),
    (2, 2): (12, False),
}
_N_SOURCES = 13
_PICK = np.empty((4, 4, 4), dtype=np.int64)  # [k, i, j] → row (corner kk) · 13 + source
for (_p, _q), (_s, _from_prev) in _FRAME.items():
    for _k in range(4):
        _PICK[_k, _LOCAL[_k, _p, _q, 0], _LOCAL[_k, _p, _q, 1]] = (
            (_k - _from_prev) % 4
        ) * _N_SOURCES + _s
_GATHER = (3 * _PICK.reshape(-1, 1) + np.arange(3)).reshape(-1)  # per coordinate: 8-byte copies
_BLOCK = 1024  # faces per assembly block: sources and output stay in cache


def _assemble(
    points: tuple[FloatArray, ...],
    centres: FloatArray,
    twist: FloatArray,
    corners: FloatArray,
    scale: float,
    centre: FloatArray,
) -> FloatArray:
    """The (F, 4, 4, 4, 3) sub-patch controls from per-half-edge sources, in blocks of faces:
    every point ``x · scale + centre`` except the corners at mesh vertices, which are
    ``corners``."""
    n_faces = len(centres)
    control = np.empty((n_faces, 4, 4, 4, 3))
    flat = control.reshape(n_faces, 192)
    sources = np.empty((_BLOCK, 4, _N_SOURCES, 3))
    for f0 in range(0, n_faces, _BLOCK):
        f1 = min(f0 + _BLOCK, n_faces)
        nb, h0, h1 = f1 - f0, 4 * f0, 4 * f1
        block = sources[:nb]
        for s, values in enumerate(points, start=1):
            block[:, :, s] = values[h0:h1].reshape(nb, 4, 3)
        block[:, :, 8] = centres[f0:f1, None]
        block[:, :, 9:] = twist[h0:h1].reshape(nb, 4, 4, 3)
        block[:, :, 1:] *= scale
        block[:, :, 1:] += centre
        block[:, :, 0] = corners[f0:f1]
        # mode "wrap": indices are in range; the default "raise" buffers ``out`` on every call
        np.take(block.reshape(nb, 12 * _N_SOURCES), _GATHER, axis=1, out=flat[f0:f1], mode="wrap")
    return control


#: no star tangent may exceed this multiple of its own target tangent's length: a regular star
#: fitted to an irregular fan gives a short edge opposite a long one a tangent several times its
#: length, and its boundary cubic then overshoots the neighbour (shape-diagnosis.md cause 1); nor
#: of the circle-aware length of its edge: a target fan that is itself a regular star (the legacy
#: rule) gives the short edge at a box corner a tangent several chords long, and the cubic loops
STAR_LENGTH_LIMIT = 1.5


class SplitStar(NamedTuple):
    """The stars of :func:`split4_star`: tangents per ring slot (S, 3); per slot j the half ``c_j``
    of its star coefficient, ``t_{j−1} + t_{j+1} = 2 c_j t_j`` (S,) (a regular star's slots all have
    the cosine of its angle step); the vertices whose fan was refitted to spread directions
    (``refitted``: a real fallback), those whose star the length safeguard scaled down (``shrunk``)
    and the scale factor (≤ 1) per vertex."""

    star: FloatArray
    cosine: FloatArray
    refitted: NDArray[np.bool_]
    shrunk: NDArray[np.bool_]
    factor: FloatArray


def _per_slot(topology: QuadTopology, values: FloatArray) -> FloatArray:
    """A value per vertex repeated on each of its ring slots (S,)."""
    return np.repeat(values, np.diff(topology.neighbor_offsets))


def edge_end_cosines(topology: QuadTopology, cosine: FloatArray) -> FloatArray:
    """(E, 2): the star's ``c`` (:class:`SplitStar`, per slot) of each edge at X and at Y (its first
    half-edge X → Y)."""
    slot_out, slot_in = halfedge_slots(topology)
    h = topology.edge_halfedges[:, 0]
    return np.stack([cosine[slot_out[h]], cosine[slot_in[h]]], axis=1)


def split4_star(
    targets: Targets, *, compiled: bool | None = None, equal_sectors: bool = False
) -> SplitStar:
    """The stars split4 needs, fitted to the target fans: the regular star (at even interior
    valence the twist systems are solvable only for affine-regular stars) ``t_j = a cos θ_j + b sin
    θ_j``, ``c_v = cos`` of the angle step. With ``equal_sectors``, on the boundary and at odd
    valence the nearest fan of equal sectors instead (:func:`_equal_area_fans`): for reproducing a
    surface whose fans are given (a Gregory network's, :mod:`~g1patch.construct.polynomial`); a
    build keeps the regular stars, which are fairer where the targets' angles are uneven (a genus-2
    cage's odd vertices: turn p99 5.2° against 6.4°) and closer to the Catmull–Clark limit (Spot,
    limit: 3.8e-4 of the diagonal against 5.0e-4). A star that does not turn counter-clockwise is
    refitted to evenly spread target directions (a fallback). Length safeguard: each vertex's star
    is scaled down uniformly (it stays regular) until no tangent is longer than
    :data:`STAR_LENGTH_LIMIT` × the shorter of its target's and the circle-aware Hermite length of
    its edge (``2|d|²/(|d| + |P d|)``, P the projection onto the tangent plane: what the interpolate
    rule's tangents are). ``compiled``: vertex by vertex in :func:`_star_kernel` (ranges side by
    side), default from :data:`KERNEL_FACES` faces on; where a fan needs the refit, the NumPy
    reference.
    """
    from ..targets.interpolate import fit_regular_star, slot_vertices, spread_fan

    topology = targets.topology
    wanted = targets.tangents
    if (topology.n_faces >= KERNEL_FACES) if compiled is None else compiled:
        from ..kernels import in_chunks, jit_kernel

        star = np.empty(wanted.shape)
        valid = np.empty(topology.n_vertices, dtype=bool)
        factor = np.empty(topology.n_vertices)
        kernel = jit_kernel(_star_kernel)
        arrays = [
            np.ascontiguousarray(a, dtype=np.float64)
            for a in (targets.normals, wanted, targets.positions)
        ]
        in_chunks(
            lambda lo, hi: kernel(
                *arrays,
                topology.neighbor_offsets,
                topology.neighbors,
                topology.face_count,
                topology.valence,
                topology.is_boundary_vertex,
                STAR_LENGTH_LIMIT,
                star,
                valid,
                factor,
                lo,
                hi,
            ),
            topology.n_vertices,
        )
        if valid.all():
            step = np.where(
                topology.is_boundary_vertex,
                np.pi / topology.face_count,
                2.0 * np.pi / topology.valence,
            )
            stars = _rim_stars(
                targets,
                SplitStar(star, _per_slot(topology, np.cos(step)), ~valid, factor < 1.0, factor),
            )
            return _equal_area_fans(targets, stars) if equal_sectors else stars
    star, cosine, valid = fit_regular_star(topology, targets.normals, wanted)
    if not valid.all():
        chord = np.linalg.norm(wanted, axis=1)
        wanted = spread_fan(topology, targets.normals, wanted, chord, np.flatnonzero(~valid))
        star, cosine, _ = fit_regular_star(topology, targets.normals, wanted)
    slot_vertex = slot_vertices(topology)
    shrink = _length_shrink(
        targets, star, wanted, np.arange(len(star)), slot_vertex, slot_vertex, topology.n_vertices
    )
    star *= shrink[slot_vertex, None]
    stars = _rim_stars(targets, SplitStar(star, cosine[slot_vertex], ~valid, shrink < 1.0, shrink))
    return _equal_area_fans(targets, stars) if equal_sectors else stars


def _length_shrink(
    targets: Targets,
    star: FloatArray,
    wanted: FloatArray,
    slots: IntArray,
    vertex: IntArray,
    owner: IntArray,
    count: int,
) -> FloatArray:
    """:func:`split4_star`'s length safeguard: per owner (``count`` of them) ``min(1, 1 / max_j
    |t_j| / allowed_j)`` over its ``slots`` at their ``vertex`` (star rows ``t_j``, target rows
    ``wanted``), ``allowed = limit · min(|s|, 2|d|²/(|d| + |P d|))``."""
    topology = targets.topology
    edge = targets.positions[topology.neighbors[slots]] - targets.positions[vertex]
    normal = targets.normals[vertex]
    chord = np.linalg.norm(edge, axis=1)
    in_plane = np.linalg.norm(edge - _dot(edge, normal)[:, None] * normal, axis=1)
    arc = (
        2.0 * chord**2 / np.where(chord > 0, chord + in_plane, 1.0)
    )  # the circle-aware Hermite length
    allowed = STAR_LENGTH_LIMIT * np.minimum(np.linalg.norm(wanted, axis=1), arc)
    ratio = np.linalg.norm(star, axis=1) / np.where(allowed > 0, allowed, np.inf)
    worst = np.zeros(count)
    np.maximum.at(worst, owner, ratio)
    return np.minimum(1.0, 1.0 / np.where(worst > 0, worst, 1.0))


class FanWalk(NamedTuple):
    """The k + 1 slots of each of some boundary fans in ring order: per slot its fan (``owner``),
    its place in the fan (``j``), its slot index, its target tangent; per fan the total turn ``Φ``
    from the first slot to the last about the vertex normal (the sum of the turns between
    consecutive slots, ``atan2(n·(t_{j−1} × t_j), t_{j−1}·t_j)``)."""

    owner: IntArray
    j: IntArray
    slot: IntArray
    tangent: FloatArray
    turn: FloatArray


def fan_walk(targets: Targets, vertices: IntArray) -> FanWalk:
    """:class:`FanWalk` of the fans of ``vertices`` (boundary vertices, k = face count slots +
    1)."""
    topology = targets.topology
    k = topology.face_count[vertices]
    owner = np.repeat(np.arange(vertices.size), k + 1)
    j = np.arange(owner.size) - np.repeat(np.cumsum(k + 1) - (k + 1), k + 1)
    slot = topology.neighbor_offsets[vertices][owner] + j
    t = targets.tangents[slot]
    previous = targets.tangents[np.where(j > 0, slot - 1, slot)]
    normal = targets.normals[vertices][owner]
    turn = np.arctan2(_dot(np.cross(previous, t), normal), _dot(previous, t))
    return FanWalk(owner, j, slot, t, np.bincount(owner, turn, minlength=vertices.size))


#: a boundary fan turning by at least this (and at most 2π minus it) gets a star of its own turn
#: (:func:`_rim_stars`); below :data:`_RIM_TURN_NONE` one straight through, blended between
_RIM_TURN_FULL = np.radians(60.0)
_RIM_TURN_NONE = np.radians(30.0)


def _rim_stars(targets: Targets, base: SplitStar) -> SplitStar:
    """``base`` with the stars of the boundary vertices with k ≥ 2 faces fitted to the turn of their
    own fan: ``Φ`` the fan's turn from its first rim slot to its last about the normal (the sum of
    the turns between consecutive slots), step ``θ = Φ/k`` (π/k in ``base``: the rim straight
    through), ``[a b]`` by least squares over the k + 1 slots, ``t_j = a cos jθ + b sin jθ`` (the
    2 × 2 Gram matrix, no longer diagonal), ``c_v = cos θ``, the same length safeguard. A rim that
    turns at the vertex (a boundary corner of a coarse cage: the interpolate rule keeps it) keeps
    its direction: fitted to a straight star its rim tangents turned by up to 30°, and the CAD
    surface of catmark_xord_boundary lay 1.3e-2 of the diagonal off the Gregory one (now 1.8e-3).
    A fan turning by less than :data:`_RIM_TURN_FULL` (or more than 2π minus it) fits a turn
    blended towards π, ``w Φ + (1 − w) π``, w the smoothstep of ``min(Φ, 2π − Φ)`` from
    :data:`_RIM_TURN_NONE` to :data:`_RIM_TURN_FULL`: the sliver faces of a zigzag rim (the flat
    360-valent fan's spokes, Φ ≈ 1°) folded with a star that thin. Where Φ is π this is ``base``'s
    fit; a fan that does not turn once forward (Φ ∉ (0, 2π)), a refitted one, or a star that would
    not turn counter-clockwise keeps ``base``."""
    topology = targets.topology
    rims = np.flatnonzero(topology.is_boundary_vertex & (topology.face_count >= 2) & ~base.refitted)
    if not rims.size:
        return base
    k = topology.face_count[rims]
    owner, j, slot, t, own = fan_walk(targets, rims)
    narrow = np.clip(
        (np.minimum(own, 2.0 * np.pi - own) - _RIM_TURN_NONE) / (_RIM_TURN_FULL - _RIM_TURN_NONE),
        0.0,
        1.0,
    )
    weight = narrow * narrow * (3.0 - 2.0 * narrow)
    total = weight * own + (1.0 - weight) * np.pi
    theta = j * (total / k)[owner]
    c, s = np.cos(theta), np.sin(theta)
    cc, cs, ss = (np.bincount(owner, w, minlength=rims.size) for w in (c * c, c * s, s * s))
    moment_c = np.stack(
        [np.bincount(owner, c * t[:, d], minlength=rims.size) for d in range(3)], axis=1
    )
    moment_s = np.stack(
        [np.bincount(owner, s * t[:, d], minlength=rims.size) for d in range(3)], axis=1
    )
    det = cc * ss - cs * cs
    safe = np.where(det > 0, det, 1.0)[:, None]
    a = (ss[:, None] * moment_c - cs[:, None] * moment_s) / safe
    b = (cc[:, None] * moment_s - cs[:, None] * moment_c) / safe
    area = _dot(np.cross(a, b), targets.normals[rims])
    good = (own > 0) & (own < 2.0 * np.pi) & (det > 0) & (area > 1e-12 * (_dot(a, a) + _dot(b, b)))
    fitted = c[:, None] * a[owner] + s[:, None] * b[owner]
    shrink = _length_shrink(targets, fitted, t, slot, rims[owner], owner, rims.size)
    keep = good[owner]
    star, cosine, factor = base.star.copy(), base.cosine.copy(), base.factor.copy()
    star[slot[keep]] = fitted[keep] * shrink[owner[keep], None]
    cosine[slot[keep]] = np.cos(total / k)[owner[keep]]
    factor[rims[good]] = shrink[good]
    return SplitStar(star, cosine, base.refitted, factor < 1.0, factor)


#: Gauss–Newton steps of :func:`_equal_area_fans`' projection, and the largest relative difference
#: of its sectors' areas that is taken as equal (to rounding: G1 depends on it)
EQUAL_AREA_STEPS = 12
EQUAL_AREA_RTOL = 1e-13
#: :func:`_equal_area_fans` keeps ``base`` where a sector of its fan turns by less than this (sine)
EQUAL_AREA_SINE = 0.05


def _equal_area_fans(targets: Targets, base: SplitStar) -> SplitStar:
    """``base`` with the fans of boundary vertices (k ≥ 2 faces) and of interior vertices of odd
    valence replaced by the nearest fan (least squares over its tangents, in the tangent plane)
    whose sectors all have the same area ``t_j × t_{j+1}``: then ``t_{j−1} + t_{j+1} = λ_j t_j`` at
    every slot (cross both sides with t_j), ``λ_j = (t_{j−1} + t_{j+1})·t_j / |t_j|²``, which is all
    split4's G1 needs there, their twist systems having no compatibility condition (a path, an odd
    cycle). Regular stars are such fans too, but most target fans are not regular (a coarse cage's
    boundary corner, a valence-3 or 5 vertex with unequal angles), and a regular star turned their
    tangents by degrees. The nearest fan is the projection onto ``A_j − A_{j+1} = 0`` by
    Gauss–Newton from the targets (:data:`EQUAL_AREA_STEPS` steps ``δ = r − Jᵀ (J Jᵀ)⁻¹ (J r + h)``,
    r the way back to the targets). The same length safeguard as the regular stars. ``base`` is kept
    where the areas do not agree to :data:`EQUAL_AREA_RTOL`, a sector of the target fan or of the
    result turns by less than :data:`EQUAL_AREA_SINE` (sine), or the vertex was refitted."""
    topology = targets.topology
    boundary = topology.is_boundary_vertex
    eligible = ~base.refitted & np.where(
        boundary, topology.face_count >= 2, topology.valence % 2 == 1
    )
    star, cosine, factor = base.star.copy(), base.cosine.copy(), base.factor.copy()
    size = topology.face_count + boundary  # slots in the fan: k + 1 on the boundary, n inside
    keys = np.unique(2 * size[eligible] + boundary[eligible])  # one group per (fan size, boundary)
    for m, is_open in zip((keys // 2).tolist(), (keys % 2 == 1).tolist()):
        vs = np.flatnonzero(eligible & (boundary == is_open) & (size == m))
        slots = topology.neighbor_offsets[vs][:, None] + np.arange(m)  # (g, m)
        normal = targets.normals[vs]
        first = targets.tangents[slots[:, 0]]
        e1 = _unit(first - _dot(first, normal)[:, None] * normal)
        e2 = np.cross(normal, e1)
        wanted = targets.tangents[slots]
        goal = np.stack(
            [_dot(wanted, e1[:, None]), _dot(wanted, e2[:, None])], axis=-1
        )  # (g, m, 2) in the plane
        sectors = m - 1 if is_open else m
        j = np.arange(sectors)
        nxt = (j + 1) % m

        def areas(fan: FloatArray) -> FloatArray:
            """(g, sectors): ``t_j × t_{j+1}`` of plane fans (g, m, 2)."""
            return fan[:, j, 0] * fan[:, nxt, 1] - fan[:, j, 1] * fan[:, nxt, 0]

        start_area = areas(goal)
        start_length = np.linalg.norm(goal, axis=-1)
        posed = (start_area >= EQUAL_AREA_SINE * start_length[:, j] * start_length[:, nxt]).all(
            axis=1
        )
        posed &= (start_length > 0).all(
            axis=1
        )  # every sector turns forward: the projection is well posed
        vs, slots, wanted, goal, e1, e2 = (
            vs[posed],
            slots[posed],
            wanted[posed],
            goal[posed],
            e1[posed],
            e2[posed],
        )
        if not vs.size:
            continue
        fan = goal.copy()
        for _ in range(EQUAL_AREA_STEPS):
            u, w = fan[..., 0], fan[..., 1]
            area = areas(fan)
            grad = np.zeros((len(vs), sectors, m, 2))  # ∂A_j / ∂(u, w)
            grad[:, j, j, 0], grad[:, j, j, 1] = w[:, nxt], -u[:, nxt]
            grad[:, j, nxt, 0], grad[:, j, nxt, 1] = -w[:, j], u[:, j]
            jac = (grad[:, :-1] - grad[:, 1:]).reshape(
                len(vs), sectors - 1, 2 * m
            )  # rows: A_j − A_{j+1}
            gap = area[:, :-1] - area[:, 1:]
            back = (goal - fan).reshape(len(vs), 2 * m)
            normal_matrix = jac @ jac.transpose(0, 2, 1)
            normal_matrix += (
                1e-14
                * np.trace(normal_matrix, axis1=1, axis2=2)[:, None, None]
                * np.eye(sectors - 1)
            )
            rhs = np.einsum("gcz,gz->gc", jac, back) + gap
            multiplier = np.linalg.solve(normal_matrix, rhs[..., None])[..., 0]
            fan = fan + (back - np.einsum("gcz,gc->gz", jac, multiplier)).reshape(len(vs), m, 2)
        area = areas(fan)
        length = np.linalg.norm(fan, axis=-1)
        turn = area / np.maximum(length[:, j] * length[:, nxt], 1e-300)
        good = (
            np.abs(area - area.mean(axis=1, keepdims=True))
            <= EQUAL_AREA_RTOL * np.abs(area).mean(axis=1, keepdims=True)
        ).all(axis=1) & (turn >= EQUAL_AREA_SINE).all(axis=1)
        tangents = fan[..., :1] * e1[:, None] + fan[..., 1:] * e2[:, None]  # (g, m, 3)
        lam = _dot(np.roll(tangents, 1, axis=1) + np.roll(tangents, -1, axis=1), tangents) / _dot(
            tangents, tangents
        )
        shrink = _length_shrink(
            targets,
            tangents.reshape(-1, 3),
            wanted.reshape(-1, 3),
            slots.reshape(-1),
            np.repeat(vs, m),
            np.repeat(np.arange(len(vs)), m),
            len(vs),
        )
        keep = np.flatnonzero(good)
        star[slots[keep]] = tangents[keep] * shrink[keep, None, None]
        inner = (
            slice(1, m - 1) if is_open else slice(0, m)
        )  # a boundary fan's rim slots have no relation
        cosine[slots[keep, inner]] = 0.5 * lam[keep, inner]
        factor[vs[keep]] = shrink[keep]
    return SplitStar(star, cosine, base.refitted, factor < 1.0, factor)


# : what :func:`split4_patches` returns: sub-patches, edge-midpoint and centre positions, their
# normals, the stars
Split4Parts = tuple[PatchSet, FloatArray, FloatArray, SplitStar]


def split4_patches(
    targets: Targets,
    corners: FloatArray,
    centre: FloatArray,
    scale: float,
    guide: FloatArray | None = None,
    star: SplitStar | None = None,
    *,
    compiled: bool | None = None,
) -> Split4Parts:
    """The 4 F Bézier sub-patches (sub-patch ``4 f + k`` at corner k of face f), and the positions
    and unit surface normals of the edge midpoints and face centres, each stacked as (E + F, 3).
    The normal at M is ``t_L × t_X`` (⊥ the curve and seam tangents of its star); at C it is ``(b_0
    − b_2) × (b_1 − b_3)``, the cross of the centre's star. Also returns the star
    (:func:`split4_star`: which vertices were refitted or shrunk).

    ``targets`` are in local coordinates ``(x − centre) / scale``; the sub-patches are mapped
    back and their corners at mesh vertices set to ``corners`` (the input positions, (V, 3))
    exactly.

    ``guide`` (F, 7, 7, 3), local coordinates: a macro net per face (:func:`macro_nets`) whose
    interior the split should follow instead of the targets' bicubic, e.g. a fit of another surface
    (:mod:`g1patch.construct.polynomial`): its detail over its own boundary is taken (module
    docstring, "Shape"), and the min-norm G1 corrections move it only as far as G1 requires.
    ``star``: the vertex stars to use instead of :func:`split4_star`'s (regular per vertex, each
    ``c_v`` its angle step's cosine). ``compiled``: by the numba kernels (:func:`_compiled_patches`,
    item by item into the controls, ranges side by side), else the NumPy reference; default from
    :data:`KERNEL_FACES` faces on. The two agree to rounding (tests/test_split4_kernels.py).
    """
    if guide is not None and np.shape(guide) != (targets.topology.n_faces, 7, 7, 3):
        raise InputError(
            f"guide: expected shape ({targets.topology.n_faces}, 7, 7, 3), got {np.shape(guide)}"
        )
    topology = targets.topology
    n_faces = topology.n_faces
    pos = targets.positions
    compiled = (n_faces >= KERNEL_FACES) if compiled is None else compiled
    stars = split4_star(targets, compiled=compiled) if star is None else star
    star = stars.star
    ends = edge_end_cosines(topology, stars.cosine)  # (E, 2): c at X and at Y

    # -- edges: canonical half-edge X → Y (face L), twin Y → X (face R)
    h_l = topology.edge_halfedges[:, 0]
    h_r = topology.edge_halfedges[:, 1]
    interior = h_r >= 0
    x_of, y_of = topology.origin(h_l), topology.target(h_l)
    mu = _chain_shears(topology, ends, compiled=compiled)
    if compiled:
        control, extra, extra_normals = _compiled_patches(
            targets, corners, centre, scale, guide, stars, mu
        )
        return PatchSet(control.reshape(-1, 4, 4, 3)), extra, extra_normals, stars
    slot_out, slot_in = halfedge_slots(topology)
    curve = np.stack(
        _edge_curves(
            pos[x_of],
            pos[y_of],
            star[slot_out[h_l]],
            star[slot_in[h_l]],
            mu,
            ends[:, 0],
            ends[:, 1],
        ),
        axis=1,
    )  # (E, 5, 3): P1, P2, M, P4, P5
    p1, p2, m, p4, p5 = (curve[:, i] for i in range(5))
    del star

    halfedges = np.arange(4 * n_faces)
    edge_of = topology.halfedge_edge
    canonical = h_l[edge_of] == halfedges
    slope = np.where(canonical, mu[edge_of], -mu[edge_of])  # m = λ(M → origin(h))

    flat_curve = curve.reshape(-1, 3)

    def on_side(at_x: int, at_y: int, origin_side: NDArray[np.bool_]) -> FloatArray:
        """Per half-edge, curve point ``at_x`` of its edge when ``origin_side`` is the X side, else
        ``at_y``."""
        return flat_curve[5 * edge_of + np.where(origin_side, at_x, at_y)]

    moved, shift = _even_vertex_shifts(
        topology, 2.0 * stars.cosine[topology.neighbor_offsets[:-1]], curve, mu, pos
    )
    curve[moved, 1:4] += shift[:, None]
    o1, o2 = on_side(0, 4, canonical), on_side(1, 3, canonical)  # from the origin of h
    d1, d2 = on_side(0, 4, ~canonical), on_side(1, 3, ~canonical)  # from the target of h

    # -- the free choices follow the face's own macro net (the targets' bicubic subdivided at ½, or
    # the
    # guide): what its boundary predicts from the split curves plus the net's detail over that
    # (:data:`_QUANTITIES`); G1 then moves them as little as it requires. A face whose corners'
    # stars
    # the safeguard shrank takes the detail scaled by the smallest factor: its curves are that much
    # shorter than the net's, so the net's full detail would overhang them
    own = _own_quantities(targets, guide)  # (4F, 7, 3) per half-edge, frame of its corner
    own[:, :_TWIST_VERTEX] *= np.repeat(stars.factor[topology.faces].min(axis=1), 4)[:, None, None]
    own[:, _TWIST_VERTEX] *= stars.factor[
        topology.faces.reshape(-1), None
    ]  # the twist at V shrinks with its star
    prev = QuadTopology.prev(halfedges)
    t_x = 3.0 * (p2 - m)

    # -- centres (any C keeps G1: its star is a plain cross): the bilinear Coons centre ΣM/2 − ΣV/4
    # plus the net's detail; its cross b_k = C + (M_k − M_{k+2})/6 plus the net's (opposite arms
    # stay opposite)
    mids = m[edge_of].reshape(n_faces, 4, 3)
    own_face = own.reshape(n_faces, 4, -1, 3)
    centres = (
        0.5 * mids.sum(axis=1)
        - 0.25 * pos[topology.faces].sum(axis=1)
        + own_face[:, :, _CENTRE].mean(axis=1)
    )
    arms = mids / 6.0 + 0.5 * own_face[:, :, _CROSS]
    b = centres[:, None] + arms - np.roll(arms, -2, axis=1)
    del own_face, arms

    # -- midpoint stars t_L + t_R = μ t_X: C − M plus the net's detail on either side, the gap of
    # the
    # star split equally (the least change); a boundary midpoint keeps its own; seam points e = M +
    # t/3
    own_seam = np.repeat(centres, 4, axis=0) - m[edge_of] + own[:, _SEAM]
    star_gap = own_seam[h_l] + np.where(interior[:, None], own_seam[h_r], 0.0) - mu[:, None] * t_x
    t_l = own_seam[h_l] - np.where(interior, 0.5, 0.0)[:, None] * star_gap
    t_r = np.where(interior[:, None], own_seam[h_r] - 0.5 * star_gap, 0.0)
    n_m = np.cross(t_l, t_x)  # ⊥ both tangents of the star at M
    e_l = m + t_l / 3.0
    e_r = m + t_r / 3.0
    seam = np.where(canonical[:, None], e_l[edge_of], e_r[edge_of])  # into the face of h
    del t_x, t_l, t_r, own_seam, star_gap

    # -- twist targets at the corners V, MID[k], MID[k−1], C of each sub-patch: the parallelogram
    # of the twist point's three neighbours (as G1 left them) plus the net's offset
    m_h = m[edge_of]
    b_flat = b.reshape(-1, 3)
    corner_points = pos[topology.faces.reshape(-1)]
    centre_points = np.repeat(centres, 4, axis=0)
    twist = np.empty((4 * n_faces, 4, 3))  # targets, replaced in place by the solved twists
    twist[:, 0] = o1 + d1[prev] - corner_points + own[:, _TWIST_VERTEX]
    twist[:, 1] = o2 + seam - m_h + own[:, _TWIST_MID]
    twist[:, 2] = d2[prev] + seam[prev] - m_h[prev] + own[:, _TWIST_PREV]
    twist[:, 3] = b_flat + b_flat[prev] - centre_points + own[:, _TWIST_CENTRE]
    del centre_points, own

    # -- original vertices: F_{j−1} + F_j = R_j over the interior ring edges
    origin = topology.faces.reshape(-1)
    lam = 2.0 * np.where(
        canonical, ends[edge_of, 0], ends[edge_of, 1]
    )  # λ_j of the slot of h at its origin
    rhs = 2.0 * o1 + (2.0 * lam[:, None] * (o2 - o1) - slope[:, None] * (o1 - pos[origin])) / 3.0
    del corner_points
    boundary = topology.is_boundary_vertex
    base = int(topology.face_count.max()) + 1
    keys = np.unique(boundary.astype(np.int64) * base + topology.face_count)
    for is_open, n in zip(keys // base, keys % base):
        vs = np.flatnonzero((boundary == is_open) & (topology.face_count == n))
        ring = topology.ring_halfedges[topology.ring_offsets[vs][:, None] + np.arange(n)]
        equations = _cycle(int(n), closed=not is_open)
        if equations.size:
            rows = ring if not is_open else ring[:, 1:]
            twist[ring, 0] = _min_norm(equations, rhs[rows], twist[ring, 0])

    # -- midpoints: G_LX + G_RX = A_X, G_LY + G_RY = A_Y, G_LX + G_LY = 2 e_L, G_RX + G_RY = 2 e_R
    inner = np.flatnonzero(interior)
    a_x = 2.0 * p2 + (2.0 * ends[:, 0, None] * (m - p2) - 2.0 * mu[:, None] * (p2 - p1)) / 3.0
    a_y = 2.0 * p4 + (2.0 * ends[:, 1, None] * (m - p4) + 2.0 * mu[:, None] * (p4 - p5)) / 3.0
    hl, hr = h_l[inner], h_r[inner]
    sides_h = (hl, QuadTopology.next(hr), QuadTopology.next(hl), hr)
    kinds = (1, 2, 2, 1)
    unknowns = np.stack([twist[h, kind] for h, kind in zip(sides_h, kinds)], axis=1)
    sides = np.stack([a_x[inner], a_y[inner], 2.0 * e_l[inner], 2.0 * e_r[inner]], axis=1)
    solved = _min_norm(_MIDPOINT, sides, unknowns)
    for column, (h, kind) in enumerate(zip(sides_h, kinds)):
        twist[h, kind] = solved[:, column]
    outer = np.flatnonzero(~interior)
    pair = (h_l[outer], QuadTopology.next(h_l[outer]))
    unknowns = np.stack([twist[pair[0], 1], twist[pair[1], 2]], axis=1)
    solved = _min_norm(np.ones((1, 2)), 2.0 * e_l[outer, None], unknowns)
    twist[pair[0], 1], twist[pair[1], 2] = solved[:, 0], solved[:, 1]

    # -- centres: K_k + K_{k+1} = 2 b_k (the C1 parallelogram rule)
    twist[:, 3] = _min_norm(
        _cycle(4, closed=True), 2.0 * np.roll(b, 1, axis=1), twist[:, 3].reshape(-1, 4, 3)
    ).reshape(-1, 3)
    del rhs

    # -- sub-patch k in the frame of corner k, back to the input coordinates, corners exact
    control = _assemble(
        (o1, o2, m_h, d1, d2, seam, b_flat), centres, twist, corners[topology.faces], scale, centre
    )
    del o1, o2, m_h, d1, d2, seam, twist
    extra = np.concatenate([m, centres]) * scale + centre
    extra_normals = np.concatenate(
        [_unit(n_m), _unit(np.cross(b[:, 0] - b[:, 2], b[:, 1] - b[:, 3]))]
    )
    return PatchSet(control.reshape(-1, 4, 4, 3)), extra, extra_normals, stars


def macro_nets(control: FloatArray) -> FloatArray:
    """The (F, 7, 7, 3) macro nets of sub-patch controls (4F, 4, 4, 3) (sub-patch 4f+k at corner
    k)."""
    sub = control.reshape(-1, 4, 4, 4, 3)
    nets = np.empty((sub.shape[0], 7, 7, 3))
    for k, (a, b) in enumerate(_SUB_ORIGIN):
        nets[:, a : a + 4, b : b + 4] = sub[:, k]
    return nets


def bspline_nets(source: PatchNetwork | PatchSet) -> FloatArray:
    """Per-quad bicubic B-spline nets (F, 6, 6, 3), knots :data:`BSPLINE_KNOTS` in u and v.

    The macro net minus its row and column 3: those hold exact midpoints of their neighbours
    (the pieces join C1), which is what a double knot at ½ encodes.
    """
    patches = source.patches if isinstance(source, PatchNetwork) else source
    if not isinstance(patches, PatchSet) or patches.form != "bezier" or len(patches) % 4:
        raise InputError(
            "bspline_nets: expected the Bézier sub-patches of a split4 network (4 per quad)"
        )
    keep = np.array([0, 1, 2, 4, 5, 6])
    return np.ascontiguousarray(macro_nets(patches.world_control())[:, keep][:, :, keep])


def _split4_network(
    topology: QuadTopology,
    patches: PatchSet,
    points: FloatArray,
    point_normals: FloatArray,
    provenance: dict[str, str],
    *,
    compiled: bool | None = None,
) -> PatchNetwork:
    """Connectivity of the 4 F sub-patches. Sub-patch k of face f has local corner k at V_k,
    k+1 at MID[k], k+2 at C, k+3 at MID[k−1]; its local edge k is the first half of half-edge
    h = 4f+k, edge k+1 seam k (M_k → C), edge k+2 seam k−1 reversed, edge k+3 the second half of
    prev(h). Edge ids: 2e (X half), 2e+1 (Y half) of mesh edge e, then 2E + 4f + k for seams.
    ``compiled``: face by face in :func:`_network_kernel` (the same integers), default from
    :data:`KERNEL_FACES` faces on.
    """
    n_faces, n_edges, nv = topology.n_faces, topology.n_edges, topology.n_vertices
    if (n_faces >= KERNEL_FACES) if compiled is None else compiled:
        from ..kernels import in_chunks, jit_kernel

        corner, edge_id, neighbor, neighbor_edge = (
            np.empty((n_faces, 4, 4), dtype=np.int64) for _ in range(4)
        )
        reversed_ = np.empty((n_faces, 4, 4), dtype=bool)
        kernel = jit_kernel(_network_kernel)
        in_chunks(
            lambda lo, hi: kernel(
                topology.faces,
                topology.halfedge_edge,
                topology.edge_halfedges,
                topology.twin,
                nv,
                corner,
                edge_id,
                reversed_,
                neighbor,
                neighbor_edge,
                lo,
                hi,
            ),
            n_faces,
        )
        return _network_of(
            patches,
            n_edges,
            n_faces,
            corner,
            edge_id,
            reversed_,
            neighbor,
            neighbor_edge,
            points,
            point_normals,
            provenance,
        )
    h = np.arange(4 * n_faces).reshape(n_faces, 4)  # half-edge k = sub-patch k of face f
    k = np.arange(4)
    prev = QuadTopology.prev(h)
    role = (k[None, :] - k[:, None]) % 4  # [sub-patch k, local edge l] → role (l − k) % 4
    twin = topology.twin
    canonical = topology.edge_halfedges[topology.halfedge_edge, 0] == np.arange(4 * n_faces)
    edge = topology.halfedge_edge

    corner = np.empty((n_faces, 4, 4), dtype=np.int64)  # [f, sub-patch, local corner]
    by_role = [
        topology.faces,
        nv + edge[h],
        np.broadcast_to(nv + n_edges + np.arange(n_faces)[:, None], h.shape),
        nv + edge[prev],
    ]
    edge_id = np.empty_like(corner)
    reversed_ = np.empty(corner.shape, dtype=bool)
    neighbor = np.empty_like(corner)
    neighbor_edge = np.empty_like(corner)
    seam = 2 * n_edges + h
    for r in range(4):
        rows = np.nonzero(role == r)  # (sub-patch, local edge) pairs with this role
        corner[:, rows[0], rows[1]] = by_role[r][:, rows[0]]
    first_half = 2 * edge[h] + ~canonical[h]
    second_half = 2 * edge[prev] + canonical[prev]
    twin_h, twin_prev = twin[h], twin[prev]
    cases = [
        (
            first_half,
            ~canonical[h],
            np.where(twin_h >= 0, QuadTopology.next(twin_h), -1),
            twin_h & 3,
        ),
        (
            seam,
            np.zeros(h.shape, bool),
            4 * (h >> 2) + (k + 1) % 4,
            np.broadcast_to((k + 3) % 4, h.shape),
        ),
        (
            seam[:, (k - 1) % 4],
            np.ones(h.shape, bool),
            4 * (h >> 2) + (k - 1) % 4,
            np.broadcast_to(k, h.shape),
        ),
        (second_half, ~canonical[prev], twin_prev, twin_prev & 3),
    ]
    for r, (ids, rev, other, other_edge) in enumerate(cases):
        rows = np.nonzero(role == r)
        edge_id[:, rows[0], rows[1]] = ids[:, rows[0]]
        reversed_[:, rows[0], rows[1]] = rev[:, rows[0]]
        neighbor[:, rows[0], rows[1]] = np.where(other >= 0, other, -1)[:, rows[0]]
        neighbor_edge[:, rows[0], rows[1]] = np.where(other >= 0, other_edge, -1)[:, rows[0]]
    return _network_of(
        patches,
        n_edges,
        n_faces,
        corner,
        edge_id,
        reversed_,
        neighbor,
        neighbor_edge,
        points,
        point_normals,
        provenance,
    )


def _network_of(
    patches: PatchSet,
    n_edges: int,
    n_faces: int,
    corner: IntArray,
    edge_id: IntArray,
    reversed_: NDArray[np.bool_],
    neighbor: IntArray,
    neighbor_edge: IntArray,
    points: FloatArray,
    point_normals: FloatArray,
    provenance: dict[str, str],
) -> PatchNetwork:
    """The :class:`PatchNetwork` of the (F, 4, 4) connectivity arrays (sub-patch rows 4f + k)."""
    shape = (4 * n_faces, 4)
    return PatchNetwork(
        patches=patches,
        corner_ids=corner.reshape(shape),
        edge_ids=edge_id.reshape(shape),
        edge_reversed=reversed_.reshape(shape),
        neighbor=neighbor.reshape(shape),
        neighbor_edge=neighbor_edge.reshape(shape),
        same_direction=np.zeros(shape, dtype=bool),
        edge_collapsed=np.zeros(2 * n_edges + 4 * n_faces, dtype=bool),
        vertices=points,
        vertex_normals=point_normals,
        provenance=provenance,
    )


def split4_network_from_targets(
    mesh: QuadMesh,
    targets: Targets,
    frame: Frame,
    provenance: dict[str, str],
    seam_edges: ArrayLike | None = None,
    guide: FloatArray | None = None,
    parts: Split4Parts | None = None,
) -> PatchNetwork:
    """The 2×2-split bicubic network of ``targets`` (in the local coordinates of ``frame``):
    polynomial, exactly G1 on mesh edges and seams, C1 inside each quad, interpolating the mesh
    vertices (module docstring). The sub-patches stay in local coordinates and carry the frame.
    Provenance: vertices whose fan was refitted to spread directions join ``fallback_vertices``;
    those whose star the length safeguard scaled down are counted in ``star_safeguard_vertices``.

    ``seam_edges`` (E,) bool, in ``mesh.topology.edges`` order: mesh edges sharp on purpose; both
    halves of each (edge ids 2e, 2e + 1) become :attr:`PatchNetwork.seam` edges on both sides (the
    split's own inner seams M–C never are). ``guide``: per-face macro nets to follow
    (:func:`split4_patches`). ``parts``: ``split4_patches(targets, targets.positions, 0, 1)`` when
    the caller has it already."""
    if parts is None:
        parts = split4_patches(targets, targets.positions, np.zeros(3), 1.0, guide)
    patches, extra, extra_normals, stars = parts
    return split4_network_from_parts(
        mesh,
        patches,
        extra,
        extra_normals,
        targets.normals,
        frame,
        split4_provenance(provenance, targets, stars),
        seam_edges,
    )


def split4_provenance(
    provenance: dict[str, str], targets: Targets, stars: SplitStar
) -> dict[str, str]:
    """``provenance`` with split4's counts: ``fallback_vertices``, the vertices whose rule fell back
    or whose fan was refitted to spread directions, and ``star_safeguard_vertices``, those whose
    star the length safeguard scaled down."""
    return dict(
        provenance,
        fallback_vertices=str(int((targets.fallback | stars.refitted).sum())),
        star_safeguard_vertices=str(int(stars.shrunk.sum())),
    )


def split4_network_from_parts(
    mesh: QuadMesh,
    patches: PatchSet,
    extra: FloatArray,
    extra_normals: FloatArray,
    normals: FloatArray,
    frame: Frame,
    provenance: dict[str, str],
    seam_edges: ArrayLike | None = None,
) -> PatchNetwork:
    """:func:`split4_network_from_targets` of assembled parts (:func:`split4_patches`: ``patches``,
    the midpoints and centres ``extra`` and their normals, in the local coordinates of ``frame``)
    and the unit ``normals`` at the mesh vertices, without the targets: a caller that drops its
    targets and stars first builds the network's arrays without them (the build's peak, DESIGN
    §6)."""
    patches = patches.with_frame(frame)
    points = np.empty((mesh.topology.n_vertices + len(extra), 3))
    points[: mesh.topology.n_vertices] = mesh.vertices
    frame.to_world(
        extra, out=points[mesh.topology.n_vertices :]
    )  # the midpoints and centres, without a copy
    point_normals = np.concatenate([normals, extra_normals])
    network = _split4_network(mesh.topology, patches, points, point_normals, provenance)
    if seam_edges is None:
        return network
    sharp = np.asarray(seam_edges)
    if sharp.shape != (mesh.topology.n_edges,):
        raise InputError(
            f"seam_edges: expected shape ({mesh.topology.n_edges},), one per mesh edge, got "
            f"{sharp.shape}"
        )
    return network.with_seams(
        np.concatenate(
            [np.repeat(sharp, 2), np.zeros(4 * mesh.topology.n_faces, dtype=sharp.dtype)]
        )
    )


# -- the compiled path of split4_patches: the same formulas, item by item, in five passes that write
# straight into the (F, 4, 4, 4, 3) controls (its twist and seam slots hold the net's offsets until
# the passes that solve them), so no (4F, ·, 3) temporary is made. Each pass writes only its own
# items' points (a face's, an edge's seam and midpoint twists, a vertex's ring twists), so the
# ranges
# run side by side (g1patch.kernels.in_chunks) with the one-range result.

#: where in the target net (4 i + j of the 4×4 net) corner k's points go: the corner, the edge
#: point next to it along edge k, the one next to corner k + 1 along edge k, its interior point
_NET_CORNER = np.array([0, 12, 15, 3])
_NET_OUT = np.array([4, 13, 11, 2])
_NET_IN = np.array([8, 14, 7, 1])
_NET_INTERIOR = np.array([5, 9, 10, 6])
# : [k, p, q]: where point (p, q) of corner k's frame sits in sub-patch k's 48 coordinates, 3 (4 i +
# j)
_PLACE = 3 * (4 * _LOCAL[..., 0] + _LOCAL[..., 1])


def _sparse(weights: FloatArray) -> tuple[IntArray, IntArray, FloatArray]:
    """The nonzero entries of ``weights`` [k, c, n] along n, in n order: counts (4, 7), their n and
    their values (4, 7, most), zero-padded (the kernel's sums skip exact zeros: the same sums)."""
    counts = (weights != 0.0).sum(axis=2)
    terms = np.zeros((*counts.shape, counts.max()), dtype=np.int64)
    values = np.zeros(terms.shape)
    for k, c in np.ndindex(counts.shape):
        (nonzero,) = np.nonzero(weights[k, c])
        terms[k, c, : nonzero.size], values[k, c, : nonzero.size] = nonzero, weights[k, c, nonzero]
    return counts, terms, values


def _curve_kernel(
    pos: FloatArray,
    star: FloatArray,
    ends: FloatArray,
    mu: FloatArray,
    edge_halfedges: IntArray,
    origin: IntArray,
    slot_out: NDArray[np.int32],
    slot_in: NDArray[np.int32],
    curve: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """:func:`_edge_curves` of edges ``lo:hi`` into ``curve`` (E, 5, 3): ``P1 = X + T_XY/6``,
    ``M = (X + Y)/2 + (T_XY + T_YX)/8``, ``P2, P4 = M ± δ (P1 − P5)/2``, ``P5 = Y + T_YX/6``."""
    for e in range(lo, hi):
        h = edge_halfedges[e, 0]
        x, y = origin[h], origin[(h & ~3) | ((h + 1) & 3)]
        sx, sy = slot_out[h], slot_in[h]
        delta = 0.5
        if mu[e] != 0.0:
            delta = 2.0 * mu[e] / (5.0 * mu[e] + ends[e, 0] - ends[e, 1])
        for d in range(3):
            p1 = pos[x, d] + star[sx, d] / 6.0
            p5 = pos[y, d] + star[sy, d] / 6.0
            m = 0.5 * (pos[x, d] + pos[y, d]) + (star[sx, d] + star[sy, d]) / 8.0
            half = 0.5 * delta * (p1 - p5)
            curve[e, 0, d] = p1
            curve[e, 1, d] = m + half
            curve[e, 2, d] = m
            curve[e, 3, d] = m - half
            curve[e, 4, d] = p5


def _face_kernel(
    pos: FloatArray,
    tangents: FloatArray,
    interior: FloatArray,
    faces: IntArray,
    halfedge_edge: IntArray,
    edge_halfedges: IntArray,
    slot_out: NDArray[np.int32],
    slot_in: NDArray[np.int32],
    curve: FloatArray,
    factor: FloatArray,
    counts: IntArray,
    terms: IntArray,
    weights: FloatArray,
    guide: FloatArray,
    use_guide: bool,
    place: IntArray,
    net_corner: IntArray,
    net_out: IntArray,
    net_in: IntArray,
    net_interior: IntArray,
    n_edges: int,
    scale: float,
    centre: FloatArray,
    control: FloatArray,
    extra: FloatArray,
    extra_normals: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """Faces ``lo:hi``: the net's quantities ``Σ_n w[k, c, n] net_n`` (the targets' bicubic, or the
    guide; the nonzero weights in n order: ``counts[k, c]`` of them, at ``terms[k, c]``), scaled by
    the stars' factors; ``C = ΣM/2 − ΣV/4 + Σ own_centre/4``, arms ``a_k = M_k/6 + own_cross/2``,
    ``b_k = C + a_k − a_{k+2}``; the curve points, b and C into each sub-patch, ``C − M_k +
    own_seam`` into its seam slot and the twist offsets into its twist slots (the later passes
    replace them); ``C · scale + centre`` and ``unit((b_0 − b_2) × (b_1 − b_3))`` into ``extra``,
    ``extra_normals`` at ``n_edges + f``."""
    net = np.empty((49 if use_guide else 16, 3))
    own = np.empty((4, 7, 3))
    b = np.empty((4, 3))
    c = np.empty(3)
    for f in range(lo, hi):
        if use_guide:
            net[:] = guide[f]
        else:
            for k in range(4):
                h = 4 * f + k
                a, z = faces[f, k], faces[f, (k + 1) & 3]
                for d in range(3):
                    net[net_corner[k], d] = pos[a, d]
                    net[net_out[k], d] = pos[a, d] + tangents[slot_out[h], d] / 3.0
                    net[net_in[k], d] = pos[z, d] + tangents[slot_in[h], d] / 3.0
                    net[net_interior[k], d] = 0.5 * (interior[f, k, 0, d] + interior[f, k, 1, d])
        least = min(
            factor[faces[f, 0]], factor[faces[f, 1]], factor[faces[f, 2]], factor[faces[f, 3]]
        )
        for k in range(4):
            for q in range(7):
                total0, total1, total2 = 0.0, 0.0, 0.0
                for t in range(counts[k, q]):
                    n, w = terms[k, q, t], weights[k, q, t]
                    total0 += w * net[n, 0]
                    total1 += w * net[n, 1]
                    total2 += w * net[n, 2]
                scaled = least if q < 6 else factor[faces[f, k]]
                own[k, q, 0], own[k, q, 1], own[k, q, 2] = (
                    total0 * scaled,
                    total1 * scaled,
                    total2 * scaled,
                )
        for d in range(3):
            mids, corners, centres = 0.0, 0.0, 0.0
            for k in range(4):
                mids += curve[halfedge_edge[4 * f + k], 2, d]
                corners += pos[faces[f, k], d]
                centres += own[k, 0, d]
            c[d] = 0.5 * mids - 0.25 * corners + centres / 4.0
            for k in range(4):
                b[k, d] = (
                    c[d]
                    + (curve[halfedge_edge[4 * f + k], 2, d] / 6.0 + 0.5 * own[k, 1, d])
                    - (
                        curve[halfedge_edge[4 * f + ((k + 2) & 3)], 2, d] / 6.0
                        + 0.5 * own[(k + 2) & 3, 1, d]
                    )
                )
        for k in range(4):
            h = 4 * f + k
            hp = 4 * f + ((k + 3) & 3)
            e, ep = halfedge_edge[h], halfedge_edge[hp]
            near = 0 if edge_halfedges[e, 0] == h else 4  # P1 from the origin of h: 0 on the X side
            far = 4 if edge_halfedges[ep, 0] == hp else 0  # P1 of prev(h) from its target
            for d in range(3):
                control[h, place[k, 1, 0] + d] = curve[e, near, d]
                control[h, place[k, 2, 0] + d] = curve[e, 1 + near // 2, d]
                control[h, place[k, 3, 0] + d] = curve[e, 2, d]
                control[h, place[k, 0, 1] + d] = curve[ep, far, d]
                control[h, place[k, 0, 2] + d] = curve[ep, 1 + far // 2, d]
                control[h, place[k, 0, 3] + d] = curve[ep, 2, d]
                control[h, place[k, 3, 2] + d] = b[k, d]
                control[h, place[k, 2, 3] + d] = b[(k + 3) & 3, d]
                control[h, place[k, 3, 3] + d] = c[d]
                control[h, place[k, 3, 1] + d] = c[d] - curve[e, 2, d] + own[k, 2, d]
                control[h, place[k, 2, 1] + d] = own[k, 3, d]
                control[h, place[k, 1, 2] + d] = own[k, 4, d]
                control[h, place[k, 2, 2] + d] = own[k, 5, d]
                control[h, place[k, 1, 1] + d] = own[k, 6, d]
        n0 = (b[0, 1] - b[2, 1]) * (b[1, 2] - b[3, 2]) - (b[0, 2] - b[2, 2]) * (b[1, 1] - b[3, 1])
        n1 = (b[0, 2] - b[2, 2]) * (b[1, 0] - b[3, 0]) - (b[0, 0] - b[2, 0]) * (b[1, 2] - b[3, 2])
        n2 = (b[0, 0] - b[2, 0]) * (b[1, 1] - b[3, 1]) - (b[0, 1] - b[2, 1]) * (b[1, 0] - b[3, 0])
        length = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        extra_normals[n_edges + f, 0] = n0 / length
        extra_normals[n_edges + f, 1] = n1 / length
        extra_normals[n_edges + f, 2] = n2 / length
        for d in range(3):
            extra[n_edges + f, d] = c[d] * scale + centre[d]


def _edge_kernel(
    curve: FloatArray,
    mu: FloatArray,
    ends: FloatArray,
    edge_halfedges: IntArray,
    place: IntArray,
    inner_operator: FloatArray,
    outer_operator: FloatArray,
    scale: float,
    centre: FloatArray,
    control: FloatArray,
    extra: FloatArray,
    extra_normals: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """Edges ``lo:hi``: the star at M, ``t_L + t_R = μ t_X`` with ``t_X = 3 (P2 − M)``, each side
    its seam slot's ``C − M + own`` minus half the gap; the seam points ``M + t/3`` on both sides of
    both sub-patches; the midpoint twists' targets (``P + e − M`` plus the net's offset) moved onto
    ``G_LX + G_RX = A_X``, ``G_LY + G_RY = A_Y``, ``G_LX + G_LY = 2 e_L``, ``G_RX + G_RY = 2 e_R``
    by the min-norm operator; M and ``unit(t_L × t_X)`` into ``extra``, ``extra_normals``."""
    stacked = np.empty((8, 3))
    solved = np.empty(4)
    e_l = np.empty(3)
    e_r = np.empty(3)
    t_l = np.empty(3)
    t_x = np.empty(3)
    for e in range(lo, hi):
        hl, hr = edge_halfedges[e, 0], edge_halfedges[e, 1]
        inside = hr >= 0
        fl, kl = hl >> 2, hl & 3
        nl = (hl & ~3) | ((hl + 1) & 3)
        fnl, knl = nl >> 2, nl & 3
        fr, kr = hr >> 2, hr & 3
        nr = (hr & ~3) | ((hr + 1) & 3)
        fnr, knr = nr >> 2, nr & 3
        for d in range(3):
            p1, p2, m, p4, p5 = (
                curve[e, 0, d],
                curve[e, 1, d],
                curve[e, 2, d],
                curve[e, 3, d],
                curve[e, 4, d],
            )
            seam_l = control[hl, place[kl, 3, 1] + d]
            seam_r = control[hr, place[kr, 3, 1] + d] if inside else 0.0
            t_x[d] = 3.0 * (p2 - m)
            gap = seam_l + seam_r - mu[e] * t_x[d]
            t_l[d] = seam_l - (0.5 if inside else 0.0) * gap
            t_r = seam_r - 0.5 * gap if inside else 0.0
            e_l[d] = m + t_l[d] / 3.0
            e_r[d] = m + t_r / 3.0
            extra[e, d] = m * scale + centre[d]
            stacked[0, d] = p2 + e_l[d] - m + control[hl, place[kl, 2, 1] + d]
            if inside:
                stacked[1, d] = p2 + e_r[d] - m + control[nr, place[knr, 1, 2] + d]
                stacked[2, d] = p4 + e_l[d] - m + control[nl, place[knl, 1, 2] + d]
                stacked[3, d] = p4 + e_r[d] - m + control[hr, place[kr, 2, 1] + d]
                stacked[4, d] = (
                    2.0 * p2 + (2.0 * ends[e, 0] * (m - p2) - 2.0 * mu[e] * (p2 - p1)) / 3.0
                )
                stacked[5, d] = (
                    2.0 * p4 + (2.0 * ends[e, 1] * (m - p4) + 2.0 * mu[e] * (p4 - p5)) / 3.0
                )
                stacked[6, d] = 2.0 * e_l[d]
                stacked[7, d] = 2.0 * e_r[d]
            else:
                stacked[1, d] = p4 + e_l[d] - m + control[nl, place[knl, 1, 2] + d]
                stacked[2, d] = 2.0 * e_l[d]
        n0 = t_l[1] * t_x[2] - t_l[2] * t_x[1]
        n1 = t_l[2] * t_x[0] - t_l[0] * t_x[2]
        n2 = t_l[0] * t_x[1] - t_l[1] * t_x[0]
        length = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        extra_normals[e, 0] = n0 / length
        extra_normals[e, 1] = n1 / length
        extra_normals[e, 2] = n2 / length
        for d in range(3):
            control[hl, place[kl, 3, 1] + d] = e_l[d]
            control[nl, place[knl, 1, 3] + d] = e_l[d]
            if inside:
                control[hr, place[kr, 3, 1] + d] = e_r[d]
                control[nr, place[knr, 1, 3] + d] = e_r[d]
            operator = inner_operator if inside else outer_operator
            for j in range(operator.shape[0]):
                total = 0.0
                for i in range(operator.shape[1]):
                    total += operator[j, i] * stacked[i, d]
                solved[j] = total
            control[hl, place[kl, 2, 1] + d] = solved[0]
            if inside:
                control[nr, place[knr, 1, 2] + d] = solved[1]
                control[nl, place[knl, 1, 2] + d] = solved[2]
                control[hr, place[kr, 2, 1] + d] = solved[3]
            else:
                control[nl, place[knl, 1, 2] + d] = solved[1]


def _vertex_kernel(
    pos: FloatArray,
    curve: FloatArray,
    mu: FloatArray,
    ends: FloatArray,
    halfedge_edge: IntArray,
    edge_halfedges: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    is_boundary: NDArray[np.bool_],
    table: IntArray,
    operators: FloatArray,
    place: IntArray,
    control: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """Vertices ``lo:hi``: the twist targets at V of their ring's sub-patches (``P1 + P1' − V`` plus
    the net's offset in the slot) moved onto ``F_{j−1} + F_j = R_j``,
    ``R_j = 2 P1_j + (2 λ_j (P2_j − P1_j) − m_j (P1_j − v))/3`` (rows j ≥ 1 at a boundary vertex),
    by the min-norm operator at ``operators[table[open, n]:]`` (none where ``table`` is −1)."""
    width = 1
    for v in range(lo, hi):
        width = max(width, ring_offsets[v + 1] - ring_offsets[v])
    stacked = np.empty((2 * width, 3))
    for v in range(lo, hi):
        start, n = ring_offsets[v], ring_offsets[v + 1] - ring_offsets[v]
        is_open = 1 if is_boundary[v] else 0
        for j in range(n):
            h = ring_halfedges[start + j]
            hp = (h & ~3) | ((h + 3) & 3)
            e, ep = halfedge_edge[h], halfedge_edge[hp]
            near = 0 if edge_halfedges[e, 0] == h else 4
            far = 4 if edge_halfedges[ep, 0] == hp else 0
            slope = mu[e] if near == 0 else -mu[e]
            lam = 2.0 * ends[e, near // 4]  # λ_j of this ring slot
            slot = place[h & 3, 1, 1]
            for d in range(3):
                o1, o2 = curve[e, near, d], curve[e, 1 + near // 2, d]
                stacked[j, d] = o1 + curve[ep, far, d] - pos[v, d] + control[h, slot + d]
                if j >= is_open:
                    stacked[n + j - is_open, d] = (
                        2.0 * o1 + (2.0 * lam * (o2 - o1) - slope * (o1 - pos[v, d])) / 3.0
                    )
        offset = table[is_open, n]
        columns = 2 * n - is_open
        for j in range(n):
            h = ring_halfedges[start + j]
            slot = place[h & 3, 1, 1]
            for d in range(3):
                if offset < 0:
                    control[h, slot + d] = stacked[j, d]
                    continue
                total = 0.0
                for i in range(columns):
                    total += operators[offset + j * columns + i] * stacked[i, d]
                control[h, slot + d] = total


def _centre_kernel(
    corners: FloatArray,
    faces: IntArray,
    operator: FloatArray,
    place: IntArray,
    scale: float,
    centre: FloatArray,
    control: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """Faces ``lo:hi``: the twists at C (``b_k + b_{k−1} − C`` plus the net's offset in the slot)
    moved onto ``K_k + K_{k+1} = 2 b_k`` by the min-norm operator; then every point to
    ``x · scale + centre``, the corners at mesh vertices ``corners``."""
    stacked = np.empty((8, 3))
    for f in range(lo, hi):
        for k in range(4):
            h = 4 * f + k
            for d in range(3):
                b_prev = control[h, place[k, 2, 3] + d]
                stacked[k, d] = (
                    control[h, place[k, 3, 2] + d]
                    + b_prev
                    - control[h, place[k, 3, 3] + d]
                    + control[h, place[k, 2, 2] + d]
                )
                stacked[4 + k, d] = 2.0 * b_prev
        for k in range(4):
            h = 4 * f + k
            for d in range(3):
                total = 0.0
                for i in range(8):
                    total += operator[k, i] * stacked[i, d]
                control[4 * f + k, place[k, 2, 2] + d] = total
            for i in range(16):
                for d in range(3):
                    control[h, 3 * i + d] = control[h, 3 * i + d] * scale + centre[d]
            for d in range(3):
                control[h, place[k, 0, 0] + d] = corners[faces[f, k], d]


def _compiled_patches(
    targets: Targets,
    corners: FloatArray,
    centre: FloatArray,
    scale: float,
    guide: FloatArray | None,
    stars: SplitStar,
    mu: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`split4_patches`' controls (4F, 48), extra points and normals by the kernels
    above, ranges side by side (:func:`~g1patch.kernels.in_chunks`)."""
    from ..kernels import in_chunks, jit_kernel
    from ..targets.local import slot_tables

    topology = targets.topology
    n_faces, n_edges = topology.n_faces, topology.n_edges
    pos = np.ascontiguousarray(targets.positions, dtype=np.float64)
    star = np.ascontiguousarray(stars.star)
    ends = np.ascontiguousarray(edge_end_cosines(topology, stars.cosine))
    origin, edge_halfedges, halfedge_edge = (
        topology.faces.reshape(-1),
        topology.edge_halfedges,
        topology.halfedge_edge,
    )
    slot_out, slot_in = slot_tables(topology)
    centre = np.asarray(centre, dtype=np.float64).reshape(3)
    scale = float(scale)

    curve = np.empty((n_edges, 5, 3))
    kernel = jit_kernel(_curve_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            pos, star, ends, mu, edge_halfedges, origin, slot_out, slot_in, curve, lo, hi
        ),
        n_edges,
    )
    moved, shift = _even_vertex_shifts(
        topology, 2.0 * stars.cosine[topology.neighbor_offsets[:-1]], curve, mu, pos
    )
    curve[moved, 1:4] += shift[:, None]

    control = np.empty((4 * n_faces, 48))  # row h = 4f + k: sub-patch k's 4×4×3 points
    extra = np.empty((n_edges + n_faces, 3))
    extra_normals = np.empty((n_edges + n_faces, 3))
    counts, terms, weights = _sparse(_NET_WEIGHTS if guide is None else _MACRO_WEIGHTS)
    nets = (
        np.zeros((1, 49, 3))
        if guide is None
        else np.ascontiguousarray(guide, dtype=np.float64).reshape(n_faces, 49, 3)
    )
    tangents, interior = (
        np.ascontiguousarray(targets.tangents),
        np.ascontiguousarray(targets.interior),
    )
    factor = np.ascontiguousarray(stars.factor)
    kernel = jit_kernel(_face_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            pos,
            tangents,
            interior,
            topology.faces,
            halfedge_edge,
            edge_halfedges,
            slot_out,
            slot_in,
            curve,
            factor,
            counts,
            terms,
            weights,
            nets,
            guide is not None,
            _PLACE,
            _NET_CORNER,
            _NET_OUT,
            _NET_IN,
            _NET_INTERIOR,
            n_edges,
            scale,
            centre,
            control,
            extra,
            extra_normals,
            lo,
            hi,
        ),
        n_faces,
    )

    inner, outer = _operator(_MIDPOINT), _operator(np.ones((1, 2)))
    kernel = jit_kernel(_edge_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            curve,
            mu,
            ends,
            edge_halfedges,
            _PLACE,
            inner,
            outer,
            scale,
            centre,
            control,
            extra,
            extra_normals,
            lo,
            hi,
        ),
        n_edges,
    )

    boundary = topology.is_boundary_vertex
    table = np.full((2, int(topology.face_count.max()) + 1), -1, dtype=np.int64)
    operators = [np.zeros(0)]
    size = 0
    for is_open in (0, 1):
        for n in np.unique(topology.face_count[boundary == is_open]):
            equations = _cycle(int(n), closed=not is_open)
            if equations.size:
                operators.append(_operator(equations).reshape(-1))
                table[is_open, n] = size
                size += operators[-1].size
    flat = np.concatenate(operators)
    kernel = jit_kernel(_vertex_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            pos,
            curve,
            mu,
            ends,
            halfedge_edge,
            edge_halfedges,
            topology.ring_offsets,
            topology.ring_halfedges,
            boundary,
            table,
            flat,
            _PLACE,
            control,
            lo,
            hi,
        ),
        topology.n_vertices,
    )
    del curve

    corners = np.ascontiguousarray(corners, dtype=np.float64)
    face_operator = _operator(_cycle(4, closed=True))
    kernel = jit_kernel(_centre_kernel)
    in_chunks(
        lambda lo, hi: kernel(
            corners, topology.faces, face_operator, _PLACE, scale, centre, control, lo, hi
        ),
        n_faces,
    )
    return control, extra, extra_normals


def _network_kernel(
    faces: IntArray,
    halfedge_edge: IntArray,
    edge_halfedges: IntArray,
    twin: IntArray,
    n_vertices: int,
    corner: IntArray,
    edge_id: IntArray,
    reversed_: NDArray[np.bool_],
    neighbor: IntArray,
    neighbor_edge: IntArray,
    lo: int,
    hi: int,
) -> None:
    """:func:`_split4_network`'s connectivity of faces ``lo:hi`` into the (F, 4, 4) arrays: local
    edge l of sub-patch k has role r = (l − k) mod 4 (0: first half of h, 1: seam k, 2: seam k − 1
    reversed, 3: second half of prev(h)), and its corner l is, by role, V_k, MID[k], C, MID[k−1]."""
    n_edges = edge_halfedges.shape[0]
    for f in range(lo, hi):
        for k in range(4):
            h, hp = 4 * f + k, 4 * f + ((k + 3) & 3)
            e, ep = halfedge_edge[h], halfedge_edge[hp]
            canonical, canonical_prev = edge_halfedges[e, 0] == h, edge_halfedges[ep, 0] == hp
            for r in range(4):
                l = (k + r) & 3
                if r == 0:
                    corner[f, k, l] = faces[f, k]
                    edge_id[f, k, l] = 2 * e + (0 if canonical else 1)
                    reversed_[f, k, l] = not canonical
                    other = twin[h]
                    neighbor[f, k, l] = (other & ~3) | ((other + 1) & 3) if other >= 0 else -1
                    neighbor_edge[f, k, l] = other & 3 if other >= 0 else -1
                elif r == 1:
                    corner[f, k, l] = n_vertices + e
                    edge_id[f, k, l] = 2 * n_edges + h
                    reversed_[f, k, l] = False
                    neighbor[f, k, l] = 4 * f + ((k + 1) & 3)
                    neighbor_edge[f, k, l] = (k + 3) & 3
                elif r == 2:
                    corner[f, k, l] = n_vertices + n_edges + f
                    edge_id[f, k, l] = 2 * n_edges + hp
                    reversed_[f, k, l] = True
                    neighbor[f, k, l] = hp
                    neighbor_edge[f, k, l] = k
                else:
                    corner[f, k, l] = n_vertices + ep
                    edge_id[f, k, l] = 2 * ep + (1 if canonical_prev else 0)
                    reversed_[f, k, l] = not canonical_prev
                    other = twin[hp]
                    neighbor[f, k, l] = other if other >= 0 else -1
                    neighbor_edge[f, k, l] = other & 3 if other >= 0 else -1


def _star_kernel(
    normals: FloatArray,
    wanted: FloatArray,
    positions: FloatArray,
    offsets: IntArray,
    neighbors: IntArray,
    face_count: IntArray,
    valence: IntArray,
    boundary: NDArray[np.bool_],
    limit: float,
    star: FloatArray,
    valid: NDArray[np.bool_],
    factor: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """:func:`~g1patch.targets.interpolate.fit_regular_star` and :func:`split4_star`'s length
    safeguard for vertices ``lo:hi``: ``[a b] = Σ_j s_j [cos θ_j, sin θ_j] G⁻¹``, ``t_j = a cos θ_j
    + b sin θ_j`` (a boundary corner keeps ``s``), valid where ``(a × b)·n > 1e-12 (|a|² + |b|²)``;
    then the star scaled by ``min(1, 1 / max_j |t_j| / allowed_j)``, ``allowed = limit · min(|s|,
    2|d|²/(|d| + |P d|))``."""
    width = 1
    for v in range(lo, hi):
        width = max(width, offsets[v + 1] - offsets[v])
    cos, sin = np.empty(width), np.empty(width)
    a, b = np.empty(3), np.empty(3)
    for v in range(lo, hi):
        start, stop = offsets[v], offsets[v + 1]
        step = np.pi / face_count[v] if boundary[v] else 2.0 * np.pi / valence[v]
        corner = boundary[v] and face_count[v] == 1
        a[:] = 0.0
        b[:] = 0.0
        for s in range(start, stop):
            theta = (s - start) * step
            cos[s - start], sin[s - start] = np.cos(theta), np.sin(theta)
            for d in range(3):
                a[d] += cos[s - start] * wanted[s, d]
                b[d] += sin[s - start] * wanted[s, d]
        half = 0.5 * (face_count[v] if boundary[v] else valence[v])
        a /= half + 1.0 if boundary[v] else half
        b /= 1.0 if corner else half
        n = normals[v]
        area = (
            (a[1] * b[2] - a[2] * b[1]) * n[0]
            + (a[2] * b[0] - a[0] * b[2]) * n[1]
            + (a[0] * b[1] - a[1] * b[0]) * n[2]
        )
        valid[v] = corner or area > 1e-12 * (
            (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) + (b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
        )
        worst = 0.0
        for s in range(start, stop):
            for d in range(3):
                star[s, d] = (
                    wanted[s, d] if corner else a[d] * cos[s - start] + b[d] * sin[s - start]
                )
            e = positions[neighbors[s]] - positions[v]
            chord = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            along = e[0] * n[0] + e[1] * n[1] + e[2] * n[2]
            p0, p1, p2 = e[0] - along * n[0], e[1] - along * n[1], e[2] - along * n[2]
            in_plane = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
            arc = 2.0 * chord**2 / (chord + in_plane if chord > 0 else 1.0)
            length = np.sqrt(
                wanted[s, 0] * wanted[s, 0]
                + wanted[s, 1] * wanted[s, 1]
                + wanted[s, 2] * wanted[s, 2]
            )
            allowed = limit * min(length, arc)
            ratio = np.sqrt(
                star[s, 0] * star[s, 0] + star[s, 1] * star[s, 1] + star[s, 2] * star[s, 2]
            ) / (allowed if allowed > 0 else np.inf)
            if ratio > worst or np.isnan(ratio):
                worst = ratio
        shrink = min(1.0, 1.0 / (worst if worst > 0 else 1.0))
        factor[v] = shrink
        for s in range(start, stop):
            for d in range(3):
                star[s, d] *= shrink


def _chain_kernel(
    node_cosine: FloatArray,
    x_of: IntArray,
    y_of: IntArray,
    interior: NDArray[np.bool_],
    through: NDArray[np.bool_],
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    halfedge_edge: IntArray,
    edge_halfedges: IntArray,
    lam: FloatArray,
) -> None:
    """:func:`_chain_shears` by walking each grid line from its first end (node ``2e + s``, s = 1
    at Y): across an edge λ changes sign, through a valence-4 vertex (``partner``) it keeps it. The
    line's dominant end is the one with the larger ``|c_end − c_next|`` (the smaller node on a tie),
    where λ = −(c_end − c_next); λ per node into ``lam`` (2E,), zero on closed lines."""
    nodes = lam.size
    partner = np.full(
        nodes, -1, dtype=np.int64
    )  # the node through the valence-4 vertex: ring edge j ↔ j + 2
    ring = np.empty(4, dtype=np.int64)
    for v in range(through.size):
        if through[v]:
            for j in range(4):
                h = ring_halfedges[ring_offsets[v] + j]
                ring[j] = 2 * halfedge_edge[h] + (
                    0 if edge_halfedges[halfedge_edge[h], 0] == h else 1
                )
            for j in range(4):
                partner[ring[j]] = ring[(j + 2) & 3]
    done = np.zeros(nodes, dtype=np.bool_)
    for first in range(nodes):
        e = first >> 1
        v = x_of[e] if first & 1 == 0 else y_of[e]
        if done[first] or not interior[e] or through[v]:
            continue
        gap_first = node_cosine[first] - node_cosine[first ^ 1]
        last, sign = first, 1.0
        for _ in range(nodes):  # to the other end: across the edge, then through the vertex, if any
            last, sign = last ^ 1, -sign
            if partner[last] < 0:
                break
            last = partner[last]
        gap_last = node_cosine[last] - node_cosine[last ^ 1]
        # λ(last) = sign · λ(first); the dominant end takes −gap
        if abs(gap_first) > abs(gap_last) or (abs(gap_first) == abs(gap_last) and first < last):
            at_first = -gap_first
        else:
            at_first = sign * -gap_last
        node, current = first, at_first
        for _ in range(nodes):
            lam[node] = current
            done[node] = True
            node, current = node ^ 1, -current
            lam[node] = current
            done[node] = True
            if partner[node] < 0:
                break
            node = partner[node]
