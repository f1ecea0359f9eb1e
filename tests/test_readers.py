"""The vectorised mesh readers against the line-by-line reference parsers.

Hypothesis writes small OBJ and OFF files in every spelling the formats allow (comments, blank
lines, CR LF and lone CR, tabs and runs of spaces, ``v`` with ``w``, ``vt`` / ``vn`` and other
skipped statements, ``f a/b/c`` forms, negative indices, polygons, tags, colours after OFF
faces), valid or damaged one way. Whatever the fast path returns is the reference's result bit for
bit (vertices, faces, tags), and a file it declines reaches the reference, so a damaged file gives
the same line-numbered :class:`FormatError`. Binary PLY of the common layouts, read as NumPy
records, equals meshio's reading.
"""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from g1patch import shapes
from g1patch.errors import FormatError, G1PatchError
from g1patch.io import meshfile
from g1patch.io.meshfile import read_mesh
from g1patch.mesh import QuadMesh

SETTINGS = settings(
    max_examples=300, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck)
)
PATH = Path("mesh.obj")

# : how a coordinate may be spelt; the fast path reads those with '_' as float() does, not by
# np.fromstring
PLAIN_COORDINATES = st.one_of(
    st.floats(-1e6, 1e6, allow_nan=False).map(repr),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-1000, 1000).map(str),
    st.sampled_from(
        [
            "0",
            "-0",
            "+1.5",
            ".5",
            "-.25",
            "5.",
            "1e3",
            "1E-3",
            "-2.5e+2",
            "0.30000000000000004",
            "4.9e-324",
        ]
    ),
)
COORDINATES = st.one_of(PLAIN_COORDINATES, st.sampled_from(["1_0", "1_000.5"]))
SPACE = st.sampled_from([" ", "  ", "\t", " \t "])
NEWLINE = st.sampled_from(["\n", "\r\n", "\r"])


def outcome(read, path: Path, data: bytes) -> tuple:
    """A reader's result as comparable values, bitwise for the coordinates, or its error."""
    try:
        parsed = read(path, data)
    except G1PatchError as error:
        return (type(error).__name__, str(error), getattr(error, "line", None))
    faces = parsed.faces if isinstance(parsed.faces, np.ndarray) else np.concatenate(parsed.faces)
    sizes = (
        [parsed.faces.shape[1]] * len(parsed.faces)
        if isinstance(parsed.faces, np.ndarray)
        else [len(f) for f in parsed.faces]
    )
    return (parsed.vertices.shape, parsed.vertices.tobytes(), faces.tolist(), sizes, parsed.tags)


@st.composite
def obj_files(draw) -> bytes:
    """An OBJ file of a few polygons, maybe damaged."""
    n = draw(st.integers(3, 12))
    coordinates = draw(
        st.lists(st.lists(COORDINATES, min_size=3, max_size=3), min_size=n, max_size=n)
    )
    lines: list[str] = []
    defined = 0
    for row in coordinates:
        while draw(st.integers(0, 4)) == 0:  # decoration between vertices
            lines.append(
                draw(
                    st.sampled_from(
                        [
                            "",
                            "# a comment",
                            "vt 0.5 0.5",
                            "vn 0 0 1",
                            "vp 1",
                            "g part",
                            "s off",
                            "o thing",
                            "  ",
                            "usemtl a/b",
                        ]
                    )
                )
            )
        w = [draw(st.sampled_from(["1", "1.0", "0.5"]))] if draw(st.integers(0, 5)) == 0 else []
        space = draw(SPACE)
        lines.append(space.join(["v", *row, *w]) + draw(st.sampled_from(["", " ", "  # end"])))
        defined += 1
    for _ in range(draw(st.integers(1, 6))):
        corners = draw(st.lists(st.integers(0, n - 1), min_size=3, max_size=6))
        spelt = []
        for c in corners:
            index = (
                str(c + 1) if draw(st.booleans()) else str(c - defined)
            )  # 1-based or counted back
            spelt.append(index + draw(st.sampled_from(["", "", "/1", "//2", "/3/4"])))
        lines.append(draw(SPACE).join(["f", *spelt]))
    if draw(st.booleans()):
        lines.append("t crease 2/1/0 0 1 2.5")
    if draw(st.booleans()):
        lines.append("t corner 1/1/0 2 inf")
    lines.insert(0, draw(st.sampled_from(["", "# written by a test", "mtllib x.mtl"])))
    damage = draw(st.sampled_from([None] * 4 + ["token", "line", "insert", "leading"]))
    if damage == "token":
        row = draw(st.integers(0, len(lines) - 1))
        parts = lines[row].split()
        if len(parts) > 1:
            parts[draw(st.integers(1, len(parts) - 1))] = draw(
                st.sampled_from(
                    [
                        "x",
                        "1.2.3",
                        "-",
                        "+",
                        "0",
                        "nan",
                        "inf",
                        "99999999999999999999",
                        "1-2",
                        "--1",
                        "1e",
                        "",
                    ]
                )
            )
            lines[row] = " ".join(parts)
    elif damage == "line":
        del lines[draw(st.integers(0, len(lines) - 1))]
    elif damage == "insert":
        lines.insert(
            draw(st.integers(0, len(lines))),
            draw(
                st.sampled_from(
                    [
                        "f 1 2",
                        "v 1 2",
                        "v a b c",
                        "hello",
                        "f 1/2/3/4 x",
                        "v",
                        "f",
                        "t x 1/0/0",
                        "f 1 2 999",
                    ]
                )
            ),
        )
    elif damage == "leading":
        row = draw(st.integers(0, len(lines) - 1))
        lines[row] = draw(SPACE) + lines[row]
    newline = draw(NEWLINE)
    return (newline.join(lines) + (newline if draw(st.booleans()) else "")).encode()


