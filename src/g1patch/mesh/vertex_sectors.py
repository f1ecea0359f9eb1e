"""The sectors of every vertex: its ring of faces cut at seam edges and at the boundary."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .connectivity import _Connectivity
from .topology import QuadTopology

__all__ = ["Sectors", "lonely_seams", "sectors"]

IntArray = NDArray[np.int64]


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
    ``topology`` may be a quad topology or the connectivity of polygons
    (:func:`~g1patch.mesh.connectivity._connect`), ``seams`` per edge."""
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


def lonely_seams(topology: QuadTopology, seams: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """The ``seams`` (per edge) that cut no ring: both ends have one sector (an isolated sharp
    edge between two darts, which leaves every vertex's fan whole)."""
    count = sectors(topology, seams).count
    a, b = topology.edges[:, 0], topology.edges[:, 1]
    return seams & (count[a] == 1) & (count[b] == 1)
