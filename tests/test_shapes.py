"""Generated shapes: counts, orientation (outward / +z), geometry, and one Catmull–Clark topology
step."""

from __future__ import annotations

import numpy as np
import pytest

from g1patch import shapes
from g1patch.errors import InputError, NonManifoldError
from g1patch.mesh import QuadMesh


def signed_volume(mesh: QuadMesh) -> float:
    """Σ over the triangles (p0, p1, p2), (p0, p2, p3) of det(a, b, c) / 6: positive when faces
    point outward."""
    p = mesh.vertices[mesh.faces]
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2]))
    volume += np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 2], p[:, 3]))
    return float(volume.sum() / 6.0)


def signed_areas_xy(mesh: QuadMesh) -> np.ndarray:
    """Shoelace area of each face projected on the xy plane: positive when counter-clockwise seen
    from +z."""
    p = mesh.vertices[mesh.faces][:, :, :2]
    q = np.roll(p, -1, axis=1)
    return 0.5 * (p[:, :, 0] * q[:, :, 1] - q[:, :, 0] * p[:, :, 1]).sum(axis=1)


def counts(mesh: QuadMesh) -> tuple[int, int, int, int]:
    t = mesh.topology
    return t.n_vertices, t.n_edges, t.n_faces, int(np.count_nonzero(t.is_boundary_edge))


def test_cube() -> None:
    mesh = shapes.cube()
    assert counts(mesh) == (8, 12, 6, 0)
    np.testing.assert_array_equal(np.abs(mesh.vertices), 1.0)
    assert signed_volume(mesh) == pytest.approx(8.0)
    normals = np.cross(
        *(
            mesh.vertices[mesh.faces[:, 2]] - mesh.vertices[mesh.faces[:, 0]],
            mesh.vertices[mesh.faces[:, 3]] - mesh.vertices[mesh.faces[:, 1]],
        )
    )
    centres = mesh.vertices[mesh.faces].mean(axis=1)
    np.testing.assert_allclose(
        normals / np.linalg.norm(normals, axis=1, keepdims=True), centres
    )  # outward


@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_cube_sphere(level: int) -> None:
    mesh = shapes.cube_sphere(level)
    n_faces = 6 * 4**level
    assert counts(mesh) == (n_faces + 2, 2 * n_faces, n_faces, 0)
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 1.0, rtol=0, atol=1e-15)
    assert signed_volume(mesh) > 0
    assert mesh.topology.euler_characteristic == 2
    assert (mesh.topology.valence[:8] == 3).all() and (mesh.topology.valence[8:] == 4).all()


def test_cube_sphere_level_0_is_the_scaled_cube() -> None:
    np.testing.assert_allclose(
        shapes.cube_sphere(0).vertices, shapes.cube().vertices / np.sqrt(3.0)
    )
    assert [shapes.cube_sphere(level).n_faces for level in (1, 2, 3)] == [24, 96, 384]


def test_grid_and_strip() -> None:
    mesh = shapes.grid(4, 3, size=(2.0, 3.0), height=lambda x, y: x * y)
    assert counts(mesh) == (20, 31, 12, 14)
    assert mesh.topology.euler_characteristic == 1 and len(mesh.topology.boundary_loops()) == 1
    np.testing.assert_allclose(mesh.vertices[-1], [2.0, 3.0, 6.0])
    np.testing.assert_allclose(mesh.vertices[:, 2], mesh.vertices[:, 0] * mesh.vertices[:, 1])
    np.testing.assert_allclose(signed_areas_xy(mesh), 0.5)
    strip = shapes.strip(5)
    assert counts(strip) == (12, 16, 5, 12)
    np.testing.assert_allclose(signed_areas_xy(strip), 1.0)


def test_torus() -> None:
    R, r = 2.0, 0.5
    mesh = shapes.torus(12, 6, R, r)
    assert counts(mesh) == (72, 144, 72, 0)
    assert mesh.topology.euler_characteristic == 0 and (mesh.topology.valence == 4).all()
    x, y, z = mesh.vertices.T
    np.testing.assert_allclose((np.hypot(x, y) - R) ** 2 + z**2, r**2)
    assert signed_volume(mesh) > 0


def test_large_torus_size() -> None:
    mesh = shapes.large_torus(4000)
    assert mesh.n_faces == 4000 and mesh.topology.is_closed


