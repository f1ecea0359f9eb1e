"""The 2×2-split bicubic network (g1patch.construct.split4): polynomial, exactly G1, C1 inside
quads.

Acceptance measures come from continuity.check over the 4 F sub-patches, whose network covers
both the mesh edges (each split in two halves) and the internal seams:

* G1 angle ≤ 1e-9° on every refined edge and at every corner (measured: ≤ 4e-11°, Spot);
* G0 gap ≤ 1e-12 of the bbox diagonal (shared control points are bit-identical: ~1e-16);
* vertex deviation ≤ 1e-12 (it is 0: sub-patch corners at mesh vertices are the input points).

Inside each quad the pieces join C1, checked on derivatives, and the per-quad B-spline net
evaluates (scipy's NdBSpline, an independent evaluator) to the Bézier pieces. The grid-line
shear μ is checked against a plain Python walk along each line.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
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
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.interpolate import NdBSpline

from g1patch import shapes
from g1patch.build import build_gregory_network, build_split4_network
from g1patch.construct.split4 import BSPLINE_KNOTS, _chain_shears, bspline_nets, macro_nets
from g1patch.continuity import ContinuityReport, check
from g1patch.errors import G1PatchError, InputError
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh
from g1patch.network import check_consistent
from g1patch.patches import PatchSet
from g1patch.targets.interpolate import tangent_stars
from g1patch.targets.local import fan_normals


def collapsed(base: QuadMesh, picks: Sequence[int]) -> QuadMesh | None:
    """``base`` with the quads ``picks`` collapsed along their 0–2 diagonal (the two corners merge
    at their midpoint): valence-3 and even-valence (6, 8, …) vertices, adjacent when picks touch.
    None where the result is not a valid manifold quad mesh."""
    faces, vertices = base.faces.copy(), base.vertices.copy()
    root = np.arange(len(vertices))

    def find(a: int) -> int:
        while root[a] != a:
            a = root[a]
        return a

    keep = np.ones(len(faces), dtype=bool)
    for f in picks:
        a, c = find(faces[f, 0]), find(faces[f, 2])
        if a == c:
            return None
        root[c] = a
        vertices[a] = 0.5 * (vertices[a] + vertices[c])
        keep[f] = False
    final = np.array([find(i) for i in range(len(vertices))])
    try:
        return QuadMesh.from_arrays(vertices, final[faces[keep]])
    except G1PatchError:
        return None


def build_and_check(mesh: QuadMesh, shape: str = "interpolate") -> ContinuityReport:
    network = build_split4_network(mesh, shape=shape)  # type: ignore[arg-type]
    check_consistent(network)
    topology = mesh.topology
    assert network.n_patches == 4 * topology.n_faces
    interior = int((~topology.is_boundary_edge).sum())
    report = check(network)
    assert (
        report.shared_edges == 2 * interior + 4 * topology.n_faces
    )  # two halves per mesh edge + 4 seams per quad
    return report


# ------------------------------------------------------------------------------ shared meshes
@pytest.mark.parametrize("name", SHARED_MESHES)
@pytest.mark.parametrize("shape", INTERPOLATING)
def test_shared_meshes_are_exactly_g1(shared_data: Path, name: str, shape: str) -> None:
    mesh = read_mesh(shared_data / name)
    network = build_split4_network(mesh, shape=shape)  # type: ignore[arg-type]
    assert network.provenance["method"] == "split4" and network.provenance["shape"] == shape
    assert isinstance(network.patches, PatchSet) and network.patches.form == "bezier"
    corners = network.patches.world_control()[:, [0, 3, 3, 0], [0, 0, 3, 3]].reshape(-1, 4, 4, 3)
    np.testing.assert_allclose(
        corners[:, np.arange(4), np.arange(4)],
        mesh.vertices[mesh.faces],
        rtol=0,
        atol=4 * np.finfo(float).eps * np.abs(mesh.vertices).max(),
    )  # stored in the working frame
    assert_exact_g1(build_and_check(mesh, shape))


@pytest.mark.slow
@settings(deadline=None, max_examples=20)
@given(
    st.sampled_from(SHARED_MESHES),
    st.floats(0.0, NOISE),
    st.integers(0, 2**32 - 1),
    st.sampled_from(INTERPOLATING),
)
def test_perturbed_shared_meshes_are_exactly_g1(
    name: str, amplitude: float, seed: int, shape: str
) -> None:
    from conftest import shared_data_path

    mesh = perturbed(read_mesh(shared_data_path(name)), amplitude, seed)
    assert_exact_g1(build_and_check(mesh, shape))


# ------------------------------------------------------------------------------ generated meshes


@pytest.mark.slow
@settings(deadline=None, max_examples=120)
@given(noisy_generated_meshes())
def test_generated_meshes_are_exactly_g1(drawn: tuple[QuadMesh, str]) -> None:
    mesh, shape = drawn
    assert_exact_g1(build_and_check(mesh, shape))


@pytest.mark.parametrize("valence", range(3, 13))
def test_every_interior_valence(valence: int) -> None:
    """A lifted, noisy fan: interior valence n next to valence-4 and -3 vertices and the
    boundary."""
    mesh = shapes.fan(valence, 3)
    lifted = mesh.with_vertices(
        mesh.vertices + np.c_[0 * mesh.vertices[:, :2], 0.1 * mesh.vertices[:, 0] ** 2]
    )
    assert_exact_g1(build_and_check(perturbed(lifted, NOISE, valence)))


@pytest.mark.parametrize("k", range(1, 8))
def test_every_boundary_face_count(k: int) -> None:
    assert_exact_g1(build_and_check(perturbed(shapes.boundary_fan(k), NOISE, k)))


COLLAPSE_BASES: dict[str, Callable[[int], QuadMesh]] = {
    "grid": lambda n: shapes.grid(n, n, height=height),
    "cube_sphere": lambda n: shapes.cube_sphere(1 + n % 2),
}


@pytest.mark.slow
@settings(deadline=None, max_examples=120)
@given(
    st.sampled_from(sorted(COLLAPSE_BASES)),
    st.integers(3, 9),
    st.lists(st.integers(0, 10**6), min_size=1, max_size=6, unique=True),
    st.floats(0.0, 0.03),
    st.integers(0, 2**32 - 1),
)
def test_collapsed_meshes_are_exactly_g1(
    base: str, n: int, picks: list[int], amplitude: float, seed: int
) -> None:
    """Diagonal collapses: valence 3, 5, 6, 8, … with adjacent even-valence (≥ 6) vertices, open and
    closed."""
    mesh = COLLAPSE_BASES[base](n)
    mesh = collapsed(mesh, sorted({p % mesh.topology.n_faces for p in picks}))
    assume(mesh is not None)
    assert mesh is not None
    assert_exact_g1(build_and_check(perturbed(mesh, amplitude, seed)), folds=False)


def adjacent_even_valence(mesh: QuadMesh) -> bool:
    t = mesh.topology
    even = ~t.is_boundary_vertex & (t.valence >= 6) & (t.valence % 2 == 0)
    return bool((even[t.edges[:, 0]] & even[t.edges[:, 1]]).any())


@pytest.mark.parametrize(
    ("picks", "valences"), [([9, 19], {6}), ([18, 28, 34, 43], {6, 8}), ([12, 29, 45, 46], {5, 6})]
)
def test_adjacent_even_valence_clusters(picks: list[int], valences: set[int]) -> None:
    """Clusters of adjacent even-valence vertices are solved jointly (one sparse min-norm solve)."""
    mesh = collapsed(shapes.grid(8, 8, height=height), picks)
    assert mesh is not None
    t = mesh.topology
    assert valences <= set(t.valence[~t.is_boundary_vertex].tolist()) and adjacent_even_valence(
        mesh
    )
    assert_exact_g1(build_and_check(perturbed(mesh, 0.02, 5)))


LONG_GRID = shapes.grid(40, 3, size=(40.0, 3.0), height=lambda x, y: 0.3 * np.sin(0.5 * x) * y)


@pytest.mark.parametrize("mesh", [LONG_GRID, shapes.torus(60, 5)], ids=["grid", "torus"])
def test_long_grid_lines(mesh: QuadMesh) -> None:
    """One collapse sends sheared grid lines of ~40–60 edges through valence-4 vertices (closed ones
    on the torus)."""
    picked = collapsed(mesh, [mesh.topology.n_faces // 2 + 1])
    assert picked is not None
    mu = _shears(picked)
    assert np.count_nonzero(mu) >= 30
    assert_exact_g1(build_and_check(perturbed(picked, 0.02, 11)))


# ------------------------------------------------------------------------------ grid-line shear
def _shears(mesh: QuadMesh) -> np.ndarray:
    t = mesh.topology
    _, cosine = tangent_stars(mesh, fan_normals(mesh))
    h = t.edge_halfedges[:, 0]
    return _chain_shears(t, cosine[np.stack([t.origin(h), t.target(h)], axis=1)])


def walked_shears(mesh: QuadMesh) -> np.ndarray:
    """Reference: walk each grid line edge by edge (Python), |μ| = max end mismatch, signs
    alternating."""
    t = mesh.topology
    _, cosine = tangent_stars(mesh, fan_normals(mesh))
    through = ~t.is_boundary_vertex & (t.valence == 4)
    x_of, y_of = t.origin(t.edge_halfedges[:, 0]), t.target(t.edge_halfedges[:, 0])
    ring_edges = {v: [int(t.halfedge_edge[h]) for h in t.ring(v)] for v in np.flatnonzero(through)}

    def continuation(e: int, v: int) -> int:
        ring = ring_edges[v]
        return ring[(ring.index(e) + 2) % 4]

    mu = np.zeros(t.n_edges)
    seen: set[int] = set()
    for start in range(t.n_edges):
        if start in seen or t.is_boundary_edge[start]:
            continue
        # run back to an end (or all round a closed line), then forward collecting (edge, far
        # vertex)
        e, v = start, int(x_of[start])
        for _ in range(t.n_edges):
            if not through[v]:
                break
            e = continuation(e, v)
            v = int(x_of[e] + y_of[e] - v)
            if e == start:
                break
        closed = through[v]
        line, near = [], v
        while True:
            far = int(x_of[e] + y_of[e] - near)
            line.append((e, near, far))
            seen.add(e)
            if not through[far]:
                break
            e, near = continuation(e, far), far
            if e == line[0][0]:
                break
        if closed:
            continue
        first, last = line[0], line[-1]
        gaps = [cosine[first[1]] - cosine[first[2]], cosine[last[2]] - cosine[last[1]]]
        size = max(abs(g) for g in gaps)
        # λ towards the k-th vertex along the line alternates: ε_k = (−1)^k ε_0
        nodes = [
            2 * first[0] + (x_of[first[0]] != first[1]),
            2 * last[0] + (x_of[last[0]] != last[2]),
        ]
        at_start = (-abs(gaps[0]), nodes[0]) <= (
            -abs(gaps[1]),
            nodes[1],
        )  # ties: the smaller node 2e + side
        sign0 = -np.sign(gaps[0]) if at_start else -np.sign(gaps[1]) * (-1) ** len(line)
        for k, (edge, _near_v, far_v) in enumerate(line):
            towards_far = sign0 * size * (-1) ** (k + 1)
            mu[edge] = towards_far if x_of[edge] == far_v else -towards_far
    return mu


@pytest.mark.parametrize(
    "mesh",
    [shapes.fan(5, 3), shapes.cube_sphere(2), shapes.torus(6, 5), shapes.boundary_fan(5)],
    ids=["fan5", "cube_sphere", "torus", "boundary_fan"],
)
def test_chain_shears_match_a_walk(mesh: QuadMesh) -> None:
    np.testing.assert_allclose(_shears(mesh), walked_shears(mesh), atol=1e-15)


@settings(deadline=None, max_examples=30)
@given(st.integers(3, 8), st.lists(st.integers(0, 10**6), min_size=1, max_size=4, unique=True))
def test_chain_shears_match_a_walk_on_collapsed_grids(n: int, picks: list[int]) -> None:
    mesh = collapsed(shapes.grid(n, n, height=height), sorted({p % (n * n) for p in picks}))
    assume(mesh is not None)
    assert mesh is not None
    mu = _shears(mesh)
    np.testing.assert_allclose(mu, walked_shears(mesh), atol=1e-15)
    t = mesh.topology  # λ towards a valence-4 vertex is the same from opposite ring edges
    for v in np.flatnonzero(~t.is_boundary_vertex & (t.valence == 4)):
        ring = t.ring(v)
        edges = t.halfedge_edge[ring]
        towards_v = np.where(t.edge_halfedges[edges, 0] == ring, mu[edges], -mu[edges])
        assert towards_v[0] == towards_v[2] and towards_v[1] == towards_v[3]


# ------------------------------------------------------------------------------ inside a quad
C1_MESHES = [
    perturbed(shapes.fan(7, 2), NOISE, 1),
    perturbed(collapsed(shapes.grid(6, 6, height=height), [14, 21]), 0.02, 2),
    # fmt: skip
    perturbed(shapes.genus2(), NOISE, 3),
    perturbed(shapes.boundary_fan(5), NOISE, 4),
]
C1_IDS = ["fan7", "collapsed", "genus2", "boundary_fan"]


@pytest.mark.parametrize("mesh", C1_MESHES, ids=C1_IDS)
def test_pieces_join_c1_inside_each_quad(mesh: QuadMesh) -> None:
    """Across a seam both pieces have equal position and equal first derivatives (each piece spans
    half the quad, so equal derivatives per piece are equal derivatives per quad)."""
    patches = build_split4_network(mesh).patches
    t = np.linspace(0.0, 1.0, 17)
    zero, one = np.zeros_like(t), np.ones_like(t)
    pairs = [  # (piece a, its parameters, piece b, its parameters) along the four seams
        (0, np.c_[one, t], 1, np.c_[zero, t]),
        (3, np.c_[one, t], 2, np.c_[zero, t]),
        (0, np.c_[t, one], 3, np.c_[t, zero]),
        (1, np.c_[t, one], 2, np.c_[t, zero]),
    ]
    faces = np.arange(mesh.topology.n_faces) * 4
    scale = np.abs(patches.control).max()
    for a, uv_a, b, uv_b in pairs:
        for du, dv in ((0, 0), (1, 0), (0, 1)):
            left = patches.take(faces + a).evaluate(uv_a, du, dv)
            right = patches.take(faces + b).evaluate(uv_b, du, dv)
            np.testing.assert_allclose(left, right, rtol=0, atol=1e-13 * scale)


@pytest.mark.parametrize("mesh", C1_MESHES, ids=C1_IDS)
def test_bspline_nets_evaluate_to_the_pieces(mesh: QuadMesh) -> None:
    """scipy's NdBSpline on the (F, 6, 6, 3) nets with knots [0,0,0,0,½,½,1,1,1,1] equals the
    pieces."""
    network = build_split4_network(mesh)
    nets = bspline_nets(network)
    assert nets.shape == (mesh.topology.n_faces, 6, 6, 3)
    s = np.linspace(0.0, 1.0, 9)
    u, v = np.meshgrid(s, s, indexing="ij")
    scale = np.abs(nets).max()
    for f in range(0, mesh.topology.n_faces, max(1, mesh.topology.n_faces // 8)):
        spline = NdBSpline((BSPLINE_KNOTS, BSPLINE_KNOTS), nets[f], 3)
        for k, (su, sv) in enumerate(((0, 0), (1, 0), (1, 1), (0, 1))):
            expected = network.patches.take([4 * f + k]).evaluate_grid(s, s)[0]
            points = np.stack([0.5 * (su + u), 0.5 * (sv + v)], axis=-1).reshape(-1, 2)
            np.testing.assert_allclose(
                spline(points).reshape(9, 9, 3), expected, rtol=0, atol=1e-13 * scale
            )


def test_macro_net_rows_three_are_midpoints() -> None:
    """Row and column 3 of every 7×7 macro net are the midpoints of their neighbours (C1 ⇔ double
    knot)."""
    nets = macro_nets(
        build_split4_network(perturbed(shapes.cube_sphere(1), NOISE, 8)).patches.world_control()
    )
    scale = np.abs(nets).max()
    np.testing.assert_allclose(
        nets[:, 3], 0.5 * (nets[:, 2] + nets[:, 4]), rtol=0, atol=1e-14 * scale
    )
    np.testing.assert_allclose(
        nets[:, :, 3], 0.5 * (nets[:, :, 2] + nets[:, :, 4]), rtol=0, atol=1e-14 * scale
    )


# ------------------------------------------------------------------------------ other properties
def test_network_connectivity_and_points() -> None:
    mesh = perturbed(shapes.fan(5, 2), NOISE, 9)
    network = build_split4_network(mesh)
    t = mesh.topology
    assert network.n_corners == t.n_vertices + t.n_edges + t.n_faces
    assert network.vertices is not None and network.vertex_normals is not None
    corners = network.patches.evaluate(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
    np.testing.assert_allclose(corners, network.vertices[network.corner_ids], rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(network.vertex_normals, axis=1), 1.0)
    assert len(network.open_edges()[0]) == 2 * int(t.is_boundary_edge.sum())


def test_similarity_invariance() -> None:
    """Built in centred, unit-scaled coordinates: a moved and scaled mesh gives the moved and scaled
    surface."""
    mesh = perturbed(shapes.cube_sphere(1), NOISE, 10)
    moved = mesh.with_vertices(1000.0 + 250.0 * mesh.vertices)
    a = build_split4_network(mesh).patches.world_control()
    b = build_split4_network(moved).patches.world_control()
    np.testing.assert_allclose(b, 1000.0 + 250.0 * a, rtol=0, atol=1e-10 * 250.0)
    assert_exact_g1(check(build_split4_network(moved)))


def test_close_to_the_gregory_network() -> None:
    """Same stars and boundary tangents: the two exact surfaces stay within a few % of the bbox."""
    mesh = perturbed(shapes.cube_sphere(2), NOISE, 12)
    split = (
        build_split4_network(mesh)
        .patches.evaluate_grid(np.linspace(0.0, 1.0, 5))
        .reshape(-1, 4, 5, 5, 3)
    )
    gregory = build_gregory_network(mesh).patches.evaluate_grid(np.linspace(0.0, 1.0, 9))
    pieces = np.stack(
        [gregory[:, :5, :5], gregory[:, 4:, :5], gregory[:, 4:, 4:], gregory[:, :5, 4:]], axis=1
    )
    np.testing.assert_allclose(split[:, 0, 0, 0], pieces[:, 0, 0, 0], atol=1e-15)  # mesh vertices
    assert np.abs(split - pieces).max() < 0.05 * 2.0 * np.sqrt(3.0)


def test_unknown_tangent_rule() -> None:
    with pytest.raises(InputError, match="tangents: unknown value 'bogus'"):
        build_split4_network(shapes.cube(), tangents="bogus")  # type: ignore[arg-type]


def test_bspline_nets_needs_split4_pieces() -> None:
    with pytest.raises(InputError, match="bspline_nets"):
        bspline_nets(PatchSet(np.zeros((3, 4, 4, 3))))


def test_blocked_assembly_does_not_depend_on_the_block_size(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The sub-patch controls are assembled in blocks of faces: any block size (one face, a
    partial last block, all faces at once) gives bit-identical controls."""
    from g1patch.construct.split4 import reference as split4

    mesh = perturbed(shapes.fan(5, 2), NOISE, 9)  # open, with boundary vertices
    reference = build_split4_network(mesh).patches.world_control()
    for block in (1, 7, 4 * mesh.topology.n_faces):
        monkeypatch.setattr(split4, "_BLOCK", block)
        np.testing.assert_array_equal(build_split4_network(mesh).patches.world_control(), reference)


