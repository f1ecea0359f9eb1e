"""Exact G1 everywhere: the interpolating Gregory network (g1-constructions.md §2, §4.4).

One Gregory patch per quad (:mod:`g1patch.gregory`), interpolating the mesh vertices. For an
interior edge A → B with boundary cubic ``(A, e_AB, e_BA, B)``, shared by face L (holding A → B)
and face R (holding B → A), and cross-boundary derivatives D_L, D_R pointing into each patch,

    D_L(t) + D_R(t) = Φ(t) c'(t),     Φ(t) = 2 c_A (1 − t) − 2 c_B t                    (G1)

makes the normals of both sides equal: with ``n_L = c' × D_L`` and ``n_R = D_R × c'``,
``n_R = (Φ c' − D_L) × c' = n_L``. In Bézier coefficients (G1) is four equations along the edge:

* ends (rows 0 and 3): ``t_{j−1} + t_{j+1} = 2 c_A t_j`` for the edge points ``e_j = A + t_j/3``
  around A. The regular star ``t_j = cos θ_j a + sin θ_j b`` satisfies it with
  ``c_A = cos(θ_{j+1} − θ_j)``: θ_j = 2πj/n at an interior vertex of valence n, θ_j = πj/k over
  the k + 1 edges of a boundary vertex with k ≥ 2 faces (its two boundary edges take part in the
  fit only). A boundary corner (k = 1) has no interior edge and keeps ``t_j = s_j``. The vectors
  a, b fit the corner tangents s_j (:func:`~g1patch.construct.corner.corner_tangents`, chord or
  arc length, in the plane ⊥ the fan normal) by least squares,
  ``[a b] = (Σ_j s_j [cos θ_j, sin θ_j]) G⁻¹`` with the Gram matrix
  ``G = Σ_j [cos θ_j, sin θ_j]ᵀ [cos θ_j, sin θ_j]``, which is diagonal (:func:`tangent_stars`).
* interior (rows 1 and 2): the two interior points next to A, Fn of L and Fp of R, must average
  to the face point

      avg_A = (c_B A + (3 − 2 c_A − c_B) e_AB + 2 c_A e_BA) / 3                          (FP)

  Each face corner gets a target ``Ft = e_AB + e_AD − A + (A − B + C − D)/9`` (bilinear twist;
  corners A, B, C, D counter-clockwise) and the pair is moved onto (FP) by the minimum-norm
  correction: ``Fn_L = avg_A + (Ft_L − Ft_R)/2``, ``Fp_R = avg_A + (Ft_R − Ft_L)/2``. Boundary
  edges keep their targets.

Every step is a gather, a scatter or a segmented sum (``np.add.reduceat``) over the flat
half-edge and ring arrays, so vertices of every valence are handled at once: there is no Python
loop over vertices, edges, faces or valences.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import ConstructionError, check_choice
from ..gregory import GregoryPatchSet
from ..mesh import QuadMesh, QuadTopology
from ..network import PatchNetwork, network_from_mesh
from .corner import TANGENTS, TangentRule, corner_tangents, fan_normals

__all__ = ["build_gregory_network", "gregory_patches", "halfedge_slots", "tangent_stars"]

_NEXT = np.array([1, 2, 3, 0])


def tangent_stars(
    mesh: QuadMesh, normals: NDArray[np.float64], tangents: TangentRule = "arc"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The regular tangent star of every vertex and its G1 coefficient.

    Returns ``star`` (S, 3), one tangent per ring slot in the order of ``topology.neighbors``
    (slot ``neighbor_offsets[v] + j`` points towards neighbour j of v, counter-clockwise), and
    ``cosine`` (nv,): ``c_v = cos(2π/n)`` inside, ``cos(π/k)`` on the boundary (see the module
    docstring). The Gram matrix of the fit is diagonal: ``G = diag(n/2, n/2)`` at an interior
    vertex and ``diag((k + 2)/2, k/2)`` at a boundary vertex with k ≥ 2 faces (Σ_{j=0..k} cos 2πj/k
    = 1, Σ sin 2πj/k = 0), so ``a = Σ cos θ_j s_j / G_11`` and ``b = Σ sin θ_j s_j / G_22``, one
    segmented sum per vertex. Raises :class:`ConstructionError` where a fitted star is degenerate
    or turns clockwise about the normal.
    """
    topology = mesh.topology
    offsets = topology.neighbor_offsets
    boundary = topology.is_boundary_vertex
    slot_vertex = np.repeat(np.arange(topology.n_vertices), np.diff(offsets))
    step = np.where(boundary, np.pi / topology.face_count, 2.0 * np.pi / topology.valence)
    theta = (np.arange(len(slot_vertex)) - offsets[slot_vertex]) * step[slot_vertex]
    cos, sin = np.cos(theta), np.sin(theta)
    del theta

    s = _slot_tangents(mesh, normals, tangents, slot_vertex)
    corner = boundary & (topology.face_count == 1)
    free = np.flatnonzero(corner[slot_vertex])
    free_tangents = s[free]
    moments = np.empty((len(slot_vertex), 6))
    np.multiply(cos[:, None], s, out=moments[:, :3])
    np.multiply(sin[:, None], s, out=moments[:, 3:])
    del s
    moments = np.add.reduceat(moments, offsets[:-1])
    half = 0.5 * np.where(boundary, topology.face_count, topology.valence)
    a = moments[:, :3] / np.where(boundary, half + 1.0, half)[:, None]
    b = moments[:, 3:] / np.where(corner, 1.0, half)[:, None]
    _check_stars(topology, a, b, normals, corner)

    star = a[slot_vertex]
    star *= cos[:, None]
    turned = b[slot_vertex]
    turned *= sin[:, None]
    star += turned
    star[free] = free_tangents
    return star, np.cos(step)


