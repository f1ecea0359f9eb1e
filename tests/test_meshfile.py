"""Mesh files: the shared meshes' statistics, OBJ/PLY/OFF details, the malformed corpus, atomic
writes."""

from __future__ import annotations

import logging
from pathlib import Path

import meshio
import numpy as np
import pytest

from g1patch import shapes
from g1patch.errors import (
    DegenerateFaceError,
    FormatError,
    G1PatchError,
    InputError,
    MeshError,
    NonManifoldError,
    OrientationError,
    ValenceError,
)
from g1patch.io.meshfile import read_mesh, write_quads, write_triangles
from g1patch.mesh import Tag

MALFORMED = Path(__file__).parent / "data" / "malformed"
INTERPOLATE_BOUNDARY = (Tag("interpolateboundary", (1,), (), ()),)

# The statistics table of ../shared/data/README.md: V, F, E, boundary edges, boundary loops,
# components, Euler characteristic, genus (single closed component only), valences, tags.
STATISTICS = {
    "catmark_cube": (8, 6, 12, 0, 0, 1, 2, 0, {3: 8}, {}, ()),
    "catmark_torus": (32, 32, 64, 0, 0, 1, 0, 1, {4: 32}, {}, ()),
    "catmark_xord_boundary": (
        44,
        18,
        58,
        44,
        4,
        4,
        4,
        None,
        {},
        {2: 26, 3: 14, 4: 1, 5: 1, 6: 1, 7: 1},
        INTERPOLATE_BOUNDARY,
    ),
    "catmark_xord_interior": (
        151,
        71,
        213,
        142,
        9,
        9,
        9,
        None,
        {3: 1, 5: 1, 6: 1, 7: 1, 8: 1, 9: 1, 10: 1, 11: 1, 12: 1},
        {2: 71, 3: 71},
        INTERPOLATE_BOUNDARY,
    ),
    "spot_quadrangulated": (2930, 2928, 5856, 0, 0, 1, 2, 0, {3: 56, 4: 2830, 5: 40, 6: 4}, {}, ()),
}


def histogram(values: np.ndarray) -> dict[int, int]:
    keys, counts = np.unique(values, return_counts=True)
    return dict(zip(keys.tolist(), counts.tolist(), strict=True))


@pytest.mark.parametrize("name", STATISTICS)
def test_shared_mesh_statistics(shared_data: Path, name: str, caplog) -> None:
    path = shared_data / f"{name}.obj"
    with caplog.at_level(logging.INFO, logger="g1patch"):
        mesh = read_mesh(path)
    assert caplog.records == []  # all quads, no unused vertices: nothing dropped or split
    t = mesh.topology
    V, F, E, boundary_edges, loops, components, chi, genus, interior, boundary, tags = STATISTICS[
        name
    ]
    v_lines = sum(line.startswith("v ") for line in path.read_text().splitlines())
    assert (t.n_vertices, t.n_faces, t.n_edges) == (V, F, E) and v_lines == V
    assert np.count_nonzero(t.is_boundary_edge) == boundary_edges
    assert len(t.boundary_loops()) == loops and t.is_closed == (loops == 0)
    assert t.n_components == components and t.euler_characteristic == chi
    if genus is not None:
        assert (2 - chi) // 2 == genus
    assert histogram(t.valence[~t.is_boundary_vertex]) == interior
    assert histogram(t.valence[t.is_boundary_vertex]) == boundary
    assert mesh.tags == tags
    assert mesh.source == str(path)


# -- the malformed corpus: one error each, naming the file and the item ----------------------------

