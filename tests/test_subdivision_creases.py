"""OpenSubdiv's semi-sharp creases, corners and holes in g1patch.subdivision: against Blender's
OpenSubdiv limit on the crease shapes, and the rules' own properties."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree
from test_subdivision import grid_torus, square_grid

from g1patch.compare import load_reference
from g1patch.errors import InputError
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh, Tag
from g1patch.subdivision import (
    RULE_CORNER,
    RULE_CREASE,
    RULE_SMOOTH,
    limit_corner_normals,
    limit_matrix,
    limit_normals,
    limit_points,
    limit_stars,
    limit_tangents,
    refine,
    refine_grids,
    vertex_rules,
)

CREASED = [
    "catmark_cube_creases2",
    "catmark_tent_creases1",
    "catmark_dart_edgecorner",
    "catmark_torus_creases0",
]
SMOOTH = ["catmark_cube", "catmark_torus", "catmark_xord_interior", "catmark_xord_boundary"]
#: Blender's limit evaluation isolates features to this level (the modifier's quality)
REFERENCE_ISOLATION = 6


def one_face_corners(mesh: QuadMesh) -> np.ndarray:
    topology = mesh.topology
    return np.flatnonzero(topology.is_boundary_vertex & (topology.face_count == 1))


def with_tags(mesh: QuadMesh, *tags: Tag) -> QuadMesh:
    return QuadMesh.from_arrays(mesh.vertices, mesh.faces, tags=tags)


@pytest.mark.parametrize("name", CREASED + SMOOTH)
def test_refined_limit_matches_opensubdiv(shared_data, name: str) -> None:
    """``limit_points(refine(mesh, levels))`` is the reference's point set to ≤ 1e-6 of the diagonal
    (nearest neighbour both ways: past the cage's own vertices Blender numbers the refined ones
    differently). The exception: in edge-only mode a boundary vertex with one face is a crease
    vertex whose limit is ``(E_0 + 4V + E_1)/6``; Blender's patches stop at isolation level 6 and
    put that corner at its level-6 control point, ``4^-6 (V − limit)`` away (≈ 1e-5)."""
    mesh = read_mesh(shared_data / f"{name}.obj")
    reference = load_reference(shared_data / "reference" / f"{name}.limit.npz")
    diagonal = reference.bounding_box_diagonal
    fine = refine(mesh, reference.levels)
    points = limit_points(fine)
    assert points.shape == reference.points.shape
    corners = (
        one_face_corners(mesh)
        if mesh.features.boundary != "edge-and-corner"
        else np.zeros(0, dtype=int)
    )
    ours = np.delete(np.arange(len(points)), corners)
    theirs = np.delete(np.arange(len(reference.points)), corners)
    ours_to_theirs = cKDTree(reference.points).query(points[ours])[0] / diagonal
    theirs_to_ours = cKDTree(points).query(reference.points[theirs])[0] / diagonal
    assert max(ours_to_theirs.max(), theirs_to_ours.max()) <= 1e-6
    # the cage's own vertices keep their numbers: compare them point for point
    cage = (
        np.linalg.norm(points[: mesh.n_vertices] - reference.points[: mesh.n_vertices], axis=1)
        / diagonal
    )
    assert np.delete(cage, corners).max() <= 1e-6
    if corners.size:
        level6 = refine(mesh, REFERENCE_ISOLATION).vertices[corners]
        assert np.linalg.norm(level6 - reference.points[corners], axis=1).max() / diagonal <= 1e-6
        x = mesh.vertices
        ring = np.stack([mesh.topology.one_ring(v) for v in corners])
        np.testing.assert_allclose(
            points[corners], (x[ring[:, 0]] + 4 * x[corners] + x[ring[:, 1]]) / 6, atol=1e-14
        )


@pytest.mark.parametrize("name", CREASED)
def test_cage_limit_points_match_opensubdiv(shared_data, name: str) -> None:
    """``limit_points`` of the unrefined crease cages (refined near the semi-sharp features
    inside)."""
    mesh = read_mesh(shared_data / f"{name}.obj")
    reference = load_reference(shared_data / "reference" / f"{name}.limit.npz")
    error = (
        np.linalg.norm(limit_points(mesh) - reference.points[: mesh.n_vertices], axis=1)
        / reference.bounding_box_diagonal
    )
    corners = (
        one_face_corners(mesh)
        if mesh.features.boundary != "edge-and-corner"
        else np.zeros(0, dtype=int)
    )
    assert np.delete(error, corners).max() <= 1e-6
    assert error[corners].max(initial=0.0) <= 2e-5


# ----------------------------------------------------------------------------------------------
# A small mesh with a crease line through interior vertices and a semi-sharp corner


def crease_line(size: int = 4) -> tuple[QuadMesh, np.ndarray]:
    """A bumpy (size × size)-face grid and the vertex pairs of its middle column line."""
    mesh = square_grid(size)
    column = size // 2
    line = np.array([[column * (size + 1) + j, column * (size + 1) + j + 1] for j in range(size)])
    return mesh, line


def crease_tags(
    line: np.ndarray, values, corner: tuple[int, float] | None = None, *extra: Tag
) -> tuple[Tag, ...]:
    tags = [
        Tag(
            "crease",
            tuple(line.ravel().tolist()),
            tuple(np.broadcast_to(values, len(line)).tolist()),
        )
    ]
    if corner is not None:
        tags.append(Tag("corner", (corner[0],), (corner[1],)))
    return (*tags, *extra)


def test_zero_sharpness_is_smooth() -> None:
    mesh, line = crease_line()
    tagged = with_tags(mesh, *crease_tags(line, 0.0, (12, 0.0)))
    np.testing.assert_array_equal(refine(tagged, 3).vertices, refine(mesh, 3).vertices)
    np.testing.assert_array_equal(limit_points(tagged), limit_points(mesh))
    assert not any(tag.name in ("crease", "corner") for tag in refine(tagged, 1).tags)


def test_infinite_sharpness_is_the_sharp_rule() -> None:
    """Any s ≥ 10 is OpenSubdiv's infinitely sharp crease: the same refinement, the crease rules."""
    mesh, line = crease_line()
    sharp = with_tags(mesh, *crease_tags(line, 10.0))
    beyond = with_tags(mesh, *crease_tags(line, 25.0))
    np.testing.assert_array_equal(refine(beyond, 3).vertices, refine(sharp, 3).vertices)
    x = mesh.vertices
    v = line[1, 1]  # inside the line: a crease vertex between line[1, 0] and line[2, 1]
    a, b = line[1, 0], line[2, 1]
    np.testing.assert_allclose(
        refine(sharp, 1).vertices[v], (6 * x[v] + x[a] + x[b]) / 8, atol=1e-14
    )
    np.testing.assert_allclose(limit_points(sharp)[v], (4 * x[v] + x[a] + x[b]) / 6, atol=1e-14)
    assert vertex_rules(sharp)[v] == RULE_CREASE and vertex_rules(mesh)[v] == RULE_SMOOTH
    fine = refine(sharp, 2)
    assert {tag.name for tag in fine.tags} == {"crease"} and set(fine.tags[0].floats) == {10.0}


