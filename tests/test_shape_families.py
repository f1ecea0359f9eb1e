"""Generated refinement families and fold-provoking cages: counts, closedness, valences,
orientation, and the exact closest-point helpers of the smooth surfaces they are sampled from."""

from __future__ import annotations

import numpy as np
import pytest

from g1patch import shapes
from g1patch.errors import InputError
from g1patch.mesh import QuadMesh

AXES = np.array([1.0, 0.7, 0.5])


def signed_volume(mesh: QuadMesh) -> float:
    """Σ det(p0, p1, p2) + det(p0, p2, p3) over the quads, / 6: positive when faces point
    outward."""
    p = mesh.vertices[mesh.faces]
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])) + np.einsum(
        "ij,ij->i", p[:, 0], np.cross(p[:, 2], p[:, 3])
    )
    return float(volume.sum() / 6.0)


def valences(mesh: QuadMesh, boundary: bool = False) -> dict[int, int]:
    topology = mesh.topology
    values, counts = np.unique(
        topology.valence[topology.is_boundary_vertex == boundary], return_counts=True
    )
    return dict(zip(values.tolist(), counts.tolist(), strict=True))


def edge_lengths(mesh: QuadMesh) -> np.ndarray:
    ends = mesh.vertices[mesh.topology.edges]
    return np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)


@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_sphere_quads(level: int) -> None:
    mesh = shapes.sphere_quads(level)
    assert (
        mesh.n_faces == 6 * 4**level
        and mesh.topology.is_closed
        and mesh.topology.euler_characteristic == 2
    )
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 1.0, rtol=0, atol=1e-15)
    assert valences(mesh) == ({3: 8} if level == 0 else {3: 8, 4: mesh.n_vertices - 8})
    assert signed_volume(mesh) > 0


def test_sphere_quads_projects_after_each_split() -> None:
    """Level 1 equals cube_sphere(1) (one split, one projection); from level 2 the edge midpoints
    are taken on the sphere, so the quads are more even than cube_sphere's."""
    np.testing.assert_allclose(
        shapes.sphere_quads(1).vertices, shapes.cube_sphere(1).vertices, atol=1e-15
    )
    fine, once = shapes.sphere_quads(3), shapes.cube_sphere(3)
    assert not np.allclose(fine.vertices, once.vertices)
    spread = [lengths.max() / lengths.min() for lengths in (edge_lengths(fine), edge_lengths(once))]
    assert spread[0] < spread[1]


@pytest.mark.parametrize("level", [1, 2])
def test_ellipsoid_quads_lie_on_the_ellipsoid(level: int) -> None:
    mesh = shapes.ellipsoid_quads(level, AXES)
    np.testing.assert_allclose(((mesh.vertices / AXES) ** 2).sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(mesh.vertices, shapes.sphere_quads(level).vertices * AXES)
    assert mesh.topology.is_closed and signed_volume(mesh) > 0


def test_torus_quads() -> None:
    mesh = shapes.torus_quads(12, 6)
    assert (mesh.n_faces, mesh.topology.euler_characteristic) == (72, 0)
    assert valences(mesh) == {4: 72}
    rho = np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1])
    np.testing.assert_allclose(np.hypot(rho - 2.0, mesh.vertices[:, 2]), 0.7)
    assert 0 < signed_volume(mesh) < 2 * np.pi**2 * 2.0 * 0.7**2  # outward, inscribed in the torus


@pytest.mark.parametrize("level", [0, 1, 2])
def test_icosa_ellipsoid(level: int) -> None:
    mesh = shapes.icosa_ellipsoid(level, AXES)
    assert (
        mesh.n_faces == 60 * 4**level
        and mesh.topology.is_closed
        and mesh.topology.euler_characteristic == 2
    )
    found = valences(mesh)
    assert (found[3], found[5]) == (20, 12) and set(found) == {3, 4, 5}
    np.testing.assert_allclose(((mesh.vertices / AXES) ** 2).sum(axis=1), 1.0, atol=1e-14)
    assert signed_volume(mesh) > 0


def test_box_cage_alternates_short_and_long_edges() -> None:
    mesh = shapes.box_cage((4.0, 1.0, 0.3), (8, 4, 2))
    assert mesh.topology.is_closed and mesh.topology.euler_characteristic == 2
    assert mesh.n_faces == 2 * (8 * 4 + 8 * 2 + 4 * 2)
    assert signed_volume(mesh) == pytest.approx(4.0 * 1.0 * 0.3)
    np.testing.assert_allclose(mesh.bounding_box[1] - mesh.bounding_box[0], [4.0, 1.0, 0.3])
    x = np.unique(mesh.vertices[:, 0])
    steps = np.diff(x)
    np.testing.assert_allclose(steps[1:] / steps[:-1], np.where(np.arange(7) % 2 == 0, 4.0, 0.25))


def test_box_cage_jitter_is_seeded_and_small() -> None:
    plain = shapes.box_cage()
    a, b = shapes.box_cage(jitter_seed=3), shapes.box_cage(jitter_seed=3)
    np.testing.assert_array_equal(a.vertices, b.vertices)
    moved = np.abs(a.vertices - plain.vertices)
    assert 0 < moved.max() <= 0.1 * edge_lengths(plain).min()


