"""Catmull–Clark limit targets: the mesh taken as a subdivision cage, not as points to interpolate.

:func:`limit_targets` returns :class:`~g1patch.targets.Targets` on the mesh's own positions
(:mod:`g1patch.subdivision` for the stencils):

* positions: the limit points; normals: ``a × b`` of the limit stars (unit);
* tangents: the limit tangent of every slot, :func:`~g1patch.subdivision.limit_tangents`. Where
  that is the uniform bicubic B-spline's Hermite tangent exactly (valence 4 inside, two faces on a
  boundary, the boundary slots, corners) it is kept. At the other vertices the limit surface has
  no finite cubic tangent (its parameterisation is singular there), so the slot tangent
  ``t = α e1 + β e2`` in the vertex's exact tangent plane is fitted to the exact limit curve
  ``c(i/m)`` of the edge, ``m = 2^L`` (limit points and normals ``n_i`` of the cage refined L
  times, :func:`~g1patch.subdivision.refine_grids`): ``min Σ_i rᵀ (n_i n_iᵀ + ρ I) r``,
  ``r = H(i/m) − c(i/m)``, a 4 × 4 solve per edge. The normal part is the geometric error; the
  small parametric share ρ (:data:`_PARAMETRIC_EDGE`) fixes the tangential freedom. Matching the
  singular parameterisation point for point (ρ = ∞) left 5–8e-3 of the diagonal on the cube;
  ρ = 0.05 left 0.8e-3, ρ = 0.01 leaves 3.9e-4 (the surface, after the assembly);
* interior points: on a face whose four corners are regular the uniform B-spline's Bézier points,
  ``b11 = (4A + 2B + 2D + C)/9`` at corner A of face (A, B, C, D) of the cage (the tensor product
  of the curve rule ``(2P_0 + P_1)/3``), exactly; elsewhere the four interior points of the
  bicubic with those boundary curves that fit the exact limit samples inside the face in the
  same weighted sense, with a larger share ρ (:data:`_PARAMETRIC_INTERIOR`) (a 12 × 12 solve per
  face). Next to a vertex of valence n > 8 the normal in that weight is the exact one only by a
  share ``(8/n)²``, the rest the blend of the face's corner normals: the exact normal ripples
  sideways with the n sectors, and weighted by it the points slid sideways by more than a narrow
  sector (:func:`_exact_normal_share`). The Gregory assembly then moves them as far as G1 requires.

At a corner with two seams each sector's plane is the one its two sharp chords span (the
subdivision layer's sector normals), unless that plane stands more than 25° off a sector's faces
or the chords are nearly parallel (a crease through a tagged corner, a ridge's apex): there the
corner is taken as a crease, as the interpolating rule does
(:func:`~g1patch.targets.creases.ridge_corners`), since a plane on edge holds no valid fan. At a
corner with three or more seams a sector whose chords span no such plane (the straight bar of a
T) takes its faces' fan normal and its seams are moved into that plane, the other sectors
spanning theirs (:func:`~g1patch.targets.creases.loose_corners`).

Every manifold quad mesh gets valid targets: a fitted fan that does not turn counter-clockwise
falls back to the limit star, and where the two limit tangents of a vertex are parallel (a
degenerate cage) the fan normal and the safeguard of
:func:`~g1patch.targets.interpolate.safeguarded_fans` take over, counted in ``Targets.fallback``.
A boundary vertex with one face keeps its exact boundary tangents (in ``edge-only`` mode they
are opposite: the boundary curve is smooth there, as on the limit surface); it has no interior
edge, so the assembly has nothing to split there.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .. import subdivision
from ..gregory import INTERIOR_INDEX
from ..kernels import jit_kernel, use_kernels
from ..mesh import QuadMesh, QuadTopology, Sectors, sectors
from ..mesh.neighbourhood import neighbourhood
from ..subdivision import (
    boundary_mode,
    corner_vertices,
    limit_corner_normals,
    limit_data,
    limit_normals,
    limit_points,
    refine_grids,
)
from .creases import loose_corners, ridge_corners, seam_edges, sector_fan_normals, spread_sectors
from .fans import safeguarded_fans
from .local import cross, dot, fan_normals, slot_tables, slot_vertices
from .value import TangentRule, Targets, halfedge_slots, slot_sector_normals

__all__ = ["FIT_LEVELS", "bspline_slots", "limit_targets", "regular_faces"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
#: ``(slot_out, slot_in)`` of :func:`~g1patch.targets.value.halfedge_slots` (int64) or of
#: :func:`~g1patch.targets.local.slot_tables` (int32)
SlotTables = tuple[NDArray[np.integer], NDArray[np.integer]]

#: refinement levels of the exact limit samples the free tangents and interior points are fitted to
FIT_LEVELS = 3
#: vertex rings of faces around those whose limit samples are needed, refined with them
_SAMPLE_MARGIN = 3
#: weight of the parametric residual against the normal one in the fits of the edge tangents
#: and of the interior points: the limit surface's parameterisation is singular at
#: extraordinary vertices (speed ~ (2λ)^m), so matching it point for point would bend the
#: cubics; the normal distance is the geometric error, and this small share fixes the
#: tangential freedom it leaves. An edge cubic has 4 free numbers and follows the limit curve
#: better with a small share (the cube's edge curves: 4.7e-4 of the diagonal at 0.01, 8.0e-4
#: at 0.05; at 0.001, 4.5e-4, but the wild cages of ``limit-interpolate`` then fold); the
#: interior points need more (at 0.001 they drift along the surface, and the assembly, which
#: keeps them only as far as G1 allows, then bent the cube's patches to 1.2e-3)
_PARAMETRIC_EDGE = 0.01
_PARAMETRIC_INTERIOR = 0.05
#: a vertex whose limit tangents span less than this (|a × b| / (|a|² + |b|²)) has no usable plane
_DEGENERATE = 1e-9
#: edge k of a face as grid positions (i, j) at parameter t = s/m, from corner k to corner k + 1
_EDGE_GRID = (
    lambda s, m: (s, 0 * s),
    lambda s, m: (m + 0 * s, s),
    lambda s, m: (m - s, m + 0 * s),
    lambda s, m: (0 * s, m - s),
)


def _bernstein(t: FloatArray) -> FloatArray:
    s = 1.0 - t
    return np.stack([s**3, 3 * t * s * s, 3 * t * t * s, t**3], axis=-1)


def bspline_slots(mesh: QuadMesh) -> BoolArray:
    """Slots whose limit tangent is exactly the B-spline Hermite tangent: all slots of a regular
    vertex (4 faces inside, 2 on a boundary), the two boundary slots of every boundary vertex, and
    the slots of an ``edge-and-corner`` corner."""
    topology = mesh.topology
    offsets = topology.neighbor_offsets
    boundary = topology.is_boundary_vertex
    regular = np.where(boundary, topology.face_count == 2, topology.face_count == 4)
    regular |= corner_vertices(topology, boundary_mode(mesh))
    exact = regular[slot_vertices(topology)]
    rims = np.flatnonzero(boundary)
    exact[offsets[rims]] = exact[offsets[rims + 1] - 1] = True
    return exact


def regular_faces(topology: QuadTopology) -> BoolArray:
    """Faces whose four corners are interior vertices of valence 4: their limit is the uniform
    bicubic B-spline."""
    regular = ~topology.is_boundary_vertex & (topology.face_count == 4)
    return regular[topology.faces].all(axis=1)


def _weigh(r: FloatArray, n: FloatArray) -> FloatArray:
    """``W r`` with ``W = n nᵀ + ρ I``: the residual's normal part, plus :data:`_PARAMETRIC_EDGE` of
    all of it."""
    return dot(r, n)[..., None] * n + _PARAMETRIC_EDGE * r


def _plane_bases(normals: FloatArray, a: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Orthonormal ``(e1, e2)`` of each tangent plane, e1 along ``a`` projected (any direction in
    the plane where that vanishes)."""
    e1 = a - dot(a, normals)[:, None] * normals
    length = np.linalg.norm(e1, axis=1, keepdims=True)
    other = np.cross(
        normals, np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    )
    e1 = np.where(
        length > 1e-12,
        e1 / np.where(length > 0, length, 1.0),
        other / np.linalg.norm(other, axis=1, keepdims=True),
    )
    return e1, np.cross(normals, e1)


