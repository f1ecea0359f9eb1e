"""Interpolating Catmull–Clark targets: the limit surface of a solved cage that passes through the
mesh vertices.

Halstead, Kass and DeRose (SIGGRAPH 1993), and Rhino's interpolating SubD: the mesh's vertices V
are not the control cage but the limit positions wanted. The limit position of every cage vertex
is a fixed linear combination of the cage (the masks of :func:`~g1patch.subdivision.limit_points`),
so with the V × V sparse *limit stencil* L
(:func:`~g1patch.subdivision.matrix.limit_matrix`, re-exported here)

    ``limit_points(cage C) = L C``,

a cage of the same topology and tags whose limit passes through V solves ``L C = V``. L depends on
the topology, the boundary mode and the sharp edges only, not on the positions. Rows:

* smooth vertex v with n faces, ring neighbours ``E_i``, opposite face corners ``D_i``:
  ``L_vv = n/(n + 5)``, ``L_vE_i = 4/(n(n + 5))``, ``L_vD_i = 1/(n(n + 5))``;
* crease vertex (two sharp edges to A, B): ``L_vv = 2/3``, ``L_vA = L_vB = 1/6``;
* corner vertex: ``L_vv = 1``.

:func:`interpolating_cage` solves it for the correction ``D = C − V``,
``L D = V − L V``: by a sparse LU (SuperLU) where L is well conditioned (1-norm condition estimate
``κ₁ = ‖L‖₁ · est ‖L⁻¹‖₁ ≤`` :data:`MAX_CONDITION`), else by LSMR to
:data:`LSMR_TOLERANCE`, which from a zero start converges to the least-norm correction: the
cage closest to the mesh. L can be exactly singular: on the cube every vertex has valence 3 and
the checkerboard mode ``s_v = ±1`` (+ at v and its face-opposite corners, − at its neighbours)
has ``(L s)_v = (n − 3)/(n + 5) = 0``. A symmetric cube's vertices are orthogonal to that mode,
so the system still has solutions (the least-norm one is the cube scaled by 2); a jittered cube's
are not, and no cage of that topology has them as its limit. Either way the relative residual
``max_v |(L C − V)_v| / diag(V)`` is measured and, above :data:`MAX_RESIDUAL`, a
:class:`~g1patch.errors.ConstructionError` names the problem: no silent approximation.

:func:`limit_interpolate_targets` then takes :func:`~g1patch.targets.limit.limit_targets` of the
cage (normals, tangents and interior points of its limit surface) with the positions set to V
exactly (they differ from the cage's limit points by the residual only).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import LinearOperator, SuperLU, lsmr, onenormest, splu

from ..errors import ConstructionError, MeshError
from ..mesh import QuadMesh
from ..mesh.cage import PolygonTopology
from ..mesh.neighbourhood import cage_neighbourhood
from ..subdivision import catmull_clark_cage, limit_normals, limit_points, limit_stars
from ..subdivision.matrix import cage_step_matrix, limit_matrix, refine_matrix
from .limit import limit_targets
from .value import TangentRule, Targets

__all__ = [
    "LSMR_ITERATIONS",
    "LSMR_TOLERANCE",
    "MAX_CONDITION",
    "MAX_RESIDUAL",
    "FOLD_ANGLE_DEG",
    "CLEAN_ANGLE_DEG",
    "PINCH_RATIO",
    "CageSolution",
    "interpolating_cage",
    "limit_interpolate_near",
    "limit_interpolate_targets",
    "limit_matrix",
]

FloatArray = NDArray[np.float64]

#: the largest relative residual ``max_v |(L C − V)_v| / diag(V)`` accepted
MAX_RESIDUAL = 1e-10
#: the largest 1-norm condition estimate of L for which the LU solution is used; above it LSMR
#: finds the least-norm correction (a near-null mode of L would otherwise blow up the cage)
MAX_CONDITION = 1e8
#: LSMR's ``atol = btol`` (relative residual of the least-squares problem) and its iteration cap
LSMR_TOLERANCE = 1e-14
LSMR_ITERATIONS = 20_000
#: a condition estimate above this (≈ 1/ε) is reported as numerically singular
_SINGULAR = 1e15

Solver = Literal["lu", "lsmr"]
_logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class CageSolution:
    """The solved cage of :func:`interpolating_cage`.

    * ``cage`` (V, 3): the control points C, on the mesh's quad topology;
    * ``mesh``: the cage as a quad mesh (C with the cage's tags): the mesh itself with new
      positions where it was read as quads; for a mesh split from polygons the Catmull–Clark step
      of the solved polygon cage (:func:`~g1patch.subdivision.catmull_clark_cage`, its tags);
    * ``residual``: ``max_v |(L C − V)_v| / diag(V)`` over the interpolated vertices, measured
      with :func:`~g1patch.subdivision.limit_points`;
    * ``condition``: the 1-norm condition estimate of the system (``inf`` where the LU found it
      singular);
    * ``solver``: ``lu`` (sparse LU) or ``lsmr`` (least-norm correction, singular or ill
      conditioned);
    * ``points`` (V, 3): where the limit passes by the mesh's vertices: the vertices themselves
      (for a quad mesh the same array) except at ``relaxed`` and, for a mesh split from polygons,
      at the split's edge and face points, there the cage's limit points;
    * ``relaxed``: the vertices not interpolated (:func:`_relaxed`: exact interpolation would turn
      the surface inside out or pinch it there), empty on most meshes;
    * ``relaxed_distance``: the largest distance from a relaxed vertex to its limit point,
      relative to the bounding-box diagonal (0 where none is relaxed); the residual is measured
      at the other vertices.
    """

    cage: FloatArray
    mesh: QuadMesh
    residual: float
    condition: float
    solver: Solver
    points: FloatArray
    relaxed: NDArray[np.int64]
    relaxed_distance: float = 0.0


@dataclass(frozen=True)
class _System:
    """What :func:`interpolating_cage` solves: unknown points U (n, 3) that give the quad cage
    ``C = spread @ U`` on ``mesh``'s topology and tags, whose limit ``limit @ C`` must pass
    through ``targets`` at the first n vertices: ``matrix @ U = targets``,
    ``matrix = (limit @ spread)[:n]``.
    For a quad mesh U is the cage itself (``spread`` the identity, n = V); for a mesh split from
    polygons U is the polygon cage, ``spread`` its Catmull–Clark step (the same cage ``limit``
    takes, :func:`~g1patch.subdivision.catmull_clark_cage`), and only the polygons' own vertices
    are interpolated: the split's edge and face points follow from the step. ``edges`` join the
    unknowns (for fairing); ``through`` maps U to the cage refined once (``fine``), where the
    normals and tangents are compared (:func:`_turned`)."""

    mesh: QuadMesh
    spread: sp.csr_matrix
    limit: sp.csr_matrix
    matrix: sp.csr_matrix
    targets: FloatArray
    edges: NDArray[np.int64]
    through: sp.csr_matrix
    fine: QuadMesh
    diagonal: float

    def cage(self, unknowns: FloatArray) -> FloatArray:
        return np.asarray(self.spread @ unknowns)


def _system(mesh: QuadMesh) -> _System:
    """The :class:`_System` of ``mesh``: on its own quads, or through its polygon cage's step."""
    spread = cage_step_matrix(mesh)
    polygons = mesh.cage
    if spread is None or polygons is None:
        limit = limit_matrix(mesh)
        refine, fine = refine_matrix(mesh, 1)
        identity = sp.identity(mesh.n_vertices, format="csr")
        return _System(
            mesh,
            identity,
            limit,
            limit,
            mesh.vertices,
            mesh.topology.edges,
            refine,
            fine,
            mesh.bounding_box_diagonal,
        )
    stepped = catmull_clark_cage(mesh)
    limit = limit_matrix(stepped)
    count = polygons.points.shape[0]
    refine, fine = refine_matrix(stepped, 1)
    edges = PolygonTopology.from_polygons(polygons.corners, polygons.sizes, count).edges
    return _System(
        stepped,
        spread,
        limit,
        sp.csr_matrix(limit[:count] @ spread),
        polygons.points,
        edges,
        sp.csr_matrix(refine @ spread),
        fine,
        mesh.bounding_box_diagonal,
    )


def _condition(matrix: sp.csr_matrix, lu: SuperLU) -> float:
    """``κ₁ = ‖L‖₁ · est ‖L⁻¹‖₁`` by Hager–Higham's estimator (``onenormest``) on the LU's
    solves."""
    size = matrix.shape[0]
    inverse = LinearOperator(
        (size, size),
        matvec=lambda x: lu.solve(np.asarray(x, dtype=np.float64)),
        rmatvec=lambda x: lu.solve(np.asarray(x, dtype=np.float64), trans="T"),
        dtype=np.float64,
    )
    return float(abs(matrix).sum(axis=0).max() * onenormest(inverse))


def _solve(matrix: sp.csr_matrix, rhs: FloatArray) -> tuple[FloatArray, float, Solver]:
    """The correction D with ``L D = rhs`` (3 columns) and κ₁: LU where ``κ₁ ≤``
    :data:`MAX_CONDITION`, else the least-norm LSMR solution per coordinate (κ₁ = ∞ where SuperLU
    finds L exactly singular)."""
    try:
        lu = splu(matrix.tocsc())
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        condition = float("inf")
    else:
        condition = _condition(matrix, lu)
        if condition <= MAX_CONDITION:
            return lu.solve(rhs), condition, "lu"
    columns = [
        lsmr(matrix, rhs[:, d], atol=LSMR_TOLERANCE, btol=LSMR_TOLERANCE, maxiter=LSMR_ITERATIONS)[
            0
        ]
        for d in range(3)
    ]
    return np.stack(columns, axis=1), condition, "lsmr"


def interpolating_cage(mesh: QuadMesh) -> CageSolution:
    """The cage C of ``mesh``'s topology and tags whose Catmull–Clark limit points are the mesh's
    vertices V: ``L C = V`` (module docstring), solved as ``C = V + D``, ``L D = V − L V``. For a
    mesh split from polygons (:attr:`~g1patch.mesh.QuadMesh.cage`) the polygon cage P is solved
    instead, ``(L S P)_v = V_v`` at the polygons' own vertices (S its Catmull–Clark step, as
    ``limit`` takes it), and C = S P: the limit is that of a polygon cage, and the split's edge
    and face points are not asked to lie on it.

    Raises :class:`ConstructionError` where no such cage exists to :data:`MAX_RESIDUAL` (L singular
    and V outside its range), or where the solved cage has a degenerate face.
    """
    system = _system(mesh)
    x = system.targets
    matrix = system.matrix
    correction, condition, solver = _solve(matrix, x - matrix @ x)
    unknowns = x + correction
    diagonal = system.diagonal
    try:
        cage = system.mesh.with_vertices(system.cage(unknowns))
    except MeshError as error:
        raise ConstructionError(
            f"limit-interpolate: the interpolating cage is degenerate ({error})"
        ) from None
    limit = limit_points(cage)
    residual = float(np.linalg.norm(limit[: len(x)] - x, axis=1).max() / diagonal)
    if not residual <= MAX_RESIDUAL:
        singular = ", numerically singular" if condition > _SINGULAR else ""
        raise ConstructionError(
            "limit-interpolate: no Catmull–Clark cage of this mesh's topology has its vertices "
            "as limit points: the limit "
            f"stencil has 1-norm condition estimate {condition:.1e}{singular}, and the closest "
            f"cage ({solver}) leaves a "
            f"relative residual of {residual:.1e} > {MAX_RESIDUAL:g}. On a cage whose vertices "
            "all have valence 3 (a cube) "
            "the checkerboard mode is in the stencil's null space and only vertices symmetric to "
            "it can be interpolated; "
            "use refine=1 (--refine 1) first, or shape 'interpolate'"
        )
    points = mesh.vertices if len(x) == mesh.n_vertices else np.vstack([x, limit[len(x) :]])
    exact = CageSolution(
        cage.vertices, cage, residual, condition, solver, points, np.zeros(0, np.int64)
    )
    return _relaxed(system, exact, unknowns)


#: the solved cage's limit is *inside out* where one of its normals, at the vertices, edge
#: midpoints and face centres of one Catmull–Clark step, is turned more than this from the normal
#: of the mesh's own Catmull–Clark limit at the same point: the exact solve is then relaxed
#: (:func:`_relaxed`). No mesh without folds comes near it (the shared meshes and the coarse
#: cages that interpolate fold-free turn at most 95°); the cages whose interpolating cage folds
#: turn 170–180°.
FOLD_ANGLE_DEG = 120.0
#: once relaxing, vertices are freed until no normal is turned more than this (a fold)
CLEAN_ANGLE_DEG = 90.0
#: the solved cage's limit is *pinched* where the sine of the angle between its two limit tangents
#: (:func:`~g1patch.subdivision.limit_stars`) is below this fraction of the mesh's own limit's at
#: the same point: a near-cusp, parametrised almost along one direction, that the patches of a
#: refined cage resolve as folds (issue 31). The cages that fold so pinch to 0.02 (a cow's muzzle
#: cap, exact) and 0.07 (a thin muzzle's tip, relaxed) of it; the other zoo cages and the shared
#: meshes stay at 0.16 or more (the shared meshes 0.62)
PINCH_RATIO = 0.1
#: rounds of freeing at most (each frees the vertices under the turned normals, or their ring)
MAX_ROUNDS = 16


def _sines(mesh: QuadMesh) -> FloatArray:
    """Per vertex ``|a × b| / (|a| |b|)`` of the limit tangents (:func:`limit_stars`): 1 where
    the limit is parametrised square, 0 where its two tangents are parallel (pinched)."""
    a, b = limit_stars(mesh)
    lengths = np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
    return np.linalg.norm(np.cross(a, b), axis=1) / np.maximum(lengths, np.finfo(float).tiny)


def _turned(system: _System, unknowns: FloatArray, angle: float) -> NDArray[np.int64]:
    """The unknowns under the points of the solved cage's limit that are turned more than
    ``angle`` degrees from the mesh's own limit (``limit``: the cage of the targets themselves),
    or pinched against it (:data:`PINCH_RATIO`), at the vertices, edge points and face points of
    one more step; under a point: the unknowns of that point's largest weights (for a quad mesh
    the vertex itself, the edge's two ends, the face's corners)."""
    through, fine = system.through, system.fine
    ours_mesh = fine.with_vertices(through @ unknowns)
    theirs_mesh = fine.with_vertices(through @ system.targets)
    ours = limit_normals(ours_mesh)
    theirs = limit_normals(theirs_mesh)
    cosine = np.einsum("ij,ij->i", ours, theirs)
    defined = (np.einsum("ij,ij->i", ours, ours) > 0.25) & (
        np.einsum("ij,ij->i", theirs, theirs) > 0.25
    )
    pinched = _sines(ours_mesh) < PINCH_RATIO * _sines(theirs_mesh)
    rows = np.flatnonzero((defined & (cosine < np.cos(np.radians(angle)))) | pinched)
    if not len(rows):
        return np.zeros(0, np.int64)
    weights = sp.csr_matrix(through[rows]).tocoo()
    peak = np.zeros(len(rows))
    np.maximum.at(peak, weights.row, np.abs(weights.data))
    under = np.abs(weights.data) >= 0.5 * peak[weights.row]
    return np.unique(weights.col[under]).astype(np.int64)


def _fair_correction(
    system: _System, rhs: FloatArray, fixed: NDArray[np.int64]
) -> FloatArray | None:
    """The correction D of least ``Σ_edges |D_i − D_j|² + Σ_v |D_v|²`` (over the unknowns' edges)
    with ``(M D)_v = rhs_v`` at the ``fixed`` vertices only (KKT system, sparse LU); None where
    that system is singular."""
    n = len(system.targets)
    edges = system.edges
    count = len(edges)
    difference = sp.csr_matrix(
        (
            np.r_[np.ones(count), -np.ones(count)],
            (np.r_[np.arange(count), np.arange(count)], np.r_[edges[:, 0], edges[:, 1]]),
        ),
        shape=(count, n),
    )
    energy = difference.T @ difference + sp.identity(n, format="csr")
    rows = system.matrix[fixed]
    kkt = sp.bmat([[energy, rows.T], [rows, None]], format="csc")
    try:
        solution = splu(kkt).solve(np.vstack([np.zeros((n, 3)), rhs[fixed]]))
    except RuntimeError:  # SuperLU: the fixed rows of L are dependent (the cube's checkerboard)
        return None
    return np.asarray(solution[:n])


def _relaxed(system: _System, exact: CageSolution, unknowns: FloatArray) -> CageSolution:
    """``exact`` (its unknowns ``unknowns``), unless its limit is inside out or pinched against
    the mesh's own limit (:data:`FOLD_ANGLE_DEG`, :data:`PINCH_RATIO`, :func:`_turned`). Then the
    interpolation is relaxed there: the vertices under the turned or pinched points are freed,
    the cage is solved again with ``L C = V`` at the others only and the freed degrees of freedom
    faired (:func:`_fair_correction`: the correction ``C − V`` as even and small as the remaining
    constraints allow), and vertices are freed (those under normals turned more than
    :data:`CLEAN_ANGLE_DEG` or pinched points, else their ring) until none is. Fairing can pinch
    what it frees (a thin muzzle's tip pushed out along it): the pinch is tested on every round.
    Every vertex free is the mesh's own limit, fold-free wherever ``limit`` is. The relaxed
    vertices and their distance to the surface are logged at WARNING."""
    x = system.targets
    free = _turned(system, unknowns, FOLD_ANGLE_DEG)
    if not len(free):
        return exact
    matrix = system.matrix
    rhs = x - matrix @ x
    everything = np.arange(len(x))
    edges = system.edges
    for _ in range(MAX_ROUNDS):
        fixed = np.setdiff1d(everything, free)
        correction = _fair_correction(system, rhs, fixed) if len(fixed) else 0.0 * x
        if correction is None:
            _logger.warning("limit-interpolate: the relaxed solve is singular, the exact cage kept")
            return exact
        unknowns = x + correction
        turned = _turned(system, unknowns, CLEAN_ANGLE_DEG)
        if not len(turned):
            break
        new = np.setdiff1d(turned, free)
        if not len(new):  # all already free: their ring too
            new = np.setdiff1d(edges[np.isin(edges, turned).any(axis=1)].ravel(), free)
        if not len(new):
            break
        free = np.union1d(free, new)
    cage = system.cage(unknowns)
    limit = system.limit @ cage
    fixed = np.setdiff1d(everything, free)
    diagonal = system.diagonal
    points = limit.copy()
    points[fixed] = x[fixed]
    distance = float(np.linalg.norm(limit[free] - x[free], axis=1).max() / diagonal)
    residual = float(np.linalg.norm(limit[fixed] - x[fixed], axis=1).max(initial=0.0) / diagonal)
    return CageSolution(
        cage,
        system.mesh.with_vertices(cage),
        residual,
        exact.condition,
        exact.solver,
        points,
        free,
        distance,
    )


def limit_interpolate_targets(mesh: QuadMesh, *, tangents: TangentRule = "arc") -> Targets:
    """Targets through the mesh vertices on the Catmull–Clark limit of the interpolating cage
    (:func:`interpolating_cage`): :func:`~g1patch.targets.limit.limit_targets` of the cage,
    positions set to the vertices exactly. Logs the residual, condition estimate and solver at
    INFO. ``tangents`` is ignored, as by :func:`~g1patch.targets.limit.limit_targets`."""
    solution = interpolating_cage(mesh)
    _logger.info(
        "limit-interpolate: cage solved by %s, relative residual %.1e, condition estimate %.1e",
        solution.solver,
        solution.residual,
        solution.condition,
    )
    targets = limit_targets(solution.mesh)
    return targets.with_changes(positions=solution.points, rule="limit-interpolate")


def limit_interpolate_near(
    mesh: QuadMesh, base: Targets, faces: NDArray[np.int64], rings: int
) -> tuple[Targets, NDArray[np.bool_]]:
    """``base`` with the limit-interpolate targets of ``mesh`` at the vertices near ``faces``, and
    those vertices, (V,) bool. The cage is solved on the faces within ``rings`` vertex rings of
    ``faces`` alone (:func:`~g1patch.mesh.neighbourhood.neighbourhood`, whose rim is a boundary
    there), so its cost follows the part, not the mesh; the targets are taken at the part's
    vertices whose whole ring it holds (positions, normals, ring slots, and the interior targets
    of their face corners). Raises :class:`ConstructionError` where the part's cage cannot be
    solved (:func:`interpolating_cage`)."""
    whole = mesh.topology
    part = cage_neighbourhood(mesh, faces, rings)
    solution = interpolating_cage(part.mesh)
    fair = limit_targets(solution.mesh).with_changes(positions=solution.points)
    kept, whole_slots, part_slots = part.rings_kept(whole)
    vertices = part.vertices[kept]
    covered = np.zeros(whole.n_vertices, dtype=bool)
    covered[vertices] = True
    positions = base.positions.copy()
    positions[vertices] = fair.positions[kept]
    normals = base.normals.copy()
    normals[vertices] = fair.normals[kept]
    tangents = base.tangents.copy()
    tangents[whole_slots] = fair.tangents[part_slots]
    interior = base.interior.copy()
    corners = covered[whole.faces[part.faces]]
    interior[part.faces[np.nonzero(corners)[0]], np.nonzero(corners)[1]] = fair.interior[corners]
    targets = base.with_changes(
        positions=positions, normals=normals, tangents=tangents, interior=interior
    )
    return targets, covered
