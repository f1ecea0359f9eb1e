"""split4's shears along grid lines: μ_e = λ(M_e → X_e) per mesh edge (:func:`_chain_shears`).

At an interior valence-4 vertex the twist system is singular unless opposite ring edges carry
equal λ, so μ is carried along each grid line, alternating in sign, its size set at the line's
dominant end; :func:`_chain_kernel` walks the lines instead (the same values bit for bit).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ...kernels import jit_kernel
from ...mesh import QuadTopology

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


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
    ``ends`` (E, 2) holds each edge's c at X and at Y
    (:func:`~g1patch.construct.split4.stars.edge_end_cosines`).
    Closed lines (all valence 4) get μ = 0. ``compiled``: by walking the lines
    (:func:`_chain_kernel`, the same values bit for bit).
    """
    n_edges = topology.n_edges
    nodes = 2 * n_edges
    interior = ~topology.is_boundary_edge
    through = ~topology.is_boundary_vertex & (topology.valence == 4)
    h = topology.edge_halfedges[:, 0]
    x_of, y_of = topology.origin(h), topology.target(h)
    node_cosine = np.ascontiguousarray(ends, dtype=np.float64).reshape(-1)  # node 2e + s: c there
    if compiled:
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
    line_ends = np.flatnonzero(np.repeat(interior, 2) & ~through[vertex])
    gap = node_cosine[line_ends] - node_cosine[line_ends ^ 1]
    order = np.lexsort((line_ends, -np.abs(gap), chain[line_ends]))
    _, first = np.unique(chain[line_ends[order]], return_index=True)
    dominant = line_ends[order[first]]
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
