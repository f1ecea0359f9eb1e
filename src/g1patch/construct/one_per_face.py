"""The network of an assembly that makes one patch per quad (gregory, corner): the patches read in
the working frame, the hole faces left out (their edges become open boundaries)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ..mesh import QuadTopology
from ..network import Patches, PatchNetwork, network_from_mesh
from ..targets import Targets
from .stage import NetworkParts


def keep_patches(
    patches: Patches, targets: Targets, provenance: dict[str, str]
) -> tuple[tuple[Patches, np.ndarray, np.ndarray], dict[str, str]]:
    """The patches, the unit normals at the vertices and the seams: all the network needs."""
    return (patches, targets.normals, targets.seams), provenance


def patch_per_face_network(
    kept: tuple[Any, np.ndarray, np.ndarray], parts: NetworkParts
) -> PatchNetwork:
    """The network of one patch per face (``kept`` from :func:`keep_patches`)."""
    patches, normals, seams = kept
    framed = patches.with_frame(parts.frame)
    holes = parts.mesh.features.holes
    topology, vertices = parts.mesh.topology, parts.surface.vertices
    if holes.any():
        return _without_holes(topology, framed, vertices, normals, seams, parts.provenance, ~holes)
    return network_from_mesh(
        topology, framed, vertices, normals, parts.provenance, seam_edges=seams
    )


def _without_holes(
    topology: QuadTopology,
    patches: Patches,
    vertices: np.ndarray,
    normals: np.ndarray,
    seams: np.ndarray,
    provenance: dict[str, str],
    keep: np.ndarray,
) -> PatchNetwork:
    """The network of the faces ``keep`` only: hole faces take part in every rule around them
    (OpenSubdiv's semantics), but get no patch, so their edges become open boundaries."""
    if not keep.any():
        raise InputError("every face of the mesh is tagged as a hole: there is no surface to build")
    faces = topology.faces[keep]
    used = np.zeros(topology.n_vertices, dtype=bool)
    used[faces] = True
    index = np.cumsum(used) - 1
    sub = QuadTopology.from_faces(index[faces], int(used.sum()))
    # an edge of the sub-mesh is a seam where its parent edge was
    parent = topology.halfedge_edge[(4 * np.flatnonzero(keep)[:, None] + np.arange(4)).ravel()]
    sub_seams = np.zeros(sub.n_edges, dtype=bool)
    sub_seams[sub.halfedge_edge] = seams[parent]
    provenance = {**provenance, "holes": str(int((~keep).sum()))}
    return network_from_mesh(
        sub,
        patches.take(np.flatnonzero(keep)),
        vertices[used],
        normals[used],
        provenance,
        seam_edges=sub_seams,
    )