def _fitted_edges(topology: QuadTopology, free: BoolArray, slots: SlotTables) -> IntArray:
    """Canonical half-edges of the interior edges with a free end (their tangents are fitted);
    ``slots``: :func:`~g1patch.targets.halfedge_slots`."""
    slot_out, slot_in = slots
    h = topology.edge_halfedges[:, 0]
    return h[~topology.is_boundary_edge & (free[slot_out[h]] | free[slot_in[h]])]


def _limit_samples(mesh: QuadMesh, faces: IntArray, levels: int) -> tuple[FloatArray, FloatArray]:
    """Exact limit points and normals on the ``(m + 1)²`` grids of ``faces`` (``m = 2^levels``),
    refining only their neighbourhood: the faces within :data:`_SAMPLE_MARGIN` vertex rings of them,
    as a mesh of its own (:func:`~g1patch.mesh.neighbourhood.neighbourhood`). A face's refined
    points read its 1-ring only, and the cut of the neighbourhood is a boundary whose rules reach
    less than two rings inwards, so the samples equal the whole mesh's."""
    part = neighbourhood(mesh, faces, _SAMPLE_MARGIN)
    fine, grid = refine_grids(part.mesh, levels)
    rows = np.searchsorted(part.faces, faces)
    return limit_points(fine)[grid[rows]], limit_normals(fine)[grid[rows]]


