"""Comparisons with exact surfaces and with triangulated references: distances (against brute
force), normal errors, fairness (normal turns) and the reference file reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from g1patch import compare, shapes
from g1patch.errors import FormatError, InputError
from g1patch.network import PatchNetwork, network_from_mesh
from g1patch.patches import PatchSet

#: Bézier coefficients of u² in degree 3
SQUARE = np.array([0.0, 0.0, 1.0 / 3.0, 1.0])


def sheet_network(height: np.ndarray, provenance: dict[str, str] | None = None) -> PatchNetwork:
    """One bicubic Bézier patch (u, v, height_i) over the unit square, on a one-quad mesh."""
    mesh = shapes.grid(1, 1)
    i, j = np.meshgrid(np.arange(4) / 3.0, np.arange(4) / 3.0, indexing="ij")
    control = np.stack([i, j, np.broadcast_to(height[:, None], (4, 4))], axis=-1)
    return network_from_mesh(
        mesh.topology, PatchSet(control[None], "bezier"), mesh.vertices, provenance=provenance
    )


def plane_projection(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest points on the plane z = 0 and its normal +z."""
    return points * np.array([1.0, 1.0, 0.0]), np.broadcast_to([0.0, 0.0, 1.0], points.shape)


def brute_force_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance to the nearest triangle, independently of Ericson's regions: the smaller of the
    distance to the triangle's plane (where the foot lies inside) and to its three sides."""
    p = points[:, None]
    a, b, c = (triangles[None, :, k] for k in range(3))
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    height = ((p - a) * normal).sum(-1)
    foot = p - height[..., None] * normal
    inside = np.ones(height.shape, dtype=bool)
    for start, end in ((a, b), (b, c), (c, a)):
        inside &= (np.cross(end - start, foot - start) * normal).sum(-1) >= 0
    best = np.where(inside, np.abs(height), np.inf)
    for start, end in ((a, b), (b, c), (c, a)):
        side = end - start
        t = np.clip(((p - start) * side).sum(-1) / (side * side).sum(-1), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(p - start - t[..., None] * side, axis=-1))
    return best.min(axis=1)


# -- samples and exact surfaces
# ---------------------------------------------------------------------


def test_surface_samples_shapes_and_unit_normals() -> None:
    network = sheet_network(SQUARE)
    positions, normals = compare.surface_samples(network, 5)
    assert positions.shape == normals.shape == (1, 5, 5, 3)
    u = np.linspace(0.0, 1.0, 5)
    np.testing.assert_allclose(positions[0, :, 0, 2], u**2, atol=1e-15)
    expected = (
        np.stack([-2.0 * u, np.zeros(5), np.ones(5)], axis=1) / np.sqrt(1.0 + 4.0 * u**2)[:, None]
    )
    np.testing.assert_allclose(normals[0, :, 2], expected, atol=1e-15)


def test_deviation_from_a_plane() -> None:
    lifted = compare.deviation(sheet_network(np.full(4, 0.25)), plane_projection, samples=7)
    assert (lifted.max_distance, lifted.mean_distance) == pytest.approx((0.25, 0.25))
    assert lifted.max_normal_error_deg == pytest.approx(0.0, abs=1e-12)
    curved = compare.deviation(sheet_network(SQUARE), plane_projection, samples=11)
    assert curved.max_distance == pytest.approx(1.0)
    assert curved.max_normal_error_deg == pytest.approx(np.degrees(np.arctan(2.0)))


def test_distance_to_sphere_of_the_sphere_mesh_corners() -> None:
    """A patch through points of the unit sphere is 0 away at its corners and inside between
    them."""
    mesh = shapes.sphere_quads(2)
    corners = mesh.vertices[mesh.faces]  # a bilinear patch per quad, as Bézier control points
    weights = np.linspace(0.0, 1.0, 4)
    s, t = weights[:, None, None], weights[None, :, None]
    control = (
        ((1 - s) * (1 - t))[None] * corners[:, None, None, 0]
        + (s * (1 - t))[None] * corners[:, None, None, 1]
        + (s * t)[None] * corners[:, None, None, 2]
        + ((1 - s) * t)[None] * corners[:, None, None, 3]
    )
    network = network_from_mesh(mesh.topology, PatchSet(control, "bezier"), mesh.vertices)
    found = compare.distance_to_sphere(network, samples=9)
    positions, _ = compare.surface_samples(network, 9)
    radial = 1.0 - np.linalg.norm(positions, axis=-1)
    assert found.max_distance == pytest.approx(radial.max()) and radial.min() > -1e-15
    np.testing.assert_allclose(radial[:, [0, 0, -1, -1], [0, -1, 0, -1]], 0.0, atol=1e-15)