@pytest.mark.parametrize("s", [0.25, 0.5, 0.8])
def test_fractional_sharpness_blends_the_first_step(s: float) -> None:
    """For 0 ≤ s ≤ 1 a step's edge and vertex points are ``s·sharp + (1 − s)·smooth`` (both ends of
    the crease decay together, so OpenSubdiv's fractional weight is s), hence linear in s."""
    mesh, line = crease_line()
    smooth = refine(mesh, 1).vertices
    sharp = refine(with_tags(mesh, *crease_tags(line, 1.0)), 1).vertices
    blended = refine(with_tags(mesh, *crease_tags(line, s)), 1).vertices
    np.testing.assert_allclose(blended, s * sharp + (1 - s) * smooth, atol=1e-14)


def test_sharpness_one_is_one_sharp_step_then_smooth() -> None:
    """s = 1: the first step is the infinitely sharp one (fractional weight 1); nothing is sharp
    after it."""
    mesh, line = crease_line()
    one = with_tags(mesh, *crease_tags(line, 1.0, (12, 1.0)))
    infinite = with_tags(mesh, *crease_tags(line, 10.0, (12, 10.0)))
    fine = refine(one, 1)
    np.testing.assert_array_equal(fine.vertices, refine(infinite, 1).vertices)
    assert not any(tag.name in ("crease", "corner") for tag in fine.tags)
    np.testing.assert_array_equal(
        refine(one, 3).vertices, refine(QuadMesh.from_arrays(fine.vertices, fine.faces), 2).vertices
    )


