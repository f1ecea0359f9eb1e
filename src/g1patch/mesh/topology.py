"""Quad mesh topology as flat half-edge arrays (:class:`QuadTopology`).

Half-edge ``h = 4 f + k`` runs from corner ``k`` of face ``f`` to corner ``k + 1 (mod 4)``:

    next(h) = 4 (h // 4) + (h % 4 + 1) % 4,     prev(h) = 4 (h // 4) + (h % 4 + 3) % 4,
    next_ccw(h) = twin(prev(h))                 (the next outgoing half-edge counter-clockwise).

Faces are counter-clockwise seen from outside, so the two half-edges of an interior edge run in
opposite directions and a boundary half-edge has its face on the left. A topology is built from
faces alone (it never looks at positions), so one topology serves many position sets. Every step
is vectorised: the only Python loops run over rotation steps around a vertex (at most the largest
valence) or over ``log2`` of a loop length.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import InputError, MeshError, as_index_array
from .connectivity import _connect, _Connectivity
from .validate import _few

__all__ = ["QuadTopology"]

IntArray = NDArray[np.int64]


def _next(h: ArrayLike) -> IntArray:
    h = np.asarray(h, dtype=np.int64)
    return (h & ~3) | ((h + 1) & 3)


def _prev(h: ArrayLike) -> IntArray:
    h = np.asarray(h, dtype=np.int64)
    return (h & ~3) | ((h + 3) & 3)


@dataclass(frozen=True, eq=False)
class QuadTopology(_Connectivity):
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
    is_boundary_edge: NDArray[np.bool_]

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
            faces=quads, n_vertices=nv, is_boundary_edge=is_boundary_edge, **vars(connectivity)
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

    @staticmethod
    def face_of(h: ArrayLike) -> IntArray:
        """The face of half-edge ``h``: ``h // 4``."""
        return np.asarray(h, dtype=np.int64) >> 2

    def face_points(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per face the centroid of its corners, ``(1/4) Σ x_i``."""
        return x[self.faces].mean(axis=1)

    def polygons(self) -> tuple[IntArray, IntArray]:
        """The faces as flat ``(corners, sizes)``."""
        return self.faces.ravel(), np.full(self.n_faces, 4, dtype=np.int64)

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
