"""The interpolating Gregory network (g1patch.construct.gregory): exact G1 on every mesh.

Acceptance measures come from continuity.check (exact first derivatives, atan2 angles):

* G1 angle ≤ 1e-9° on every interior edge and at every corner. The construction satisfies the
  G1 equations to rounding, so the measured angles are ~1e-13°–1e-11° (Spot, the largest mesh,
  ~1e-11°); 1e-9° is the project's "exactly G1" bar (DESIGN §4).
* G0 gap ≤ 1e-12 of the bbox diagonal: both sides evaluate the same four control points, so the
  gap is the rounding of two cubic evaluations, ~1e-16.
* vertex deviation ≤ 1e-12 (it is 0: corners are evaluated with exact 0/1 weights).

Independently of the analytic derivatives, G1 is re-measured from finite differences of positions
only (``fd_normals``), and the G1 equation ``D_L + D_R = Φ c'`` is checked as a vector identity
with Φ computed here from the valences. Noise is relative to the shortest mesh edge, at most 5 %,
where no patch folds. Beyond it folds appear in thin, strongly perturbed quads for this and the
corner construction alike (300 noisy fans and boundary fans: 3 vs 3 meshes with a fold at 10 %,
54 vs 42 at 15 %); G1 stays exact there, the fold count reports them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from exactness import (
    INTERPOLATING,
    NOISE,
    SHARED_MESHES,
    assert_exact_g1,
    height,
    noisy_generated_meshes,
    perturbed,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.build import build_gregory_network
from g1patch.construct.corner import build_corner_network
from g1patch.continuity import angle_between, check
from g1patch.errors import ConstructionError, InputError
from g1patch.gregory import GregoryPatchSet
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork, edge_parameters
from g1patch.targets.interpolate import tangent_stars
from g1patch.targets.local import corner_tangents, fan_normals

EDGE_DIRECTION = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
INWARD = np.array(
    [[0.0, 1.0], [-1.0, 0.0], [0.0, -1.0], [1.0, 0.0]]
)  # EDGE_DIRECTION turned by +90°


# ------------------------------------------------------------------------------ shared meshes
@pytest.mark.parametrize("name", SHARED_MESHES)
@pytest.mark.parametrize("shape", INTERPOLATING)
def test_shared_meshes_are_exactly_g1(shared_data: Path, name: str, shape: str) -> None:
    mesh = read_mesh(shared_data / name)
    network = build_gregory_network(mesh, shape=shape)  # type: ignore[arg-type]
    assert isinstance(network.patches, GregoryPatchSet)
    assert network.provenance["method"] == "gregory" and network.provenance["shape"] == shape
    # stored in the working frame (centred, unit-scaled): corners come back within rounding
    np.testing.assert_allclose(
        network.patches.corners(),
        mesh.vertices[mesh.faces],
        rtol=0,
        atol=4 * np.finfo(float).eps * np.abs(mesh.vertices).max(),
    )
    assert_exact_g1(check(network))


@settings(deadline=None, max_examples=30)
@given(
    st.sampled_from(SHARED_MESHES[:4]),
    st.floats(0.0, NOISE),
    st.integers(0, 2**32 - 1),
    st.sampled_from(INTERPOLATING),
)
def test_perturbed_shared_meshes_are_exactly_g1(
    name: str, amplitude: float, seed: int, shape: str
) -> None:
    from conftest import shared_data_path

    mesh = perturbed(read_mesh(shared_data_path(name)), amplitude, seed)
    assert_exact_g1(check(build_gregory_network(mesh, shape=shape)))  # type: ignore[arg-type]


def test_perturbed_spot_is_exactly_g1(shared_data: Path) -> None:
    mesh = perturbed(read_mesh(shared_data / "spot_quadrangulated.obj"), NOISE, 2024)
    assert_exact_g1(check(build_gregory_network(mesh)))


# ------------------------------------------------------------------------------ generated meshes


@pytest.mark.slow
@settings(deadline=None, max_examples=150)
@given(noisy_generated_meshes())
def test_generated_meshes_are_exactly_g1(drawn: tuple[QuadMesh, str]) -> None:
    mesh, shape = drawn
    assert_exact_g1(check(build_gregory_network(mesh, shape=shape)))  # type: ignore[arg-type]


@pytest.mark.parametrize("valence", range(3, 13))
def test_every_interior_valence(valence: int) -> None:
    mesh = perturbed(shapes.fan(valence, 2), NOISE, valence)
    assert_exact_g1(check(build_gregory_network(mesh)))


# ------------------------------------------------------------------------------ independent checks
def fd_normals(network: PatchNetwork, t: np.ndarray, h: float) -> np.ndarray:
    """Normals on every patch edge from positions only, (N, 4, K, 3): ``T × C`` with T the central
    difference along the edge and C the one-sided second-order difference (−3p₀ + 4p₁ − p₂)/2h
    into the patch; (edge direction, inward) is a rotation of (u, v), so T × C ∥ p_u × p_v."""
    edge = np.arange(4)[:, None, None]
    stencil = np.array(
        [[0, 0], [1, 0], [-1, 0], [0, 1], [0, 2]], dtype=float
    )  # (along, inward) steps
    offsets = h * (
        stencil[:, None, 0, None] * EDGE_DIRECTION + stencil[:, None, 1, None] * INWARD
    )  # (5, 4, 2)
    uv = (
        edge_parameters(edge, t[None, :, None]) + np.moveaxis(offsets, 0, 1)[:, None]
    )  # (4, K, 5, 2)
    p = network.patches.evaluate(uv.reshape(-1, 2)).reshape(-1, 4, len(t), 5, 3)
    along = (p[..., 1, :] - p[..., 2, :]) / (2 * h)
    inward = (-3 * p[..., 0, :] + 4 * p[..., 3, :] - p[..., 4, :]) / (2 * h)
    return np.cross(along, inward)


def fd_edge_angles(network: PatchNetwork, t: np.ndarray, h: float) -> np.ndarray:
    """Angles (deg) between the two sides' finite-difference normals at the samples of every shared
    edge."""
    normals = fd_normals(network, t, h)
    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    return angle_between(normals[patch, edge], normals[other, other_edge, ::-1])  # t ↔ 1 − t


@pytest.mark.parametrize(
    "mesh",
    [shapes.cube(), perturbed(shapes.fan(7, 2), NOISE, 1), perturbed(shapes.genus2(), NOISE, 2)],
    ids=["cube", "fan7", "genus2"],
)
def test_finite_difference_normals_agree_across_edges(mesh: QuadMesh) -> None:
    """The FD angle between the two sides is truncation error O(h²) (rounding, eps/h ≈ 1e-9°, is far
    below): measured ≤ 4.4e-5° at h = 1e-4 and ≤ 4.4e-7° at h = 1e-5, i.e. it falls 100× per 10×
    smaller h and tends to 0. Asserted: ≤ 5e-6° at h = 1e-5 and a fall ≥ 30× (second order, with
    margin). The corner construction's creases stay ≥ 1° at every h."""
    t = np.linspace(0.1, 0.9, 9)  # symmetric, so the reversed side samples the same points
    network = build_gregory_network(mesh)
    coarse, fine = fd_edge_angles(network, t, 1e-4).max(), fd_edge_angles(network, t, 1e-5).max()
    assert fine <= 5e-6 and coarse >= 30 * fine
    assert fd_edge_angles(build_corner_network(mesh), t, 1e-5).max() >= 1.0


