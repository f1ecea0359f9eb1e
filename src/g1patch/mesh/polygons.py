"""Faces that are not quads, split: one Catmull–Clark topology step turns every n-gon into n
quads (:func:`refine_polygons`), its new points on a smooth surface through the old vertices
(circle-aware Hermite edge points, Coons face points, creases kept), and the way from checked
polygons to quads (:func:`_quads_from_polygons`: drop unused vertices, split the non-quads, carry
the tags along).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..errors import MeshError
from .cage import PolygonCage
from .connectivity import _connect
from .faces import _edge_keys, _following_corner
from .tags import INFINITE_SHARPNESS, Tag, _refine_tags, _renumber_tags
from .validate import _few
from .vertex_sectors import sectors

__all__ = ["SPLIT_SHARPNESS", "refine_corner_uvs", "refine_polygons"]

logger = logging.getLogger(__name__)

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]

#: an edge end whose tangent-plane projection is shorter than this fraction of the edge
#: (the edge runs along the vertex normal) gets no smooth tangent: the edge keeps its midpoint
_SPLIT_PARALLEL_TOLERANCE = 1e-6
#: a fan normal shorter than this fraction of its corners' summed |cross products| counts as zero
_SPLIT_NORMAL_TOLERANCE = 1e-12


def _corner_normals(
    vertices: FloatArray, corners: IntArray, sizes: IntArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Area-weighted fan normals ``N_v = Σ (v_next − v) × (v_prev − v)`` over v's corners, unit.

    Vertices at the boundary take the same sum over their faces. Returns ``(normals, valid)``;
    where ``|N_v| <= _SPLIT_NORMAL_TOLERANCE · Σ |cross|`` (or v has no corner) the normal is
    zero and ``valid`` is False.
    """
    nv = vertices.shape[0]
    following = _following_corner(sizes)
    preceding = np.empty_like(following)
    preceding[following] = np.arange(corners.size)
    here = vertices[corners]
    cross = np.cross(vertices[corners[following]] - here, vertices[corners[preceding]] - here)
    summed = np.stack(
        [np.bincount(corners, weights=cross[:, k], minlength=nv) for k in range(3)], axis=1
    )
    scale = np.bincount(corners, weights=np.linalg.norm(cross, axis=1), minlength=nv)
    length = np.linalg.norm(summed, axis=1)
    valid = (length > _SPLIT_NORMAL_TOLERANCE * scale) & np.isfinite(length)
    normals = np.zeros(summed.shape)  # summed: float64 (bincount with weights)
    normals[valid] = summed[valid] / length[valid, None]
    return normals, valid