def _fit_tangents(
    mesh: QuadMesh,
    x: FloatArray,
    t: FloatArray,
    free: BoolArray,
    planes: FloatArray,
    plane_of: IntArray | None,
    samples: FloatArray,
    sample_normals: FloatArray,
    row: IntArray,
    m: int,
    slots: SlotTables,
    h: IntArray,
) -> FloatArray:
    """The free slot tangents fitted in their tangent planes: per interior edge A → B with a free
    end the least-squares fit of ``H(s) = B0 A + B1 (A + t_A/3) + B2 (B + t_B/3) + B3 B`` to the
    limit curve samples, ``t = α e1 + β e2`` at a free end (a 4 × 4 solve per edge; ``(e1, e2)`` per
    slot, :func:`_plane_bases` of the normal of the slot's sector, ``planes[plane_of[s]]``, or
    ``planes[s]`` without ``plane_of``), the other end fixed; ``samples[row[f]]`` holds face f's
    grid of limit samples; ``slots``: :func:`~g1patch.targets.halfedge_slots`, ``h``:
    :func:`_fitted_edges`."""
    topology = mesh.topology
    slot_out, slot_in = slots
    out = t.copy()
    if not h.size:
        return out
    sa, sb = slot_out[h], slot_in[h]
    plane_a, plane_b = (
        (planes[sa], planes[sb])
        if plane_of is None
        else (planes[plane_of[sa]], planes[plane_of[sb]])
    )
    face, k = row[h >> 2], h & 3
    s = np.arange(m + 1)
    positions = np.stack([np.stack(edge(s, m), axis=0) for edge in _EDGE_GRID])  # (4, 2, m + 1)
    curve = samples[face[:, None], positions[k, 0], positions[k, 1]]  # (E, m + 1, 3)
    normal = sample_normals[face[:, None], positions[k, 0], positions[k, 1]]
    w = _bernstein(s / m)
    va, vb = topology.origin(h), topology.target(h)
    base = (
        (w[:, 0] + w[:, 1])[None, :, None] * x[va][:, None]
        + (w[:, 2] + w[:, 3])[None, :, None] * x[vb][:, None]
        - curve
    )
    (e1a, e2a), (e1b, e2b) = _plane_bases(plane_a, t[sa]), _plane_bases(plane_b, t[sb])
    columns = np.stack(
        [  # ∂H/∂(α_A, β_A, α_B, β_B): (E, 4, m + 1, 3)
            w[None, :, 1, None] * e1a[:, None] / 3.0,
            w[None, :, 1, None] * e2a[:, None] / 3.0,
            w[None, :, 2, None] * e1b[:, None] / 3.0,
            w[None, :, 2, None] * e2b[:, None] / 3.0,
        ],
        axis=1,
    )
    known = np.stack([dot(t[sa], e1a), dot(t[sa], e2a), dot(t[sb], e1b), dot(t[sb], e2b)], axis=1)
    unknown = np.repeat(np.stack([free[sa], free[sb]], axis=1), 2, axis=1)  # (E, 4)
    fixed_part = np.einsum("ec,ecsd->esd", np.where(unknown, 0.0, known), columns)
    weighted = _weigh(columns, normal[:, None])
    gram = np.einsum("eisd,ejsd->eij", weighted, columns)
    rhs = -np.einsum("eisd,esd->ei", weighted, base + fixed_part)
    both = unknown[:, :, None] & unknown[:, None, :]
    eye = np.eye(4, dtype=bool)[None]
    gram = np.where(both, gram, np.where(eye, 1.0, 0.0))
    rhs = np.where(unknown, rhs, known)
    p = np.linalg.solve(gram, rhs[..., None])[..., 0]
    fitted_a = p[:, 0, None] * e1a + p[:, 1, None] * e2a
    fitted_b = p[:, 2, None] * e1b + p[:, 3, None] * e2b
    out[sa[free[sa]]] = fitted_a[free[sa]]
    out[sb[free[sb]]] = fitted_b[free[sb]]
    return out


