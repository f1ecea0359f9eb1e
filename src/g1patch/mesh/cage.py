"""The polygon cage a quad mesh was split from, and its half-edge connectivity.

A mesh with triangles or n-gons becomes quads on reading (:func:`~g1patch.mesh.refine_polygons`,
one Catmull–Clark topology step with new points on a smooth surface through the vertices: right
for the interpolating shape). The Catmull–Clark *limit* of the cage is another surface: its first
step moves the old vertices too. :class:`PolygonCage` keeps the checked polygons so that the
limit shapes can take that step by the Catmull–Clark rules instead
(:func:`g1patch.subdivision.catmull_clark_cage`), on the very same quad topology.

:class:`PolygonTopology` is the connectivity of the polygons with the part of
:class:`~g1patch.mesh.QuadTopology`'s interface that one refinement step reads: half-edge ``h``
is corner ``h`` (``corners[h]`` to the next corner of its face), edges are sorted vertex pairs in
lexicographic order, as for quads.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .connectivity import _connect
from .faces import _following_corner
from .tags import Tag

__all__ = ["PolygonCage", "PolygonTopology"]

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]


class PolygonCage(NamedTuple):
    """Checked polygons (flat ``corners`` with ``sizes``, at least one face not a quad), their
    ``points`` and tags: what :meth:`QuadMesh.from_arrays <g1patch.mesh.QuadMesh.from_arrays>`
    split into quads."""

    points: FloatArray
    corners: IntArray
    sizes: IntArray
    tags: tuple[Tag, ...]


@dataclass(frozen=True, eq=False)
class PolygonTopology:
    """Half-edge connectivity of manifold, oriented polygons (:func:`from_polygons`)."""

    corners: IntArray
    sizes: IntArray
    n_vertices: int
    corner_face: IntArray
    following: IntArray
    edges: IntArray
    edge_halfedges: IntArray
    is_boundary_edge: NDArray[np.bool_]
    face_count: IntArray
    is_boundary_vertex: NDArray[np.bool_]

    @classmethod
    def from_polygons(cls, corners: IntArray, sizes: IntArray, n_vertices: int) -> PolygonTopology:
        """The connectivity of polygons already checked (:func:`_connect` raises otherwise)."""
        connected = _connect(corners, sizes, n_vertices)
        return cls(
            corners,
            sizes,
            n_vertices,
            np.repeat(np.arange(sizes.size), sizes),
            _following_corner(sizes),
            connected.edges,
            connected.edge_halfedges,
            connected.edge_halfedges[:, 1] < 0,
            connected.face_count,
            connected.is_boundary_vertex,
        )

    @property
    def n_faces(self) -> int:
        return int(self.sizes.size)

    @property
    def n_edges(self) -> int:
        return int(self.edges.shape[0])

    @property
    def n_halfedges(self) -> int:
        return int(self.corners.size)

    def origin(self, h: ArrayLike) -> IntArray:
        """The vertex half-edge ``h`` starts from: ``corners[h]``."""
        return self.corners[np.asarray(h, dtype=np.int64)]

    def target(self, h: ArrayLike) -> IntArray:
        """The vertex half-edge ``h`` points to: the next corner of its face."""
        return self.corners[self.following[np.asarray(h, dtype=np.int64)]]

    def face_of(self, h: ArrayLike) -> IntArray:
        """The face of half-edge ``h``."""
        return self.corner_face[np.asarray(h, dtype=np.int64)]

    def face_points(self, x: FloatArray) -> FloatArray:
        """Per face the centroid of its corners, ``(1/n) Σ x_i``."""
        offsets = np.concatenate([[0], np.cumsum(self.sizes)[:-1]])
        return np.add.reduceat(x[self.corners], offsets, axis=0) / self.sizes[:, None]

    def polygons(self) -> tuple[IntArray, IntArray]:
        """``(corners, sizes)``."""
        return self.corners, self.sizes
