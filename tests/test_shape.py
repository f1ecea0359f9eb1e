"""Surfaces a person accepts (issue 9): round where the data are round, convergent, no folds, no
refusals.

Distances are to the exact surfaces the meshes are sampled from (closest points by
:mod:`g1patch.shapes`' projections, independent of the construction); folds and exactness by the
continuity report; fairness against OpenSubdiv's Catmull–Clark limit (../shared/data/reference).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from exactness import MAX_ANGLE_DEG, SHARED_MESHES, perturbed

from g1patch import shapes
from g1patch.build import build_network
from g1patch.compare import (
    Deviation,
    compare_fairness,
    distance_to_ellipsoid,
    distance_to_sphere,
    distance_to_torus,
    load_reference,
    reference_path,
)
from g1patch.continuity import check
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh
from g1patch.network import PatchNetwork


def _exact_and_unfolded(network: PatchNetwork) -> None:
    report = check(network)
    assert report.max_edge_angle_deg <= MAX_ANGLE_DEG, report.worst_edge
    assert report.max_corner_angle_deg <= MAX_ANGLE_DEG
    assert report.max_g0_gap <= 1e-12
    assert report.folds == 0, report.fold_locations


def test_the_cube_comes_out_round() -> None:
    """The paper's example: 6 quads, valence 3 → the unit sphere (measured 6.2e-5 and 9.6e-3)."""
    cube = shapes.sphere_quads(0)
    gregory = distance_to_sphere(build_network(cube, "gregory"), samples=41)
    split4 = distance_to_sphere(build_network(cube, "split4"), samples=21)
    assert gregory.max_distance <= 1e-4  # issue bar 1e-3; DESIGN's 1e-4
    assert split4.max_distance <= 1e-2


FAMILIES: dict[str, tuple[Callable[[int], QuadMesh], tuple[int, int], Callable[..., Deviation]]] = {
    "sphere": (shapes.sphere_quads, (3, 4), distance_to_sphere),  # 384, 1536 quads
    "ellipsoid": (shapes.ellipsoid_quads, (3, 4), distance_to_ellipsoid),
    "torus": (
        lambda level: shapes.torus_quads(12 * 2**level, 6 * 2**level),
        (2, 3),
        distance_to_torus,
    ),  # 48×24, 96×48
    "icosa_ellipsoid": (shapes.icosa_ellipsoid, (1, 2), distance_to_ellipsoid),  # valences 3–5
}


@pytest.mark.slow
@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_refinement_orders(family: str) -> None:
    """Position order ≥ 3.5 and normal order ≥ 2.5 over the two finest levels (h halves per level);
    measured 3.8–4.0 and 2.8–3.8."""
    make, levels, distance = FAMILIES[family]
    coarse, fine = (distance(build_network(make(level), "gregory")) for level in levels)
    assert np.log2(coarse.max_distance / fine.max_distance) >= 3.5
    assert np.log2(coarse.max_normal_error_deg / fine.max_normal_error_deg) >= 2.5


def test_smooth_mesh_lines_run_straight_through_their_vertices() -> None:
    """A coarse torus (8 × 4, R = 2, r = 0.7): every mesh line is a sampled circle, so at every
    vertex the two tangents of a line are opposite (the projected chords made a V), and split4's
    re-assembly of the same targets, which needs such stars, lies within 1e-4 of the diagonal of
    the Gregory surface (measured 4.6e-5; with the chords' V 6.7e-3)."""
    from g1patch.construct.polynomial import split4_of_gregory, surface_deviation
    from g1patch.targets.interpolate import interpolate_targets

    mesh = shapes.torus_quads(8, 4)
    fans = interpolate_targets(mesh).tangents.reshape(mesh.n_vertices, 4, 3)
    unit = fans / np.linalg.norm(fans, axis=2, keepdims=True)
    assert np.abs(np.cross(unit[:, :2], unit[:, 2:])).max() <= 1e-12
    assert (np.einsum("vkd,vkd->vk", unit[:, :2], unit[:, 2:]) < 0.0).all()
    network = build_network(mesh, "gregory")
    assert (
        surface_deviation(network, split4_of_gregory(network))[1]
        <= 1e-4 * network.bounding_box_diagonal()
    )


def test_kinked_mesh_lines_keep_their_chords() -> None:
    """The projected cube's lines kink where two of its faces meet: there the slots keep the
    projected chords (the sphere's edge curves stay on great circles)."""
    from g1patch.targets import interpolate
    from g1patch.targets.frames import vertex_frames

    mesh = shapes.sphere_quads(3)
    normals = vertex_frames(mesh).normals
    raw = interpolate._projected_tangents(mesh, normals)[0]
    turned = interpolate._along_smooth_lines(mesh, normals, raw)
    size = np.sort(np.abs(mesh.vertices), axis=1)
    on_cube_edges = np.isclose(
        size[:, 1], size[:, 2], rtol=1e-12
    )  # the two largest coordinates agree
    slots = np.isin(interpolate.slot_vertices(mesh.topology), np.flatnonzero(on_cube_edges))
    change = np.linalg.norm(turned - raw, axis=1) / np.linalg.norm(raw, axis=1)
    assert (
        on_cube_edges.sum() > 24 and change[slots].max() <= 4 * np.finfo(float).eps
    )  # the lines along the
    # edges are great circles: straight through, they turn by rounding only (measured ≤ 2.1e-16)