@pytest.mark.parametrize("s", [2.0, 3.0])
def test_integer_sharpness_is_that_many_sharp_steps(s: float) -> None:
    mesh, line = crease_line()
    semi = with_tags(mesh, *crease_tags(line, s, (12, s)))
    infinite = with_tags(mesh, *crease_tags(line, 10.0, (12, 10.0)))
    levels = int(s)
    np.testing.assert_allclose(
        refine(semi, levels).vertices, refine(infinite, levels).vertices, atol=1e-14
    )
    assert not any(tag.name in ("crease", "corner") for tag in refine(semi, levels).tags)
    # s = 1 + t: one sharp step, then t left on every half
    fine = refine(with_tags(mesh, *crease_tags(line, 1.3)), 1)
    np.testing.assert_allclose(
        fine.vertices, refine(with_tags(mesh, *crease_tags(line, 10.0)), 1).vertices, atol=1e-14
    )
    crease = [tag for tag in fine.tags if tag.name == "crease"]
    assert (
        len(crease) == 1
        and len(crease[0].ints) == 4 * len(line)
        and np.allclose(crease[0].floats, 0.3)
    )


@pytest.mark.parametrize("name", CREASED)
def test_refining_twice_by_one_is_refining_by_two(shared_data, name: str) -> None:
    mesh = read_mesh(shared_data / f"{name}.obj")
    twice, once = refine(refine(mesh, 1), 1), refine(mesh, 2)
    np.testing.assert_array_equal(twice.vertices, once.vertices)
    np.testing.assert_array_equal(twice.faces, once.faces)
    assert twice.tags == once.tags
    np.testing.assert_array_equal(twice.features.edge_sharpness, once.features.edge_sharpness)


def test_refined_tags_carry_the_decremented_sharpness() -> None:
    mesh, line = crease_line()
    tagged = with_tags(
        mesh, *crease_tags(line, [4.7, 2.5, 0.5, 10.0], (12, 3.0)), Tag("interpolateboundary", (1,))
    )
    fine = refine(tagged, 1)
    assert fine.tags[0] == Tag("interpolateboundary", (1,))
    features = fine.features
    nv = mesh.n_vertices
    keys = fine.topology.edges[:, 0] * fine.n_vertices + fine.topology.edges[:, 1]
    for (a, b), _, child in zip(line, [4.7, 2.5, 0.5, 10.0], [3.7, 1.5, 0.0, 10.0], strict=True):
        e = np.searchsorted(
            mesh.topology.edges[:, 0] * nv + mesh.topology.edges[:, 1], min(a, b) * nv + max(a, b)
        )
        m = nv + e
        for end in (a, b):
            half = np.searchsorted(keys, min(end, m) * fine.n_vertices + max(end, m))
            assert features.edge_sharpness[half] == pytest.approx(child)
    assert features.vertex_sharpness[12] == 2.0 and np.count_nonzero(features.vertex_sharpness) == 1
    assert np.count_nonzero(features.edge_sharpness) == 6


def test_chaikin_subdivides_the_sharpness_with_its_neighbours() -> None:
    """Chaikin: a child edge at a vertex with other semi-sharp edges takes ``0.75 s + 0.25 s̄ − 1``
    (s̄ their mean), else ``s − 1``; equal sharpness along the line is the uniform rule."""
    mesh, line = crease_line()
    method = Tag("creasemethod", strings=("chaikin",))
    uneven = with_tags(mesh, *crease_tags(line, [2.0, 4.0, 4.0, 2.0]), method)
    fine = refine(uneven, 1)
    nv, fv = mesh.n_vertices, fine.n_vertices
    edge_keys = mesh.topology.edges[:, 0] * nv + mesh.topology.edges[:, 1]
    fine_keys = fine.topology.edges[:, 0] * fv + fine.topology.edges[:, 1]

    def child(a: int, b: int, end: int) -> float:
        m = nv + np.searchsorted(edge_keys, min(a, b) * nv + max(a, b))
        return float(
            fine.features.edge_sharpness[np.searchsorted(fine_keys, min(end, m) * fv + max(end, m))]
        )

    (a0, b0), (a1, b1) = line[0], line[1]
    assert child(a0, b0, a0) == pytest.approx(1.0)  # the line's end: no other semi-sharp edge
    assert child(a0, b0, b0) == pytest.approx(0.75 * 2 + 0.25 * 4 - 1)
    assert child(a1, b1, a1) == pytest.approx(0.75 * 4 + 0.25 * 2 - 1)
    assert child(a1, b1, b1) == pytest.approx(3.0)  # its neighbour there has 4 too
    even = refine(with_tags(mesh, *crease_tags(line, 2.5), method), 3)
    np.testing.assert_allclose(
        even.vertices, refine(with_tags(mesh, *crease_tags(line, 2.5)), 3).vertices, atol=1e-14
    )
    twice = refine(refine(uneven, 1), 2)
    once = refine(uneven, 3)
    np.testing.assert_array_equal(twice.vertices, once.vertices)
    assert twice.tags == once.tags


