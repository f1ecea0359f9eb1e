"""Catmull–Clark subdivision of quad meshes: refinement and limit stencils (OpenSubdiv's rules).

Every rule is a gather and a segmented sum (``np.bincount``) over half-edges or edges; the only
Python loops run over refinement levels or coordinates. With ``n`` faces at a smooth vertex V,
ring neighbours ``E_i`` (counter-clockwise, ring order of :class:`~g1patch.mesh.QuadTopology`),
``D_i`` the corner of face i (between ``E_i`` and ``E_{i+1}``) opposite V, and face points ``F_i``:

* **refinement** (:func:`refine`): face point = centroid; smooth edge point
  ``(A + B + F_L + F_R)/4``, sharp edge point ``(A + B)/2``; smooth vertex
  ``((n − 2) V + ΣE_i/n + ΣF_i/n)/n``, crease vertex (two sharp edges to A, B)
  ``(6V + A + B)/8``, corner vertex (more than two sharp edges, or a corner tagged by the
  boundary mode) ``V``;
* **limit positions** (:func:`limit_points`): smooth ``(n² V + 4ΣE_i + ΣD_i)/(n(n + 5))``,
  crease ``(4V + A + B)/6``, corner ``V``;
* **limit tangents** (:func:`limit_tangents`), per ring slot: at a smooth vertex the eigen
  tangents ``A = Σ 4 cos(iθ) E_i + c (cos iθ + cos(i+1)θ) D_i`` and the same ``B`` with sines,
  ``θ = 2π/n``, ``c = 1/(4λ − 1)``, ``λ = 5/16 + (cos θ + cos(θ/2) √(2(9 + cos θ)))/16`` (OpenSubdiv's
  mask; its rotation by one slot is ``cos θ A + sin θ B``), so slot j gets ``s_n (cos jθ A + sin jθ B)``;
  at a boundary (crease) vertex with k faces the boundary slots get ``±(E_0 − E_k)/2`` and slot j
  ``cos(jπ/k) a + sin(jπ/k) b`` with ``a = (E_0 − E_k)/2`` and b the cross eigen-mask of the
  boundary ring (:func:`_cross_mask`; for k = 2 the B-spline's). Scale: every star is normalised
  so that the planar fan of unit spokes at even angles with parallelogram faces gets unit
  tangents, ``s_n = 1/(2n + c n (1 + cos θ))``. On a regular
  region (valence 4 inside, two faces on a boundary) this is exactly the uniform bicubic
  B-spline's Hermite tangent (``s_4 = 1/12``), i.e. 3 × (Bézier edge point − corner); at an
  extraordinary vertex the limit surface has no finite non-zero derivative along the edge
  (speed ``~ (2λ)^m`` after m steps), so any length is a choice: this one is the regular
  case's reading of the same fan; :mod:`g1patch.targets.limit` fits it to the limit curve.

Boundary modes (``t interpolateboundary`` tag of the mesh, read by :func:`boundary_mode`):
1 → ``edge-only`` (also the default, and for 0 = "none", which OpenSubdiv turns into holes: here
treated as edge-only): boundary edges are sharp, so the boundary is the cubic B-spline of the
boundary polygon and a boundary vertex with one face follows the crease rule;
2 → ``edge-and-corner``: such vertices are corners (kept fixed). This follows the shared
reference data's reading (``data/README.md``); OpenSubdiv's own regression loader maps 1 to
edge-and-corner and 2 to edge-only.

Creases: ``sharpness`` per edge (``QuadTopology.edges`` order), 0 smooth or ≥ 10 infinitely sharp
(OpenSubdiv's ``SHARPNESS_INFINITE``); semi-sharp values are refused for now. Refinement and limit
positions honour them; the tangents handle the boundary only.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InputError, as_float_array
from .mesh import QuadMesh, QuadTopology, subdivide

__all__ = [
    "BOUNDARY_MODES", "BoundaryMode", "INFINITE_SHARPNESS", "boundary_mode", "catmull_clark_points",
    "corner_vertices", "limit_normals", "limit_points", "limit_stars", "limit_tangents", "refine", "refine_grids",
    "sharp_edges",
]

BoundaryMode = Literal["edge-only", "edge-and-corner"]
BOUNDARY_MODES: tuple[BoundaryMode, ...] = ("edge-only", "edge-and-corner")
#: OpenSubdiv's infinitely sharp crease
INFINITE_SHARPNESS = 10.0

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

_SMOOTH, _CREASE, _CORNER = 0, 1, 2


def boundary_mode(mesh: QuadMesh) -> BoundaryMode:
    """The mesh's ``interpolateboundary`` tag: 2 → edge-and-corner, anything else (or none) → edge-only."""
    for tag in mesh.tags:
        if tag.name == "interpolateboundary" and tag.ints:
            return "edge-and-corner" if tag.ints[0] == 2 else "edge-only"
    return "edge-only"


