"""split4's assembly in numba kernels (:func:`_compiled_patches`): the same formulas as the
NumPy reference (:mod:`~g1patch.construct.split4.reference`), item by item.

Five passes write straight into the (F, 4, 4, 4, 3) controls (their twist and seam slots hold the
net's offsets until the passes that solve them), so no (4F, ·, 3) temporary is made: the curves
edge by edge, the net's quantities and the centre face by face, the midpoint stars and twists edge
by edge, the ring twists vertex by vertex, the centre twists face by face. Each pass writes only
its own items' points (a face's, an edge's seam and midpoint twists, a vertex's ring twists), so
the ranges run side by side (:func:`~g1patch.kernels.in_chunks`) with the one-range result.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from numpy.typing import NDArray

from ...kernels import in_chunks, jit_kernel
from ...targets.local import slot_tables
from .nets import _LOCAL, _MACRO_WEIGHTS, _NET_WEIGHTS
from .reference import SplitInputs
from .stars import STAR_LENGTH_LIMIT
from .systems import _MIDPOINT, _cycle, _even_vertex_shifts, _operator

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: where in the target net (4 i + j of the 4×4 net) corner k's points go: the corner, the edge
#: point next to it along edge k, the one next to corner k + 1 along edge k, its interior point
_NET_CORNER = np.array([0, 12, 15, 3])
_NET_OUT = np.array([4, 13, 11, 2])
_NET_IN = np.array([8, 14, 7, 1])
_NET_INTERIOR = np.array([5, 9, 10, 6])
#: [k, p, q]: where point (p, q) of corner k's frame sits in sub-patch k's 48 coordinates,
#: 3 (4 i + j)
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
    limit: float,
    scale: float,
    centre: FloatArray,
    control: FloatArray,
    extra: FloatArray,
    extra_normals: FloatArray,
    lo: int,
    hi: int,
) -> None:
    """Edges ``lo:hi``: the star at M, ``t_L + t_R = μ t_X`` with ``t_X = 3 (P2 − M)``, each side
    its seam slot's ``C − M + own`` minus half the gap, the common cross part at most ``limit``
    × the shorter seam wanted (the seam length safeguard); the seam points ``M + t/3`` on both
    sides of both sub-patches; the midpoint twists' targets (``P + e − M`` plus the net's
    offset) moved onto ``G_LX + G_RX = A_X``, ``G_LY + G_RY = A_Y``, ``G_LX + G_LY = 2 e_L``,
    ``G_RX + G_RY = 2 e_R`` by the min-norm operator; M and ``unit(t_L × t_X)`` into
    ``extra``, ``extra_normals``."""
    stacked = np.empty((8, 3))
    solved = np.empty(4)
    e_l = np.empty(3)
    e_r = np.empty(3)
    t_l = np.empty(3)
    t_x = np.empty(3)
    for e in range(lo, hi):
        hl, hr = edge_halfedges[e, 0], edge_halfedges[e, 1]
        inside = hr >= 0
        kl, kr = hl & 3, hr & 3
        nl = (hl & ~3) | ((hl + 1) & 3)
        nr = (hr & ~3) | ((hr + 1) & 3)
        knl, knr = nl & 3, nr & 3
        # the seam length safeguard (reference: _reference_patches): the star's common cross part
        # D = (own_L − own_R)/2 at most limit × the shorter seam wanted
        keep = 1.0
        if inside:
            size = shorter_l = shorter_r = 0.0
            for d in range(3):
                a = control[hl, place[kl, 3, 1] + d]
                b = control[hr, place[kr, 3, 1] + d]
                shorter_l += a * a
                shorter_r += b * b
                size += 0.25 * (a - b) * (a - b)
            shorter = np.sqrt(min(shorter_l, shorter_r))
            size = np.sqrt(size)
            if size > 0.0 and limit * shorter < size:
                keep = limit * shorter / size
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
            if inside:
                along = 0.5 * mu[e] * t_x[d]
                cross_part = keep * 0.5 * (seam_l - seam_r)
                t_l[d] = along + cross_part
                t_r = along - cross_part
            else:
                t_l[d] = seam_l
                t_r = 0.0
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
    by the min-norm operator at ``operators[table[open, n]:]`` (none where ``table`` is −1); both
    sides relative to V, as the reference solves them."""
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
            for d in range(3):  # relative to V (see the reference)
                o1, o2 = curve[e, near, d], curve[e, 1 + near // 2, d]
                arm = o1 - pos[v, d]
                stacked[j, d] = arm + (curve[ep, far, d] - pos[v, d]) + control[h, slot + d]
                if j >= is_open:
                    stacked[n + j - is_open, d] = (
                        2.0 * arm + (2.0 * lam * (o2 - o1) - slope * arm) / 3.0
                    )
        offset = table[is_open, n]
        columns = 2 * n - is_open
        for j in range(n):
            h = ring_halfedges[start + j]
            slot = place[h & 3, 1, 1]
            for d in range(3):
                if offset < 0:
                    control[h, slot + d] = pos[v, d] + stacked[j, d]
                    continue
                total = 0.0
                for i in range(columns):
                    total += operators[offset + j * columns + i] * stacked[i, d]
                control[h, slot + d] = pos[v, d] + total


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


def _compiled_patches(given: SplitInputs) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`~g1patch.construct.split4.assembly.split4_patches`' controls (4F, 48), edge
    midpoints and face centres (E + F, 3) and their unit normals by the kernels above, ranges side
    by side (:func:`~g1patch.kernels.in_chunks`)."""
    targets, guide, stars, ends, mu, corners, centre, scale = given
    topology = targets.topology
    n_faces, n_edges = topology.n_faces, topology.n_edges
    pos = np.ascontiguousarray(targets.positions, dtype=np.float64)
    star = np.ascontiguousarray(stars.star)
    ends = np.ascontiguousarray(ends)
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
        partial(kernel, pos, star, ends, mu, edge_halfedges, origin, slot_out, slot_in, curve),
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
        partial(
            kernel,
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
        ),
        n_faces,
    )

    inner, outer = _operator(_MIDPOINT), _operator(np.ones((1, 2)))
    kernel = jit_kernel(_edge_kernel)
    in_chunks(
        partial(
            kernel,
            curve,
            mu,
            ends,
            edge_halfedges,
            _PLACE,
            inner,
            outer,
            STAR_LENGTH_LIMIT,
            scale,
            centre,
            control,
            extra,
            extra_normals,
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
        partial(
            kernel,
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
        ),
        topology.n_vertices,
    )
    del curve

    corners = np.ascontiguousarray(corners, dtype=np.float64)
    face_operator = _operator(_cycle(4, closed=True))
    kernel = jit_kernel(_centre_kernel)
    in_chunks(
        partial(kernel, corners, topology.faces, face_operator, _PLACE, scale, centre, control),
        n_faces,
    )
    return control, extra, extra_normals
