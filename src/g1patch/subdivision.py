"""Catmull–Clark subdivision of quad meshes: refinement and limit stencils (OpenSubdiv's rules).

Every rule is a gather and a segmented sum (``np.bincount``) over half-edges or edges; the only
Python loops run over refinement levels or coordinates. From :data:`KERNEL_VERTICES` vertices on,
the smooth vertices' limit stencils (positions, stars, slot tangents) run as numba kernels, vertex
by vertex, that add the same terms in the same order: the same floats as the NumPy code, which
stays as the reference (and does the crease and corner vertices). With ``n`` faces at a smooth
vertex V, ring neighbours ``E_i`` (counter-clockwise, ring order of
:class:`~g1patch.mesh.QuadTopology`), ``D_i`` the corner of face i (between ``E_i`` and ``E_{i+1}``)
opposite V, and face points ``F_i``:

* **refinement** (:func:`refine`): face point = centroid; smooth edge point
  ``(A + B + F_L + F_R)/4``, sharp edge point ``(A + B)/2``; smooth vertex
  ``((n − 2) V + ΣE_i/n + ΣF_i/n)/n``, crease vertex (two sharp edges to A, B)
  ``(6V + A + B)/8``, corner vertex ``V``;
* **limit positions** (:func:`limit_points`): smooth ``(n² V + 4ΣE_i + ΣD_i)/(n(n + 5))``,
  crease ``(4V + A + B)/6``, corner ``V``;
* **limit tangents** (:func:`limit_tangents`), per ring slot: at a smooth vertex the eigen
  tangents ``A = Σ 4 cos(iθ) E_i + c (cos iθ + cos(i+1)θ) D_i`` and the same ``B`` with sines,
  ``θ = 2π/n``, ``c = 1/(4λ − 1)``, ``λ = 5/16 + (cos θ + cos(θ/2) √(2(9 + cos θ)))/16``
  (OpenSubdiv's mask; its rotation by one slot is ``cos θ A + sin θ B``), so slot j gets ``s_n (cos
  jθ A + sin jθ B)``; in a crease sector with k faces between the sharp slots ``E_0`` (leading,
  counter-clockwise first) and ``E_k`` those two slots get ``±(E_0 − E_k)/2`` and slot j ``cos(jπ/k)
  a + sin(jπ/k) b`` with ``a = (E_0 − E_k)/2`` and b the cross eigen-mask of the sector
  (:func:`_cross_mask`; for k = 2 the B-spline's). A boundary vertex is a crease vertex with one
  sector; an interior crease vertex has two, each with its own b (the sectors do not see each
  other's faces). At a corner every slot gets its chord ``E_j − V`` (OpenSubdiv's corner tangent
  mask; exact on the sharp slots, whose limit curves are end-interpolating B-splines; a corner
  sector with ≥ 3 faces has a subdominant eigenvalue above 1/2, so its inner slots have no exact
  tangent). Scale: every smooth star is normalised so that the planar fan of unit spokes at even
  angles with parallelogram faces gets unit tangents, ``s_n = 1/(2n + c n (1 + cos θ))``. On a
  regular region (valence 4 inside, two faces on a boundary or crease) this is exactly the uniform
  bicubic B-spline's Hermite tangent (``s_4 = 1/12``), i.e. 3 × (Bézier edge point − corner); at an
  extraordinary vertex the limit surface has no finite non-zero derivative along the edge (speed ``~
  (2λ)^m`` after m steps), so any length is a choice: this one is the regular case's reading of the
  same fan; :mod:`g1patch.targets.limit` fits it to the limit curve.

**Features** come from :attr:`QuadMesh.features <g1patch.mesh.QuadMesh.features>` (OpenSubdiv's
``t crease``, ``t corner``, ``t hole``, ``t interpolateboundary``, ``t creasemethod`` tags); the
``sharpness`` argument of the functions, per edge in ``QuadTopology.edges`` order, overrides the
edge sharpness of the tags. OpenSubdiv's (Sdc) rules, per level:

* boundary edges are infinitely sharp; the boundary rule ``edge-only`` keeps a boundary vertex
  with one face a crease vertex, ``edge-and-corner`` makes it a corner (vertex sharpness ∞).
  ``none`` (OpenSubdiv turns the boundary faces into holes) is treated as ``edge-only`` here;
* a vertex's rule comes from its vertex sharpness and the count of incident edges with sharpness
  > 0: corner if the vertex sharpness is > 0 or more than two edges are sharp, crease with two,
  smooth with fewer (one: a dart, smooth rules);
* an edge point blends: smooth mask for sharpness 0; the midpoint where both child edges stay
  sharp; otherwise ``s·midpoint + (1 − s)·smooth`` (OpenSubdiv's crease-to-smooth transition,
  s clamped to 1);
* a vertex point: the smooth mask if the parent vertex is smooth; else the parent rule's mask,
  and where the child's rule differs (some sharpness decayed to 0 this step) ``w·parent +
  (1 − w)·child`` with w the mean of the decaying sharpness values (OpenSubdiv's
  ``ComputeFractionalWeightAtVertex``: the vertex sharpness if it decays, every incident edge
  with ``0 < s ≤ 1`` — or, with Chaikin, every edge whose child at this vertex decays — clamped to
  1);
* child sharpness: ``s − 1`` (0 once ≤ 0) for edges and vertices, ∞ (≥ 10) stays ∞; with
  ``creasemethod chaikin`` each child edge takes ``0.75 s + 0.25 s̄ − 1`` where s̄ is the mean of
  the other semi-sharp edges at the end vertex it touches (plain ``s − 1`` if there is none);
* hole faces take part in every rule; their children are holes.

:func:`refine` returns the refined mesh with tags rebuilt from the child sharpness (one ``crease``
tag with a value per edge, one ``corner`` tag, one ``hole`` tag; zeros dropped), so refining twice
by one level is refining once by two. Limits: the masks above hold once no sharpness is
fractional; where the mesh is semi-sharp, :func:`limit_points`, :func:`limit_tangents`,
:func:`limit_stars`, :func:`limit_normals` and :func:`limit_corner_normals` refine the faces around
the affected vertices (those with a semi-sharp vertex sharpness or incident edge) until every
sharpness has decayed (⌈max s⌉ levels) and take the masks there, the vertices keeping their
indices. Tangents are then in the original face's parameter scale: the refined tangents times
``2^levels`` (a refined edge spans half the parameter of its parent).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache, lru_cache
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError, MeshError, as_float_array
from .mesh import QuadMesh, QuadTopology, Tag, refine_polygons

__all__ = [
    "BOUNDARY_MODES",
    "BoundaryMode",
    "INFINITE_SHARPNESS",
    "KERNEL_VERTICES",
    "RULE_CORNER",
    "RULE_CREASE",
    "RULE_SMOOTH",
    "boundary_mode",
    "LimitData",
    "catmull_clark_points",
    "corner_vertices",
    "limit_corner_normals",
    "limit_data",
    "limit_normals",
    "limit_points",
    "limit_stars",
    "limit_tangents",
    "refine",
    "refine_grids",
    "sharp_edges",
    "vertex_rules",
]

BoundaryMode = Literal["edge-only", "edge-and-corner"]
BOUNDARY_MODES: tuple[BoundaryMode, ...] = ("edge-only", "edge-and-corner")
#: OpenSubdiv's infinitely sharp crease
INFINITE_SHARPNESS = 10.0
#: vertex rules (:func:`vertex_rules`)
RULE_SMOOTH, RULE_CREASE, RULE_CORNER = 0, 1, 2

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

_SMOOTH, _CREASE, _CORNER = RULE_SMOOTH, RULE_CREASE, RULE_CORNER
#: from this many vertices on, the smooth vertices' limit stencils run as numba kernels (bit for
#: bit the NumPy reference's values); below it the compile, once per install, would cost more
KERNEL_VERTICES = 20_000
#: tags that :func:`refine` rebuilds from the child sharpness
_FEATURE_TAGS = frozenset({"crease", "corner", "hole"})


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
    topology: QuadTopology, edge: FloatArray, vertex: FloatArray, mode: BoundaryMode
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


def _decrement(s: FloatArray) -> FloatArray:
    """OpenSubdiv's uniform sharpness subdivision: ∞ stays ∞, else ``s − 1``, 0 once ≤ 0."""
    return np.where(s >= INFINITE_SHARPNESS, INFINITE_SHARPNESS, np.maximum(s - 1.0, 0.0))