def test_thin_slab() -> None:
    mesh = shapes.thin_slab((2.0, 1.0), 0.05, (8, 4), rim=2)
    assert mesh.topology.is_closed and mesh.n_faces == 2 * (8 * 4 + 8 * 2 + 4 * 2)
    assert signed_volume(mesh) == pytest.approx(2.0 * 1.0 * 0.05)
    assert set(np.round(np.unique(mesh.vertices[:, 2]), 12)) == {-0.025, 0.0, 0.025}


def test_noisy_sphere() -> None:
    plain = shapes.sphere_quads(2)
    noisy = shapes.noisy_sphere(2, noise=0.08, seed=5)
    moved = np.abs(noisy.vertices - plain.vertices)
    assert 0 < moved.max() <= 0.08 * edge_lengths(plain).min()
    np.testing.assert_array_equal(
        noisy.vertices, shapes.noisy_sphere(2, noise=0.08, seed=5).vertices
    )
    assert noisy.topology.is_closed and signed_volume(noisy) > 0
    with pytest.raises(InputError, match="noise"):
        shapes.noisy_sphere(1, noise=0.7)


@pytest.mark.parametrize("valence", [3, 5, 17, 360])
def test_flat_fan(valence: int) -> None:
    mesh = shapes.flat_fan(valence)
    assert mesh.n_faces == valence and not mesh.topology.is_closed
    assert valences(mesh) == {valence: 1}
    assert valences(mesh, boundary=True) == {2: valence, 3: valence}
    np.testing.assert_array_equal(mesh.vertices[:, 2], 0.0)
    p = mesh.vertices[mesh.faces][:, :, :2]
    q = np.roll(p, -1, axis=1)
    a, b = q - p, np.roll(q, -1, axis=1) - q
    turn = (
        a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    )  # z of the turn at every corner: all left turns = convex
    assert (turn > 0).all()


# -- exact closest points
# ---------------------------------------------------------------------------


def near_points(seed: int, count: int = 2000) -> np.ndarray:
    """Random directions scaled to radius 0.6 … 1.6 (inside and outside the unit-sized surfaces)."""
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(count, 3))
    return (
        directions
        / np.linalg.norm(directions, axis=1, keepdims=True)
        * rng.uniform(0.6, 1.6, (count, 1))
    )


def assert_closest(
    points: np.ndarray, closest: np.ndarray, normals: np.ndarray, gradient: np.ndarray
) -> None:
    """Normals unit, along the surface gradient at the closest point (outward), and p − q along the
    normal."""
    np.testing.assert_allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-15)
    unit_gradient = gradient / np.linalg.norm(gradient, axis=-1, keepdims=True)
    np.testing.assert_allclose(normals, unit_gradient, atol=1e-14)
    offset = points - closest
    np.testing.assert_allclose(np.linalg.norm(np.cross(offset, normals), axis=-1), 0.0, atol=1e-13)


def test_sphere_project() -> None:
    points = near_points(0)
    closest, normals = shapes.sphere_project(points, radius=2.0)
    np.testing.assert_allclose(np.linalg.norm(closest, axis=1), 2.0)
    assert_closest(points, closest, normals, closest)


def test_ellipsoid_project() -> None:
    points = near_points(1) * AXES
    closest, normals = shapes.ellipsoid_project(points, AXES)
    np.testing.assert_allclose(((closest / AXES) ** 2).sum(axis=-1), 1.0, atol=1e-14)
    assert_closest(points, closest, normals, closest / AXES**2)


def test_ellipsoid_project_is_the_nearest_point() -> None:
    """No point of a dense sampling of the ellipsoid is nearer than the projection."""
    points = near_points(2, 50) * AXES
    closest, _ = shapes.ellipsoid_project(points, AXES)
    surface = shapes.ellipsoid_quads(5, AXES).vertices
    sampled = np.linalg.norm(points[:, None] - surface[None], axis=-1).min(axis=1)
    exact = np.linalg.norm(points - closest, axis=1)
    assert (exact <= sampled + 1e-12).all()
    assert (sampled - exact).max() < 0.01  # the sampling's spacing is about 0.02


def test_ellipsoid_project_keeps_batch_shape() -> None:
    closest, normals = shapes.ellipsoid_project(near_points(3, 12).reshape(3, 4, 3), AXES)
    assert closest.shape == normals.shape == (3, 4, 3)


def test_torus_project() -> None:
    rng = np.random.default_rng(4)
    u, v = rng.uniform(0, 2 * np.pi, (2, 2000))
    radius = rng.uniform(0.2, 1.2, 2000)  # around the tube, inside and outside it
    ring = 2.0 + radius * 0.7 * np.cos(v)
    points = np.stack([ring * np.cos(u), ring * np.sin(u), radius * 0.7 * np.sin(v)], axis=1)
    closest, normals = shapes.torus_project(points, 2.0, 0.7)
    rho = np.hypot(closest[:, 0], closest[:, 1])
    np.testing.assert_allclose(np.hypot(rho - 2.0, closest[:, 2]), 0.7)
    # gradient of (rho − R)² + z² − r²
    gradient = np.stack(
        [(rho - 2.0) * closest[:, 0] / rho, (rho - 2.0) * closest[:, 1] / rho, closest[:, 2]],
        axis=1,
    )
    assert_closest(points, closest, normals, gradient)
    np.testing.assert_allclose(
        np.linalg.norm(points - closest, axis=1), np.abs(radius - 1.0) * 0.7, atol=1e-14
    )
