"""Shape targets: what the surface should look like, before anything is made exactly G1.

The front door of the shape-rule stage: :data:`SHAPES`, the registry of the rules by name, and
:func:`shape_targets`, the one dispatcher. Every rule is a
:class:`~g1patch.targets.value.ShapeFunction`, ``mesh → Targets``; the value it returns and the
stage's other types live in the leaf module :mod:`g1patch.targets.value` (those the registry
names are re-exported here), so the rules import that and never this package: the registry
imports the implementations, never the reverse.

* ``interpolate`` (:mod:`~g1patch.targets.interpolate`): through the mesh vertices, shaped by local
  rules (fitted frames, projected tangents, twists);
* ``limit`` (:mod:`~g1patch.targets.limit`): the Catmull–Clark limit of the mesh as a control cage;
* ``limit-interpolate`` (:mod:`~g1patch.targets.limit_interpolate`): the limit of the cage whose
  limit passes through the mesh vertices;
* ``legacy`` (:mod:`~g1patch.targets.interpolate`): the previous release's rule, the benchmarks'
  baseline.

An *assembly* (:mod:`g1patch.construct`) turns any valid :class:`Targets` into patches that are
exactly G1.
"""

from __future__ import annotations

from ..errors import check_choice
from ..mesh import QuadMesh
from .interpolate import interpolate_targets, legacy_targets
from .limit import limit_targets
from .limit_interpolate import limit_interpolate_targets
from .value import ShapeFunction, TangentRule, Targets, halfedge_slots, slot_sector_normals

__all__ = [
    "SHAPES",
    "ShapeFunction",
    "TangentRule",
    "Targets",
    "halfedge_slots",
    "shape_targets",
    "slot_sector_normals",
]

#: the shape rules by name (:data:`~g1patch.targets.value.ShapeRule`), in the order the command line
#: lists them
SHAPES: dict[str, ShapeFunction] = {
    "interpolate": interpolate_targets,
    "limit": limit_targets,
    "limit-interpolate": limit_interpolate_targets,
    "legacy": legacy_targets,
}


def shape_targets(
    mesh: QuadMesh, shape: str = "interpolate", *, tangents: TangentRule = "arc"
) -> Targets:
    """The targets of ``mesh`` by the rule named ``shape`` (:data:`SHAPES`); ``tangents`` is for the
    rules that read their tangents' lengths off the mesh edges (``legacy``)."""
    check_choice("shape", shape, tuple(SHAPES))
    return SHAPES[shape](mesh, tangents=tangents)