def _segment_sum(index: IntArray, values: FloatArray, count: int) -> FloatArray:
    """``out[v] = Σ_{index[i] = v} values[i]`` for (N, 3) values."""
    return np.stack([np.bincount(index, weights=values[:, d], minlength=count) for d in range(3)], axis=1)


def sharp_edges(topology: QuadTopology, sharpness: ArrayLike | None = None) -> BoolArray:
    """Per edge: boundary, or sharpness ≥ :data:`INFINITE_SHARPNESS`. Semi-sharp values raise :class:`InputError`."""
    sharp = topology.is_boundary_edge.copy()
    if sharpness is None:
        return sharp
    values = as_float_array("sharpness", sharpness)
    if values.shape != (topology.n_edges,):
        raise InputError(f"sharpness: expected shape ({topology.n_edges},), got {values.shape}")
    semi = np.flatnonzero((values > 0) & (values < INFINITE_SHARPNESS))
    if semi.size:
        raise InputError(
            f"sharpness: edge {semi[0]} has semi-sharp value {values[semi[0]]:g}; only 0 and ≥ {INFINITE_SHARPNESS:g} "
            f"(infinitely sharp) are supported ({semi.size} such edges)"
        )
    return sharp | (values >= INFINITE_SHARPNESS)


def corner_vertices(topology: QuadTopology, mode: BoundaryMode) -> BoolArray:
    """Vertices the boundary mode keeps fixed: boundary vertices with one face in ``edge-and-corner``."""
    corner = topology.is_boundary_vertex & (topology.face_count == 1)
    return corner if mode == "edge-and-corner" else np.zeros_like(corner)


def _vertex_rules(topology: QuadTopology, sharp: BoolArray, mode: BoundaryMode) -> tuple[IntArray, FloatArray, IntArray]:
    """Per vertex its rule (smooth, crease, corner) by the count of sharp edges (0–1, 2, > 2), and
    the (edge index, weight) pairs that sum the far ends of its sharp edges."""
    ends = topology.edges[sharp]
    count = np.bincount(ends.ravel(), minlength=topology.n_vertices)
    rule = np.select([count > 2, count == 2], [_CORNER, _CREASE], _SMOOTH)
    rule[corner_vertices(topology, mode)] = _CORNER
    return rule, ends[:, 0], ends[:, 1]


def _crease_sums(x: FloatArray, a: IntArray, b: IntArray) -> FloatArray:
    """Per vertex the sum of the far ends of its sharp edges ``(a, b)``."""
    n = len(x)
    return _segment_sum(a, x[b], n) + _segment_sum(b, x[a], n)