@pytest.mark.slow
@SETTINGS
@given(obj_files())
def test_obj_fast_path_is_the_reference(data: bytes) -> None:
    fast = meshfile._obj_fast(data)
    reference = outcome(meshfile._read_obj_lines, PATH, data)
    assert outcome(meshfile._read_obj, PATH, data) == reference
    if fast is not None:
        assert outcome(lambda path, data: fast, PATH, data) == reference
    else:
        assert len(reference) == 3, "the fast path declined a valid file"  # an error


@st.composite
def off_files(draw) -> bytes:
    """An OFF file of a few polygons (counts beside the header or on their own line, colours after
    vertices or faces), maybe damaged."""
    n = draw(st.integers(3, 10))
    coordinates = draw(
        st.lists(st.lists(COORDINATES, min_size=3, max_size=3), min_size=n, max_size=n)
    )
    faces = draw(
        st.lists(st.lists(st.integers(0, n - 1), min_size=3, max_size=6), min_size=1, max_size=6)
    )
    header = draw(
        st.sampled_from(["OFF\n{} {} 0", "OFF {} {} 0", "COFF\n# counts\n{} {} 0", "OFF\n\n{} {}"])
    )
    lines = header.format(n, len(faces)).split("\n")
    colour = draw(st.sampled_from(["", " 0.5 0.5 0.5", " 255 0 0"]))
    for row in coordinates:
        lines.append(draw(SPACE).join(row) + (colour if draw(st.integers(0, 3)) == 0 else ""))
        if draw(st.integers(0, 4)) == 0:
            lines.append(draw(st.sampled_from(["", "# comment", "   "])))
    for face in faces:
        lines.append(
            draw(SPACE).join(map(str, [len(face), *face])) + (colour if draw(st.booleans()) else "")
        )
    if draw(st.booleans()):
        lines.append("anything after the faces is ignored")
    damage = draw(st.sampled_from([None] * 4 + ["token", "line", "header"]))
    if damage == "token":
        row = draw(st.integers(1, len(lines) - 1))
        parts = lines[row].split()
        if parts:
            parts[draw(st.integers(0, len(parts) - 1))] = draw(
                st.sampled_from(["x", "-", "+", "nan", "2", "99", "-1", "1.5", "1e"])
            )
            lines[row] = " ".join(parts)
    elif damage == "line":
        del lines[draw(st.integers(0, len(lines) - 1))]
    elif damage == "header":
        lines[0] = draw(st.sampled_from(["OF", "off", "OFF -1 2 0", "OFF 3"]))
    newline = draw(NEWLINE)
    return (newline.join(lines) + (newline if draw(st.booleans()) else "")).encode()


