"""Local refinement that stays a quad mesh (``mesh.conforming``): marked faces split into four,
the faces round them closed by the three templates, never a T-junction.

Properties checked on any marking (hypothesis) of meshes with boundaries, holes' worth of
irregular vertices and a closed torus: the result is a valid oriented manifold quad mesh of the
same Euler characteristic (``QuadTopology.from_faces`` refuses anything else), every marked face
is split into four, every face is filled by a template of its own split sides, and in the plane
the quads cover the old faces exactly with positive areas.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.mesh import QuadMesh, QuadTopology
from g1patch.mesh.conforming import local_split, split_sides


def grid(n: int, jitter: float = 0.0) -> QuadMesh:
    """An n × n grid of unit quads in the plane z = 0, interior vertices moved by ``jitter``."""
    x, y = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    inner = (x.ravel() % n != 0) & (y.ravel() % n != 0)
    moved = np.random.default_rng(3).uniform(-jitter, jitter, (int(inner.sum()), 2))
    points[inner, :2] += moved
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    corner = (i * (n + 1) + j).ravel()
    faces = np.stack([corner, corner + n + 1, corner + n + 2, corner + 1], axis=1)
    return QuadMesh.from_arrays(points, faces)


def signed_areas(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Shoelace areas of planar quads (x, y)."""
    x, y = points[faces, 0], points[faces, 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)


MESHES = {
    "grid": grid(8),
    "jittered grid": grid(9, jitter=0.3),
    "torus": shapes.torus_quads(12, 8, 2.0, 0.7),
}


def refined(mesh: QuadMesh, marked: np.ndarray) -> tuple[np.ndarray, np.ndarray, QuadTopology]:
    split = local_split(mesh.topology, marked)
    points = split.weights @ mesh.vertices
    return points, split.faces, QuadTopology.from_faces(split.faces, len(points))


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(sorted(MESHES)), seed=st.integers(0, 2**31), share=st.floats(0, 0.4))
def test_any_marking_gives_a_valid_quad_mesh(name: str, seed: int, share: float) -> None:
    mesh = MESHES[name]
    marked = np.random.default_rng(seed).random(mesh.n_faces) < share
    points, faces, topology = refined(mesh, marked)
    assert topology.euler_characteristic == mesh.topology.euler_characteristic
    split, full = split_sides(mesh.topology, marked)
    parents = local_split(mesh.topology, marked).parent
    children = np.bincount(parents, minlength=mesh.n_faces)
    sides = split[mesh.topology.halfedge_edge.reshape(-1, 4)].sum(axis=1)
    assert np.all(full[marked]) and np.all(children[full] == 4)
    # each face by its split sides: kept (0), halved (2 opposite), three quads (2 adjacent), four
    assert set(sides.tolist()) <= {0, 2, 4} and np.all(children[sides == 0] == 1)
    assert np.all(children[sides == 4] == 4) and np.all(np.isin(children[sides == 2], (2, 3)))
    if name != "torus":  # planar: the new quads tile the old faces, all turned the same way
        areas = signed_areas(points, faces)
        assert np.all(areas > 0)
        assert areas.sum() == pytest.approx(signed_areas(mesh.vertices, mesh.faces).sum())


def test_new_points_are_midpoints_and_centres() -> None:
    """Every new vertex is the mean of two (edge) or four (face) old ones: rows of the weights
    sum to one, old vertices stay where they were."""
    mesh = MESHES["jittered grid"]
    marked = np.zeros(mesh.n_faces, dtype=bool)
    marked[[20, 21, 40]] = True
    split = local_split(mesh.topology, marked)
    weights = split.weights.toarray()
    assert np.allclose(weights.sum(axis=1), 1.0)
    assert np.array_equal(weights[: mesh.n_vertices], np.eye(mesh.n_vertices))
    assert set(np.count_nonzero(weights[mesh.n_vertices :], axis=1).tolist()) <= {2, 4}


def test_one_face_is_closed_by_its_ring_alone() -> None:
    """One face in the middle of a 10 × 10 grid: it becomes 4 quads and its ring of 8 faces is
    closed in pairs by 3-quad corner templates, 6 of them (two ring corners untouched): 100 − 7 +
    4 + 18 = 115 quads, nothing outside the ring changed."""
    mesh = grid(10)
    marked = np.zeros(100, dtype=bool)
    marked[55] = True
    split = local_split(mesh.topology, marked)
    assert len(split.faces) == 115
    changed = np.unique(split.parent[np.bincount(split.parent, minlength=100)[split.parent] > 1])
    ring = {44, 45, 46, 54, 56, 64, 65, 66}
    assert set(changed.tolist()) <= ring | {55} and len(changed) == 7


def test_a_corner_face_closes_through_its_diagonal_neighbour() -> None:
    """The corner face of a 6 × 6 grid: its two neighbours pair through the face diagonal to
    it, all three by corner templates: 36 − 4 + 4 + 9 = 45 quads, nothing else changed."""
    mesh = grid(6)
    marked = np.zeros(36, dtype=bool)
    marked[0] = True
    split = local_split(mesh.topology, marked)
    children = np.bincount(split.parent, minlength=36)
    assert len(split.faces) == 45 and np.flatnonzero(children > 1).tolist() == [0, 1, 6, 7]
    assert np.all(signed_areas(split.weights @ mesh.vertices, split.faces) > 0)