def test_holes_take_part_and_their_children_are_holes() -> None:
    mesh, line = crease_line()
    holed = with_tags(mesh, Tag("hole", (5, 6)), *crease_tags(line, 1.5))
    plain = with_tags(mesh, *crease_tags(line, 1.5))
    fine = refine(holed, 2)
    np.testing.assert_array_equal(fine.vertices, refine(plain, 2).vertices)
    expected = np.concatenate([16 * f + np.arange(16) for f in (5, 6)])
    np.testing.assert_array_equal(np.flatnonzero(fine.features.holes), expected)
    np.testing.assert_array_equal(limit_points(holed), limit_points(plain))


def test_sharpness_argument_overrides_the_tags() -> None:
    mesh, line = crease_line()
    tagged = with_tags(mesh, *crease_tags(line, 2.0))
    np.testing.assert_array_equal(
        refine(tagged, 2, np.zeros(mesh.n_edges)).vertices, refine(mesh, 2).vertices
    )
    np.testing.assert_array_equal(
        refine(mesh, 2, tagged.features.edge_sharpness).vertices, refine(tagged, 2).vertices
    )
    np.testing.assert_array_equal(
        limit_points(mesh, tagged.features.edge_sharpness), limit_points(tagged)
    )
    with pytest.raises(InputError, match="sharpness"):
        refine(mesh, 1, -np.ones(mesh.n_edges))
    with pytest.raises(InputError, match="shape"):
        limit_points(mesh, np.zeros(3))


# ----------------------------------------------------------------------------------------------
# Limits of semi-sharp meshes: the masks on the decayed refinement


SEMI = ["catmark_tent_creases1", "catmark_dart_edgecorner", "catmark_torus_creases0"]


def decay_levels(mesh: QuadMesh) -> int:
    values = np.concatenate([mesh.features.edge_sharpness, mesh.features.vertex_sharpness])
    return int(np.ceil(values[(values > 0) & (values < 10)].max()))


@pytest.mark.parametrize("name", SEMI)
def test_semi_sharp_limits_are_those_of_the_decayed_refinement(shared_data, name: str) -> None:
    """The local refinement around the semi-sharp features gives the whole mesh's refined masks:
    positions, slot tangents (× 2^levels), stars and per-corner normals, at every affected
    vertex."""
    mesh = read_mesh(shared_data / f"{name}.obj")
    levels = decay_levels(mesh)
    fine = refine(mesh, levels)
    nv = mesh.n_vertices
    np.testing.assert_allclose(limit_points(mesh), limit_points(fine)[:nv], atol=1e-14)
    features = mesh.features
    semi = (features.edge_sharpness > 0) & (features.edge_sharpness < 10)
    near = np.zeros(nv, dtype=bool)
    near[mesh.topology.edges[semi].ravel()] = True
    near |= (features.vertex_sharpness > 0) & (features.vertex_sharpness < 10)
    offsets, fine_offsets = mesh.topology.neighbor_offsets, fine.topology.neighbor_offsets
    ours, theirs = limit_tangents(mesh), limit_tangents(fine)
    for v in np.flatnonzero(near):
        np.testing.assert_allclose(
            ours[offsets[v] : offsets[v + 1]],
            2**levels * theirs[fine_offsets[v] : fine_offsets[v] + offsets[v + 1] - offsets[v]],
            atol=1e-12,
        )
    np.testing.assert_allclose(
        limit_normals(mesh)[near], limit_normals(fine)[:nv][near], atol=1e-12
    )
    a, b = limit_stars(mesh)
    fine_a, fine_b = limit_stars(fine)
    np.testing.assert_allclose(a[near], 2**levels * fine_a[:nv][near], atol=1e-12)
    np.testing.assert_allclose(b[near], 2**levels * fine_b[:nv][near], atol=1e-12)
    # corner (f, c) is corner 0 of face 4^L f + 4^(L−1) c after L ≥ 1 steps
    f, c = np.meshgrid(np.arange(mesh.n_faces), np.arange(4), indexing="ij")
    fine_corner = limit_corner_normals(fine)[4**levels * f + 4 ** (levels - 1) * c, 0]
    np.testing.assert_allclose(limit_corner_normals(mesh), fine_corner, atol=1e-12)