@pytest.mark.parametrize(("valence", "rings"), [(3, 1), (4, 2), (6, 1), (12, 3)])
def test_fan(valence: int, rings: int) -> None:
    mesh = shapes.fan(valence, rings)
    t = mesh.topology
    assert t.valence[0] == valence and not t.is_boundary_vertex[0]
    assert t.n_faces == valence + 2 * valence * (rings - 1)
    assert t.euler_characteristic == 1 and len(t.boundary_loops()) == 1
    assert (signed_areas_xy(mesh) > 0).all()
    np.testing.assert_array_equal(mesh.vertices[:, 2], 0.0)


@pytest.mark.parametrize("k", [1, 2, 3, 6])
def test_boundary_fan(k: int) -> None:
    mesh = shapes.boundary_fan(k)
    t = mesh.topology
    assert t.is_boundary_vertex[0] and t.face_count[0] == k and t.valence[0] == k + 1
    assert counts(mesh) == (2 * k + 2, 3 * k + 1, k, 2 * k + 2)
    assert (signed_areas_xy(mesh) > 0).all()


def test_genus2() -> None:
    mesh = shapes.genus2()
    t = mesh.topology
    assert t.is_closed and t.n_components == 1 and t.euler_characteristic == -2
    assert signed_volume(mesh) == pytest.approx(13.0)  # 15 unit cubes less the 2 holes
    low, high = mesh.bounding_box
    np.testing.assert_array_equal(low, [-2.5, -1.5, -0.5])
    np.testing.assert_array_equal(high, [2.5, 1.5, 0.5])


def test_voxel_surface_of_one_cube_is_the_unit_cube() -> None:
    mesh = shapes.voxel_surface(np.ones((1, 1, 1), dtype=bool))
    assert counts(mesh) == (8, 12, 6, 0)
    assert signed_volume(mesh) == pytest.approx(1.0)


def test_voxel_surface_rejects_cubes_touching_along_an_edge() -> None:
    filled = np.zeros((2, 2, 1), dtype=bool)
    filled[0, 0, 0] = filled[1, 1, 0] = True
    with pytest.raises(NonManifoldError, match=r"edge \(\d+, \d+\) is used by 4 faces"):
        shapes.voxel_surface(filled)


def test_subdivide_is_linear() -> None:
    """Old vertices stay, new ones sit at edge midpoints and face centroids; a planar grid keeps its
    area."""
    mesh = shapes.grid(2, 3, height=lambda x, y: 0 * x)
    refined = shapes.subdivide(mesh)
    t = mesh.topology
    np.testing.assert_array_equal(refined.vertices[: t.n_vertices], mesh.vertices)
    midpoints = mesh.vertices[t.edges].mean(axis=1)
    np.testing.assert_allclose(refined.vertices[t.n_vertices : t.n_vertices + t.n_edges], midpoints)
    np.testing.assert_allclose(
        refined.vertices[t.n_vertices + t.n_edges :], mesh.vertices[mesh.faces].mean(axis=1)
    )
    assert signed_areas_xy(refined).sum() == pytest.approx(signed_areas_xy(mesh).sum())
    assert (signed_areas_xy(refined) > 0).all()


def test_subdivide_keeps_closed_shapes_outward() -> None:
    refined = shapes.subdivide(shapes.torus(6, 4))
    assert signed_volume(refined) > 0 and refined.n_faces == 96


@pytest.mark.parametrize(
    "call",
    [
        lambda: shapes.grid(0, 2),
        lambda: shapes.torus(2, 5),
        lambda: shapes.fan(2),
        lambda: shapes.fan(4, rings=0),
        lambda: shapes.boundary_fan(0),
        lambda: shapes.cube_sphere(-1),
        lambda: shapes.grid(2.5, 2),
    ],
)
def test_invalid_arguments(call) -> None:
    with pytest.raises(InputError, match="expected an integer"):
        call()


def test_bump_sphere_scan() -> None:
    """A closed, outward triangle scan: every edge in two triangles, opposite ways; the volume
    (divergence theorem) above the unit ball's; the bump's tip at 1 + height on the z axis."""
    points, triangles = shapes.bump_sphere_scan(2_000, 0.4, 0.1)
    assert triangles.shape == (2 * 2_000 - 4, 3)
    directed = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)  # no edge twice the same way
    a, b, c = (points[triangles[:, k]] for k in range(3))
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    assert 4.0 / 3.0 * np.pi * 0.99 < volume < 4.0 / 3.0 * np.pi * 1.02
    first = np.arccos(1.0 - 1.0 / 2_000)  # the point nearest the pole, 0.032 rad from it
    tip = 1.0 + 0.4 * np.exp(-((first / 0.1) ** 2))
    assert np.linalg.norm(points, axis=1).max() == pytest.approx(tip, rel=1e-12)
