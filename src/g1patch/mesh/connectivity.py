"""Half-edge connectivity of polygons given as flat ``corners`` with ``sizes`` (:func:`_connect`):
half-edges paired into edges, the ring of outgoing half-edges around every vertex, and the checks
that fall out of building them (at most two faces per edge, in opposite directions; one fan per
vertex; interior valence at least 3), each naming the item at fault.

The NumPy code is the reference; from :data:`KERNEL_HALFEDGES` half-edges on a compiled kernel
(:func:`_connect_kernel`) builds the same arrays, and where it finds a problem the reference runs
and names it. :class:`~g1patch.mesh.QuadTopology` holds the result for quads.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import NonManifoldError, OrientationError, ValenceError
from .faces import _following_corner
from .validate import _all_of, _check_index_range, _check_repeated_vertices, _few

__all__ = ["KERNEL_HALFEDGES"]

IntArray = NDArray[np.int64]


class _EdgePairing(NamedTuple):
    edges: IntArray  # (ne, 2) sorted vertex pairs
    halfedge_edge: IntArray  # (nh,)
    edge_halfedges: IntArray  # (ne, 2), second -1 on the boundary


def _face_of(halfedges: ArrayLike, face_ends: IntArray) -> IntArray:
    """The face of each half-edge (corner), for faces ending at ``face_ends = cumsum(sizes)``."""
    return np.searchsorted(face_ends, halfedges, side="right")


def _pair_halfedges(
    origin: IntArray, target: IntArray, face_ends: IntArray, n_vertices: int
) -> _EdgePairing:
    """Group half-edges by undirected edge ``key = min·nv + max`` (one sort) and check each group.

    An edge may have at most two half-edges (else :class:`NonManifoldError`), and two of them must
    run in opposite directions (else :class:`OrientationError`).
    """
    key = np.minimum(origin, target) * n_vertices + np.maximum(origin, target)
    order = np.argsort(key)
    sorted_key = key[order]
    is_first = np.empty(key.size, dtype=bool)
    is_first[0] = True
    np.not_equal(sorted_key[1:], sorted_key[:-1], out=is_first[1:])
    first = np.flatnonzero(is_first)
    count = np.diff(np.append(first, key.size))

    crowded = np.flatnonzero(count > 2)
    if crowded.size:
        e = crowded[0]
        h = order[first[e] : first[e] + count[e]]
        raise NonManifoldError(
            f"edge {divmod(int(key[h[0]]), n_vertices)} is used by {count[e]} faces "
            f"({_few(_face_of(np.sort(h), face_ends))}); an edge may have at most 2"
            + _all_of(crowded, "edges")
        )

    a = order[first]
    b = np.where(count == 2, order[np.minimum(first + 1, key.size - 1)], -1)
    paired = b >= 0
    same_direction = np.flatnonzero(paired & (origin[a] == origin[np.maximum(b, 0)]))
    if same_direction.size:
        e = same_direction[0]
        raise OrientationError(
            f"faces {_face_of(a[e], face_ends)} and {_face_of(b[e], face_ends)} both traverse edge "
            f"{origin[a[e]]} -> {target[a[e]]} in the same direction; neighbouring faces must be "
            f"oriented consistently" + _all_of(same_direction, "edges")
        )

    halfedge_edge = np.empty(key.size, dtype=np.int64)
    halfedge_edge[order] = np.cumsum(is_first) - 1
    edge_halfedges = np.stack(
        [np.where(paired, np.minimum(a, b), a), np.where(paired, np.maximum(a, b), -1)], axis=1
    )
    edge_keys = sorted_key[first]
    edges = np.stack([edge_keys // n_vertices, edge_keys % n_vertices], axis=1)
    return _EdgePairing(edges, halfedge_edge, edge_halfedges)


@dataclass(frozen=True, eq=False)
class _Connectivity:
    """The half-edge arrays :func:`_connect` computes: the base of
    :class:`~g1patch.mesh.QuadTopology`, which adds the faces, the vertex count and the boundary
    edges."""

    twin: IntArray
    edges: IntArray
    halfedge_edge: IntArray
    edge_halfedges: IntArray
    valence: IntArray
    face_count: IntArray
    is_boundary_vertex: NDArray[np.bool_]
    ring_offsets: IntArray
    ring_halfedges: IntArray
    neighbor_offsets: IntArray
    neighbors: IntArray


#: from this many half-edges on (``compiled=None``) :func:`_connect` runs :func:`_connect_kernel`
#: (20 000 quads, as ``continuity.KERNEL_PATCHES``: a fresh install's first use compiles it, a few
#: seconds)
KERNEL_HALFEDGES = 80_000


def _connect(
    corners: IntArray, sizes: IntArray, n_vertices: int, *, compiled: bool | None = None
) -> _Connectivity:
    """Half-edge connectivity of polygons given as flat ``corners`` with ``sizes``, validated.

    Half-edge ``h`` is corner ``h``, running to the next corner of its face; unused vertices get
    empty rings. Checks, in order: index range, repeated vertex, edges (at most two faces,
    opposite directions), one fan per vertex, interior valence ≥ 3. ``compiled`` (default: from
    :data:`KERNEL_HALFEDGES` half-edges on): by :func:`_connect_kernel`, the same arrays; where it
    finds a problem, the NumPy code below, the reference, runs and names it.
    """
    _check_index_range(corners, sizes, n_vertices)
    _check_repeated_vertices(corners, sizes, n_vertices)
    from ..kernels import jit_kernel, use_kernels  # numba, imported on first use

    if use_kernels(corners.size >= KERNEL_HALFEDGES) if compiled is None else compiled:
        outcome = cast(tuple[Any, ...], jit_kernel(_connect_kernel)(corners, sizes, n_vertices))
        valid, *arrays = outcome
        if valid:
            return _Connectivity(*arrays)
    halfedges = np.arange(corners.size, dtype=np.int64)
    following = _following_corner(sizes)
    preceding = np.empty_like(following)
    preceding[following] = halfedges
    face_ends = np.cumsum(sizes)
    target = corners[following]
    pairing = _pair_halfedges(corners, target, face_ends, n_vertices)
    twin = np.full(corners.size, -1, dtype=np.int64)
    paired = pairing.edge_halfedges[pairing.edge_halfedges[:, 1] >= 0]
    twin[paired[:, 0]] = paired[:, 1]
    twin[paired[:, 1]] = paired[:, 0]

    face_count = np.bincount(corners, minlength=n_vertices)
    boundary_out = np.flatnonzero(twin < 0)
    open_fans = np.bincount(corners[boundary_out], minlength=n_vertices)
    if (open_fans > 1).any():
        _raise_fans(np.flatnonzero(open_fans > 1), corners, face_ends, face_count)
    is_boundary_vertex = open_fans == 1

    # each ring starts at the outgoing boundary half-edge, or else at the smallest outgoing one
    start = np.full(n_vertices, corners.size, dtype=np.int64)
    np.minimum.at(start, corners, halfedges)
    start[corners[boundary_out]] = boundary_out
    ring_offsets = np.concatenate([[0], np.cumsum(face_count)])
    fans = _Fans(face_count, ring_offsets, twin, preceding, corners, face_ends)
    ring = _walk_rings(start, fans)
    visited = np.zeros(corners.size, dtype=bool)
    visited[ring] = True
    if not visited.all():  # a closed fan came round before visiting all faces of its vertex
        _raise_fans(np.unique(corners[~visited]), corners, face_ends, face_count)

    valence = np.bincount(pairing.edges.ravel(), minlength=n_vertices)
    low = np.flatnonzero(~is_boundary_vertex & (face_count > 0) & (valence < 3))
    if low.size:
        raise ValenceError(
            f"interior vertex {low[0]} has valence {valence[low[0]]}; an interior vertex needs at "
            "least 3 edges" + _all_of(low, "vertices")
        )

    # neighbours: the ring's targets, then at a boundary vertex the origin of prev(last)
    neighbor_offsets = np.concatenate([[0], np.cumsum(face_count + is_boundary_vertex)])
    neighbors = np.empty(neighbor_offsets[-1], dtype=np.int64)
    boundary_before = np.repeat(neighbor_offsets[:-1] - ring_offsets[:-1], face_count)
    neighbors[halfedges + boundary_before] = target[ring]
    boundary = np.flatnonzero(is_boundary_vertex)
    neighbors[neighbor_offsets[boundary + 1] - 1] = corners[
        preceding[ring[ring_offsets[boundary + 1] - 1]]
    ]
    counts = (valence, face_count, is_boundary_vertex)
    return _Connectivity(twin, *pairing, *counts, ring_offsets, ring, neighbor_offsets, neighbors)


#: half-edges sharing their smaller vertex that :func:`_connect_kernel` sorts (by insertion); a
#: vertex that is the smaller end of more leaves the mesh to the NumPy code
_KERNEL_BUCKET = 256


def _connect_kernel(corners: IntArray, sizes: IntArray, n_vertices: int) -> tuple:
    """:func:`_connect`'s arrays, compiled by :func:`~g1patch.kernels.jit_kernel`, with
    ``valid`` first: False (the other arrays unset) where a check of :func:`_connect` fails or a
    vertex is the smaller end of more than :data:`_KERNEL_BUCKET` half-edges.

    Half-edges are bucketed by their smaller vertex (a counting sort), each bucket sorted by the
    larger vertex, then ``h``, so edges come in the reference's lexicographic order; rings are
    walked vertex by vertex. Indices must be in range.
    """
    nh = corners.size
    quads = sizes.size * 4 == nh and (sizes == 4).all()
    following = np.empty(0 if quads else nh, dtype=np.int64)  # of quads: (h & ~3) | ((h + 1) & 3)
    at = 0
    for f in range(0 if quads else sizes.size):
        for k in range(sizes[f]):
            following[at + k] = at + (k + 1) % sizes[f]
        at += sizes[f]
    preceding = np.empty(0 if quads else nh, dtype=np.int64)
    for h in range(0 if quads else nh):
        preceding[following[h]] = h
    bucket = np.zeros(n_vertices + 1, dtype=np.int64)
    for h in range(nh):  # counting sort by the smaller vertex
        bucket[
            min(corners[h], corners[(h & ~3) | ((h + 1) & 3) if quads else following[h]]) + 1
        ] += 1
    for v in range(n_vertices):
        bucket[v + 1] += bucket[v]
    fill = bucket[:-1].copy()
    order = np.empty(nh, dtype=np.int64)
    high = np.empty(nh, dtype=np.int64)  # the larger vertex of order[i]
    for h in range(nh):
        target = corners[(h & ~3) | ((h + 1) & 3) if quads else following[h]]
        low = min(corners[h], target)
        order[fill[low]], high[fill[low]] = h, max(corners[h], target)
        fill[low] += 1
    valid = True
    for v in range(n_vertices):  # by the larger vertex, stable (h increases within a bucket)
        if bucket[v + 1] - bucket[v] > _KERNEL_BUCKET:
            valid = False
            break
        for i in range(bucket[v] + 1, bucket[v + 1]):
            h, key = order[i], high[i]
            j = i - 1
            while j >= bucket[v] and high[j] > key:
                order[j + 1], high[j + 1] = order[j], high[j]
                j -= 1
            order[j + 1], high[j + 1] = h, key

    twin = np.full(nh, -1, dtype=np.int64)
    halfedge_edge = np.empty(nh, dtype=np.int64)
    edges = np.empty(
        (nh, 2), dtype=np.int64
    )  # the first n_edges rows are written (and their pages touched)
    edge_halfedges = np.empty((nh, 2), dtype=np.int64)
    valence = np.zeros(n_vertices, dtype=np.int64)
    n_edges = 0
    for v in range(n_vertices if valid else 0):
        i = bucket[v]
        while i < bucket[v + 1]:
            a = order[i]
            count = 1
            while i + count < bucket[v + 1] and high[i + count] == high[i]:
                count += 1
            if count > 2 or (
                count == 2 and corners[a] == corners[order[i + 1]]
            ):  # crowded, or one direction
                valid = False
                break
            halfedge_edge[a] = n_edges
            edges[n_edges, 0], edges[n_edges, 1] = v, high[i]
            edge_halfedges[n_edges, 0], edge_halfedges[n_edges, 1] = a, -1
            if count == 2:
                b = order[i + 1]
                twin[a], twin[b] = b, a
                halfedge_edge[b] = n_edges
                edge_halfedges[n_edges, 1] = b  # a < b: h increases within a key
            valence[v] += 1
            valence[high[i]] += 1
            n_edges += 1
            i += count
        if not valid:
            break

    face_count = np.zeros(n_vertices, dtype=np.int64)
    is_boundary_vertex = np.zeros(n_vertices, dtype=np.bool_)
    start = fill  # its memory: where each ring starts
    start[:] = nh
    for h in range(nh if valid else 0):
        v = corners[h]
        face_count[v] += 1
        if twin[h] < 0:
            valid = valid and not is_boundary_vertex[v]  # a second boundary fan
            is_boundary_vertex[v] = True
            start[v] = h
        elif not is_boundary_vertex[v]:
            start[v] = min(start[v], h)
    ring_offsets = np.zeros(n_vertices + 1, dtype=np.int64)
    neighbor_offsets = np.zeros(n_vertices + 1, dtype=np.int64)
    for v in range(n_vertices if valid else 0):
        valid = valid and (is_boundary_vertex[v] or face_count[v] == 0 or valence[v] >= 3)
        ring_offsets[v + 1] = ring_offsets[v] + face_count[v]
        neighbor_offsets[v + 1] = neighbor_offsets[v] + face_count[v] + is_boundary_vertex[v]
    ring = order  # its memory: order is read no more
    neighbors = np.empty(neighbor_offsets[n_vertices], dtype=np.int64)
    for v in range(n_vertices if valid else 0):
        h = start[v]
        for k in range(face_count[v]):
            if h < 0 or (
                k > 0 and h == start[v]
            ):  # the boundary, or round a closed fan, before all faces: another fan
                valid = False
                break
            ring[ring_offsets[v] + k] = h
            neighbors[neighbor_offsets[v] + k] = corners[
                (h & ~3) | ((h + 1) & 3) if quads else following[h]
            ]
            h = twin[(h & ~3) | ((h + 3) & 3) if quads else preceding[h]]
        if not valid:
            break
        if is_boundary_vertex[v]:
            last = ring[ring_offsets[v + 1] - 1]
            neighbors[neighbor_offsets[v + 1] - 1] = corners[
                (last & ~3) | ((last + 3) & 3) if quads else preceding[last]
            ]
    pairing = (edges[:n_edges], halfedge_edge, edge_halfedges[:n_edges])
    rings = (ring_offsets, ring, neighbor_offsets, neighbors)
    return (valid, twin, *pairing, valence, face_count, is_boundary_vertex, *rings)


#: ring positions written one rotation step at a time (for all vertices at once); the rest of the
#: rings of vertices with more faces are ranked by pointer jumping, so a 100 000-valent vertex
#: costs ``log2`` rounds instead of 100 000 steps
_WALK_STEPS = 32


class _Fans(NamedTuple):
    """What the ring walk reads: per vertex its face count and ring offset; per half-edge its
    twin, its predecessor in its face and its origin; the faces' ends (for the errors)."""

    face_count: IntArray
    ring_offsets: IntArray
    twin: IntArray
    preceding: IntArray
    corners: IntArray
    face_ends: IntArray


