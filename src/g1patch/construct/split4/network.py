"""The split4 network: the connectivity of the 4 F sub-patches (:func:`_split4_network`, face by
face in :func:`_network_kernel` from :data:`~g1patch.construct.split4.threshold.KERNEL_FACES`
faces on), with the mesh vertices, edge midpoints and face centres as its corners, and the build's
entry points from targets or from assembled parts.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import InputError
from ...frame import Frame
from ...kernels import in_chunks, jit_kernel
from ...mesh import QuadMesh, QuadTopology
from ...network import PatchNetwork
from ...patches import PatchSet
from ...targets import Targets
from .assembly import Split4Parts, split4_patches
from .stars import SplitStar
from .threshold import use_kernels

__all__ = [
    "split4_network_from_parts",
    "split4_network_from_points",
    "split4_network_from_targets",
    "split4_provenance",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


#: the (F, 4, 4) connectivity of the sub-patches, [f, sub-patch k, local corner or edge]: corner
#: ids, edge ids, edge reversed, neighbouring sub-patch, its edge (−1 on the boundary)
Connectivity = tuple[IntArray, IntArray, NDArray[np.bool_], IntArray, IntArray]


def _split4_network(
    topology: QuadTopology,
    patches: PatchSet,
    points: FloatArray,
    point_normals: FloatArray,
    provenance: dict[str, str],
    *,
    compiled: bool | None = None,
) -> PatchNetwork:
    """Connectivity of the 4 F sub-patches. Sub-patch k of face f has local corner k at V_k,
    k+1 at MID[k], k+2 at C, k+3 at MID[k−1]; its local edge k is the first half of half-edge
    h = 4f+k, edge k+1 seam k (M_k → C), edge k+2 seam k−1 reversed, edge k+3 the second half of
    prev(h). Edge ids: 2e (X half), 2e+1 (Y half) of mesh edge e, then 2E + 4f + k for seams.
    ``compiled``: face by face in :func:`_network_kernel` (the same integers), default from
    :data:`~g1patch.construct.split4.threshold.KERNEL_FACES` faces on.
    """
    n_faces, n_edges = topology.n_faces, topology.n_edges
    connect = _compiled_connectivity if use_kernels(n_faces, compiled) else _connectivity
    corner, edge_id, reversed_, neighbor, neighbor_edge = connect(topology)
    shape = (4 * n_faces, 4)
    return PatchNetwork(
        patches=patches,
        corner_ids=corner.reshape(shape),
        edge_ids=edge_id.reshape(shape),
        edge_reversed=reversed_.reshape(shape),
        neighbor=neighbor.reshape(shape),
        neighbor_edge=neighbor_edge.reshape(shape),
        same_direction=np.zeros(shape, dtype=bool),
        edge_collapsed=np.zeros(2 * n_edges + 4 * n_faces, dtype=bool),
        vertices=points,
        vertex_normals=point_normals,
        provenance=provenance,
    )


def _connectivity(topology: QuadTopology) -> Connectivity:
    """:data:`Connectivity` of the sub-patches by role, in NumPy (the reference): local edge l of
    sub-patch k has role (l − k) mod 4."""
    n_faces, n_edges, nv = topology.n_faces, topology.n_edges, topology.n_vertices
    h = np.arange(4 * n_faces).reshape(n_faces, 4)  # half-edge k = sub-patch k of face f
    k = np.arange(4)
    prev = QuadTopology.prev(h)
    role = (k[None, :] - k[:, None]) % 4  # [sub-patch k, local edge l] → role (l − k) % 4
    twin = topology.twin
    canonical = topology.edge_halfedges[topology.halfedge_edge, 0] == np.arange(4 * n_faces)
    edge = topology.halfedge_edge

    corner = np.empty((n_faces, 4, 4), dtype=np.int64)  # [f, sub-patch, local corner]
    by_role = [
        topology.faces,
        nv + edge[h],
        np.broadcast_to(nv + n_edges + np.arange(n_faces)[:, None], h.shape),
        nv + edge[prev],
    ]
    edge_id = np.empty_like(corner)
    reversed_ = np.empty(corner.shape, dtype=bool)
    neighbor = np.empty_like(corner)
    neighbor_edge = np.empty_like(corner)
    seam = 2 * n_edges + h
    for r in range(4):
        rows = np.nonzero(role == r)  # (sub-patch, local edge) pairs with this role
        corner[:, rows[0], rows[1]] = by_role[r][:, rows[0]]
    first_half = 2 * edge[h] + ~canonical[h]
    second_half = 2 * edge[prev] + canonical[prev]
    twin_h, twin_prev = twin[h], twin[prev]
    cases = [
        (
            first_half,
            ~canonical[h],
            np.where(twin_h >= 0, QuadTopology.next(twin_h), -1),
            twin_h & 3,
        ),
        (
            seam,
            np.zeros(h.shape, bool),
            4 * (h >> 2) + (k + 1) % 4,
            np.broadcast_to((k + 3) % 4, h.shape),
        ),
        (
            seam[:, (k - 1) % 4],
            np.ones(h.shape, bool),
            4 * (h >> 2) + (k - 1) % 4,
            np.broadcast_to(k, h.shape),
        ),
        (second_half, ~canonical[prev], twin_prev, twin_prev & 3),
    ]
    for r, (ids, rev, other, other_edge) in enumerate(cases):
        rows = np.nonzero(role == r)
        edge_id[:, rows[0], rows[1]] = ids[:, rows[0]]
        reversed_[:, rows[0], rows[1]] = rev[:, rows[0]]
        neighbor[:, rows[0], rows[1]] = np.where(other >= 0, other, -1)[:, rows[0]]
        neighbor_edge[:, rows[0], rows[1]] = np.where(other >= 0, other_edge, -1)[:, rows[0]]
    return corner, edge_id, reversed_, neighbor, neighbor_edge


def _compiled_connectivity(topology: QuadTopology) -> Connectivity:
    """:data:`Connectivity` of the sub-patches face by face (:func:`_network_kernel`, ranges side
    by side): the same integers as :func:`_connectivity`."""
    n_faces = topology.n_faces
    corner, edge_id, neighbor, neighbor_edge = (
        np.empty((n_faces, 4, 4), dtype=np.int64) for _ in range(4)
    )
    reversed_ = np.empty((n_faces, 4, 4), dtype=bool)
    in_chunks(
        partial(
            jit_kernel(_network_kernel),
            topology.faces,
            topology.halfedge_edge,
            topology.edge_halfedges,
            topology.twin,
            topology.n_vertices,
            corner,
            edge_id,
            reversed_,
            neighbor,
            neighbor_edge,
        ),
        n_faces,
    )
    return corner, edge_id, reversed_, neighbor, neighbor_edge


def _network_kernel(
    faces: IntArray,
    halfedge_edge: IntArray,
    edge_halfedges: IntArray,
    twin: IntArray,
    n_vertices: int,
    corner: IntArray,
    edge_id: IntArray,
    reversed_: NDArray[np.bool_],
    neighbor: IntArray,
    neighbor_edge: IntArray,
    lo: int,
    hi: int,
) -> None:
    """:func:`_split4_network`'s connectivity of faces ``lo:hi`` into the (F, 4, 4) arrays: local
    edge l of sub-patch k has role r = (l − k) mod 4 (0: first half of h, 1: seam k, 2: seam k − 1
    reversed, 3: second half of prev(h)), and its corner l is, by role, V_k, MID[k], C, MID[k−1]."""
    n_edges = edge_halfedges.shape[0]
    for f in range(lo, hi):
        for k in range(4):
            h, hp = 4 * f + k, 4 * f + ((k + 3) & 3)
            e, ep = halfedge_edge[h], halfedge_edge[hp]
            canonical, canonical_prev = edge_halfedges[e, 0] == h, edge_halfedges[ep, 0] == hp
            for r in range(4):
                side = (k + r) & 3
                if r == 0:
                    corner[f, k, side] = faces[f, k]
                    edge_id[f, k, side] = 2 * e + (0 if canonical else 1)
                    reversed_[f, k, side] = not canonical
                    other = twin[h]
                    neighbor[f, k, side] = (other & ~3) | ((other + 1) & 3) if other >= 0 else -1
                    neighbor_edge[f, k, side] = other & 3 if other >= 0 else -1
                elif r == 1:
                    corner[f, k, side] = n_vertices + e
                    edge_id[f, k, side] = 2 * n_edges + h
                    reversed_[f, k, side] = False
                    neighbor[f, k, side] = 4 * f + ((k + 1) & 3)
                    neighbor_edge[f, k, side] = (k + 3) & 3
                elif r == 2:
                    corner[f, k, side] = n_vertices + n_edges + f
                    edge_id[f, k, side] = 2 * n_edges + hp
                    reversed_[f, k, side] = True
                    neighbor[f, k, side] = hp
                    neighbor_edge[f, k, side] = k
                else:
                    corner[f, k, side] = n_vertices + ep
                    edge_id[f, k, side] = 2 * ep + (1 if canonical_prev else 0)
                    reversed_[f, k, side] = not canonical_prev
                    other = twin[hp]
                    neighbor[f, k, side] = other if other >= 0 else -1
                    neighbor_edge[f, k, side] = other & 3 if other >= 0 else -1


def split4_network_from_targets(
    mesh: QuadMesh,
    targets: Targets,
    frame: Frame,
    provenance: dict[str, str],
    seam_edges: ArrayLike | None = None,
    guide: FloatArray | None = None,
    parts: Split4Parts | None = None,
) -> PatchNetwork:
    """The 2×2-split bicubic network of ``targets`` (in the local coordinates of ``frame``):
    polynomial, exactly G1 on mesh edges and seams, C1 inside each quad, interpolating the mesh
    vertices (:mod:`g1patch.construct.split4`). The sub-patches stay in local coordinates and carry
    the frame.
    Provenance: vertices whose fan was refitted to spread directions join ``fallback_vertices``;
    those whose star the length safeguard scaled down are counted in ``star_safeguard_vertices``.

    ``seam_edges`` (E,) bool, in ``mesh.topology.edges`` order: mesh edges sharp on purpose; both
    halves of each (edge ids 2e, 2e + 1) become :attr:`PatchNetwork.seam` edges on both sides (the
    split's own inner seams M–C never are). ``guide``: per-face macro nets to follow
    (:func:`split4_patches`). ``parts``: ``split4_patches(targets, targets.positions, 0, 1)`` when
    the caller has it already."""
    if parts is None:
        parts = split4_patches(targets, targets.positions, np.zeros(3), 1.0, guide)
    patches, extra, extra_normals, stars = parts
    return split4_network_from_parts(
        mesh,
        patches,
        extra,
        extra_normals,
        targets.normals,
        frame,
        split4_provenance(provenance, targets, stars),
        seam_edges,
    )


def split4_provenance(
    provenance: dict[str, str], targets: Targets, stars: SplitStar
) -> dict[str, str]:
    """``provenance`` with split4's counts: ``fallback_vertices``, the vertices whose rule fell back
    or whose fan was refitted to spread directions, and ``star_safeguard_vertices``, those whose
    star the length safeguard scaled down."""
    return dict(
        provenance,
        fallback_vertices=str(int((targets.fallback | stars.refitted).sum())),
        star_safeguard_vertices=str(int(stars.shrunk.sum())),
    )


def split4_network_from_parts(
    mesh: QuadMesh,
    patches: PatchSet,
    extra: FloatArray,
    extra_normals: FloatArray,
    normals: FloatArray,
    frame: Frame,
    provenance: dict[str, str],
    seam_edges: ArrayLike | None = None,
) -> PatchNetwork:
    """:func:`split4_network_from_targets` of assembled parts (:func:`split4_patches`: ``patches``,
    the midpoints and centres ``extra`` and their normals, in the local coordinates of ``frame``)
    and the unit ``normals`` at the mesh vertices, without the targets: a caller that drops its
    targets and stars first builds the network's arrays without them (the build's peak, DESIGN
    §6)."""
    patches = patches.with_frame(frame)
    points = np.empty((mesh.topology.n_vertices + len(extra), 3))
    points[: mesh.topology.n_vertices] = mesh.vertices
    frame.to_world(
        extra, out=points[mesh.topology.n_vertices :]
    )  # the midpoints and centres, without a copy
    point_normals = np.concatenate([normals, extra_normals])
    return split4_network_from_points(
        mesh.topology, patches, points, point_normals, provenance, seam_edges
    )


def split4_network_from_points(
    topology: QuadTopology,
    patches: PatchSet,
    points: FloatArray,
    point_normals: FloatArray,
    provenance: dict[str, str],
    seam_edges: ArrayLike | None = None,
) -> PatchNetwork:
    """The network of the 4 F sub-patches ``patches`` (:func:`split4_patches`, with their frame)
    on ``topology``, its corners ``points`` (V + E + F, 3: the mesh vertices, the edge midpoints,
    the face centres) in world coordinates with their unit ``point_normals``; ``seam_edges`` as in
    :func:`split4_network_from_targets`."""
    network = _split4_network(topology, patches, points, point_normals, provenance)
    if seam_edges is None:
        return network
    sharp = np.asarray(seam_edges)
    if sharp.shape != (topology.n_edges,):
        raise InputError(
            f"seam_edges: expected shape ({topology.n_edges},), one per mesh edge, got "
            f"{sharp.shape}"
        )
    return network.with_seams(
        np.concatenate([np.repeat(sharp, 2), np.zeros(4 * topology.n_faces, dtype=sharp.dtype)])
    )
