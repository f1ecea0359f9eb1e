"""Catmull–Clark refinement with OpenSubdiv's creasing (the rules are told in
:mod:`g1patch.subdivision`): one step of positions, topology and child sharpness, the tags of the
refined mesh, and the refined grids of the original faces.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..mesh import INFINITE_SHARPNESS, QuadMesh, QuadTopology, Tag, refine_polygons
from ..mesh.cage import PolygonCage, PolygonTopology
from ..mesh.features import features_from_tags
from ..mesh.polygons import refine_corner_uvs
from .features import (
    RULE_CREASE,
    RULE_SMOOTH,
    BoundaryMode,
    _effective,
    _end_sums,
    _Level,
    _level_of,
    _rules,
    _segment_sum,
)

__all__ = ["catmull_clark_cage", "catmull_clark_points", "refine", "refine_grids"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: tags that :func:`refine` rebuilds from the child sharpness
_FEATURE_TAGS = frozenset({"crease", "corner", "hole"})


class _CageLevel(NamedTuple):
    """A polygon cage as a :class:`_Level` (the fields :func:`_step` reads)."""

    x: FloatArray
    topology: PolygonTopology
    edge: FloatArray
    vertex: FloatArray
    holes: BoolArray
    mode: BoundaryMode
    chaikin: bool


def _decrement(s: FloatArray) -> FloatArray:
    """OpenSubdiv's uniform sharpness subdivision: ∞ stays ∞, else ``s − 1``, 0 once ≤ 0."""
    return np.where(s >= INFINITE_SHARPNESS, INFINITE_SHARPNESS, np.maximum(s - 1.0, 0.0))


def _child_edge_halves(level: _Level | _CageLevel) -> tuple[FloatArray, FloatArray]:
    """Sharpness of each edge's two children, the one at ``edges[:, 0]`` and the one at ``edges[:,
    1]``."""
    s = level.edge
    if not level.chaikin:
        child = _decrement(s)
        return child, child
    topology = level.topology
    nv = topology.n_vertices
    a, b = topology.edges[:, 0], topology.edges[:, 1]
    semi = (s > 0) & (s < INFINITE_SHARPNESS)
    count = np.bincount(a[semi], minlength=nv) + np.bincount(b[semi], minlength=nv)
    total = np.bincount(a[semi], weights=s[semi], minlength=nv) + np.bincount(
        b[semi], weights=s[semi], minlength=nv
    )

    def at(end: IntArray) -> FloatArray:
        others = count[end] - 1
        mean = np.divide(total[end] - s, others, out=np.zeros_like(s), where=others > 0)
        blended = np.where(others > 0, 0.75 * s + 0.25 * mean, s)
        return np.where(semi, np.maximum(blended - 1.0, 0.0), _decrement(s))

    return at(a), at(b)


class _Weights(NamedTuple):
    """The coefficients of one step (:func:`_weights`): they depend on the features only, not on
    the positions."""

    half_a: FloatArray  # sharpness of each edge's child at ``edges[:, 0]``
    half_b: FloatArray  # ... and at ``edges[:, 1]``
    child_vertex: FloatArray  # the vertices' child sharpness
    edge: FloatArray  # per edge the weight s of the midpoint: ``s·midpoint + (1 − s)·smooth``
    parent_rule: IntArray
    child_rule: IntArray
    vertex: (
        FloatArray  # per vertex w: ``w·parent mask + (1 − w)·child mask`` where the rules differ
    )