@pytest.mark.parametrize("k", [2, 3, 5])
def test_a_turning_rim_gets_the_nearest_fan_of_equal_sectors(k: int) -> None:
    """A boundary vertex whose rim turns (``boundary_fan(k)``: its k quads span kπ/(k + 1), lifted
    onto z = r²/4). A split4 build's star there steps by Φ/k, Φ the turn of the target fan, not π/k
    (a straight rim); the re-assembly of a Gregory network takes the nearest fan whose sectors have
    equal areas (all split4 needs on a boundary), so the rim keeps its turn and spacing; both are
    exactly G1, and the re-assembly lies within 6e-4 of the diagonal of the Gregory surface
    (measured 3.5e-5, 4.5e-4, 4.4e-4; with regular stars of the rim's own turn 3.2e-4, 4.6e-3,
    5.4e-3, with straight rim stars 1.4e-2, 7.5e-3, 8.4e-3)."""
    from g1patch.construct.polynomial import split4_of_gregory, surface_deviation
    from g1patch.construct.split4 import split4_star
    from g1patch.targets.interpolate import interpolate_targets

    mesh = shapes.boundary_fan(k)
    lifted = mesh.vertices.copy()
    lifted[:, 2] = 0.25 * (lifted[:, 0] ** 2 + lifted[:, 1] ** 2)
    mesh = mesh.with_vertices(lifted)
    targets = interpolate_targets(mesh)
    n = targets.normals[0]
    wanted = sum(
        np.arctan2(np.cross(a, b) @ n, a @ b)
        for a, b in itertools.pairwise(targets.tangents[: k + 1])
    )
    assert split4_star(targets).cosine[: k + 1] == pytest.approx(
        np.cos(wanted / k), abs=1e-12
    )  # a build: regular
    stars = split4_star(targets, equal_sectors=True)
    fan = stars.star[: k + 1]  # vertex 0, the hub
    areas = np.array([np.cross(a, b) @ n for a, b in itertools.pairwise(fan)])
    assert np.abs(areas - areas.mean()).max() <= 1e-13 * areas.mean()
    turn = sum(np.arctan2(np.cross(a, b) @ n, a @ b) for a, b in itertools.pairwise(fan))
    assert turn == pytest.approx(wanted, abs=np.radians(12.0))  # not π: the rim turns
    assert_exact_g1(check(build_split4_network(mesh)))
    gregory = build_gregory_network(mesh)
    assert (
        surface_deviation(gregory, split4_of_gregory(gregory))[1]
        <= 6e-4 * gregory.bounding_box_diagonal()
    )