def _boundary_nets(
    mesh: QuadMesh, x: FloatArray, t: FloatArray, faces: IntArray, slots: SlotTables
) -> FloatArray:
    """The 4 × 4 Bézier nets ``b[f, i, j]`` of ``faces`` with corners and edge points set, interior
    zero; ``slots``: :func:`~g1patch.targets.halfedge_slots`."""
    topology = mesh.topology
    slot_out, slot_in = slots
    h = 4 * faces[:, None] + np.arange(4)
    corner = x[topology.faces[faces]]  # (F, 4, 3)
    near = corner + t[slot_out[h]] / 3.0  # edge k's point next to corner k
    far = corner[:, [1, 2, 3, 0]] + t[slot_in[h]] / 3.0  # edge k's point next to corner k + 1
    net = np.zeros((len(faces), 4, 4, 3))
    net[:, [0, 3, 3, 0], [0, 0, 3, 3]] = corner
    net[:, [1, 3, 2, 0], [0, 1, 3, 2]] = near
    net[:, [2, 3, 1, 0], [0, 2, 3, 1]] = far
    return net


#: up to this valence the interior fit weighs by the exact limit normal alone (its sideways tilt
#: inside a face is a few hundredths there: every common cage is fitted as before)
_SMOOTH_VALENCE = 8.0


