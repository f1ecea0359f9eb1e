"""The value passed between the shape-rule stage and the assembly, and the stage's types.

A *shape rule* (:data:`g1patch.targets.SHAPES`) decides what the surface should look like; an
*assembly* (:mod:`g1patch.construct`) turns any valid :class:`Targets` into patches that are
exactly G1, moving the targets only as far as G1 requires (DESIGN §1). The value passed between
them is one :class:`Targets`: flat arrays over the topology's vertices, ring slots, face corners and
edges, in the coordinates the assembly works in. Every rule is a :class:`ShapeFunction`.

Ring slots follow :class:`~g1patch.mesh.QuadTopology`: slot ``neighbor_offsets[v] + j`` of vertex v
points towards its neighbour ``neighbors[...]`` j, counter-clockwise; a boundary vertex with k faces
has k + 1 slots, the last one along its incoming boundary edge. So every directed mesh edge A → B,
boundary edges in both directions included, has exactly one slot at A.

A leaf of :mod:`g1patch.targets`: the rules import it, and the registry in the package imports the
rules.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError, as_float_array
from ..mesh import QuadMesh, QuadTopology

__all__ = [
    "TANGENTS",
    "ShapeFunction",
    "ShapeRule",
    "TangentRule",
    "Targets",
    "halfedge_slots",
    "slot_sector_normals",
]

#: the names of the shape rules (the keys of :data:`g1patch.targets.SHAPES`)
ShapeRule = Literal["interpolate", "limit", "limit-interpolate", "legacy"]
#: how a slot tangent's length is read off its mesh edge: the chord, or the circle-aware arc
TangentRule = Literal["chord", "arc"]
TANGENTS: tuple[TangentRule, ...] = ("chord", "arc")

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
#: the default of the :class:`Targets` fields that ``__post_init__`` fills in (None: not given)
_FILLED_IN: Any = None


def halfedge_slots(topology: QuadTopology) -> tuple[IntArray, IntArray]:
    """Ring slot of each half-edge A → B at A (``slot_out``), and of B → A at B (``slot_in``).

    The reverse of a boundary half-edge is the last slot of its target: the virtual ring edge k.
    """
    ring_vertex = np.repeat(np.arange(topology.n_vertices), topology.face_count)
    slot_out = np.empty(topology.n_halfedges, dtype=np.int64)
    slot_out[topology.ring_halfedges] = (
        np.arange(len(ring_vertex))
        - topology.ring_offsets[ring_vertex]
        + topology.neighbor_offsets[ring_vertex]
    )
    twin = topology.twin
    target = topology.target(np.arange(topology.n_halfedges))
    slot_in = np.where(twin >= 0, slot_out[twin], topology.neighbor_offsets[target + 1] - 1)
    return slot_out, slot_in


@dataclass(frozen=True, eq=False)
class Targets:
    """What the surface should interpolate and how it should bend, per mesh element.

    * ``positions`` (V, 3): the surface point at each vertex;
    * ``normals`` (V, 3): unit surface normal there;
    * ``tangents`` (S, 3): per ring slot, the full Hermite tangent of the boundary curve leaving
      the vertex along that edge (its Bézier edge point is ``x + t/3``); any fan, not only a
      regular star, as long as the slots turn counter-clockwise about the normal;
    * ``interior`` (F, 4, 2, 3): per face corner k, the targets of the interior Bézier point next
      to that corner (``b11`` at corner 0), i.e. ``x + (t_next + t_prev)/3 + twist/9``, as seen by
      edge k (``[..., 0, :]``) and by edge k − 1 (``[..., 1, :]``): a Gregory patch has one per
      edge, a tensor-product patch takes their mean (:attr:`corner_interior`);
    * ``seams`` (E,): edges the surface is meant to cross with a crease (only C0 there, on
      purpose): the two faces share the boundary curve and nothing more;
    * ``fallback`` (V,): vertices where the rule could not use its normal recipe and fell back;
    * ``corner_normals`` (F, 4, 3): the unit normal of each face corner's *sector* (the faces
      around its vertex reached without crossing a seam or the boundary); ``normals[faces]``
      (the default) wherever a vertex has one sector. A seam slot's tangent lies in the planes of
      both sectors it separates, a smooth slot's in its sector's plane.
    """

    topology: QuadTopology
    positions: FloatArray
    normals: FloatArray
    tangents: FloatArray
    interior: FloatArray
    seams: NDArray[np.bool_] = field(default=_FILLED_IN)
    fallback: NDArray[np.bool_] = field(default=_FILLED_IN)
    rule: str = "custom"
    corner_normals: FloatArray = field(default=_FILLED_IN)

    def __post_init__(self) -> None:
        topology = self.topology
        shapes = {
            "positions": (topology.n_vertices, 3),
            "normals": (topology.n_vertices, 3),
            "tangents": (int(topology.neighbor_offsets[-1]), 3),
            "interior": (topology.n_faces, 4, 2, 3),
        }
        for name, shape in shapes.items():
            value = as_float_array(f"targets.{name}", getattr(self, name), shape[1:])
            if value.shape != shape:
                raise InputError(f"targets.{name}: expected shape {shape}, got {value.shape}")
            object.__setattr__(self, name, value)
        flags = {"seams": topology.n_edges, "fallback": topology.n_vertices}
        for name, size in flags.items():
            value = getattr(self, name)
            value = np.zeros(size, dtype=bool) if value is None else np.asarray(value, dtype=bool)
            if value.shape != (size,):
                raise InputError(f"targets.{name}: expected shape ({size},), got {value.shape}")
            object.__setattr__(self, name, value)
        corner_normals = (
            self.normals[topology.faces]
            if self.corner_normals is None
            else as_float_array("targets.corner_normals", self.corner_normals, (4, 3))
        )
        if corner_normals.shape != (topology.n_faces, 4, 3):
            raise InputError(
                f"targets.corner_normals: expected shape ({topology.n_faces}, 4, 3), got "
                f"{corner_normals.shape}"
            )
        object.__setattr__(self, "corner_normals", corner_normals)

    @property
    def corner_interior(self) -> FloatArray:
        """One interior target per face corner, (F, 4, 3): the mean of the two edges' targets."""
        return 0.5 * (self.interior[:, :, 0] + self.interior[:, :, 1])

    @property
    def has_sectors(self) -> bool:
        """Whether any vertex has more than one sector (a seam or a creased boundary runs through
        it)."""
        return bool(self.seams.any())

    def with_changes(self, **changes: Any) -> Targets:
        """A copy with some fields replaced (validated again)."""
        return replace(self, **changes)

    @property
    def n_fallback(self) -> int:
        """How many vertices needed a fallback."""
        return int(self.fallback.sum())