CORPUS = {
    "bad_header.off": (FormatError, r"expected the header 'OFF'", 1),
    "bad_number.obj": (FormatError, r"expected 'v x y z' with 3 numbers, got '1 0\.0\.0 0'", 2),
    "bad_tag.obj": (FormatError, r"tag 'crease' announces 2/1/0 values but has 2", 6),
    "blank.off": (FormatError, r"the file is empty", None),
    "degenerate_face.obj": (DegenerateFaceError, r"face 1 \(1, 0, 4, 5\) has zero area", None),
    "empty.obj": (FormatError, r"the file is empty", None),
    "garbage.obj": (FormatError, r"not a text file", None),
    "garbage.off": (FormatError, r"not a text file", None),
    "garbage.ply": (FormatError, r"expected a PLY header", 1),
    "inconsistent_orientation.obj": (
        OrientationError,
        r"faces 0 and 1 both traverse edge 1 -> 2 in the same direction",
        None,
    ),
    "nan_coordinates.obj": (
        FormatError,
        r"vertex 2 has a non-finite coordinate \(1\.0, nan, 0\.0\)",
        3,
    ),
    "nan_coordinates.off": (
        FormatError,
        r"vertex 2 has a non-finite coordinate \(1\.0, 1\.0, inf\)",
        5,
    ),
    "nan_coordinates.ply": (
        FormatError,
        r"vertex 2 has a non-finite coordinate \(nan, 1\.0, 0\.0\)",
        12,
    ),
    "no_faces.obj": (FormatError, r"no faces", None),
    "nonmanifold_edge.obj": (
        NonManifoldError,
        r"edge \(0, 1\) is used by 3 faces \(0, 1, 2\)",
        None,
    ),
    "out_of_range.obj": (
        FormatError,
        r"face 1 names vertex 4 \(0-based\), but the file has 4 vertices",
        6,
    ),
    "out_of_range.off": (
        FormatError,
        r"face 0 names vertex 7 \(0-based\), but the file has 4 vertices",
        7,
    ),
    "out_of_range.ply": (
        FormatError,
        r"face 0 names vertex 4 \(0-based\), but the file has 4 vertices",
        14,
    ),
    "repeated_vertex.obj": (
        DegenerateFaceError,
        r"face 0 repeats a vertex: corners \(0, 1, 1, 3\)",
        None,
    ),
    "tag_out_of_range.obj": (MeshError, r"tag 'corner' names vertex 9, outside 0\.\.3", None),
    "truncated.obj": (FormatError, r"a face needs at least 3 corners, got 2", 12),
    "truncated.off": (FormatError, r"truncated: the header announces 8 vertices and 6 faces", 8),
    "truncated.ply": (
        FormatError,
        r"truncated: the header announces 6 'face' elements of at least 13 bytes each, 270 bytes "
        r"\(after 192 for the elements before them\), but only 202 bytes follow the header",
        7,
    ),
    "truncated_ascii.ply": (
        FormatError,
        r"truncated: the header announces 4 'vertex' elements of at least 6 bytes each, 24 bytes, "
        r"but only 18 bytes follow the header",
        3,
    ),
    "two_closed_fans.obj": (
        NonManifoldError,
        r"the 6 faces around vertex 7 \(1, 3, 5, 6, 8, 10\) form more than one fan",
        None,
    ),
    "two_fans.obj": (
        NonManifoldError,
        r"the 2 faces around vertex 2 \(0, 1\) form more than one fan",
        None,
    ),
    "unknown_statement.obj": (FormatError, r"unknown OBJ statement 'hello'", 5),
    "unsupported.xyz": (
        FormatError,
        r"unsupported extension '\.xyz'; expected one of \.obj, \.ply, \.off",
        None,
    ),
    "valence2_interior.obj": (ValenceError, r"interior vertex 0 has valence 2", None),
    "zero_index.obj": (FormatError, r"vertex index 0 in a face; OBJ indices start at 1", 5),
}


def test_every_corpus_file_is_listed() -> None:
    assert sorted(p.name for p in MALFORMED.iterdir()) == sorted(CORPUS)


@pytest.mark.parametrize("name", CORPUS)
def test_malformed_file(name: str) -> None:
    error, pattern, line = CORPUS[name]
    path = MALFORMED / name
    with pytest.raises(G1PatchError, match=pattern) as caught:
        read_mesh(path, strict=True)
    assert type(caught.value) is error
    where = f"{path}:{line}: " if line is not None else f"{path}: "
    assert str(caught.value).startswith(where)
    if error is FormatError:
        assert caught.value.line == line and caught.value.path == path


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match=r"missing\.obj: cannot read the file"):
        read_mesh(tmp_path / "missing.obj")


# -- OBJ ------------------------------------------------------------------------------------------

OBJ_WITH_EVERYTHING = """\
# two unit squares side by side, written the long way
mtllib squares.mtl
o squares
v 0 0 0 1.0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 1
g left
usemtl plain
s off
f 1/1/1 2/1/1 3/1/1 4/1/1
v 2 0 0
v 2 1 0
g right
f 2//1 -2//1 -1//1 3//1   # negative indices count back from the last vertex
t crease 2/1/0 1 2 4.5
t creasemethod 0/0/1 chaikin
"""


