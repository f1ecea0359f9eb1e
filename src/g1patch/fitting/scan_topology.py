"""The topology of a scan's (or a layout's) polygons, from their corner indices alone: which
sides are open (:func:`boundary_edges`), which faces form one connected part
(:func:`triangle_parts`), which open edges form one boundary loop (:func:`boundary_loops`), which
triangles to turn over so that neighbours agree (:func:`orientation_flips`)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import breadth_first_order, connected_components

__all__ = [
    "boundary_edges",
    "boundary_loops",
    "orientation_flips",
    "polygon_sides",
    "side_edges",
    "triangle_parts",
]

IntArray = NDArray[np.int64]


def side_edges(faces: IntArray) -> tuple[IntArray, IntArray, IntArray]:
    """The sides ``(F, k, 2)`` of polygons ``faces`` (F, k), side i from corner i to i + 1, the
    edge each is (F, k; an edge is a pair of vertices either way round, numbered 0, 1, …), and
    how many sides each edge has (per edge)."""
    sides = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1)
    key = sides.min(axis=-1).astype(np.int64) * (1 << 31) + sides.max(axis=-1)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    return sides, inverse.reshape(key.shape).astype(np.int64), counts.astype(np.int64)


def polygon_sides(faces: IntArray) -> tuple[IntArray, NDArray[np.bool_]]:
    """The sides ``(F, k, 2)`` of polygons ``faces`` (F, k), side i from corner i to i + 1, and
    which of them only one face has (boundary sides)."""
    sides, edge, counts = side_edges(faces)
    return sides, counts[edge] == 1


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


def orientation_flips(triangles: IntArray, count: int) -> NDArray[np.bool_]:
    """Per triangle (T, 3) over ``count`` vertices whether to reverse it so that every edge two
    triangles share is run in opposite directions by them (a consistent orientation), in each
    part (triangles sharing such edges) the fewer of the two ways. An edge of more than two
    triangles joins nothing; where no orientation agrees everywhere (a Möbius strip) one along
    a spanning tree of each part is taken. The tree is breadth-first from a root joined to a
    triangle of every part; the parity to the root is summed by pointer doubling,
    ``p(i) ← p(i) ⊕ p(a(i))``, ``a(i) ← a(a(i))``, log₂(depth) vectorised steps."""
    faces = len(triangles)
    sides = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=-1).reshape(-1, 2)
    key = sides.min(axis=1) * np.int64(count) + sides.max(axis=1)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    runs = np.flatnonzero(np.diff(np.concatenate([[-1], sorted_key, [-1]])))
    length = np.diff(runs)
    pair = runs[:-1][length == 2]  # sides of edges two triangles share
    first, second = order[pair], order[pair + 1]
    a, b = first // 3, second // 3
    disagree = (sides[first, 0] == sides[second, 0]).astype(np.int64)  # run the same way
    graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(faces, faces)).tocsr()
    part = connected_components(graph, directed=False)[1]
    root = faces  # a root joined to the first triangle of every part
    heads = np.unique(part, return_index=True)[1]
    rows = np.concatenate([a, b, np.full(heads.size, root)])
    cols = np.concatenate([b, a, heads])
    parity = np.concatenate([disagree, disagree, np.zeros(heads.size, np.int64)])
    tree = sp.coo_matrix((parity + 1, (rows, cols)), shape=(faces + 1,) * 2).tocsr()
    _, predecessor = breadth_first_order(tree, root, directed=False, return_predecessors=True)
    ancestor = np.append(predecessor[:faces], root).astype(np.int64)
    ancestor[heads] = root
    step = np.zeros(faces + 1, dtype=np.int64)
    child = np.flatnonzero(ancestor[:faces] != root)
    links = rows * np.int64(faces + 1) + cols  # each tree edge's parity, looked up by key
    ordered = np.argsort(links, kind="stable")
    found = np.searchsorted(links[ordered], ancestor[child] * np.int64(faces + 1) + child)
    step[child] = parity[ordered[found]]
    while (ancestor != root).any():
        step = step ^ step[ancestor]
        ancestor = ancestor[ancestor]
    flip = step[:faces].astype(bool)
    flipped = np.bincount(part, weights=flip, minlength=heads.size)
    sizes = np.bincount(part, minlength=heads.size)
    return flip ^ (flipped > sizes / 2)[part]