class ShapeFunction(Protocol):
    """A shape rule: the :class:`Targets` of a mesh. ``tangents`` (:data:`TANGENTS`) chooses the
    slot tangents' lengths where the rule reads them off the mesh edges (``legacy``); the other
    rules take their own lengths and ignore it."""

    def __call__(self, mesh: QuadMesh, *, tangents: TangentRule = "arc") -> Targets: ...


def slot_sector_normals(targets: Targets) -> tuple[FloatArray, FloatArray]:
    """Per ring slot the corner normals of its two faces: ``(left, right)``, (S, 3) each.

    Slot j of a vertex lies between ring faces j − 1 (left, clockwise of it) and j (right); a
    boundary vertex's first slot has no left face and its last (virtual) slot no right face: the
    other one stands in for it.
    """
    topology = targets.topology
    corner = targets.corner_normals.reshape(-1, 3)[topology.ring_halfedges]  # per ring position
    face_count = topology.face_count
    ring_vertex = np.repeat(np.arange(topology.n_vertices), face_count)
    position = np.arange(ring_vertex.size) - topology.ring_offsets[ring_vertex]
    slot = topology.neighbor_offsets[ring_vertex] + position
    slot_count = int(topology.neighbor_offsets[-1])
    right = np.empty((slot_count, 3))
    left = np.empty((slot_count, 3))
    right[slot] = corner
    boundary = topology.is_boundary_vertex
    last = topology.neighbor_offsets[1:] - 1  # the virtual slot of a boundary vertex
    right[last[boundary]] = corner[topology.ring_offsets[1:][boundary] - 1]
    # left of slot j is ring face j − 1: cyclic inside, the slot's own face at a boundary's first
    # slot
    shifted = np.where(position == 0, position + face_count[ring_vertex] - 1, position - 1)
    left[slot] = np.where(
        ((position == 0) & boundary[ring_vertex])[:, None],
        corner,
        corner[topology.ring_offsets[ring_vertex] + shifted],
    )
    left[last[boundary]] = right[last[boundary]]
    return left, right
