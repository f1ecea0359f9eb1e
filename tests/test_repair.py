"""Repair instead of refusal (issue 11, parts 4 and 5): every mesh the checks used to refuse
builds by default into an exactly G1 network, names what was repaired in one line, and still
refuses with ``strict``; one polygon of 100 000 sides builds in linear time and memory."""

from __future__ import annotations

import re
import subprocess
import sys
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from environment import own_lines

from g1patch import shapes
from g1patch.build import build_network
from g1patch.cli import main
from g1patch.continuity import check
from g1patch.errors import (
    DegenerateFaceError,
    InputError,
    MeshError,
    NonManifoldError,
    OrientationError,
    ValenceError,
)
from g1patch.io.network_file import load_network
from g1patch.mesh import QuadMesh, Tag, strict_meshes

Faces = np.ndarray | list[list[int]]
Case = tuple[np.ndarray, Faces]


# -- meshes the checks refuse, generated here
# -------------------------------------------------------


def bumpy_grid(n: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """An n × n grid on a gentle bump; vertex j (n + 1) + i at (i, j, 0.1 sin i cos j)."""
    grid = shapes.grid(
        n, n, size=(float(n), float(n)), height=lambda x, y: 0.1 * np.sin(x) * np.cos(y)
    )
    return np.array(grid.vertices), np.array(grid.faces)


def fold_in(vertices: np.ndarray, faces: np.ndarray, f: int) -> tuple[np.ndarray, np.ndarray]:
    """Quad f = (a, x, b, y) becomes (v, a, x, b) and (v, b, y, a) about a new vertex v of valence 2
    at its centre; the other faces keep their order, the two new ones come last."""
    a, x, b, y = faces[f]
    v = len(vertices)
    vertices = np.vstack([vertices, vertices[[a, x, b, y]].mean(axis=0)])
    return vertices, np.vstack([np.delete(faces, f, axis=0), [[v, a, x, b], [v, b, y, a]]])


def book(pages: int) -> tuple[np.ndarray, np.ndarray]:
    """``pages`` unit quads (0, 1, 2 + i, 2 + pages + i) on the spine 0–1 (the z axis), fanned out
    around it; every other page runs the other way round."""
    t = 2 * np.pi * np.arange(pages) / pages
    out = np.stack([np.cos(t), np.sin(t), np.zeros(pages)], axis=1)
    vertices = np.vstack([[[0, 0, 0], [0, 0, 1.0]], out + [0, 0, 1], out])
    i = np.arange(pages)
    faces = np.stack([np.zeros(pages, dtype=int), np.full(pages, 1), 2 + i, 2 + pages + i], axis=1)
    faces[1::2] = faces[1::2, ::-1]
    return vertices, faces


def two_cubes() -> tuple[np.ndarray, np.ndarray]:
    """Two cubes sharing one corner (vertex 7): every edge is fine, the corner has two closed
    fans."""
    cube = shapes.cube()
    return np.concatenate([cube.vertices, cube.vertices[1:] + 2.0]), np.concatenate(
        [cube.faces, cube.faces + 7]
    )


def two_pyramids() -> tuple[np.ndarray, list[list[int]]]:
    """Three sides of each of two square pyramids touching apex to apex: two open fans at vertex
    0."""
    base = np.array([[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0.0]])
    vertices = np.vstack([[[0, 0, 0]], base + [0, 0, 1], base - [0, 0, 1]])
    up = [[0, 1 + k, 1 + (k + 1) % 4] for k in range(3)]
    down = [[0, 5 + (k + 1) % 4, 5 + k] for k in range(3)]
    return vertices, up + down


def cube_with_flipped_face(face: int = 2) -> tuple[np.ndarray, np.ndarray]:
    cube = shapes.cube()
    faces = np.array(cube.faces)
    faces[face] = faces[face, ::-1]
    return np.array(cube.vertices), faces


def cube_with_repeated_corner() -> tuple[np.ndarray, list[list[int]]]:
    """The cube with face 2 written (0, 4, 4, 5, 1): a consecutive duplicate."""
    cube = shapes.cube()
    faces = cube.faces.tolist()
    a, b, c, d = faces[2]
    faces[2] = [a, b, b, c, d]
    return np.array(cube.vertices), faces


def moebius(n: int = 12, width: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    """A Möbius strip of n quads: vertex 2 i + j at angle 2πi/n, side j; the last quad joins side 0
    to side 1."""
    t = 2 * np.pi * np.arange(n)[:, None] / n
    s = np.array([-width, width])[None, :]
    radius = 1 + s * np.cos(t / 2)
    vertices = np.stack(
        [radius * np.cos(t), radius * np.sin(t), s * np.sin(t / 2)], axis=-1
    ).reshape(-1, 3)
    i = np.arange(n)
    faces = np.stack([2 * i, 2 * ((i + 1) % n), 2 * ((i + 1) % n) + 1, 2 * i + 1], axis=1)
    faces[-1] = [2 * (n - 1), 1, 0, 2 * (n - 1) + 1]  # the half twist
    return vertices, faces


def cyclic(faces: np.ndarray) -> set[tuple[int, ...]]:
    """Faces up to the choice of first corner (orientation kept)."""
    rows = np.asarray(faces)
    start = np.argmin(rows, axis=1)
    return {tuple(np.roll(row, -k).tolist()) for row, k in zip(rows, start, strict=True)}


def assert_builds_exactly(mesh: QuadMesh) -> None:
    report = check(build_network(mesh))
    assert report.passes(), (report.max_edge_angle_deg, report.folds)
    assert report.max_edge_angle_deg <= 1e-9 and report.max_corner_angle_deg <= 1e-9


# -- every case: repaired by default, refused with strict
# ---------------------------------------------

SPLIT_EDGE = (
    r"^1 non-manifold edge \(0, 1\) with {} faces split into sheets \(\+{} vertex copies\)$"
)
SPLIT_VERTEX = r"^1 non-manifold vertex \({}\) split into one copy per fan \(\+1 vertex\)$"
CASES: dict[str, tuple[Callable[[], Case], type[MeshError], str]] = {
    "valence-2": (
        lambda: fold_in(*bumpy_grid(), 5),
        ValenceError,
        r"^1 valence-2 vertex \(25\) dissolved$",
    ),
    "book-3": (lambda: book(3), NonManifoldError, SPLIT_EDGE.format(3, 4)),
    "book-100": (lambda: book(100), NonManifoldError, SPLIT_EDGE.format(100, 198)),
    "two-cubes": (two_cubes, NonManifoldError, SPLIT_VERTEX.format(7)),
    "two-pyramids": (two_pyramids, NonManifoldError, SPLIT_VERTEX.format(0)),
    "repeated-vertex": (
        cube_with_repeated_corner,
        DegenerateFaceError,
        r"^1 face repeating a vertex \(2\) reduced to 1 simple polygon$",
    ),
    "flipped-face": (cube_with_flipped_face, OrientationError, r"^1 face \(2\) reoriented$"),
}


@pytest.mark.parametrize("name", CASES)
def test_repaired_by_default_and_refused_when_strict(name: str) -> None:
    make, error, note = CASES[name]
    vertices, faces = make()
    mesh = QuadMesh.from_arrays(vertices, faces, source="case.obj")
    assert len(mesh.repairs) >= 1
    assert mesh.repair_note.startswith("repaired: ")
    assert mesh.repair_note.removeprefix("repaired: ") == ", ".join(mesh.repairs)
    assert re.match(note, ", ".join(mesh.repairs)), mesh.repair_note
    assert_builds_exactly(mesh)
    assert build_network(mesh).provenance["repairs"] == ", ".join(mesh.repairs)
    with pytest.raises(error) as caught:
        QuadMesh.from_arrays(vertices, faces, source="case.obj", strict=True)
    assert type(caught.value) is error and str(caught.value).startswith("case.obj: ")
    with strict_meshes(), pytest.raises(error):
        QuadMesh.from_arrays(vertices, faces)


def test_a_valid_mesh_is_not_repaired() -> None:
    vertices, faces = bumpy_grid()
    mesh = QuadMesh.from_arrays(vertices, faces)
    assert mesh.repairs == () and mesh.repair_note == ""
    assert "repairs" not in build_network(mesh).provenance


# -- valence 2 -------------------------------------------------------------------------------------


def test_valence_two_dissolves_back_into_the_grid() -> None:
    vertices, faces = bumpy_grid()
    mesh = QuadMesh.from_arrays(*fold_in(vertices, faces, 5))
    np.testing.assert_array_equal(mesh.vertices, vertices)
    assert cyclic(mesh.faces) == cyclic(faces)  # (a, x, b, y), counter-clockwise like the rest


def test_several_and_chained_valence_two_vertices() -> None:
    vertices, faces = bumpy_grid()
    several = fold_in(*fold_in(*fold_in(vertices, faces, 5), 9), 0)
    mesh = QuadMesh.from_arrays(*several)
    assert mesh.repairs == ("3 valence-2 vertices (25, 26, 27) dissolved",)
    assert cyclic(mesh.faces) == cyclic(faces)
    # fold a folded quad again along its diagonal v–x: w has valence 2, v gets it once w is gone
    once = fold_in(vertices, faces, 5)
    chain = fold_in(*once, len(once[1]) - 2)
    mesh = QuadMesh.from_arrays(*chain)
    assert mesh.repairs == ("2 valence-2 vertices (25, 26) dissolved",)
    assert cyclic(mesh.faces) == cyclic(faces)
    assert_builds_exactly(mesh)


def test_valence_two_between_a_triangle_and_a_pentagon_leaves_the_quad() -> None:
    """Polygons merge the same way: (v, a, x) and (v, x, b, y, a) give (a, x, b, y)."""
    vertices, faces = bumpy_grid(2)
    a, x, b, y = faces[0]
    vertices = np.vstack([vertices, 0.8 * vertices[a] + 0.2 * vertices[b] + [0.3, 0.0, 0.0]])
    polygons = [[9, a, x], [9, x, b, y, a]] + faces[1:].tolist()  # v inside the square, next to a–x
    mesh = QuadMesh.from_arrays(vertices, polygons)
    assert mesh.repairs == ("1 valence-2 vertex (9) dissolved",)
    assert cyclic(mesh.faces) == cyclic(faces)  # all quads again: nothing to split
    assert_builds_exactly(mesh)


def test_a_closed_pillow_leaves_nothing_and_says_so() -> None:
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    with pytest.raises(
        ValenceError,
        match=r"no face is left after the repairs \(1 valence-2 vertex .* dissolved, "
        r"2 faces \(0, 1\) dropped: their merge left no polygon\)",
    ):
        QuadMesh.from_arrays(square, [[0, 1, 2, 3], [0, 3, 2, 1]])
    with pytest.raises(ValenceError, match=r"interior vertex 0 has valence 2"):
        QuadMesh.from_arrays(square, [[0, 1, 2, 3], [0, 3, 2, 1]], strict=True)


# -- non-manifold edges and vertices
# ----------------------------------------------------------------


@pytest.mark.parametrize("pages", [3, 4, 100])
def test_a_book_splits_into_its_pages(pages: int) -> None:
    vertices, faces = book(pages)
    mesh = QuadMesh.from_arrays(vertices, faces, tags=[Tag("crease", (0, 1), (10.0,))])
    assert mesh.n_faces == pages and mesh.n_vertices == 4 * pages
    assert mesh.topology.n_components == pages and mesh.topology.is_boundary_edge.all()
    # the copies sit exactly where the spine was: the pages still meet
    on_spine = (mesh.vertices[:, :2] == 0).all(axis=1)
    assert on_spine.sum() == 2 * pages
    np.testing.assert_array_equal(np.unique(mesh.vertices[on_spine], axis=0), vertices[:2])
    assert mesh.features.sharp_edges.sum() == pages  # the crease follows every copy of the spine
    assert_builds_exactly(mesh)


def test_two_cubes_at_a_corner_become_two_cubes() -> None:
    vertices, faces = two_cubes()
    mesh = QuadMesh.from_arrays(vertices, faces, tags=[Tag("corner", (7,), (10.0,))])
    assert mesh.n_vertices == 16 and mesh.topology.n_components == 2 and mesh.topology.is_closed
    np.testing.assert_array_equal(mesh.vertices[15], vertices[7])
    assert mesh.tags == (Tag("corner", (7, 15), (10.0,)),)
    assert np.flatnonzero(mesh.features.corner_vertices).tolist() == [7, 15]


# -- repeated vertices
# ------------------------------------------------------------------------------


def test_repeated_vertices_cut_faces_into_simple_polygons() -> None:
    vertices, faces = bumpy_grid(2)
    polygons = faces.tolist()
    a, x, b, y = polygons[3]
    polygons[3] = [a, x, a, b]  # a, x, a, b: two edges walked twice, nothing left
    mesh = QuadMesh.from_arrays(vertices, polygons, tags=[Tag("hole", (3,))])
    assert mesh.repairs == (
        "1 degenerate face (3) dropped",
        "1 vertex left without a face (8) dropped",
    )
    assert mesh.n_faces == 3
    assert mesh.tags == (Tag("hole", ()),)
    # a face that touches itself at the centre 4: the triangles (4, 0, 1) and (4, 8, 7), corner to
    # corner
    mesh = QuadMesh.from_arrays(vertices, [[4, 0, 1, 4, 8, 7]])
    assert mesh.repairs == (
        "1 face repeating a vertex (0) reduced to 2 simple polygons",
        "1 non-manifold vertex (4) split into one copy per fan (+1 vertex)",
    )
    assert mesh.n_faces == 6 and mesh.topology.n_components == 2
    assert_builds_exactly(mesh)


def test_faces_with_nothing_left_is_an_error() -> None:
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    with pytest.raises(
        DegenerateFaceError,
        match=r"no face is left after the repairs \(1 degenerate face \(0\) dropped\)",
    ):
        QuadMesh.from_arrays(square, [[0, 1, 0, 2]])


# -- orientation -----------------------------------------------------------------------------------


def test_the_majority_keeps_its_orientation() -> None:
    cube = shapes.cube()
    faces = np.array(cube.faces)
    faces[:4] = faces[:4, ::-1]  # four of six faces turned inwards: the cube is turned inside out
    mesh = QuadMesh.from_arrays(cube.vertices, faces)
    assert mesh.repairs == ("2 faces (4, 5) reoriented",)
    assert cyclic(mesh.faces) == cyclic(np.array(cube.faces)[:, ::-1])


def test_a_moebius_strip_is_still_refused() -> None:
    vertices, faces = moebius()
    with pytest.raises(
        OrientationError, match=r"^strip\.obj: face 0 lies on a non-orientable sheet"
    ):
        QuadMesh.from_arrays(vertices, faces, source="strip.obj")
    with pytest.raises(OrientationError, match=r"both traverse edge"):
        QuadMesh.from_arrays(vertices, faces, strict=True)


def test_what_no_repair_mends_still_raises() -> None:
    vertices, faces = fold_in(*bumpy_grid(), 5)
    bad = vertices.copy()
    bad[3, 1] = np.nan
    with pytest.raises(InputError, match=r"vertex 3 has a non-finite coordinate"):
        QuadMesh.from_arrays(bad, faces)
    out_of_range = faces.copy()
    out_of_range[2, 1] = 99
    with pytest.raises(MeshError, match=r"face 2 has vertex index 99 outside 0\.\.25"):
        QuadMesh.from_arrays(vertices, out_of_range)


# -- tags through repairs
# ------------------------------------------------------------------------------


def test_tags_follow_the_repairs() -> None:
    """Holes and creases survive a dissolution; a crease on a dissolved edge is dropped and said
    so."""
    vertices, faces = bumpy_grid()
    folded_vertices, folded = fold_in(vertices, faces, 5)
    v, a, x, b = folded[-2]
    tags = [
        Tag("hole", (len(folded) - 1,)),
        Tag("crease", (0, 1, v, a), (10.0, 10.0)),
        Tag("corner", (v, 0)),
    ]
    mesh = QuadMesh.from_arrays(folded_vertices, folded, tags=tags)
    assert mesh.repairs == (
        "1 valence-2 vertex (25) dissolved",
        "2 tag items on removed vertices or edges (25, 25) dropped",
    )
    hole, crease, corner = mesh.tags
    assert len(hole.ints) == 1 and cyclic(mesh.faces[list(hole.ints)]) == cyclic(faces[[5]])
    assert sorted(crease.ints) == [0, 1] and crease.floats == (10.0,)
    assert corner.ints == (0,)
    assert_builds_exactly(mesh)


# -- the command line
# --------------------------------------------------------------------------------


def write_obj(path: Path, vertices: np.ndarray, faces: Faces) -> Path:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=float).tolist()]
    lines += [
        "f " + " ".join(str(i + 1) for i in face)
        for face in np.asarray(faces, dtype=object).tolist()
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(
    "name", ["valence-2", "book-3", "two-cubes", "repeated-vertex", "flipped-face"]
)
def test_cli_repairs_with_one_line_and_refuses_when_strict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    make, _, note = CASES[name]
    source = write_obj(tmp_path / f"{name}.obj", *make())
    out = tmp_path / "out.npz"
    assert main(["build", str(source), "-o", str(out), "-q"]) == 0
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"g1patch: {source}: repaired: "), captured.err
    assert load_network(out).provenance["repairs"] == lines[0].split("repaired: ", 1)[1]
    strict_out = tmp_path / "strict.npz"
    assert main(["build", str(source), "-o", str(strict_out), "-q", "--strict"]) == 2
    captured = capsys.readouterr()
    assert len(captured.err.splitlines()) == 1 and captured.err.startswith(
        f"g1patch: error: {source}: "
    )
    assert not strict_out.exists()


