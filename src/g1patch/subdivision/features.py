"""Sharp features of Catmull–Clark subdivision (OpenSubdiv's Sdc rules, told in
:mod:`g1patch.subdivision`): the boundary rule, the infinitely sharp edges and corners, the vertex
rules, and one level of a mesh with its effective sharpness, which refinement steps and the limit
stencils read. The gathers and segmented sums they share live here too.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, as_float_array
from ..mesh import INFINITE_SHARPNESS, QuadMesh, QuadTopology
from ..mesh.cage import PolygonTopology

__all__ = [
    "BOUNDARY_MODES",
    "BoundaryMode",
    "INFINITE_SHARPNESS",
    "RULE_CORNER",
    "RULE_CREASE",
    "RULE_SMOOTH",
    "boundary_mode",
    "corner_vertices",
    "sharp_edges",
    "vertex_rules",
]

BoundaryMode = Literal["edge-only", "edge-and-corner"]
BOUNDARY_MODES: tuple[BoundaryMode, ...] = ("edge-only", "edge-and-corner")
#: vertex rules (:func:`vertex_rules`)
RULE_SMOOTH, RULE_CREASE, RULE_CORNER = 0, 1, 2

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


def boundary_mode(mesh: QuadMesh) -> BoundaryMode:
    """The mesh's boundary rule (``features.boundary``): ``edge-and-corner``, or ``edge-only`` (also
    for ``none``)."""
    return "edge-and-corner" if mesh.features.boundary == "edge-and-corner" else "edge-only"


def _segment_sum(index: IntArray, values: FloatArray, count: int) -> FloatArray:
    """``out[v] = Σ_{index[i] = v} values[i]`` for (N, 3) values."""
    return np.stack(
        [np.bincount(index, weights=values[:, d], minlength=count) for d in range(3)], axis=1
    )


def _edge_override(topology: QuadTopology, sharpness: ArrayLike) -> FloatArray:
    values = as_float_array("sharpness", sharpness)
    if values.shape != (topology.n_edges,):
        raise InputError(f"sharpness: expected shape ({topology.n_edges},), got {values.shape}")
    negative = np.flatnonzero(values < 0)
    if negative.size:
        raise InputError(
            f"sharpness: edge {negative[0]} has sharpness {values[negative[0]]:g}; a sharpness is "
            "≥ 0"
        )
    return values


def sharp_edges(mesh: QuadMesh | QuadTopology, sharpness: ArrayLike | None = None) -> BoolArray:
    """Per edge: infinitely sharp at every level, i.e. a boundary edge or sharpness ≥
    :data:`INFINITE_SHARPNESS`.

    The sharpness is ``sharpness`` where given, else the mesh's features (a bare topology has none).
    Semi-sharp edges are not in it (they are sharp for a few levels only)."""
    topology = mesh if isinstance(mesh, QuadTopology) else mesh.topology
    if sharpness is not None:
        values = _edge_override(topology, sharpness)
    elif isinstance(mesh, QuadMesh):
        values = mesh.features.edge_sharpness
    else:
        return topology.is_boundary_edge.copy()
    return topology.is_boundary_edge | (values >= INFINITE_SHARPNESS)


def corner_vertices(mesh: QuadMesh | QuadTopology, mode: BoundaryMode | None = None) -> BoolArray:
    """Vertices kept fixed at every level by the boundary rule: boundary vertices with one face in
    ``edge-and-corner`` mode. Given a mesh (and no mode), also the vertices tagged infinitely sharp
    (``t corner`` ≥ 10), with the mesh's own boundary rule."""
    topology = mesh if isinstance(mesh, QuadTopology) else mesh.topology
    if mode is None:
        mode = boundary_mode(mesh) if isinstance(mesh, QuadMesh) else "edge-only"
    corner = topology.is_boundary_vertex & (topology.face_count == 1)
    corner = corner if mode == "edge-and-corner" else np.zeros_like(corner)
    if isinstance(mesh, QuadMesh):
        corner = corner | mesh.features.corner_vertices
    return corner


# ----------------------------------------------------------------------------------------------
# One level: positions, topology and effective sharpness


class _Level(NamedTuple):
    """A mesh at one level of refinement with OpenSubdiv's effective sharpness: boundary edges ∞,
    and in ``edge-and-corner`` mode the one-face boundary vertices ∞."""

    x: FloatArray
    topology: QuadTopology
    edge: FloatArray
    vertex: FloatArray
    holes: BoolArray
    mode: BoundaryMode
    chaikin: bool

    @property
    def semi_sharp(self) -> bool:
        values = np.concatenate([self.edge, self.vertex])
        return bool(((values > 0) & (values < INFINITE_SHARPNESS)).any())


def _effective(
    topology: QuadTopology | PolygonTopology,
    edge: FloatArray,
    vertex: FloatArray,
    mode: BoundaryMode,
) -> tuple[FloatArray, FloatArray]:
    edge = np.where(
        topology.is_boundary_edge, INFINITE_SHARPNESS, np.minimum(edge, INFINITE_SHARPNESS)
    )
    vertex = np.minimum(vertex, INFINITE_SHARPNESS)
    if mode == "edge-and-corner":
        vertex = np.where(
            topology.is_boundary_vertex & (topology.face_count == 1), INFINITE_SHARPNESS, vertex
        )
    return edge, vertex


def _level_of(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> _Level:
    features = mesh.features
    topology = mesh.topology
    edge = features.edge_sharpness if sharpness is None else _edge_override(topology, sharpness)
    mode = boundary_mode(mesh)
    edge, vertex = _effective(topology, edge, features.vertex_sharpness, mode)
    return _Level(
        np.asarray(mesh.vertices, dtype=np.float64),
        topology,
        edge,
        vertex,
        np.asarray(features.holes, dtype=bool),
        mode,
        features.crease_method == "chaikin",
    )


def _rules(vertex_sharpness: FloatArray, sharp_count: IntArray) -> IntArray:
    """OpenSubdiv's vertex rule: corner if the vertex is sharp or more than two edges are, crease
    with two."""
    return np.select(
        [(vertex_sharpness > 0) | (sharp_count > 2), sharp_count == 2],
        [RULE_CORNER, RULE_CREASE],
        RULE_SMOOTH,
    )


def _end_sums(
    x: FloatArray, edges: IntArray, at_a: BoolArray, at_b: BoolArray, nv: int
) -> FloatArray:
    """Per vertex the sum of the far ends of the edges marked at that end."""
    a, b = edges[:, 0], edges[:, 1]
    return _segment_sum(a[at_a], x[b[at_a]], nv) + _segment_sum(b[at_b], x[a[at_b]], nv)


def _limit_rules(level: _Level) -> IntArray:
    """The rules of the limit masks (no fractional sharpness left): from the infinitely sharp
    features."""
    sharp = level.edge >= INFINITE_SHARPNESS
    count = np.bincount(level.topology.edges[sharp].ravel(), minlength=level.topology.n_vertices)
    return _rules(np.where(level.vertex >= INFINITE_SHARPNESS, 1.0, 0.0), count)


def vertex_rules(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> IntArray:
    """Per vertex the rule of its limit masks, :data:`RULE_SMOOTH` / :data:`RULE_CREASE` /
    :data:`RULE_CORNER`: that of the infinitely sharp features (semi-sharp ones decay before the
    limit)."""
    return _limit_rules(_level_of(mesh, sharpness))
