"""Quad mesh topology as flat half-edge arrays, and quad meshes that pair it with positions.

Half-edge ``h = 4 f + k`` runs from corner ``k`` of face ``f`` to corner ``k + 1 (mod 4)``:

    next(h) = 4 (h // 4) + (h % 4 + 1) % 4,     prev(h) = 4 (h // 4) + (h % 4 + 3) % 4,
    next_ccw(h) = twin(prev(h))                 (the next outgoing half-edge counter-clockwise).

Faces are counter-clockwise seen from outside, so the two half-edges of an interior edge run in
opposite directions and a boundary half-edge has its face on the left. :class:`QuadTopology` is
built from faces alone (it never looks at positions), so one topology serves many position sets;
:class:`QuadMesh` adds the positions. Every step is vectorised: the only Python loops run over
rotation steps around a vertex (at most the largest valence) or over ``log2`` of a loop length.

Indices in error messages are 0-based.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .display import bbox_text, picture, short_source
from .errors import (
    DegenerateFaceError,
    InputError,
    MeshError,
    NonManifoldError,
    OrientationError,
    ValenceError,
    as_float_array,
    as_index_array,
)

__all__ = [
    "Tag",
    "Features",
    "Sectors",
    "features_from_tags",
    "sectors",
    "INFINITE_SHARPNESS",
    "MAX_COORDINATE",
    "QuadTopology",
    "QuadMesh",
    "refine_polygons",
    "subdivide",
    "strict_meshes",
    "REPAIRABLE",
    "DEGENERATE_AREA_TOLERANCE",
]

logger = logging.getLogger(__name__)

#: A face is degenerate when ``|d1 × d2| <= tol · max(|d1|, |d2|)²`` for its diagonals d1, d2
#: (twice its vector area against the square of its size).
DEGENERATE_AREA_TOLERANCE = 1e-12

#: OpenSubdiv's infinitely sharp crease (``Sdc::Crease::SHARPNESS_INFINITE``): at or above it an
#: edge or vertex is sharp at every level of refinement
INFINITE_SHARPNESS = 10.0
#: the largest coordinate magnitude accepted (and stored in network files): products of two
#: coordinates and sums of many of them stay far from overflow, and 1e30 of any unit is larger
#: than anything a model describes
MAX_COORDINATE = 1e30
#: the boundary rules of the ``interpolateboundary`` tag, by its integer (OpenSubdiv's numbering)
BOUNDARY_RULES = ("none", "edge-only", "edge-and-corner")
CREASE_METHODS = ("normal", "chaikin")

#: OpenSubdiv tags whose integers are vertex indices, and those whose integers are face indices.
VERTEX_TAGS = frozenset({"crease", "corner"})
FACE_TAGS = frozenset({"hole"})

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]


class Tag(NamedTuple):
    """An OpenSubdiv tag line ``t name nints/nfloats/nstrings ints… floats… strings…``."""

    name: str
    ints: tuple[int, ...] = ()
    floats: tuple[float, ...] = ()
    strings: tuple[str, ...] = ()


def _few(items: ArrayLike, limit: int = 5) -> str:
    """``"3, 7, 9 and 12 more"``: the first ``limit`` items of a list for an error message."""
    values = np.asarray(items).ravel().tolist()
    text = ", ".join(map(str, values[:limit]))
    return text + (f" and {len(values) - limit} more" if len(values) > limit else "")


def _all_of(items: ArrayLike, noun: str) -> str:
    """``" (3 such faces: 1, 4, 9)"``, or nothing when there is only one."""
    count = np.asarray(items).size
    return f" ({count} such {noun}: {_few(items)})" if count > 1 else ""


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


def _next(h: ArrayLike) -> IntArray:
    h = np.asarray(h, dtype=np.int64)
    return (h & ~3) | ((h + 1) & 3)


def _prev(h: ArrayLike) -> IntArray:
    h = np.asarray(h, dtype=np.int64)
    return (h & ~3) | ((h + 3) & 3)


# ----------------------------------------------------------------------------------------------
# Checks shared by quads and general polygons (flat ``corners`` with ``sizes`` per face)


def _check_index_range(corners: IntArray, sizes: IntArray, n_vertices: int) -> None:
    bad = np.flatnonzero((corners < 0) | (corners >= n_vertices))
    if bad.size:
        face = np.repeat(np.arange(sizes.size), sizes)[bad]
        raise MeshError(
            f"face {face[0]} has vertex index {corners[bad[0]]} outside 0..{n_vertices - 1}"
            + _all_of(np.unique(face), "faces")
        )


# : faces of at most this many corners are checked for a repeated vertex pair by pair (n (n - 1) / 2
# pairs)
_PAIRWISE_SIZE = 8


def _check_repeated_vertices(corners: IntArray, sizes: IntArray, n_vertices: int) -> None:
    """A face may not visit a vertex twice: compare corner pairs (all faces of one small size, at
    most :data:`_PAIRWISE_SIZE` corners) or sort (face, vertex) keys (linear in memory for any
    size)."""
    if sizes[0] <= _PAIRWISE_SIZE and (sizes == sizes[0]).all():
        table = corners.reshape(-1, int(sizes[0]))
        repeats = np.zeros(table.shape[0], dtype=bool)
        for i, j in zip(*np.triu_indices(table.shape[1], 1)):
            repeats |= table[:, i] == table[:, j]
        faces = np.flatnonzero(repeats)
    else:
        face = np.repeat(np.arange(sizes.size, dtype=np.int64), sizes)
        keys = np.sort(face * n_vertices + corners)
        faces = np.unique(keys[1:][keys[1:] == keys[:-1]] // n_vertices)
    if faces.size:
        start = int(np.sum(sizes[: faces[0]]))
        face_corners = corners[start : start + sizes[faces[0]]]
        raise DegenerateFaceError(
            f"face {faces[0]} repeats a vertex: corners {tuple(face_corners.tolist())}"
            + _all_of(faces, "faces")
        )


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


# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class QuadTopology:
    """Half-edge connectivity of a manifold, consistently oriented quad mesh; build it with
    :meth:`from_faces`.

    All arrays are int64 (or bool) and read-only. Edges are sorted vertex pairs in lexicographic
    order; ``edge_halfedges`` lists an edge's half-edges by increasing id.

    ``ring_halfedges[ring_offsets[v]:ring_offsets[v+1]]`` are the outgoing half-edges of ``v``
    counter-clockwise, ``h_{i+1} = twin(prev(h_i))``. At a boundary vertex the list starts at the
    outgoing boundary half-edge (``twin = -1``); it always has ``face_count[v]`` entries.
    ``neighbors`` holds the targets of those half-edges and, at a boundary vertex, one more:
    ``origin(prev(last))``, the far end of the incoming boundary edge. ``valence`` counts edges,
    so it is ``face_count`` inside and ``face_count + 1`` on the boundary.
    """

    faces: IntArray
    n_vertices: int
    twin: IntArray
    edges: IntArray
    halfedge_edge: IntArray
    edge_halfedges: IntArray
    is_boundary_edge: NDArray[np.bool_]
    valence: IntArray
    face_count: IntArray
    is_boundary_vertex: NDArray[np.bool_]
    ring_offsets: IntArray
    ring_halfedges: IntArray
    neighbor_offsets: IntArray
    neighbors: IntArray

    @classmethod
    def from_faces(cls, faces: ArrayLike, n_vertices: int | None = None) -> QuadTopology:
        """Build and validate the topology of ``faces`` (nf, 4) over vertices ``0..n_vertices-1``.

        Raises :class:`MeshError` (index out of range, unused vertex), :class:`DegenerateFaceError`
        (repeated vertex), :class:`NonManifoldError` (edge with > 2 faces, vertex with > 1 fan),
        :class:`OrientationError` or :class:`ValenceError` (interior valence < 3), naming the item.
        """
        quads = as_index_array("faces", faces, (4,))
        if quads.ndim != 2:
            raise InputError(f"faces: expected shape (nf, 4), got {quads.shape}")
        if quads.shape[0] == 0:
            raise MeshError("the mesh has no faces")
        nv = int(quads.max()) + 1 if n_vertices is None else int(n_vertices)
        quads = quads.copy()
        connectivity = _connect(quads.ravel(), np.full(quads.shape[0], 4, dtype=np.int64), nv)
        unused = np.flatnonzero(connectivity.face_count == 0)
        if unused.size:
            raise MeshError(
                f"vertices {_few(unused)} are used by no face; QuadMesh.from_arrays drops unused "
                "vertices"
            )
        is_boundary_edge = connectivity.edge_halfedges[:, 1] < 0
        return cls(
            faces=quads, n_vertices=nv, is_boundary_edge=is_boundary_edge, **connectivity._asdict()
        )

    def __post_init__(self) -> None:
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False

    def _counts(self) -> str:
        boundary = int(self.is_boundary_edge.sum())
        shape = "closed" if not boundary else f"open ({boundary} boundary edges)"
        return f"{self.n_vertices} vertices, {self.n_faces} quads, {self.n_edges} edges, {shape}"

    def __repr__(self) -> str:
        """``<QuadTopology 8 vertices, 6 quads, 12 edges, closed>``: counts, never the arrays."""
        return f"<QuadTopology {self._counts()}>"

    # -- half-edge arithmetic ------------------------------------------------------------------

    @staticmethod
    def next(h: ArrayLike) -> IntArray:
        """The following half-edge in the same face: ``4 (h // 4) + (h % 4 + 1) % 4``."""
        return _next(h)

    @staticmethod
    def prev(h: ArrayLike) -> IntArray:
        """The preceding half-edge in the same face: ``4 (h // 4) + (h % 4 + 3) % 4``."""
        return _prev(h)

    def origin(self, h: ArrayLike) -> IntArray:
        """The vertex half-edge ``h`` starts from: ``faces.ravel()[h]``."""
        return self.faces.ravel()[np.asarray(h, dtype=np.int64)]

    def target(self, h: ArrayLike) -> IntArray:
        """The vertex half-edge ``h`` points to: ``origin(next(h))``."""
        return self.faces.ravel()[_next(h)]

    def next_ccw(self, h: ArrayLike) -> IntArray:
        """The next outgoing half-edge counter-clockwise about ``origin(h)``: ``twin(prev(h))`` (-1
        past a boundary)."""
        return self.twin[_prev(h)]

    def ring(self, v: int) -> IntArray:
        """Outgoing half-edges of vertex ``v``, counter-clockwise."""
        return self.ring_halfedges[self.ring_offsets[v] : self.ring_offsets[v + 1]]

    def one_ring(self, v: int) -> IntArray:
        """Neighbour vertices of ``v``, counter-clockwise."""
        return self.neighbors[self.neighbor_offsets[v] : self.neighbor_offsets[v + 1]]

    # -- counts and global structure ------------------------------------------------------------

    @property
    def n_faces(self) -> int:
        return int(self.faces.shape[0])

    @property
    def n_edges(self) -> int:
        return int(self.edges.shape[0])

    @property
    def n_halfedges(self) -> int:
        return 4 * self.n_faces

    @property
    def is_closed(self) -> bool:
        return not bool(self.is_boundary_edge.any())

    @property
    def euler_characteristic(self) -> int:
        """χ = V − E + F."""
        return self.n_vertices - self.n_edges + self.n_faces

    @cached_property
    def n_components(self) -> int:
        """Number of connected components (of the vertex–edge graph)."""
        graph = coo_matrix(
            (np.ones(self.n_edges, dtype=np.int8), (self.edges[:, 0], self.edges[:, 1])),
            shape=(self.n_vertices, self.n_vertices),
        )
        return int(connected_components(graph, directed=False)[0])

    def boundary_loops(self) -> list[IntArray]:
        """The boundary loops as arrays of vertex indices, each following its boundary half-edges.

        A boundary half-edge has its face on the left; its successor is the boundary half-edge
        leaving its target, i.e. the first ring half-edge there. Each loop starts at its smallest
        half-edge; loops are ordered by that half-edge. Labels and positions come from pointer
        jumping (``log2`` of the longest loop rounds).
        """
        boundary = np.flatnonzero(self.twin < 0)
        if boundary.size == 0:
            return []
        index = np.full(self.n_halfedges, -1, dtype=np.int64)
        index[boundary] = np.arange(boundary.size)
        successor = index[self.ring_halfedges[self.ring_offsets[self.target(boundary)]]]
        predecessor = np.empty_like(successor)
        predecessor[successor] = np.arange(boundary.size)

        rounds = int(np.ceil(np.log2(boundary.size))) + 1
        head, jump = np.arange(boundary.size), successor
        for _ in range(rounds):  # head[i] = min over i … i + 2^r − 1 along the loop
            head, jump = np.minimum(head, head[jump]), jump[jump]
        is_head = head == np.arange(boundary.size)
        back = np.where(is_head, np.arange(boundary.size), predecessor)
        distance = (~is_head).astype(np.int64)
        for _ in range(rounds):  # distance from the head, by doubling the backward links
            distance, back = distance + distance[back], back[back]

        order = np.lexsort((distance, head))
        cuts = np.flatnonzero(np.diff(head[order])) + 1
        return np.split(self.origin(boundary[order]), cuts)


class _Connectivity(NamedTuple):
    """The arrays of :class:`QuadTopology` that :func:`_connect` computes, under the same names."""

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


# : from this many half-edges on (``compiled=None``) :func:`_connect` runs :func:`_connect_kernel`
# (20 000 quads,
#: as ``continuity.KERNEL_PATCHES``: a fresh install's first use compiles it, a few seconds)
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
    if corners.size >= KERNEL_HALFEDGES if compiled is None else compiled:
        from .kernels import jit_kernel  # numba, imported on first use

        valid, *arrays = jit_kernel(_connect_kernel)(corners, sizes, n_vertices)
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
    ring = _walk_rings(start, face_count, ring_offsets, twin, preceding, corners, face_ends)
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
    return _Connectivity(
        twin,
        pairing.edges,
        pairing.halfedge_edge,
        pairing.edge_halfedges,
        valence,
        face_count,
        is_boundary_vertex,
        ring_offsets,
        ring,
        neighbor_offsets,
        neighbors,
    )


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
    return (
        valid,
        twin,
        edges[:n_edges],
        halfedge_edge,
        edge_halfedges[:n_edges],
        valence,
        face_count,
        is_boundary_vertex,
        ring_offsets,
        ring,
        neighbor_offsets,
        neighbors,
    )


#: ring positions written one rotation step at a time (for all vertices at once); the rest of the
#: rings of vertices with more faces are ranked by pointer jumping, so a 100 000-valent vertex
#: costs ``log2`` rounds instead of 100 000 steps
_WALK_STEPS = 32


def _walk_rings(
    start: IntArray,
    face_count: IntArray,
    ring_offsets: IntArray,
    twin: IntArray,
    preceding: IntArray,
    corners: IntArray,
    face_ends: IntArray,
) -> IntArray:
    """Write ``h_{i+1} = twin(prev(h_i))`` from ``start`` for every vertex at once, one rotation
    step at a time.

    Vertices are sorted by decreasing face count, so the vertices still walking at step ``i`` are
    a prefix of that order. Running into the boundary early means a second fan. After
    :data:`_WALK_STEPS` steps the remaining positions are ranked (:func:`_rank_ring_tails`).
    """
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
        _rank_ring_tails(
            ring,
            tail,
            current[: tail.size],
            face_count,
            ring_offsets,
            twin,
            preceding,
            corners,
            face_ends,
        )
    return ring


def _rank_ring_tails(
    ring: IntArray,
    tail: IntArray,
    first: IntArray,
    face_count: IntArray,
    ring_offsets: IntArray,
    twin: IntArray,
    preceding: IntArray,
    corners: IntArray,
    face_ends: IntArray,
) -> None:
    """Ring positions ``_WALK_STEPS`` onwards of the vertices ``tail``, whose walk has reached
    ``first``.

    The half-edges left are those of ``tail`` not yet written; each points to its successor
    ``twin(prev(h))`` among them (the walk ends at the boundary or back at a written one).
    Pointer jumping gives each its distance ``d`` to the end of its chain, so ``h`` sits at
    ``_WALK_STEPS + d(first) - d(h)``. A chain from ``first`` shorter than the rest of the ring
    means a second fan.
    """
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


# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Sectors:
    """The sectors of every vertex, over the ring positions of :class:`~g1patch.mesh.QuadTopology`.

    ``label[p]``: global sector of ring position p (face corner ``ring_halfedges[p]``);
    ``count[v]``: sectors at v (≥ 1); ``cuts[v]``: seam and boundary slots at v;
    per sector: ``vertex``, and the slots bounding it counter-clockwise, ``start`` and ``end``
    (-1 for the single sector of a vertex without cuts). A boundary vertex's first and last
    slots are cuts.
    """

    label: IntArray
    count: IntArray
    cuts: IntArray
    vertex: IntArray
    start: IntArray
    end: IntArray

    @property
    def creased(self) -> NDArray[np.bool_]:
        """Vertices with more than one sector."""
        return self.count > 1


def sectors(topology: QuadTopology | _Connectivity, seams: NDArray[np.bool_]) -> Sectors:
    """Cut every ring at its seam slots and its boundary (:class:`Sectors`), by segmented sums;
    ``topology`` may be a quad topology or the connectivity of polygons (:func:`_connect`),
    ``seams`` per edge."""
    face_count = topology.face_count
    nv = face_count.size
    ring_vertex = np.repeat(np.arange(nv), face_count)
    position = np.arange(ring_vertex.size) - topology.ring_offsets[ring_vertex]
    boundary = topology.is_boundary_vertex
    cut = seams[topology.halfedge_edge[topology.ring_halfedges]] | (
        (position == 0) & boundary[ring_vertex]
    )
    cuts = np.bincount(ring_vertex, cut, minlength=nv).astype(np.int64)
    total = np.cumsum(cut)
    before = np.concatenate([[0], total])[
        topology.ring_offsets[:-1]
    ]  # cuts before each vertex's ring
    local = total - before[ring_vertex]  # cuts at positions ≤ p of its vertex
    count = np.maximum(cuts, 1)
    local_label = np.where(boundary[ring_vertex], local - 1, (local - 1) % count[ring_vertex])
    sector_offsets = np.concatenate([[0], np.cumsum(count)])
    label = sector_offsets[ring_vertex] + local_label
    vertex = np.repeat(np.arange(nv), count)
    start = np.full(vertex.size, -1, dtype=np.int64)
    slot = topology.neighbor_offsets[ring_vertex] + position
    start[label[cut]] = slot[cut]
    # a sector ends where the next one (counter-clockwise) starts; a boundary's last at its virtual
    # slot
    following = (
        sector_offsets[vertex]
        + (np.arange(vertex.size) - sector_offsets[vertex] + 1) % count[vertex]
    )
    end = np.where(start >= 0, start[following], -1)
    last = sector_offsets[1:][boundary] - 1
    end[last] = topology.neighbor_offsets[1:][boundary] - 1
    return Sectors(label, count, cuts, vertex, start, end)


# ----------------------------------------------------------------------------------------------


def _check_finite(vertices: FloatArray) -> None:
    """Every coordinate finite and within :data:`MAX_COORDINATE` (two reductions, which NaN makes
    fail, before any search for the vertex to name)."""
    if vertices.size == 0 or (
        vertices.max() <= MAX_COORDINATE and vertices.min() >= -MAX_COORDINATE
    ):
        return
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        raise InputError(
            f"vertex {bad[0]} has a non-finite coordinate {tuple(vertices[bad[0]].tolist())}"
            + _all_of(bad, "vertices")
        )
    huge = np.flatnonzero((np.abs(vertices) > MAX_COORDINATE).any(axis=1))
    if huge.size:
        raise InputError(
            f"vertex {huge[0]} has a coordinate beyond ±{MAX_COORDINATE:g}: "
            f"{tuple(vertices[huge[0]].tolist())}" + _all_of(huge, "vertices")
        )


# : from this many faces on (``compiled=None``) :func:`_check_face_areas` first runs
# :func:`_face_area_kernel`
KERNEL_FACES = 20_000
#: faces the kernel finds within this relative margin of the tolerance go to the NumPy check
_AREA_MARGIN = 1e-6


def _check_face_areas(
    vertices: FloatArray, faces: IntArray, *, compiled: bool | None = None
) -> None:
    """Zero area: ``|d1 × d2| <= tol · max(|d1|, |d2|)²`` for the diagonals d1 = p2 − p0, d2 = p3 −
    p1.

    ``compiled`` (default: from :data:`KERNEL_FACES` faces on): :func:`_face_area_kernel` passes
    the mesh when every face clears the tolerance by the margin :data:`_AREA_MARGIN` (far beyond
    any rounding of the two computations); otherwise the NumPy code below, the reference, decides.
    """
    if faces.shape[0] >= KERNEL_FACES if compiled is None else compiled:
        from .kernels import jit_kernel  # numba, imported on first use

        if jit_kernel(_face_area_kernel)(
            vertices, faces, DEGENERATE_AREA_TOLERANCE * (1.0 + _AREA_MARGIN)
        ):
            return
    corners = vertices[faces]
    d1 = corners[:, 2] - corners[:, 0]
    d2 = corners[:, 3] - corners[:, 1]
    double_area = np.linalg.norm(np.cross(d1, d2), axis=1)
    size = np.maximum(np.einsum("ij,ij->i", d1, d1), np.einsum("ij,ij->i", d2, d2))
    bad = np.flatnonzero(double_area <= DEGENERATE_AREA_TOLERANCE * size)
    if bad.size:
        f = bad[0]
        raise DegenerateFaceError(
            f"face {f} {tuple(faces[f].tolist())} has zero area (|d1 x d2| = {double_area[f]:.3g})"
            + _all_of(bad, "faces")
        )


def _face_area_kernel(vertices: FloatArray, faces: IntArray, tolerance: float) -> bool:
    """Whether every face has ``|d1 × d2|² > (tolerance · max(|d1|², |d2|²))²`` (NaN fails), face
    by face; compiled by :func:`~g1patch.kernels.jit_kernel`."""
    for f in range(faces.shape[0]):
        a, b, c, d = faces[f, 0], faces[f, 1], faces[f, 2], faces[f, 3]
        u0, u1, u2 = (
            vertices[c, 0] - vertices[a, 0],
            vertices[c, 1] - vertices[a, 1],
            vertices[c, 2] - vertices[a, 2],
        )
        w0, w1, w2 = (
            vertices[d, 0] - vertices[b, 0],
            vertices[d, 1] - vertices[b, 1],
            vertices[d, 2] - vertices[b, 2],
        )
        n0, n1, n2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
        size = tolerance * max(u0 * u0 + u1 * u1 + u2 * u2, w0 * w0 + w1 * w1 + w2 * w2)
        if not n0 * n0 + n1 * n1 + n2 * n2 > size * size:
            return False
    return True


def _as_polygons(faces: ArrayLike | Sequence[Sequence[int]]) -> tuple[IntArray, IntArray]:
    """Faces as flat ``corners`` and ``sizes``, from an (nf, n) array or a list of index lists."""
    try:
        table = np.asarray(faces)
    except ValueError:  # ragged: a list of lists of different lengths
        table = None
    if table is not None and table.dtype != object:
        table = as_index_array("faces", table, (None,))
        if table.ndim != 2:
            raise InputError(
                f"faces: expected shape (nf, n) or a list of index lists, got shape {table.shape}"
            )
        return table.ravel(), np.full(table.shape[0], table.shape[1], dtype=np.int64)
    try:
        sizes = np.fromiter(map(len, faces), dtype=np.int64)
        corners = np.fromiter(
            (int(v) for face in faces for v in face), dtype=np.int64, count=int(sizes.sum())
        )
    except (TypeError, ValueError) as exc:
        raise InputError(f"faces: expected a list of lists of vertex indices ({exc})") from None
    return corners, sizes


def _following_corner(sizes: IntArray) -> IntArray:
    """Index of the next corner in the same face, for flat corners with ``sizes`` per face."""
    offsets = np.cumsum(sizes)
    following = np.arange(1, int(offsets[-1]) + 1)
    following[offsets - 1] = offsets - sizes
    return following


def _edge_keys(corners: IntArray, sizes: IntArray, n_vertices: int) -> IntArray:
    """Undirected edge key ``min·nv + max`` of each corner's edge to the next corner."""
    target = corners[_following_corner(sizes)]
    return np.minimum(corners, target) * n_vertices + np.maximum(corners, target)


#: an edge end whose tangent-plane projection is shorter than this fraction of the edge
#: (the edge runs along the vertex normal) gets no smooth tangent: the edge keeps its midpoint
_SPLIT_PARALLEL_TOLERANCE = 1e-6
#: a fan normal shorter than this fraction of its corners' summed |cross products| counts as zero
_SPLIT_NORMAL_TOLERANCE = 1e-12


def _corner_normals(
    vertices: FloatArray, corners: IntArray, sizes: IntArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Area-weighted fan normals ``N_v = Σ (v_next − v) × (v_prev − v)`` over v's corners, unit.

    Vertices at the boundary take the same sum over their faces. Returns ``(normals, valid)``;
    where ``|N_v| <= _SPLIT_NORMAL_TOLERANCE · Σ |cross|`` (or v has no corner) the normal is
    zero and ``valid`` is False.
    """
    nv = vertices.shape[0]
    following = _following_corner(sizes)
    preceding = np.empty_like(following)
    preceding[following] = np.arange(corners.size)
    here = vertices[corners]
    cross = np.cross(vertices[corners[following]] - here, vertices[corners[preceding]] - here)
    summed = np.stack(
        [np.bincount(corners, weights=cross[:, k], minlength=nv) for k in range(3)], axis=1
    )
    scale = np.bincount(corners, weights=np.linalg.norm(cross, axis=1), minlength=nv)
    length = np.linalg.norm(summed, axis=1)
    valid = (length > _SPLIT_NORMAL_TOLERANCE * scale) & np.isfinite(length)
    normals = np.zeros_like(summed)
    normals[valid] = summed[valid] / length[valid, None]
    return normals, valid


def _edge_tangents(
    d: FloatArray, normal: FloatArray, valid_normal: NDArray[np.bool_]
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Circle-aware Hermite tangents of chords ``d`` at an end with unit ``normal``, batched.

    Direction ``s = d − (N·d) N``, length ``L = |d| / cos²(θ/4)`` with ``sin(θ/2) = |N·d| / |d|``,
    i.e. ``L = 2|d|² / (|d| + |s|)`` (the tangent of a circular arc through both ends, tangent
    to the plane). Returns ``(tangents, ok)``; not ok (tangent zero) where the normal is invalid
    or ``|s| <= _SPLIT_PARALLEL_TOLERANCE · |d|``.
    """
    s = d - np.einsum("ij,ij->i", d, normal)[:, None] * normal
    in_plane = np.linalg.norm(s, axis=1)
    chord = np.linalg.norm(d, axis=1)
    ok = valid_normal & (in_plane > _SPLIT_PARALLEL_TOLERANCE * chord)
    scale = np.zeros_like(chord)
    scale[ok] = 2.0 * chord[ok] ** 2 / ((chord[ok] + in_plane[ok]) * in_plane[ok])
    return s * scale[:, None], ok


def _smooth_edge_points(
    vertices: FloatArray,
    a: IntArray,
    b: IntArray,
    normals: tuple[FloatArray, FloatArray],
    valid: tuple[NDArray[np.bool_], NDArray[np.bool_]],
) -> FloatArray:
    """Midpoints of the cubic Hermite curves of edges a–b: ``(A + B)/2 + (t_AB + t_BA)/8``.

    ``t_AB`` is A's tangent towards B, ``t_BA`` B's towards A (:func:`_edge_tangents`), on the
    per-edge end normals ``normals = (at A, at B)``; an edge that lacks a tangent at one of its
    ends keeps its chord midpoint.
    """
    d = vertices[b] - vertices[a]
    t_ab, ok_a = _edge_tangents(d, normals[0], valid[0])
    t_ba, ok_b = _edge_tangents(-d, normals[1], valid[1])
    bend = np.where((ok_a & ok_b)[:, None], t_ab + t_ba, 0.0)
    return 0.5 * (vertices[a] + vertices[b]) + 0.125 * bend


def _creased_edge_points(
    vertices: FloatArray,
    corners: IntArray,
    sizes: IntArray,
    a: IntArray,
    b: IntArray,
    sharp: NDArray[np.bool_],
) -> FloatArray:
    """Edge points of a polygon mesh with creases ``sharp`` (per edge a–b, sorted pairs).

    Smooth edges: :func:`_smooth_edge_points` on each end's *sector* normal, the area-weighted
    fan normal of the faces reached from the edge without crossing a crease or the boundary.
    Creases: ``(A + B)/2 + (t_AB + t_BA)/8`` with t along the crease curve: at a vertex with
    exactly two creases (inside) the tangent of the circle through it and its two crease
    neighbours, ``d ∥ |c_P|² c_Q − |c_Q|² c_P``, of length ``2|c|/(1 + ĉ·d)``; elsewhere the chord
    (a crease between two corners stays straight).
    """
    nv = vertices.shape[0]
    connectivity = _connect(corners, sizes, nv)
    cut = sharp & (connectivity.edge_halfedges[:, 1] >= 0)
    found = sectors(connectivity, cut)
    following = _following_corner(sizes)
    preceding = np.empty_like(following)
    preceding[following] = np.arange(corners.size)
    here = vertices[corners]
    cross = np.cross(vertices[corners[following]] - here, vertices[corners[preceding]] - here)
    position = np.empty(corners.size, dtype=np.int64)
    position[connectivity.ring_halfedges] = np.arange(corners.size)
    label = found.label[position]  # sector of each corner
    count = found.vertex.size
    summed = np.stack([np.bincount(label, cross[:, k], minlength=count) for k in range(3)], axis=1)
    scale = np.bincount(label, np.linalg.norm(cross, axis=1), minlength=count)
    length = np.linalg.norm(summed, axis=1)
    valid = (length > _SPLIT_NORMAL_TOLERANCE * scale) & np.isfinite(length)
    normals = np.divide(summed, length[:, None], out=np.zeros_like(summed), where=valid[:, None])
    start = connectivity.edge_halfedges[
        :, 0
    ]  # corner at a (a → b or b → a), its face touches the edge
    at_a = np.where(corners[start] == a, start, following[start])
    at_b = np.where(corners[start] == b, start, following[start])
    out = _smooth_edge_points(
        vertices,
        a,
        b,
        (normals[label[at_a]], normals[label[at_b]]),
        (valid[label[at_a]], valid[label[at_b]]),
    )

    # crease curves: the two crease neighbours of every vertex with exactly two creases inside
    e = np.flatnonzero(sharp)
    ends = np.concatenate([a[e], b[e]])
    others = np.concatenate([b[e], a[e]])
    creases = np.bincount(ends, minlength=nv)
    order = np.argsort(ends, kind="stable")
    ends, others = ends[order], others[order]
    two = (creases[ends] == 2) & ~connectivity.is_boundary_vertex[ends]
    pairs = others[two].reshape(-1, 2)
    owner = ends[two][0::2]
    c_p, c_q = vertices[pairs[:, 0]] - vertices[owner], vertices[pairs[:, 1]] - vertices[owner]
    direction = np.zeros((nv, 3))
    d = (
        c_q * np.einsum("ij,ij->i", c_p, c_p)[:, None]
        - c_p * np.einsum("ij,ij->i", c_q, c_q)[:, None]
    )
    d_length = np.linalg.norm(d, axis=1, keepdims=True)
    direction[owner] = np.divide(d, d_length, out=np.zeros_like(d), where=d_length > 0)

    def crease_tangent(start_vertex: IntArray, end_vertex: IntArray) -> FloatArray:
        chord = vertices[end_vertex] - vertices[start_vertex]
        along = direction[start_vertex]
        chord_length = np.linalg.norm(chord, axis=1)
        cosine = np.einsum("ij,ij->i", chord, along) / np.where(chord_length > 0, chord_length, 1.0)
        along = along * np.sign(cosine)[:, None]  # towards this end
        curved = np.abs(cosine) > 0.1
        length = 2.0 * chord_length / (1.0 + np.abs(cosine))
        return np.where(curved[:, None], length[:, None] * along, chord)

    out[e] = 0.5 * (vertices[a[e]] + vertices[b[e]]) + 0.125 * (
        crease_tangent(a[e], b[e]) + crease_tangent(b[e], a[e])
    )
    return out


def refine_polygons(
    vertices: FloatArray,
    corners: IntArray,
    sizes: IntArray,
    *,
    smooth: bool = False,
    sharp: NDArray[np.bool_] | None = None,
) -> tuple[FloatArray, IntArray, IntArray]:
    """One Catmull–Clark topology step: every n-gon becomes n quads.

    New vertices: the old ones (same indices and positions), then one per edge (``nv + e``, edges
    sorted by vertex pair), then one per face (``nv + ne + f``). Corner ``i`` of face ``f``
    becomes quad ``offsets[f] + i = (v_i, E(v_i v_{i+1}), F(f), E(v_{i-1} v_i))``,
    counter-clockwise like its face. Returns ``(vertices, quads, parent_face)``.

    Positions, linear (default): edge midpoints and face centroids. ``smooth``: on a surface
    through the old vertices — edge points at the middle of the edges' circle-aware cubic
    Hermite curves on area-weighted fan normals (:func:`_smooth_edge_points`), face points at the
    Coons centre ``C = (2/n) Σ M_i − (1/n) Σ V_i`` of the face's corners ``V_i`` and edge points
    ``M_i``. Both give midpoints and centroids on flat input. ``smooth`` expects a validated,
    oriented manifold topology (:func:`_connect`). ``sharp`` (per edge, sorted vertex pairs) marks
    creases for ``smooth``: the normals of an edge's ends are then those of its sector of faces
    (:func:`sectors`), and a crease's point is the middle of its crease curve
    (:func:`_creased_edge_points`), so a flat face bounded by creases stays flat.
    """
    nv = vertices.shape[0]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    corner_face = np.repeat(np.arange(sizes.size), sizes)
    preceding = np.empty(corners.size, dtype=np.int64)
    preceding[_following_corner(sizes)] = np.arange(corners.size)

    edge_keys, corner_edge = np.unique(_edge_keys(corners, sizes, nv), return_inverse=True)
    a, b = edge_keys // nv, edge_keys % nv
    corner_sums = np.add.reduceat(vertices[corners], offsets[:-1], axis=0)
    if smooth:
        if sharp is not None and sharp.any():
            edge_points = _creased_edge_points(vertices, corners, sizes, a, b, sharp)
        else:
            normals, valid = _corner_normals(vertices, corners, sizes)
            edge_points = _smooth_edge_points(
                vertices, a, b, (normals[a], normals[b]), (valid[a], valid[b])
            )
        edge_sums = np.add.reduceat(edge_points[corner_edge], offsets[:-1], axis=0)
        face_points = (2.0 * edge_sums - corner_sums) / sizes[:, None]
    else:
        edge_points = 0.5 * (vertices[a] + vertices[b])
        face_points = corner_sums / sizes[:, None]
    quads = np.stack(
        [corners, nv + corner_edge, nv + edge_keys.size + corner_face, nv + corner_edge[preceding]],
        axis=1,
    )
    return np.concatenate([vertices, edge_points, face_points]), quads, corner_face


def _check_tags(tags: Sequence[Tag], n_vertices: int, n_faces: int) -> None:
    """Vertex tags (crease pairs, corners) and face tags (holes) must name existing items."""
    for tag in tags:
        limit = (
            n_vertices if tag.name in VERTEX_TAGS else n_faces if tag.name in FACE_TAGS else None
        )
        if limit is None:
            continue
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease" and ints.size % 2:
            raise MeshError(f"tag 'crease' needs pairs of vertex indices, got {ints.size} integers")
        bad = ints[(ints < 0) | (ints >= limit)]
        if bad.size:
            item = "vertex" if tag.name in VERTEX_TAGS else "face"
            raise MeshError(f"tag {tag.name!r} names {item} {bad[0]}, outside 0..{limit - 1}")


def _renumber_tags(tags: Sequence[Tag], new_index: IntArray) -> tuple[Tag, ...]:
    """Carry vertex tags through dropping unused vertices: ``new_index[old]``, -1 where dropped."""
    renumbered = []
    for tag in tags:
        if tag.name in VERTEX_TAGS:
            ints = new_index[np.asarray(tag.ints, dtype=np.int64)]
            if (ints < 0).any():
                raise MeshError(f"tag {tag.name!r} names a vertex that no face uses")
            tag = tag._replace(ints=tuple(ints.tolist()))
        renumbered.append(tag)
    return tuple(renumbered)


#: creases at least this sharp shape the smooth split (the interpolating rule's threshold)
SPLIT_SHARPNESS = 1.0


def _crease_edges(
    tags: Sequence[Tag], corners: IntArray, sizes: IntArray, n_vertices: int
) -> NDArray[np.bool_] | None:
    """Per edge of the polygons (sorted vertex pairs), whether a crease tag of sharpness ≥
    :data:`SPLIT_SHARPNESS` names it; None without such tags."""
    edge_keys = np.unique(_edge_keys(corners, sizes, n_vertices))
    sharp = np.zeros(edge_keys.size, dtype=bool)
    for tag in tags:
        if tag.name != "crease" or not tag.ints:
            continue
        ints = np.asarray(tag.ints, dtype=np.int64)
        pa, pb = ints[0::2], ints[1::2]
        floats = np.asarray(tag.floats, dtype=np.float64)
        values = (
            floats
            if floats.size == pa.size
            else np.full(pa.size, floats[0] if floats.size else INFINITE_SHARPNESS)
        )
        keys = np.minimum(pa, pb) * n_vertices + np.maximum(pa, pb)
        found = np.minimum(np.searchsorted(edge_keys, keys), edge_keys.size - 1)
        hit = (edge_keys[found] == keys) & (values >= SPLIT_SHARPNESS)
        sharp[found[hit]] = True
    return sharp if sharp.any() else None


def _refine_tags(
    tags: Sequence[Tag], corners: IntArray, sizes: IntArray, n_vertices: int
) -> tuple[Tag, ...]:
    """Carry tags through :func:`refine_polygons`: crease (a, b) becomes (a, m), (m, b); a hole its
    quads."""
    edge_keys = np.unique(_edge_keys(corners, sizes, n_vertices))
    refined = []
    for tag in tags:
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease":
            a, b = ints[0::2], ints[1::2]
            keys = np.minimum(a, b) * n_vertices + np.maximum(a, b)
            m = np.minimum(np.searchsorted(edge_keys, keys), edge_keys.size - 1)
            missing = np.flatnonzero(edge_keys[m] != keys)
            if missing.size:
                raise MeshError(
                    f"tag 'crease' names ({a[missing[0]]}, {b[missing[0]]}), which is not an edge"
                )
            m += n_vertices
            tag = tag._replace(ints=tuple(np.stack([a, m, m, b], axis=1).ravel().tolist()))
            if len(tag.floats) == a.size > 1:  # one sharpness per edge
                tag = tag._replace(floats=tuple(np.repeat(tag.floats, 2).tolist()))
        elif tag.name in FACE_TAGS:
            quads_of_holes = np.isin(np.repeat(np.arange(sizes.size), sizes), ints)
            tag = tag._replace(ints=tuple(np.flatnonzero(quads_of_holes).tolist()))
        refined.append(tag)
    return tuple(refined)


def _checked_polygons(
    vertices: ArrayLike, faces: ArrayLike | Sequence[Sequence[int]], tags: tuple[Tag, ...]
) -> tuple[FloatArray, IntArray, IntArray]:
    """Positions (finite), faces as flat ``corners`` and ``sizes`` (≥ 3 corners, indices in range)
    and tags naming existing items: what no repair can mend."""
    points = as_float_array("vertices", vertices, (3,), finite=False)
    if points.ndim != 2:
        raise InputError(f"vertices: expected shape (nv, 3), got {points.shape}")
    _check_finite(points)
    corners, sizes = _as_polygons(faces)
    if sizes.size == 0:
        raise MeshError("the mesh has no faces")
    short = np.flatnonzero(sizes < 3)
    if short.size:
        raise DegenerateFaceError(
            f"face {short[0]} has {sizes[short[0]]} corners; a face needs at least 3"
            + _all_of(short, "faces")
        )
    _check_tags(tags, points.shape[0], sizes.size)
    _check_index_range(corners, sizes, points.shape[0])
    return points, corners, sizes


def _quads_from_polygons(
    points: FloatArray,
    corners: IntArray,
    sizes: IntArray,
    split: bool,
    source: str | None,
    tags: tuple[Tag, ...],
) -> tuple[FloatArray, IntArray, tuple[Tag, ...]]:
    """Drop unused vertices and split non-quads of checked polygons (see
    :meth:`QuadMesh.from_arrays`).

    When anything is dropped or split, the polygon topology is validated first, so that errors
    name the input's faces and vertices.
    """
    used = np.bincount(corners, minlength=points.shape[0]) > 0
    non_quads = np.flatnonzero(sizes != 4)
    if used.all() and non_quads.size == 0:
        return points, corners.reshape(-1, 4), tags
    if non_quads.size and not split:
        raise MeshError(
            f"{non_quads.size} faces are not quads (face {non_quads[0]} has {sizes[non_quads[0]]} "
            "corners; "
            f"faces {_few(non_quads)}) and splitting is off (--no-split)"
        )
    _connect(corners, sizes, points.shape[0])

    if not used.all():
        unused = np.flatnonzero(~used)
        logger.info(
            "%s: dropped %d unused vertices (%s)", source or "mesh", unused.size, _few(unused)
        )
        new_index = np.cumsum(used) - 1
        new_index[~used] = -1
        points, corners = points[used], new_index[corners]
        tags = _renumber_tags(tags, new_index)
    if non_quads.size == 0:
        return points, corners.reshape(-1, 4), tags
    sharp = _crease_edges(tags, corners, sizes, points.shape[0])
    tags = _refine_tags(tags, corners, sizes, points.shape[0])
    points, quads, _ = refine_polygons(points, corners, sizes, smooth=True, sharp=sharp)
    logger.info(
        "%s: %d of %d faces are not quads; refined the whole mesh once (every n-gon into n quads, "
        "new points on a smooth surface through the vertices)",
        source or "mesh",
        non_quads.size,
        sizes.size,
    )
    return points, quads, tags


#: what :meth:`QuadMesh.from_arrays` repairs unless strict (:mod:`g1patch.repair`)
REPAIRABLE = (DegenerateFaceError, NonManifoldError, OrientationError, ValenceError)

_STRICT: ContextVar[bool] = ContextVar("g1patch_strict_meshes", default=False)


@contextmanager
def strict_meshes(strict: bool = True) -> Iterator[None]:
    """Within the block, :meth:`QuadMesh.from_arrays` calls that do not pass ``strict`` use this
    one: for callers that cannot pass it on, such as :func:`~g1patch.io.meshfile.read_mesh`."""
    token = _STRICT.set(strict)
    try:
        yield
    finally:
        _STRICT.reset(token)


@dataclass(frozen=True, eq=False)
class Features:
    """The sharp features a mesh's tags ask for, OpenSubdiv's semantics, per topology item.

    * ``edge_sharpness`` (E,), in ``QuadTopology.edges`` order, and ``vertex_sharpness`` (V,):
      0 smooth, ≥ :data:`INFINITE_SHARPNESS` infinitely sharp, in between semi-sharp (sharp for
      that many subdivision levels, then smooth);
    * ``holes`` (F,): faces that get no surface (their edges bound it);
    * ``boundary``: the ``interpolateboundary`` rule, ``none`` / ``edge-only`` /
      ``edge-and-corner`` (default ``edge-only``);
    * ``crease_method``: ``normal`` or ``chaikin`` (the ``creasemethod`` tag).
    """

    edge_sharpness: FloatArray
    vertex_sharpness: FloatArray
    holes: NDArray[np.bool_]
    boundary: str = "edge-only"
    crease_method: str = "normal"

    def __post_init__(self) -> None:
        for name in ("edge_sharpness", "vertex_sharpness", "holes"):
            _read_only(getattr(self, name))

    @classmethod
    def smooth(cls, topology: QuadTopology) -> Features:
        """No sharp edge or vertex, no hole, edge-only boundary."""
        return cls(
            np.zeros(topology.n_edges),
            np.zeros(topology.n_vertices),
            np.zeros(topology.n_faces, dtype=bool),
        )

    @property
    def sharp_edges(self) -> NDArray[np.bool_]:
        """Edges tagged infinitely sharp (boundary edges not included)."""
        return self.edge_sharpness >= INFINITE_SHARPNESS

    @property
    def corner_vertices(self) -> NDArray[np.bool_]:
        """Vertices tagged infinitely sharp (``t corner`` ≥ 10)."""
        return self.vertex_sharpness >= INFINITE_SHARPNESS

    @property
    def is_semi_sharp(self) -> bool:
        """Whether any edge or vertex has a sharpness strictly between 0 and infinite."""
        values = np.concatenate([self.edge_sharpness, self.vertex_sharpness])
        return bool(((values > 0) & (values < INFINITE_SHARPNESS)).any())

    @property
    def is_smooth(self) -> bool:
        """No sharpness anywhere and no hole (the boundary rule aside)."""
        return not (self.edge_sharpness.any() or self.vertex_sharpness.any() or self.holes.any())


def _tag_values(tag: Tag, count: int) -> FloatArray:
    """One sharpness per item: the tag's floats, or its one float for all of them (10 if it has
    none)."""
    floats = np.asarray(tag.floats, dtype=np.float64)
    if floats.size == count:
        values = floats
    elif floats.size <= 1:
        values = np.full(count, floats[0] if floats.size else INFINITE_SHARPNESS)
    else:
        raise MeshError(
            f"tag {tag.name!r} has {count} items but {floats.size} sharpness values; expected 1 "
            f"or {count}"
        )
    bad = np.flatnonzero(~np.isfinite(values) | (values < 0))
    if bad.size:
        raise MeshError(
            f"tag {tag.name!r} has sharpness {values[bad[0]]:g}; a sharpness is a finite number ≥ 0"
        )
    return values


def features_from_tags(topology: QuadTopology, tags: Sequence[Tag]) -> Features:
    """The :class:`Features` of OpenSubdiv tags on ``topology``: ``crease`` (vertex pairs, one
    sharpness each or one for all), ``corner`` (vertices), ``hole`` (faces), ``interpolateboundary``
    (0/1/2) and ``creasemethod`` (``normal``/``chaikin``); repeated items keep their largest
    sharpness, other tags are ignored. A crease pair that is not an edge raises
    :class:`MeshError`."""
    nv = topology.n_vertices
    edge_keys = topology.edges[:, 0] * nv + topology.edges[:, 1]
    edge = np.zeros(topology.n_edges)
    vertex = np.zeros(nv)
    holes = np.zeros(topology.n_faces, dtype=bool)
    boundary, method = "edge-only", "normal"
    for tag in tags:
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease":
            a, b = ints[0::2], ints[1::2]
            keys = np.minimum(a, b) * nv + np.maximum(a, b)
            found = np.minimum(np.searchsorted(edge_keys, keys), max(edge_keys.size - 1, 0))
            missing = np.flatnonzero(edge_keys[found] != keys)
            if missing.size:
                raise MeshError(
                    f"tag 'crease' names ({a[missing[0]]}, {b[missing[0]]}), which is not an edge"
                )
            np.maximum.at(edge, found, _tag_values(tag, a.size))
        elif tag.name == "corner":
            np.maximum.at(vertex, ints, _tag_values(tag, ints.size))
        elif tag.name == "hole":
            holes[ints] = True
        elif tag.name == "interpolateboundary" and ints.size:
            if not 0 <= ints[0] < len(BOUNDARY_RULES):
                raise MeshError(
                    f"tag 'interpolateboundary' has value {ints[0]}; expected 0, 1 or 2"
                )
            boundary = BOUNDARY_RULES[ints[0]]
        elif tag.name == "creasemethod" and tag.strings:
            if tag.strings[0] not in CREASE_METHODS:
                raise MeshError(
                    f"tag 'creasemethod' has value {tag.strings[0]!r}; expected 'normal' or "
                    "'chaikin'"
                )
            method = tag.strings[0]
    return Features(edge, vertex, holes, boundary, method)


@contextmanager
def _named_errors(source: str | None) -> Iterator[None]:
    """Prefix mesh and input errors with the source file name, keeping their class."""
    try:
        yield
    except (MeshError, InputError) as error:
        if source is None:
            raise
        raise type(error)(f"{source}: {error}") from None


@dataclass(frozen=True, eq=False)
class QuadMesh:
    """Positions ``vertices`` (nv, 3) on a :class:`QuadTopology`, with the OpenSubdiv tags of its
    file.

    Validated on construction: finite coordinates, and no face of zero area
    (:data:`DEGENERATE_AREA_TOLERANCE`). ``repairs`` names what :meth:`from_arrays` repaired
    (short phrases, :attr:`repair_note` joins them), empty if nothing.
    """

    vertices: FloatArray
    topology: QuadTopology
    tags: tuple[Tag, ...] = ()
    source: str | None = None
    repairs: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        with _named_errors(self.source):
            vertices = as_float_array("vertices", self.vertices, (3,), finite=False)
            if vertices.shape != (self.topology.n_vertices, 3):
                raise InputError(
                    f"vertices: expected shape ({self.topology.n_vertices}, 3) for this topology, "
                    f"got {vertices.shape}"
                )
            _check_finite(vertices)
            _check_face_areas(vertices, self.topology.faces)
        object.__setattr__(self, "vertices", _read_only(vertices.copy()))
        object.__setattr__(self, "tags", tuple(Tag(*tag) for tag in self.tags))
        object.__setattr__(self, "repairs", tuple(self.repairs))

    @classmethod
    def from_arrays(
        cls,
        vertices: ArrayLike,
        faces: ArrayLike | Sequence[Sequence[int]],
        *,
        split: bool = True,
        source: str | None = None,
        tags: Sequence[Tag] = (),
        strict: bool | None = None,
    ) -> QuadMesh:
        """Validate and build a quad mesh from positions and faces ((nf, 4) array or lists of
        indices).

        Unused vertices are dropped (one ``logging`` info line). If any face has 3 or ≥ 5 corners
        the whole mesh is refined once (:func:`refine_polygons`, new points on a smooth surface
        through the vertices) with ``split``, else a :class:`MeshError` is raised. A mesh the
        checks refuse (:data:`REPAIRABLE`: repeated vertices, non-manifold edges or vertices,
        inconsistent orientation, interior valence 2) is repaired
        (:func:`g1patch.repair.repair_polygons`, one info line, the repairs kept in
        :attr:`repairs`), unless ``strict`` (default: the one of :func:`strict_meshes`, else False),
        which raises the check's error. Non-finite coordinates, out-of-range indices, faces of < 3
        corners, zero area and non-orientable components raise either way. Errors name ``source`` (a
        file name) when given.
        """
        strict = _STRICT.get() if strict is None else strict
        tags = tuple(Tag(*tag) for tag in tags)
        repairs: tuple[str, ...] = ()
        with _named_errors(source):
            points, corners, sizes = _checked_polygons(vertices, faces, tags)
            try:
                quad_points, quads, quad_tags = _quads_from_polygons(
                    points, corners, sizes, split, source, tags
                )
                topology = QuadTopology.from_faces(quads, quad_points.shape[0])
            except REPAIRABLE as refusal:
                if strict:
                    raise
                from .repair import repair_polygons  # repair builds on this module

                repaired = repair_polygons(points, corners, sizes, tags)
                if not repaired.repairs:
                    raise refusal
                repairs = repaired.repairs
                logger.info("%s: repaired: %s", source or "mesh", ", ".join(repairs))
                quad_points, quads, quad_tags = _quads_from_polygons(
                    repaired.points, repaired.corners, repaired.sizes, split, source, repaired.tags
                )
                topology = QuadTopology.from_faces(quads, quad_points.shape[0])
        return cls(quad_points, topology, quad_tags, source, repairs)

    def __repr__(self) -> str:
        """``<QuadMesh 8 vertices, 6 quads, 12 edges, closed, bbox (-1, -1, -1)…(1, 1, 1),
        cube.obj>``: counts, tags, repairs, the box and the file name, never the arrays."""
        parts = [self.topology._counts()]
        if self.tags:
            parts.append("tags " + " ".join(dict.fromkeys(tag.name for tag in self.tags)))
        if self.repairs:
            parts.append("repaired")
        parts.append(bbox_text(*self.bounding_box))
        if self.source:
            parts.append(short_source(self.source))
        return f"<QuadMesh {', '.join(parts)}>"

    def _repr_png_(self) -> bytes | None:
        """A small flat-shaded picture of the quads for Jupyter (None above
        :data:`g1patch.display.PREVIEW_MAX_PATCHES` faces)."""
        return picture("mesh", self, self.n_faces)

    def with_vertices(self, new_vertices: ArrayLike) -> QuadMesh:
        """The same topology, tags and repair record with new positions (validated the same way)."""
        return QuadMesh(
            np.asarray(new_vertices), self.topology, self.tags, self.source, self.repairs
        )

    @property
    def repair_note(self) -> str:
        """The repairs as one line, ``"repaired: 1 valence-2 vertex (137) dissolved, …"``; empty if
        none."""
        return "repaired: " + ", ".join(self.repairs) if self.repairs else ""

    @cached_property
    def features(self) -> Features:
        """Sharpness per edge and vertex, holes and boundary rule from the tags
        (:func:`features_from_tags`)."""
        with _named_errors(self.source):
            return features_from_tags(self.topology, self.tags)

    @property
    def faces(self) -> IntArray:
        return self.topology.faces

    @property
    def n_vertices(self) -> int:
        return self.topology.n_vertices

    @property
    def n_faces(self) -> int:
        return self.topology.n_faces

    @property
    def n_edges(self) -> int:
        return self.topology.n_edges

    @property
    def bounding_box(self) -> tuple[FloatArray, FloatArray]:
        """(lowest, highest) corner of the axis-aligned box around the vertices."""
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    @property
    def bounding_box_diagonal(self) -> float:
        low, high = self.bounding_box
        return float(np.linalg.norm(high - low))


def subdivide(mesh: QuadMesh) -> QuadMesh:
    """One Catmull–Clark topology step with linear positions: 4 F quads on V + E + F vertices.

    Old vertices keep their indices, edge midpoints follow (in edge order), then face centroids
    (:func:`refine_polygons`). Crease and hole tags are carried over.
    """
    corners = mesh.faces.ravel()
    sizes = np.full(mesh.n_faces, 4, dtype=np.int64)
    vertices, quads, _ = refine_polygons(mesh.vertices, corners, sizes)
    tags = _refine_tags(mesh.tags, corners, sizes, mesh.n_vertices)
    return QuadMesh(
        vertices, QuadTopology.from_faces(quads, vertices.shape[0]), tags, mesh.source, mesh.repairs
    )