def test_obj_statements_indices_and_tags(tmp_path: Path) -> None:
    path = tmp_path / "squares.OBJ"
    path.write_text(OBJ_WITH_EVERYTHING)
    mesh = read_mesh(path)
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2, 3], [1, 4, 5, 2]])
    np.testing.assert_array_equal(mesh.vertices[4:], [[2, 0, 0], [2, 1, 0]])
    assert mesh.tags == (
        Tag("crease", (1, 2), (4.5,), ()),
        Tag("creasemethod", (), (), ("chaikin",)),
    )


MIXED_OBJ = """\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 3 0.5 0
v 2 1 0
v 1 -1 0
f 1 2 3 4
f 2 5 6 7 3
f 1 8 2
"""


def test_obj_with_polygons_is_refined_once(tmp_path: Path, caplog) -> None:
    path = tmp_path / "mixed.obj"
    path.write_text(MIXED_OBJ)
    with caplog.at_level(logging.INFO, logger="g1patch"):
        mesh = read_mesh(path)
    assert [r.getMessage() for r in caplog.records] == [
        f"{path}: 2 of 3 faces are not quads; refined the whole mesh once (every n-gon into n "
        "quads, new points on a smooth surface through the vertices)"
    ]
    assert (mesh.n_faces, mesh.n_vertices) == (12, 8 + 10 + 3)
    with pytest.raises(MeshError, match=r"mixed\.obj: 2 faces are not quads .* \(--no-split\)"):
        read_mesh(path, split=False)


def test_obj_round_trip(tmp_path: Path) -> None:
    mesh = shapes.torus(6, 4)
    write_quads(tmp_path / "torus.obj", mesh.vertices, mesh.faces)
    again = read_mesh(tmp_path / "torus.obj")
    np.testing.assert_array_equal(again.faces, mesh.faces)
    np.testing.assert_allclose(again.vertices, mesh.vertices, rtol=0, atol=1e-15)


# -- OFF ------------------------------------------------------------------------------------------


def off_text(vertices: np.ndarray, faces: np.ndarray, header: str) -> str:
    rows = [" ".join(map(repr, v.tolist())) for v in vertices]
    rows += [
        f"{len(f)} " + " ".join(map(str, f.tolist())) + "  0.5 0.5 0.5" for f in faces
    ]  # with face colours
    return header + "\n# a comment line\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize("header", ["OFF\n8 6 12", "OFF 8 6 12"])
def test_off(tmp_path: Path, header: str) -> None:
    cube = shapes.cube()
    path = tmp_path / "cube.off"
    path.write_text(off_text(cube.vertices, cube.faces, header))
    mesh = read_mesh(path)
    np.testing.assert_array_equal(mesh.faces, cube.faces)
    np.testing.assert_array_equal(mesh.vertices, cube.vertices)


def test_off_with_a_triangle(tmp_path: Path) -> None:
    path = tmp_path / "mixed.off"
    path.write_text("OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n1 -1 0\n4 0 1 2 3\n3 0 4 1\n")
    assert read_mesh(path).n_faces == 7


# -- PLY ------------------------------------------------------------------------------------------


def test_ply_binary_round_trip(tmp_path: Path) -> None:
    mesh = shapes.genus2()
    write_quads(tmp_path / "genus2.ply", mesh.vertices, mesh.faces)
    again = read_mesh(tmp_path / "genus2.ply")
    np.testing.assert_array_equal(again.faces, mesh.faces)
    np.testing.assert_array_equal(again.vertices, mesh.vertices)


def test_ply_ascii_with_mixed_faces_keeps_their_order(tmp_path: Path) -> None:
    path = tmp_path / "mixed.ply"
    header = (
        "ply\nformat ascii 1.0\ncomment two quads and a triangle\nelement vertex 7\nproperty "
        "float x\n"
        "property float y\nproperty float z\nelement face 3\nproperty list uchar int "
        "vertex_indices\nend_header\n"
    )
    body = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n1 -1 0\n4 0 1 2 3\n3 0 6 1\n4 1 4 5 2\n"
    path.write_text(header + body)
    mesh = read_mesh(path)
    assert mesh.n_faces == 4 + 3 + 4
    quads_only = tmp_path / "quads.ply"
    quads_only.write_text(
        header.replace("vertex 7", "vertex 6").replace("face 3", "face 2")
        + body.replace("1 -1 0\n", "").replace("3 0 6 1\n", "")
    )
    np.testing.assert_array_equal(read_mesh(quads_only).faces, [[0, 1, 2, 3], [1, 4, 5, 2]])