@pytest.mark.slow
@SETTINGS
@given(off_files())
def test_off_fast_path_is_the_reference(data: bytes) -> None:
    path = Path("mesh.off")
    fast = meshfile._off_fast(data)
    reference = outcome(meshfile._read_off_lines, path, data)
    assert outcome(meshfile._read_off, path, data) == reference
    if fast is not None:
        assert outcome(lambda path, data: fast, path, data) == reference
    else:
        assert len(reference) == 3, "the fast path declined a valid file"  # an error


def test_read_mesh_gives_the_reference_mesh(tmp_path: Path) -> None:
    """The whole read: the same QuadMesh (vertices bitwise, faces, tags) as the reference's arrays
    give."""
    path = tmp_path / "squares.obj"
    path.write_bytes(
        b"# two squares\r\nv 0 0 0 1\r\nv 1 0 0\r\nv\t1 1 0\r\nv 0 1 0\r\nvt 0 0\r\nf 1/1 2/1 3/1 "
        b"4/1\r\n"
        b"v 2 0 0\r\nv 2 1 0\r\n  f 2//1 -2//1 -1//1 3//1   # negative\r\nt crease 2/1/0 1 2 "
        b"4.5\r\n"
    )
    data = path.read_bytes()
    assert meshfile._obj_fast(data) is not None
    mesh = read_mesh(path)
    parsed = meshfile._read_obj_lines(path, data)
    expected = QuadMesh.from_arrays(
        parsed.vertices, parsed.faces, source=str(path), tags=parsed.tags
    )
    assert mesh.vertices.tobytes() == expected.vertices.tobytes()
    assert mesh.faces.tolist() == expected.faces.tolist() == [[0, 1, 2, 3], [1, 4, 5, 2]]
    assert mesh.tags == expected.tags


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 x\nf 1 2 3 4\n",
            "expected 'v x y z' with 3 numbers, got '0 1 x'",
            4,
        ),
        (
            "v 0 0 0\r\nv 1 0 0\r\n\r\nf 1 2 3 -\r\n",
            "expected 'f' with integer vertex indices, got '-'",
            4,
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 0\n# c\nf 1 2 4\n",
            "face 0 names vertex 3 (0-based), but the file has 3 vertices",
            5,
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 nan 0\nf 1 2 3\n",
            "vertex 2 has a non-finite coordinate (1.0, nan, 0.0)",
            3,
        ),
        ("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nvx 1\n", "unknown OBJ statement 'vx'", 5),
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nv\n",
            "expected 'v x y z' with 3 numbers, got 'v'",
            5,
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 0\n",
            "vertex index 0 in a face; OBJ indices start at 1",
            4,
        ),
    ],
)
def test_malformed_obj_keeps_the_line_numbered_message(
    tmp_path: Path, text: str, message: str, line: int
) -> None:
    path = tmp_path / "bad.obj"
    path.write_text(text, newline="")
    with pytest.raises(FormatError) as caught:
        read_mesh(path)
    assert str(caught.value) == f"{path}:{line}: {message}" and caught.value.line == line


# -- binary PLY ----------------------------------------------------------------------------------


def ply_bytes(
    points: np.ndarray,
    faces: np.ndarray | list[list[int]],
    coordinate: str,
    count: str,
    index: str,
    order: str,
    extra: bool,
) -> bytes:
    """A binary PLY file of ``points`` and ``faces`` (a table, or a list of faces of any sizes)
    with the given types, byte order and an extra vertex property."""
    names = {
        "f4": "float",
        "f8": "double",
        "u1": "uchar",
        "i4": "int",
        "u4": "uint",
        "u2": "ushort",
    }
    fields = [("x", order + coordinate), ("y", order + coordinate), ("z", order + coordinate)]
    if extra:
        fields.insert(1, ("red", "u1"))
    vertex = np.zeros(len(points), dtype=fields)
    for k, axis in enumerate("xyz"):
        vertex[axis] = points[:, k]
    if isinstance(faces, np.ndarray):
        face = np.zeros(
            len(faces), dtype=[("n", order + count), ("i", order + index, (faces.shape[1],))]
        )
        face["n"], face["i"] = faces.shape[1], faces
        face_bytes = face.tobytes()
    else:
        face_bytes = b"".join(
            np.array([len(f)], order + count).tobytes() + np.array(f, order + index).tobytes()
            for f in faces
        )
    header = [
        "ply",
        f"format binary_{'little' if order == '<' else 'big'}_endian 1.0",
        "comment test",
        f"element vertex {len(points)}",
    ]
    header += [f"property {names[kind.lstrip('<>')]} {name}" for name, kind in fields]
    header += [
        f"element face {len(faces)}",
        f"property list {names[count]} {names[index]} vertex_indices",
        "end_header",
        "",
    ]
    return "\n".join(header).encode() + vertex.tobytes() + face_bytes


