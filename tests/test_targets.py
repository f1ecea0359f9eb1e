"""Targets → assembly: the Gregory assembly is exactly G1 for any valid fan and keeps targets that
already are.

Reference data are independent of the assembly: a periodic uniform bicubic B-spline surface (its
Bézier pieces by the exact change of basis, so C2 across every edge) and random fans drawn by
hypothesis, checked by the continuity report's own sampling.
"""

from __future__ import annotations

import numpy as np
import pytest
from exactness import MAX_ANGLE_DEG, perturbed
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.build import build_network
from g1patch.construct.corner import assemble_corner
from g1patch.construct.gregory import assemble_gregory, corner_split
from g1patch.continuity import check
from g1patch.errors import ConstructionError, InputError
from g1patch.mesh import QuadMesh
from g1patch.network import network_from_mesh
from g1patch.patches import PatchSet
from g1patch.targets import Targets, halfedge_slots
from g1patch.targets.interpolate import (
    interpolate_targets,
    legacy_targets,
    safeguarded_fans,
    slot_vertices,
)


def _torus_grid(n: int, m: int) -> QuadMesh:
    """A periodic n × m grid on the torus; vertex i m + j, face (i, j) = [(i, j), (i+1, j), (i+1,
    j+1), (i, j+1)]."""
    return shapes.torus(n, m, 2.0, 0.7)


def _bspline_patches(mesh: QuadMesh, n: int, m: int, seed: int) -> np.ndarray:
    """Bézier nets (F, 4, 4, 3) of a periodic uniform bicubic B-spline over the grid: the torus's
    vertices as control points, perturbed so nothing is symmetric."""
    control = mesh.vertices.reshape(n, m, 3) + 0.05 * np.random.default_rng(seed).normal(
        size=(n, m, 3)
    )
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    rows = (i[..., None] + np.arange(-1, 3)) % n  # the 4 × 4 control block of face (i, j)
    cols = (j[..., None] + np.arange(-1, 3)) % m
    block = control[rows[:, :, :, None], cols[:, :, None, :]].reshape(-1, 4, 4, 3)
    return PatchSet(block, "bspline").convert("bezier").control


def _targets_of_bezier(mesh: QuadMesh, nets: np.ndarray) -> Targets:
    """Targets read off C1 Bézier nets: corners, edge tangents 3 (b_10 − b_00), interior points
    b_11."""
    topology = mesh.topology
    corner_index = [(0, 0), (3, 0), (3, 3), (0, 3)]
    toward_next = [(1, 0), (3, 1), (2, 3), (0, 2)]  # edge point on edge k next to corner k
    toward_prev = [(0, 1), (2, 0), (3, 2), (1, 3)]  # edge point on edge k − 1 next to corner k
    inner = [(1, 1), (2, 1), (2, 2), (1, 2)]
    corners = np.stack([nets[:, a, b] for a, b in corner_index], axis=1)
    positions = np.empty((topology.n_vertices, 3))
    positions[mesh.faces] = corners
    slot_out, slot_in = halfedge_slots(topology)
    tangents = np.empty((int(topology.neighbor_offsets[-1]), 3))
    count = topology.n_faces
    prev = topology.prev(np.arange(4 * count))
    tangents[slot_out] = (
        3.0 * (np.stack([nets[:, a, b] for a, b in toward_next], axis=1) - corners)
    ).reshape(-1, 3)
    tangents[slot_in[prev]] = (
        3.0 * (np.stack([nets[:, a, b] for a, b in toward_prev], axis=1) - corners)
    ).reshape(-1, 3)
    normals = np.zeros((topology.n_vertices, 3))
    u_dir = tangents[slot_out].reshape(count, 4, 3)
    v_dir = tangents[slot_in[prev]].reshape(count, 4, 3)
    normals[mesh.faces] = np.cross(u_dir, v_dir)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    interior = np.stack([nets[:, a, b] for a, b in inner], axis=1)
    return Targets(topology, positions, normals, tangents, np.stack([interior, interior], axis=2))


