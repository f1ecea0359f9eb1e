"""Vertex frames: exact on spheres, O(h³)-type normals on smooth meshes, fan normal where the fit is
not trusted."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from g1patch import shapes
from g1patch.mesh import QuadMesh
from g1patch.targets.frame_fit import CUBIC_POINTS, _face_rings, _fit_all, _Ring
from g1patch.targets.frame_kernels import SMALL_RING
from g1patch.targets.frames import (
    MAX_TILT,
    VertexFrames,
    _face_ring_rows,
    _fit_compiled,
    vertex_frames,
)
from g1patch.targets.local import fan_normals

AXES = np.array([1.0, 0.7, 0.5])


def angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(
        np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("vd,vd->v", a, b))
    )


def tangent_projector(n: np.ndarray) -> np.ndarray:
    return np.eye(3) - n[:, :, None] * n[:, None, :]


def ellipsoid(level: int) -> tuple[QuadMesh, np.ndarray]:
    mesh = shapes.cube_sphere(level)
    x = mesh.vertices * AXES
    n = x / AXES**2
    return mesh.with_vertices(x), n / np.linalg.norm(n, axis=1, keepdims=True)


def torus(
    n_major: int, n_minor: int, R: float = 2.0, r: float = 0.7
) -> tuple[QuadMesh, np.ndarray, np.ndarray]:
    """The mesh, exact normals and exact shape operators (principal curvatures 1/r and cos φ/(R + r
    cos φ))."""
    mesh = shapes.torus(n_major, n_minor, R, r)
    u = np.repeat(np.linspace(0.0, 2.0 * np.pi, n_major, endpoint=False), n_minor)
    phi = np.tile(np.linspace(0.0, 2.0 * np.pi, n_minor, endpoint=False), n_major)
    n = np.stack([np.cos(phi) * np.cos(u), np.cos(phi) * np.sin(u), np.sin(phi)], axis=1)
    t_u = np.stack([-np.sin(u), np.cos(u), 0.0 * u], axis=1)
    t_phi = np.stack([-np.sin(phi) * np.cos(u), -np.sin(phi) * np.sin(u), np.cos(phi)], axis=1)
    s = (
        t_phi[:, :, None] * t_phi[:, None, :] / r
        + (np.cos(phi) / (R + r * np.cos(phi)))[:, None, None] * t_u[:, :, None] * t_u[:, None, :]
    )
    return mesh, n, s


def goes_once_around(mesh: QuadMesh, v: int, n: np.ndarray) -> bool:
    """The ring edges of interior vertex ``v`` projected on the plane ⊥ n turn CCW and once
    around."""
    d = mesh.vertices[mesh.topology.one_ring(v)] - mesh.vertices[v]
    e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    angles = np.arctan2(d @ e2, d @ e1)
    turns = (np.diff(np.append(angles, angles[0])) + np.pi) % (2.0 * np.pi) - np.pi
    return bool((turns > 0).all() and abs(turns.sum() - 2.0 * np.pi) < 1e-9)


def check_invariants(frames: VertexFrames) -> None:
    n, s = frames.normals, frames.shape_operator
    assert np.isfinite(n).all() and np.isfinite(s).all()
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(s, s.transpose(0, 2, 1), atol=1e-14)
    np.testing.assert_allclose(
        np.einsum("vij,vj->vi", s, n), 0.0, atol=1e-12 * max(1.0, np.abs(s).max())
    )


@pytest.mark.parametrize("level", range(5))
def test_sphere_is_exact(level: int) -> None:
    mesh = shapes.cube_sphere(level)  # level 0: the cube's 8 valence-3 vertices on the sphere
    frames = vertex_frames(mesh)
    check_invariants(frames)
    assert frames.fitted.all() and not frames.repaired.any()
    np.testing.assert_allclose(frames.normals, mesh.vertices, atol=1e-12)
    np.testing.assert_allclose(frames.shape_operator, tangent_projector(mesh.vertices), atol=1e-12)


def test_cube_on_a_moved_sphere_of_radius_3() -> None:
    unit = shapes.cube_sphere(0).vertices
    frames = vertex_frames(shapes.cube_sphere(0).with_vertices(3.0 * unit + [5.0, -2.0, 1.0]))
    assert frames.fitted.all()
    np.testing.assert_allclose(frames.normals, unit, atol=1e-12)
    np.testing.assert_allclose(frames.shape_operator, tangent_projector(unit) / 3.0, atol=1e-12)


def test_ellipsoid_normals_converge_at_order_two_or_more_and_beat_the_fan() -> None:
    error, fan_error = [], []
    for level in (2, 3, 4):
        mesh, exact = ellipsoid(level)
        frames = vertex_frames(mesh)
        check_invariants(frames)
        error.append(angle_deg(frames.normals, exact).max())
        fan_error.append(angle_deg(fan_normals(mesh), exact).max())
    order = np.log2(np.array(error[:-1]) / np.array(error[1:]))
    assert (order >= 2.0).all(), (error, order)
    assert error[1] < fan_error[1] / 5 and error[2] < fan_error[2] / 20, (error, fan_error)


def test_torus_normals_and_shape_operator_converge() -> None:
    normal_error, shape_error = [], []
    for n_major, n_minor in ((24, 12), (48, 24), (96, 48)):
        mesh, exact_n, exact_s = torus(n_major, n_minor)
        frames = vertex_frames(mesh)
        check_invariants(frames)
        normal_error.append(angle_deg(frames.normals, exact_n).max())
        shape_error.append(np.abs(frames.shape_operator - exact_s).max())
    assert normal_error[0] > normal_error[1] > normal_error[2] and normal_error[2] < 0.01, (
        normal_error
    )
    assert shape_error[0] > shape_error[1] > shape_error[2] and shape_error[2] < 0.02, shape_error


def test_coarse_torus_keeps_the_fan_normal() -> None:
    """12 × 6 quads on r = 0.25: the 2-ring fit is off by up to 4°, the (symmetric) fan normal
    exact."""
    mesh, exact_n, _ = torus(12, 6, 1.0, 0.25)
    frames = vertex_frames(mesh)
    assert not frames.fitted.any()
    np.testing.assert_array_equal(frames.normals, fan_normals(mesh))
    assert angle_deg(frames.normals, exact_n).max() < 1e-10


@pytest.mark.parametrize(
    "mesh",
    [shapes.grid(5, 4), shapes.fan(5, 2), shapes.boundary_fan(3), shapes.strip(4)],
    ids=["grid", "fan", "boundary_fan", "strip"],
)
def test_flat_meshes_have_normal_z_and_no_curvature(mesh: QuadMesh) -> None:
    frames = vertex_frames(mesh)
    np.testing.assert_array_equal(
        frames.normals, np.broadcast_to([0.0, 0.0, 1.0], frames.normals.shape)
    )
    np.testing.assert_array_equal(frames.shape_operator, 0.0)


def test_curved_open_grid() -> None:
    mesh = shapes.grid(8, 8, height=lambda x, y: 0.3 * x * x - 0.2 * y * y + 0.1 * x * y)
    frames = vertex_frames(mesh)
    check_invariants(frames)
    assert frames.fitted[~mesh.topology.is_boundary_vertex].all()


@pytest.mark.parametrize("seed", range(4))
def test_noisy_coarse_sphere(seed: int) -> None:
    mesh = shapes.cube_sphere(1)
    shortest = np.linalg.norm(np.diff(mesh.vertices[mesh.topology.edges], axis=1), axis=-1).min()
    noise = np.random.default_rng(seed).uniform(-1.0, 1.0, mesh.vertices.shape) * 0.08 * shortest
    mesh = mesh.with_vertices(mesh.vertices + noise)
    frames = vertex_frames(mesh)
    check_invariants(frames)
    fan = fan_normals(mesh)
    kept = ~frames.fitted & ~frames.repaired
    np.testing.assert_array_equal(frames.normals[kept], fan[kept])
    assert (angle_deg(frames.normals[frames.fitted], fan[frames.fitted]) <= MAX_TILT).all()
    for v in range(mesh.n_vertices):
        assert goes_once_around(mesh, v, frames.normals[v])


def test_folded_ring_is_repaired() -> None:
    """One long, steep edge (towards −y) tilts the fan normal until the short ring edges fold
    over."""
    mesh = shapes.grid(2, 2, size=(2.0, 2.0))
    x = mesh.vertices - [1.0, 1.0, 0.0]
    x[[1, 3, 5, 7]] = [
        [0.0, -1.73, 2.167],
        [-0.398, 0.0, 0.657],
        [0.159, 0.0, 0.068],
        [0.0, 0.145, 0.133],
    ]
    mesh = mesh.with_vertices(x)
    assert not goes_once_around(mesh, 4, fan_normals(mesh)[4])
    frames = vertex_frames(mesh)
    check_invariants(frames)
    assert frames.repaired[4] and not frames.repaired[np.arange(9) != 4].any()
    assert goes_once_around(mesh, 4, frames.normals[4])


def _reference_meshes() -> list[QuadMesh]:
    noisy = shapes.cube_sphere(2)
    noise = np.random.default_rng(5).uniform(-0.02, 0.02, noisy.vertices.shape)
    folded = shapes.grid(2, 2, size=(2.0, 2.0))
    x = folded.vertices - [1.0, 1.0, 0.0]
    x[[1, 3, 5, 7]] = [
        [0.0, -1.73, 2.167],
        [-0.398, 0.0, 0.657],
        [0.159, 0.0, 0.068],
        [0.0, 0.145, 0.133],
    ]
    return [
        ellipsoid(3)[0],
        torus(24, 12)[0],
        torus(12, 6, 1.0, 0.25)[0],
        noisy.with_vertices(noisy.vertices + noise),
        shapes.cube_sphere(0),
        shapes.boundary_fan(3),
        shapes.fan(7, 2),
        folded.with_vertices(x),
        shapes.grid(8, 8, height=lambda x, y: 0.3 * x * x - 0.2 * y * y + 0.1 * x * y),
    ]


def split_polygon(n: int) -> QuadMesh:
    """One n-gon on the monkey saddle z = 0.1 sin 3θ around the unit circle, split into n quads
    around a centre hub whose whole 2-ring lies near the rim."""
    theta = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return QuadMesh.from_arrays(
        np.stack([np.cos(theta), np.sin(theta), 0.1 * np.sin(3.0 * theta)], axis=1),
        [list(range(n))],
    )


@pytest.mark.parametrize("n", [16, 1000])
def test_hub_of_a_split_polygon_keeps_the_fan_normal(n: int) -> None:
    """On one circle the slope columns x, y of the fit are combinations of cubic ones (x r² = x³ +
    xy²), so the fit is not trusted there: the hub keeps its fan normal, z by the 3-fold symmetry
    (the fit tilted it 20° at n = 1000)."""
    mesh = split_polygon(n)
    hub = int(np.argmax(np.bincount(mesh.faces.ravel())))
    frames = vertex_frames(mesh)
    assert not frames.fitted[hub]
    assert angle_deg(frames.normals[[hub]], np.array([[0.0, 0.0, 1.0]]))[0] < 1e-12


@pytest.mark.parametrize("index", range(9))
def test_compiled_kernel_matches_the_numpy_reference(index: int) -> None:
    """Same masks; normals within 256 ε (radians; measured ≤ 27 ε), S within 2¹⁴ ε of each vertex's
    largest entry.

    The normal equations' condition amplifies the different rounding of the sums: ≤ 63 ε measured
    on the smooth and noisy meshes, 4.6e3 ε at a corner of the folded 2 × 2 grid (fixed-normal
    fit)."""
    mesh = _reference_meshes()[index]
    fast, reference = vertex_frames(mesh), vertex_frames(mesh, compiled=False)
    eps = np.finfo(np.float64).eps
    np.testing.assert_array_equal(fast.fitted, reference.fitted)
    np.testing.assert_array_equal(fast.repaired, reference.repaired)
    assert (angle_deg(fast.normals, reference.normals) <= np.degrees(256 * eps)).all()
    scale = np.maximum(np.abs(reference.shape_operator).max(axis=(1, 2)), np.finfo(np.float64).tiny)
    assert (
        np.abs(fast.shape_operator - reference.shape_operator).max(axis=(1, 2))
        <= 2.0**14 * eps * scale
    ).all()


def test_compiled_kernel_matches_the_numpy_reference_around_a_hub() -> None:
    """The kernel's batches of similar sizes (a hub of 200 points fitted apart from rings of 3–9):
    same masks and normals as the reference, and S at the hub within 2¹⁴ ε of the largest S of the
    mesh (the saddle's centre has S = 0 up to rounding, so its own scale is no measure). The rim's
    corners (three points, a held fit through them) differ by ~6e5 ε there and are not compared."""
    mesh = split_polygon(100)
    fast, reference = vertex_frames(mesh), vertex_frames(mesh, compiled=False)
    np.testing.assert_array_equal(fast.fitted, reference.fitted)
    assert (
        angle_deg(fast.normals, reference.normals) <= np.degrees(256 * np.finfo(np.float64).eps)
    ).all()
    inner = ~mesh.topology.is_boundary_vertex
    difference = np.abs(fast.shape_operator[inner] - reference.shape_operator[inner]).max()
    assert difference <= 2.0**14 * np.finfo(np.float64).eps * np.abs(reference.shape_operator).max()


@pytest.mark.parametrize(
    "mesh",
    [
        split_polygon(SMALL_RING),
        split_polygon(SMALL_RING + 1),
        split_polygon(1000),
        shapes.torus(6, 4),
    ],
    ids=["hub at the limit", "hub above it", "hub of 1000", "torus"],
)
def test_face_ring_rows_are_scipys_rows_of_the_incidence_product(mesh: QuadMesh) -> None:
    """The kernel's rows of ``I Iᵀ`` are scipy's, point for point and in its order, on both of its
    paths: rings up to SMALL_RING faces (insertion sort, row scan), larger ones (sort, marks)."""
    nv, nf = mesh.n_vertices, mesh.n_faces
    incidence = sp.csr_matrix(
        (np.ones(4 * nf, dtype=bool), (mesh.faces.ravel(), np.repeat(np.arange(nf), 4))),
        shape=(nv, nf),
    )
    product = (incidence @ incidence.T).tocsr()
    offsets, points = _face_ring_rows(mesh)
    np.testing.assert_array_equal(offsets, product.indptr)
    np.testing.assert_array_equal(points, product.indices)


@pytest.mark.parametrize(
    ("mesh", "drops"),
    [
        (split_polygon(16), False),
        (split_polygon(100), True),
        (shapes.grid(6, 5), True),
        (shapes.strip(4), True),
    ],
    ids=["hub of 16", "hub of 100", "flat grid", "strip"],
)
def test_fit_kernel_residual_and_determination_match_the_numpy_reference(
    mesh: QuadMesh, drops: bool
) -> None:
    """The kernel computes a vertex's residual and determination (pivot) once, on its last refit,
    as vectors across lanes; they are the reference's, which computes them on every refit: squared
    residual within 2¹⁴ ε of the largest, pivot (a sin²) within 2¹⁴ ε, and the same dropped columns
    (pivot 0 where a ring has fewer points than unknowns: the grid's corners, the strip, the
    100-gon's rim)."""
    start = fan_normals(mesh)
    everything = np.arange(mesh.n_vertices)
    fast = _fit_compiled(mesh, _face_ring_rows(mesh), everything, start, True)
    residual, pivot = np.empty(mesh.n_vertices), np.empty(mesh.n_vertices)
    one, two = _face_rings(mesh)
    large = two.sizes >= CUBIC_POINTS
    for hood, cubic in ((two, True), (one, False)):
        vertices = np.flatnonzero(large == cubic)
        fit = _fit_all(mesh, _Ring.of(mesh), hood, vertices, start, cubic, True)
        residual[vertices], pivot[vertices] = fit.residual, fit.pivot
    eps = 2.0**14 * np.finfo(np.float64).eps
    np.testing.assert_array_equal(fast.pivot == 0.0, pivot == 0.0)
    np.testing.assert_allclose(
        fast.pivot, pivot, rtol=0.0, atol=eps
    )  # a sin² in [0, 1]; near-dropped columns differ ~1e-15
    # residual² is a difference of sums (exact fits: rounding either side of 0, clipped), so
    # compared squared
    np.testing.assert_allclose(
        fast.residual**2, residual**2, rtol=0.0, atol=eps * max(1.0, float((residual**2).max()))
    )
    assert (fast.pivot == 0.0).any() == drops
