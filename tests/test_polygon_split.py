"""Splitting non-quad faces: new points on a smooth surface through the vertices (issue 9, build
4)."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from numpy.typing import NDArray

from g1patch.mesh import QuadMesh, refine_polygons, subdivide

Faces = list[list[int]]


def _outward(vertices: NDArray[np.float64], faces: Faces) -> Faces:
    """Faces of a convex solid around the origin, turned counter-clockwise seen from outside."""
    oriented = []
    for face in faces:
        p = vertices[face]
        normal = np.cross(p[1] - p[0], p[2] - p[0])
        oriented.append(face if normal @ p.mean(axis=0) > 0 else face[::-1])
    return oriented


def _around(
    vertices: NDArray[np.float64], centre: NDArray[np.float64], ids: NDArray[np.int64]
) -> list[int]:
    """``ids`` sorted counter-clockwise around the outward direction ``centre``."""
    e1 = np.cross(centre, [0.3, 0.5, 0.7])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(centre, e1)
    return ids[np.argsort(np.arctan2(vertices[ids] @ e2, vertices[ids] @ e1))].tolist()


def icosahedron() -> tuple[NDArray[np.float64], Faces]:
    """20 triangles, vertices on the unit sphere."""
    g = (1 + 5**0.5) / 2
    vertices = np.array(
        [p for a in (-1, 1) for b in (-g, g) for p in ((0, a, b), (a, b, 0), (b, 0, a))],
        dtype=float,
    )
    vertices /= np.linalg.norm(vertices, axis=1)[:, None]
    distance = np.linalg.norm(vertices[:, None] - vertices[None], axis=2)
    edge = distance[distance > 0].min()
    near = np.abs(distance - edge) < 1e-9
    faces = [
        [i, j, k]
        for i in range(12)
        for j in range(i + 1, 12)
        for k in range(j + 1, 12)
        if near[i, j] and near[j, k] and near[i, k]
    ]
    return vertices, _outward(vertices, faces)


def dodecahedron() -> tuple[NDArray[np.float64], Faces]:
    """12 pentagons: the icosahedron's dual, vertices on the unit sphere."""
    ico, triangles = icosahedron()
    tri = np.array(triangles)
    vertices = ico[tri].mean(axis=1)
    vertices /= np.linalg.norm(vertices, axis=1)[:, None]
    faces = [_around(vertices, ico[v], np.flatnonzero((tri == v).any(axis=1))) for v in range(12)]
    return vertices, faces


