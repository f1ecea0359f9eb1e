"""QuadTopology / QuadMesh: half-edge invariants, counter-clockwise rings, validation errors,
splitting."""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.errors import (
    DegenerateFaceError,
    InputError,
    MeshError,
    NonManifoldError,
    OrientationError,
    ValenceError,
)
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh, QuadTopology, Tag, refine_polygons

SHAPES: dict[str, Callable[[], QuadMesh]] = {
    "cube": shapes.cube,
    "cube_sphere0": lambda: shapes.cube_sphere(0),
    "cube_sphere3": lambda: shapes.cube_sphere(3),
    "grid3x2": lambda: shapes.grid(3, 2),
    "grid1x1": lambda: shapes.grid(1, 1),
    "strip5": lambda: shapes.strip(5),
    "torus8x4": lambda: shapes.torus(8, 4),
    "torus3x3": lambda: shapes.torus(3, 3),
    "fan3": lambda: shapes.fan(3),
    "fan7x3": lambda: shapes.fan(7, rings=3),
    "boundary_fan1": lambda: shapes.boundary_fan(1),
    "boundary_fan5": lambda: shapes.boundary_fan(5),
    "genus2": shapes.genus2,
    "genus2_refined": lambda: shapes.subdivide(shapes.genus2()),
}


def assert_topology_invariants(topology: QuadTopology) -> None:
    """Every relation the half-edge arrays promise, checked from first principles."""
    t = topology
    h = np.arange(t.n_halfedges)
    origin, target = t.origin(h), t.target(h)
    np.testing.assert_array_equal(origin, t.faces.ravel())
    np.testing.assert_array_equal(t.next(t.prev(h)), h)
    np.testing.assert_array_equal(t.next(t.next(t.next(t.next(h)))), h)

    # twins: an involution between opposite half-edges; -1 exactly on boundary edges
    paired = t.twin >= 0
    np.testing.assert_array_equal(t.twin[t.twin[paired]], h[paired])
    np.testing.assert_array_equal(origin[t.twin[paired]], target[paired])
    np.testing.assert_array_equal(target[t.twin[paired]], origin[paired])
    assert np.count_nonzero(~paired) == np.count_nonzero(t.is_boundary_edge)

    # edges: unique sorted pairs, each with its one or two half-edges
    assert (t.edges[:, 0] < t.edges[:, 1]).all()
    assert np.unique(t.edges, axis=0).shape == t.edges.shape
    np.testing.assert_array_equal(
        t.edges[t.halfedge_edge], np.sort(np.stack([origin, target], axis=1), axis=1)
    )
    np.testing.assert_array_equal(t.is_boundary_edge, t.edge_halfedges[:, 1] < 0)
    listed = t.edge_halfedges[t.edge_halfedges >= 0]
    np.testing.assert_array_equal(np.sort(listed), h)
    np.testing.assert_array_equal(t.halfedge_edge[t.edge_halfedges[:, 0]], np.arange(t.n_edges))

    # counts
    np.testing.assert_array_equal(t.valence, np.bincount(t.edges.ravel(), minlength=t.n_vertices))
    np.testing.assert_array_equal(
        t.face_count, np.bincount(t.faces.ravel(), minlength=t.n_vertices)
    )
    np.testing.assert_array_equal(t.valence, t.face_count + t.is_boundary_vertex)
    boundary_vertices = np.unique(t.edges[t.is_boundary_edge])
    np.testing.assert_array_equal(np.flatnonzero(t.is_boundary_vertex), boundary_vertices)
    assert (t.valence[~t.is_boundary_vertex] >= 3).all()

    # rings: every half-edge once, grouped by origin, h_{i+1} = twin(prev(h_i))
    np.testing.assert_array_equal(np.diff(t.ring_offsets), t.face_count)
    np.testing.assert_array_equal(np.sort(t.ring_halfedges), h)
    ring_vertex = np.repeat(np.arange(t.n_vertices), t.face_count)
    np.testing.assert_array_equal(t.origin(t.ring_halfedges), ring_vertex)
    first, last = t.ring_offsets[:-1], t.ring_offsets[1:] - 1
    not_last = np.setdiff1d(np.arange(t.ring_halfedges.size), last)
    np.testing.assert_array_equal(
        t.next_ccw(t.ring_halfedges[not_last]), t.ring_halfedges[not_last + 1]
    )
    interior = ~t.is_boundary_vertex
    np.testing.assert_array_equal(
        t.next_ccw(t.ring_halfedges[last[interior]]), t.ring_halfedges[first[interior]]
    )
    assert (t.twin[t.ring_halfedges[first[~interior]]] == -1).all()
    assert (t.next_ccw(t.ring_halfedges[last[~interior]]) == -1).all()

    # neighbours: the targets of the ring, plus the far end of the incoming boundary edge
    np.testing.assert_array_equal(np.diff(t.neighbor_offsets), t.valence)
    for v in range(t.n_vertices):
        ring_targets = t.target(t.ring(v))
        expected = (
            ring_targets
            if interior[v]
            else np.append(ring_targets, t.origin(t.prev(t.ring(v)[-1])))
        )
        np.testing.assert_array_equal(t.one_ring(v), expected)
        adjacent = np.sort(
            np.concatenate([t.edges[t.edges[:, 0] == v, 1], t.edges[t.edges[:, 1] == v, 0]])
        )
        np.testing.assert_array_equal(np.sort(t.one_ring(v)), adjacent)

    assert t.euler_characteristic == t.n_vertices - t.n_edges + t.n_faces
    assert t.is_closed == (not t.is_boundary_edge.any())
    for loop in t.boundary_loops():  # consecutive loop vertices are joined by boundary half-edges
        steps = set(zip(loop.tolist(), np.roll(loop, -1).tolist(), strict=True))
        boundary = set(zip(origin[~paired].tolist(), target[~paired].tolist(), strict=True))
        assert steps <= boundary
    assert sum(len(loop) for loop in t.boundary_loops()) == np.count_nonzero(t.is_boundary_edge)