@pytest.mark.parametrize(
    "mesh",
    [shapes.box_cage(), shapes.genus2(), shapes.noisy_sphere(1), shapes.boundary_fan(4)],
    ids=["box_cage", "genus2", "noisy_sphere", "boundary_fan"],
)
def test_equal_sector_fans_are_nearer_than_regular_stars(mesh: QuadMesh) -> None:
    """With ``equal_sectors``, at boundary vertices and odd valences the fan is one of equal sectors
    (the nearest to the targets): its sectors' areas agree to 1e-12, each relation
    ``t_{j−1} + t_{j+1} = 2 c_j t_j`` holds to rounding, and the re-assembly of the Gregory network
    that uses them is exactly G1."""
    from g1patch.construct import split4
    from g1patch.construct.polynomial import split4_of_gregory
    from g1patch.targets.interpolate import interpolate_targets

    targets = interpolate_targets(mesh)
    topology = targets.topology
    stars = split4.split4_star(targets, equal_sectors=True)
    boundary = topology.is_boundary_vertex
    chosen = np.flatnonzero(
        np.where(boundary, topology.face_count >= 2, topology.valence % 2 == 1) & ~stars.shrunk
    )
    assert chosen.size
    for v in chosen:
        lo, hi = topology.neighbor_offsets[v], topology.neighbor_offsets[v + 1]
        fan, n = stars.star[lo:hi], targets.normals[v]
        pairs = list(itertools.pairwise(fan)) + ([] if boundary[v] else [(fan[-1], fan[0])])
        areas = np.array([np.cross(a, b) @ n for a, b in pairs])
        assert np.abs(areas - areas.mean()).max() <= 1e-12 * areas.mean()
        inner = range(1, len(fan) - 1) if boundary[v] else range(len(fan))
        for j in inner:
            relation = fan[j - 1] + fan[(j + 1) % len(fan)] - 2.0 * stars.cosine[lo + j] * fan[j]
            assert np.linalg.norm(relation) <= 1e-13 * np.linalg.norm(fan[j])
    assert_exact_g1(check(split4_of_gregory(build_gregory_network(mesh))))


