"""Tessellation: watertight by construction, points on the surface, collapsed edges welded."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from g1patch import shapes
from g1patch.construct.corner import build_corner_network
from g1patch.errors import InputError
from g1patch.io.bpt import read_bpt
from g1patch.io.meshfile import read_mesh
from g1patch.network import network_from_patch_points
from g1patch.tessellate import TriangleMesh, tessellate


def edge_use_counts(mesh: TriangleMesh) -> tuple[np.ndarray, np.ndarray]:
    """Undirected triangle edges and how many triangles use each; also directed-edge repeats."""
    t = mesh.triangles
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    _, counts = np.unique(undirected, axis=0, return_counts=True)
    _, directed_counts = np.unique(directed, axis=0, return_counts=True)
    return counts, directed_counts


def assert_watertight(mesh: TriangleMesh) -> None:
    counts, directed = edge_use_counts(mesh)
    assert (counts == 2).all(), f"edges with {sorted(set(counts.tolist()))} triangles"
    assert (directed == 1).all(), "an edge is used twice in the same direction: orientation broken"


@pytest.mark.parametrize(
    "mesh",
    [shapes.cube(), shapes.torus(8, 5), shapes.genus2(), shapes.cube_sphere(2)],
    ids=["cube", "torus", "genus2", "sphere"],
)
@pytest.mark.parametrize("resolution", [2, 3, 9])
def test_closed_networks_tessellate_watertight(mesh, resolution: int) -> None:  # type: ignore[no-untyped-def]
    surface = tessellate(build_corner_network(mesh), resolution)
    assert_watertight(surface)
    chi = len(surface.points) - len(edge_use_counts(surface)[0]) + len(surface.triangles)
    assert chi == mesh.topology.euler_characteristic


@pytest.mark.parametrize("name", ["catmark_cube", "catmark_torus", "spot_quadrangulated"])
def test_closed_shared_meshes_tessellate_watertight(shared_data: Path, name: str) -> None:
    assert_watertight(tessellate(build_corner_network(read_mesh(shared_data / f"{name}.obj")), 5))


def test_open_network_has_a_boundary_of_the_expected_length() -> None:
    mesh = shapes.grid(3, 2)
    resolution = 5
    surface = tessellate(build_corner_network(mesh), resolution)
    counts, _ = edge_use_counts(surface)
    boundary_edges = int(mesh.topology.is_boundary_edge.sum())
    assert (counts == 1).sum() == boundary_edges * (resolution - 1)
    assert set(counts.tolist()) <= {1, 2}


def test_points_lie_on_the_patches_and_normals_are_unit() -> None:
    network = build_corner_network(shapes.torus(6, 4))
    resolution = 7
    surface = tessellate(network, resolution)
    grid = np.linspace(0.0, 1.0, resolution)
    sampled = network.patches.evaluate_grid(grid).reshape(-1, 3)
    # every point is one of the grid samples (welded points come from one of the patches,
    # which agree to the G0 gap, here exact)
    distance = np.min(
        np.linalg.norm(surface.points[:, None, :] - sampled[None, :, :], axis=-1), axis=1
    )
    assert distance.max() <= 1e-15
    np.testing.assert_allclose(np.linalg.norm(surface.normals, axis=1), 1.0, rtol=1e-15, atol=4e-16)


def test_triangles_face_like_the_surface_normals() -> None:
    surface = tessellate(build_corner_network(shapes.cube_sphere(1)), 5)
    p = surface.points[surface.triangles]
    face_normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert (
        np.einsum("td,td->t", face_normals, surface.normals[surface.triangles].mean(axis=1)) > 0
    ).all()


def test_teapot_collapsed_edges_are_welded(shared_data: Path) -> None:
    surface = tessellate(network_from_patch_points(read_bpt(shared_data / "teapot.bpt")), 9)
    t = surface.triangles
    assert ((t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])).all()
    counts, _ = edge_use_counts(surface)
    assert set(counts.tolist()) <= {1, 2}  # open at the rim, spout, handle ends; never 3


@pytest.mark.parametrize("resolution", [1, 0, 2.5])
def test_bad_resolution(resolution) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(InputError, match="resolution"):
        tessellate(build_corner_network(shapes.cube()), resolution)
