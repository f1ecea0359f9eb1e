"""The Catmull–Clark limit of polygon cages (triangles, n-gons): the first step by the
Catmull–Clark rules (:func:`g1patch.subdivision.catmull_clark_cage`), against a textbook step
written here with dictionaries and loops (Catmull & Clark 1978; boundary and crease rules as
OpenSubdiv's: edge midpoints, ``(A + 6V + B)/8``, corners fixed), and ``--shape limit`` through
the limit of the cage rather than of its smooth split."""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest
from scipy.spatial import cKDTree

from g1patch.build import build_network
from g1patch.continuity import check
from g1patch.mesh import QuadMesh, Tag
from g1patch.subdivision import catmull_clark_cage, limit_points, refine
from g1patch.subdivision.matrix import cage_step_matrix

EPS = float(np.finfo(float).eps)


def textbook_step(
    points: np.ndarray, faces: list[list[int]], sharp: set[tuple[int, int]] = frozenset()
) -> dict[str, object]:
    """One Catmull–Clark step, vertex by vertex: ``{"vertex": {v: p}, "edge": {(a, b): p},
    "face": [p]}``. Boundary edges count as sharp; a vertex on 2 sharp edges is a crease vertex,
    on more a corner, on one face only (a boundary corner, edge-only rule) a crease vertex too."""
    edge_faces: dict[tuple[int, int], list[int]] = defaultdict(list)
    for f, face in enumerate(faces):
        for i, a in enumerate(face):
            b = face[(i + 1) % len(face)]
            edge_faces[(min(a, b), max(a, b))].append(f)
    face_points = [sum(points[v] for v in face) / len(face) for face in faces]
    is_sharp = {e: len(fs) == 1 or e in sharp for e, fs in edge_faces.items()}
    edge_points = {}
    for (a, b), fs in edge_faces.items():
        if is_sharp[(a, b)]:
            edge_points[(a, b)] = (points[a] + points[b]) / 2
        else:
            edge_points[(a, b)] = (
                points[a] + points[b] + face_points[fs[0]] + face_points[fs[1]]
            ) / 4
    vertex_points = {}
    for v in range(len(points)):
        edges = [e for e in edge_faces if v in e]
        around = sorted({f for e in edges for f in edge_faces[e]})
        creases = [e for e in edges if is_sharp[e]]
        if len(creases) == 2:
            a, b = (e[0] if e[1] == v else e[1] for e in creases)
            vertex_points[v] = (points[a] + 6 * points[v] + points[b]) / 8
        elif len(creases) > 2:
            vertex_points[v] = points[v]
        else:
            n = len(around)
            face_mean = sum(face_points[f] for f in around) / n
            mid_mean = sum((points[e[0]] + points[e[1]]) / 2 for e in edges) / n
            vertex_points[v] = (face_mean + 2 * mid_mean + (n - 3) * points[v]) / n
    return {"vertex": vertex_points, "edge": edge_points, "face": face_points}


def assert_step_matches(mesh: QuadMesh, points: np.ndarray, faces: list[list[int]], sharp=()):
    stepped = catmull_clark_cage(mesh)
    want = textbook_step(points, faces, set(sharp))
    nv = len(points)
    edges = sorted(want["edge"])
    expected = np.concatenate(
        [
            np.array([want["vertex"][v] for v in range(nv)]),
            np.array([want["edge"][e] for e in edges]),
            np.array(want["face"]),
        ]
    )
    scale = np.abs(points).max()
    # each point is a mean of at most ~3n terms, summed in another order: a few ULP of the scale
    np.testing.assert_allclose(stepped.vertices, expected, rtol=0, atol=16 * EPS * scale)
    np.testing.assert_array_equal(stepped.topology.faces, mesh.topology.faces)
    # the same step as a matrix on the cage's points (what limit-interpolate solves through)
    matrix = cage_step_matrix(mesh)
    assert matrix is not None and matrix.shape == (len(expected), nv)
    np.testing.assert_allclose(matrix @ points, expected, rtol=0, atol=16 * EPS * scale)
    np.testing.assert_allclose(matrix.sum(axis=1), 1.0, rtol=0, atol=8 * EPS)


def _octahedron() -> tuple[np.ndarray, list[list[int]]]:
    points = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float
    )
    faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return points, faces


def _mixed_open() -> tuple[np.ndarray, list[list[int]]]:
    """A pentagon ringed by quads and triangles, with a boundary, unequal edges and some height."""
    rng = np.random.default_rng(7)
    angles = np.linspace(0, 2 * np.pi, 5, endpoint=False)
    inner = np.c_[np.cos(angles), np.sin(angles), np.zeros(5)]
    outer = np.c_[2.2 * np.cos(angles + 0.3), 2.0 * np.sin(angles + 0.3), 0.4 * np.ones(5)]
    points = np.vstack([inner, outer]) + 0.05 * rng.normal(size=(10, 3))
    faces = [[0, 1, 2, 3, 4]]
    for i in range(5):
        j = (i + 1) % 5
        faces.append([i, 5 + i, 5 + j, j] if i % 2 == 0 else [i, 5 + i, j])
        if i % 2:
            faces.append([j, 5 + i, 5 + j])
    return points, faces


def test_a_triangle_cage_steps_as_the_textbook() -> None:
    points, faces = _octahedron()
    mesh = QuadMesh.from_arrays(points, faces)
    assert mesh.cage is not None
    assert_step_matches(mesh, points, faces)


def test_a_mixed_cage_with_boundary_steps_as_the_textbook() -> None:
    points, faces = _mixed_open()
    assert_step_matches(QuadMesh.from_arrays(points, faces), points, faces)


def test_infinitely_sharp_creases_step_as_the_textbook() -> None:
    points, faces = _octahedron()
    loop = [(0, 2), (2, 1), (1, 3), (3, 0)]  # the equator
    tags = [Tag("crease", tuple(v for e in loop for v in e), (10.0,))]
    mesh = QuadMesh.from_arrays(points, faces, tags=tags)
    assert_step_matches(mesh, points, faces, {(min(e), max(e)) for e in loop})


def test_quad_meshes_and_new_positions_have_no_cage() -> None:
    quads = QuadMesh.from_arrays(np.eye(4, 3), [[0, 1, 2, 3]])
    assert quads.cage is None and catmull_clark_cage(quads) is quads
    assert cage_step_matrix(quads) is None
    points, faces = _octahedron()
    split = QuadMesh.from_arrays(points, faces)
    assert split.with_vertices(split.vertices).cage is None


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_limit_shape_of_a_polygon_cage_passes_through_its_limit(method: str) -> None:
    """The network's vertices are the cage's Catmull–Clark limit points: those of the textbook
    step's mesh, refined further until the vertices stop moving (4⁻ᵏ)."""
    points, faces = _mixed_open()
    mesh = QuadMesh.from_arrays(points, faces)
    network = build_network(mesh, method, "limit")
    assert check(network).max_edge_angle_deg < 1e-9
    exact = limit_points(catmull_clark_cage(mesh))
    fine = refine(catmull_clark_cage(mesh), 6).vertices[: mesh.n_vertices]
    assert np.abs(fine - exact).max() < 4.0**-5
    corners = network.patches.evaluate(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float))
    nearest, _ = cKDTree(corners.reshape(-1, 3)).query(exact)
    assert nearest.max() <= 64 * EPS * np.abs(points).max()  # a frame's round trip: a few ULP
    # the smooth split's limit is another surface, visibly off on a cage this coarse
    assert np.abs(limit_points(mesh) - exact).max() > 1e-2
