"""Catmull–Clark refinement and limit stencils (g1patch.subdivision) against B-splines and
OpenSubdiv's limit."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from g1patch.compare import load_reference
from g1patch.errors import InputError
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh, Tag
from g1patch.subdivision import (
    boundary_mode,
    limit_normals,
    limit_points,
    limit_tangents,
    refine,
    refine_grids,
)
from g1patch.targets import halfedge_slots

REFERENCE_MESHES = [
    "catmark_cube",
    "catmark_torus",
    "catmark_xord_interior",
    "catmark_xord_boundary",
    "spot_quadrangulated",
]


def grid_torus(
    n: int = 8, m: int = 6, R: float = 2.0, r: float = 0.7, noise: float = 0.0
) -> QuadMesh:
    """A periodic n × m control grid on a torus; vertex (i, j) is i·m + j, face (i, j) runs (i,j),
    (i+1,j), (i+1,j+1), (i,j+1)."""
    u, v = np.meshgrid(2 * np.pi * np.arange(n) / n, 2 * np.pi * np.arange(m) / m, indexing="ij")
    points = np.stack(
        [(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], axis=-1
    ).reshape(-1, 3)
    points += noise * np.random.default_rng(1).standard_normal(points.shape)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    index = lambda a, b: (a % n) * m + b % m  # noqa: E731
    faces = np.stack(
        [index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)], axis=-1
    ).reshape(-1, 4)
    return QuadMesh.from_arrays(points, faces)


def bspline(t: np.ndarray, derivative: bool = False) -> np.ndarray:
    """Uniform cubic B-spline basis (or its derivative) at t ∈ [0, 1], shape t.shape + (4,)."""
    if derivative:
        return (
            np.stack([-((1 - t) ** 2), 3 * t**2 - 4 * t, -3 * t**2 + 2 * t + 1, t**2], axis=-1) / 2
        )
    return (
        np.stack(
            [(1 - t) ** 3, 3 * t**3 - 6 * t**2 + 4, -3 * t**3 + 3 * t**2 + 3 * t + 1, t**3], axis=-1
        )
        / 6
    )


def torus_surface(
    points: np.ndarray, n: int, m: int, s: np.ndarray, du: int = 0, dv: int = 0
) -> np.ndarray:
    """The uniform bicubic B-spline of the periodic grid at parameters s × s of every face, (n·m, S,
    S, 3)."""
    grid = points.reshape(n, m, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a = np.arange(-1, 3)
    control = grid[
        (i.ravel()[:, None, None] + a[:, None]) % n, (j.ravel()[:, None, None] + a[None, :]) % m
    ]
    return np.einsum("sa,tb,fabd->fstd", bspline(s, du == 1), bspline(s, dv == 1), control)


def test_refined_torus_limit_is_the_bspline() -> None:
    mesh = grid_torus(noise=0.05)
    s = np.linspace(0.0, 1.0, 5)
    fine, grid = refine_grids(mesh, 2)
    np.testing.assert_allclose(
        limit_points(fine)[grid], torus_surface(mesh.vertices, 8, 6, s), atol=1e-13
    )
    np.testing.assert_allclose(
        limit_points(mesh), torus_surface(mesh.vertices, 8, 6, np.zeros(1))[:, 0, 0], atol=1e-13
    )


def test_torus_tangents_are_the_bspline_hermite_tangents() -> None:
    mesh = grid_torus(noise=0.05)
    topology = mesh.topology
    slot_out, _ = halfedge_slots(topology)
    t = limit_tangents(mesh)[slot_out].reshape(-1, 4, 3)  # per face corner k, along edge k
    zero = np.zeros(1)
    du = torus_surface(mesh.vertices, 8, 6, zero, du=1)[:, 0, 0]  # at corner 0 along edge 0
    dv = torus_surface(mesh.vertices, 8, 6, zero, dv=1)[:, 0, 0]
    np.testing.assert_allclose(t[:, 0], du, atol=1e-13)
    # corner 0's edge 3 runs corner 3 → corner 0; the slot of corner 0 towards corner 3 is the
    # reverse of that edge
    _, slot_in = halfedge_slots(topology)
    np.testing.assert_allclose(
        limit_tangents(mesh)[slot_in[4 * np.arange(topology.n_faces) + 3]], dv, atol=1e-13
    )
    normals = np.cross(du, dv)
    np.testing.assert_allclose(
        limit_normals(mesh), normals / np.linalg.norm(normals, axis=1, keepdims=True), atol=1e-12
    )


def test_limit_points_are_invariant_under_refinement_and_vertices_converge(shared_data) -> None:
    mesh = read_mesh(shared_data / "catmark_cube.obj")
    limit = limit_points(mesh)
    errors = []
    for levels in (1, 2, 3, 4):
        fine = refine(mesh, levels)
        np.testing.assert_allclose(limit_points(fine)[: mesh.n_vertices], limit, atol=1e-12)
        errors.append(np.linalg.norm(fine.vertices[: mesh.n_vertices] - limit, axis=1).max())
    assert all(b < 0.5 * a for a, b in itertools.pairwise(errors))


@pytest.mark.parametrize("name", REFERENCE_MESHES)
def test_limit_points_match_opensubdiv(shared_data, name: str) -> None:
    """≤ 1e-6 of the diagonal, but at the one-face boundary corners of the edge-only xord shapes,
    where the reference (Blender's patch evaluation, which approximates that irregular corner)
    is 1e-5 off the exact crease limit ``(A + 4V + B)/6`` of the boundary B-spline."""
    mesh = read_mesh(shared_data / f"{name}.obj")
    reference = load_reference(shared_data / "reference" / f"{name}.limit.npz")
    error = (
        np.linalg.norm(limit_points(mesh) - reference.points[: mesh.n_vertices], axis=1)
        / reference.bounding_box_diagonal
    )
    topology = mesh.topology
    corner = topology.is_boundary_vertex & (topology.face_count == 1)
    assert error[~corner].max() <= 1e-6
    assert error[corner].max(initial=0.0) <= 2e-5


def square_grid(size: int = 3, tags: tuple[Tag, ...] = ()) -> QuadMesh:
    i, j = np.meshgrid(np.arange(size + 1), np.arange(size + 1), indexing="ij")
    points = np.stack([i, j, np.sin(i + 2.0 * j)], axis=-1).reshape(-1, 3).astype(float)
    index = lambda a, b: a * (size + 1) + b  # noqa: E731
    a, b = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
    faces = np.stack(
        [index(a, b), index(a + 1, b), index(a + 1, b + 1), index(a, b + 1)], axis=-1
    ).reshape(-1, 4)
    return QuadMesh.from_arrays(points, faces, tags=tags)


def test_boundary_modes() -> None:
    edge_only = square_grid()
    corners = square_grid(tags=(Tag("interpolateboundary", (2,)),))
    assert boundary_mode(edge_only) == "edge-only" and boundary_mode(corners) == "edge-and-corner"
    assert boundary_mode(square_grid(tags=(Tag("interpolateboundary", (0,)),))) == "edge-only"
    x = edge_only.vertices
    one_face = np.flatnonzero(edge_only.topology.face_count == 1)
    limit = limit_points(edge_only)
    for v in one_face:
        a, b = edge_only.topology.one_ring(v)
        np.testing.assert_allclose(limit[v], (x[a] + 4 * x[v] + x[b]) / 6, atol=1e-14)
    np.testing.assert_array_equal(limit_points(corners)[one_face], x[one_face])
    np.testing.assert_array_equal(refine(corners, 2).vertices[one_face], x[one_face])
    # the boundary of a refined edge-only grid keeps its B-spline: limit points unchanged
    np.testing.assert_allclose(limit_points(refine(edge_only))[: len(x)], limit, atol=1e-13)
    np.testing.assert_allclose(
        limit_points(refine(corners))[: len(x)], limit_points(corners), atol=1e-13
    )


def test_sharp_creases_follow_the_crease_rule() -> None:
    mesh = grid_torus()
    sharpness = np.zeros(mesh.n_edges)
    ring = (
        mesh.topology.edges[:, 0] // 6 == mesh.topology.edges[:, 1] // 6
    )  # edges within one ring i = const
    crease = ring & (mesh.topology.edges[:, 0] // 6 == 0)
    sharpness[crease] = 10.0
    limit = limit_points(mesh, sharpness)
    x = mesh.vertices
    v = np.arange(6)
    np.testing.assert_allclose(
        limit[v], (x[(v + 1) % 6] + 4 * x[v] + x[(v - 1) % 6]) / 6, atol=1e-14
    )
    fine = refine(mesh, 1, sharpness)
    np.testing.assert_allclose(
        fine.vertices[v], (x[(v + 1) % 6] + 6 * x[v] + x[(v - 1) % 6]) / 8, atol=1e-14
    )
    # semi-sharp (tests/test_subdivision_creases.py): s = 2 is two steps of the crease rule, then
    # smooth
    semi = np.where(crease, 2.0, 0.0)
    np.testing.assert_allclose(
        refine(mesh, 2, semi).vertices, refine(mesh, 2, sharpness).vertices, atol=1e-14
    )
    with pytest.raises(InputError, match="sharpness"):
        refine(mesh, 1, np.where(crease, -1.0, 0.0))


def _stencil_cages(shared_data) -> list[QuadMesh]:
    """Shared meshes (creases, darts, corners, boundaries) and generated cages with valences 3 to
    7."""
    from g1patch import shapes

    meshes = [read_mesh(path) for path in sorted(shared_data.glob("*.obj"))]
    torus = grid_torus(noise=0.05)
    corner_tag = Tag("corner", (3, 20), (10.0, 2.5))
    return meshes + [
        refine(shapes.genus2(), 1),
        shapes.fan(7, 2),
        shapes.boundary_fan(3),
        shapes.noisy_sphere(2),
        QuadMesh(
            torus.vertices,
            torus.topology,
            (corner_tag, Tag("crease", (0, 1, 1, 2, 2, 3), (10.0, 10.0, 0.5))),
            torus.source,
        ),
    ]


def test_stencil_kernels_equal_the_numpy_reference_bit_for_bit(shared_data) -> None:
    """The numba kernels of the smooth vertices' limit stencils add in the reference's order, so
    positions, stars, slot tangents and sector normals are the same floats, not merely close."""
    from g1patch.subdivision.features import _level_of
    from g1patch.subdivision.stencils import _limit_frames, _limit_positions

    for mesh in _stencil_cages(shared_data):
        level = _level_of(mesh)
        if level.semi_sharp:  # the masks hold on the decayed refinement
            level = _level_of(refine(mesh, 3))
        np.testing.assert_array_equal(
            _limit_positions(level, compiled=True), _limit_positions(level, compiled=False)
        )
        kernel, numpy = (
            _limit_frames(level, corners=True, compiled=True),
            _limit_frames(level, corners=True, compiled=False),
        )
        for name in ("tangents", "a", "b", "ring_normals"):
            np.testing.assert_array_equal(getattr(kernel, name), getattr(numpy, name), err_msg=name)


def test_public_limits_with_kernels_equal_those_without(shared_data, monkeypatch) -> None:
    """:func:`limit_data` and :func:`limit_corner_normals` above and below the kernels' size
    threshold, semi-sharp meshes included (their refined neighbourhood takes the same path)."""
    import g1patch.subdivision as subdivision

    for mesh in _stencil_cages(shared_data):
        monkeypatch.setattr(subdivision, "KERNEL_VERTICES", 10**9)
        before = subdivision.limit_data(mesh), subdivision.limit_corner_normals(mesh)
        monkeypatch.setattr(subdivision, "KERNEL_VERTICES", 0)
        after = subdivision.limit_data(mesh), subdivision.limit_corner_normals(mesh)
        for name, old, new in zip(
            (*before[0]._fields, "corner normals"),
            (*before[0], before[1]),
            (*after[0], after[1]),
            strict=True,
        ):
            np.testing.assert_array_equal(new, old, err_msg=name)
