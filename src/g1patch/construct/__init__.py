"""The assembly stage: any valid targets in, patches that are exactly G1 out (DESIGN §1).

:data:`ASSEMBLIES` is the registry the build, the API and the command line take their choices
from (``--method``): a new assembly is one module plus one line here. The contract an assembly
meets is :class:`~g1patch.construct.stage.Assembly`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import InputError
from ..network import Patches, PatchNetwork
from ..targets import Targets
from .corner import assemble_corner
from .gregory import assemble_gregory
from .one_per_face import keep_patches, patch_per_face_network
from .split4 import split4_network_from_parts, split4_patches, split4_provenance
from .split4.seams import split4_seam_patches
from .stage import Assembly, NetworkParts

__all__ = ["ASSEMBLIES", "DEFAULT_METHOD", "METHODS", "Assembly", "NetworkParts"]


def _assemble_split4(targets: Targets) -> Any:
    """split4's parts of ``targets`` (their positions are the corners; already in the frame) and
    the seams it keeps: cut open along them where there are any
    (:func:`~g1patch.construct.split4.seams.split4_seam_patches`)."""
    if targets.seams.any():
        return split4_seam_patches(targets)
    return split4_patches(targets, targets.positions, np.zeros(3), 1.0), targets.seams


def _split4_patches(parts: Any) -> Patches:
    patches: Patches = parts[0][0]
    return patches


def _keep_split4(parts: Any, targets: Targets, provenance: dict[str, str]) -> Any:
    """The sub-patches, midpoints, centres and their normals, the vertex normals; the stars only
    count into the provenance."""
    (sub_patches, extra, extra_normals, stars), seams = parts
    provenance = split4_provenance(provenance, targets, stars)
    return (sub_patches, extra, extra_normals, targets.normals, seams), provenance


def _split4_network(kept: Any, parts: NetworkParts) -> PatchNetwork:
    """The sub-patches connected on the mesh, seams marked; a hole face's four left out (they take
    part in every rule around them, as OpenSubdiv's holes do, but get no surface)."""
    sub_patches, extra, extra_normals, normals, seams = kept
    network = split4_network_from_parts(
        parts.surface,
        sub_patches,
        extra,
        extra_normals,
        normals,
        parts.frame,
        parts.provenance,
        seams if seams.any() else None,
    )
    holes = parts.mesh.features.holes
    if not holes.any():
        return network
    if holes.all():
        raise InputError("every face of the mesh is tagged as a hole: there is no surface to build")
    provenance = {**network.provenance, "holes": str(int(holes.sum()))}
    return replace(network.take_patches(np.repeat(~holes, 4)), provenance=provenance)


#: ``--method`` name → assembly, the default first
ASSEMBLIES: dict[str, Assembly] = {
    assembly.name: assembly
    for assembly in (
        Assembly(
            "split4",
            "exact G1, 2×2 polynomial bicubics per quad: exact in STEP (default)",
            _assemble_split4,
            4,
            _split4_patches,
            _keep_split4,
            _split4_network,
            3000,
            4900,
        ),
        Assembly(
            "gregory",
            "exact G1, one rational Gregory patch per quad: the fairest shape",
            assemble_gregory,
            1,
            lambda patches: patches,
            keep_patches,
            patch_per_face_network,
            1150,
            4000,
        ),
        Assembly(
            "corner",
            "the paper's construction: one Hermite patch per quad, G1 at corners only",
            assemble_corner,
            1,
            lambda patches: patches,
            keep_patches,
            patch_per_face_network,
            1700,
            1850,
        ),
    )
}
#: the names, default first
METHODS: tuple[str, ...] = tuple(ASSEMBLIES)
#: the method a build takes unless told: polynomial, so the CAD file is the surface itself
DEFAULT_METHOD = METHODS[0]