def face_vector_areas(mesh: QuadMesh) -> np.ndarray:
    corners = mesh.vertices[mesh.faces]
    return 0.5 * np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])


def assert_rings_turn_with_faces(mesh: QuadMesh) -> None:
    """Consecutive ring neighbours n_i, n_{i+1} span the face between them counter-clockwise:
    ((n_i − v) × (n_{i+1} − v)) · (that face's normal) > 0."""
    t = mesh.topology
    ring = t.ring_halfedges
    v = mesh.vertices[t.origin(ring)]
    a = mesh.vertices[t.target(ring)] - v
    b = mesh.vertices[t.origin(t.prev(ring))] - v
    normals = face_vector_areas(mesh)[ring // 4]
    assert (np.einsum("ij,ij->i", np.cross(a, b), normals) > 0).all()


@pytest.mark.parametrize("name", SHAPES)
def test_invariants_on_generated_shapes(name: str) -> None:
    mesh = SHAPES[name]()
    assert_topology_invariants(mesh.topology)
    assert_rings_turn_with_faces(mesh)


@pytest.mark.slow
def test_invariants_on_shared_meshes(shared_data) -> None:
    for path in sorted(shared_data.glob("*.obj")):
        mesh = read_mesh(path)
        assert_topology_invariants(mesh.topology)
        assert_rings_turn_with_faces(mesh)


@pytest.mark.parametrize(
    "mesh",
    [shapes.grid(4, 3), shapes.fan(5, rings=2), shapes.fan(12), shapes.boundary_fan(4)],
    ids=["grid", "fan5x2", "fan12", "boundary_fan4"],
)
def test_rings_are_counter_clockwise_in_the_plane(mesh: QuadMesh) -> None:
    """Planar meshes facing +z: neighbour angles about a vertex increase, by one full turn inside,
    less outside."""
    t = mesh.topology
    for v in range(t.n_vertices):
        offsets = mesh.vertices[t.one_ring(v)] - mesh.vertices[v]
        angles = np.arctan2(offsets[:, 1], offsets[:, 0])
        if t.is_boundary_vertex[v]:
            turns = np.mod(np.diff(angles), 2 * np.pi)
            assert (turns > 0).all() and (turns < np.pi).all() and turns.sum() < 2 * np.pi
        else:
            turns = np.mod(np.diff(np.append(angles, angles[0])), 2 * np.pi)
            assert (turns > 0).all() and turns.sum() == pytest.approx(2 * np.pi)


def test_grid_vertex_rings_by_hand() -> None:
    t = shapes.grid(2, 2).topology  # vertices j * 3 + i
    np.testing.assert_array_equal(t.one_ring(4), [3, 1, 5, 7])  # left, down, right, up
    np.testing.assert_array_equal(t.one_ring(1), [2, 4, 0])  # boundary: along the boundary first
    np.testing.assert_array_equal(t.one_ring(0), [1, 3])
    np.testing.assert_array_equal(t.ring(4), [2, 7, 12, 9])
    assert [loop.tolist() for loop in t.boundary_loops()] == [[0, 1, 2, 5, 8, 7, 6, 3]]


def test_boundary_loops_of_a_grid_with_a_hole() -> None:
    grid = shapes.grid(3, 3)
    faces = np.delete(grid.faces, 4, axis=0)  # the middle quad
    t = QuadTopology.from_faces(faces)
    outer, inner = t.boundary_loops()
    assert outer.tolist() == [0, 1, 2, 3, 7, 11, 15, 14, 13, 12, 8, 4]
    assert inner.tolist() == [6, 5, 9, 10]  # clockwise seen from +z: the faces stay on the left
    assert t.euler_characteristic == 0


@pytest.mark.parametrize("valence", [3, 5, 8])
def test_fan_centre_valence(valence: int) -> None:
    t = shapes.fan(valence, rings=2).topology
    assert t.valence[0] == valence and not t.is_boundary_vertex[0]
    assert np.count_nonzero(~t.is_boundary_vertex) == 1 + 2 * valence


def test_boundary_fan_centre() -> None:
    t = shapes.boundary_fan(4).topology
    assert t.is_boundary_vertex[0] and t.face_count[0] == 4 and t.valence[0] == 5
    np.testing.assert_array_equal(t.one_ring(0), [1, 2, 3, 4, 5])


def test_counts_and_properties() -> None:
    mesh = shapes.cube()
    t = mesh.topology
    assert (t.n_faces, t.n_edges, t.n_halfedges, t.n_vertices) == (6, 12, 24, 8)
    assert t.is_closed and t.n_components == 1 and t.boundary_loops() == []
    assert mesh.n_vertices == 8 and mesh.n_faces == 6 and mesh.n_edges == 12
    assert mesh.faces is t.faces
    assert mesh.bounding_box_diagonal == pytest.approx(2 * np.sqrt(3))
    low, high = mesh.bounding_box
    np.testing.assert_array_equal(low, [-1, -1, -1])
    np.testing.assert_array_equal(high, [1, 1, 1])


def test_arrays_are_read_only() -> None:
    mesh = shapes.cube()
    with pytest.raises(ValueError):
        mesh.vertices[0, 0] = 5.0
    with pytest.raises(ValueError):
        mesh.topology.twin[0] = 3


def test_from_arrays_copies_its_input() -> None:
    vertices = shapes.cube().vertices.copy()
    mesh = QuadMesh.from_arrays(vertices, shapes.cube().faces)
    vertices[0] = 7.0
    assert mesh.vertices[0, 0] == -1.0


def test_with_vertices_keeps_the_topology() -> None:
    mesh = shapes.torus(6, 4)
    moved = mesh.with_vertices(2.0 * mesh.vertices)
    assert moved.topology is mesh.topology
    np.testing.assert_array_equal(moved.vertices, 2.0 * mesh.vertices)
    with pytest.raises(InputError, match=r"expected shape \(24, 3\)"):
        mesh.with_vertices(mesh.vertices[:-1])
    bad = mesh.vertices.copy()
    bad[5, 1] = np.nan
    with pytest.raises(InputError, match="vertex 5 has a non-finite"):
        mesh.with_vertices(bad)
    with pytest.raises(DegenerateFaceError, match="zero area"):
        mesh.with_vertices(mesh.vertices * [1, 0, 0])  # every face collapses onto the x axis


# -- validation: one clear error per problem, naming the item ------------------------------------

SQUARE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
TWO_SQUARES = SQUARE + [[2, 0, 0], [2, 1, 0]]


@pytest.mark.parametrize(
    ("vertices", "faces", "error", "pattern"),
    [
        (
            TWO_SQUARES,
            [[0, 1, 2, 3], [1, 4, 9, 2]],
            MeshError,
            r"face 1 has vertex index 9 outside 0\.\.5",
        ),
        (TWO_SQUARES, [[0, 1, 2, 3], [1, -1, 5, 2]], MeshError, r"face 1 has vertex index -1"),
        (
            SQUARE,
            [[0, 1, 1, 3]],
            DegenerateFaceError,
            r"face 0 repeats a vertex: corners \(0, 1, 1, 3\)",
        ),
        (
            TWO_SQUARES,
            [[0, 1, 2, 3], [1, 2, 5, 4]],
            OrientationError,
            r"faces 0 and 1 both traverse edge 1 -> 2",
        ),
        (
            SQUARE + [[1, -1, 0], [0, -1, 0], [1, 0, 1], [0, 0, 1]],
            [[0, 1, 2, 3], [1, 0, 5, 4], [0, 1, 6, 7]],
            NonManifoldError,
            r"edge \(0, 1\) is used by 3 faces \(0, 1, 2\)",
        ),
        (
            SQUARE + [[2, 1, 0], [2, 2, 0], [1, 2, 0]],
            [[0, 1, 2, 3], [2, 4, 5, 6]],
            NonManifoldError,
            r"faces around vertex 2 \(0, 1\) form more than one fan",
        ),
        (SQUARE, [[0, 1, 2, 3], [0, 3, 2, 1]], ValenceError, r"interior vertex 0 has valence 2"),
        (
            TWO_SQUARES,
            [[0, 1, 2, 3], [1, 4, 5, 2], [1, 0, 4]],
            MeshError,
            r"1 faces are not quads.*--no-split",
        ),
        (
            [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]],
            [[0, 1, 2, 3]],
            DegenerateFaceError,
            r"face 0 \(0, 1, 2, 3\) has zero area",
        ),
        (
            [[0, 0, 0], [1, 0, 0], [np.inf, 1, 0], [0, 1, 0]],
            [[0, 1, 2, 3]],
            InputError,
            r"vertex 2 has a non-finite coordinate",
        ),
        (SQUARE, [[0, 1, 2, 3], [0, 1]], DegenerateFaceError, r"face 1 has 2 corners"),
        (SQUARE, np.zeros((0, 4), dtype=int), MeshError, r"no faces"),
    ],
    ids=[
        "index-too-large",
        "index-negative",
        "repeated-vertex",
        "orientation",
        "non-manifold-edge",
        "two-fans",
        "valence-2",
        "non-quad-no-split",
        "zero-area",
        "non-finite",
        "short-face",
        "no-faces",
    ],
)
def test_validation_errors(vertices, faces, error, pattern) -> None:
    with pytest.raises(error, match=pattern) as caught:
        QuadMesh.from_arrays(vertices, faces, split=False, source="model.obj", strict=True)
    assert str(caught.value).startswith("model.obj: ")