CAGES: dict[str, Callable[[], QuadMesh]] = {
    "box_cage": shapes.box_cage,
    "box_cage_jittered": lambda: shapes.box_cage(jitter_seed=3),
    "thin_slab": shapes.thin_slab,
    **{
        f"noisy_sphere_{level}_{seed}": (
            lambda level=level, seed=seed: shapes.noisy_sphere(level, 0.08, seed)
        )
        for level in (1, 2)
        for seed in range(3)
    },
    **{
        f"flat_fan_{n}": (lambda n=n: shapes.flat_fan(n))
        for n in (3, 4, 5, 6, 8, 12, 16, 32, 64, 128, 360)
    },
}


@pytest.mark.parametrize("name", sorted(CAGES))
def test_cages_built_to_fold_do_not(name: str) -> None:
    """Meshes made to provoke folds: 1:4 edges at every vertex, thin slabs with 90° rims, 8 %-noise
    coarse spheres, flat fans of valence 3…360 — exactly G1 and unfolded, and never refused."""
    _exact_and_unfolded(build_network(CAGES[name](), "gregory"))


@pytest.mark.slow
@pytest.mark.parametrize("name", SHARED_MESHES)
@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_shared_meshes_do_not_fold(shared_data: Path, name: str, method: str) -> None:
    mesh = read_mesh(shared_data / name)
    _exact_and_unfolded(build_network(mesh, method))  # type: ignore[arg-type]
    _exact_and_unfolded(build_network(perturbed(mesh, 0.05, 7), method))  # type: ignore[arg-type]


#: p99 normal turn over the Catmull–Clark limit's, measured; the bar is 1.5. The one-ring disks
#: (OpenSubdiv's xord shapes: every rim vertex a corner or a 2-face boundary vertex) miss it: an
#: interpolant must reach the rim vertices that the limit surface pulls away from.
P99_RATIO = {
    "catmark_cube.obj": 1.5,
    "catmark_torus.obj": 1.5,
    "spot_quadrangulated.obj": 1.5,
    "catmark_xord_boundary.obj": 2.4,  # measured 2.24 (legacy 3.01)
    "catmark_xord_interior.obj": 2.0,  # measured 1.89 (legacy 1.87)
}


@pytest.mark.slow
@pytest.mark.parametrize("name", SHARED_MESHES)
def test_fairness_against_the_catmull_clark_limit(shared_data: Path, name: str) -> None:
    reference = load_reference(reference_path(shared_data / name))
    network = build_network(read_mesh(shared_data / name), "gregory")
    assert compare_fairness(network, reference).p99_ratio <= P99_RATIO[name]


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_translation_and_scale_do_not_change_the_angles(method: str) -> None:
    """Built in centred, unit-scaled coordinates and stored with the frame: moved by 1e6 or scaled
    by 1e±6, every reported angle stays ≤ 1e-9° and within 10× (plus a 1e-12° floor) of the
    untransformed mesh's."""
    mesh = perturbed(shapes.sphere_quads(2), 0.05, 11)
    base = check(build_network(mesh, method))  # type: ignore[arg-type]
    for transform in (
        lambda x: x + 1e6,
        lambda x: 1e6 * x,
        lambda x: 1e-6 * x,
        lambda x: 1e-6 * x - 3e5,
    ):
        report = check(build_network(mesh.with_vertices(transform(mesh.vertices)), method))  # type: ignore[arg-type]
        for name in ("max_edge_angle_deg", "max_corner_angle_deg"):
            value = getattr(report, name)
            assert value <= MAX_ANGLE_DEG
            assert value <= 10 * getattr(base, name) + 1e-12
        assert report.folds == 0


def _edge_along_its_normal() -> QuadMesh:
    """A valence-6 fan whose first spoke is moved onto the centre's own fan normal (fixed point)."""
    from g1patch.targets.local import fan_normals

    mesh = shapes.fan(6, 1)
    centre = int(np.flatnonzero(~mesh.topology.is_boundary_vertex)[0])
    spoke = int(mesh.topology.one_ring(centre)[0])
    vertices = mesh.vertices.copy()
    for _ in range(60):
        vertices[spoke] = vertices[centre] + fan_normals(mesh.with_vertices(vertices))[centre]
    return mesh.with_vertices(vertices)


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_an_edge_along_its_vertex_normal_falls_back(method: str) -> None:
    """The first release refused this (split4: 'parallel to its vertex normal'); now the vertex
    falls back, is counted, and the surface stays exact and unfolded."""
    network = build_network(_edge_along_its_normal(), method)  # type: ignore[arg-type]
    assert int(network.provenance["fallback_vertices"]) >= 1
    _exact_and_unfolded(network)