def test_patch_samples_follow_the_face_grid() -> None:
    assert compare.patch_samples(sheet_network(SQUARE), 32) == 33
    split = sheet_network(SQUARE, {"method": "split4"})
    assert compare.patch_samples(split, 32) == 17
    with pytest.raises(InputError, match="even"):
        compare.patch_samples(split, 5)


# -- distance to a triangulated mesh
# ----------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_closest_points_on_triangles_match_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    triangles = rng.normal(size=(30, 3, 3))
    points = 2.0 * rng.normal(size=(200, 3))
    closest = compare.closest_points_on_triangles(
        points[:, None], triangles[None, :, 0], triangles[None, :, 1], triangles[None, :, 2]
    )
    np.testing.assert_allclose(
        np.linalg.norm(closest - points[:, None], axis=-1).min(axis=1),
        brute_force_distance(points, triangles),
        atol=1e-12,
    )


@pytest.mark.parametrize("seed", range(4))
def test_mesh_distance_matches_brute_force(seed: int) -> None:
    """Random triangle soups of very different sizes, points near and far."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(40, 3)) * rng.choice([0.05, 1.0, 5.0], size=(40, 1))
    faces = np.array([rng.choice(40, 3, replace=False) for _ in range(60)])
    queries = rng.normal(size=(3000, 3)) * rng.choice([0.1, 1.0, 10.0], size=(3000, 1))
    np.testing.assert_allclose(
        compare.mesh_distance(queries, points, faces),
        brute_force_distance(queries, points[faces]),
        atol=1e-12,
    )


def test_mesh_distance_to_quads_near_a_sphere() -> None:
    """Quads split along 0–2; samples just off a refined sphere and on its vertices."""
    mesh = shapes.noisy_sphere(3, noise=0.2, seed=1)
    rng = np.random.default_rng(7)
    queries = shapes.sphere_quads(4).vertices * rng.uniform(0.97, 1.03, (1, 1))
    queries = (queries * rng.uniform(0.95, 1.05, (len(queries), 1))).reshape(-1, 2, 3)
    triangles = mesh.vertices[np.concatenate([mesh.faces[:, [0, 1, 2]], mesh.faces[:, [0, 2, 3]]])]
    found = compare.mesh_distance(queries, mesh.vertices, mesh.faces)
    assert found.shape == (len(queries), 2)
    np.testing.assert_allclose(
        found.ravel(), brute_force_distance(queries.reshape(-1, 3), triangles), atol=1e-12
    )
    np.testing.assert_allclose(
        compare.mesh_distance(mesh.vertices, mesh.vertices, mesh.faces), 0.0, atol=1e-15
    )


@pytest.mark.parametrize("seed", range(4))
def test_nearest_triangles_meet_the_distance(seed: int) -> None:
    """The triangle found is one at the exact distance: random soups of triangles and of quads
    (their halves numbered as ``_triangles`` cuts them), and the mesh's own vertices, whose
    nearest point is a corner (the bound from the nearest vertex is already exact there)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(40, 3)) * rng.choice([0.05, 1.0, 5.0], size=(40, 1))
    queries = np.concatenate([rng.normal(size=(2000, 3)) * 2.0, points])
    for corners in (3, 4):
        faces = np.array([rng.choice(40, corners, replace=False) for _ in range(60)])
        halves = faces if corners == 3 else np.concatenate([faces[:, :3], faces[:, [0, 2, 3]]])
        distance, triangle = compare.nearest_triangles(queries, points, faces)
        a, b, c = (points[halves[triangle, k]] for k in range(3))
        met = np.linalg.norm(
            compare.closest_points_on_triangles(queries, a, b, c) - queries, axis=1
        )
        np.testing.assert_allclose(met, distance, atol=1e-12)
        np.testing.assert_allclose(
            distance, brute_force_distance(queries, points[halves]), atol=1e-12
        )


def test_mesh_distance_rejects_bad_faces() -> None:
    points = np.eye(3)
    with pytest.raises(InputError, match="0..2"):
        compare.mesh_distance(np.zeros(3), points, [[0, 1, 3]])
    with pytest.raises(InputError, match="faces"):
        compare.mesh_distance(np.zeros(3), points, [[0, 1]])


# -- fairness -------------------------------------------------------------------------------------


def test_network_normal_turns_of_a_parabolic_sheet() -> None:
    """z = u²: the normal (−2u, 0, 1) turns by atan(2u') − atan(2u) along u and not at all along
    v."""
    turns = compare.network_normal_turns(sheet_network(SQUARE), 9)
    u = np.linspace(0.0, 1.0, 9)
    along_u = np.degrees(np.diff(np.arctan(2.0 * u)))
    assert turns.shape == (2 * 9 * 8,)
    np.testing.assert_allclose(np.sort(turns)[-8 * 9 :], np.sort(np.repeat(along_u, 9)), atol=1e-12)
    np.testing.assert_allclose(np.sort(turns)[: 8 * 9], 0.0, atol=1e-12)