def _edge_tangents(
    d: FloatArray, normal: FloatArray, valid_normal: NDArray[np.bool_]
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Circle-aware Hermite tangents of chords ``d`` at an end with unit ``normal``, batched.

    Direction ``s = d − (N·d) N``, length ``L = |d| / cos²(θ/4)`` with ``sin(θ/2) = |N·d| / |d|``,
    i.e. ``L = 2|d|² / (|d| + |s|)`` (the tangent of a circular arc through both ends, tangent
    to the plane). Returns ``(tangents, ok)``; not ok (tangent zero) where the normal is invalid
    or ``|s| <= _SPLIT_PARALLEL_TOLERANCE · |d|``.
    """
    s = d - np.einsum("ij,ij->i", d, normal)[:, None] * normal
    in_plane = np.linalg.norm(s, axis=1)
    chord = np.linalg.norm(d, axis=1)
    ok = valid_normal & (in_plane > _SPLIT_PARALLEL_TOLERANCE * chord)
    scale = np.zeros_like(chord)
    scale[ok] = 2.0 * chord[ok] ** 2 / ((chord[ok] + in_plane[ok]) * in_plane[ok])
    return s * scale[:, None], ok


def _smooth_edge_points(
    vertices: FloatArray,
    a: IntArray,
    b: IntArray,
    normals: tuple[FloatArray, FloatArray],
    valid: tuple[NDArray[np.bool_], NDArray[np.bool_]],
) -> FloatArray:
    """Midpoints of the cubic Hermite curves of edges a–b: ``(A + B)/2 + (t_AB + t_BA)/8``.

    ``t_AB`` is A's tangent towards B, ``t_BA`` B's towards A (:func:`_edge_tangents`), on the
    per-edge end normals ``normals = (at A, at B)``; an edge that lacks a tangent at one of its
    ends keeps its chord midpoint.
    """
    d = vertices[b] - vertices[a]
    t_ab, ok_a = _edge_tangents(d, normals[0], valid[0])
    t_ba, ok_b = _edge_tangents(-d, normals[1], valid[1])
    bend = np.where((ok_a & ok_b)[:, None], t_ab + t_ba, 0.0)
    return 0.5 * (vertices[a] + vertices[b]) + 0.125 * bend


def _creased_edge_points(
    vertices: FloatArray,
    corners: IntArray,
    sizes: IntArray,
    a: IntArray,
    b: IntArray,
    sharp: NDArray[np.bool_],
) -> FloatArray:
    """Edge points of a polygon mesh with creases ``sharp`` (per edge a–b, sorted pairs).

    Smooth edges: :func:`_smooth_edge_points` on each end's *sector* normal, the area-weighted
    fan normal of the faces reached from the edge without crossing a crease or the boundary.
    Creases: ``(A + B)/2 + (t_AB + t_BA)/8`` with t along the crease curve: at a vertex with
    exactly two creases (inside) the tangent of the circle through it and its two crease
    neighbours, ``d ∥ |c_P|² c_Q − |c_Q|² c_P``, of length ``2|c|/(1 + ĉ·d)``; elsewhere the chord
    (a crease between two corners stays straight).
    """
    nv = vertices.shape[0]
    connectivity = _connect(corners, sizes, nv)
    cut = sharp & (connectivity.edge_halfedges[:, 1] >= 0)
    found = sectors(connectivity, cut)
    following = _following_corner(sizes)
    preceding = np.empty_like(following)
    preceding[following] = np.arange(corners.size)
    here = vertices[corners]
    cross = np.cross(vertices[corners[following]] - here, vertices[corners[preceding]] - here)
    position = np.empty(corners.size, dtype=np.int64)
    position[connectivity.ring_halfedges] = np.arange(corners.size)
    label = found.label[position]  # sector of each corner
    count = found.vertex.size
    summed = np.stack([np.bincount(label, cross[:, k], minlength=count) for k in range(3)], axis=1)
    scale = np.bincount(label, np.linalg.norm(cross, axis=1), minlength=count)
    length = np.linalg.norm(summed, axis=1)
    valid = (length > _SPLIT_NORMAL_TOLERANCE * scale) & np.isfinite(length)
    normals = np.divide(summed, length[:, None], out=np.zeros_like(summed), where=valid[:, None])
    start = connectivity.edge_halfedges[
        :, 0
    ]  # corner at a (a → b or b → a), its face touches the edge
    at_a = np.where(corners[start] == a, start, following[start])
    at_b = np.where(corners[start] == b, start, following[start])
    out = _smooth_edge_points(
        vertices,
        a,
        b,
        (normals[label[at_a]], normals[label[at_b]]),
        (valid[label[at_a]], valid[label[at_b]]),
    )

    # crease curves: the two crease neighbours of every vertex with exactly two creases inside
    e = np.flatnonzero(sharp)
    ends = np.concatenate([a[e], b[e]])
    others = np.concatenate([b[e], a[e]])
    creases = np.bincount(ends, minlength=nv)
    order = np.argsort(ends, kind="stable")
    ends, others = ends[order], others[order]
    two = (creases[ends] == 2) & ~connectivity.is_boundary_vertex[ends]
    pairs = others[two].reshape(-1, 2)
    owner = ends[two][0::2]
    c_p, c_q = vertices[pairs[:, 0]] - vertices[owner], vertices[pairs[:, 1]] - vertices[owner]
    direction = np.zeros((nv, 3))
    d = (
        c_q * np.einsum("ij,ij->i", c_p, c_p)[:, None]
        - c_p * np.einsum("ij,ij->i", c_q, c_q)[:, None]
    )
    d_length = np.linalg.norm(d, axis=1, keepdims=True)
    direction[owner] = np.divide(d, d_length, out=np.zeros_like(d), where=d_length > 0)

    def crease_tangent(start_vertex: IntArray, end_vertex: IntArray) -> FloatArray:
        chord = vertices[end_vertex] - vertices[start_vertex]
        along = direction[start_vertex]
        chord_length = np.linalg.norm(chord, axis=1)
        cosine = np.einsum("ij,ij->i", chord, along) / np.where(chord_length > 0, chord_length, 1.0)
        along = along * np.sign(cosine)[:, None]  # towards this end
        curved = np.abs(cosine) > 0.1
        length = 2.0 * chord_length / (1.0 + np.abs(cosine))
        return np.where(curved[:, None], length[:, None] * along, chord)

    out[e] = 0.5 * (vertices[a[e]] + vertices[b[e]]) + 0.125 * (
        crease_tangent(a[e], b[e]) + crease_tangent(b[e], a[e])
    )
    return out


def refine_polygons(
    vertices: FloatArray,
    corners: IntArray,
    sizes: IntArray,
    *,
    smooth: bool = False,
    sharp: NDArray[np.bool_] | None = None,
) -> tuple[FloatArray, IntArray, IntArray]:
    """One Catmull–Clark topology step: every n-gon becomes n quads.

    New vertices: the old ones (same indices and positions), then one per edge (``nv + e``, edges
    sorted by vertex pair), then one per face (``nv + ne + f``). Corner ``i`` of face ``f``
    becomes quad ``offsets[f] + i = (v_i, E(v_i v_{i+1}), F(f), E(v_{i-1} v_i))``,
    counter-clockwise like its face. Returns ``(vertices, quads, parent_face)``.

    Positions, linear (default): edge midpoints and face centroids. ``smooth``: on a surface
    through the old vertices — edge points at the middle of the edges' circle-aware cubic
    Hermite curves on area-weighted fan normals (:func:`_smooth_edge_points`), face points at the
    Coons centre ``C = (2/n) Σ M_i − (1/n) Σ V_i`` of the face's corners ``V_i`` and edge points
    ``M_i``. Both give midpoints and centroids on flat input. ``smooth`` expects a validated,
    oriented manifold topology (:func:`_connect`). ``sharp`` (per edge, sorted vertex pairs) marks
    creases for ``smooth``: the normals of an edge's ends are then those of its sector of faces
    (:func:`sectors`), and a crease's point is the middle of its crease curve
    (:func:`_creased_edge_points`), so a flat face bounded by creases stays flat.
    """
    nv = vertices.shape[0]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    corner_face = np.repeat(np.arange(sizes.size), sizes)
    preceding = np.empty(corners.size, dtype=np.int64)
    preceding[_following_corner(sizes)] = np.arange(corners.size)

    edge_keys, corner_edge = np.unique(_edge_keys(corners, sizes, nv), return_inverse=True)
    a, b = edge_keys // nv, edge_keys % nv
    corner_sums = np.add.reduceat(vertices[corners], offsets[:-1], axis=0)
    if smooth:
        if sharp is not None and sharp.any():
            edge_points = _creased_edge_points(vertices, corners, sizes, a, b, sharp)
        else:
            normals, valid = _corner_normals(vertices, corners, sizes)
            edge_points = _smooth_edge_points(
                vertices, a, b, (normals[a], normals[b]), (valid[a], valid[b])
            )
        edge_sums = np.add.reduceat(edge_points[corner_edge], offsets[:-1], axis=0)
        face_points = (2.0 * edge_sums - corner_sums) / sizes[:, None]
    else:
        edge_points = 0.5 * (vertices[a] + vertices[b])
        face_points = corner_sums / sizes[:, None]
    quads = np.stack(
        [corners, nv + corner_edge, nv + edge_keys.size + corner_face, nv + corner_edge[preceding]],
        axis=1,
    )
    return np.concatenate([vertices, edge_points, face_points]), quads, corner_face


def refine_corner_uvs(uv: FloatArray, sizes: IntArray) -> FloatArray:
    """Face-varying texture coordinates through :func:`refine_polygons`' split: ``uv`` (C, 2),
    one per polygon corner, becomes (C, 4, 2), the corners of quad ``offsets[f] + i``:
    ``(u_i, (u_i + u_{i+1})/2, (1/n) Σ u_k, (u_{i-1} + u_i)/2)``, bilinear on a quad (edge
    midpoints and centre at parameters ½), the same per face, so seams in UV space stay."""
    following = _following_corner(sizes)
    preceding = np.empty_like(following)
    preceding[following] = np.arange(following.size)
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    centre = np.add.reduceat(uv, offsets, axis=0) / sizes[:, None]
    corner_face = np.repeat(np.arange(sizes.size), sizes)
    return np.stack(
        [uv, 0.5 * (uv + uv[following]), centre[corner_face], 0.5 * (uv[preceding] + uv)], axis=1
    )


#: creases at least this sharp shape the smooth split (the interpolating rule's threshold)
SPLIT_SHARPNESS = 1.0


def _crease_edges(
    tags: Sequence[Tag], corners: IntArray, sizes: IntArray, n_vertices: int
) -> NDArray[np.bool_] | None:
    """Per edge of the polygons (sorted vertex pairs), whether a crease tag of sharpness ≥
    :data:`SPLIT_SHARPNESS` names it; None without such tags."""
    edge_keys = np.unique(_edge_keys(corners, sizes, n_vertices))
    sharp = np.zeros(edge_keys.size, dtype=bool)
    for tag in tags:
        if tag.name != "crease" or not tag.ints:
            continue
        ints = np.asarray(tag.ints, dtype=np.int64)
        pa, pb = ints[0::2], ints[1::2]
        floats = np.asarray(tag.floats, dtype=np.float64)
        values = (
            floats
            if floats.size == pa.size
            else np.full(pa.size, floats[0] if floats.size else INFINITE_SHARPNESS)
        )
        keys = np.minimum(pa, pb) * n_vertices + np.maximum(pa, pb)
        found = np.minimum(np.searchsorted(edge_keys, keys), edge_keys.size - 1)
        hit = (edge_keys[found] == keys) & (values >= SPLIT_SHARPNESS)
        sharp[found[hit]] = True
    return sharp if sharp.any() else None


def _quads_from_polygons(
    points: FloatArray,
    corners: IntArray,
    sizes: IntArray,
    split: bool,
    source: str | None,
    tags: tuple[Tag, ...],
    uv: FloatArray | None = None,
) -> tuple[FloatArray, IntArray, tuple[Tag, ...], PolygonCage | None, FloatArray | None]:
    """Drop unused vertices and split non-quads of checked polygons (see
    :meth:`QuadMesh.from_arrays <g1patch.mesh.QuadMesh.from_arrays>`); the polygons split, as a
    :class:`PolygonCage`, or None where all were quads; the quads' corner UVs (F, 4, 2) of the
    polygons' ``uv`` (C, 2) (:func:`refine_corner_uvs`), None without.

    When anything is dropped or split, the polygon topology is validated first, so that errors
    name the input's faces and vertices.
    """
    used = np.bincount(corners, minlength=points.shape[0]) > 0
    non_quads = np.flatnonzero(sizes != 4)
    quad_uv = None if uv is None else uv.reshape(-1, 4, 2) if non_quads.size == 0 else None
    if used.all() and non_quads.size == 0:
        return points, corners.reshape(-1, 4), tags, None, quad_uv
    if non_quads.size and not split:
        raise MeshError(
            f"{non_quads.size} faces are not quads (face {non_quads[0]} has {sizes[non_quads[0]]} "
            "corners; "
            f"faces {_few(non_quads)}) and splitting is off (--no-split)"
        )
    _connect(corners, sizes, points.shape[0])

    if not used.all():
        unused = np.flatnonzero(~used)
        logger.info(
            "%s: dropped %d unused vertices (%s)", source or "mesh", unused.size, _few(unused)
        )
        new_index = np.cumsum(used) - 1
        new_index[~used] = -1
        points, corners = points[used], new_index[corners]
        tags = _renumber_tags(tags, new_index)
    if non_quads.size == 0:
        return points, corners.reshape(-1, 4), tags, None, quad_uv
    cage = PolygonCage(points, corners, sizes, tags)
    sharp = _crease_edges(tags, corners, sizes, points.shape[0])
    tags = _refine_tags(tags, corners, sizes, points.shape[0])
    points, quads, _ = refine_polygons(points, corners, sizes, smooth=True, sharp=sharp)
    logger.info(
        "%s: %d of %d faces are not quads; refined the whole mesh once (every n-gon into n quads, "
        "new points on a smooth surface through the vertices)",
        source or "mesh",
        non_quads.size,
        sizes.size,
    )
    return points, quads, tags, cage, None if uv is None else refine_corner_uvs(uv, sizes)