def _ring_sums(topology: QuadTopology, x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(ΣE_i, ΣD_i)`` per vertex over its face corners: the next corner and the opposite one."""
    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    opposite = topology.origin(QuadTopology.next(QuadTopology.next(h)))
    return _segment_sum(origin, x[topology.target(h)], topology.n_vertices), _segment_sum(origin, x[opposite], topology.n_vertices)


def catmull_clark_points(vertices: FloatArray, topology: QuadTopology, sharp: BoolArray, mode: BoundaryMode) -> FloatArray:
    """One Catmull–Clark step's positions (module docstring), numbered like :func:`~g1patch.mesh.refine_polygons`:
    the V vertex points, then one point per edge (``topology.edges`` order), then one per face."""
    x = np.asarray(vertices, dtype=np.float64)
    n_vertices = topology.n_vertices
    face_points = x[topology.faces].mean(axis=1)
    a, b = topology.edges[:, 0], topology.edges[:, 1]
    left = topology.edge_halfedges[:, 0] >> 2
    right = np.maximum(topology.edge_halfedges[:, 1], 0) >> 2
    edge_points = np.where(
        sharp[:, None], 0.5 * (x[a] + x[b]), 0.25 * (x[a] + x[b] + face_points[left] + face_points[right])
    )
    h = np.arange(topology.n_halfedges)
    origin = topology.origin(h)
    n = topology.face_count[:, None].astype(np.float64)
    neighbour_sum = _segment_sum(origin, x[topology.target(h)], n_vertices)
    face_sum = _segment_sum(origin, face_points[h >> 2], n_vertices)
    smooth = ((n - 2.0) * x + (neighbour_sum + face_sum) / n) / n
    rule, ca, cb = _vertex_rules(topology, sharp, mode)
    crease = (6.0 * x + _crease_sums(x, ca, cb)) / 8.0
    vertex_points = np.select([rule[:, None] == _SMOOTH, rule[:, None] == _CREASE], [smooth, crease], x)
    return np.concatenate([vertex_points, edge_points, face_points])


def _child_sharpness(parent: QuadTopology, child: QuadTopology, sharp: BoolArray) -> BoolArray:
    """Sharp edges after a step: both halves ``(a, m)``, ``(m, b)`` of a sharp edge, m its edge point."""
    nv = child.n_vertices
    keys = child.edges[:, 0] * nv + child.edges[:, 1]
    e = np.flatnonzero(sharp)
    m = parent.n_vertices + e
    halves = (np.minimum(parent.edges[e], m[:, None]) * nv + np.maximum(parent.edges[e], m[:, None])).ravel()
    out = np.zeros(child.n_edges, dtype=bool)
    out[np.searchsorted(keys, halves)] = True
    return out


def _step(mesh: QuadMesh, sharp: BoolArray, mode: BoundaryMode) -> tuple[QuadMesh, BoolArray]:
    linear = subdivide(mesh)
    points = catmull_clark_points(mesh.vertices, mesh.topology, sharp, mode)
    return linear.with_vertices(points), _child_sharpness(mesh.topology, linear.topology, sharp)


def refine(mesh: QuadMesh, levels: int = 1, sharpness: ArrayLike | None = None) -> QuadMesh:
    """``levels`` Catmull–Clark steps (module docstring) on the topology of :func:`~g1patch.mesh.subdivide`
    (old vertices, then one per edge, then one per face; tags carried over). The boundary mode
    comes from the mesh's tags; ``sharpness`` per edge, 0 or ≥ 10 (default: all 0)."""
    return refine_grids(mesh, levels, sharpness)[0]


def refine_grids(mesh: QuadMesh, levels: int, sharpness: ArrayLike | None = None) -> tuple[QuadMesh, IntArray]:
    """:func:`refine`, and per original face the refined vertices as a grid ``(F, m + 1, m + 1)``,
    ``m = 2^levels``: ``grid[f, i, j]`` sits at parameter ``(i/m, j/m)`` of face f (u from corner 0
    to 1, v from corner 0 to 3). Cell (i, j) of a level is the face holding the half-edge
    ``grid[i, j] → grid[i + 1, j]`` (refinement keeps orientation), its face point the cell's centre."""
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise InputError(f"levels: expected a non-negative integer, got {levels!r}")
    mode = boundary_mode(mesh)
    sharp = sharp_edges(mesh.topology, sharpness)
    grid = mesh.faces[:, [[0, 3], [1, 2]]]
    for _ in range(int(levels)):
        topology = mesh.topology
        nv = topology.n_vertices
        edge_keys = topology.edges[:, 0] * nv + topology.edges[:, 1]
        h = np.arange(topology.n_halfedges)
        directed = topology.origin(h) * nv + topology.target(h)
        order = np.argsort(directed)

        def edge_point(p: IntArray, q: IntArray) -> IntArray:
            return nv + np.searchsorted(edge_keys, np.minimum(p, q) * nv + np.maximum(p, q))

        cell = order[np.searchsorted(directed[order], grid[:, :-1, :-1] * nv + grid[:, 1:, :-1])] >> 2
        size = 2 * grid.shape[1] - 1
        fine = np.empty((grid.shape[0], size, size), dtype=np.int64)
        fine[:, ::2, ::2] = grid
        fine[:, 1::2, ::2] = edge_point(grid[:, :-1], grid[:, 1:])
        fine[:, ::2, 1::2] = edge_point(grid[:, :, :-1], grid[:, :, 1:])
        fine[:, 1::2, 1::2] = nv + topology.n_edges + cell
        mesh, sharp = _step(mesh, sharp, mode)
        grid = fine
    return mesh, grid


def limit_points(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """The Catmull–Clark limit position of every vertex, (V, 3) (module docstring)."""
    topology = mesh.topology
    x = mesh.vertices
    rule, ca, cb = _vertex_rules(topology, sharp_edges(topology, sharpness), boundary_mode(mesh))
    neighbours, opposite = _ring_sums(topology, x)
    n = topology.face_count[:, None].astype(np.float64)
    smooth = (n * n * x + 4.0 * neighbours + opposite) / (n * (n + 5.0))
    crease = (4.0 * x + _crease_sums(x, ca, cb)) / 6.0
    return np.select([rule[:, None] == _SMOOTH, rule[:, None] == _CREASE], [smooth, crease], x)


def _interior_mask_weights(n: IntArray, i: IntArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Weights of ``E_i`` and ``D_i`` in the scaled eigen tangents A (cosines) and B (sines) at valence n."""
    theta = 2.0 * np.pi / n
    cos_t = np.cos(theta)
    lam = 5.0 / 16.0 + (cos_t + np.cos(0.5 * theta) * np.sqrt(2.0 * (9.0 + cos_t))) / 16.0
    c = 1.0 / (4.0 * lam - 1.0)
    scale = 1.0 / (2.0 * n + c * n * (1.0 + cos_t))
    a0, a1 = i * theta, (i + 1) * theta
    return (
        scale * 4.0 * np.cos(a0), scale * c * (np.cos(a0) + np.cos(a1)),
        scale * 4.0 * np.sin(a0), scale * c * (np.sin(a0) + np.sin(a1)),
    )


@lru_cache(maxsize=None)
def _cross_mask(k: int) -> tuple[float, FloatArray, FloatArray]:
    """The across-boundary tangent mask at a boundary vertex with k faces: ``(w_V, w_E (k + 1), w_D (k))``.

    k = 2: the B-spline's ``(−4V − E_0 + 4E_1 − E_2 + D_0 + D_1)/6``; k = 1 (its subdominant
    eigenvalue 1/4 is double): OpenSubdiv's ``3(E_0 + E_1) − 6V``. Otherwise the left eigenvector
    of the ring's subdivision matrix (crease rule at V, midpoints on the boundary, smooth rules
    inside) that is symmetric under the reflection ``E_i ↔ E_{k−i}``, ``D_i ↔ D_{k−1−i}`` with the
    largest eigenvalue below 1, scaled to unit response on the planar half-fan (``E_i`` at angle
    ``πi/k``, ``D_i = E_i + E_{i+1}``) and signed to point into the faces. OpenSubdiv's Biermann et
    al. mask is derived for modified rules: on its own rules its plane is 7–17° off for k = 3–6.
    For k ≥ 5 the ring has a third eigenvalue above 1/2, so the limit surface is not tangent-plane
    continuous there and this plane is the one through the boundary's own modes.
    """
    if k == 1:
        return -6.0, np.array([3.0, 3.0]), np.zeros(1)
    if k == 2:
        return -4.0 / 6.0, np.array([-1.0, 4.0, -1.0]) / 6.0, np.array([1.0, 1.0]) / 6.0
    size = 2 * k + 2
    unit = np.eye(size)
    edge, diagonal = unit[1:k + 2], unit[k + 2:]
    face_points = 0.25 * (unit[0] + edge[:-1] + diagonal + edge[1:])
    matrix = np.empty((size, size))
    matrix[0] = (6.0 * unit[0] + edge[0] + edge[k]) / 8.0
    matrix[1] = 0.5 * (unit[0] + edge[0])
    matrix[k + 1] = 0.5 * (unit[0] + edge[k])
    matrix[2:k + 1] = 0.25 * (unit[0] + edge[1:k] + face_points[:-1] + face_points[1:])
    matrix[k + 2:] = face_points
    values, vectors = np.linalg.eig(matrix.T)
    mirror = np.concatenate([[0], 1 + np.arange(k + 1)[::-1], k + 2 + np.arange(k)[::-1]])
    vectors = vectors.real / np.linalg.norm(vectors.real, axis=0)
    symmetric = (np.abs(values.imag) < 1e-12) & (np.abs(vectors - vectors[mirror]).max(axis=0) < 1e-9)
    candidates = np.flatnonzero(symmetric & (values.real < 1.0 - 1e-9))
    mask = vectors[:, candidates[np.argmax(values.real[candidates])]]
    angles = np.pi * np.arange(k + 1) / k
    planar = np.concatenate([[0.0], np.sin(angles), np.sin(angles[:-1]) + np.sin(angles[1:])])
    mask = mask / (mask @ planar)
    return float(mask[0]), mask[1:k + 2], mask[k + 2:]


def limit_stars(mesh: QuadMesh) -> tuple[FloatArray, FloatArray]:
    """Per vertex the two scaled limit tangents ``(a, b)``, (V, 3) each, spanning the tangent plane
    with ``a × b`` along the outward normal: inside A and B of the module docstring; at a boundary
    vertex a along the boundary (towards ``E_0``) and b across it, into the faces; at an
    ``edge-and-corner`` corner ``a = E_0 − V``, ``b = E_1 − V``."""
    topology = mesh.topology
    x = mesh.vertices
    nv = topology.n_vertices
    offsets = topology.neighbor_offsets
    ring_vertex = np.repeat(np.arange(nv), topology.face_count)
    h = topology.ring_halfedges
    i = np.arange(len(h)) - topology.ring_offsets[ring_vertex]
    e_i = x[topology.target(h)]
    d_i = x[topology.origin(QuadTopology.next(QuadTopology.next(h)))]
    boundary = topology.is_boundary_vertex
    k = topology.face_count

    # interior: the eigen tangents
    ea, da, eb, db = _interior_mask_weights(np.where(boundary, 4, k)[ring_vertex], i)
    a = _segment_sum(ring_vertex, ea[:, None] * e_i + da[:, None] * d_i, nv)
    b = _segment_sum(ring_vertex, eb[:, None] * e_i + db[:, None] * d_i, nv)

    # boundary: along (E_0 − E_k)/2, across by the cross eigen-mask of the k-face boundary ring
    first, last = x[topology.neighbors[offsets[:-1]]], x[topology.neighbors[offsets[1:] - 1]]
    across = np.zeros((nv, 3))
    for count in np.unique(k[boundary]):
        vertex_weight, spoke, face = _cross_mask(int(count))
        at = boundary[ring_vertex] & (k[ring_vertex] == count)
        rows = ring_vertex[at]
        across += _segment_sum(rows, spoke[i[at], None] * e_i[at] + face[i[at], None] * d_i[at], nv)
        here = boundary & (k == count)
        across[here] += vertex_weight * x[here] + spoke[count] * last[here]
    a = np.where(boundary[:, None], 0.5 * (first - last), a)
    b = np.where(boundary[:, None], across, b)

    corner = corner_vertices(topology, boundary_mode(mesh))
    a[corner] = first[corner] - x[corner]
    b[corner] = last[corner] - x[corner]
    return a, b


def _slot_angles(topology: QuadTopology) -> FloatArray:
    """Angle of every slot in its star: ``2πj/n`` inside, ``πj/k`` over the k + 1 slots of a boundary vertex."""
    offsets = topology.neighbor_offsets
    slot_vertex = np.repeat(np.arange(topology.n_vertices), np.diff(offsets))
    step = np.where(topology.is_boundary_vertex, np.pi / topology.face_count, 2.0 * np.pi / topology.face_count)
    return (np.arange(len(slot_vertex)) - offsets[slot_vertex]) * step[slot_vertex]


def limit_tangents(mesh: QuadMesh) -> FloatArray:
    """Per ring slot the limit tangent along its edge, (S, 3): ``cos φ_j a + sin φ_j b`` over
    :func:`limit_stars` (``φ_j = 2πj/n`` inside, ``πj/k`` at a boundary vertex with k faces); an
    ``edge-and-corner`` corner keeps its two edges ``E − V`` (module docstring for the lengths)."""
    topology = mesh.topology
    a, b = limit_stars(mesh)
    slot_vertex = np.repeat(np.arange(topology.n_vertices), np.diff(topology.neighbor_offsets))
    phi = _slot_angles(topology)
    t = np.cos(phi)[:, None] * a[slot_vertex] + np.sin(phi)[:, None] * b[slot_vertex]
    corner = np.flatnonzero(corner_vertices(topology, boundary_mode(mesh)))
    offsets = topology.neighbor_offsets
    t[offsets[corner]] = a[corner]
    t[offsets[corner] + 1] = b[corner]
    return t


def limit_normals(mesh: QuadMesh) -> FloatArray:
    """``a × b`` of :func:`limit_stars`, unit; zero where the two tangents are parallel."""
    a, b = limit_stars(mesh)
    n = np.cross(a, b)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)
