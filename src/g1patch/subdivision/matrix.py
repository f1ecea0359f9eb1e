"""Catmull–Clark subdivision as sparse matrices: every rule of :mod:`g1patch.subdivision` is linear
in the positions with weights that depend on the topology and the features only, so

* :func:`step_matrix`: one step, ``S @ x`` = :func:`~g1patch.subdivision.refine`'s vertices
  ((V + E + F) × V: vertex points, edge points in ``edges`` order, face points);
* :func:`refine_matrix`: ``levels`` steps, ``R = S_levels ⋯ S_1``;
* :func:`limit_matrix`: the V × V limit stencil L, ``L @ x`` =
  :func:`~g1patch.subdivision.limit_points`;
* :func:`limit_grid_matrix`: ``G = L(M_levels) R``, the exact limit points of the refined mesh's
  vertices, with the grid of each original face.

Rows of S (n the vertex's face count, ``E_i`` its ring neighbours, ``F_i`` its face points, the
features' weights from the same code as the refinement step, :func:`~.refine._weights`):

* face point: ``1/4`` at each corner;
* edge A–B with midpoint weight s (0 smooth, 1 sharp, fractional while a crease decays):
  ``s (A + B)/2 + (1 − s)(A + B + F_L + F_R)/4``;
* vertex: ``p·(parent mask) + (1 − p)·(child mask)``, p = 1 where the rules agree (or the vertex
  is smooth), else OpenSubdiv's fractional weight; masks smooth ``(n − 2)/n V + ΣE_i/n² +
  ΣF_i/n²``, crease ``(6V + A + B)/8`` over the sharp edges (the parent's, or the children's),
  corner ``V``.

Semi-sharp features are covered exactly by S and R (their weights are those of the step).
L holds the 1-ring masks, so L itself refuses semi-sharp features; :func:`limit_grid_matrix`
refines past them (⌈max s⌉ more steps) and takes the limit rows of the refined level's first
vertices, which keep their indices and their limit points. Built by COO assembly (rows, columns,
weights; duplicates summed), float64.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..mesh import INFINITE_SHARPNESS, QuadMesh, QuadTopology
from .features import RULE_CORNER, RULE_CREASE, RULE_SMOOTH, _Level, _level_of, _limit_rules
from .refine import _cage_level, _CageLevel, _refined_mesh, _refinement, _step, _weights

__all__ = ["cage_step_matrix", "limit_grid_matrix", "limit_matrix", "refine_matrix", "step_matrix"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _assemble(
    rows: list[IntArray], columns: list[IntArray], weights: list[FloatArray], shape: tuple[int, int]
) -> sp.csr_matrix:
    """The sparse matrix of the triplets, zero weights dropped, duplicates summed."""
    r, c, w = np.concatenate(rows), np.concatenate(columns), np.concatenate(weights)
    keep = w != 0
    return sp.coo_matrix((w[keep], (r[keep], c[keep])), shape=shape).tocsr()


def _step_matrix(level: _Level | _CageLevel) -> sp.csr_matrix:
    """S of one step of ``level`` (module docstring), quads or polygons: a face point is the
    centroid of its n corners, ``1/n`` each."""
    topology = level.topology
    nv, ne, nf = topology.n_vertices, topology.n_edges, topology.n_faces
    corners, sizes = topology.polygons()
    corner_face = np.repeat(np.arange(nf), sizes)
    centroid = sp.csr_matrix((1.0 / sizes[corner_face], (corner_face, corners)), shape=(nf, nv))
    a, b = topology.edges[:, 0], topology.edges[:, 1]
    weights = _weights(level)

    s = weights.edge
    left = topology.face_of(topology.edge_halfedges[:, 0])
    right = topology.face_of(np.maximum(topology.edge_halfedges[:, 1], 0))
    ends = 0.5 * s + 0.25 * (1.0 - s)
    beside = 0.25 * (1.0 - s)  # at the face points F_L and F_R

    parent, child = weights.parent_rule, weights.child_rule
    p = np.where((parent == RULE_SMOOTH) | (child == parent), 1.0, weights.vertex)
    q = 1.0 - p
    smooth = np.where(parent == RULE_SMOOTH, p, 0.0) + np.where(child == RULE_SMOOTH, q, 0.0)
    corner = np.where(parent == RULE_CORNER, p, 0.0) + np.where(child == RULE_CORNER, q, 0.0)
    parent_crease = np.where(parent == RULE_CREASE, p, 0.0)
    child_crease = np.where(child == RULE_CREASE, q, 0.0)
    n = topology.face_count.astype(np.float64)
    diagonal = smooth * (n - 2.0) / n + 0.75 * (parent_crease + child_crease) + corner
    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    ring = smooth[origin] / (n[origin] * n[origin])
    sharp = level.edge > 0
    at_a, at_b = weights.half_a > 0, weights.half_b > 0

    edge_rows = nv + np.arange(ne)
    vertices = np.arange(nv)
    rows = [edge_rows, edge_rows, vertices, origin, a[sharp], b[sharp], a[at_a], b[at_b]]
    columns = [a, b, vertices, topology.target(h), b[sharp], a[sharp], b[at_a], a[at_b]]
    values = [ends, ends, diagonal, ring]
    values += [parent_crease[a[sharp]] / 8.0, parent_crease[b[sharp]] / 8.0]
    values += [child_crease[a[at_a]] / 8.0, child_crease[b[at_b]] / 8.0]
    direct = _assemble(rows, columns, values, (nv + ne, nv))
    faces_of = _assemble(  # the face points each vertex and edge point reads
        [origin, edge_rows, edge_rows],
        [topology.face_of(h), left, right],
        [ring, beside, beside],
        (nv + ne, nf),
    )
    return sp.vstack([direct + faces_of @ centroid, centroid], format="csr")


def step_matrix(mesh: QuadMesh) -> sp.csr_matrix:
    """The (V + E + F) × V matrix S of one Catmull–Clark step of ``mesh`` (features from its tags):
    ``S @ mesh.vertices`` is ``refine(mesh, 1).vertices`` to rounding; every row sums to 1."""
    return _step_matrix(_level_of(mesh))


def _chain(mesh: QuadMesh, levels: int) -> tuple[sp.csr_matrix, _Level, IntArray]:
    """``R = S_levels ⋯ S_1``, the last level and its grid of the original faces."""
    steps = _refinement(mesh, levels)
    level, grid = next(steps)
    matrix = sp.identity(level.topology.n_vertices, dtype=np.float64, format="csr")
    for fine, fine_grid in steps:
        matrix = _step_matrix(level) @ matrix
        level, grid = fine, fine_grid
    return matrix, level, grid


def refine_matrix(mesh: QuadMesh, levels: int) -> tuple[sp.csr_matrix, QuadMesh]:
    """``R = S_levels ⋯ S_1`` (:func:`step_matrix` of each level) and the refined mesh
    ``refine(mesh, levels)``: ``R @ mesh.vertices`` is its vertices to rounding. The identity and
    the mesh itself for ``levels = 0``."""
    matrix, level, _ = _chain(mesh, levels)
    return matrix, _refined_mesh(mesh, level, levels)


def _limit_stencil(level: _Level) -> sp.csr_matrix:
    """L of a level without semi-sharp features (:func:`limit_matrix`)."""
    topology = level.topology
    nv = topology.n_vertices
    rules = _limit_rules(level)
    smooth, crease = rules == RULE_SMOOTH, rules == RULE_CREASE
    ends = topology.edges[level.edge >= INFINITE_SHARPNESS]

    n = topology.face_count.astype(np.float64)
    h = np.flatnonzero(smooth[topology.origin(np.arange(topology.n_halfedges))])
    origin = topology.origin(h)
    ring_weight = 1.0 / (n[origin] * (n[origin] + 5.0))
    crease_rows, crease_columns = np.concatenate([ends, ends[:, ::-1]]).T
    at_crease = crease[crease_rows]
    rows = [np.arange(nv), origin, origin, crease_rows[at_crease]]
    columns = [
        np.arange(nv),
        topology.target(h),
        topology.origin(QuadTopology.next(QuadTopology.next(h))),
        crease_columns[at_crease],
    ]
    diagonal = np.select([smooth, crease], [n / (n + 5.0), 2.0 / 3.0], 1.0)
    weights = [diagonal, 4.0 * ring_weight, ring_weight, np.full(int(at_crease.sum()), 1.0 / 6.0)]
    return _assemble(rows, columns, weights, (nv, nv))


def limit_matrix(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> sp.csr_matrix:
    """The sparse V × V limit stencil L with ``L @ mesh.vertices == limit_points(mesh, sharpness)``
    (to rounding), assembled from the half-edges. Rows:

    * smooth vertex with n faces: ``n/(n + 5)`` at v, ``4/(n(n + 5))`` at each ring neighbour
      (the half-edges' targets), ``1/(n(n + 5))`` at each face corner opposite v;
    * crease vertex (two infinitely sharp edges to A, B): ``2/3`` at v, ``1/6`` at A and B;
    * corner vertex: 1 at v.

    Rules from :func:`~g1patch.subdivision.vertex_rules` (the mesh's tags and boundary mode, edge
    sharpness from ``sharpness`` where given). A semi-sharp edge or vertex (0 < s < 10) raises
    :class:`InputError`: its limit reads more than the 1-ring masks (refine past it first, or use
    :func:`limit_grid_matrix`)."""
    level = _level_of(mesh, sharpness)
    for name, values in (("edge", level.edge), ("vertex", level.vertex)):
        semi = np.flatnonzero((values > 0) & (values < INFINITE_SHARPNESS))
        if semi.size:
            raise InputError(
                f"limit_matrix: {name} {semi[0]} is semi-sharp ({values[semi[0]]:g}; {semi.size} "
                "such); the limit stencil covers smooth and infinitely sharp (≥ 10) features "
                "only: refine the mesh past its semi-sharp levels first (subdivision.refine)"
            )
    return _limit_stencil(level)


def cage_step_matrix(mesh: QuadMesh) -> sp.csr_matrix | None:
    """The (V + E + F) × V₀ matrix of the Catmull–Clark step of the polygon cage ``mesh`` was split
    from (:attr:`~g1patch.mesh.QuadMesh.cage`, V₀ points): ``S @ mesh.cage.points`` is
    :func:`~g1patch.subdivision.catmull_clark_cage`'s vertices to rounding, on ``mesh``'s own
    numbering. None where ``mesh`` was read as quads."""
    cage = mesh.cage
    return None if cage is None else _step_matrix(_cage_level(cage))


def limit_grid_matrix(mesh: QuadMesh, levels: int) -> tuple[sp.csr_matrix, IntArray]:
    """``G = L(M_levels) R`` (:func:`refine_matrix`, :func:`limit_matrix` of the refined mesh
    ``M_levels``): ``G @ mesh.vertices`` is ``limit_points(refine(mesh, levels))`` to rounding,
    and the grid ``(F, m + 1, m + 1)``, ``m = 2^levels``, of
    :func:`~g1patch.subdivision.refine_grids`: ``(G @ x)[grid[f, i, j]]`` is the limit point at
    parameter ``(i/m, j/m)`` of face f. Where ``M_levels`` is still semi-sharp, L is taken on the
    level where every sharpness has decayed, its rows of ``M_levels``' vertices."""
    matrix, level, grid = _chain(mesh, levels)
    count = level.topology.n_vertices
    while level.semi_sharp:
        matrix = _step_matrix(level) @ matrix
        level = _step(level)
    return (_limit_stencil(level)[:count] @ matrix).tocsr(), grid
