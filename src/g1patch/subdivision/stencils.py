"""The limit stencils of one level without fractional sharpness (the masks are told in
:mod:`g1patch.subdivision`): limit positions, and per ring slot the limit tangents, the stars and
the sectors' normals. ``compiled``: the smooth vertices by the numba kernels of
:mod:`g1patch.subdivision.stencil_kernels`, bit for bit the NumPy code's values; the NumPy code
does the crease and corner vertices either way.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..kernels import jit_kernel
from ..mesh import INFINITE_SHARPNESS, QuadTopology
from .features import (
    RULE_CORNER,
    RULE_CREASE,
    RULE_SMOOTH,
    _end_sums,
    _Level,
    _limit_rules,
    _segment_sum,
)
from .stencil_kernels import _positions_kernel, _stars_kernel

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def _limit_positions(level: _Level, *, compiled: bool) -> FloatArray:
    """Limit positions (:mod:`g1patch.subdivision`). ``compiled``: the smooth vertices by
    :func:`~g1patch.subdivision.stencil_kernels._positions_kernel`, bit for bit the NumPy
    reference's values."""
    topology, x = level.topology, level.x
    nv = topology.n_vertices
    rule = _limit_rules(level)
    if compiled:
        points = x.copy()  # corners stay
        creased = np.flatnonzero(rule == RULE_CREASE)
        if creased.size:
            sharp = level.edge >= INFINITE_SHARPNESS
            points[creased] = ((4.0 * x + _end_sums(x, topology.edges, sharp, sharp, nv)) / 6.0)[
                creased
            ]
        jit_kernel(_positions_kernel)(
            x,
            topology.faces,
            topology.ring_offsets,
            topology.ring_halfedges,
            rule == RULE_SMOOTH,
            points,
        )
        return points
    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    neighbours = _segment_sum(origin, x[topology.target(h)], nv)
    opposite = _segment_sum(origin, x[topology.origin(QuadTopology.next(QuadTopology.next(h)))], nv)
    n = topology.face_count[:, None].astype(np.float64)
    smooth = (n * n * x + 4.0 * neighbours + opposite) / (n * (n + 5.0))
    sharp = level.edge >= INFINITE_SHARPNESS
    crease = (4.0 * x + _end_sums(x, topology.edges, sharp, sharp, nv)) / 6.0
    return np.select(
        [rule[:, None] == RULE_SMOOTH, rule[:, None] == RULE_CREASE], [smooth, crease], x
    )


def _by_valence(
    n: IntArray, i: IntArray, table: Callable[[IntArray, IntArray], tuple[FloatArray, ...]]
) -> tuple[FloatArray, ...]:
    """``table(n, i)`` for many entries, evaluated once per distinct ``(n, i)`` (valences
    repeat)."""
    valences = np.unique(n)
    if len(valences) * int(valences.max(initial=0)) > len(n):
        return table(n, i)
    starts = np.concatenate([[0], np.cumsum(valences)])
    keys = np.repeat(valences, valences), np.arange(starts[-1]) - np.repeat(starts[:-1], valences)
    rows = starts[np.searchsorted(valences, n)] + i
    return tuple(column[rows] for column in table(*keys))