def test_two_closed_fans_at_a_vertex() -> None:
    """Two cubes sharing one corner: every edge is fine, but the corner has two closed fans."""
    cube = shapes.cube()
    second = cube.faces + 7  # cube vertex 0 of the second cube is vertex 7 of the first
    vertices = np.concatenate([cube.vertices, cube.vertices[1:] + 2.0])
    with pytest.raises(NonManifoldError, match=r"faces around vertex 7 .* more than one fan"):
        QuadMesh.from_arrays(vertices, np.concatenate([cube.faces, second]), strict=True)


def test_polygon_errors_name_the_input_faces_before_splitting() -> None:
    vertices = TWO_SQUARES + [[1, -1, 0]]
    with pytest.raises(OrientationError, match=r"faces 0 and 1 both traverse edge 1 -> 2"):
        QuadMesh.from_arrays(vertices, [[0, 1, 2, 3], [1, 2, 5, 4], [0, 6, 1]], strict=True)
    with pytest.raises(DegenerateFaceError, match=r"face 1 repeats a vertex"):
        QuadMesh.from_arrays(vertices, [[0, 1, 2, 3], [1, 4, 4], [0, 6, 1]], strict=True)


def test_topology_rejects_unused_vertices() -> None:
    with pytest.raises(MeshError, match=r"vertices 4, 5 are used by no face"):
        QuadTopology.from_faces([[0, 1, 2, 3]], n_vertices=6)