@pytest.mark.parametrize("form", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_other_scalar_elements_around_the_mesh_are_skipped(tmp_path: Path, form: str) -> None:
    """A range scan as MeshLab writes it starts with a ``camera`` element (floats and ints; meshio
    refuses it): skipped, as is a scalar element after the faces; the mesh is the one between."""
    mesh = shapes.genus2()
    points = mesh.vertices.astype(np.float32)
    header = (
        f"ply\nformat {form} 1.0\nelement camera 1\nproperty float focal\n"
        f"property int viewportx\nelement vertex {len(points)}\nproperty float x\n"
        f"property float y\nproperty float z\nelement face {mesh.n_faces}\n"
        "property list uchar int vertex_indices\nelement note 2\nproperty uchar level\n"
        "end_header\n"
    )
    if form == "ascii":
        body = "35.5 640\n"
        body += "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
        body += "".join(f"4 {a} {b} {c} {d}\n" for a, b, c, d in mesh.faces.tolist())
        data = (header + body + "7\n9\n").encode()
    else:
        order = "<" if form == "binary_little_endian" else ">"
        camera = np.array([(35.5, 640)], dtype=[("f", order + "f4"), ("v", order + "i4")])
        faces = np.zeros(mesh.n_faces, dtype=[("n", "u1"), ("i", order + "i4", 4)])
        faces["n"], faces["i"] = 4, mesh.faces
        data = (
            header.encode()
            + camera.tobytes()
            + points.astype(order + "f4").tobytes()
            + faces.tobytes()
            + bytes([7, 9])
        )
    path = tmp_path / "framed.ply"
    path.write_bytes(data)
    again = read_mesh(path)
    np.testing.assert_array_equal(again.faces, mesh.faces)
    np.testing.assert_array_equal(again.vertices, points.astype(np.float64))


# -- writing --------------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl"])
def test_write_triangles(tmp_path: Path, suffix: str) -> None:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    path = tmp_path / f"tetra{suffix}"
    write_triangles(path, points, triangles)
    back = meshio.read(path)
    got = back.points[back.get_cells_type("triangle")]
    np.testing.assert_allclose(got, points[triangles])
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary file left


def test_write_quads_as_stl_splits_each_quad(tmp_path: Path) -> None:
    cube = shapes.cube()
    write_quads(tmp_path / "cube.stl", cube.vertices, cube.faces)
    triangles = meshio.read(tmp_path / "cube.stl").get_cells_type("triangle")
    assert triangles.shape == (12, 3)


def test_write_rejects_bad_input_before_writing(tmp_path: Path) -> None:
    with pytest.raises(
        FormatError,
        match=r"unsupported extension '\.vtk' for writing; expected one of \.obj, \.ply, \.stl",
    ):
        write_triangles(tmp_path / "out.vtk", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(
        InputError, match=r"triangles: row 0 \(0, 1, 3\) names a point outside 0\.\.2"
    ):
        write_triangles(tmp_path / "out.obj", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]])
    with pytest.raises(InputError, match=r"vertices: non-finite value"):
        write_quads(
            tmp_path / "out.ply", [[0, 0, 0], [1, 0, 0], [1, 1, np.nan], [0, 1, 0]], [[0, 1, 2, 3]]
        )
    assert list(tmp_path.iterdir()) == []


def test_a_failing_write_leaves_no_file(tmp_path: Path, monkeypatch) -> None:
    """The writer dies half-way: no partial output, no temporary file, an old file untouched."""

    def write_half_then_fail(filename: str, mesh: meshio.Mesh, binary: bool = True) -> None:
        Path(filename).write_bytes(b"ply\nformat binary_little_endian 1.0\n")
        raise OSError("disk full")

    monkeypatch.setattr(meshio.ply, "write", write_half_then_fail)
    cube = shapes.cube()
    with pytest.raises(OSError, match="disk full"):
        write_quads(tmp_path / "new.ply", cube.vertices, cube.faces)
    assert list(tmp_path.iterdir()) == []

    old = tmp_path / "old.ply"
    old.write_bytes(b"previous contents")
    with pytest.raises(OSError, match="disk full"):
        write_quads(old, cube.vertices, cube.faces)
    assert [p.name for p in tmp_path.iterdir()] == [
        "old.ply"
    ] and old.read_bytes() == b"previous contents"