_CHUNK = 1 << 16


def _slot_tangents(
    mesh: QuadMesh, normals: NDArray[np.float64], tangents: TangentRule, slot_vertex: NDArray[np.int64]
) -> NDArray[np.float64]:
    """``corner_tangents`` from each slot's vertex towards its neighbour, (S, 3), in fixed-size
    chunks of slots so that its temporaries stay small."""
    x = mesh.vertices
    neighbors = mesh.topology.neighbors
    s = np.empty((len(slot_vertex), 3))
    for low in range(0, len(slot_vertex), _CHUNK):
        chunk = slice(low, low + _CHUNK)
        origin, target = slot_vertex[chunk], neighbors[chunk]
        s[chunk] = corner_tangents(x[origin], x[target], normals[origin], tangents, np.stack([origin, target], axis=1))
    return s


def _check_stars(
    topology: QuadTopology,
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    normals: NDArray[np.float64],
    corner: NDArray[np.bool_],
) -> None:
    """Every fitted star must turn counter-clockwise about its normal: ``(a × b)·n > 0``."""
    area = np.einsum("vd,vd->v", np.cross(a, b), normals)
    scale = np.einsum("vd,vd->v", a, a) + np.einsum("vd,vd->v", b, b)
    bad = np.flatnonzero(~corner & ~(area > 1e-12 * scale))
    if bad.size:
        v = int(bad[0])
        raise ConstructionError(
            f"tangent star: the regular star fitted to the ring of vertex {v} "
            f"({'boundary' if topology.is_boundary_vertex[v] else 'interior'}, valence {topology.valence[v]}) "
            f"is degenerate or folded ((a × b)·n = {area[v]:.3g}); its ring edges do not turn once around the normal"
            + (f" ({bad.size} such vertices)" if bad.size > 1 else "")
        )