def test_the_deviation_finds_foot_points_in_the_next_patch() -> None:
    """``surface_deviation`` against the distance to a fine triangulation of the Gregory surface (64
    steps a patch) from the same split4 samples: the same to 2 % (an upper bound: never below it by
    more than the chords lie off the surface, measured at the cells' middles), where searching from
    one start, stuck at the edge of its patch, overestimated 4.7× (lifted boundary_fan(3): 1.4e-2
    against 3.0e-3)."""
    from g1patch.compare import mesh_distance, surface_samples
    from g1patch.construct.polynomial import split4_of_gregory, surface_deviation

    mesh = shapes.boundary_fan(3)
    lifted = mesh.vertices.copy()
    lifted[:, 2] = 0.25 * (lifted[:, 0] ** 2 + lifted[:, 1] ** 2)
    gregory = build_gregory_network(mesh.with_vertices(lifted))
    split4 = split4_of_gregory(gregory)
    steps = 65
    points = surface_samples(gregory, steps)[0]
    grid = np.arange(steps * steps).reshape(steps, steps)
    quads = np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], axis=-1).reshape(
        -1, 4
    )
    quads = (quads[None] + steps * steps * np.arange(len(points))[:, None, None]).reshape(-1, 4)
    half = np.linspace(0.0, 1.0, 3)  # surface_deviation's default: 5 samples a quad, 3 a sub-patch
    samples = split4.patches.evaluate(
        np.stack(np.meshgrid(half, half, indexing="ij"), axis=-1).reshape(-1, 2)
    )
    exact = mesh_distance(samples, points.reshape(-1, 3), quads).max()
    centres = surface_samples(gregory, 2 * steps - 1)[0][
        :, 1::2, 1::2
    ]  # the cells' middles on the surface
    corners = 0.25 * (
        points[:, :-1, :-1] + points[:, 1:, :-1] + points[:, 1:, 1:] + points[:, :-1, 1:]
    )
    sag = float(
        np.linalg.norm(centres - corners, axis=-1).max()
    )  # how far the chords lie off the surface
    assert exact - sag <= surface_deviation(gregory, split4)[1] <= 1.02 * exact