def _child_edge_halves(level: _Level) -> tuple[FloatArray, FloatArray]:
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


def _rules(vertex_sharpness: FloatArray, sharp_count: IntArray) -> IntArray:
    """OpenSubdiv's vertex rule: corner if the vertex is sharp or more than two edges are, crease
    with two."""
    return np.select(
        [(vertex_sharpness > 0) | (sharp_count > 2), sharp_count == 2], [_CORNER, _CREASE], _SMOOTH
    )


def _end_sums(
    x: FloatArray, edges: IntArray, at_a: BoolArray, at_b: BoolArray, nv: int
) -> FloatArray:
    """Per vertex the sum of the far ends of the edges marked at that end."""
    a, b = edges[:, 0], edges[:, 1]
    return _segment_sum(a[at_a], x[b[at_a]], nv) + _segment_sum(b[at_b], x[a[at_b]], nv)


def _step(level: _Level) -> _Level:
    """One Catmull–Clark step with OpenSubdiv's creasing (module docstring), numbered like
    :func:`~g1patch.mesh.refine_polygons`: the V vertex points, one per edge (``edges`` order), one
    per face."""
    topology, x = level.topology, level.x
    nv, ne = topology.n_vertices, topology.n_edges
    edges = topology.edges
    a, b = edges[:, 0], edges[:, 1]
    s = level.edge
    half_a, half_b = _child_edge_halves(level)
    child_vertex = _decrement(level.vertex)

    face_points = x[topology.faces].mean(axis=1)
    left = topology.edge_halfedges[:, 0] >> 2
    right = np.maximum(topology.edge_halfedges[:, 1], 0) >> 2
    middle = 0.5 * (x[a] + x[b])
    smooth_edge = 0.25 * (x[a] + x[b] + face_points[left] + face_points[right])
    weight = np.where(s <= 0, 0.0, np.where((half_a > 0) & (half_b > 0), 1.0, np.minimum(s, 1.0)))[
        :, None
    ]
    edge_points = np.where(
        weight == 0,
        smooth_edge,
        np.where(weight == 1, middle, weight * middle + (1 - weight) * smooth_edge),
    )

    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    n = topology.face_count[:, None].astype(np.float64)
    neighbour_sum = _segment_sum(origin, x[topology.target(h)], nv)
    face_sum = _segment_sum(origin, face_points[h >> 2], nv)
    smooth = ((n - 2.0) * x + (neighbour_sum + face_sum) / n) / n

    sharp = s > 0
    parent_rule = _rules(level.vertex, np.bincount(edges[sharp].ravel(), minlength=nv))
    child_count = np.bincount(a[half_a > 0], minlength=nv) + np.bincount(
        b[half_b > 0], minlength=nv
    )
    child_rule = _rules(child_vertex, child_count)
    vertex_points = smooth.copy()
    creased = np.flatnonzero(parent_rule != _SMOOTH)
    if creased.size:
        parent_crease = (6.0 * x + _end_sums(x, edges, sharp, sharp, nv)) / 8.0
        child_crease = (6.0 * x + _end_sums(x, edges, half_a > 0, half_b > 0, nv)) / 8.0
        parent_mask = np.where((parent_rule == _CREASE)[:, None], parent_crease, x)
        child_mask = np.select(
            [child_rule[:, None] == _SMOOTH, child_rule[:, None] == _CREASE],
            [smooth, child_crease],
            x,
        )
        # the fractional weight of the transition: the mean of the sharpness values that decay to 0
        # here
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
        w = np.minimum(np.divide(total, count, out=np.zeros(nv), where=count > 0), 1.0)[:, None]
        blended = np.where(
            child_rule[:, None] == parent_rule[:, None],
            parent_mask,
            w * parent_mask + (1 - w) * child_mask,
        )
        vertex_points[creased] = blended[creased]
    points = np.concatenate([vertex_points, edge_points, face_points])

    _, quads, _ = refine_polygons(
        x, topology.faces.ravel(), np.full(topology.n_faces, 4, dtype=np.int64)
    )
    child = QuadTopology.from_faces(quads, len(points))
    child_edge = np.zeros(child.n_edges)
    keys = child.edges[:, 0] * len(points) + child.edges[:, 1]
    m = nv + np.arange(ne)
    for end, values in ((a, half_a), (b, half_b)):
        positive = values > 0
        half_keys = np.minimum(end, m) * len(points) + np.maximum(end, m)
        child_edge[np.searchsorted(keys, half_keys[positive])] = values[positive]
    child_vertices = np.concatenate([child_vertex, np.zeros(ne + topology.n_faces)])
    child_edge, child_vertices = _effective(child, child_edge, child_vertices, level.mode)
    return _Level(
        points,
        child,
        child_edge,
        child_vertices,
        np.repeat(level.holes, 4),
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
    """One Catmull–Clark step's positions (module docstring), numbered like
    :func:`~g1patch.mesh.refine_polygons`: the V vertex points, then one point per edge
    (``topology.edges`` order), then one per face."""
    return _step(_level_of(mesh, sharpness)).x


def refine(mesh: QuadMesh, levels: int = 1, sharpness: ArrayLike | None = None) -> QuadMesh:
    """``levels`` Catmull–Clark steps (module docstring) on the topology of
    :func:`~g1patch.mesh.subdivide` (old vertices, then one per edge, then one per face). Features
    from the mesh's tags, edge sharpness overridden by ``sharpness`` where given; the result's tags
    carry the child features (the other tags are kept). ``levels = 0`` returns the mesh itself."""
    return refine_grids(mesh, levels, sharpness)[0]


def refine_grids(
    mesh: QuadMesh, levels: int, sharpness: ArrayLike | None = None
) -> tuple[QuadMesh, IntArray]:
    """:func:`refine`, and per original face the refined vertices as a grid ``(F, m + 1, m + 1)``,
    ``m = 2^levels``: ``grid[f, i, j]`` sits at parameter ``(i/m, j/m)`` of face f (u from corner 0
    to 1, v from corner 0 to 3). Cell (i, j) of a level is the face holding the half-edge
    ``grid[i, j] → grid[i + 1, j]`` (refinement keeps orientation), its face point the cell's
    centre."""
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise InputError(f"levels: expected a non-negative integer, got {levels!r}")
    level = _level_of(mesh, sharpness)
    grid = mesh.faces[:, [[0, 3], [1, 2]]]
    for _ in range(int(levels)):
        topology = level.topology
        nv = topology.n_vertices
        edge_keys = topology.edges[:, 0] * nv + topology.edges[:, 1]
        h = np.arange(topology.n_halfedges)
        directed = topology.origin(h) * nv + topology.target(h)
        order = np.argsort(directed)

        def edge_point(p: IntArray, q: IntArray) -> IntArray:
            return nv + np.searchsorted(edge_keys, np.minimum(p, q) * nv + np.maximum(p, q))

        cell = (
            order[np.searchsorted(directed[order], grid[:, :-1, :-1] * nv + grid[:, 1:, :-1])] >> 2
        )
        size = 2 * grid.shape[1] - 1
        fine = np.empty((grid.shape[0], size, size), dtype=np.int64)
        fine[:, ::2, ::2] = grid
        fine[:, 1::2, ::2] = edge_point(grid[:, :-1], grid[:, 1:])
        fine[:, ::2, 1::2] = edge_point(grid[:, :, :-1], grid[:, :, 1:])
        fine[:, 1::2, 1::2] = nv + topology.n_edges + cell
        level = _step(level)
        grid = fine
    if not levels:
        return mesh, grid
    return QuadMesh(level.x, level.topology, _level_tags(mesh.tags, level), mesh.source), grid


# ----------------------------------------------------------------------------------------------
# Limit stencils


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


def _limit_positions(level: _Level, compiled: bool | None = None) -> FloatArray:
    """Limit positions (module docstring). ``compiled`` (None: from :data:`KERNEL_VERTICES` vertices
    on): the smooth vertices by :func:`_positions_kernel`, bit for bit the NumPy reference's
    values."""
    topology, x = level.topology, level.x
    nv = topology.n_vertices
    rule = _limit_rules(level)
    if _kernel_wanted(compiled, nv):
        from .kernels import jit_kernel  # numba, imported on first use

        points = x.copy()  # corners stay
        crease = np.flatnonzero(rule == _CREASE)
        if crease.size:
            sharp = level.edge >= INFINITE_SHARPNESS
            points[crease] = ((4.0 * x + _end_sums(x, topology.edges, sharp, sharp, nv)) / 6.0)[
                crease
            ]
        jit_kernel(_positions_kernel)(
            x,
            topology.faces,
            topology.ring_offsets,
            topology.ring_halfedges,
            rule == _SMOOTH,
            points,
        )
        return points
    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    neighbours = _segment_sum(origin, x[topology.target(h)], nv)
    opposite = _segment_sum(origin, x[topology.origin(QuadTopology.next(QuadTopology.next(h)))], nv)
    n = topology.face_count[:, None].astype(np.float64)
    smooth = (n * n * x + 4.0 * neighbours + opposite) / (n * (n + 5.0))
    sharp = level.edge >= INFINITE_SHARPNESS
    crease = (4.0 * x + _end_sums(x, topology.edges, sharp, sharp, nv)) / 6.0
    return np.select([rule[:, None] == _SMOOTH, rule[:, None] == _CREASE], [smooth, crease], x)


def _kernel_wanted(compiled: bool | None, count: int) -> bool:
    """Whether the limit stencils run as numba kernels: ``compiled`` when given, else from
    :data:`KERNEL_VERTICES` on."""
    return count >= KERNEL_VERTICES if compiled is None else compiled


def _positions_kernel(
    x: FloatArray,
    faces: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    smooth: BoolArray,
    points: FloatArray,
) -> None:
    """``points[v] = (n² V + 4ΣE_i + ΣD_i)/(n(n + 5))`` at the smooth vertices, the sums in
    half-edge order as :func:`_segment_sum` adds them (the ring sorted), so the values are the
    reference's."""
    order = np.empty(max(1, int(np.max(ring_offsets[1:] - ring_offsets[:-1]))), dtype=np.int64)
    for v in range(smooth.size):
        if not smooth[v]:
            continue
        r0 = ring_offsets[v]
        k = ring_offsets[v + 1] - r0
        for i in range(k):  # insertion sort: rings are short
            h = ring_halfedges[r0 + i]
            j = i
            while j > 0 and order[j - 1] > h:
                order[j] = order[j - 1]
                j -= 1
            order[j] = h
        n0 = n1 = n2 = o0 = o1 = o2 = 0.0
        for i in range(k):
            h = order[i]
            f, c = h >> 2, h & 3
            e, d = faces[f, (c + 1) & 3], faces[f, (c + 2) & 3]
            n0 += x[e, 0]
            n1 += x[e, 1]
            n2 += x[e, 2]
            o0 += x[d, 0]
            o1 += x[d, 1]
            o2 += x[d, 2]
        n = float(k)
        scale = n * (n + 5.0)
        points[v, 0] = (n * n * x[v, 0] + 4.0 * n0 + o0) / scale
        points[v, 1] = (n * n * x[v, 1] + 4.0 * n1 + o1) / scale
        points[v, 2] = (n * n * x[v, 2] + 4.0 * n2 + o2) / scale


def _by_valence(
    n: IntArray, i: IntArray, table: Callable[[IntArray, IntArray], tuple[FloatArray, ...]]
) -> tuple[FloatArray, ...]:
    """``table(n, i)`` for many entries, evaluated once per distinct ``(n, i)`` (valences
    repeat)."""
    valences = np.unique(n)
    if len(valences) * int(valences.max(initial=0)) > len(n):
        return table(n, i)
    starts = np.concatenate([[0], np.cumsum(valences)])
    keys = np.repeat(valences, valences), np.arange(starts[-1]) - np.repeat(starts[:-1], valences)
    rows = starts[np.searchsorted(valences, n)] + i
    return tuple(column[rows] for column in table(*keys))


def _interior_mask_weights(
    n: IntArray, i: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Weights of ``E_i`` and ``D_i`` in the scaled eigen tangents A (cosines) and B (sines) at
    valence n."""
    theta = 2.0 * np.pi / n
    cos_t = np.cos(theta)
    lam = 5.0 / 16.0 + (cos_t + np.cos(0.5 * theta) * np.sqrt(2.0 * (9.0 + cos_t))) / 16.0
    c = 1.0 / (4.0 * lam - 1.0)
    scale = 1.0 / (2.0 * n + c * n * (1.0 + cos_t))
    a0, a1 = i * theta, (i + 1) * theta
    return (
        scale * 4.0 * np.cos(a0),
        scale * c * (np.cos(a0) + np.cos(a1)),
        scale * 4.0 * np.sin(a0),
        scale * c * (np.sin(a0) + np.sin(a1)),
    )


@cache
def _cross_mask(k: int) -> tuple[float, FloatArray, FloatArray]:
    """The across-crease tangent mask of a crease sector with k faces: ``(w_V, w_E (k + 1), w_D
    (k))``.

    k = 2: the B-spline's ``(−4V − E_0 + 4E_1 − E_2 + D_0 + D_1)/6``; k = 1 (its subdominant
    eigenvalue 1/4 is double): OpenSubdiv's ``3(E_0 + E_1) − 6V``. Otherwise the left eigenvector
    of the sector's subdivision matrix (crease rule at V, midpoints on the sharp edges, smooth rules
    inside) that is symmetric under the reflection ``E_i ↔ E_{k−i}``, ``D_i ↔ D_{k−1−i}`` with the
    largest eigenvalue below 1, scaled to unit response on the planar half-fan (``E_i`` at angle
    ``πi/k``, ``D_i = E_i + E_{i+1}``) and signed to point into the faces. OpenSubdiv's Biermann et
    al. mask is derived for modified rules: on its own rules its plane is 7–17° off for k = 3–6.
    For k ≥ 5 the ring has a third eigenvalue above 1/2, so the limit surface is not tangent-plane
    continuous there and this plane is the one through the crease's own modes.
    """
    if k == 1:
        return -6.0, np.array([3.0, 3.0]), np.zeros(1)
    if k == 2:
        return -4.0 / 6.0, np.array([-1.0, 4.0, -1.0]) / 6.0, np.array([1.0, 1.0]) / 6.0
    size = 2 * k + 2
    unit = np.eye(size)
    edge, diagonal = unit[1 : k + 2], unit[k + 2 :]
    face_points = 0.25 * (unit[0] + edge[:-1] + diagonal + edge[1:])
    matrix = np.empty((size, size))
    matrix[0] = (6.0 * unit[0] + edge[0] + edge[k]) / 8.0
    matrix[1] = 0.5 * (unit[0] + edge[0])
    matrix[k + 1] = 0.5 * (unit[0] + edge[k])
    matrix[2 : k + 1] = 0.25 * (unit[0] + edge[1:k] + face_points[:-1] + face_points[1:])
    matrix[k + 2 :] = face_points
    values, vectors = np.linalg.eig(matrix.T)
    mirror = np.concatenate([[0], 1 + np.arange(k + 1)[::-1], k + 2 + np.arange(k)[::-1]])
    vectors = vectors.real / np.linalg.norm(vectors.real, axis=0)
    symmetric = (np.abs(values.imag) < 1e-12) & (
        np.abs(vectors - vectors[mirror]).max(axis=0) < 1e-9
    )
    candidates = np.flatnonzero(symmetric & (values.real < 1.0 - 1e-9))
    mask = vectors[:, candidates[np.argmax(values.real[candidates])]]
    angles = np.pi * np.arange(k + 1) / k
    planar = np.concatenate([[0.0], np.sin(angles), np.sin(angles[:-1]) + np.sin(angles[1:])])
    mask = mask / (mask @ planar)
    return float(mask[0]), mask[1 : k + 2], mask[k + 2 :]


class _Limit(NamedTuple):
    """Limit data of a level: positions (V, 3); or slot tangents (S, 3), the stars ``a``, ``b`` (V,
    3) and where asked the unit normal of each ring entry's sector (``ring_halfedges`` order)."""

    points: FloatArray | None
    tangents: FloatArray | None = None
    a: FloatArray | None = None
    b: FloatArray | None = None
    ring_normals: FloatArray | None = None