def finite_difference_normals(mesh: QuadMesh, levels: int = 6) -> np.ndarray:
    """Per face corner ``(p(c+1) − p(c)) × (p(c−1) − p(c))`` of the limit points at the corner's
    smallest refined face: the limit surface's normal on that sector, to O(2^-levels)."""
    fine, grid = refine_grids(mesh, levels)
    points = limit_points(fine)
    g = grid
    corner = np.stack([g[:, 0, 0], g[:, -1, 0], g[:, -1, -1], g[:, 0, -1]], axis=1)
    after = np.stack([g[:, 1, 0], g[:, -1, 1], g[:, -2, -1], g[:, 0, -2]], axis=1)
    before = np.stack([g[:, 0, 1], g[:, -2, 0], g[:, -1, -2], g[:, 1, -1]], axis=1)
    n = np.cross(points[after] - points[corner], points[before] - points[corner])
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


@pytest.mark.parametrize("name", CREASED)
def test_corner_normals_are_the_sector_normals_of_the_limit(shared_data, name: str) -> None:
    """At smooth and crease vertices, and at corners whose sector is one face, the per-corner normal
    is the limit surface's normal on that sector (compared with finite differences of refined limit
    points). Faces at semi-sharp features are left out: their limit bends on the scale of
    2^-sharpness, too fine for the differences (there the normals are those of the decayed
    refinement, test above)."""
    mesh = read_mesh(shared_data / f"{name}.obj")
    normals = limit_corner_normals(mesh)
    estimate = finite_difference_normals(mesh)
    rules = vertex_rules(mesh)[mesh.faces]
    features = mesh.features
    semi = (
        (features.edge_sharpness > 0)
        & (features.edge_sharpness < 10)
        & (features.edge_sharpness > 0.5)
    )
    near = np.zeros(mesh.n_vertices, dtype=bool)
    near[mesh.topology.edges[semi].ravel()] = True
    near |= (features.vertex_sharpness > 0) & (features.vertex_sharpness < 10)
    checked = (rules != RULE_CORNER) & ~near[mesh.faces].any(axis=1, keepdims=True)
    if (
        name == "catmark_cube_creases2"
    ):  # the cube's corners: three sharp edges, one face per sector
        checked |= rules == RULE_CORNER
    angle = np.arccos(np.clip(np.einsum("fcd,fcd->fc", normals, estimate), -1, 1))
    assert angle[checked].max() < 0.05
    assert np.allclose(np.linalg.norm(normals, axis=-1), 1.0)