def expected_cosines(mesh: QuadMesh) -> np.ndarray:
    topology = mesh.topology
    return np.where(
        topology.is_boundary_vertex,
        np.cos(np.pi / topology.face_count),
        np.cos(2 * np.pi / topology.valence),
    )


@pytest.mark.parametrize(
    "mesh",
    [
        perturbed(shapes.fan(6, 2), NOISE, 3),
        perturbed(shapes.boundary_fan(4), NOISE, 4),
        perturbed(shapes.cube_sphere(1), NOISE, 5),
    ],
    ids=["fan6", "boundary_fan4", "sphere"],
)
def test_the_g1_equation_holds_as_a_vector_identity(mesh: QuadMesh) -> None:
    """Regular stars (the legacy rule): D_L + D_R = Φ c' with Φ(t) = 2 c_A (1 − t) − 2 c_B t on
    every interior edge (t from A); flexible fans use the general form (test_targets.py)."""
    network = build_gregory_network(mesh, shape="legacy")
    t = np.linspace(0.0, 1.0, 11)
    patches = network.patches
    uv = edge_parameters(np.arange(4)[:, None], t[None, :]).reshape(-1, 2)
    p_u = patches.evaluate(uv, 1, 0).reshape(-1, 4, len(t), 3)
    p_v = patches.evaluate(uv, 0, 1).reshape(-1, 4, len(t), 3)
    cross = (
        INWARD[None, :, None, 0, None] * p_u + INWARD[None, :, None, 1, None] * p_v
    )  # into the patch
    tangent = (
        EDGE_DIRECTION[None, :, None, 0, None] * p_u + EDGE_DIRECTION[None, :, None, 1, None] * p_v
    )
    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    cosine = expected_cosines(mesh)
    start, end = network.corner_ids[patch, edge], network.corner_ids[patch, (edge + 1) % 4]
    phi = 2 * cosine[start, None] * (1 - t) - 2 * cosine[end, None] * t
    residual = (
        cross[patch, edge] + cross[other, other_edge, ::-1] - phi[..., None] * tangent[patch, edge]
    )
    scale = np.abs(cross).max() + np.abs(tangent).max()
    assert np.abs(residual).max() <= 1e-13 * scale