def ply_records(data: bytes) -> tuple | None:
    """``_ply_records`` of a binary PLY file's bytes, its header parsed first (None: not the
    common layout)."""
    header = meshfile._ply_header(PATH, data)
    layout = meshfile._ply_layout(header)
    return None if layout is None else meshfile._ply_records(data, header, layout)


@SETTINGS
@given(
    st.sampled_from(["f4", "f8"]),
    st.sampled_from(["u1", "i4"]),
    st.sampled_from(["i4", "u4"]),
    st.sampled_from(["<", ">"]),
    st.booleans(),
    st.integers(3, 5),
    st.integers(0, 2**32 - 1),
)
def test_binary_ply_records_are_meshio(
    tmp_path_factory,
    coordinate: str,
    count: str,
    index: str,
    order: str,
    extra: bool,
    corners: int,
    seed: int,
) -> None:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(int(rng.integers(3, 20)), 3)) * 10.0 ** rng.integers(-3, 4)
    faces = rng.integers(0, len(points), size=(int(rng.integers(1, 8)), corners))
    path = tmp_path_factory.mktemp("ply") / "m.ply"
    data = ply_bytes(points, faces, coordinate, count, index, order, extra)
    path.write_bytes(data)
    records = ply_records(data)
    assert records is not None
    expected = meshfile._ply_meshio(path, meshfile._ply_header(path, data))
    assert records[0].tobytes() == expected[0].tobytes()
    assert (
        records[1].tolist() == expected[1].tolist() and records[2].tolist() == expected[2].tolist()
    )


def test_binary_ply_other_layouts_go_to_meshio(tmp_path: Path) -> None:
    """Mixed corner counts are walked, a cut file or more bytes than announced are errors naming
    the face, a face list of another name goes to meshio."""
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], dtype=float)
    path = tmp_path / "mixed.ply"
    meshio.ply.write(
        str(path),
        meshio.Mesh(
            points, [("quad", np.array([[0, 1, 2, 3]])), ("triangle", np.array([[1, 4, 2]]))]
        ),
        binary=True,
    )
    data = path.read_bytes()
    assert ply_records(data) is None
    assert read_mesh(path).n_faces == 4 + 3
    quads = ply_bytes(points, np.array([[0, 1, 2, 3]]), "f8", "u1", "i4", "<", False)
    assert ply_records(quads + b"\0") is None and ply_records(quads[:-1]) is None
    path.write_bytes(quads[:-3])
    with pytest.raises(FormatError, match=r"truncated: face 0 announces 4 corners"):
        read_mesh(path)
    path.write_bytes(quads + b"\0")
    with pytest.raises(FormatError, match=r"1 bytes after the last of the 1 faces"):
        read_mesh(path)
    path.write_bytes(
        quads.replace(
            b"property list uchar int vertex_indices", b"property list uchar int corner_indices"
        )
    )
    assert meshfile._ply_layout(meshfile._ply_header(path, path.read_bytes())) is None


# -- ASCII PLY -----------------------------------------------------------------------------------