def _walk_rings(start: IntArray, fans: _Fans) -> IntArray:
    """Write ``h_{i+1} = twin(prev(h_i))`` from ``start`` for every vertex at once, one rotation
    step at a time.

    Vertices are sorted by decreasing face count, so the vertices still walking at step ``i`` are
    a prefix of that order. Running into the boundary early means a second fan. After
    :data:`_WALK_STEPS` steps the remaining positions are ranked (:func:`_rank_ring_tails`).
    """
    face_count, ring_offsets, twin, preceding, corners, face_ends = fans
    order = np.argsort(-face_count, kind="stable")
    walking = np.searchsorted(-face_count[order], -np.arange(int(face_count.max())), side="left")
    ring = np.empty(int(ring_offsets[-1]), dtype=np.int64)
    current = start[order]
    for step, count in enumerate(walking[:_WALK_STEPS]):
        h = current[:count]
        stuck = h < 0
        if stuck.any():
            _raise_fans(order[:count][stuck], corners, face_ends, face_count)
        ring[ring_offsets[order[:count]] + step] = h
        current[:count] = twin[preceding[h]]
    if walking.size > _WALK_STEPS:
        tail = order[: walking[_WALK_STEPS]]
        _rank_ring_tails(ring, tail, current[: tail.size], fans)
    return ring