@pytest.mark.slow
def test_cli_as_a_user_runs_it(tmp_path: Path) -> None:
    source = write_obj(tmp_path / "book.obj", *book(100))
    out = tmp_path / "book.npz"
    run = [sys.executable, "-m", "g1patch.cli", "build", str(source), "-o", str(out)]
    result = subprocess.run(run, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert own_lines(result.stderr) == [
        f"g1patch: {source}: repaired: 1 non-manifold edge (0, 1) with 100 faces split into "
        "sheets (+198 vertex copies)"
    ]
    out.unlink()
    result = subprocess.run([*run, "--strict"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 2 and not out.exists()
    assert own_lines(result.stderr) == [
        f"g1patch: error: {source}: edge (0, 1) is used by 100 faces (0, 1, 2, 3, 4 and 95 more); "
        "an edge may have at most 2"
    ]


# -- large polygons: linear in time and memory
# -----------------------------------------------------------


def regular_polygon(n: int) -> np.ndarray:
    t = 2 * np.pi * np.arange(n) / n
    return np.stack([np.cos(t), np.sin(t), np.zeros(n)], axis=1)


def peak_memory(build: Callable[[], QuadMesh]) -> tuple[int, QuadMesh]:
    tracemalloc.start()
    try:
        mesh = build()
        return tracemalloc.get_traced_memory()[1], mesh
    finally:
        tracemalloc.stop()


def test_one_large_polygon_splits_in_linear_memory() -> None:
    """10 000 and 100 000 sides: the peak grows by at most 15× (it was quadratic: 37 GiB at 100
    000)."""
    peaks = {}
    for n in (10_000, 100_000):
        peaks[n], mesh = peak_memory(
            lambda n=n: QuadMesh.from_arrays(regular_polygon(n), [list(range(n))])
        )
        assert mesh.n_faces == n and mesh.topology.valence.max() == n
    assert peaks[100_000] <= 15 * peaks[10_000], peaks
    assert peaks[100_000] <= 500 * 2**20


def test_a_cylinder_with_one_large_cap() -> None:
    n = 20_000
    ring = regular_polygon(n)
    i = np.arange(n)
    band = np.stack([i, (i + 1) % n, n + (i + 1) % n, n + i], axis=1).tolist()
    mesh = QuadMesh.from_arrays(np.vstack([ring, ring + [0, 0, 1]]), band + [list(range(n, 2 * n))])
    assert mesh.n_faces == 5 * n and mesh.topology.valence.max() == n
    assert len(mesh.topology.boundary_loops()) == 1


@pytest.mark.parametrize(
    "make", [lambda: shapes.fan(300), lambda: shapes.boundary_fan(300)], ids=["closed", "boundary"]
)
def test_rings_beyond_the_walk_are_ranked_in_order(make: Callable[[], QuadMesh]) -> None:
    """A 300-face fan: the first positions are walked, the rest ranked; either way h_{i+1} =
    twin(prev(h_i))."""
    topology = make().topology
    ring = topology.ring(0)
    assert ring.size == 300 and np.unique(ring).size == 300
    np.testing.assert_array_equal(topology.next_ccw(ring[:-1]), ring[1:])
    if topology.is_boundary_vertex[0]:
        assert topology.twin[ring[0]] < 0 and topology.next_ccw(ring[-1]) < 0
    else:
        assert topology.next_ccw(ring[-1]) == ring[0]


def test_two_large_closed_fans_at_one_vertex() -> None:
    """Two 40-quad disks sharing their centre: the walk stays in one of them, the ranking finds the
    other."""
    disk = shapes.fan(40)
    n = disk.n_vertices
    vertices = np.concatenate([disk.vertices, disk.vertices[1:] + [0, 0, 1]])
    faces = np.concatenate([disk.faces, np.where(disk.faces == 0, 0, disk.faces + n - 1)])
    with pytest.raises(
        NonManifoldError, match=r"the 80 faces around vertex 0 .* form more than one fan"
    ):
        QuadMesh.from_arrays(vertices, faces, strict=True)
    mesh = QuadMesh.from_arrays(vertices, faces)
    assert mesh.repairs == ("1 non-manifold vertex (0) split into one copy per fan (+1 vertex)",)
    assert mesh.topology.n_components == 2 and mesh.topology.valence.max() == 40