def _interior_mask_weights(
    n: IntArray, i: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Weights of ``E_i`` and ``D_i`` in the scaled eigen tangents A (cosines) and B (sines) at
    valence n."""
    theta = 2.0 * np.pi / n
    cos_t = np.cos(theta)
    lam = 5.0 / 16.0 + (cos_t + np.cos(0.5 * theta) * np.sqrt(2.0 * (9.0 + cos_t))) / 16.0
    c = 1.0 / (4.0 * lam - 1.0)
    scale = 1.0 / (2.0 * n + c * n * (1.0 + cos_t))
    a0, a1 = i * theta, (i + 1) * theta
    return (
        scale * 4.0 * np.cos(a0),
        scale * c * (np.cos(a0) + np.cos(a1)),
        scale * 4.0 * np.sin(a0),
        scale * c * (np.sin(a0) + np.sin(a1)),
    )


@cache
def _cross_mask(k: int) -> tuple[float, FloatArray, FloatArray]:
    """The across-crease tangent mask of a crease sector with k faces: ``(w_V, w_E (k + 1), w_D
    (k))``.

    k = 2: the B-spline's ``(−4V − E_0 + 4E_1 − E_2 + D_0 + D_1)/6``; k = 1 (its subdominant
    eigenvalue 1/4 is double): OpenSubdiv's ``3(E_0 + E_1) − 6V``. Otherwise the left eigenvector
    of the sector's subdivision matrix (crease rule at V, midpoints on the sharp edges, smooth rules
    inside) that is symmetric under the reflection ``E_i ↔ E_{k−i}``, ``D_i ↔ D_{k−1−i}`` with the
    largest eigenvalue below 1, scaled to unit response on the planar half-fan (``E_i`` at angle
    ``πi/k``, ``D_i = E_i + E_{i+1}``) and signed to point into the faces. OpenSubdiv's Biermann et
    al. mask is derived for modified rules: on its own rules its plane is 7–17° off for k = 3–6.
    For k ≥ 5 the ring has a third eigenvalue above 1/2, so the limit surface is not tangent-plane
    continuous there and this plane is the one through the crease's own modes.
    """
    if k == 1:
        return -6.0, np.array([3.0, 3.0]), np.zeros(1)
    if k == 2:
        return -4.0 / 6.0, np.array([-1.0, 4.0, -1.0]) / 6.0, np.array([1.0, 1.0]) / 6.0
    size = 2 * k + 2
    unit = np.eye(size)
    edge, diagonal = unit[1 : k + 2], unit[k + 2 :]
    face_points = 0.25 * (unit[0] + edge[:-1] + diagonal + edge[1:])
    matrix = np.empty((size, size))
    matrix[0] = (6.0 * unit[0] + edge[0] + edge[k]) / 8.0
    matrix[1] = 0.5 * (unit[0] + edge[0])
    matrix[k + 1] = 0.5 * (unit[0] + edge[k])
    matrix[2 : k + 1] = 0.25 * (unit[0] + edge[1:k] + face_points[:-1] + face_points[1:])
    matrix[k + 2 :] = face_points
    values, vectors = np.linalg.eig(matrix.T)
    mirror = np.concatenate([[0], 1 + np.arange(k + 1)[::-1], k + 2 + np.arange(k)[::-1]])
    vectors = vectors.real / np.linalg.norm(vectors.real, axis=0)
    symmetric = (np.abs(values.imag) < 1e-12) & (
        np.abs(vectors - vectors[mirror]).max(axis=0) < 1e-9
    )
    candidates = np.flatnonzero(symmetric & (values.real < 1.0 - 1e-9))
    mask = vectors[:, candidates[np.argmax(values.real[candidates])]]
    angles = np.pi * np.arange(k + 1) / k
    planar = np.concatenate([[0.0], np.sin(angles), np.sin(angles[:-1]) + np.sin(angles[1:])])
    mask = mask / (mask @ planar)
    return float(mask[0]), mask[1 : k + 2], mask[k + 2 :]


class _Frames(NamedTuple):
    """Limit frames of a level: slot tangents (S, 3), the stars ``a``, ``b`` (V, 3) and, where
    asked, the unit normal of each ring entry's sector (``ring_halfedges`` order)."""

    tangents: FloatArray
    a: FloatArray
    b: FloatArray
    ring_normals: FloatArray | None = None


def _where(mask: BoolArray) -> BoolArray | slice:
    """``mask`` for indexing, or the whole axis (a view, no copy) where it is all true."""
    return slice(None) if mask.all() else mask


def _slot_rotation(n: IntArray, j: IntArray) -> tuple[FloatArray, FloatArray]:
    phi = 2.0 * np.pi * j / n
    return np.cos(phi), np.sin(phi)


def _unit(v: FloatArray) -> FloatArray:
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


#: a corner sector's bounding chords closer to parallel than this (sine) span no plane
CORNER_PLANE_SINE = 0.02


def _corner_plane(fan: FloatArray, start: FloatArray, end: FloatArray) -> FloatArray:
    """A corner sector's normal (not unit): the plane of its bounding chords ``start × end``
    (their limit tangents: the sharp curves end there along them, so the sector's tangent plane
    holds both), turned to the side of the sector's ``fan`` sum ``Σ t_i × t_{i+1}``; where the two
    are nearly parallel (:data:`CORNER_PLANE_SINE`: a crease running straight through the corner)
    the fan sum made perpendicular to their common line ``d ∥ ŝ − ê``. The fan sum alone is not
    perpendicular to the chords of a sector of two faces or more, and the chords, shared by the
    sectors on both sides of a crease, are not projected: G1 inside the sector broke at the
    corner (49° on a fitted cage)."""
    plane = np.cross(start, end)
    lengths = np.linalg.norm(start, axis=1) * np.linalg.norm(end, axis=1)
    spanned = np.linalg.norm(plane, axis=1) >= CORNER_PLANE_SINE * lengths
    along = _unit(_unit(start) - _unit(end))
    straight = fan - np.einsum("sd,sd->s", fan, along)[:, None] * along
    turned = np.where((np.einsum("sd,sd->s", plane, fan) < 0)[:, None], -plane, plane)
    return np.where(spanned[:, None], turned, straight)


