"""PLY: the header checked here; files of the common layout read as NumPy records (binary) or
parsed as OBJ and OFF text is (ASCII), any other by ``meshio.ply``, whose counts are checked
against the header (meshio silently returns fewer faces from a truncated binary file)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import NamedTuple

import meshio
import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from .parsed import _faces_in_range, _finite_vertices, _Parsed, _polygon_list
from .text import _numbers, _scan


class _PlyHeader(NamedTuple):
    ascii: bool
    elements: list[tuple[str, int]]
    lines: int


def _ply_header(path: Path, data: bytes) -> _PlyHeader:
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise FormatError(path, "expected a PLY header: 'ply' ... 'end_header'", 1)
    try:
        header = data[:end].decode("ascii").splitlines()
    except UnicodeDecodeError:
        raise FormatError(path, "the PLY header is not ASCII text") from None
    elements = []
    for number, line in enumerate(header, start=1):
        parts = line.split()
        if parts[:1] == ["element"]:
            if len(parts) != 3 or not parts[2].isdigit():
                raise FormatError(
                    path, f"expected 'element name count', got {line.strip()!r}", number
                )
            elements.append((parts[1], int(parts[2])))
    return _PlyHeader("format ascii" in data[:end].decode("ascii"), elements, len(header) + 1)


def _read_ply(path: Path, data: bytes) -> _Parsed:
    """PLY of the common layout as NumPy records (binary, :func:`_ply_records`) or parsed as OBJ
    and OFF are (ASCII, :func:`_ply_text`), any other through ``meshio.ply``, the vertex and face
    counts checked against the header."""
    header = _ply_header(path, data)
    counts = dict(header.elements)
    if counts.get("face", 0) == 0:
        raise FormatError(path, "no faces: the header declares no 'element face'")
    records = _ply_text(data) if header.ascii else _ply_records(data)
    if records is not None:
        points, corners, sizes = records
        vertex_lines = face_lines = None
    else:
        points, corners, sizes, vertex_lines, face_lines = _ply_meshio(path, header)
    _finite_vertices(path, points, vertex_lines)
    _faces_in_range(path, corners, sizes, points.shape[0], face_lines)
    return _Parsed(points, _polygon_list(corners, sizes))


#: PLY scalar types as NumPy codes (without the byte order), those of meshio's binary reader as it
#: maps them (``uchar`` signed), so that a file reads the same by either path
_PLY_TYPES = {
    "uchar": "i1",
    "uint": "u4",
    "uint8": "u1",
    "uint16": "u2",
    "uint32": "u4",
    "uint64": "u8",
    "int": "i4",
    "int8": "i1",
    "int32": "i4",
    "int64": "i8",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
}
_PLY_ORDER = {"format binary_little_endian 1.0": "<", "format binary_big_endian 1.0": ">"}


class _PlyLayout(NamedTuple):
    """A PLY file of the common layout: one vertex element of scalar properties with x, y, z, then
    one face element of one list ``vertex_indices``; ``start``: the first byte after the header."""

    format: str
    n_vertices: int
    vertex_properties: list[tuple[str, str]]  # (type, name)
    n_faces: int
    count_type: str
    index_type: str
    start: int


def _ply_layout(data: bytes) -> _PlyLayout | None:
    """The layout of a PLY file whose header :func:`_ply_header` accepted, None if it is not the
    common one."""
    end = data.find(b"end_header")  # the header is ASCII before it
    lines = [line.strip() for line in data[:end].decode("ascii").splitlines()]
    if data[end : end + 11] != b"end_header\n" or len(lines) < 2 or lines[0] != "ply":
        return None
    elements: list[tuple[str, int, list[list[str]]]] = []
    for line in lines[2:]:
        parts = line.split()
        if parts[:1] == ["element"]:
            elements.append((parts[1], int(parts[2]), []))
        elif parts[:1] == ["property"] and elements:
            elements[-1][2].append(parts[1:])
        elif parts[:1] not in (["comment"], ["obj_info"]):
            return None
    if [name for name, _, _ in elements] != ["vertex", "face"]:
        return None
    (_, n_vertices, vertex_properties), (_, n_faces, face_properties) = elements
    names = [p[-1] for p in vertex_properties]
    if (
        any(len(p) != 2 for p in vertex_properties)
        or len(set(names)) != len(names)
        or not {"x", "y", "z"} <= set(names)
        or len(face_properties) != 1
        or len(face_properties[0]) != 4
        or face_properties[0][0] != "list"
        or face_properties[0][3] != "vertex_indices"
    ):
        return None
    count_type, index_type = face_properties[0][1:3]
    return _PlyLayout(
        lines[1],
        n_vertices,
        [(p[0], p[1]) for p in vertex_properties],
        n_faces,
        count_type,
        index_type,
        end + 11,
    )


def _ply_records(
    data: bytes,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]] | None:
    """Points, corners and sizes of a binary PLY file of the common layout (:func:`_ply_layout`),
    every face with as many corners and nothing after them, read as NumPy records; None for any
    other file."""
    layout = _ply_layout(data)
    if layout is None or layout.format not in _PLY_ORDER:
        return None
    order = _PLY_ORDER[layout.format]
    kinds = [kind for kind, _ in layout.vertex_properties] + [layout.count_type, layout.index_type]
    if not set(kinds) <= _PLY_TYPES.keys() or {
        _PLY_TYPES[layout.count_type][0],
        _PLY_TYPES[layout.index_type][0],
    } & {"f"}:
        return None
    vertex_type = np.dtype(
        [(name, order + _PLY_TYPES[kind]) for kind, name in layout.vertex_properties]
    )
    count_type, index_type = (
        np.dtype(order + _PLY_TYPES[kind]) for kind in (layout.count_type, layout.index_type)
    )
    faces_start = layout.start + layout.n_vertices * vertex_type.itemsize
    if len(data) < faces_start + count_type.itemsize:
        return None
    corners = int(np.frombuffer(data, count_type, 1, faces_start)[0])
    face_type = np.dtype([("n", count_type), ("i", index_type, (max(corners, 0),))])
    if corners < 3 or len(data) != faces_start + layout.n_faces * face_type.itemsize:
        return None
    faces = np.frombuffer(data, face_type, layout.n_faces, faces_start)
    if (faces["n"] != corners).any():
        return None
    vertices = np.frombuffer(data, vertex_type, layout.n_vertices, layout.start)
    points = np.stack([vertices[axis].astype(np.float64) for axis in "xyz"], axis=1)
    return (
        points,
        faces["i"].astype(np.int64).ravel(),
        np.full(layout.n_faces, corners, dtype=np.int64),
    )


#: the PLY types of an ASCII file's faces the fast path reads (meshio's integer ones)
_PLY_ASCII_INTEGERS = frozenset(
    {"uchar", "uint8", "uint16", "uint", "uint32", "int", "int8", "int32", "int64", "uint64"}
)


def _ply_text(
    data: bytes,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]] | None:
    """Points, corners and sizes of an ASCII PLY file of the common layout (:func:`_ply_layout`)
    with x, y, z first and every vertex property ``double``, one line per vertex then per face
    with exactly its numbers, no blank line or comment among them: parsed as the OBJ and OFF text
    is; None for any other file (meshio reads it)."""
    layout = _ply_layout(data)
    if (
        layout is None
        or layout.format != "format ascii 1.0"
        or [name for _, name in layout.vertex_properties[:3]] != ["x", "y", "z"]
        or any(kind not in ("double", "float64") for kind, _ in layout.vertex_properties)
        or not {layout.count_type, layout.index_type} <= _PLY_ASCII_INTEGERS
    ):
        return None
    body = data[layout.start :]
    lines = (
        None if b"#" in body or b"\r" in body else _scan(body)
    )  # meshio: '#' starts a comment, only LF ends a line
    n_vertices, n_faces, width = layout.n_vertices, layout.n_faces, len(layout.vertex_properties)
    if lines is None or lines.tokens.size < n_vertices + n_faces:
        return None
    vertex_tokens, face_tokens = (
        lines.tokens[:n_vertices],
        lines.tokens[n_vertices : n_vertices + n_faces],
    )
    if (vertex_tokens != width).any() or (face_tokens == 0).any():
        return None
    values = _numbers(lines.chunk(np.arange(n_vertices)), b"", width * n_vertices, np.float64)
    if values is None or not np.isfinite(points := values.reshape(-1, width)[:, :3]).all():
        return None
    numbers = _numbers(
        lines.chunk(np.arange(n_vertices, n_vertices + n_faces)),
        b"",
        int(face_tokens.sum()),
        np.int64,
    )
    offsets = np.cumsum(face_tokens) - face_tokens
    if numbers is None or (numbers[offsets] != face_tokens - 1).any():
        return None
    sizes, corners = numbers[offsets], np.delete(numbers, offsets)
    if (sizes < 3).any() or (sizes > 127).any() or corners.min() < 0 or corners.max() >= n_vertices:
        return None
    return np.ascontiguousarray(points), corners, sizes


def _ply_meshio(
    path: Path, header: _PlyHeader
) -> tuple[
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64] | None,
    NDArray[np.int64] | None,
]:
    """Points, corners, sizes and, for an ASCII file of vertices then faces, the vertices' and
    faces' lines, read by ``meshio.ply``."""
    counts = dict(header.elements)
    try:
        with (
            warnings.catch_warnings()
        ):  # numbers beyond the declared type: the finite-coordinate check names them
            warnings.simplefilter("ignore", RuntimeWarning)
            mesh = meshio.ply.read(str(path))
    except (
        meshio.ReadError,
        ValueError,
        OverflowError,
        IndexError,
        KeyError,
        TypeError,
        AssertionError,
        EOFError,
    ) as exc:
        # one line, whatever the library wrote
        reason = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        raise FormatError(
            path, f"cannot read the PLY data, truncated or malformed ({reason})"
        ) from None
    points = np.asarray(mesh.points, dtype=np.float64)
    polygon_types = ("triangle", "quad", "polygon")
    blocks = [
        np.asarray(block.data, dtype=np.int64)
        for block in mesh.cells
        if block.type in polygon_types
    ]
    sizes = np.repeat(
        [b.shape[1] if b.ndim == 2 else 0 for b in blocks], [len(b) for b in blocks]
    ).astype(np.int64)
    if points.shape != (counts.get("vertex", 0), 3) or sizes.size != counts["face"]:
        raise FormatError(
            path,
            f"truncated or malformed: the header announces {counts.get('vertex', 0)} vertices (x, "
            "y, z) and "
            f"{counts['face']} faces, meshio read {points.shape[0]} vertices and {sizes.size} "
            "faces",
        )
    # for an ASCII file with vertices then faces, one element per line after the header
    in_order = header.ascii and [name for name, _ in header.elements] == ["vertex", "face"]
    vertex_lines = header.lines + 1 + np.arange(points.shape[0]) if in_order else None
    face_lines = header.lines + 1 + points.shape[0] + np.arange(sizes.size) if in_order else None
    return points, np.concatenate([b.ravel() for b in blocks]), sizes, vertex_lines, face_lines