def _where(mask: BoolArray) -> BoolArray | slice:
    """``mask`` for indexing, or the whole axis (a view, no copy) where it is all true."""
    return slice(None) if mask.all() else mask


def _slot_rotation(n: IntArray, j: IntArray) -> tuple[FloatArray, FloatArray]:
    phi = 2.0 * np.pi * j / n
    return np.cos(phi), np.sin(phi)


def _unit(v: FloatArray) -> FloatArray:
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


def _limit_frames(level: _Level, corners: bool = False, compiled: bool | None = None) -> _Limit:
    """Slot tangents, stars and (``corners``) sector normals of a level without fractional sharpness
    (module docstring). ``compiled`` (None: from :data:`KERNEL_VERTICES` vertices on): the smooth
    vertices' stars and tangents by :func:`_stars_kernel` (bit for bit the NumPy values), the
    NumPy code then only at the crease and corner vertices."""
    topology, x = level.topology, level.x
    nv = topology.n_vertices
    offsets = topology.neighbor_offsets
    k = topology.face_count
    boundary = topology.is_boundary_vertex
    rule = _limit_rules(level)
    slot_count = np.diff(offsets)
    smooth = rule == _SMOOTH
    tangents = np.zeros((int(offsets[-1]), 3))
    a = np.zeros((nv, 3))
    b = np.zeros((nv, 3))
    kernel = _kernel_wanted(compiled, nv)
    # the vertices the NumPy code below handles (all, or those the kernel leaves), their slots and
    # ring entries
    chosen = np.flatnonzero(~smooth) if kernel else np.arange(nv)
    slot_vertex = np.repeat(chosen, slot_count[chosen])
    slot = np.arange(len(slot_vertex)) - np.repeat(
        np.cumsum(slot_count[chosen]) - slot_count[chosen], slot_count[chosen]
    )
    slot_index = offsets[slot_vertex] + slot
    ring_vertex = np.repeat(chosen, k[chosen])
    i = np.arange(len(ring_vertex)) - np.repeat(np.cumsum(k[chosen]) - k[chosen], k[chosen])
    ring_index = topology.ring_offsets[ring_vertex] + i
    h = topology.ring_halfedges[ring_index]
    ring_slot = offsets[ring_vertex] + i
    e_i = x[topology.target(h)]
    d_i = x[topology.origin(QuadTopology.next(QuadTopology.next(h)))]

    slot_edge = np.empty(len(tangents), dtype=np.int64)  # written and read at the chosen slots only
    slot_edge[ring_slot] = topology.halfedge_edge[h]
    rims = chosen[boundary[chosen]]
    slot_edge[offsets[rims + 1] - 1] = topology.halfedge_edge[
        QuadTopology.prev(topology.ring_halfedges[topology.ring_offsets[rims + 1] - 1])
    ]
    slot_sharp = np.zeros(len(tangents), dtype=bool)
    slot_sharp[slot_index] = level.edge[slot_edge[slot_index]] >= INFINITE_SHARPNESS
    sharp_slots = np.flatnonzero(slot_sharp[slot_index])  # positions in the chosen slots
    first = np.zeros(nv, dtype=np.int64)
    last = np.zeros(nv, dtype=np.int64)
    owners, at_first = np.unique(slot_vertex[sharp_slots], return_index=True)
    first[owners] = slot[sharp_slots[at_first]]
    owners, at_last = np.unique(slot_vertex[sharp_slots[::-1]], return_index=True)
    last[owners] = slot[sharp_slots[::-1][at_last]]

    # smooth: the eigen tangents
    if kernel and smooth.any():
        from .kernels import jit_kernel  # numba, imported on first use

        valences = np.unique(k[smooth])
        starts = np.concatenate([[0], np.cumsum(valences)])
        keys = (
            np.repeat(valences, valences),
            np.arange(starts[-1]) - np.repeat(starts[:-1], valences),
        )
        start_of = np.zeros(int(valences[-1]) + 1, dtype=np.int64)
        start_of[valences] = starts[:-1]
        jit_kernel(_stars_kernel)(
            x,
            topology.faces,
            topology.ring_offsets,
            topology.ring_halfedges,
            offsets,
            smooth,
            start_of,
            np.stack(_interior_mask_weights(*keys)),
            np.stack(_slot_rotation(*keys)),
            a,
            b,
            tangents,
        )
    elif smooth.any():
        on_ring = _where(smooth[ring_vertex])
        rv = ring_vertex[on_ring]
        ea, da, eb, db = _by_valence(k[rv], i[on_ring], _interior_mask_weights)
        a += _segment_sum(rv, ea[:, None] * e_i[on_ring] + da[:, None] * d_i[on_ring], nv)
        b += _segment_sum(rv, eb[:, None] * e_i[on_ring] + db[:, None] * d_i[on_ring], nv)
        at = _where(smooth[slot_vertex])
        sv = slot_vertex[at]
        cos_phi, sin_phi = _by_valence(k[sv], slot[at], _slot_rotation)
        tangents[slot_index[at]] = cos_phi[:, None] * a[sv] + sin_phi[:, None] * b[sv]

    # crease: sector 0 from the first sharp slot p to the second q, sector 1 from q round to p
    crease = rule == _CREASE
    cv = np.flatnonzero(crease)
    along = np.zeros((nv, 3))
    across = np.zeros((2 * cv.size, 3))  # sectors 2c, 2c + 1 of the c-th crease vertex
    if cv.size:
        p, q = first, last
        span = q - p  # faces in sector 0
        along[cv] = 0.5 * (
            x[topology.neighbors[offsets[cv] + p[cv]]] - x[topology.neighbors[offsets[cv] + q[cv]]]
        )
        at = crease[ring_vertex]
        rv, ri = ring_vertex[at], i[at]
        second = (ri < p[rv]) | (ri >= q[rv])
        sector = 2 * np.searchsorted(cv, rv) + second
        start = np.where(second, q[rv], p[rv])
        size = np.where(second, k[rv] - span[rv], span[rv])
        offset = (ri - start) % k[rv]
        ends = np.stack([q[cv], p[cv]], axis=1).ravel()  # the closing slot of sectors 2c, 2c + 1
        sector_size = np.stack([span[cv], k[cv] - span[cv]], axis=1).ravel()
        for count in np.unique(size):
            vertex_weight, spoke, face = _cross_mask(int(count))
            sel = size == count
            o = offset[sel]
            across += _segment_sum(
                sector[sel],
                spoke[o, None] * e_i[at][sel] + face[o, None] * d_i[at][sel],
                2 * cv.size,
            )
            closing = np.flatnonzero(sector_size == count)
            owner = cv[closing // 2]
            across[closing] += (
                vertex_weight * x[owner]
                + spoke[count] * x[topology.neighbors[offsets[owner] + ends[closing]]]
            )
        a[cv] = along[cv]
        b[cv] = across[0::2]
        at = crease[slot_vertex]
        sv, sj = slot_vertex[at], slot[at]
        second = (sj < p[sv]) | (sj > q[sv])
        sector_along = np.where(second[:, None], -along[sv], along[sv])
        sector_across = across[2 * np.searchsorted(cv, sv) + second]
        angle = np.pi * np.where(
            second,
            (sj - q[sv]) % k[sv] / np.maximum(k[sv] - span[sv], 1),
            (sj - p[sv]) / np.maximum(span[sv], 1),
        )
        t = np.cos(angle)[:, None] * sector_along + np.sin(angle)[:, None] * sector_across
        t = np.where(
            (sj == p[sv])[:, None], along[sv], np.where((sj == q[sv])[:, None], -along[sv], t)
        )
        tangents[slot_index[at]] = t

    # corner: the chords, a and b on the first sharp slot and the next one
    corner = rule == _CORNER
    if corner.any():
        at = corner[slot_vertex]
        tangents[slot_index[at]] = x[topology.neighbors[slot_index[at]]] - x[slot_vertex[at]]
        corners_at = np.flatnonzero(corner)
        a[corners_at] = tangents[offsets[corners_at] + first[corners_at]]
        b[corners_at] = tangents[
            offsets[corners_at] + (first[corners_at] + 1) % slot_count[corners_at]
        ]

    if not corners:
        return _Limit(None, tangents, a, b)
    # sector normals: Σ t_i × t_{i+1} over the ring entries of each sector (a × b for one star)
    following = offsets[ring_vertex] + (i + 1) % slot_count[ring_vertex]
    cross = np.cross(tangents[ring_slot], tangents[following])
    shifted = (i - first[ring_vertex]) % slot_count[ring_vertex]
    order = np.lexsort((shifted, ring_vertex))
    starts = slot_sharp[ring_slot]
    label = np.empty(len(h), dtype=np.int64)
    label[order] = np.cumsum(starts[order] | (shifted[order] == 0)) - 1
    ring_normals = _unit(
        _segment_sum(label, cross, int(label.max()) + 1) if len(label) else np.zeros((0, 3))
    )[label]
    star_normals = _unit(np.cross(a, b))
    one_star = smooth[ring_vertex]
    ring_normals[one_star] = star_normals[ring_vertex[one_star]]
    if (
        cv.size
    ):  # each sector's own star (a one-face sector has no second slot tangent off the crease)
        at = crease[ring_vertex]
        rv, ri = ring_vertex[at], i[at]
        second = (ri < first[rv]) | (ri >= last[rv])
        ring_normals[at] = _unit(
            np.cross(
                np.where(second[:, None], -along[rv], along[rv]),
                across[2 * np.searchsorted(cv, rv) + second],
            )
        )
    if not kernel:
        return _Limit(None, tangents, a, b, ring_normals)
    every = star_normals[np.repeat(np.arange(nv), k)]  # the kernel's smooth vertices: one star each
    every[ring_index] = ring_normals
    return _Limit(None, tangents, a, b, every)


def _stars_kernel(
    x: FloatArray,
    faces: IntArray,
    ring_offsets: IntArray,
    ring_halfedges: IntArray,
    offsets: IntArray,
    smooth: BoolArray,
    start_of: IntArray,
    weights: FloatArray,
    rotation: FloatArray,
    a: FloatArray,
    b: FloatArray,
    tangents: FloatArray,
) -> None:
    """At each smooth vertex the stars ``A = Σ w_E,i E_i + w_D,i D_i`` (``weights[0:2]``), B
    (``weights[2:4]``), in ring order as :func:`_segment_sum` adds them, and slot j's tangent
    ``cos φ_j A + sin φ_j B`` (``rotation``); the tables' row for valence n, entry i, is
    ``start_of[n] + i``."""
    for v in range(smooth.size):
        if not smooth[v]:
            continue
        r0 = ring_offsets[v]
        k = ring_offsets[v + 1] - r0
        base = start_of[k]
        a0 = a1 = a2 = b0 = b1 = b2 = 0.0
        for i in range(k):
            h = ring_halfedges[r0 + i]
            f, c = h >> 2, h & 3
            e, d = faces[f, (c + 1) & 3], faces[f, (c + 2) & 3]
            ea, da, eb, db = (
                weights[0, base + i],
                weights[1, base + i],
                weights[2, base + i],
                weights[3, base + i],
            )
            a0 += ea * x[e, 0] + da * x[d, 0]
            a1 += ea * x[e, 1] + da * x[d, 1]
            a2 += ea * x[e, 2] + da * x[d, 2]
            b0 += eb * x[e, 0] + db * x[d, 0]
            b1 += eb * x[e, 1] + db * x[d, 1]
            b2 += eb * x[e, 2] + db * x[d, 2]
        a[v, 0], a[v, 1], a[v, 2] = a0, a1, a2
        b[v, 0], b[v, 1], b[v, 2] = b0, b1, b2
        s0 = offsets[v]
        for j in range(k):
            cj, sj = rotation[0, base + j], rotation[1, base + j]
            tangents[s0 + j, 0] = cj * a0 + sj * b0
            tangents[s0 + j, 1] = cj * a1 + sj * b1
            tangents[s0 + j, 2] = cj * a2 + sj * b2


def _affected(level: _Level) -> BoolArray:
    """Vertices whose limit sees a semi-sharp feature: a semi-sharp vertex, or an incident
    semi-sharp edge."""
    semi_edge = (level.edge > 0) & (level.edge < INFINITE_SHARPNESS)
    out = (level.vertex > 0) & (level.vertex < INFINITE_SHARPNESS)
    out[level.topology.edges[semi_edge].ravel()] = True
    return out


def _sublevel(level: _Level, faces: BoolArray) -> tuple[_Level, IntArray]:
    """The faces as a level of their own (vertices renumbered in order), and the new index of every
    vertex (-1 outside)."""
    topology = level.topology
    kept = topology.faces[faces]
    used = np.zeros(topology.n_vertices, dtype=bool)
    used[kept] = True
    index = np.cumsum(used) - 1
    index[~used] = -1
    sub = QuadTopology.from_faces(index[kept], int(used.sum()))
    original = np.flatnonzero(used)
    keys = topology.edges[:, 0] * topology.n_vertices + topology.edges[:, 1]
    sub_keys = original[sub.edges[:, 0]] * topology.n_vertices + original[sub.edges[:, 1]]
    edge, vertex = _effective(
        sub, level.edge[np.searchsorted(keys, sub_keys)], level.vertex[original], level.mode
    )
    return _Level(
        level.x[original], sub, edge, vertex, level.holes[faces], level.mode, level.chaikin
    ), index


def _neighbourhood(level: _Level, vertices: BoolArray, rings: int) -> BoolArray:
    """Faces within ``rings`` vertex rings of ``vertices`` (1: the faces at them)."""
    faces = level.topology.faces
    touched = vertices.copy()
    keep = touched[faces].any(axis=1)
    for _ in range(rings - 1):
        touched = np.zeros_like(touched)
        touched[faces[keep]] = True
        keep = touched[faces].any(axis=1)
    return keep


def _decayed(level: _Level) -> tuple[_Level, int]:
    """Refined until no fractional sharpness is left (at most ⌈max s⌉ ≤ 10 steps), and the steps
    taken."""
    steps = 0
    while level.semi_sharp:
        level = _step(level)
        steps += 1
    return level, steps


def _limit(
    mesh: QuadMesh, sharpness: ArrayLike | None, frames: bool, corners: bool = False
) -> _Limit:
    """Limit data of the mesh's own vertices (module docstring): the masks where no semi-sharp
    feature reaches, the masks on the decayed refinement of a neighbourhood elsewhere."""
    level = _level_of(mesh, sharpness)
    if not level.semi_sharp:
        return _limit_frames(level, corners) if frames else _Limit(_limit_positions(level))
    affected = _affected(level)
    # the limit of v reads its 1-ring and the sharpness at v; with Chaikin also that at its
    # neighbours
    rings = 2 if level.chaikin else 1
    sub, index = level, np.arange(level.topology.n_vertices)
    for extra in range(3):
        faces = _neighbourhood(level, affected, rings + extra)
        if faces.all():
            break
        try:
            sub, index = _sublevel(level, faces)
            break
        except MeshError:  # the cut leaves a vertex with two fans: take a ring more, at last all
            sub, index = level, np.arange(level.topology.n_vertices)
    fine, steps = _decayed(sub)
    near = np.flatnonzero(affected)
    if not frames:
        points = _limit_positions(level)
        points[near] = _limit_positions(fine)[index[near]]
        return _Limit(points)
    coarse, refined = _limit_frames(level, corners), _limit_frames(fine, corners)
    scale = 2.0**steps
    rows = index[near]
    a, b = coarse.a, coarse.b
    a[near] = scale * refined.a[rows]
    b[near] = scale * refined.b[rows]
    counts = np.diff(level.topology.neighbor_offsets)[near]
    within = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    tangents = coarse.tangents
    tangents[np.repeat(level.topology.neighbor_offsets[near], counts) + within] = (
        scale * refined.tangents[np.repeat(fine.topology.neighbor_offsets[rows], counts) + within]
    )
    ring_normals = coarse.ring_normals
    if not corners:
        return _Limit(None, tangents, a, b)
    faces = level.topology.face_count[near]
    within = np.arange(faces.sum()) - np.repeat(np.cumsum(faces) - faces, faces)
    ring_normals[np.repeat(level.topology.ring_offsets[near], faces) + within] = (
        refined.ring_normals[np.repeat(fine.topology.ring_offsets[rows], faces) + within]
    )
    return _Limit(None, tangents, a, b, ring_normals)


def limit_points(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """The Catmull–Clark limit position of every vertex, (V, 3) (module docstring)."""
    return _limit(mesh, sharpness, frames=False).points


def limit_stars(
    mesh: QuadMesh, sharpness: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Per vertex the two scaled limit tangents ``(a, b)``, (V, 3) each, ``a × b`` along the outward
    normal (OpenSubdiv's tangent pair): inside A and B of the module docstring; at a crease vertex
    (boundary or interior) a along the crease towards the first sharp slot ``E_p`` of the ring,
    ``(E_p − E_q)/2``, and b across the sector that follows it counter-clockwise, into its faces;
    at a corner ``a = E_p − V``, ``b = E_{p+1} − V`` (p the first sharp slot, 0 if none)."""
    data = _limit(mesh, sharpness, frames=True)
    return data.a, data.b


def limit_tangents(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """Per ring slot the limit tangent along its edge, (S, 3) (module docstring): ``cos φ_j a + sin
    φ_j b`` over the star of the slot's sector (``φ_j = 2πj/n`` at a smooth vertex, ``πj/k`` in a
    crease sector with k faces), the crease tangent ``±(E_p − E_q)/2`` on the two sharp slots of a
    crease, ``E_j − V`` at a corner. Along a sharp edge it is the tangent of the crease curve, the
    same for the sectors on both sides."""
    return _limit(mesh, sharpness, frames=True).tangents


def limit_normals(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """``a × b`` of :func:`limit_stars`, unit; zero where the two tangents are parallel. At a crease
    vertex this is the normal of the sector after the first sharp slot (:func:`limit_corner_normals`
    gives every sector's)."""
    data = _limit(mesh, sharpness, frames=True)
    return _unit(np.cross(data.a, data.b))


class LimitData(NamedTuple):
    """What :func:`limit_points`, :func:`limit_stars`, :func:`limit_tangents` and
    :func:`limit_normals` return."""

    points: FloatArray
    a: FloatArray
    b: FloatArray
    tangents: FloatArray
    normals: FloatArray


def limit_data(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> LimitData:
    """:func:`limit_points`, :func:`limit_stars`, :func:`limit_tangents` and :func:`limit_normals`
    at once, each stencil applied once (called one by one, the stars are computed three times)."""
    frames = _limit(mesh, sharpness, frames=True)
    assert frames.tangents is not None and frames.a is not None and frames.b is not None
    points = _limit(mesh, sharpness, frames=False).points
    assert points is not None
    return LimitData(
        points, frames.a, frames.b, frames.tangents, _unit(np.cross(frames.a, frames.b))
    )


def limit_corner_normals(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """Per face corner ``[f, c]`` (F, 4, 3) the unit normal of the limit surface at vertex
    ``faces[f, c]`` on the sector holding face f: the sectors of a vertex are the runs of faces
    between its infinitely sharp edges (boundary edges included), one sector where there are fewer
    than two.

    * smooth vertex (fewer than two sharp edges): the vertex normal of :func:`limit_normals`;
    * crease vertex: ``a × b`` of the sector's own star, a the crease tangent ``(E_0 − E_k)/2``
      (``E_0`` the sector's first sharp slot counter-clockwise, ``E_k`` its last), b the sector's
      cross tangent: its tangent plane holds the crease curve's tangent on both sides;
    * corner vertex: the normalised fan sum ``Σ t_i × t_{i+1}`` of the sector's slot chords
      ``t_i = E_i − V``: ``(E_0 − V) × (E_1 − V)`` for one face, the exact plane of the two crease
      tangents when a sector is one quad;

    zero where that vanishes. Hole faces get theirs too. Where the mesh is semi-sharp, the normals
    at the affected vertices come from the decayed refinement (module docstring), whose sectors
    are those of the infinitely sharp features. The two limit tangents of a corner, along its
    face's edges, are :func:`limit_tangents` at the slots of the half-edges ``4f + c`` (out along
    edge c) and of the reverse of ``4f + (c + 3) % 4`` (towards corner c − 1); at smooth and crease
    vertices they lie in this plane."""
    topology = mesh.topology
    ring_normals = _limit(mesh, sharpness, frames=True, corners=True).ring_normals
    position = np.empty(topology.n_halfedges, dtype=np.int64)
    position[topology.ring_halfedges] = np.arange(topology.n_halfedges)
    return ring_normals[position].reshape(topology.n_faces, 4, 3)