def gregory_patches(mesh: QuadMesh, normals: NDArray[np.float64], tangents: TangentRule = "arc") -> GregoryPatchSet:
    """The patches of the interpolating Gregory network (module docstring), one per face.

    Face corner k of face f is half-edge ``h = 4 f + k`` (A → B); arrays shaped (F, 4, 3) are
    indexed by it. Everything is written into the (F, 20, 3) output in place, so the build's
    temporaries stay a few (F, 4, 3) arrays.
    """
    topology = mesh.topology
    faces = topology.faces
    count = topology.n_faces
    x = mesh.vertices
    star, cosine = tangent_stars(mesh, normals, tangents)
    star /= 3.0  # edge point offsets t_j / 3
    slot_out, slot_in = halfedge_slots(topology)
    following = faces[:, _NEXT]

    points = np.empty((count, 20, 3))
    corner_points, e_next, e_prev = points[:, :4], points[:, 4:12:2], points[:, 5:12:2]
    near, far = points[:, 12::2], points[:, 13::2]
    corner_points[...] = x[faces]
    np.add(corner_points, star[slot_out].reshape(count, 4, 3), out=e_next)  # E+_k = e(A → B)
    back = x[following]
    back += star[slot_in].reshape(count, 4, 3)  # e(B → A): the same bits as the twin's e(A → B)
    e_prev[:, 1:], e_prev[:, 0] = back[:, :3], back[:, 3]  # E-_k = e(A → D)
    del star, slot_out, slot_in, back

    # Targets Ft = E+ + E- − A + (A − B + C − D)/9, with A − B + C − D = ±(x0 − x1 + x2 − x3); kept in Fp.
    np.add(e_next, e_prev, out=far)
    far -= corner_points
    bilinear = (corner_points[:, 0] - corner_points[:, 1] + corner_points[:, 2] - corner_points[:, 3]) / 9.0
    far[:, 0::2] += bilinear[:, None]
    far[:, 1::2] -= bilinear[:, None]

    # avg_A (FP) for every half-edge h = A → B, with e(B → A) = E-_{k+1}.
    c_a, c_b = cosine[faces][..., None], cosine[following][..., None]
    correction = (3.0 - 2.0 * c_a - c_b) * e_next
    scratch = c_b * corner_points
    correction += scratch
    scratch[:, :3], scratch[:, 3] = e_prev[:, 1:], e_prev[:, 0]
    scratch *= 2.0 * c_a
    correction += scratch
    correction /= 3.0
    del scratch

    # d = avg_A − (Ft_L + Ft_R)/2, R's point at next(twin(h)); d = 0 on boundary half-edges.
    twin = topology.twin
    halfedges = np.arange(4 * count)
    partner = np.where(twin >= 0, QuadTopology.next(twin), halfedges)
    mean = far[partner >> 2, partner & 3].reshape(count, 4, 3)
    mean += far
    mean *= 0.5
    correction -= mean
    del mean
    flat_correction = correction.reshape(-1, 3)
    flat_correction[twin < 0] = 0.0
    np.add(far, correction, out=near)  # Fn_k = Ft + d of h, the edge-k point
    previous = QuadTopology.prev(halfedges)
    incoming = twin[previous]  # A → D leaves A along edge k − 1: Fp_k = Ft + its d
    far += flat_correction[np.where(incoming >= 0, incoming, previous)].reshape(count, 4, 3)
    return GregoryPatchSet(points)


def halfedge_slots(topology: QuadTopology) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Ring slot (see :func:`tangent_stars`) of each half-edge A → B at A, and of B → A at B.

    The reverse of a boundary half-edge is the last slot of its target: the virtual ring edge k.
    """
    ring_vertex = np.repeat(np.arange(topology.n_vertices), topology.face_count)
    slot_out = np.empty(topology.n_halfedges, dtype=np.int64)
    slot_out[topology.ring_halfedges] = (
        np.arange(len(ring_vertex)) - topology.ring_offsets[ring_vertex] + topology.neighbor_offsets[ring_vertex]
    )
    twin = topology.twin
    target = topology.target(np.arange(topology.n_halfedges))
    slot_in = np.where(twin >= 0, slot_out[twin], topology.neighbor_offsets[target + 1] - 1)
    return slot_out, slot_in


def build_gregory_network(mesh: QuadMesh, *, tangents: TangentRule = "arc") -> PatchNetwork:
    """The interpolating Gregory network of ``mesh``: exact G1 on every interior edge and corner."""
    check_choice("tangents", tangents, TANGENTS)
    normals = fan_normals(mesh)
    provenance = {"method": "gregory", "tangents": tangents}
    if mesh.source:
        provenance["source"] = str(mesh.source)
    return network_from_mesh(mesh.topology, gregory_patches(mesh, normals, tangents), mesh.vertices, normals, provenance)
