"""split4's assembly in NumPy, batched (:func:`_reference_patches`): the reference that the
numba passes (:mod:`~g1patch.construct.split4.compiled`) reproduce to rounding.

The edge curves (:func:`_edge_curves`), the even-valence midpoint shifts, the free choices from the
face's macro net, the centres and their crosses, the midpoint stars and seam points, the twist
targets moved onto their vertex, midpoint and centre systems; then every sub-patch gathered in the
frame of its corner (:func:`_assemble`), back in the input coordinates.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...mesh import QuadTopology
from ...targets import Targets, halfedge_slots
from .nets import (
    _CENTRE,
    _CROSS,
    _LOCAL,
    _SEAM,
    _TWIST_CENTRE,
    _TWIST_MID,
    _TWIST_PREV,
    _TWIST_VERTEX,
    _own_quantities,
)
from .stars import STAR_LENGTH_LIMIT, SplitStar
from .systems import _MIDPOINT, _cycle, _even_vertex_shifts, _min_norm

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class SplitInputs(NamedTuple):
    """What the sub-patches are assembled from, by :func:`_reference_patches` and by the numba
    passes (:func:`~g1patch.construct.split4.compiled._compiled_patches`) alike: the ``targets``
    (local coordinates), the ``guide`` macro nets (F, 7, 7, 3) or None, the ``stars``, each edge's
    star ``c`` at X and at Y (``ends``, (E, 2)) and its shear ``mu`` (E,); and the way back to the
    input coordinates, ``x · scale + centre`` with the ``corners`` (V, 3) at the mesh vertices
    exact."""

    targets: Targets
    guide: FloatArray | None
    stars: SplitStar
    ends: FloatArray
    mu: FloatArray
    corners: FloatArray
    centre: FloatArray
    scale: float


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


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
#: faces per assembly block: sources and output stay in cache
_BLOCK = 1024


def _gather_indices() -> IntArray:
    """Per coordinate of a face's (4, 4, 4, 3) controls its place among the face's sources (4, 13,
    3), by :data:`_FRAME` in the frame of each corner k: one 8-byte copy each."""
    pick = np.empty((4, 4, 4), dtype=np.int64)  # [k, i, j] → row (corner kk) · 13 + source
    for (p, q), (source, from_prev) in _FRAME.items():
        for k in range(4):
            pick[k, _LOCAL[k, p, q, 0], _LOCAL[k, p, q, 1]] = (
                (k - from_prev) % 4
            ) * _N_SOURCES + source
    return (3 * pick.reshape(-1, 1) + np.arange(3)).reshape(-1)


_GATHER = _gather_indices()


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


def _reference_patches(given: SplitInputs) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`~g1patch.construct.split4.assembly.split4_patches`' controls (F, 4, 4, 4, 3), edge
    midpoints and face centres (E + F, 3) and their unit normals."""
    targets, guide, stars, ends, mu, corners, centre, scale = given
    topology = targets.topology
    n_faces = topology.n_faces
    pos = targets.positions
    star = stars.star

    # -- edges: canonical half-edge X → Y (face L), twin Y → X (face R)
    h_l = topology.edge_halfedges[:, 0]
    h_r = topology.edge_halfedges[:, 1]
    interior = h_r >= 0
    x_of, y_of = topology.origin(h_l), topology.target(h_l)
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
    # the guide): what its boundary predicts from the split curves plus the net's detail over that
    # (:data:`_QUANTITIES`); G1 then moves them as little as it requires. A face whose corners'
    # stars the safeguard shrank takes the detail scaled by the smallest factor: its curves are
    # that much shorter than the net's, so the net's full detail would overhang them
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
    # the star split equally (the least change); a boundary midpoint keeps its own; seam points
    # e = M + t/3
    own_seam = np.repeat(centres, 4, axis=0) - m[edge_of] + own[:, _SEAM]
    star_gap = own_seam[h_l] + np.where(interior[:, None], own_seam[h_r], 0.0) - mu[:, None] * t_x
    t_l = own_seam[h_l] - np.where(interior, 0.5, 0.0)[:, None] * star_gap
    t_r = np.where(interior[:, None], own_seam[h_r] - 0.5 * star_gap, 0.0)
    # seam length safeguard: the star makes both seams' cross parts D = (own_L − own_R)/2 equal,
    # the mean of their lengths; between faces of very unequal width (a support loop beside a
    # wide face) that is many times the narrow face's own seam, whose curve then overshoots its
    # centre and folds. D is shortened to STAR_LENGTH_LIMIT × the shorter seam wanted
    cross_part = 0.5 * (t_l - t_r)
    shorter = np.minimum(
        np.linalg.norm(own_seam[h_l], axis=1),
        np.where(interior, np.linalg.norm(own_seam[h_r], axis=1), np.inf),
    )
    size = np.linalg.norm(cross_part, axis=1)
    keep = np.minimum(1.0, STAR_LENGTH_LIMIT * shorter / np.where(size > 0, size, np.inf))
    keep = np.where(interior, keep, 1.0)[:, None]
    along = 0.5 * (t_l + t_r)
    t_l = np.where(interior[:, None], along + keep * cross_part, t_l)
    t_r = np.where(interior[:, None], along - keep * cross_part, 0.0)
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
    # at V relative to V until its ring is solved (below)
    twist[:, 0] = (o1 - corner_points) + (d1[prev] - corner_points) + own[:, _TWIST_VERTEX]
    twist[:, 1] = o2 + seam - m_h + own[:, _TWIST_MID]
    twist[:, 2] = d2[prev] + seam[prev] - m_h[prev] + own[:, _TWIST_PREV]
    twist[:, 3] = b_flat + b_flat[prev] - centre_points + own[:, _TWIST_CENTRE]
    del centre_points, own

    # -- original vertices: F_{j−1} + F_j = R_j over the interior ring edges, solved relative to
    # V (both sides less 2 V): the pseudo-inverse amplifies its right-hand side's rounding by up to
    # ~n/π (eigenvalues 1 + ω^k of the cycle), so that rounding is of the ring's size, not of the
    # model's, and the G1 error no longer grows with the distance from the origin times n
    lam = 2.0 * np.where(
        canonical, ends[edge_of, 0], ends[edge_of, 1]
    )  # λ_j of the slot of h at its origin
    arm = o1 - corner_points
    rhs = 2.0 * arm + (2.0 * lam[:, None] * (o2 - o1) - slope[:, None] * arm) / 3.0
    del arm
    boundary = topology.is_boundary_vertex
    base = int(topology.face_count.max()) + 1
    keys = np.unique(boundary.astype(np.int64) * base + topology.face_count)
    for is_open, n in zip(keys // base, keys % base, strict=True):
        vs = np.flatnonzero((boundary == is_open) & (topology.face_count == n))
        ring = topology.ring_halfedges[topology.ring_offsets[vs][:, None] + np.arange(n)]
        equations = _cycle(int(n), closed=not is_open)
        if equations.size:
            rows = ring if not is_open else ring[:, 1:]
            twist[ring, 0] = _min_norm(equations, rhs[rows], twist[ring, 0])
    twist[:, 0] += corner_points
    del corner_points

    # -- midpoints: G_LX + G_RX = A_X, G_LY + G_RY = A_Y, G_LX + G_LY = 2 e_L, G_RX + G_RY = 2 e_R
    inner = np.flatnonzero(interior)
    a_x = 2.0 * p2 + (2.0 * ends[:, 0, None] * (m - p2) - 2.0 * mu[:, None] * (p2 - p1)) / 3.0
    a_y = 2.0 * p4 + (2.0 * ends[:, 1, None] * (m - p4) + 2.0 * mu[:, None] * (p4 - p5)) / 3.0
    hl, hr = h_l[inner], h_r[inner]
    sides_h = (hl, QuadTopology.next(hr), QuadTopology.next(hl), hr)
    kinds = (1, 2, 2, 1)
    unknowns = np.stack([twist[h, kind] for h, kind in zip(sides_h, kinds, strict=True)], axis=1)
    sides = np.stack([a_x[inner], a_y[inner], 2.0 * e_l[inner], 2.0 * e_r[inner]], axis=1)
    solved = _min_norm(_MIDPOINT, sides, unknowns)
    for column, (h, kind) in enumerate(zip(sides_h, kinds, strict=True)):
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
    return control, extra, extra_normals