def test_unused_vertices_are_dropped_with_one_note(caplog) -> None:
    vertices = [[9, 9, 9]] + SQUARE + [[8, 8, 8]]
    with caplog.at_level(logging.INFO, logger="g1patch.mesh"):
        mesh = QuadMesh.from_arrays(
            vertices, [[1, 2, 3, 4]], source="a.obj", tags=[Tag("corner", (2,))]
        )
    assert [r.getMessage() for r in caplog.records] == ["a.obj: dropped 2 unused vertices (0, 5)"]
    np.testing.assert_array_equal(mesh.vertices, SQUARE)
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2, 3]])
    assert mesh.tags == (Tag("corner", (1,), (), ()),)


# -- splitting non-quads: one Catmull–Clark topology step ---------------------------------------


def test_mixed_faces_are_refined_once(caplog) -> None:
    vertices = TWO_SQUARES + [[1, -1, 0], [3, 0.5, 0]]
    faces = [[0, 1, 2, 3], [1, 4, 7, 5, 2], [0, 6, 1]]  # quad, pentagon, triangle
    with caplog.at_level(logging.INFO, logger="g1patch.mesh"):
        mesh = QuadMesh.from_arrays(vertices, faces)
    assert len(caplog.records) == 1
    assert (
        "2 of 3 faces are not quads; refined the whole mesh once" in caplog.records[0].getMessage()
    )
    n_edges = 4 + 5 + 3 - 2  # two shared edges
    assert mesh.n_faces == 4 + 5 + 3
    assert mesh.n_vertices == 8 + n_edges + 3
    assert mesh.topology.euler_characteristic == 1
    np.testing.assert_array_equal(mesh.vertices[:8], vertices)
    assert_topology_invariants(mesh.topology)
    assert_rings_turn_with_faces(mesh)
    centroid = mesh.vertices[-2]  # the pentagon's
    np.testing.assert_allclose(centroid, np.mean(np.array(vertices)[faces[1]], axis=0))