@pytest.mark.parametrize("seed", range(3))
def test_c1_targets_come_back_unchanged(seed: int) -> None:
    """A bicubic B-spline surface already satisfies G1 (C2): the assembly must keep its Bézier
    points."""
    n, m = 7, 5
    mesh = _torus_grid(n, m)
    nets = _bspline_patches(mesh, n, m, seed)
    targets = _targets_of_bezier(mesh, nets)
    points = assemble_gregory(targets).points
    scale = np.abs(nets).max()
    flat = {  # Gregory layout → Bézier index
        0: (0, 0),
        1: (3, 0),
        2: (3, 3),
        3: (0, 3),
        4: (1, 0),
        5: (0, 1),
        6: (3, 1),
        7: (2, 0),
        8: (2, 3),
        9: (3, 2),
        10: (0, 2),
        11: (1, 3),
        12: (1, 1),
        13: (1, 1),
        14: (2, 1),
        15: (2, 1),
        16: (2, 2),
        17: (2, 2),
        18: (1, 2),
        19: (1, 2),
    }
    expected = np.stack([nets[:, a, b] for a, b in (flat[k] for k in range(20))], axis=1)
    assert np.abs(points - expected).max() <= 1e-13 * scale
    corner = assemble_corner(targets).convert("bezier").control
    assert (
        np.abs(corner - nets).max() <= 1e-13 * scale
    )  # C1 data: the paper's patches are the spline too


def _random_fan_targets(mesh: QuadMesh, seed: int) -> Targets:
    """Arbitrary valid targets: random normals tilted from the fan's, random tangent lengths and
    directions jittered inside each fan gap, random interior points."""
    rng = np.random.default_rng(seed)
    base = interpolate_targets(mesh)
    topology = mesh.topology
    slot_vertex = slot_vertices(topology)
    lengths = rng.uniform(0.3, 2.0, len(slot_vertex))[:, None]
    tangents = base.tangents * lengths
    normals = base.normals
    interior = (
        base.interior
        + 0.2 * rng.normal(size=base.interior.shape) * np.linalg.norm(base.tangents, axis=1).mean()
    )
    return Targets(topology, base.positions, normals, tangents, interior)


@settings(deadline=None, max_examples=25)
@given(
    st.sampled_from(["fan", "boundary_fan", "torus", "cube_sphere", "genus2"]),
    st.integers(0, 40),
    st.integers(0, 2**32 - 1),
)
def test_any_valid_fan_assembles_exactly_g1(kind: str, size: int, seed: int) -> None:
    """Flexible fans: lengths scaled at random per slot, interior targets anywhere: still exactly
    G1."""
    makers = {
        "fan": lambda k: shapes.fan(3 + k % 10, 1 + k % 2),
        "boundary_fan": lambda k: shapes.boundary_fan(1 + k % 7),
        "torus": lambda k: shapes.torus(4 + k % 5, 3 + k % 4),
        "cube_sphere": lambda k: shapes.cube_sphere(k % 2),
        "genus2": lambda k: shapes.genus2(),
    }
    mesh = perturbed(makers[kind](size), 0.03, seed)
    targets = _random_fan_targets(mesh, seed)
    patches = assemble_gregory(targets)
    report = check(network_from_mesh(mesh.topology, patches, mesh.vertices))
    assert report.max_edge_angle_deg <= MAX_ANGLE_DEG, report.worst_edge
    assert report.max_corner_angle_deg <= MAX_ANGLE_DEG
    assert report.max_g0_gap <= 1e-15
    np.testing.assert_array_equal(patches.corners(), mesh.vertices[mesh.faces])