@pytest.mark.parametrize(
    "mesh",
    [perturbed(shapes.fan(5, 2), NOISE, 6), perturbed(shapes.grid(3, 2, height=height), NOISE, 7)],
    ids=["fan5", "grid"],
)
def test_tangent_stars_are_regular(mesh: QuadMesh) -> None:
    """t_{j−1} + t_{j+1} = 2c t_j on interior edges, t_j ⊥ N; a corner (k = 1) keeps its corner
    tangents."""
    normals = fan_normals(mesh)
    star, cosine = tangent_stars(mesh, normals, "chord")
    topology = mesh.topology
    np.testing.assert_allclose(cosine, expected_cosines(mesh), rtol=0, atol=1e-15)
    offsets = topology.neighbor_offsets
    slot_vertex = np.repeat(np.arange(topology.n_vertices), np.diff(offsets))
    scale = np.abs(star).max()
    assert np.abs(np.einsum("sd,sd->s", star, normals[slot_vertex])).max() <= 1e-14 * scale
    for v in range(topology.n_vertices):  # a test-side loop over a few dozen vertices
        t = star[offsets[v] : offsets[v + 1]]
        if topology.is_boundary_vertex[v]:
            inner = range(1, len(t) - 1)
        else:
            inner = range(len(t))
        for j in inner:
            np.testing.assert_allclose(
                t[j - 1] + t[(j + 1) % len(t)], 2 * cosine[v] * t[j], rtol=0, atol=1e-14 * scale
            )
        if topology.is_boundary_vertex[v] and topology.face_count[v] == 1:
            ring = topology.neighbors[offsets[v] : offsets[v + 1]]
            x = mesh.vertices
            np.testing.assert_array_equal(
                t, corner_tangents(x[[v, v]], x[ring], normals[[v, v]], "chord")
            )


@pytest.mark.parametrize(
    "mesh",
    [
        perturbed(shapes.fan(7, 1), NOISE, 9),
        perturbed(shapes.boundary_fan(5), NOISE, 10),
        perturbed(shapes.boundary_fan(2), NOISE, 11),
    ],
    ids=["fan7", "boundary_fan5", "boundary_fan2"],
)
def test_stars_are_least_squares_fits(mesh: QuadMesh) -> None:
    """The closed-form fit equals a least-squares solve of t_j = cos θ_j a + sin θ_j b ≈ s_j at
    vertex 0."""
    normals = fan_normals(mesh)
    star, _ = tangent_stars(mesh, normals, "arc")
    topology = mesh.topology
    ring = topology.one_ring(0)
    faces = topology.face_count[0]
    theta = (
        np.pi * np.arange(faces + 1) / faces
        if topology.is_boundary_vertex[0]
        else 2 * np.pi * np.arange(len(ring)) / len(ring)
    )
    x = mesh.vertices
    s = corner_tangents(x[[0] * len(ring)], x[ring], normals[[0] * len(ring)], "arc")
    basis = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    coefficients = np.linalg.lstsq(basis, s, rcond=None)[0]
    np.testing.assert_allclose(
        star[: len(ring)], basis @ coefficients, rtol=0, atol=1e-14 * np.abs(s).max()
    )


