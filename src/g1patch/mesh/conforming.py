"""Local refinement of a quad mesh that stays a conforming quad mesh (no T-junctions).

The marked faces are split into four (their edges at the midpoints, a point at the centre). A
face beside them then has some of its sides split; quads can fill a face only when an even
number of its sides are (a quad mesh of a disk has an even number of boundary edges), so every
face ends with 0, 2 or 4 split sides and is filled by one of three templates:

* 4 sides: four quads round the centre (the marked faces' split);
* 2 opposite sides: two quads, the face cut in half;
* 2 sides meeting at corner ``a`` (midpoints ``m`` after ``a`` and ``n`` before it, far corners
  ``b c d``): three quads round the centre ``o``, ``(a m o n)``, ``(m b c o)``, ``(n o c d)``.

Which further sides are split so that no face keeps an odd count (:func:`split_sides`) is a
T-join problem on the face graph; it is closed in rounds: a face with three split sides joins
the marked faces; two odd faces that share a side split it; two odd faces with a common even
neighbour split their sides to it (both vectorised, repeated while they pair any); the few odd
faces left are paired by shortest paths (or led to the mesh boundary); what is still odd joins
the marked faces. The rounds stop because the marked set only grows. Topology only: positions
follow as a linear map (midpoints, centroids), so any per-vertex data can be carried the same
way.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import dijkstra

from .topology import QuadTopology

__all__ = ["LocalSplit", "local_split", "split_sides"]

IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: closing rounds at most (each one adds faces to the marked set or pairs odd faces; a few do)
MAX_ROUNDS = 64


def _side_counts(side_edge: IntArray, split: BoolArray) -> IntArray:
    return split[side_edge].sum(axis=1)


def _pair_by_shared_side(
    topology: QuadTopology, odd: BoolArray, split: BoolArray, side_edge: IntArray
) -> None:
    """Split the side shared by two odd faces, one side per face (each odd face offers its
    lowest such side; a side both its faces offer is split)."""
    halfedges = np.flatnonzero(np.repeat(odd, 4))
    twins = topology.twin[halfedges]
    inner = twins >= 0
    halfedges, twins = halfedges[inner], twins[inner]
    candidate = odd[twins >> 2] & ~split[topology.halfedge_edge[halfedges]]
    halfedges = halfedges[candidate]
    if not halfedges.size:
        return
    edges = topology.halfedge_edge[halfedges]
    offered = np.full(len(odd), np.iinfo(np.int64).max)
    np.minimum.at(offered, halfedges >> 2, edges)
    both = offered[halfedges >> 2] == edges
    twin_face = topology.twin[halfedges] >> 2
    both &= offered[twin_face] == edges
    split[edges[both]] = True


def _pair_through_neighbour(
    topology: QuadTopology, odd: BoolArray, marked: BoolArray, split: BoolArray
) -> None:
    """Two odd faces beside one even unmarked face: split both their sides to it (each middle
    face takes its two lowest odd neighbours; an odd face goes with the lowest middle face that
    takes it, and a pair stands when both its faces went with that face)."""
    face_count = len(odd)
    # half-edges of even unmarked faces whose twin face is odd, through an unsplit side
    halfedges = np.flatnonzero(np.repeat(~odd & ~marked, 4))
    twins = topology.twin[halfedges]
    keep = twins >= 0
    halfedges, twins = halfedges[keep], twins[keep]
    keep = odd[twins >> 2] & ~split[topology.halfedge_edge[halfedges]]
    halfedges, twins = halfedges[keep], twins[keep]
    if not halfedges.size:
        return
    middle, outer = halfedges >> 2, twins >> 2
    order = np.lexsort((outer, middle))
    middle, outer, halfedges = middle[order], outer[order], halfedges[order]
    distinct = np.r_[True, (middle[1:] != middle[:-1]) | (outer[1:] != outer[:-1])]
    middle, outer, halfedges = middle[distinct], outer[distinct], halfedges[distinct]
    rank = np.arange(len(middle)) - np.maximum.accumulate(
        np.where(np.r_[True, middle[1:] != middle[:-1]], np.arange(len(middle)), 0)
    )
    takes = rank < 2
    counts = np.bincount(middle[takes], minlength=face_count)
    pairs = takes & (counts[middle] == 2)
    middle, outer, halfedges = middle[pairs], outer[pairs], halfedges[pairs]
    if not middle.size:
        return
    chosen = np.full(face_count, face_count)
    np.minimum.at(chosen, outer, middle)
    agreed = chosen[outer] == middle
    stands = np.bincount(middle[agreed], minlength=face_count) == 2
    use = stands[middle]
    split[topology.halfedge_edge[halfedges[use]]] = True


def _pair_by_paths(
    topology: QuadTopology, odd: BoolArray, marked: BoolArray, split: BoolArray
) -> None:
    """Pair the odd faces left by shortest paths through unmarked faces and unsplit sides (the
    mesh boundary a node every boundary side leads to), nearest pairs first; the sides of all
    paths are split, a side two paths share is not (their symmetric difference keeps every
    face's parity). Few faces are left odd by the local passes, so one search per face."""
    face_count = len(odd)
    sink = face_count
    free = ~split[topology.halfedge_edge] & ~marked[np.arange(len(topology.twin)) >> 2]
    twins = topology.twin
    halfedges = np.flatnonzero(free & ((twins < 0) | (twins > np.arange(len(twins)))))
    far = np.where(twins[halfedges] >= 0, twins[halfedges] >> 2, sink)
    usable = (far == sink) | ~marked[np.minimum(far, face_count - 1)]
    halfedges, far = halfedges[usable], far[usable]
    near = halfedges >> 2
    low, high = np.minimum(near, far), np.maximum(near, far)
    keys, first = np.unique(low * (face_count + 1) + high, return_index=True)
    if not keys.size:
        return
    edges = topology.halfedge_edge[halfedges[first]]
    graph = sp.coo_matrix(
        (np.ones(keys.size), (low[first], high[first])), shape=(face_count + 1,) * 2
    ).tocsr()
    sources = np.flatnonzero(odd)
    distance, predecessor = dijkstra(
        graph, directed=False, indices=sources, unweighted=True, return_predecessors=True
    )
    ends = np.append(sources, sink)
    span = distance[:, ends]  # (k, k + 1): to every other odd face and to the boundary
    span[np.arange(len(sources)), np.arange(len(sources))] = np.inf
    paired = np.zeros(len(sources), dtype=bool)
    extra: set[int] = set()
    for flat in np.argsort(span, axis=None).tolist():
        row, column = divmod(flat, len(ends))
        if not np.isfinite(span[row, column]) or paired.all():
            break
        if paired[row] or (column < len(sources) and paired[column]):
            continue
        paired[row] = True
        if column < len(sources):
            paired[column] = True
        node = int(ends[column])
        while node != sources[row]:  # walk back to the source, toggling the sides passed
            previous = int(predecessor[row, node])
            key = min(node, previous) * (face_count + 1) + max(node, previous)
            extra ^= {int(edges[np.searchsorted(keys, key)])}
            node = previous
    split[list(extra)] = True


def split_sides(topology: QuadTopology, marked: BoolArray) -> tuple[BoolArray, BoolArray]:
    """Which edges to split, (E,) bool, and the faces split into four, (F,) bool (``marked`` and
    the faces the closing rounds add), so that every face has 0, 2 or 4 split sides."""
    marked = np.asarray(marked, dtype=bool).copy()
    side_edge = topology.halfedge_edge.reshape(-1, 4)
    split = np.zeros(topology.n_edges, dtype=bool)
    for _ in range(MAX_ROUNDS):
        split[side_edge[marked]] = True
        counts = _side_counts(side_edge, split)
        full = ~marked & (counts >= 3)
        if full.any():
            marked |= full
            continue
        odd = ~marked & (counts % 2 == 1)
        if not odd.any():
            return split, marked
        while True:  # pair until no pair is left (each pass takes the lowest-numbered ones)
            left = int(odd.sum())
            _pair_by_shared_side(topology, odd, split, side_edge)
            odd = ~marked & (_side_counts(side_edge, split) % 2 == 1)
            _pair_through_neighbour(topology, odd, marked, split)
            odd = ~marked & (_side_counts(side_edge, split) % 2 == 1)
            if not odd.any() or int(odd.sum()) == left:
                break
        if odd.any():
            _pair_by_paths(topology, odd, marked, split)
        counts = _side_counts(side_edge, split)
        marked |= ~marked & ((counts % 2 == 1) | (counts >= 3))
    raise RuntimeError(f"local_split: the sides did not close in {MAX_ROUNDS} rounds")


class LocalSplit(NamedTuple):
    """A conforming local refinement: the new ``faces`` (F', 4), ``weights`` (V', V) making
    the new vertices from the old (``new = weights @ old``; the old vertices first, then the
    edge midpoints, then the face centres), each new face's ``parent`` face, and the edges of
    the old mesh that were split (``split``, (E,) bool)."""

    faces: IntArray
    weights: sp.csr_matrix
    parent: IntArray
    split: BoolArray


def local_split(topology: QuadTopology, marked: BoolArray) -> LocalSplit:
    """The faces ``marked`` (F,) split into four and the mesh closed round them with the
    templates of the module docstring (:func:`split_sides` chooses the further splits)."""
    split, _ = split_sides(topology, marked)
    faces = topology.faces
    face_count, vertex_count = len(faces), topology.n_vertices
    side_edge = topology.halfedge_edge.reshape(-1, 4)
    side_split = split[side_edge]  # (F, 4): side i from corner i to i + 1
    counts = side_split.sum(axis=1)
    # new vertices: edge midpoints, then centres of the faces with 4 or 2 adjacent split sides
    midpoint = np.full(topology.n_edges, -1)
    midpoint[split] = vertex_count + np.arange(int(split.sum()))
    opposite = (side_split[:, 0] & side_split[:, 2]) | (side_split[:, 1] & side_split[:, 3])
    adjacent = (counts == 2) & ~opposite
    centred = (counts == 4) | adjacent
    centre = np.full(face_count, -1)
    first_centre = vertex_count + int(split.sum())
    centre[centred] = first_centre + np.arange(int(centred.sum()))
    mid = np.where(side_split, midpoint[side_edge], -1)  # (F, 4) midpoint of side i or -1

    new_faces, parents = [faces[counts == 0]], [np.flatnonzero(counts == 0)]
    # four quads: (v_i, m_i, o, m_{i-1})
    rows = np.flatnonzero(counts == 4)
    if rows.size:
        v, m, o = faces[rows], mid[rows], centre[rows][:, None].repeat(4, axis=1)
        quads = np.stack([v, m, o, np.roll(m, 1, axis=1)], axis=-1).reshape(-1, 4)
        new_faces.append(quads)
        parents.append(np.repeat(rows, 4))
    # two quads: sides i and i + 2 split (i = 0 or 1)
    rows = np.flatnonzero((counts == 2) & opposite)
    if rows.size:
        i = np.where(side_split[rows, 0], 0, 1)
        corner = faces[rows[:, None], (i[:, None] + np.arange(4)) % 4]
        m0, m2 = mid[rows, i], mid[rows, i + 2]
        halves = [
            np.stack([corner[:, 0], m0, m2, corner[:, 3]], axis=1),
            np.stack([m0, corner[:, 1], corner[:, 2], m2], axis=1),
        ]
        new_faces.append(np.stack(halves, axis=1).reshape(-1, 4))
        parents.append(np.repeat(rows, 2))
    # three quads: sides i - 1 and i split, meeting at corner a = v_i
    rows = np.flatnonzero(adjacent)
    if rows.size:
        i = np.argmax(side_split[rows] & np.roll(side_split[rows], 1, axis=1), axis=1)
        a, b, c, d = (faces[rows, (i + k) % 4] for k in range(4))
        m, n, o = mid[rows, i], mid[rows, (i + 3) % 4], centre[rows]
        thirds = [
            np.stack([a, m, o, n], axis=1),
            np.stack([m, b, c, o], axis=1),
            np.stack([n, o, c, d], axis=1),
        ]
        new_faces.append(np.stack(thirds, axis=1).reshape(-1, 4))
        parents.append(np.repeat(rows, 3))

    edges = topology.edges[split]
    centre_rows = np.flatnonzero(centred)
    total = first_centre + centre_rows.size
    weights = sp.csr_matrix(
        (
            np.concatenate(
                [
                    np.ones(vertex_count),
                    np.full(2 * len(edges), 0.5),
                    np.full(4 * centre_rows.size, 0.25),
                ]
            ),
            (
                np.concatenate(
                    [
                        np.arange(vertex_count),
                        np.repeat(vertex_count + np.arange(len(edges)), 2),
                        np.repeat(first_centre + np.arange(centre_rows.size), 4),
                    ]
                ),
                np.concatenate(
                    [np.arange(vertex_count), edges.reshape(-1), faces[centre_rows].reshape(-1)]
                ),
            ),
        ),
        shape=(total, vertex_count),
    )
    return LocalSplit(
        np.concatenate(new_faces).astype(np.int64),
        weights,
        np.concatenate(parents).astype(np.int64),
        split,
    )