def test_the_fold_guard_retreats_a_three_segment_torus() -> None:
    """A 3 × 5 torus with 20 % noise: the local rules fold it (with 5 % they did until its mesh
    lines ran straight through their vertices); the guard gives its vertices the faired
    limit-interpolating targets, counts them, and leaves no fold."""
    mesh = perturbed(shapes.torus(3, 5), 0.2, 0)
    network = build_network(mesh, "gregory")
    assert int(network.provenance["faired_vertices"]) >= 1
    _exact_and_unfolded(network)


@pytest.mark.parametrize("method", ["gregory", "split4"])
def test_high_valence_and_folded_rings_build(method: str) -> None:
    """A ring that winds twice (its fitted star folds: the first release refused it) and a
    valence-360 flat fan both build exactly G1, unfolded."""
    theta = 2 * np.pi * np.arange(6) / 6
    z = np.exp(2j * theta) + 0.3 * np.exp(-1j * theta)
    ring = np.stack([z.real, z.imag, np.zeros(6)], axis=1)
    vertices = np.vstack([[0.0, 0.0, 0.0], ring, 0.8 * (ring + np.roll(ring, -1, axis=0))])
    folded = QuadMesh.from_arrays(vertices, [[0, 1 + j, 7 + j, 1 + (j + 1) % 6] for j in range(6)])
    network = build_network(folded, method)  # type: ignore[arg-type]
    assert int(network.provenance["fallback_vertices"]) >= 1
    report = check(network)
    assert max(report.max_edge_angle_deg, report.max_corner_angle_deg) <= MAX_ANGLE_DEG
    _exact_and_unfolded(build_network(shapes.flat_fan(360), method))  # type: ignore[arg-type]


def test_fold_guard_never_repeats_a_retreat(monkeypatch: pytest.MonkeyPatch) -> None:
    """Faces that stay folded whatever is retreated (the fold test stubbed to say so): the guard
    retreats the folded faces' corners, then their 1-ring; once every vertex is retreated its third
    step would retreat the same vertices again and rebuild the same patches; it stops instead."""
    import g1patch.build as build_module

    retreats: list[bytes] = []
    original = build_module.retreat

    def recorded(targets, fair, vertices):  # type: ignore[no-untyped-def]
        retreats.append(vertices.tobytes())
        return original(targets, fair, vertices)

    monkeypatch.setattr(build_module, "retreat", recorded)
    monkeypatch.setattr(
        build_module, "folded_patches", lambda patches, samples: np.ones(len(patches), dtype=bool)
    )
    build_network(perturbed(shapes.torus(3, 5), 0.05, 0), "gregory")
    assert len(retreats) == 1  # every vertex is a folded face's corner: nothing more to retreat


def test_fold_guard_keeps_its_best_attempt(monkeypatch: pytest.MonkeyPatch) -> None:
    """A retreat that folds more than it mends (stubbed: every tangent tripled) is not taken: the
    network is the rule's own assembly, bit for bit."""
    import g1patch.build as build_module
    from g1patch.construct.gregory import assemble_gregory
    from g1patch.frame import Frame
    from g1patch.targets.interpolate import interpolate_targets

    mesh = perturbed(shapes.torus(3, 5), 0.05, 0)
    monkeypatch.setattr(
        build_module,
        "retreat",
        lambda targets, fair, vertices: targets.with_changes(tangents=3.0 * targets.tangents),
    )
    network = build_network(mesh, "gregory")
    frame = Frame.of_points(mesh.vertices)
    local = QuadMesh(frame.to_local(mesh.vertices), mesh.topology, mesh.tags)
    assert network.provenance["fallback_vertices"] == "0"
    np.testing.assert_array_equal(
        network.patches.points, assemble_gregory(interpolate_targets(local)).points
    )


def test_a_large_polygon_builds_unfolded_without_the_guard() -> None:
    """A wavy 20,000-gon, split around its centre into 20,000 slivers (a 0.018° corner at the hub,
    179.98° at each polygon corner): no face folds, so the guard has nothing to do. Its corners
    turn by 180° − 3ε/2 instead of being spread to 90°, their twists stay bilinear (the face reaches
    far beyond their edges), and the Gregory fit no longer damps h_L1 on edges much shorter than
    the model (all three folded it before)."""
    n = 20_000
    theta = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    mesh = QuadMesh.from_arrays(
        np.stack([np.cos(theta), np.sin(theta), 0.1 * np.sin(3.0 * theta)], axis=1),
        [list(range(n))],
    )
    network = build_network(mesh, "gregory")
    assert network.provenance["fallback_vertices"] == str(n)  # the narrowed corners
    report = check(network)
    assert report.folds == 0, report.fold_locations
    assert report.max_g0_gap <= 1e-12
    # a normal is c' × D with |D| the sliver's width, 3e-4 of the model at the rim and t times that
    # at parameter t from the hub (1/32 at the first samples): points rounded by ε turn it by
    # ~ε/width ≈ 2e-11 rad ≈ 1e-9°, measured 4.6e-9°
    assert max(report.max_edge_angle_deg, report.max_corner_angle_deg) <= 1e-7
