"""A part of a mesh as a mesh of its own: the faces within some vertex rings of given faces, with
the tags that still apply to them (:func:`neighbourhood`). Subdivision reads a face's 1-ring only,
so refining such a part gives the whole mesh's refinement on the faces well inside it; the exact
limit samples and the feature-adaptive build refine only there."""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import MeshError
from .cage import PolygonCage
from .faces import _edge_keys
from .quadmesh import QuadMesh
from .tags import Tag
from .topology import QuadTopology

IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: times a neighbourhood takes in the faces round the vertices where it pinches
PINCH_FILLS = 3


class Neighbourhood(NamedTuple):
    """``mesh``: the part; ``faces``: the index in the whole mesh of each of its faces (in order);
    ``vertices``: the index in the whole mesh of each of its vertices (in order)."""

    mesh: QuadMesh
    faces: IntArray
    vertices: IntArray

    def rings_kept(self, whole: QuadTopology) -> tuple[IntArray, IntArray, IntArray]:
        """The part's vertices whose rings are ``whole``'s (every face round them in the part,
        each neighbour once), as ``(vertices, whole_slots, part_slots)``: their ids in the part,
        and each of their ring slots in ``whole`` and in the part, matched by the neighbour they
        point to (a ring may start at another face in the part)."""
        in_part = np.zeros(whole.n_faces, dtype=bool)
        in_part[self.faces] = True
        outside = np.zeros(whole.n_vertices, dtype=bool)
        outside[whole.faces[~in_part]] = True
        part = self.mesh.topology
        sizes = np.diff(part.neighbor_offsets)
        owner = np.repeat(np.arange(part.n_vertices), sizes)
        keys = self.vertices[owner] * whole.n_vertices + self.vertices[part.neighbors]
        order = np.argsort(keys, kind="stable")
        repeated = np.zeros(part.n_vertices, dtype=bool)
        repeated[owner[order[1:][np.diff(keys[order]) == 0]]] = True
        whole_sizes = np.diff(whole.neighbor_offsets)[self.vertices]
        vertices = np.flatnonzero(~outside[self.vertices] & ~repeated & (whole_sizes == sizes))
        starts = whole.neighbor_offsets[self.vertices[vertices]]
        counts = sizes[vertices]
        whole_slots = np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(
            counts.sum()
        )
        wanted = (
            np.repeat(self.vertices[vertices], counts) * whole.n_vertices
            + whole.neighbors[whole_slots]
        )
        part_slots = order[np.searchsorted(keys, wanted, sorter=order)]
        return vertices, whole_slots, part_slots


def grow(topology: QuadTopology, faces: ArrayLike, rings: int) -> BoolArray:
    """Faces within ``rings`` vertex rings of ``faces`` (a bool mask or indices): each ring adds
    every face that shares a vertex with the faces so far (0 rings: the faces themselves)."""
    keep = np.zeros(topology.n_faces, dtype=bool)
    keep[np.asarray(faces)] = True
    for _ in range(rings):
        touched = np.zeros(topology.n_vertices, dtype=bool)
        touched[topology.faces[keep]] = True
        keep = np.any(touched[topology.faces], axis=1)
    return keep


def pinched_vertices(topology: QuadTopology, keep: BoolArray) -> BoolArray:
    """Vertices whose ``keep`` faces form more than one fan: more than one run of kept faces
    round their ring (cyclic inside, from the first face at a boundary)."""
    ring_vertex = np.repeat(np.arange(topology.n_vertices), topology.face_count)
    position = np.arange(ring_vertex.size) - topology.ring_offsets[ring_vertex]
    kept = keep[topology.ring_halfedges >> 2]
    previous = np.where(
        position == 0, topology.ring_offsets[ring_vertex + 1] - 1, np.arange(ring_vertex.size) - 1
    )
    continued = kept[previous] & ~((position == 0) & topology.is_boundary_vertex[ring_vertex])
    return np.bincount(ring_vertex[kept & ~continued], minlength=topology.n_vertices) > 1


def subset_tags(mesh: QuadMesh, inside: IntArray) -> tuple[Tag, ...]:
    """The tags of ``mesh`` that still apply to its faces ``inside``: the boundary rule, the crease
    method, creases on edges of those faces (one sharpness each), corners on their vertices (holes
    do not change the rules around them, so they are dropped)."""
    topology = mesh.topology
    features = mesh.features
    used = np.zeros(topology.n_vertices, dtype=bool)
    used[topology.faces[inside]] = True
    h = (4 * inside[:, None] + np.arange(4)).ravel()
    present = np.zeros(topology.n_edges, dtype=bool)
    present[topology.halfedge_edge[h]] = True
    tags = [tag for tag in mesh.tags if tag.name in ("interpolateboundary", "creasemethod")]
    creased = np.flatnonzero(present & (features.edge_sharpness > 0))
    if creased.size:
        tags.append(
            Tag(
                "crease",
                tuple(topology.edges[creased].ravel().tolist()),
                tuple(features.edge_sharpness[creased].tolist()),
            )
        )
    cornered = np.flatnonzero(used & (features.vertex_sharpness > 0))
    if cornered.size:
        tags.append(
            Tag(
                "corner",
                tuple(cornered.tolist()),
                tuple(features.vertex_sharpness[cornered].tolist()),
            )
        )
    return tuple(tags)