def _limit_frames(level: _Level, *, compiled: bool, corners: bool = False) -> _Frames:
    """Slot tangents, stars and (``corners``) sector normals of a level without fractional sharpness
    (:mod:`g1patch.subdivision`). ``compiled``: the smooth vertices' stars and tangents by
    :func:`~g1patch.subdivision.stencil_kernels._stars_kernel` (bit for bit the NumPy values), the
    NumPy code then only at the crease and corner vertices."""
    topology, x = level.topology, level.x
    nv = topology.n_vertices
    offsets = topology.neighbor_offsets
    k = topology.face_count
    boundary = topology.is_boundary_vertex
    rule = _limit_rules(level)
    slot_count = np.diff(offsets)
    smooth = rule == RULE_SMOOTH
    tangents = np.zeros((int(offsets[-1]), 3))
    a = np.zeros((nv, 3))
    b = np.zeros((nv, 3))
    kernel = compiled
    # the vertices the NumPy code below handles (all, or those the kernel leaves), their slots and
    # ring entries
    chosen = np.flatnonzero(~smooth) if kernel else np.arange(nv)
    slot_vertex = np.repeat(chosen, slot_count[chosen])
    slot = np.arange(len(slot_vertex)) - np.repeat(
        np.cumsum(slot_count[chosen]) - slot_count[chosen], slot_count[chosen]
    )
    slot_index = offsets[slot_vertex] + slot
    ring_vertex = np.repeat(chosen, k[chosen])
    i = np.arange(len(ring_vertex)) - np.repeat(np.cumsum(k[chosen]) - k[chosen], k[chosen])
    ring_index = topology.ring_offsets[ring_vertex] + i
    h = topology.ring_halfedges[ring_index]
    ring_slot = offsets[ring_vertex] + i
    e_i = x[topology.target(h)]
    d_i = x[topology.origin(QuadTopology.next(QuadTopology.next(h)))]

    slot_edge = np.empty(len(tangents), dtype=np.int64)  # written and read at the chosen slots only
    slot_edge[ring_slot] = topology.halfedge_edge[h]
    rims = chosen[boundary[chosen]]
    slot_edge[offsets[rims + 1] - 1] = topology.halfedge_edge[
        QuadTopology.prev(topology.ring_halfedges[topology.ring_offsets[rims + 1] - 1])
    ]
    slot_sharp = np.zeros(len(tangents), dtype=bool)
    slot_sharp[slot_index] = level.edge[slot_edge[slot_index]] >= INFINITE_SHARPNESS
    sharp_slots = np.flatnonzero(slot_sharp[slot_index])  # positions in the chosen slots
    first = np.zeros(nv, dtype=np.int64)
    last = np.zeros(nv, dtype=np.int64)
    owners, at_first = np.unique(slot_vertex[sharp_slots], return_index=True)
    first[owners] = slot[sharp_slots[at_first]]
    owners, at_last = np.unique(slot_vertex[sharp_slots[::-1]], return_index=True)
    last[owners] = slot[sharp_slots[::-1][at_last]]

    # smooth: the eigen tangents
    if kernel and smooth.any():
        valences = np.unique(k[smooth])
        starts = np.concatenate([[0], np.cumsum(valences)])
        keys = (
            np.repeat(valences, valences),
            np.arange(starts[-1]) - np.repeat(starts[:-1], valences),
        )
        start_of = np.zeros(int(valences[-1]) + 1, dtype=np.int64)
        start_of[valences] = starts[:-1]
        jit_kernel(_stars_kernel)(
            x,
            topology.faces,
            topology.ring_offsets,
            topology.ring_halfedges,
            offsets,
            smooth,
            start_of,
            np.stack(_interior_mask_weights(*keys)),
            np.stack(_slot_rotation(*keys)),
            a,
            b,
            tangents,
        )
    elif smooth.any():
        on_ring = _where(smooth[ring_vertex])
        rv = ring_vertex[on_ring]
        ea, da, eb, db = _by_valence(k[rv], i[on_ring], _interior_mask_weights)
        a += _segment_sum(rv, ea[:, None] * e_i[on_ring] + da[:, None] * d_i[on_ring], nv)
        b += _segment_sum(rv, eb[:, None] * e_i[on_ring] + db[:, None] * d_i[on_ring], nv)
        at = _where(smooth[slot_vertex])
        sv = slot_vertex[at]
        cos_phi, sin_phi = _by_valence(k[sv], slot[at], _slot_rotation)
        tangents[slot_index[at]] = cos_phi[:, None] * a[sv] + sin_phi[:, None] * b[sv]

    # crease: sector 0 from the first sharp slot p to the second q, sector 1 from q round to p
    crease = rule == RULE_CREASE
    cv = np.flatnonzero(crease)
    along = np.zeros((nv, 3))
    across = np.zeros((2 * cv.size, 3))  # sectors 2c, 2c + 1 of the c-th crease vertex
    if cv.size:
        p, q = first, last
        span = q - p  # faces in sector 0
        along[cv] = 0.5 * (
            x[topology.neighbors[offsets[cv] + p[cv]]] - x[topology.neighbors[offsets[cv] + q[cv]]]
        )
        at = crease[ring_vertex]
        rv, ri = ring_vertex[at], i[at]
        second = (ri < p[rv]) | (ri >= q[rv])
        sector = 2 * np.searchsorted(cv, rv) + second
        start = np.where(second, q[rv], p[rv])
        size = np.where(second, k[rv] - span[rv], span[rv])
        offset = (ri - start) % k[rv]
        ends = np.stack([q[cv], p[cv]], axis=1).ravel()  # the closing slot of sectors 2c, 2c + 1
        sector_size = np.stack([span[cv], k[cv] - span[cv]], axis=1).ravel()
        for count in np.unique(size):
            vertex_weight, spoke, face = _cross_mask(int(count))
            sel = size == count
            o = offset[sel]
            across += _segment_sum(
                sector[sel],
                spoke[o, None] * e_i[at][sel] + face[o, None] * d_i[at][sel],
                2 * cv.size,
            )
            closing = np.flatnonzero(sector_size == count)
            owner = cv[closing // 2]
            across[closing] += (
                vertex_weight * x[owner]
                + spoke[count] * x[topology.neighbors[offsets[owner] + ends[closing]]]
            )
        a[cv] = along[cv]
        b[cv] = across[0::2]
        at = crease[slot_vertex]
        sv, sj = slot_vertex[at], slot[at]
        second = (sj < p[sv]) | (sj > q[sv])
        sector_along = np.where(second[:, None], -along[sv], along[sv])
        sector_across = across[2 * np.searchsorted(cv, sv) + second]
        angle = np.pi * np.where(
            second,
            (sj - q[sv]) % k[sv] / np.maximum(k[sv] - span[sv], 1),
            (sj - p[sv]) / np.maximum(span[sv], 1),
        )
        t = np.cos(angle)[:, None] * sector_along + np.sin(angle)[:, None] * sector_across
        t = np.where(
            (sj == p[sv])[:, None], along[sv], np.where((sj == q[sv])[:, None], -along[sv], t)
        )
        tangents[slot_index[at]] = t

    # corner: the chords, a and b on the first sharp slot and the next one
    corner = rule == RULE_CORNER
    if corner.any():
        at = corner[slot_vertex]
        tangents[slot_index[at]] = x[topology.neighbors[slot_index[at]]] - x[slot_vertex[at]]
        corners_at = np.flatnonzero(corner)
        a[corners_at] = tangents[offsets[corners_at] + first[corners_at]]
        b[corners_at] = tangents[
            offsets[corners_at] + (first[corners_at] + 1) % slot_count[corners_at]
        ]

    if not corners:
        return _Frames(tangents, a, b)
    # sector normals: Σ t_i × t_{i+1} over the ring entries of each sector (a × b for one star)
    following = offsets[ring_vertex] + (i + 1) % slot_count[ring_vertex]
    cross = np.cross(tangents[ring_slot], tangents[following])
    shifted = (i - first[ring_vertex]) % slot_count[ring_vertex]
    order = np.lexsort((shifted, ring_vertex))
    starts = slot_sharp[ring_slot]
    label = np.empty(len(h), dtype=np.int64)
    label[order] = np.cumsum(starts[order] | (shifted[order] == 0)) - 1
    fan = _segment_sum(label, cross, int(label.max()) + 1) if len(label) else np.zeros((0, 3))
    if corner.any() and len(label):
        sorted_label = label[order]
        change = sorted_label[1:] != sorted_label[:-1]
        head, tail = order[np.r_[True, change]], order[np.r_[change, True]]  # per sector
        at = corner[ring_vertex[head]]
        fan[at] = _corner_plane(
            fan[at], tangents[ring_slot[head[at]]], tangents[following[tail[at]]]
        )
    ring_normals = _unit(fan)[label]
    star_normals = _unit(np.cross(a, b))
    one_star = smooth[ring_vertex]
    ring_normals[one_star] = star_normals[ring_vertex[one_star]]
    if (
        cv.size
    ):  # each sector's own star (a one-face sector has no second slot tangent off the crease)
        at = crease[ring_vertex]
        rv, ri = ring_vertex[at], i[at]
        second = (ri < first[rv]) | (ri >= last[rv])
        ring_normals[at] = _unit(
            np.cross(
                np.where(second[:, None], -along[rv], along[rv]),
                across[2 * np.searchsorted(cv, rv) + second],
            )
        )
    if not kernel:
        return _Frames(tangents, a, b, ring_normals)
    every = star_normals[np.repeat(np.arange(nv), k)]  # the kernel's smooth vertices: one star each
    every[ring_index] = ring_normals
    return _Frames(tangents, a, b, every)
