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

Every rule is linear in the positions: :mod:`~g1patch.subdivision.matrix` gives the sparse matrices
of a step (:func:`step_matrix`), of ``levels`` steps (:func:`refine_matrix`), of the limit points
(:func:`limit_matrix`) and of the limit points of the refined grids (:func:`limit_grid_matrix`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..kernels import use_kernels
from ..mesh import QuadMesh
from .features import (
    BOUNDARY_MODES,
    INFINITE_SHARPNESS,
    RULE_CORNER,
    RULE_CREASE,
    RULE_SMOOTH,
    BoundaryMode,
    _Level,
    _level_of,
    boundary_mode,
    corner_vertices,
    sharp_edges,
    vertex_rules,
)
from .matrix import limit_grid_matrix, limit_matrix, refine_matrix, step_matrix
from .refine import catmull_clark_cage, catmull_clark_points, refine, refine_grids
from .semisharp import _decayed_neighbourhood
from .stencils import _Frames, _limit_frames, _limit_positions, _unit

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
    "catmull_clark_cage",
    "catmull_clark_points",
    "corner_vertices",
    "limit_corner_normals",
    "limit_data",
    "limit_grid_matrix",
    "limit_matrix",
    "limit_normals",
    "limit_points",
    "limit_stars",
    "limit_tangents",
    "refine",
    "refine_grids",
    "refine_matrix",
    "sharp_edges",
    "step_matrix",
    "vertex_rules",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: from this many vertices on, the smooth vertices' limit stencils run as numba kernels (bit for
#: bit the NumPy reference's values); below it the compile, once per install, would cost more
KERNEL_VERTICES = 20_000


def _compiled(level: _Level) -> bool:
    """Whether the limit stencils of ``level`` run as numba kernels: from :data:`KERNEL_VERTICES`
    vertices on (read at each call, so that it can be changed), where they can be cached
    (:func:`~g1patch.kernels.use_kernels`)."""
    return use_kernels(level.topology.n_vertices >= KERNEL_VERTICES)


def _points(mesh: QuadMesh, sharpness: ArrayLike | None) -> FloatArray:
    """Limit positions of the mesh's own vertices (module docstring): the masks where no semi-sharp
    feature reaches, the masks on the decayed refinement of a neighbourhood elsewhere."""
    level = _level_of(mesh, sharpness)
    points = _limit_positions(level, compiled=_compiled(level))
    if not level.semi_sharp:
        return points
    fine, index, _, near = _decayed_neighbourhood(level)
    points[near] = _limit_positions(fine, compiled=_compiled(fine))[index[near]]
    return points


def _frames(mesh: QuadMesh, sharpness: ArrayLike | None, corners: bool = False) -> _Frames:
    """Limit tangents, stars and (``corners``) sector normals of the mesh's own vertices, as
    :func:`_points` takes the positions; the refined tangents scaled to the original faces."""
    level = _level_of(mesh, sharpness)
    coarse = _limit_frames(level, compiled=_compiled(level), corners=corners)
    if not level.semi_sharp:
        return coarse
    fine, index, steps, near = _decayed_neighbourhood(level)
    refined = _limit_frames(fine, compiled=_compiled(fine), corners=corners)
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
    ring_normals, refined_normals = coarse.ring_normals, refined.ring_normals
    if ring_normals is None or refined_normals is None:  # not asked for (``corners`` false)
        return _Frames(tangents, a, b)
    faces = level.topology.face_count[near]
    within = np.arange(faces.sum()) - np.repeat(np.cumsum(faces) - faces, faces)
    ring_normals[np.repeat(level.topology.ring_offsets[near], faces) + within] = refined_normals[
        np.repeat(fine.topology.ring_offsets[rows], faces) + within
    ]
    return _Frames(tangents, a, b, ring_normals)


def limit_points(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """The Catmull–Clark limit position of every vertex, (V, 3) (module docstring)."""
    return _points(mesh, sharpness)


def limit_stars(
    mesh: QuadMesh, sharpness: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Per vertex the two scaled limit tangents ``(a, b)``, (V, 3) each, ``a × b`` along the outward
    normal (OpenSubdiv's tangent pair): inside A and B of the module docstring; at a crease vertex
    (boundary or interior) a along the crease towards the first sharp slot ``E_p`` of the ring,
    ``(E_p − E_q)/2``, and b across the sector that follows it counter-clockwise, into its faces;
    at a corner ``a = E_p − V``, ``b = E_{p+1} − V`` (p the first sharp slot, 0 if none)."""
    data = _frames(mesh, sharpness)
    return data.a, data.b


def limit_tangents(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """Per ring slot the limit tangent along its edge, (S, 3) (module docstring): ``cos φ_j a + sin
    φ_j b`` over the star of the slot's sector (``φ_j = 2πj/n`` at a smooth vertex, ``πj/k`` in a
    crease sector with k faces), the crease tangent ``±(E_p − E_q)/2`` on the two sharp slots of a
    crease, ``E_j − V`` at a corner. Along a sharp edge it is the tangent of the crease curve, the
    same for the sectors on both sides."""
    return _frames(mesh, sharpness).tangents


def limit_normals(mesh: QuadMesh, sharpness: ArrayLike | None = None) -> FloatArray:
    """``a × b`` of :func:`limit_stars`, unit; zero where the two tangents are parallel. At a crease
    vertex this is the normal of the sector after the first sharp slot (:func:`limit_corner_normals`
    gives every sector's)."""
    data = _frames(mesh, sharpness)
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
    frames = _frames(mesh, sharpness)
    points = _points(mesh, sharpness)
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
    * corner vertex: the plane of the sector's two sharp chords ``(E_0 − V) × (E_k − V)`` (the
      sharp curves' limit tangents, which both sectors of a crease share), on the side of the fan
      sum ``Σ t_i × t_{i+1}`` of its slot chords ``t_i = E_i − V``; where the two chords are
      nearly parallel, that fan sum made perpendicular to their line (:func:`~g1patch.subdivision.
      stencils._corner_plane`);

    zero where that vanishes. Hole faces get theirs too. Where the mesh is semi-sharp, the normals
    at the affected vertices come from the decayed refinement (module docstring), whose sectors
    are those of the infinitely sharp features. The two limit tangents of a corner, along its
    face's edges, are :func:`limit_tangents` at the slots of the half-edges ``4f + c`` (out along
    edge c) and of the reverse of ``4f + (c + 3) % 4`` (towards corner c − 1); at smooth and crease
    vertices they lie in this plane."""
    topology = mesh.topology
    ring_normals = _frames(mesh, sharpness, corners=True).ring_normals
    assert ring_normals is not None  # asked for
    position = np.empty(topology.n_halfedges, dtype=np.int64)
    position[topology.ring_halfedges] = np.arange(topology.n_halfedges)
    return ring_normals[position].reshape(topology.n_faces, 4, 3)