def neighbourhood(mesh: QuadMesh, faces: ArrayLike, rings: int) -> Neighbourhood:
    """The faces within ``rings`` vertex rings of ``faces`` (:func:`grow`) as a mesh of their own,
    with the tags that still apply (:func:`subset_tags`; hole faces keep no hole). A vertex where
    those faces form two fans or more (two parts touching there) takes all its faces
    (:func:`pinched_vertices`, up to :data:`PINCH_FILLS` times); where the part is still not a
    manifold mesh of its own, or is all of it, it is the whole mesh (Spot refined twice: 6,272
    faces and 38 pinched vertices round a 3-ring part of them)."""
    topology = mesh.topology
    keep = grow(topology, faces, rings)
    for _ in range(PINCH_FILLS):
        pinched = pinched_vertices(topology, keep)
        if not pinched.any():
            break
        keep |= pinched[topology.faces].any(axis=1)
    whole = Neighbourhood(mesh, np.arange(topology.n_faces), np.arange(topology.n_vertices))
    if keep.all():
        return whole
    inside = np.flatnonzero(keep)
    try:
        part = QuadMesh.from_arrays(
            mesh.vertices, topology.faces[inside], tags=subset_tags(mesh, inside), strict=True
        )
    except MeshError:
        return whole
    # from_arrays keeps the used vertices in their order
    return Neighbourhood(part, inside, np.unique(topology.faces[inside]))


def cage_neighbourhood(mesh: QuadMesh, faces: ArrayLike, rings: int) -> Neighbourhood:
    """:func:`neighbourhood` of a mesh split from polygons (:attr:`QuadMesh.cage`), in whole
    polygons: every quad of a polygon it touches, and the part carries the part of the cage those
    polygons are (:func:`_part_cage`), so it is split from them as the whole is (the split's
    vertices keep their order: polygon vertices, edge points by sorted edge, face points). A mesh
    without a cage, or whose quads are not its cage's split, gets :func:`neighbourhood`."""
    cage = mesh.cage
    topology = mesh.topology
    if cage is None or cage.corners.size != topology.n_faces:
        return neighbourhood(mesh, faces, rings)
    polygon = np.repeat(np.arange(cage.sizes.size), cage.sizes)  # quad k: corner k's polygon
    keep = grow(topology, faces, rings)
    for _ in range(PINCH_FILLS + 1):
        touched = np.zeros(cage.sizes.size, dtype=bool)
        touched[polygon[keep]] = True
        keep = touched[polygon]
        pinched = pinched_vertices(topology, keep)
        if not pinched.any():
            break
        keep |= pinched[topology.faces].any(axis=1)
    whole = Neighbourhood(mesh, np.arange(topology.n_faces), np.arange(topology.n_vertices))
    if keep.all() or pinched_vertices(topology, keep).any():
        return whole
    inside = np.flatnonzero(keep)
    try:
        part = QuadMesh.from_arrays(
            mesh.vertices, topology.faces[inside], tags=subset_tags(mesh, inside), strict=True
        )
        part = replace(part, cage=_part_cage(cage, np.flatnonzero(touched)))
    except MeshError:
        return whole
    return Neighbourhood(part, inside, np.unique(topology.faces[inside]))


def _part_cage(cage: PolygonCage, polygons: IntArray) -> PolygonCage:
    """The ``polygons`` of ``cage`` as a cage of their own: the points they use (in order), their
    corners renumbered, and the tags that still apply (the boundary rule, the crease method,
    creases on their edges, corners on their points; holes dropped, as by :func:`subset_tags`)."""
    offsets = np.concatenate([[0], np.cumsum(cage.sizes)])
    sizes = cage.sizes[polygons]
    corners = cage.corners[
        np.repeat(offsets[polygons], sizes)
        + np.arange(sizes.sum())
        - np.repeat(np.cumsum(sizes) - sizes, sizes)
    ]
    n = len(cage.points)
    used = np.zeros(n, dtype=bool)
    used[corners] = True
    new_index = np.cumsum(used) - 1
    edges = np.unique(_edge_keys(corners, sizes, n))
    tags = [tag for tag in cage.tags if tag.name in ("interpolateboundary", "creasemethod")]
    for tag in cage.tags:
        ints = np.asarray(tag.ints, dtype=np.int64)
        if tag.name == "crease":
            a, b = ints[0::2], ints[1::2]
            sharpness = np.broadcast_to(np.asarray(tag.floats, dtype=np.float64), a.shape)
            present = np.isin(np.minimum(a, b) * n + np.maximum(a, b), edges)
            pairs = np.stack([new_index[a[present]], new_index[b[present]]], axis=1)
            if present.any():
                tags.append(
                    Tag("crease", tuple(pairs.ravel().tolist()), tuple(sharpness[present].tolist()))
                )
        elif tag.name == "corner":
            sharpness = np.broadcast_to(np.asarray(tag.floats, dtype=np.float64), ints.shape)
            present = used[ints]
            if present.any():
                tags.append(
                    Tag(
                        "corner",
                        tuple(new_index[ints[present]].tolist()),
                        tuple(sharpness[present].tolist()),
                    )
                )
    return PolygonCage(cage.points[used], new_index[corners], sizes, tuple(tags))