def _weights(level: _Level | _CageLevel) -> _Weights:
    """The features' part of one step (:mod:`g1patch.subdivision`): child sharpness, each edge
    point's midpoint weight, each vertex's parent and child rule and the fractional weight of the
    transition, the mean of the sharpness values that decay to 0 here."""
    nv = level.topology.n_vertices
    edges = level.topology.edges
    a, b = edges[:, 0], edges[:, 1]
    s = level.edge
    half_a, half_b = _child_edge_halves(level)
    child_vertex = _decrement(level.vertex)
    edge = np.where(s <= 0, 0.0, np.where((half_a > 0) & (half_b > 0), 1.0, np.minimum(s, 1.0)))
    sharp = s > 0
    parent_rule = _rules(level.vertex, np.bincount(edges[sharp].ravel(), minlength=nv))
    child_count = np.bincount(a[half_a > 0], minlength=nv) + np.bincount(
        b[half_b > 0], minlength=nv
    )
    child_rule = _rules(child_vertex, child_count)
    if level.chaikin:
        decay_a, decay_b = sharp & (half_a <= 0), sharp & (half_b <= 0)
    else:
        decay_a = decay_b = sharp & (s <= 1.0)
    vertex_decays = (level.vertex > 0) & (child_vertex <= 0)
    total = (
        np.bincount(a[decay_a], weights=s[decay_a], minlength=nv)
        + np.bincount(b[decay_b], weights=s[decay_b], minlength=nv)
        + np.where(vertex_decays, level.vertex, 0.0)
    )
    count = (
        np.bincount(a[decay_a], minlength=nv)
        + np.bincount(b[decay_b], minlength=nv)
        + vertex_decays
    )
    vertex = np.minimum(np.divide(total, count, out=np.zeros(nv), where=count > 0), 1.0)
    return _Weights(half_a, half_b, child_vertex, edge, parent_rule, child_rule, vertex)


def _step(level: _Level | _CageLevel) -> _Level:
    """One Catmull–Clark step with OpenSubdiv's creasing (:mod:`g1patch.subdivision`), numbered like
    :func:`~g1patch.mesh.refine_polygons`: the V vertex points, one per edge (``edges`` order), one
    per face."""
    topology, x = level.topology, level.x
    nv, ne = topology.n_vertices, topology.n_edges
    edges = topology.edges
    a, b = edges[:, 0], edges[:, 1]
    weights = _weights(level)
    half_a, half_b = weights.half_a, weights.half_b

    face_points = topology.face_points(x)
    left = topology.face_of(topology.edge_halfedges[:, 0])
    right = topology.face_of(np.maximum(topology.edge_halfedges[:, 1], 0))
    middle = 0.5 * (x[a] + x[b])
    smooth_edge = 0.25 * (x[a] + x[b] + face_points[left] + face_points[right])
    weight = weights.edge[:, None]
    edge_points = np.where(
        weight == 0,
        smooth_edge,
        np.where(weight == 1, middle, weight * middle + (1 - weight) * smooth_edge),
    )

    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    n = topology.face_count[:, None].astype(np.float64)
    neighbour_sum = _segment_sum(origin, x[topology.target(h)], nv)
    face_sum = _segment_sum(origin, face_points[topology.face_of(h)], nv)
    smooth = ((n - 2.0) * x + (neighbour_sum + face_sum) / n) / n

    sharp = level.edge > 0
    parent_rule, child_rule = weights.parent_rule, weights.child_rule
    vertex_points = smooth.copy()
    creased = np.flatnonzero(parent_rule != RULE_SMOOTH)
    if creased.size:
        parent_crease = (6.0 * x + _end_sums(x, edges, sharp, sharp, nv)) / 8.0
        child_crease = (6.0 * x + _end_sums(x, edges, half_a > 0, half_b > 0, nv)) / 8.0
        parent_mask = np.where((parent_rule == RULE_CREASE)[:, None], parent_crease, x)
        child_mask = np.select(
            [child_rule[:, None] == RULE_SMOOTH, child_rule[:, None] == RULE_CREASE],
            [smooth, child_crease],
            x,
        )
        w = weights.vertex[:, None]
        blended = np.where(
            child_rule[:, None] == parent_rule[:, None],
            parent_mask,
            w * parent_mask + (1 - w) * child_mask,
        )
        vertex_points[creased] = blended[creased]
    points = np.concatenate([vertex_points, edge_points, face_points])

    corners, sizes = topology.polygons()
    _, quads, _ = refine_polygons(x, corners, sizes)
    child = QuadTopology.from_faces(quads, len(points))
    child_edge = np.zeros(child.n_edges)
    keys = child.edges[:, 0] * len(points) + child.edges[:, 1]
    m = nv + np.arange(ne)
    for end, values in ((a, half_a), (b, half_b)):
        positive = values > 0
        half_keys = np.minimum(end, m) * len(points) + np.maximum(end, m)
        child_edge[np.searchsorted(keys, half_keys[positive])] = values[positive]
    child_vertices = np.concatenate([weights.child_vertex, np.zeros(ne + topology.n_faces)])
    child_edge, child_vertices = _effective(child, child_edge, child_vertices, level.mode)
    return _Level(
        points,
        child,
        child_edge,
        child_vertices,
        np.repeat(level.holes, sizes),
        level.mode,
        level.chaikin,
    )