@st.composite
def ascii_ply_files(draw) -> bytes:
    """An ASCII PLY file of a few faces (double or float coordinates, maybe a normal per vertex,
    mixed corner counts), maybe damaged: the fast path reads it as the reference does, or
    declines."""
    n = draw(st.integers(3, 10))
    normals = draw(st.booleans())
    width = 6 if normals else 3
    coordinates = draw(
        st.lists(
            st.lists(PLAIN_COORDINATES, min_size=width, max_size=width), min_size=n, max_size=n
        )
    )
    faces = draw(
        st.lists(st.lists(st.integers(0, n - 1), min_size=3, max_size=5), min_size=1, max_size=6)
    )
    kind = draw(st.sampled_from(["double", "double", "float"]))
    properties = [f"property {kind} x", f"property {kind} y", f"property {kind} z"]
    properties += (
        ["property double nx", "property double ny", "property double nz"] if normals else []
    )
    index = draw(st.sampled_from(["int", "uint32", "int32"]))
    lines = [
        "ply",
        "format ascii 1.0",
        "comment generated",
        f"element vertex {n}",
        *properties,
        f"element face {len(faces)}",
        f"property list uchar {index} vertex_indices",
        "end_header",
    ]
    lines += [draw(SPACE).join(row) for row in coordinates]
    lines += [draw(SPACE).join(map(str, [len(face), *face])) for face in faces]
    damage = draw(
        st.sampled_from([None] * 4 + ["token", "line", "blank", "comment", "crlf", "extra"])
    )
    if damage == "token":
        row = draw(st.integers(len(lines) - n - len(faces), len(lines) - 1))
        parts = lines[row].split()
        parts[draw(st.integers(0, len(parts) - 1))] = draw(
            st.sampled_from(["x", "-", "nan", "99", "-1", "1.5", "2", "4", "1e39"])
        )
        lines[row] = " ".join(parts)
    elif damage == "line":
        del lines[draw(st.integers(len(lines) - n - len(faces), len(lines) - 1))]
    elif damage == "blank":
        lines.insert(draw(st.integers(len(lines) - n - len(faces), len(lines))), "")
    elif damage == "comment":
        lines[-1] += " # a comment"
    elif damage == "extra":
        lines.append(draw(st.sampled_from(["3 0 1 2", "0", "end"])))
    newline = "\r\n" if damage == "crlf" else "\n"
    return (newline.join(lines) + newline).encode()


@pytest.mark.slow
@SETTINGS
@given(ascii_ply_files())
def test_ascii_ply_fast_path_is_the_reference_and_meshio(tmp_path_factory, data: bytes) -> None:
    """Where the fast path reads a file, the line-by-line reference reads the same; where the
    reference reads a file and meshio too, they agree (float coordinates rounded to float32 as
    meshio rounds them); a file meshio reads wrong (a face's count that is not its number of
    indices, lines after the last face) is an error of the reference, and blank lines and comments
    among the faces, which meshio refuses, are read."""
    path = tmp_path_factory.mktemp("ply") / "m.ply"
    path.write_bytes(data)
    header = meshfile._ply_header(path, data)
    layout = meshfile._ply_layout(header)
    assert layout is not None
    fast = meshfile._ply_text(data, header, layout)
    reference = outcome(
        lambda path, data: meshfile._read_ply_lines(path, data, header, layout), path, data
    )
    assert outcome(meshfile._read_ply, path, data) == reference
    corners = None if reference[0] == "FormatError" else np.ravel(reference[2]).tolist()
    if fast is not None:
        assert (reference[1], corners, reference[3]) == (
            fast[0].tobytes(),
            fast[1].tolist(),
            fast[2].tolist(),
        )
    if corners is None:
        return
    try:
        expected = meshfile._ply_meshio(path, header)
    except FormatError:  # blank lines or comments among the faces: meshio refuses them
        assert b"#" in data or b"\n\n" in data or b"\r\n\r\n" in data
        return
    assert (reference[1], corners, reference[3]) == (
        expected[0].tobytes(),
        expected[1].tolist(),
        expected[2].tolist(),
    )


def test_ascii_ply_as_meshio_writes_it_takes_the_fast_path(tmp_path: Path) -> None:
    mesh = shapes.torus(6, 4)
    path = tmp_path / "torus.ply"
    meshio.ply.write(
        str(path), meshio.Mesh(mesh.vertices, [("quad", mesh.faces.astype(np.int32))]), binary=False
    )
    data = path.read_bytes()
    header = meshfile._ply_header(path, data)
    assert meshfile._ply_text(data, header, meshfile._ply_layout(header)) is not None
    again = read_mesh(path)
    assert (
        again.vertices.tobytes() == mesh.vertices.tobytes()
        and again.faces.tolist() == mesh.faces.tolist()
    )