def _exact_normal_share(valence: IntArray) -> FloatArray:
    """The share ``min(1, (8/n)²)`` of the exact limit normal in :func:`_fit_interior`'s weight of
    a face whose corners have at most valence ``n`` (the rest: the blend of its corner normals).

    Next to a vertex of valence n the Catmull–Clark limit ripples with its n sectors (ridges along
    the edges): inside a face the exact normal tilts sideways by an angle that grows like n (0.07
    at valence 16, 0.25 at 64, 0.45 at 128, 0.82 at 360 on a pole), while the sector narrows like
    2π/n. Weighted by that normal the fit slid the interior points sideways along the ripple by
    an angle that did not shrink with the sector: at valence 360 the points next to the valence-4
    corners of a pole face lay outside its 1° sector (at 1.67 and −0.67 of it; 0.22 and 0.78 with
    a smooth normal, as at valence 16) and every assembly following them folded. With this share
    the tilt the exact normal brings falls like 1/n, as the sector does, so the fit keeps its
    shape in sector units at every valence; faces up to valence 8 (:data:`_SMOOTH_VALENCE`) are
    fitted as before."""
    return np.minimum(1.0, (_SMOOTH_VALENCE / np.maximum(valence, 1)) ** 2)


def _fit_interior(
    net: FloatArray,
    samples: FloatArray,
    sample_normals: FloatArray,
    corner_normals: FloatArray,
    share: FloatArray,
    m: int,
) -> FloatArray:
    """Interior points (F, 4, 3) at corners 0..3 (b11, b21, b22, b12) minimising
    ``Σ rᵀ (n nᵀ + ρ I) r``, ``r = p(i/m, j/m) − S_ij``, over the interior samples with the boundary
    of ``net`` fixed: a 12 × 12 solve per face.

    ``n`` at a sample is the exact limit normal (``sample_normals``) by ``share`` (F,) and the
    bilinear blend of the face's unit ``corner_normals`` (F, 4, 3) by the rest, normalised
    (:func:`_exact_normal_share`: the exact normal ripples sideways at high valence, the blend
    does not; where the corners are more than 120° apart and blend to less than ½, the exact
    normal alone)."""
    g = np.arange(1, m) / m
    w = _bernstein(g)
    basis = (w[:, None, :, None] * w[None, :, None, :]).reshape(
        -1, 4, 4
    )  # (K, 4, 4): B_i(u) B_j(v)
    inner = basis[:, INTERIOR_INDEX[:, 0], INTERIOR_INDEX[:, 1]]  # (K, 4)
    count = len(net)
    known = np.einsum("kij,fijd->fkd", basis, net)
    residual = known - samples[:, 1:m, 1:m].reshape(count, -1, 3)
    exact = sample_normals[:, 1:m, 1:m].reshape(count, -1, 3)
    # corner k of the face sits at grid (0, 0), (m, 0), (m, m), (0, m) (:data:`_EDGE_GRID`)
    u, v = np.meshgrid(g, g, indexing="ij")
    bilinear = np.stack([(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v], axis=-1)
    blend = np.einsum("kc,fcd->fkd", bilinear.reshape(-1, 4), corner_normals)
    length = np.linalg.norm(blend, axis=-1, keepdims=True)
    blend = np.where(length > 0.5, blend / np.where(length > 0.5, length, 1.0), exact)
    n = blend + share[:, None, None] * (exact - blend)
    size = np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where(size > 0.5, n / np.maximum(size, 0.5), exact)  # opposed normals: the exact one
    weight = n[..., :, None] * n[..., None, :] + _PARAMETRIC_INTERIOR * np.eye(3)  # (F, K, 3, 3)
    gram = np.einsum("kc,kg,fkde->fcdge", inner, inner, weight).reshape(count, 12, 12)
    rhs = -np.einsum("kc,fkde,fke->fcd", inner, weight, residual).reshape(count, 12)
    return np.linalg.solve(gram, rhs[..., None]).reshape(count, 4, 3)


def _limit_normals(mesh: QuadMesh, a: FloatArray, b: FloatArray) -> tuple[FloatArray, BoolArray]:
    """Unit ``a × b`` of the limit stars ``(a, b)``; the fan normal where the plane is degenerate
    (:data:`_DEGENERATE`), flagged."""
    a_cross_b = cross(a, b)
    length = np.linalg.norm(a_cross_b, axis=1)
    degenerate = ~(length > _DEGENERATE * (dot(a, a) + dot(b, b)))
    normals = a_cross_b / np.where(degenerate, 1.0, length)[:, None]
    if degenerate.any():
        normals[degenerate] = fan_normals(mesh)[degenerate]
    return normals, degenerate


def _guarded(
    mesh: QuadMesh, normals: FloatArray, fitted: FloatArray, star: FloatArray, keep: BoolArray
) -> tuple[FloatArray, BoolArray]:
    """Per vertex the fitted fan where it is valid, else the star where that is, else the
    safeguarded star (:func:`~g1patch.targets.interpolate.safeguarded_fans`, flagged). A boundary
    vertex with one face and the vertices in ``keep`` (creased: their sectors are checked on their
    own) keep their fitted tangents."""
    topology = mesh.topology
    slot_vertex = slot_vertices(topology)
    if _kernels_wanted(topology):
        chord = np.empty(slot_vertex.size)
        jit_kernel(_chord_kernel)(
            mesh.vertices, topology.neighbors, topology.neighbor_offsets, chord
        )
    else:
        chord = np.linalg.norm(
            mesh.vertices[topology.neighbors] - mesh.vertices[slot_vertex], axis=1
        )
    _, fitted_bad = safeguarded_fans(topology, normals, fitted, chord)
    fitted_bad &= ~(topology.is_boundary_vertex & (topology.face_count == 1)) & ~keep
    if not fitted_bad.any():
        return fitted, fitted_bad
    guarded_star, star_bad = safeguarded_fans(topology, normals, star, chord)
    out = np.where(
        fitted_bad[slot_vertex, None],
        np.where(star_bad[slot_vertex, None], guarded_star, star),
        fitted,
    )
    return out, fitted_bad & star_bad


def _touched(mesh: QuadMesh) -> BoolArray:
    """Vertices with a sharpness of their own or on an edge of theirs: near them the limit is not
    the uniform B-spline, whatever the valences."""
    topology = mesh.topology
    features = mesh.features
    touched = features.vertex_sharpness > 0
    touched[topology.edges[features.edge_sharpness > 0].ravel()] = True
    return touched


def _sector_slots(mesh: QuadMesh, seams: BoolArray) -> tuple[Sectors, BoolArray, BoolArray]:
    """The sectors of the creased vertices, which slots bound one (their tangent is the crease
    curve's, exact), and which inner slots are exact B-spline ones (a crease sector of two
    faces)."""
    topology = mesh.topology
    found = sectors(topology, seams)
    slot_vertex = slot_vertices(topology)
    bound = np.zeros(int(topology.neighbor_offsets[-1]), dtype=bool)
    cut = found.creased[found.vertex]
    bound[found.start[cut]] = True
    bound[found.end[cut]] = True
    corner = corner_vertices(mesh) | (found.cuts > 2)
    size = np.bincount(found.label, minlength=found.vertex.size)
    ring_vertex = np.repeat(np.arange(topology.n_vertices), topology.face_count)
    slot = (
        topology.neighbor_offsets[ring_vertex]
        + np.arange(ring_vertex.size)
        - topology.ring_offsets[ring_vertex]
    )
    two_face = np.zeros_like(bound)
    two_face[slot] = (size[found.label] == 2) & ~corner[ring_vertex]
    inner_exact = found.creased[slot_vertex] & ~bound & two_face
    return found, bound & found.creased[slot_vertex], inner_exact


def limit_targets(
    mesh: QuadMesh, levels: int = FIT_LEVELS, *, tangents: TangentRule = "arc"
) -> Targets:
    """The Catmull–Clark limit targets of ``mesh`` (module docstring); ``levels`` of refinement for
    the fits. ``tangents`` is ignored (the signature of a
    :class:`~g1patch.targets.value.ShapeFunction`): the limit surface has its own tangents."""
    topology = mesh.topology
    slot_vertex = slot_vertices(topology)
    limit = limit_data(mesh)
    x = limit.points
    normals, degenerate = _limit_normals(mesh, limit.a, limit.b)
    seams = seam_edges(mesh)
    star = limit.tangents
    touched = _touched(mesh)
    if seams.any():
        found, bound, inner_exact = _sector_slots(mesh, seams)
        creased = found.creased
    else:  # one sector at every vertex (a boundary cuts its ring once)
        creased = np.zeros(topology.n_vertices, dtype=bool)
    corner_normals = normals[topology.faces]
    if creased.any():
        corner_normals = np.where(
            creased[topology.faces][..., None], limit_corner_normals(mesh), corner_normals
        )
        fan = sector_fan_normals(mesh, found)
        corners = corner_vertices(mesh) | (found.cuts > 2)
        star, ridge_normals, ridge = ridge_corners(topology, found, star, fan, corners)
        star, loose_normals, loose = loose_corners(topology, found, star, fan, corners)
        ridge_normals += loose_normals
        ridge |= loose
        if ridge.any():
            at = np.flatnonzero(
                ridge[np.repeat(np.arange(topology.n_vertices), topology.face_count)]
            )
            corner_normals.reshape(-1, 3)[topology.ring_halfedges[at]] = ridge_normals[
                found.label[at]
            ]
        plane = Targets(
            topology,
            x,
            normals,
            np.zeros((slot_vertex.size, 3)),
            np.zeros((topology.n_faces, 4, 2, 3)),
            seams,
            corner_normals=corner_normals,
        )
        n, plane_of = (
            slot_sector_normals(plane)[1],
            None,
        )  # each slot's sector plane (the right-hand face's)
        projected = star - dot(star, n)[:, None] * n
        star = np.where(
            bound[:, None], star, projected
        )  # crease tangents lie in both sectors' planes already
        exact = np.where(
            creased[slot_vertex], bound | inner_exact, bspline_slots(mesh) & ~touched[slot_vertex]
        )
    else:  # every slot's sector plane is its vertex's
        n, plane_of = normals, slot_vertex
        if _kernels_wanted(topology):
            star = np.empty_like(star)
            jit_kernel(_plane_kernel)(limit.tangents, normals, topology.neighbor_offsets, star)
        else:
            slot_normals = normals[slot_vertex]
            star = star - dot(star, slot_normals)[:, None] * slot_normals
        exact = bspline_slots(mesh) & ~touched[slot_vertex]
    free = ~exact & ~degenerate[slot_vertex]
    regular = regular_faces(topology) & ~touched[topology.faces].any(axis=1)
    fitted = star
    irregular = np.flatnonzero(~regular)
    slots = slot_tables(topology) if _kernels_wanted(topology) else halfedge_slots(topology)
    if free.any() or irregular.size:
        fitted_edges = _fitted_edges(topology, free, slots)
        needed = np.unique(np.concatenate([fitted_edges >> 2, irregular]))
        row = np.full(topology.n_faces, -1, dtype=np.int64)
        row[needed] = np.arange(needed.size)
        samples, sample_normals = _limit_samples(mesh, needed, levels)
        m = 2**levels
        fitted = _fit_tangents(
            mesh, x, star, free, n, plane_of, samples, sample_normals, row, m, slots, fitted_edges
        )
    t, guarded = _guarded(mesh, normals, fitted, star, creased)
    spread = np.zeros(topology.n_vertices, dtype=bool)
    if creased.any():
        n_sector = np.zeros((found.vertex.size, 3))
        n_sector[found.label] = corner_normals.reshape(-1, 3)[topology.ring_halfedges]
        chord = mesh.vertices[topology.neighbors] - mesh.vertices[slot_vertex]
        spread = spread_sectors(topology, found, t, n_sector, creased, chord)

    interior = _bspline_interior(mesh)
    if irregular.size:
        net = _boundary_nets(mesh, x, t, irregular, slots)
        interior[irregular] = _fit_interior(
            net,
            samples[row[irregular]],
            sample_normals[row[irregular]],
            corner_normals[irregular],
            _exact_normal_share(topology.valence[topology.faces[irregular]].max(axis=1)),
            m,
        )[:, :, None]
    return Targets(
        topology,
        x,
        normals,
        t,
        interior,
        seams,
        guarded | degenerate | spread,
        "limit",
        corner_normals,
    )


def _bspline_interior(mesh: QuadMesh) -> FloatArray:
    """The uniform B-spline's interior Bézier points of every face as both edges' targets, (F, 4, 2,
    3): ``b11 = (4A + 2B + 2D + C)/9`` at corner A of face (A, B, C, D); by :func:`_interior_kernel`
    on large meshes."""
    topology = mesh.topology
    out = np.empty((topology.n_faces, 4, 2, 3))
    if _kernels_wanted(topology):
        jit_kernel(_interior_kernel)(mesh.vertices, topology.faces, out)
        return out
    corner = [mesh.vertices[topology.faces[:, c]] for c in range(4)]
    for c in range(4):
        out[:, c, 0] = (
            4.0 * corner[c]
            + 2.0 * corner[(c + 1) % 4]
            + 2.0 * corner[(c + 3) % 4]
            + corner[(c + 2) % 4]
        ) / 9.0
    out[:, :, 1] = out[:, :, 0]
    return out


def _kernels_wanted(topology: QuadTopology) -> bool:
    """Whether the passes over every slot and face run as numba kernels: as the limit stencils',
    from :data:`~g1patch.subdivision.KERNEL_VERTICES` vertices on (their compile, once per install,
    costs more below)."""
    return use_kernels(topology.n_vertices >= subdivision.KERNEL_VERTICES)


def _interior_kernel(x: FloatArray, faces: IntArray, out: FloatArray) -> None:
    """:func:`_bspline_interior` face by face, the same operations in the same order."""
    for f in range(faces.shape[0]):
        for c in range(4):
            p, q, r, s = (
                faces[f, c],
                faces[f, (c + 1) % 4],
                faces[f, (c + 2) % 4],
                faces[f, (c + 3) % 4],
            )
            for d in range(3):
                value = (4.0 * x[p, d] + 2.0 * x[q, d] + 2.0 * x[s, d] + x[r, d]) / 9.0
                out[f, c, 0, d] = value
                out[f, c, 1, d] = value


def _chord_kernel(x: FloatArray, neighbors: IntArray, offsets: IntArray, out: FloatArray) -> None:
    """``|E_j − V|`` per slot as ``np.linalg.norm`` adds it, ``√((d₀² + d₁²) + d₂²)``."""
    for v in range(offsets.size - 1):
        for j in range(offsets[v], offsets[v + 1]):
            e = neighbors[j]
            d0, d1, d2 = x[e, 0] - x[v, 0], x[e, 1] - x[v, 1], x[e, 2] - x[v, 2]
            out[j] = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


def _plane_kernel(t: FloatArray, normals: FloatArray, offsets: IntArray, out: FloatArray) -> None:
    """``t − (N·t) N`` per slot with N its vertex's normal, the dot product in the order ``_dot``
    (``np.einsum``) adds a 3-vector's terms, ``(t₀N₀ + t₂N₂) + t₁N₁``."""
    for v in range(offsets.size - 1):
        n0, n1, n2 = normals[v, 0], normals[v, 1], normals[v, 2]
        for j in range(offsets[v], offsets[v + 1]):
            t0, t1, t2 = t[j, 0], t[j, 1], t[j, 2]
            height = (t0 * n0 + t2 * n2) + t1 * n1
            out[j, 0] = t0 - height * n0
            out[j, 1] = t1 - height * n1
            out[j, 2] = t2 - height * n2
