"""Mesh → targets → assembly → network: the one call every front end uses (DESIGN §1).

``build_network(mesh, method, shape)`` picks a targets rule (``shape``: what the surface should
look like) and an assembly (``method``: how it is made exactly G1, or G1 at corners only) and runs
them in centred, unit-scaled coordinates ``x_local = (x − centre)/scale`` (bounding-box centre and
diagonal), so the result does not depend on where the model sits; the patches are mapped back to
the mesh's coordinates at the end and their corners set to the mesh vertices exactly.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from .construct.corner import TANGENTS, TangentRule, assemble_corner
from .construct.gregory import assemble_gregory
from .errors import check_choice
from .gregory import GregoryPatchSet
from .mesh import QuadMesh
from .network import PatchNetwork, network_from_mesh
from .patches import PatchSet
from .targets import Targets
from .targets.interpolate import SHAPES, ShapeRule, shape_targets

__all__ = ["METHODS", "Method", "build_gregory_network", "build_network", "build_split4_network", "local_frame"]

Method = Literal["gregory", "split4", "corner"]
METHODS: tuple[Method, ...] = ("gregory", "split4", "corner")


def local_frame(points: np.ndarray) -> tuple[np.ndarray, float]:
    """``(centre, scale)`` of the working coordinates: the bounding-box centre and diagonal (1 if 0)."""
    low, high = points.min(axis=0), points.max(axis=0)
    return 0.5 * (low + high), float(np.linalg.norm(high - low)) or 1.0


def _provenance(mesh: QuadMesh, method: str, shape: str, tangents: str, targets: Targets) -> dict[str, str]:
    provenance = {"method": method, "shape": shape, "fallback_vertices": str(targets.n_fallback)}
    if shape == "legacy":
        provenance["tangents"] = tangents
    if mesh.source:
        provenance["source"] = str(mesh.source)
    return provenance


def build_network(
    mesh: QuadMesh, method: Method = "gregory", shape: ShapeRule = "interpolate", *, tangents: TangentRule = "arc"
) -> PatchNetwork:
    """The patch network of ``mesh``: targets by ``shape``, assembled by ``method``.

    ``method``: ``gregory`` (exact G1, rational interiors), ``split4`` (exact G1, 2×2 polynomial
    bicubics per quad), ``corner`` (the paper: G1 at corners only). ``shape``: ``interpolate``
    (the default rules of :mod:`g1patch.targets.interpolate`) or ``legacy`` (the previous
    release's, for comparison). ``tangents`` (``arc`` or ``chord``) applies to ``legacy`` only.
    The network's provenance records both choices and how many vertices needed a fallback.
    """
    check_choice("method", method, METHODS)
    check_choice("shape", shape, SHAPES)
    check_choice("tangents", tangents, TANGENTS)
    centre, scale = local_frame(mesh.vertices)
    local = mesh.with_vertices((mesh.vertices - centre) / scale)
    targets = shape_targets(local, shape, tangents=tangents)
    provenance = _provenance(mesh, method, shape, tangents, targets)
    if method == "split4":
        from .construct.split4 import split4_network_from_targets

        return split4_network_from_targets(mesh, targets, centre, scale, provenance)
    if method == "corner":
        hermite = assemble_corner(targets).control
        hermite[:, :2, :2] = mesh.vertices[mesh.faces][:, [[0, 3], [1, 2]]]
        hermite[:, 2:] *= scale
        hermite[:, :2, 2:] *= scale
        patches: PatchSet | GregoryPatchSet = PatchSet(hermite, "hermite")
    else:
        points = assemble_gregory(targets).points * scale + centre
        points[:, :4] = mesh.vertices[mesh.faces]
        patches = GregoryPatchSet(points)
    return network_from_mesh(mesh.topology, patches, mesh.vertices, targets.normals, provenance)


def build_gregory_network(mesh: QuadMesh, *, shape: ShapeRule = "interpolate", tangents: TangentRule = "arc") -> PatchNetwork:
    """``build_network(mesh, "gregory", shape)``: exact G1, one rational Gregory patch per quad."""
    return build_network(mesh, "gregory", shape, tangents=tangents)


def build_split4_network(mesh: QuadMesh, *, shape: ShapeRule = "interpolate", tangents: TangentRule = "arc") -> PatchNetwork:
    """``build_network(mesh, "split4", shape)``: exact G1, 2×2 polynomial bicubics per quad."""
    return build_network(mesh, "split4", shape, tangents=tangents)