def test_refine_polygons_layout() -> None:
    vertices = np.array(SQUARE, dtype=float)
    new_vertices, quads, parent = refine_polygons(vertices, np.arange(4), np.array([4]))
    # edges sorted by vertex pair: (0,1), (0,3), (1,2), (2,3) -> vertices 4..7, centroid 8
    np.testing.assert_array_equal(quads, [[0, 4, 8, 5], [1, 6, 8, 4], [2, 7, 8, 6], [3, 5, 8, 7]])
    np.testing.assert_array_equal(parent, [0, 0, 0, 0])
    np.testing.assert_allclose(
        new_vertices[4:], [[0.5, 0, 0], [0, 0.5, 0], [1, 0.5, 0], [0.5, 1, 0], [0.5, 0.5, 0]]
    )


def test_tags_follow_refinement() -> None:
    vertices = TWO_SQUARES
    tags = [
        Tag("crease", (1, 2), (3.0,)),
        Tag("hole", (1,)),
        Tag("corner", (0,)),
        Tag("interpolateboundary", (1,)),
    ]
    mesh = QuadMesh.from_arrays(vertices, [[0, 1, 2, 3], [1, 4, 5, 2]], tags=tags)
    refined = shapes.subdivide(mesh)
    crease, hole, corner, rule = refined.tags
    a, m, m2, b = crease.ints
    assert (a, b) == (1, 2) and m == m2
    np.testing.assert_allclose(refined.vertices[m], [1, 0.5, 0])
    assert crease.floats == (3.0,)
    assert hole.ints == (4, 5, 6, 7)
    assert corner == Tag("corner", (0,)) and rule == Tag("interpolateboundary", (1,))