def _rank_ring_tails(ring: IntArray, tail: IntArray, first: IntArray, fans: _Fans) -> None:
    """Ring positions ``_WALK_STEPS`` onwards of the vertices ``tail``, whose walk has reached
    ``first``.

    The half-edges left are those of ``tail`` not yet written; each points to its successor
    ``twin(prev(h))`` among them (the walk ends at the boundary or back at a written one).
    Pointer jumping gives each its distance ``d`` to the end of its chain, so ``h`` sits at
    ``_WALK_STEPS + d(first) - d(h)``. A chain from ``first`` shorter than the rest of the ring
    means a second fan.
    """
    face_count, ring_offsets, twin, preceding, corners, face_ends = fans
    in_tail = np.zeros(face_count.size, dtype=bool)
    in_tail[tail] = True
    written = np.zeros(corners.size, dtype=bool)
    written[ring[(ring_offsets[tail][:, None] + np.arange(_WALK_STEPS)).ravel()]] = True
    left = np.flatnonzero(in_tail[corners] & ~written)
    local = np.full(corners.size + 1, -1, dtype=np.int64)  # local[-1] = -1: past the boundary
    local[left] = np.arange(left.size)
    successor = local[twin[preceding[left]]]
    distance = (successor >= 0).astype(np.int64)
    for _ in range(int(face_count.max()).bit_length()):
        live = np.flatnonzero(successor >= 0)
        if not live.size:
            break
        distance[live] += distance[successor[live]]
        successor[live] = successor[successor[live]]
    head = local[first]
    short = (head < 0) | (
        np.where(head >= 0, distance[head], 0) + 1 != face_count[tail] - _WALK_STEPS
    )
    if short.any():
        _raise_fans(tail[short], corners, face_ends, face_count)
    rank = np.zeros(face_count.size, dtype=np.int64)
    rank[tail] = distance[head]
    v = corners[left]
    ring[ring_offsets[v] + _WALK_STEPS + rank[v] - distance] = left


def _raise_fans(
    vertices: IntArray, corners: IntArray, face_ends: IntArray, face_count: IntArray
) -> None:
    v = int(vertices[0])
    faces = _face_of(np.flatnonzero(corners == v), face_ends)
    raise NonManifoldError(
        f"the {face_count[v]} faces around vertex {v} ({_few(faces, 8)}) form more than one fan; "
        f"the faces at a vertex must form a single fan" + _all_of(vertices, "vertices")
    )
