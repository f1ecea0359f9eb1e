"""Catmull–Clark subdivision as sparse matrices (g1patch.subdivision.matrix): one step, ``levels``
steps and the limit points of the refined grid against refine / refine_grids / limit_points.

Tolerances, relative to the coordinates' scale ``max |x|``: one step ``4 ε``, up to three steps
and their limit points ``8 ε`` (measured at most 1.6 ε, 5.4 ε and 6.0 ε, all on
catmark_xord_interior); row sums 1 to ``8 ε`` for a step, ``16 ε`` for the products (measured 3 ε
and 9 ε)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import shared_data_path

from g1patch import shapes
from g1patch.errors import InputError
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh, Tag
from g1patch.subdivision import (
    boundary_mode,
    limit_grid_matrix,
    limit_matrix,
    limit_points,
    refine,
    refine_grids,
    refine_matrix,
    step_matrix,
)

EPS = float(np.finfo(np.float64).eps)
SHARED = [
    "catmark_cube",
    "catmark_cube_creases2",
    "catmark_dart_edgecorner",
    "catmark_tent_creases1",
    "catmark_torus",
    "catmark_torus_creases0",
    "catmark_xord_boundary",
    "catmark_xord_interior",
]


def jittered(mesh: QuadMesh, seed: int = 0) -> QuadMesh:
    """The mesh with its vertices moved at random (no symmetry to hide a wrong weight)."""
    rng = np.random.default_rng(seed)
    scale = 0.05 * mesh.bounding_box_diagonal
    return mesh.with_vertices(mesh.vertices + scale * rng.standard_normal(mesh.vertices.shape))


def with_tags(mesh: QuadMesh, *tags: Tag) -> QuadMesh:
    return QuadMesh.from_arrays(mesh.vertices, mesh.faces, tags=tags)


def ring_edges(j: int, n_major: int = 8, n_minor: int = 4) -> tuple[int, ...]:
    """The edges of the ring ``v = 2πj/n_minor`` of ``shapes.torus(n_major, n_minor)``, flat."""
    i = np.arange(n_major)
    return tuple(np.stack([i * n_minor + j, (i + 1) % n_major * n_minor + j], axis=1).ravel())


def creased_torus() -> QuadMesh:
    """Infinitely sharp: a crease loop, a third crease edge at its vertex 0 (a corner by count), a
    dart (one sharp edge, 18–19) and a tagged corner (26)."""
    line = ring_edges(0) + (0, 1, 18, 19)
    return with_tags(
        shapes.torus(8, 4),
        Tag("crease", line, (10.0,) * (len(line) // 2)),
        Tag("corner", (26,), (10.0,)),
    )


def semi_sharp_torus(chaikin: bool = False) -> QuadMesh:
    """Semi-sharp: a crease loop of varying sharpness, a fractional dart and a corner of 0.5."""
    line = ring_edges(2) + (16, 17)
    values = (1.5, 2.5, 0.5, 3.0, 1.0, 2.0, 1.25, 2.75, 2.5)
    tags = [Tag("crease", line, values), Tag("corner", (1, 27), (0.5, 10.0))]
    if chaikin:
        tags.append(Tag("creasemethod", strings=("chaikin",)))
    return with_tags(shapes.torus(8, 4), *tags)


def corner_grid() -> QuadMesh:
    mesh = with_tags(shapes.grid(3, 2), Tag("interpolateboundary", (2,)))
    assert boundary_mode(mesh) == "edge-and-corner"
    return mesh


MESHES = {
    "cube": shapes.cube,
    "torus": lambda: shapes.torus(8, 4),
    **{f"fan{n}": (lambda n=n: shapes.fan(n, 2)) for n in range(5, 9)},
    "grid-edge-only": lambda: shapes.grid(3, 2),
    "grid-edge-and-corner": corner_grid,
    "boundary-fan": lambda: shapes.boundary_fan(3),
    "creased-torus": creased_torus,
    "semi-sharp-torus": semi_sharp_torus,
    "semi-sharp-chaikin": lambda: semi_sharp_torus(chaikin=True),
}


def assert_close(actual: np.ndarray, expected: np.ndarray, ulps: float, scale: float) -> None:
    error = np.abs(actual - expected).max()
    assert error <= ulps * EPS * scale, f"{error / (EPS * scale):.2f} ε × scale > {ulps} ε"


def assert_row_sums(matrix, ulps: float) -> None:
    sums = np.asarray(matrix.sum(axis=1)).ravel()
    assert np.abs(sums - 1.0).max() <= ulps * EPS


def check(mesh: QuadMesh, levels: int) -> None:
    """S, R and G of ``mesh`` against the refinement and the limit points."""
    x = mesh.vertices
    scale = float(np.abs(x).max())
    matrix = step_matrix(mesh)
    once = refine(mesh, 1)
    assert matrix.shape == (once.n_vertices, mesh.n_vertices)
    assert matrix.dtype == np.float64
    assert_close(matrix @ x, once.vertices, 4, scale)
    assert_row_sums(matrix, 8)

    chain, fine = refine_matrix(mesh, levels)
    expected, grid = refine_grids(mesh, levels)
    np.testing.assert_array_equal(fine.vertices, expected.vertices)
    np.testing.assert_array_equal(fine.faces, expected.faces)
    assert fine.tags == expected.tags
    assert chain.shape == (expected.n_vertices, mesh.n_vertices)
    assert_close(chain @ x, expected.vertices, 8, scale)
    assert_row_sums(chain, 16)

    limit, limit_grid = limit_grid_matrix(mesh, levels)
    np.testing.assert_array_equal(limit_grid, grid)
    assert limit.shape == chain.shape
    assert_close(limit @ x, limit_points(expected), 8, scale)
    assert_row_sums(limit, 16)


@pytest.mark.parametrize("name", list(MESHES))
def test_matrices_are_refine_and_limit_points(name: str) -> None:
    mesh = jittered(MESHES[name]())
    check(mesh, 2)


@pytest.mark.parametrize("name", SHARED)
def test_matrices_on_the_shared_meshes(name: str) -> None:
    check(read_mesh(shared_data_path(f"{name}.obj")), 3)


@pytest.mark.parametrize("name", ["semi-sharp-torus", "semi-sharp-chaikin", "creased-torus"])
def test_limit_grid_matrix_refines_past_semi_sharp_features(name: str) -> None:
    """At level 0 the limit points of a semi-sharp mesh come from the decayed refinement."""
    mesh = jittered(MESHES[name]())
    matrix, grid = limit_grid_matrix(mesh, 0)
    np.testing.assert_array_equal(grid, mesh.faces[:, [[0, 3], [1, 2]]])
    assert_close(matrix @ mesh.vertices, limit_points(mesh), 8, float(np.abs(mesh.vertices).max()))


def test_no_levels_is_the_identity() -> None:
    mesh = jittered(creased_torus())
    matrix, same = refine_matrix(mesh, 0)
    assert same is mesh
    np.testing.assert_array_equal(matrix.toarray(), np.eye(mesh.n_vertices))
    limit, _ = limit_grid_matrix(mesh, 0)
    np.testing.assert_array_equal(limit.toarray(), limit_matrix(mesh).toarray())


def test_limit_grid_points_sit_at_their_parameters() -> None:
    """``(G x)[grid[f, i, j]]``: the corners of the grid are the limit points of the cage face's
    corners."""
    mesh = jittered(shapes.fan(6, 2))
    matrix, grid = limit_grid_matrix(mesh, 2)
    points = matrix @ mesh.vertices
    corners = points[grid[:, [0, -1, -1, 0], [0, 0, -1, -1]]]
    np.testing.assert_allclose(corners, limit_points(mesh)[mesh.faces], rtol=0, atol=1e-14)


def test_semi_sharp_limit_stencil_raises() -> None:
    mesh = semi_sharp_torus()
    with pytest.raises(InputError, match="edge .* is semi-sharp"):
        limit_matrix(mesh)
    with pytest.raises(InputError, match="vertex 1 is semi-sharp"):
        limit_matrix(with_tags(shapes.torus(8, 4), Tag("corner", (1,), (0.5,))))


@pytest.mark.parametrize("levels", [-1, True, 1.5])
def test_levels_are_checked(levels) -> None:
    with pytest.raises(InputError, match="levels"):
        refine_matrix(shapes.cube(), levels)
    with pytest.raises(InputError, match="levels"):
        limit_grid_matrix(shapes.cube(), levels)