def test_tags_must_name_existing_items() -> None:
    with pytest.raises(MeshError, match=r"tag 'hole' names face 3, outside 0\.\.0"):
        QuadMesh.from_arrays(SQUARE, [[0, 1, 2, 3]], tags=[Tag("hole", (3,))])
    with pytest.raises(MeshError, match=r"tag 'crease' names \(0, 2\), which is not an edge"):
        QuadMesh.from_arrays(
            SQUARE + [[1, -1, 0]], [[0, 1, 2, 3], [0, 4, 1]], tags=[Tag("crease", (0, 2), (1.0,))]
        )
    with pytest.raises(MeshError, match=r"tag 'crease' needs pairs"):
        QuadMesh.from_arrays(SQUARE, [[0, 1, 2, 3]], tags=[Tag("crease", (0, 1, 2), (1.0,))])


def test_faces_as_lists_and_arrays_agree() -> None:
    cube = shapes.cube()
    from_lists = QuadMesh.from_arrays(cube.vertices.tolist(), cube.faces.tolist())
    np.testing.assert_array_equal(from_lists.faces, cube.faces)
    with pytest.raises(InputError, match="faces"):
        QuadMesh.from_arrays(cube.vertices, [[0, 1, 2, "x"], [0, 1, 2]])


# -- properties under relabelling (hypothesis) ---------------------------------------------------

small_meshes = st.one_of(
    st.builds(shapes.grid, st.integers(1, 4), st.integers(1, 4)),
    st.builds(shapes.torus, st.integers(3, 6), st.integers(3, 5)),
    st.builds(shapes.fan, st.integers(3, 9), st.integers(1, 3)),
    st.builds(shapes.boundary_fan, st.integers(1, 6)),
    st.sampled_from([shapes.cube(), shapes.cube_sphere(1), shapes.genus2()]),
)


@settings(max_examples=60, deadline=None)
@given(mesh=small_meshes, seed=st.integers(0, 2**32 - 1))
def test_relabelling_gives_an_isomorphic_topology(mesh: QuadMesh, seed: int) -> None:
    """Permute vertices and faces and rotate each face's corners: same structure, relabelled."""
    rng = np.random.default_rng(seed)
    t = mesh.topology
    relabel = rng.permutation(t.n_vertices)
    face_order = rng.permutation(t.n_faces)
    shift = rng.integers(0, 4, t.n_faces)
    rotated = np.take_along_axis(t.faces[face_order], (np.arange(4) + shift[:, None]) % 4, axis=1)
    u = QuadTopology.from_faces(relabel[rotated])

    assert_topology_invariants(u)
    assert (u.n_edges, u.euler_characteristic, u.n_components) == (
        t.n_edges,
        t.euler_characteristic,
        t.n_components,
    )
    np.testing.assert_array_equal(u.valence[relabel], t.valence)
    np.testing.assert_array_equal(u.face_count[relabel], t.face_count)
    np.testing.assert_array_equal(u.is_boundary_vertex[relabel], t.is_boundary_vertex)
    np.testing.assert_array_equal(u.edges, np.unique(np.sort(relabel[t.edges], axis=1), axis=0))
    for v in range(t.n_vertices):
        expected, got = relabel[t.one_ring(v)], u.one_ring(relabel[v])
        if t.is_boundary_vertex[v]:  # the start is fixed by the boundary
            np.testing.assert_array_equal(got, expected)
        else:  # the same cycle, possibly from another start
            start = int(np.flatnonzero(got == expected[0])[0])
            np.testing.assert_array_equal(np.roll(got, -start), expected)
    assert sorted(len(loop) for loop in u.boundary_loops()) == sorted(
        len(loop) for loop in t.boundary_loops()
    )


@settings(max_examples=40, deadline=None)
@given(mesh=small_meshes)
def test_subdivision_counts(mesh: QuadMesh) -> None:
    """One Catmull–Clark topology step: V' = V + E + F, E' = 2E + 4F, F' = 4F, χ and valences
    kept."""
    t = mesh.topology
    r = shapes.subdivide(mesh).topology
    assert (r.n_vertices, r.n_edges, r.n_faces) == (
        t.n_vertices + t.n_edges + t.n_faces,
        2 * t.n_edges + 4 * t.n_faces,
        4 * t.n_faces,
    )
    assert r.euler_characteristic == t.euler_characteristic
    assert np.count_nonzero(r.is_boundary_edge) == 2 * np.count_nonzero(t.is_boundary_edge)
    np.testing.assert_array_equal(r.valence[: t.n_vertices], t.valence)
    assert_topology_invariants(r)