def test_crease_sectors_have_their_own_normals() -> None:
    """An infinitely sharp crease ring on a torus: the two sectors' normals differ, both hold the
    crease tangent, and a smooth vertex's corners all carry its vertex normal."""
    mesh = grid_torus(noise=0.05)
    edges = mesh.topology.edges
    crease = (edges[:, 0] // 6 == 0) & (edges[:, 1] // 6 == 0)  # the ring of vertices 0..5
    tagged = with_tags(mesh, Tag("crease", tuple(edges[crease].ravel().tolist()), (10.0,)))
    normals = limit_corner_normals(tagged)
    on_crease = tagged.faces < 6
    tangents = limit_tangents(tagged)
    for v in range(6):
        at = tagged.faces == v
        sector_normals = normals[at]
        # two normals, one per side of the crease, each perpendicular to the crease tangent
        same = sector_normals @ sector_normals[0] > 1 - 1e-12
        assert (
            same.sum() == 2 and (sector_normals[~same] @ sector_normals[~same][0] > 1 - 1e-12).all()
        )
        assert sector_normals[~same][0] @ sector_normals[0] < 0.9999
        ring = tagged.topology.one_ring(v)
        along = [
            tangents[tagged.topology.neighbor_offsets[v] + j] for j, w in enumerate(ring) if w < 6
        ]
        assert np.abs(sector_normals @ along[0]).max() < 1e-14
    smooth = ~on_crease.any(axis=1)
    vertex_normals = limit_normals(tagged)
    np.testing.assert_allclose(normals[smooth], vertex_normals[tagged.faces[smooth]], atol=1e-15)


def test_crease_tangents_are_the_crease_curve_tangents() -> None:
    """Along an infinitely sharp crease through regular vertices the slot tangent is the crease
    B-spline's ``(E_next − E_prev)/2``; across it, the finite difference of the limit surface."""
    mesh = grid_torus(noise=0.05)
    edges = mesh.topology.edges
    crease = (edges[:, 0] // 6 == 0) & (edges[:, 1] // 6 == 0)
    tagged = with_tags(mesh, Tag("crease", tuple(edges[crease].ravel().tolist()), (10.0,)))
    t = limit_tangents(tagged)
    x = tagged.vertices
    offsets = tagged.topology.neighbor_offsets
    levels = 7
    fine = refine(tagged, levels)
    fine_points = limit_points(fine)
    for v in range(6):
        for j, w in enumerate(tagged.topology.one_ring(v)):
            slot = offsets[v] + j
            if w < 6:
                other = [u for u in tagged.topology.one_ring(v) if u < 6 and u != w][0]
                np.testing.assert_allclose(t[slot], (x[w] - x[other]) / 2, atol=1e-14)
            # the fine neighbour along this edge is the edge point chain: slot j of v in the fine
            # mesh
            near = fine.topology.one_ring(v)[j]
            estimate = 2**levels * (fine_points[near] - fine_points[v])
            assert np.linalg.norm(t[slot] - estimate) < 0.05 * np.linalg.norm(t[slot])


def test_limit_matrix_reads_the_features() -> None:
    mesh, line = crease_line()
    sharp = with_tags(mesh, *crease_tags(line, 10.0, (3, 10.0)))
    matrix = limit_matrix(sharp)
    np.testing.assert_allclose(matrix @ sharp.vertices, limit_points(sharp), atol=1e-14)
    assert vertex_rules(sharp)[3] == RULE_CORNER
    np.testing.assert_array_equal((matrix @ sharp.vertices)[3], sharp.vertices[3])
    with pytest.raises(InputError, match="semi-sharp"):
        limit_matrix(with_tags(mesh, *crease_tags(line, 2.0)))
    with pytest.raises(InputError, match="semi-sharp"):
        limit_matrix(with_tags(mesh, Tag("corner", (3,), (0.5,))))


def assert_local_limits_are_global(mesh: QuadMesh) -> None:
    levels = decay_levels(mesh)
    fine = refine(mesh, levels)
    nv = mesh.n_vertices
    np.testing.assert_allclose(limit_points(mesh), limit_points(fine)[:nv], atol=1e-14)
    np.testing.assert_allclose(limit_normals(mesh), limit_normals(fine)[:nv], atol=1e-12)
    f, c = np.meshgrid(np.arange(mesh.n_faces), np.arange(4), indexing="ij")
    fine_corner = limit_corner_normals(fine)[4**levels * f + 4 ** (levels - 1) * c, 0]
    np.testing.assert_allclose(limit_corner_normals(mesh), fine_corner, atol=1e-12)


def test_local_limits_where_the_neighbourhood_is_not_a_manifold() -> None:
    """Semi-sharp corners at (2, 2) and (4, 4) of an 8 × 8 grid: the faces at them touch at (3, 3)
    only, so a ring more is taken; the limits are still the whole mesh's refined ones."""
    mesh = square_grid(8)
    tagged = with_tags(mesh, Tag("corner", (2 * 9 + 2, 4 * 9 + 4), (1.5, 2.5)))
    assert_local_limits_are_global(tagged)


def test_local_limits_with_chaikin() -> None:
    mesh, line = crease_line(6)
    tagged = with_tags(
        mesh,
        *crease_tags(np.array(line), [1.0, 3.0, 2.0, 3.5, 0.5, 2.0]),
        Tag("creasemethod", strings=("chaikin",)),
    )
    assert_local_limits_are_global(tagged)
