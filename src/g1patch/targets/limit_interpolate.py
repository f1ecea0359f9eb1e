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
from ..subdivision import limit_points
from ..subdivision.matrix import limit_matrix
from .limit import limit_targets
from .value import TangentRule, Targets

__all__ = [
    "LSMR_ITERATIONS",
    "LSMR_TOLERANCE",
    "MAX_CONDITION",
    "MAX_RESIDUAL",
    "CageSolution",
    "interpolating_cage",
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

    * ``cage`` (V, 3): the control points C, same topology and tags as the mesh;
    * ``residual``: ``max_v |(L C − V)_v| / diag(V)``, measured with
      :func:`~g1patch.subdivision.limit_points`;
    * ``condition``: the 1-norm condition estimate of L (``inf`` where the LU found it singular);
    * ``solver``: ``lu`` (sparse LU) or ``lsmr`` (least-norm correction, L singular or ill
      conditioned).
    """

    cage: FloatArray
    residual: float
    condition: float
    solver: Solver


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
    vertices V: ``L C = V`` (module docstring), solved as ``C = V + D``, ``L D = V − L V``.

    Raises :class:`ConstructionError` where no such cage exists to :data:`MAX_RESIDUAL` (L singular
    and V outside its range), or where the solved cage has a degenerate face.
    """
    x = mesh.vertices
    matrix = limit_matrix(mesh)
    correction, condition, solver = _solve(matrix, x - limit_points(mesh))
    diagonal = mesh.bounding_box_diagonal
    try:
        cage = mesh.with_vertices(x + correction)
    except MeshError as error:
        raise ConstructionError(
            f"limit-interpolate: the interpolating cage is degenerate ({error})"
        ) from None
    residual = float(np.linalg.norm(limit_points(cage) - x, axis=1).max() / diagonal)
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
    return CageSolution(cage.vertices, residual, condition, solver)


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
    targets = limit_targets(mesh.with_vertices(solution.cage))
    return targets.with_changes(positions=mesh.vertices, rule="limit-interpolate")