def test_corner_split_solves_the_fan_equation() -> None:
    """α d_L + β d_R = φ q with α + β = 2, and α = β = 1, φ = 2 cos(2π/n) on a regular star."""
    rng = np.random.default_rng(4)
    n = np.array([[0.0, 0.0, 1.0]] * 50)
    angles = np.sort(rng.uniform(0.2, 2.9, (50, 2)), axis=1)
    q = np.stack([np.ones(50), np.zeros(50), np.zeros(50)], axis=1) * rng.uniform(0.5, 2, (50, 1))
    d_left = np.stack(
        [np.cos(angles[:, 0]), np.sin(angles[:, 0]), np.zeros(50)], axis=1
    ) * rng.uniform(0.5, 2, (50, 1))
    d_right = np.stack(
        [np.cos(-angles[:, 1]), np.sin(-angles[:, 1]), np.zeros(50)], axis=1
    ) * rng.uniform(0.5, 2, (50, 1))
    alpha, beta, phi, margin = corner_split(q, d_left, d_right, n)
    assert (margin > 0).all() and (alpha > 0).all() and (beta > 0).all()
    np.testing.assert_allclose(alpha + beta, 2.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(
        alpha[:, None] * d_left + beta[:, None] * d_right, phi[:, None] * q, rtol=0, atol=1e-14
    )
    for valence in (3, 5, 6, 9):
        theta = 2 * np.pi / valence
        star = lambda a: np.array([[np.cos(a), np.sin(a), 0.0]])  # noqa: E731
        alpha, beta, phi, _ = corner_split(star(0.0), star(theta), star(-theta), n[:1])
        np.testing.assert_allclose(
            [alpha[0], beta[0], phi[0]], [1.0, 1.0, 2 * np.cos(theta)], rtol=0, atol=1e-15
        )


def test_an_invalid_fan_is_refused_by_the_assembly() -> None:
    """The assembly never guesses shape: a fan that turns clockwise at a vertex is an error naming
    it."""
    mesh = shapes.fan(5, 1)
    targets = legacy_targets(mesh)
    tangents = targets.tangents.copy()
    offsets = mesh.topology.neighbor_offsets
    centre = int(np.flatnonzero(~mesh.topology.is_boundary_vertex)[0])
    ring = slice(offsets[centre], offsets[centre + 1])
    tangents[ring] = tangents[ring][::-1]
    bad = Targets(targets.topology, targets.positions, targets.normals, tangents, targets.interior)
    with pytest.raises(ConstructionError, match=f"vertex {centre} "):
        assemble_gregory(bad)


def test_targets_validate_their_shapes() -> None:
    targets = legacy_targets(shapes.cube())
    with pytest.raises(InputError, match="targets.interior: expected shape"):
        Targets(
            targets.topology,
            targets.positions,
            targets.normals,
            targets.tangents,
            targets.interior[:, :, 0],
        )
    with pytest.raises(InputError, match="targets.tangents: expected shape"):
        Targets(
            targets.topology,
            targets.positions,
            targets.normals,
            targets.tangents[:-1],
            targets.interior,
        )


def test_unknown_shape_and_method() -> None:
    with pytest.raises(InputError, match="shape: unknown value 'lumpy'"):
        build_network(shapes.cube(), "gregory", "lumpy")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="method: unknown value 'spline'"):
        build_network(shapes.cube(), "spline")  # type: ignore[arg-type]


@pytest.mark.parametrize("scale", [1e-3, 1e3])
def test_the_gregory_assembly_scales_with_its_targets(scale: float) -> None:
    """Targets scaled by s give points scaled by s: the k-h fit's ridge is relative to each
    unknown's own diagonal entry (G1 a length, h_L1 a number), so no size is preferred. One ridge
    scaled by the larger entry moved a noisy torus's points by 1e-4 of their size at s = 0.5
    and folded the slivers of a large polygon's split. Bound: a few ε of the points' size."""
    targets = interpolate_targets(perturbed(shapes.torus(6, 4), 0.05, 3))
    scaled = targets.with_changes(
        positions=scale * targets.positions,
        tangents=scale * targets.tangents,
        interior=scale * targets.interior,
    )
    for compiled in (True, False):
        points = assemble_gregory(targets, compiled=compiled).points
        np.testing.assert_allclose(
            assemble_gregory(scaled, compiled=compiled).points / scale,
            points,
            rtol=0,
            atol=64 * np.finfo(float).eps * np.abs(points).max(),
        )


def test_a_nearly_straight_corner_narrows_instead_of_spreading() -> None:
    """A one-face corner whose rim turns by 179.9° (a 3600-gon's corner) is its own regular star,
    so no blend towards it is valid: its tangents turn towards each other by (θ − 180° + 3ε/2)/2
    each, to 180° − 3ε/2 = 177° (ε = 2°), keeping their lengths, instead of being spread to 90°."""
    theta = np.radians(179.9)
    vertices = np.array(
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0 + np.cos(theta), 1.0, 0.0],
            [np.cos(theta), np.sin(theta), 0.0],
        ]
    )
    vertices[2] = vertices[1] + vertices[3]  # a parallelogram with a 179.9° corner at vertex 0
    mesh = QuadMesh.from_arrays(vertices, [[0, 1, 2, 3]])
    topology = mesh.topology
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    raw = (mesh.vertices[topology.neighbors] - mesh.vertices[slot_vertices(topology)]) * 1.0
    chord = np.linalg.norm(raw, axis=1)
    tangents, guarded = safeguarded_fans(topology, normals, raw, chord)
    first = topology.neighbor_offsets[0]
    a, b = tangents[first], tangents[first + 1]
    turn = np.degrees(np.arctan2(np.cross(a, b)[2], a @ b))
    assert guarded[0]
    assert turn == pytest.approx(177.0, abs=1e-12)
    np.testing.assert_allclose(
        np.linalg.norm([a, b], axis=1), chord[[first, first + 1]], rtol=1e-15
    )
    np.testing.assert_allclose(
        np.degrees(np.arctan2(a[1], a[0])) - np.degrees(np.arctan2(raw[first][1], raw[first][0])),
        1.45,
        atol=1e-12,
    )