def test_interior_edges_share_their_boundary_cubic_bit_for_bit(shared_data: Path) -> None:
    network = build_gregory_network(
        perturbed(read_mesh(shared_data / "catmark_xord_interior.obj"), NOISE, 8)
    )
    assert isinstance(network.patches, GregoryPatchSet)
    curves = network.patches.boundary_curves().control
    patch, edge = network.shared_edges()
    other, other_edge = network.neighbor[patch, edge], network.neighbor_edge[patch, edge]
    np.testing.assert_array_equal(curves[patch, edge], curves[other, other_edge, ::-1])


# ------------------------------------------------------------------------------ cube → sphere
def radial_deviation(network: PatchNetwork, resolution: int = 33) -> tuple[float, float]:
    """Max | |p| − 1 | over a grid on every patch, and over the patch boundaries alone."""
    grid = np.linspace(0.0, 1.0, resolution)
    radius = np.linalg.norm(network.patches.evaluate_grid(grid), axis=-1)
    border = np.concatenate([radius[:, 0], radius[:, -1], radius[:, :, 0], radius[:, :, -1]])
    return float(np.abs(radius - 1).max()), float(np.abs(border - 1).max())


def test_cube_to_sphere_deviation() -> None:
    """The previous release's rules (``shape="legacy"``) on the paper's example and its refinements
    (6, 24, 96, 384, 1536 quads on the unit sphere); the default rule is tested in test_shape.py.

    Locks in the measured figures (see the issue note): arc-length tangents put the boundary cubics
    of the 6-quad cube within 1e-4 of the sphere (6.3e-5); the interior sags (9.8e-2), set by the
    twist targets. At 96 quads the valence-4 vertices next to the valence-3 corners get stars
    distorted by up to 18°, so the error grows once before it falls with order ≈ 3.6.
    """
    deviation = {}
    for tangents in ("chord", "arc"):
        for level in range(5):
            network = build_gregory_network(
                shapes.cube_sphere(level), shape="legacy", tangents=tangents
            )  # type: ignore[arg-type]
            assert_exact_g1(check(network, samples=9, fold_samples=5))
            deviation[tangents, level] = radial_deviation(network)
    assert deviation["arc", 0][1] <= 1e-4
    assert deviation["arc", 0][0] <= 0.1 and deviation["chord", 0][0] <= 0.13
    for tangents in ("chord", "arc"):
        assert deviation[tangents, 4][0] <= 1.2e-4
        assert np.log2(deviation[tangents, 3][0] / deviation[tangents, 4][0]) >= 3.3


# ------------------------------------------------------------------------------ errors
def test_a_folded_ring_is_reported_by_the_legacy_rule_and_repaired_by_the_default() -> None:
    """A valence-6 ring that winds twice, with a clockwise part: its fitted star turns clockwise.
    The legacy rule refuses it; the default falls back at that vertex, counts it, and stays
    exact."""
    theta = 2 * np.pi * np.arange(6) / 6
    z = np.exp(2j * theta) + 0.3 * np.exp(-1j * theta)
    ring = np.stack([z.real, z.imag, np.zeros(6)], axis=1)
    vertices = np.vstack([[0.0, 0.0, 0.0], ring, 0.8 * (ring + np.roll(ring, -1, axis=0))])
    faces = [[0, 1 + j, 7 + j, 1 + (j + 1) % 6] for j in range(6)]
    mesh = QuadMesh.from_arrays(vertices, faces)
    with pytest.raises(ConstructionError, match="ring of vertex 0 .*folded"):
        build_gregory_network(mesh, shape="legacy")
    network = build_gregory_network(mesh)
    assert int(network.provenance["fallback_vertices"]) >= 1
    report = check(network)
    assert report.max_edge_angle_deg <= 1e-9 and report.max_corner_angle_deg <= 1e-9


def test_unknown_tangent_rule() -> None:
    with pytest.raises(InputError, match="tangents: unknown value 'bogus'"):
        build_gregory_network(shapes.cube(), shape="legacy", tangents="bogus")  # type: ignore[arg-type]
