"""The topology of a scan's (or a layout's) polygons, from their corner indices alone: which
sides are open (:func:`boundary_edges`), which faces form one connected part
(:func:`triangle_parts`), which open edges form one boundary loop (:func:`boundary_loops`)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

__all__ = ["boundary_edges", "boundary_loops", "polygon_sides", "triangle_parts"]

IntArray = NDArray[np.int64]


def polygon_sides(faces: IntArray) -> tuple[IntArray, NDArray[np.bool_]]:
    """The sides ``(F, k, 2)`` of polygons ``faces`` (F, k), side i from corner i to i + 1, and
    which of them only one face has (boundary sides)."""
    sides = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1)
    key = sides.min(axis=-1).astype(np.int64) * (1 << 31) + sides.max(axis=-1)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    return sides, (counts[inverse] == 1).reshape(key.shape)


def boundary_edges(faces: IntArray) -> IntArray:
    """The edges (E, 2) of polygons ``faces`` (F, k) that only one face has, oriented as it has."""
    sides, open_sides = polygon_sides(faces)
    return sides[open_sides]


def boundary_loops(edges: IntArray, count: int) -> IntArray:
    """Per vertex (of ``count``) the label of its connected piece of the boundary ``edges``
    (E, 2): the vertices of one boundary loop share a label (a vertex on no edge has its own)."""
    graph = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), (count, count))
    return connected_components(graph, directed=False)[1].astype(np.int64)


def triangle_parts(triangles: IntArray, count: int) -> IntArray:
    """The connected part (0, 1, …) of each face (T, k) over ``count`` vertices: faces sharing
    an edge are in one part. Faces touching at a vertex only are not: a teapot's handle welded
    to its body at a few coincident points is two surfaces, and one layout over both folds."""
    faces, corners = len(triangles), triangles.shape[1]
    sides = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=-1).reshape(-1, 2)
    key = sides.min(axis=1) * np.int64(count) + sides.max(axis=1)
    order = np.argsort(key, kind="stable")
    same = np.flatnonzero(key[order][1:] == key[order][:-1])
    a, b = order[same] // corners, order[same + 1] // corners
    graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(faces, faces))
    return connected_components(graph, directed=False)[1].astype(np.int64)
