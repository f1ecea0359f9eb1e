"""The cage whose Catmull–Clark limit surface passes nearest a scan (Eck & Hoppe 1996, Hoppe et
al. 1994: fit a subdivision surface's control mesh by linear least squares, feet re-projected).

The limit surface of a cage C over a quad layout is linear in C: at the vertices of the layout
refined ``levels`` times its points are ``G C`` exactly
(:func:`g1patch.subdivision.limit_grid_matrix`, a ``(2^levels + 1)²`` grid per face); between
them the surface is taken as the triangles of that grid (a second-order approximation: the grid
step is a quarter of a cage edge at the default two levels, where the limit bends little). Each
scan point p gets its foot on those triangles (barycentric weights b over a triangle's three grid
points), so that its model is ``B G C`` (B: one row of three weights per point), and the cage
minimises

    ``‖B G C − P‖² + λ ‖W^½ K C‖² + μ ‖C − C_prev‖²``,   ``λ = fairness · N / V``,
    ``μ = damping · N / V``

(N scan points, V cage vertices; K the umbrella Laplacian ``C_v − mean of its neighbours``: a
small fairness term keeps noise from being chased; the proximal term keeps vertices few points
reach near the previous cage while the feet settle; W a per-vertex stiffness, 1 but where a
fit folded, :func:`~g1patch.fitting._stiffened`), solved by a sparse LU of the normal
equations. The feet move with the surface, so project → solve is repeated ``iterations`` times.

The surface is also pulled to the scan the other way (a symmetric, two-way fit):

    ``+ γ min(N / M, 1) ‖G_M C − Q_M‖²``,   γ = :data:`TWO_WAY`,

Q_M the nearest points on the scan's triangles of M grid points, half a face apart
(:data:`SURFACE_STEP`; exact, :class:`~g1patch.compare.NearestTriangles`); left out are points
whose foot is farther than a layout edge (over a hole of the scan) or on a facet facing away,
and points on crease edges, whose feet fall on either side of the scan's sharp edge (a stepped
block's surface went 6.5e-4 → 1.1e-3 of the diagonal off with them). Fitted to its vertices
alone, a smooth surface bulges off the facets between them by their sag, which the tolerance
bounds too (the surface → scan maximum): on a coarse scan (libigl's fertility, 9,000 triangles,
an edge 1.5 % of the diagonal) the one-way fit of 4,232 quads was 2.1e-3 of the diagonal off
the facets at its worst, the two-way one 1.8e-3. A grid point weighs no more than γ scan
points, and a scan of more than :data:`DENSE` points per grid point gets no such rows: its
facets are near any surface that passes near its vertices, and where the layout is too coarse
for a feature (a narrow bump on a 60,000-point sphere scan) the pull back towards the flanks
costs the bump's tip (2.2e-3 → 2.4e-3 off; with each grid point weighing 7 scan points,
4.9e-3). γ = 1 weighs both ways alike; ½ did better on eleven public
scans (halftunnel, fandisk and Spot's triangles ended farther at 1, fertility nearer).

An open scan's boundary holds the surface's: the limit boundary curve (the grid points on the
layout's boundary edges; by the Catmull–Clark boundary rules the cubic B-spline of the cage's
boundary vertices) is tied to the scan's boundary polyline both ways,

    ``+ α ‖(1 − t) G_a C + t G_b C − S‖² + β ‖G_B C − Q‖²``,

S the scan's boundary vertices with their feet (segment a–b, parameter t) on the curve's grid
polyline, Q the nearest points of the scan's boundary to the curve's grid points B;
``α = N V_b / (V |S|)``, ``β = N V_b / (V |B|)`` (V_b boundary cage vertices): a boundary vertex
is pulled by as many points' worth as an interior one. Without these rows nothing holds the
boundary quads' outer vertices but fairness and damping, and the rim hangs off the scan's.
Only pairs nearer than :data:`BOUNDARY_GATE` layout edges are tied: a scan boundary the layout
has no boundary for (a small hole the remesher closed, a handle's open end inside a teapot's
body) is left alone, not pulled onto the nearest rim of the layout (spikes of half the model).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu
from scipy.spatial import cKDTree

from ..compare import NearestTriangles, _barycentric_closest, closest_points_on_triangles
from ..errors import ConstructionError
from ..mesh import QuadMesh
from ..subdivision import limit_grid_matrix
from .features import median_edge
from .scan_topology import boundary_edges, polygon_sides, triangle_parts

__all__ = [
    "FIT_ITERATIONS",
    "FIT_LEVELS",
    "FitCage",
    "fit_cage",
    "fit_parts",
    "grid_triangles",
    "vertex_normals",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: SuperLU told the normal equations are symmetric positive definite: a minimum-degree ordering
#: of A + Aᵀ and pivots on the diagonal (an 18,197-vertex cage of the Stanford bunny: 0.62 s a
#: factorisation instead of 4.39 s with the default column ordering, the same solution to 2e-13)
SYMMETRIC_LU = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.0,
    "options": {"SymmetricMode": True},
}
#: refinement levels of the limit grid the scan points are projected on
FIT_LEVELS = 2
#: project → solve alternations
FIT_ITERATIONS = 6
#: the fairness weight per scan point per cage vertex (dimensionless: both terms are lengths²)
FAIRNESS = 1e-3
#: the weight, per scan point per cage vertex, of staying near the previous solve's cage (a
#: proximal step: a vertex few points reach cannot run away while the feet settle)
DAMPING = 1e-2
#: surface points a scan point's foot may start from (the nearest that faces its way)
_NEIGHBOURS = 8
#: the farthest a scan boundary point and the layout's boundary curve are tied, and a surface
#: grid point and its foot on the scan, in median layout edges (the remesher's boundary vertices
#: start snapped onto the scan's rim, so a true pair is far nearer than this)
BOUNDARY_GATE = 1.0
#: the weight γ of the surface → scan rows, all grid points together, against the scan → surface
#: rows, all scan points together (module docstring)
TWO_WAY = 0.5
#: the surface → scan rows take every ``SURFACE_STEP``-th grid point along a face's sides (2: the
#: points of the grid one level coarser, 4 a face; fertility, bumpy, lion and the elephant came
#: out as near as with all 16, and the Stanford bunny scan's 10,159-quad fit takes 11.6 s, 3.5 s
#: of it in the rows, against 6.8 s one way)
SURFACE_STEP = 2
#: ... but not on a scan of more than this many points per grid point pulled: its facets are a
#: few to a grid cell, their sag far below the fit's, and the rows only cost (a 1 M-triangle
#: torus: 27 → 44 s, 527 → 669 MB) or pull a feature's flanks (a narrow bump on a 60,000-point
#: sphere scan, 15 points a grid point: within at 1,633 quads in 4 layouts, at 1,116 in 2 one
#: way); fertility, lion and the other coarse scans have 0.3–2
DENSE = 8.0
#: scan points whose feet and normal equations are made at a time (bounds the memory: ~2 kB a
#: point in flight)
BLOCK_POINTS = 65_536


class FitCage(NamedTuple):
    """The fitted cage (the layout's topology, new positions) and the model's RMS distance of
    the scan points after each solve, in model units."""

    cage: QuadMesh
    rms: tuple[float, ...]


def grid_triangles(grid: IntArray) -> IntArray:
    """The two triangles of every cell of per-face grids ``(F, m + 1, m + 1)``, (2 F m², 3),
    oriented as the faces (u then v)."""
    a, b = grid[:, :-1, :-1], grid[:, 1:, :-1]
    c, d = grid[:, 1:, 1:], grid[:, :-1, 1:]
    first = np.stack([a, b, c], axis=-1).reshape(-1, 3)
    second = np.stack([a, c, d], axis=-1).reshape(-1, 3)
    return np.concatenate([first, second])


def grid_sides(grid: IntArray) -> IntArray:
    """The grid points ``(F, 4, m + 1)`` along the sides of per-face grids ``(F, m + 1, m + 1)``,
    side i from the face's corner i to corner i + 1."""
    return np.stack([grid[:, :, 0], grid[:, -1, :], grid[:, ::-1, -1], grid[:, 0, ::-1]], 1)


def vertex_normals(points: FloatArray, triangles: IntArray) -> FloatArray:
    """Area-weighted unit vertex normals of a triangle mesh (zero where a vertex has none)."""
    a, b, c = (points[triangles[:, k]] for k in range(3))
    area = np.cross(b - a, c - a)
    corners = triangles.reshape(-1)
    total = np.stack(
        [np.bincount(corners, np.repeat(area[:, d], 3), minlength=len(points)) for d in range(3)],
        axis=1,
    )
    length = np.linalg.norm(total, axis=1, keepdims=True)
    return total / np.where(length > 0, length, 1.0)


def closest_on_segments(
    points: FloatArray, starts: FloatArray, ends: FloatArray
) -> tuple[IntArray, FloatArray]:
    """Per point the segment nearest it among the :data:`_NEIGHBOURS` of nearest midpoint and
    the parameter ``t`` of its closest point ``(1 − t) a + t b``, ``t = clamp((p − a)·(b − a) /
    |b − a|², 0, 1)``."""
    k = min(_NEIGHBOURS, len(starts))
    near = cKDTree(0.5 * (starts + ends)).query(points, k=k, workers=-1)[1].reshape(len(points), k)
    a, edge = starts[near], ends[near] - starts[near]
    length = np.maximum((edge * edge).sum(-1), np.finfo(np.float64).tiny)
    t = np.clip(((points[:, None, :] - a) * edge).sum(-1) / length, 0.0, 1.0)
    gap = np.linalg.norm(a + t[..., None] * edge - points[:, None, :], axis=-1)
    best = np.argmin(gap, axis=1)
    rows = np.arange(len(points))
    return near[rows, best], t[rows, best]


class _Boundary:
    """The rows tying the limit's boundary curve to a scan's boundary polyline (module
    docstring): the boundary sides of the layout's ``faces`` (a mask) as grid segments, the
    boundary edges of the scan's ``triangles``."""

    def __init__(
        self,
        points: FloatArray,
        triangles: IntArray,
        layout: QuadMesh,
        grid: IntArray,
        faces: NDArray[np.bool_],
    ) -> None:
        edges = boundary_edges(triangles)
        sides, open_sides = polygon_sides(layout.faces)
        open_sides &= faces[:, None]
        polylines = grid_sides(grid)[open_sides]  # (B, m + 1) grid points along each boundary side
        self.segments = np.stack([polylines[:, :-1], polylines[:, 1:]], -1).reshape(-1, 2)
        self.samples = np.unique(polylines)
        self.scan_vertices = points[np.unique(edges)]
        self.scan_starts, self.scan_ends = points[edges[:, 0]], points[edges[:, 1]]
        self.active = bool(len(edges) and len(polylines))
        self.cage_boundary = np.unique(sides[open_sides])
        part_sides = sides[faces].reshape(-1, 2)
        self.gate = BOUNDARY_GATE * median_edge(layout, part_sides) if faces.any() else 0.0

    def snapped(self, cage: FloatArray) -> FloatArray:
        """``cage`` with its boundary vertices moved to the nearest points of the scan's
        boundary (the remesher's boundary vertices may lie inside the scan's rim)."""
        if not self.active:
            return cage
        corners = cage[self.cage_boundary]
        nearest, s = closest_on_segments(corners, self.scan_starts, self.scan_ends)
        moved = cage.copy()
        moved[self.cage_boundary] = self.scan_starts[nearest] + s[:, None] * (
            self.scan_ends[nearest] - self.scan_starts[nearest]
        )
        return moved

    def rows(
        self, limit: sp.csr_matrix, surface: FloatArray, per_vertex: float
    ) -> tuple[sp.csr_matrix, FloatArray]:
        """The weighted rows ``(√w M, √w target)`` of both ways on the current ``surface``."""
        starts, ends = surface[self.segments[:, 0]], surface[self.segments[:, 1]]
        segment, t = closest_on_segments(self.scan_vertices, starts, ends)
        foot = starts[segment] + t[:, None] * (ends[segment] - starts[segment])
        tied = np.linalg.norm(foot - self.scan_vertices, axis=1) <= self.gate
        segment, t, scan_vertices = segment[tied], t[tied], self.scan_vertices[tied]
        count = len(segment)
        feet = sp.csr_matrix(
            (
                np.stack([1.0 - t, t], 1).reshape(-1),
                (np.repeat(np.arange(count), 2), self.segments[segment].reshape(-1)),
            ),
            shape=(count, limit.shape[0]),
        )
        nearest, s = closest_on_segments(surface[self.samples], self.scan_starts, self.scan_ends)
        targets = self.scan_starts[nearest] + s[:, None] * (
            self.scan_ends[nearest] - self.scan_starts[nearest]
        )
        near = np.linalg.norm(targets - surface[self.samples], axis=1) <= self.gate
        samples, targets = self.samples[near], targets[near]
        alpha = np.sqrt(per_vertex * self.cage_boundary.size / max(count, 1))
        beta = np.sqrt(per_vertex * self.cage_boundary.size / max(len(samples), 1))
        model = sp.vstack([alpha * (feet @ limit), beta * limit[samples]]).tocsr()
        return model, np.concatenate([alpha * scan_vertices, beta * targets])


class _Triangles:
    """A triangle mesh prepared for foot queries: a k-d tree of the points its triangles use,
    their normals and every point's fan of triangles (CSR: ``order[starts[v]:starts[v + 1]] //
    3``)."""

    def __init__(self, points: FloatArray, triangles: IntArray) -> None:
        corners = triangles.reshape(-1)
        self.points, self.triangles = points, triangles
        self.order = np.argsort(corners, kind="stable")
        self.starts = np.searchsorted(corners[self.order], np.arange(len(points) + 1))
        self.normals = vertex_normals(points, triangles)
        self.used = np.unique(corners)
        self.tree = cKDTree(points[self.used])

    def feet(self, points: FloatArray, normals: FloatArray) -> tuple[IntArray, FloatArray]:
        """Per point the triangle nearest it among those around a nearby mesh point, and the
        barycentric weights (N, 3) of the closest point on it. The mesh point is the nearest of
        the :data:`_NEIGHBOURS` nearest whose normal faces the same way as the point's (dot > 0;
        the nearest where none does): across a thin part (a tail, an ear) the nearest mesh point
        may lie on the far side, and a foot there pulls that side over."""
        near = self.used[self.tree.query(points, k=_NEIGHBOURS, workers=-1)[1]]
        facing = np.einsum("nkd,nd->nk", self.normals[near], normals) > 0
        pick = np.where(facing.any(axis=1), np.argmax(facing, axis=1), 0)
        nearest = near[np.arange(len(points)), pick]
        counts = self.starts[nearest + 1] - self.starts[nearest]
        slot = np.arange(int(counts.max()))
        valid = slot[None, :] < counts[:, None]
        last = len(self.order) - 1
        candidate = np.where(
            valid, self.order[np.minimum(self.starts[nearest][:, None] + slot, last)] // 3, 0
        )
        corners = self.points[self.triangles[candidate]]  # (N, width, 3, 3)
        a = corners[:, :, 0]
        ab, ac = corners[:, :, 1] - a, corners[:, :, 2] - a
        ap = points[:, None, :] - a
        v, w = _barycentric_closest(
            (ab * ap).sum(-1),
            (ac * ap).sum(-1),
            (ab * ab).sum(-1),
            (ab * ac).sum(-1),
            (ac * ac).sum(-1),
        )
        gap = np.linalg.norm(v[..., None] * ab + w[..., None] * ac - ap, axis=-1)
        usable = valid & np.isfinite(gap)  # a collinear triangle's weights are NaN: skipped
        best = np.argmin(np.where(usable, gap, np.inf), axis=1)
        rows = np.arange(len(points))
        v, w = np.nan_to_num(v[rows, best]), np.nan_to_num(w[rows, best])
        return candidate[rows, best], np.stack([1.0 - v - w, v, w], axis=1)


def _surface_rows(
    scan: NearestTriangles,
    triangles: FloatArray,
    limit: sp.csr_matrix,
    surface: _Triangles,
    grid: IntArray,
    weight: float,
    gate: float,
) -> tuple[sp.csr_matrix, FloatArray]:
    """The weighted rows ``(√w G_g, √w q_g)`` pulling the ``surface``'s ``grid`` points ``g`` to
    their feet ``q_g``, the nearest points of the ``scan``'s ``triangles`` (T, 3, 3),
    ``w = weight``, where the foot's facet faces the surface's way and is nearer than ``gate``
    (not a grid point over a hole of the scan)."""
    points = surface.points[grid]
    distance, triangle = scan.query(points)
    a, b, c = (triangles[triangle, k] for k in range(3))
    facing = np.einsum("nd,nd->n", np.cross(b - a, c - a), surface.normals[grid]) > 0
    use = facing & (distance <= gate)
    feet = closest_points_on_triangles(points[use], a[use], b[use], c[use])
    root = np.sqrt(weight)
    return (root * limit[grid[use]]).tocsr(), root * feet


def fit_parts(
    points: FloatArray, triangles: IntArray, layout: QuadMesh
) -> tuple[IntArray, IntArray]:
    """Which part of the fit each scan point and each layout face belongs to: a connected part
    of the scan (:func:`~g1patch.fitting.scan_topology.triangle_parts`) and the layout's connected
    parts whose vertices are mostly nearest to it. A scan part no layout part claims joins the
    part of the layout vertices nearest to its points. ``(point_part (N,), face_part (F,))``."""
    scan_part = np.full(len(points), -1)
    scan_part[triangles.reshape(-1)] = np.repeat(triangle_parts(triangles, len(points)), 3)
    faces = layout.faces
    layout_part = np.zeros(layout.n_vertices, dtype=np.int64)
    layout_part[faces.reshape(-1)] = np.repeat(triangle_parts(faces, layout.n_vertices), 4)
    used, scanned = np.unique(faces), np.unique(triangles)
    nearest = scan_part[scanned[cKDTree(points[scanned]).query(layout.vertices[used])[1]]]
    votes = sp.coo_matrix((np.ones(used.size), (layout_part[used], nearest)))
    claim = np.asarray(votes.argmax(axis=1)).ravel()  # layout part → scan part
    face_part = claim[layout_part[faces[:, 0]]]
    point_part = scan_part.copy()
    unclaimed = ~np.isin(scan_part, claim)
    if unclaimed.any():
        near = cKDTree(layout.vertices[used]).query(points[unclaimed])[1]
        point_part[unclaimed] = claim[layout_part[used[near]]]
    return point_part, face_part


def _umbrella(mesh: QuadMesh) -> sp.csr_matrix:
    """``K C = C_v − mean of v's edge neighbours`` (V × V)."""
    edges = mesh.topology.edges
    count = mesh.n_vertices
    degree = np.bincount(edges.ravel(), minlength=count).astype(np.float64)
    rows = np.concatenate([edges[:, 0], edges[:, 1]])
    columns = np.concatenate([edges[:, 1], edges[:, 0]])
    weights = -1.0 / np.maximum(degree[rows], 1.0)
    neighbours = sp.csr_matrix((weights, (rows, columns)), shape=(count, count))
    return sp.identity(count, format="csr") + neighbours


def fit_cage(
    points: FloatArray,
    normals: FloatArray,
    layout: QuadMesh,
    scan_triangles: IntArray | None = None,
    *,
    levels: int = FIT_LEVELS,
    iterations: int = FIT_ITERATIONS,
    fairness: float = FAIRNESS,
    damping: float = DAMPING,
    stiffness: FloatArray | None = None,
    two_way: float = TWO_WAY,
) -> FitCage:
    """The cage of ``layout``'s topology whose limit surface passes nearest ``points`` (N, 3,
    with unit ``normals``) (module docstring), starting from the layout's own positions; the
    ``scan_triangles`` give the scan's boundary and facets (none: the boundary rows and the
    surface → scan rows are left out); ``stiffness`` (V,) the fairness weight per cage vertex
    (W, all 1 when None); ``two_way`` the weight γ of the surface → scan rows (0: one way)."""
    limit, grid = limit_grid_matrix(layout, levels)
    if scan_triangles is None:
        point_part, face_part = np.zeros(len(points), np.int64), np.zeros(layout.n_faces, np.int64)
    else:
        point_part, face_part = fit_parts(points, scan_triangles, layout)
    topology = layout.topology
    creased = (layout.features.edge_sharpness > 0)[topology.halfedge_edge]
    on_creases = grid_sides(grid)[creased.reshape(-1, 4)]
    parts = []  # per part: points, grid triangles, boundary rows, facets, grid points pulled, w
    for part in np.unique(face_part):
        mine = np.flatnonzero(point_part == part)
        boundary, facets = None, None
        if scan_triangles is not None:
            own = scan_triangles[point_part[scan_triangles[:, 0]] == part]
            boundary = _Boundary(points, own, layout, grid, face_part == part)
        coarse = grid[face_part == part][:, ::SURFACE_STEP, ::SURFACE_STEP]
        pulled = np.setdiff1d(coarse, on_creases)
        if scan_triangles is not None and len(own) and 0 < len(mine) <= DENSE * len(pulled):
            facets = (NearestTriangles(points, own), points[own]) if two_way > 0 else None
        each = two_way * min(len(mine) / max(len(pulled), 1), 1.0)  # no more than a scan point
        triangles = grid_triangles(grid[face_part == part])
        parts.append((mine, triangles, boundary, facets, pulled, each))
    fair = _umbrella(layout)
    per_vertex = len(points) / max(layout.n_vertices, 1)
    damping = damping * per_vertex
    weights = sp.identity(layout.n_vertices) if stiffness is None else sp.diags(stiffness)
    regular = fairness * per_vertex * (fair.T @ weights @ fair) + damping * sp.identity(
        layout.n_vertices
    )
    gate = BOUNDARY_GATE * median_edge(layout)
    cage = layout.vertices.copy()
    for _, _, boundary, _, _, _ in parts:
        cage = cage if boundary is None else boundary.snapped(cage)
    rms = []
    for _ in range(iterations):
        lhs, rhs, kept = regular, damping * cage, []
        surface = limit @ cage
        for mine, triangles, boundary, facets, pulled, each in parts:
            if boundary is not None and boundary.active:
                rows, targets = boundary.rows(limit, surface, per_vertex)
                lhs, rhs = lhs + rows.T @ rows, rhs + np.asarray(rows.T @ targets)
            near = _Triangles(surface, triangles)
            if facets is not None:
                rows, targets = _surface_rows(*facets, limit, near, pulled, each, gate)
                lhs, rhs = lhs + rows.T @ rows, rhs + np.asarray(rows.T @ targets)
            for start in range(0, len(mine), BLOCK_POINTS):  # a block of points at a time
                rows = mine[start : start + BLOCK_POINTS]
                triangle, barycentric = near.feet(points[rows], normals[rows])
                count = len(triangle)
                feet = sp.csr_matrix(
                    (
                        barycentric.reshape(-1),
                        (np.repeat(np.arange(count), 3), triangles[triangle].reshape(-1)),
                    ),
                    shape=(count, limit.shape[0]),
                )
                model = (feet @ limit).tocsr()
                lhs = lhs + model.T @ model
                rhs = rhs + np.asarray(model.T @ points[rows])
                kept.append((triangles[triangle], barycentric, rows))
        try:
            factor = splu(sp.csc_matrix(lhs), **SYMMETRIC_LU)
        except RuntimeError as error:  # SuperLU: "Factor is exactly singular"
            raise ConstructionError(
                f"fit: the least-squares system is singular ({error})"
            ) from None
        cage = factor.solve(rhs)
        if not np.isfinite(cage).all():
            raise ConstructionError("fit: the least-squares solve gave non-finite positions")
        moved = limit @ cage  # the model's feet on the new surface: their squared distances
        squared = sum(
            float(np.sum((np.einsum("nk,nkd->nd", weights, moved[corners]) - points[rows]) ** 2))
            for corners, weights, rows in kept
        )
        rms.append(float(np.sqrt(squared / len(points))))
    return FitCage(layout.with_vertices(cage), tuple(rms))
