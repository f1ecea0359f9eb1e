"""The network of an assembly that makes one patch per quad (gregory, corner): the patches read in
the working frame, the hole faces left out (their edges become open boundaries)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
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
    if not holes.any():
        return network_from_mesh(
            topology, framed, vertices, normals, parts.provenance, seam_edges=seams
        )
    # hole faces take part in every rule around them (OpenSubdiv's semantics) but get no patch:
    # the network of all faces without theirs, so their edges become open boundaries (a mesh of
    # the other faces alone could be non-manifold, e.g. two holes meeting at a vertex)
    if holes.all():
        raise InputError("every face of the mesh is tagged as a hole: there is no surface to build")
    provenance = {**parts.provenance, "holes": str(int(holes.sum()))}
    whole = network_from_mesh(topology, framed, vertices, normals, provenance, seam_edges=seams)
    return whole.take_patches(~holes)