def icosidodecahedron() -> tuple[NDArray[np.float64], Faces]:
    """20 triangles and 12 pentagons, vertices at the icosahedron's edge midpoints on the unit
    sphere."""
    ico, triangles = icosahedron()
    tri = np.array(triangles)
    pairs = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    keys, inverse = np.unique(pairs[:, 0] * 12 + pairs[:, 1], return_inverse=True)
    vertices = ico[keys // 12] + ico[keys % 12]
    vertices /= np.linalg.norm(vertices, axis=1)[:, None]
    faces = inverse.reshape(3, -1).T.tolist()
    faces += [
        _around(vertices, ico[v], np.flatnonzero((keys // 12 == v) | (keys % 12 == v)))
        for v in range(12)
    ]
    return vertices, faces


SOLIDS = {
    "icosahedron": icosahedron,
    "dodecahedron": dodecahedron,
    "icosidodecahedron": icosidodecahedron,
}


def _flat(faces: Faces) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    return np.concatenate([np.asarray(f) for f in faces]), np.array([len(f) for f in faces])


def _split(vertices: NDArray[np.float64], faces: Faces, smooth: bool):
    corners, sizes = _flat(faces)
    return refine_polygons(vertices, corners, sizes, smooth=smooth)


def _n_edges(faces: Faces) -> int:
    """Edges of a closed mesh."""
    return sum(map(len, faces)) // 2


# -- (a) curved input: the new points leave the flat polygons for the sphere ---------------------


@pytest.mark.parametrize("name", SOLIDS)
def test_points_of_a_sphere_cage_approach_the_sphere(name: str) -> None:
    vertices, faces = SOLIDS[name]()
    nv, ne = len(vertices), _n_edges(faces)
    flat, _, _ = _split(vertices, faces, smooth=False)
    smooth, _, _ = _split(vertices, faces, smooth=True)
    for new in (slice(nv, nv + ne), slice(nv + ne, None)):  # edge points, then face points
        flat_error = np.abs(1 - np.linalg.norm(flat[new], axis=1))
        smooth_error = np.abs(1 - np.linalg.norm(smooth[new], axis=1))
        outward = flat[new] / np.linalg.norm(flat[new], axis=1)[:, None]
        lift = np.einsum("ij,ij->i", smooth[new] - flat[new], outward)
        assert flat_error.min() > 0.04  # the flat points are well inside the sphere
        assert (lift > 0.5 * flat_error).all()  # off the flat polygon, outwards, by a clear margin
        assert (smooth_error < 0.5 * flat_error).all()
    # edge points: the Hermite midpoint of a circle-aware cubic on radial normals is on the circle
    edge_error = np.abs(1 - np.linalg.norm(smooth[nv : nv + ne], axis=1))
    assert edge_error.max() < 1e-12
    all_new = slice(nv, None)
    ratio = (
        np.abs(1 - np.linalg.norm(smooth[all_new], axis=1)).mean()
        / np.abs(1 - np.linalg.norm(flat[all_new], axis=1)).mean()
    )
    assert ratio < 0.3


def test_face_point_is_the_coons_centre() -> None:
    vertices, faces = dodecahedron()
    nv, ne = len(vertices), _n_edges(faces)
    points, quads, parent = _split(vertices, faces, smooth=True)
    edge_of_corner = quads[:, 1]  # E(v_i v_{i+1}) of every corner
    for f, face in enumerate(faces[:3]):
        m = points[edge_of_corner[parent == f]]
        centre = 2 * m.mean(axis=0) - vertices[face].mean(axis=0)
        np.testing.assert_allclose(points[nv + ne + f], centre, rtol=0, atol=1e-15)


# -- (b) flat input: exactly the midpoints and centroids ------------------------------------------


def planar_patchwork() -> tuple[NDArray[np.float64], Faces]:
    """An open planar mesh in z = 0: a row of three pentagons with a triangle below each, jittered
    in x, y."""
    xs = np.arange(4, dtype=float)
    vertices = [(x, 0.0, 0.0) for x in xs] + [(x, 1.0, 0.0) for x in xs]  # 0..3 bottom, 4..7 top
    vertices += [(x + 0.5, 1.3, 0.0) for x in xs[:3]]  # 8..10 roof tips of the pentagons
    vertices += [(x + 0.5, -0.7, 0.0) for x in xs[:3]]  # 11..13 below
    faces: Faces = []
    for i in range(3):
        faces.append([i, i + 1, i + 5, 8 + i, i + 4])  # pentagon with a roof tip
        faces.append([i, 11 + i, i + 1])  # triangle below
    rng = np.random.default_rng(9)
    jitter = np.zeros((len(vertices), 3))
    jitter[:, :2] = rng.uniform(-0.1, 0.1, (len(vertices), 2))
    return np.array(vertices) + jitter, faces


def test_flat_input_gives_midpoints_and_centroids() -> None:
    vertices, faces = planar_patchwork()
    flat, _, _ = _split(vertices, faces, smooth=False)
    smooth, _, _ = _split(vertices, faces, smooth=True)
    assert (smooth[:, 2] == 0).all()
    scale = np.abs(flat).max()
    np.testing.assert_allclose(smooth, flat, rtol=0, atol=1e-15 * scale)


def test_flat_input_through_from_arrays(caplog) -> None:
    vertices, faces = planar_patchwork()
    with caplog.at_level(logging.INFO, logger="g1patch.mesh"):
        mesh = QuadMesh.from_arrays(vertices, faces)
    assert "smooth surface" in caplog.records[-1].getMessage()
    flat, _, _ = _split(vertices, faces, smooth=False)
    np.testing.assert_allclose(mesh.vertices, flat, rtol=0, atol=1e-15 * np.abs(flat).max())


# -- (c), (d) old vertices and topology are those of the linear split ----------------------------


@pytest.mark.parametrize("name", [*SOLIDS, "planar"])
def test_vertices_and_topology_are_kept(name: str) -> None:
    vertices, faces = planar_patchwork() if name == "planar" else SOLIDS[name]()
    flat, flat_quads, flat_parent = _split(vertices, faces, smooth=False)
    smooth, quads, parent = _split(vertices, faces, smooth=True)
    assert smooth.shape == flat.shape
    np.testing.assert_array_equal(smooth[: len(vertices)], vertices)  # bit for bit
    np.testing.assert_array_equal(quads, flat_quads)
    np.testing.assert_array_equal(parent, flat_parent)
    mesh = QuadMesh.from_arrays(vertices, faces)
    np.testing.assert_array_equal(mesh.faces, flat_quads)
    np.testing.assert_array_equal(mesh.vertices, smooth)


def test_subdivide_stays_linear() -> None:
    vertices, faces = icosahedron()
    mesh = QuadMesh.from_arrays(vertices, faces)  # smooth split of the triangles
    refined = subdivide(mesh)
    corners, sizes = mesh.faces.ravel(), np.full(mesh.n_faces, 4)
    flat, _, _ = refine_polygons(mesh.vertices, corners, sizes)
    np.testing.assert_array_equal(refined.vertices, flat)


# -- (e) safeguards
# ---------------------------------------------------------------------------------


def _wall_fan(w: tuple[float, float, float]) -> tuple[NDArray[np.float64], Faces]:
    """An open fan around vertex 0 whose edge 0–1 runs along +z; with w = (0, 1, 1) the fan normal
    at 0 is exactly (0, 0, 2), parallel to that edge; with w = (0, 0, 1) it is exactly zero."""
    vertices = np.array([(0, 0, 0), (0, 0, 1), (1, 0, 0), w, (-1, 0, 0)], dtype=float)
    return vertices, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]]


@pytest.mark.parametrize(
    "w", [(0.0, 1.0, 1.0), (0.0, 0.0, 1.0)], ids=["edge-along-normal", "zero-normal"]
)
def test_degenerate_tangents_fall_back_to_the_midpoint(w: tuple[float, float, float]) -> None:
    vertices, faces = _wall_fan(w)
    flat, _, _ = _split(vertices, faces, smooth=False)
    smooth, _, _ = _split(vertices, faces, smooth=True)
    assert np.isfinite(smooth).all()
    nv = len(vertices)
    edge_01 = nv + 0  # edges sorted by vertex pair: (0, 1) first
    np.testing.assert_array_equal(smooth[edge_01], [0, 0, 0.5])
    if w == (0.0, 0.0, 1.0):  # no normal at vertex 0: every edge at 0 keeps its midpoint
        np.testing.assert_array_equal(smooth[nv : nv + 4], flat[nv : nv + 4])
    else:  # the other edges still bend
        assert not np.allclose(smooth[nv + 1 : nv + 4], flat[nv + 1 : nv + 4])


def test_edge_along_the_normal_builds_a_mesh() -> None:
    vertices, faces = _wall_fan((0.0, 1.0, 1.0))
    mesh = QuadMesh.from_arrays(vertices, faces)
    assert np.isfinite(mesh.vertices).all() and mesh.n_faces == 12