def _level_tags(tags: tuple[Tag, ...], level: _Level) -> tuple[Tag, ...]:
    """The mesh's other tags, then ``crease``, ``corner`` and ``hole`` tags of the level's features
    (boundary edges and the boundary rule's corners left implicit, zeros dropped)."""
    topology = level.topology
    out = [tag for tag in tags if tag.name not in _FEATURE_TAGS]
    creases = np.flatnonzero((level.edge > 0) & ~topology.is_boundary_edge)
    if creases.size:
        out.append(
            Tag(
                "crease",
                tuple(topology.edges[creases].ravel().tolist()),
                tuple(level.edge[creases].tolist()),
            )
        )
    implicit = (
        topology.is_boundary_vertex & (topology.face_count == 1) & (level.mode == "edge-and-corner")
    )
    corners = np.flatnonzero((level.vertex > 0) & ~implicit)
    if corners.size:
        out.append(Tag("corner", tuple(corners.tolist()), tuple(level.vertex[corners].tolist())))
    if level.holes.any():
        out.append(Tag("hole", tuple(np.flatnonzero(level.holes).tolist())))
    return tuple(out)


def catmull_clark_points(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """One Catmull–Clark step's positions (:mod:`g1patch.subdivision`), numbered like
    :func:`~g1patch.mesh.refine_polygons`: the V vertex points, then one point per edge
    (``topology.edges`` order), then one per face."""
    return _step(_level_of(mesh, sharpness)).x


def _cage_level(cage: PolygonCage) -> _CageLevel:
    """The polygon cage as a level: its connectivity and effective features."""
    topology = PolygonTopology.from_polygons(cage.corners, cage.sizes, cage.points.shape[0])
    features = features_from_tags(topology, cage.tags)
    mode: BoundaryMode = (
        "edge-and-corner" if features.boundary == "edge-and-corner" else "edge-only"
    )
    edge, vertex = _effective(topology, features.edge_sharpness, features.vertex_sharpness, mode)
    chaikin = features.crease_method == "chaikin"
    return _CageLevel(cage.points, topology, edge, vertex, features.holes, mode, chaikin)


def catmull_clark_cage(mesh: QuadMesh) -> QuadMesh:
    """The mesh whose Catmull–Clark limit is that of the polygon cage ``mesh`` was split from:
    one Catmull–Clark step of the cage (:mod:`g1patch.subdivision`: face points the centroids of
    their n corners, the old vertices moved by the smooth, crease and corner rules, creases and
    corners one level less sharp), on ``mesh``'s own topology. ``mesh`` itself where it was read
    as quads (no :attr:`~g1patch.mesh.QuadMesh.cage`)."""
    cage: PolygonCage | None = mesh.cage
    if cage is None:
        return mesh
    child = _step(_cage_level(cage))
    return QuadMesh(
        child.x,
        mesh.topology,
        _level_tags(cage.tags, child),
        mesh.source,
        mesh.repairs,
        uv=mesh.uv,
        groups=mesh.groups,
    )


def refine(mesh: QuadMesh, levels: int = 1, sharpness: ArrayLike | None = None) -> QuadMesh:
    """``levels`` Catmull–Clark steps (:mod:`g1patch.subdivision`) on the topology of
    :func:`~g1patch.mesh.subdivide` (old vertices, then one per edge, then one per face). Features
    from the mesh's tags, edge sharpness overridden by ``sharpness`` where given; the result's tags
    carry the child features (the other tags are kept), its UVs are the parent faces' bilinear
    UVs at the children's corners (:func:`~g1patch.mesh.polygons.refine_corner_uvs` each step),
    its groups those of the parent faces (face f's children are faces ``4^levels f`` on).
    ``levels = 0`` returns the mesh itself."""
    return refine_grids(mesh, levels, sharpness)[0]


def _edge_points(edge_keys: IntArray, nv: int, p: IntArray, q: IntArray) -> IntArray:
    """The vertex a refinement step puts on each edge p–q (``nv`` + the edge's index in
    ``edges`` order, found by its key ``min · nv + max`` among ``edge_keys``)."""
    return nv + np.searchsorted(edge_keys, np.minimum(p, q) * nv + np.maximum(p, q))


def _refinement(
    mesh: QuadMesh, levels: int, sharpness: ArrayLike | None = None
) -> Iterator[tuple[_Level, IntArray]]:
    """The levels 0, 1, …, ``levels`` of :func:`refine_grids`, each with the grid of the original
    faces at that level (``levels`` checked at the first ``next``)."""
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise InputError(f"levels: expected a non-negative integer, got {levels!r}")
    level = _level_of(mesh, sharpness)
    grid = mesh.faces[:, [[0, 3], [1, 2]]]
    yield level, grid
    for _ in range(int(levels)):
        topology = level.topology
        nv = topology.n_vertices
        edge_keys = topology.edges[:, 0] * nv + topology.edges[:, 1]
        h = np.arange(topology.n_halfedges)
        directed = topology.origin(h) * nv + topology.target(h)
        order = np.argsort(directed)
        cell = (
            order[np.searchsorted(directed[order], grid[:, :-1, :-1] * nv + grid[:, 1:, :-1])] >> 2
        )
        size = 2 * grid.shape[1] - 1
        fine = np.empty((grid.shape[0], size, size), dtype=np.int64)
        fine[:, ::2, ::2] = grid
        fine[:, 1::2, ::2] = _edge_points(edge_keys, nv, grid[:, :-1], grid[:, 1:])
        fine[:, ::2, 1::2] = _edge_points(edge_keys, nv, grid[:, :, :-1], grid[:, :, 1:])
        fine[:, 1::2, 1::2] = nv + topology.n_edges + cell
        level = _step(level)
        grid = fine
        yield level, grid


def _refined_mesh(mesh: QuadMesh, level: _Level, levels: int) -> QuadMesh:
    """The mesh of ``level``, ``levels`` steps below ``mesh``: its tags rebuilt, the UVs refined,
    the groups repeated for the children (``mesh`` itself for 0 levels)."""
    if not levels:
        return mesh
    uv = mesh.uv
    if uv is not None:
        for _ in range(int(levels)):
            uv = refine_corner_uvs(uv.reshape(-1, 2), np.full(uv.shape[0], 4, dtype=np.int64))
    groups = None if mesh.groups is None else mesh.groups.repeat(4 ** int(levels))
    return QuadMesh(
        level.x, level.topology, _level_tags(mesh.tags, level), mesh.source, uv=uv, groups=groups
    )


def refine_grids(
    mesh: QuadMesh, levels: int, sharpness: ArrayLike | None = None
) -> tuple[QuadMesh, IntArray]:
    """:func:`refine`, and per original face the refined vertices as a grid ``(F, m + 1, m + 1)``,
    ``m = 2^levels``: ``grid[f, i, j]`` sits at parameter ``(i/m, j/m)`` of face f (u from corner 0
    to 1, v from corner 0 to 3). Cell (i, j) of a level is the face holding the half-edge
    ``grid[i, j] → grid[i + 1, j]`` (refinement keeps orientation), its face point the cell's
    centre."""
    level, grid = deque(_refinement(mesh, levels, sharpness), maxlen=1)[0]  # the last level
    return _refined_mesh(mesh, level, levels), grid