def test_reference_normal_turns_on_a_refined_sphere() -> None:
    """Vertex normals of a fine sphere mesh are nearly radial: each edge turns by about its arc."""
    mesh = shapes.sphere_quads(4)
    normals = compare.reference_vertex_normals(mesh.vertices, mesh.faces)
    assert np.degrees(np.arccos(np.clip((normals * mesh.vertices).sum(axis=1), -1, 1))).max() < 1.0
    turns = compare.reference_normal_turns(mesh.vertices, mesh.faces)
    ends = mesh.vertices[mesh.topology.edges]
    arcs = np.degrees(np.arccos(np.clip((ends[:, 0] * ends[:, 1]).sum(axis=1), -1, 1)))
    assert turns.shape == (mesh.n_edges,)
    error = np.abs(turns - arcs)  # both in the order of sorted vertex pairs
    assert error.max() < 0.7 and np.median(error) < 0.05  # worst beside the 8 valence-3 vertices
    assert turns.max() < 7.0


def test_turn_percentiles() -> None:
    found = compare.turn_percentiles(np.arange(101.0))
    assert found == {"median": 50.0, "p99": 99.0, "max": 100.0}
    with pytest.raises(InputError, match="turn"):
        compare.turn_percentiles([])


def test_compare_fairness_like_with_like() -> None:
    """A reference sampled from the same sheet at 3 levels is compared at 9 samples per patch: p99
    within the one-sided vertex normals of the border; at 5 samples (twice the step) it would
    double."""
    network = sheet_network(SQUARE)
    u, v = np.meshgrid(np.linspace(0.0, 1.0, 9), np.linspace(0.0, 1.0, 9), indexing="ij")
    points = np.stack([u, v, u**2], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(8), np.arange(8), indexing="ij")
    corner = (9 * i + j).ravel()
    faces = np.stack([corner, corner + 9, corner + 10, corner + 1], axis=1)
    reference = compare.Reference(points, faces, 3, Path("sheet.limit.npz"))
    found = compare.compare_fairness(network, reference)
    assert found.samples == 9
    assert found.p99_ratio == pytest.approx(found.network["p99"] / found.reference["p99"])
    assert 0.85 < found.p99_ratio < 1.15
    coarse = compare.turn_percentiles(compare.network_normal_turns(network, 5))
    assert coarse["p99"] / found.reference["p99"] > 1.8


# -- reference files ------------------------------------------------------------------------------


def test_load_reference_of_the_shared_cube(shared_data: Path) -> None:
    reference = compare.load_reference(compare.reference_path(shared_data / "catmark_cube.obj"))
    assert reference.levels == 5
    assert reference.points.shape == (6 * 4**5 + 2, 3) and reference.points.dtype == np.float64
    assert reference.faces.shape == (6 * 4**5, 4) and reference.faces.dtype == np.int64
    # the limit positions of the 8 cage vertices (|v| = √3) come first: inside the cage, all alike
    radii = np.linalg.norm(reference.points, axis=1)
    assert radii.max() < np.sqrt(3.0)
    np.testing.assert_allclose(radii[:8], radii[0], rtol=1e-6)
    np.testing.assert_allclose(np.abs(reference.points[:8, 2]), 0.5, rtol=1e-6)
    turns = compare.turn_percentiles(
        compare.reference_normal_turns(reference.points, reference.faces)
    )
    assert 0 < turns["median"] < turns["p99"] < 5.0


def test_load_reference_errors(tmp_path: Path) -> None:
    text = tmp_path / "text.limit.npz"
    text.write_text("not an archive")
    with pytest.raises(FormatError, match="text.limit.npz: not a readable .npz archive"):
        compare.load_reference(text)
    with pytest.raises(FormatError, match="cannot read"):
        compare.load_reference(tmp_path / "absent.limit.npz")
    single = tmp_path / "single.npy"
    np.save(single, np.zeros((3, 3)))
    with pytest.raises(FormatError, match="single array"):
        compare.load_reference(single)
    partial = tmp_path / "partial.limit.npz"
    np.savez(partial, points=np.zeros((4, 3), np.float32))
    with pytest.raises(FormatError, match="missing array.*faces, levels"):
        compare.load_reference(partial)
    wrong = tmp_path / "wrong.limit.npz"
    np.savez(
        wrong,
        points=np.zeros((4, 3), np.float32),
        faces=np.array([[0, 1, 2, 4]], np.int32),
        levels=np.int32(1),
    )
    with pytest.raises(FormatError, match=r"faces: indices must lie in 0\.\.3"):
        compare.load_reference(wrong)
    flat = tmp_path / "flat.limit.npz"
    np.savez(
        flat,
        points=np.zeros(12, np.float32),
        faces=np.array([[0, 1, 2, 3]], np.int32),
        levels=np.int32(1),
    )
    with pytest.raises(FormatError, match=r"points: expected .*\(M, 3\)"):
        compare.load_reference(flat)
