"""Quad mesh files: read OBJ / PLY / OFF into a :class:`QuadMesh`; write triangles or quads as OBJ / PLY / STL.

* OBJ is read by a small parser of its own (``v``, ``f``, OpenSubdiv ``t`` tag lines; other OBJ
  statements are skipped, unknown ones are errors) so that every error names its line and mixed
  polygon lists keep their order.
* PLY is read by meshio (``meshio.ply``), after checking the header here: meshio silently returns
  fewer faces from a truncated binary file.
* OFF is read by a parser of its own: meshio's OFF reader only accepts triangles.

Every problem with a file raises :class:`FormatError` (file, line where known, what was expected);
problems with the mesh it describes raise the :class:`MeshError` family, prefixed with the file
name. Writes go through :func:`atomic_path`: an error never leaves a partial file. OBJ and STL are
written here, a block of rows at a time (several times faster than meshio and in bounded
memory), binary PLY by meshio.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import meshio
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FormatError, InputError, as_float_array, as_index_array
from ..mesh import QuadMesh, Tag
from .atomic import atomic_path

__all__ = ["read_mesh", "write_triangles", "write_quads", "READ_FORMATS", "WRITE_FORMATS"]

READ_FORMATS = (".obj", ".ply", ".off")
WRITE_FORMATS = (".obj", ".ply", ".stl")

#: OBJ statements that carry nothing a quad mesh needs (normals, texture, grouping, materials,
#: free-form geometry); they are skipped. Any other keyword is an error.
OBJ_SKIPPED = frozenset(
    "vt vn vp g o s usemtl mtllib l p lod bevel c_interp d_interp shadow_obj trace_obj maplib usemap "
    "cstype deg bmat step curv curv2 surf parm trim hole scrv sp end con mg ctech stech call csh".split()
)

PathLike = str | os.PathLike[str]


def read_mesh(path: PathLike, *, split: bool = True, sharp_angle: float | None = None, strict: bool | None = None) -> QuadMesh:
    """Read an OBJ, PLY or OFF file into a validated :class:`QuadMesh` (tags from OBJ ``t`` lines).

    With ``split`` a mesh with non-quad faces is refined once into quads (see
    :meth:`QuadMesh.from_arrays`); without, such a mesh raises :class:`MeshError`.
    ``sharp_angle`` (degrees): tag the edges whose faces' normals differ by more than that as
    infinitely sharp, and vertices with three such edges as corners, before splitting
    (:func:`g1patch.sharpen.sharp_angle_tags`); the file's own tags are kept. ``strict``: refuse
    a mesh that needs repair instead of repairing it (:meth:`QuadMesh.from_arrays`).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    readers = {".obj": _read_obj, ".ply": _read_ply, ".off": _read_off}
    if suffix not in readers:
        raise FormatError(path, f"unsupported extension {path.suffix!r}; expected one of {', '.join(READ_FORMATS)}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise FormatError(path, f"cannot read the file ({exc.strerror or exc})") from None
    if not data or data.isspace():
        raise FormatError(path, "the file is empty")
    parsed = readers[suffix](path, data)
    tags = parsed.tags
    if sharp_angle is not None:
        tags = tags + _sharp_angle_tags(path, parsed, sharp_angle)
    return QuadMesh.from_arrays(parsed.vertices, parsed.faces, split=split, source=str(path), tags=tags, strict=strict)


def _sharp_angle_tags(path: Path, parsed: _Parsed, degrees: float) -> tuple[Tag, ...]:
    """The ``--sharp-angle`` tags of a parsed file, on its own polygons (index errors are left to the mesh checks)."""
    from ..mesh import _as_polygons
    from ..sharpen import sharp_angle_tags

    corners, sizes = _as_polygons(parsed.faces)
    vertices = np.asarray(parsed.vertices, dtype=np.float64)
    if sizes.size == 0 or corners.size == 0 or corners.min() < 0 or corners.max() >= len(vertices) or not np.isfinite(vertices).all():
        return ()
    return sharp_angle_tags(vertices, corners, sizes, degrees)


class _Parsed(NamedTuple):
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64] | list[NDArray[np.int64]]
    tags: tuple[Tag, ...] = ()


def _decode(path: Path, data: bytes) -> list[str]:
    try:
        return data.decode("utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise FormatError(path, f"not a text file (byte {exc.start} is not UTF-8)") from None


def _finite_vertices(path: Path, vertices: NDArray[np.float64], lines: NDArray[np.int64] | None) -> None:
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if bad.size:
        v = int(bad[0])
        raise FormatError(
            path,
            f"vertex {v} has a non-finite coordinate {tuple(vertices[v].tolist())}",
            None if lines is None else int(lines[v]),
        )


def _faces_in_range(
    path: Path, corners: NDArray[np.int64], sizes: NDArray[np.int64], n_vertices: int, lines: NDArray[np.int64] | None
) -> None:
    bad = np.flatnonzero((corners < 0) | (corners >= n_vertices))
    if bad.size:
        face = int(np.searchsorted(np.cumsum(sizes), bad[0], side="right"))
        raise FormatError(
            path,
            f"face {face} names vertex {corners[bad[0]]} (0-based), but the file has {n_vertices} vertices",
            None if lines is None else int(lines[face]),
        )


def _polygon_list(corners: NDArray[np.int64], sizes: NDArray[np.int64]) -> NDArray[np.int64] | list[NDArray[np.int64]]:
    """An (nf, n) table when all faces have n corners, else one index array per face."""
    if (sizes == sizes[0]).all():
        return corners.reshape(-1, int(sizes[0]))
    return np.split(corners, np.cumsum(sizes)[:-1])


# -- OBJ ---------------------------------------------------------------------------------------


def _read_obj(path: Path, data: bytes) -> _Parsed:
    """OBJ: ``v x y z [w]``; ``f a b c …`` with ``a`` = ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``.

    Indices are 1-based; negative ones count back from the last vertex defined so far.

    The loop over lines only sorts tokens; NumPy converts them in bulk, and only on a bad number
    are the lines searched again to name the one at fault.
    """
    vertex_tokens: list[list[str]] = []
    vertex_lines: list[int] = []
    face_tokens: list[str] = []
    sizes: list[int] = []
    face_lines: list[int] = []
    vertices_before_face: list[int] = []
    tags: list[Tag] = []
    for number, line in enumerate(_decode(path, data), start=1):
        if "#" in line:
            line = line.split("#", 1)[0]
        parts = line.split()
        if not parts:
            continue
        keyword = parts[0]
        if keyword == "v":
            if not 4 <= len(parts) <= 8:
                raise FormatError(path, f"expected 'v x y z' with 3 numbers, got {line.strip()!r}", number)
            vertex_tokens.append(parts[1:4])
            vertex_lines.append(number)
        elif keyword == "f":
            if len(parts) < 4:
                raise FormatError(path, f"a face needs at least 3 corners, got {len(parts) - 1}", number)
            indices = parts[1:]
            if "/" in line:  # v/vt/vn: keep v
                indices = [token.partition("/")[0] for token in indices]
            face_tokens.extend(indices)
            sizes.append(len(parts) - 1)
            face_lines.append(number)
            vertices_before_face.append(len(vertex_tokens))
        elif keyword == "t":
            tags.append(_parse_tag(path, parts, number))
        elif keyword not in OBJ_SKIPPED:
            raise FormatError(path, f"unknown OBJ statement {keyword[:40]!r}", number)
    if not sizes:
        raise FormatError(path, "no faces: expected 'f' lines")

    face_sizes = np.array(sizes, dtype=np.int64)
    points = _convert(path, vertex_tokens, np.float64, "'v x y z' with 3 numbers", vertex_lines).reshape(-1, 3)
    _finite_vertices(path, points, np.array(vertex_lines))
    token_lines = np.repeat(face_lines, face_sizes)
    written = _convert(path, face_tokens, np.int64, "'f' with integer vertex indices", token_lines)
    if (written == 0).any():
        line = face_lines[int(np.searchsorted(np.cumsum(face_sizes), np.flatnonzero(written == 0)[0], side="right"))]
        raise FormatError(path, "vertex index 0 in a face; OBJ indices start at 1", line)
    # 1-based; negative indices count back from the last vertex defined before the face
    corners = np.where(written > 0, written - 1, np.repeat(vertices_before_face, face_sizes) + written)
    _faces_in_range(path, corners, face_sizes, points.shape[0], np.array(face_lines))
    return _Parsed(points, _polygon_list(corners, face_sizes), tuple(tags))


def _convert(path: Path, tokens: list, dtype: type, expected: str, lines: Sequence[int] | NDArray[np.int64]) -> NDArray:
    """``np.array(tokens, dtype)``; on a bad token, a :class:`FormatError` naming its line (``lines`` per row)."""
    try:
        return np.array(tokens, dtype=dtype)
    except (ValueError, OverflowError):
        for row, line in zip(tokens, lines):
            try:
                np.array(row, dtype=dtype)
            except (ValueError, OverflowError):
                text = row if isinstance(row, str) else " ".join(row)
                raise FormatError(path, f"expected {expected}, got {text!r}", int(line)) from None
        raise


def _parse_tag(path: Path, parts: Sequence[str], line: int) -> Tag:
    """OpenSubdiv ``t name nints/nfloats/nstrings ints… floats… strings…`` (integers 0-based)."""
    usage = "expected 't name nints/nfloats/nstrings ints... floats... strings...'"
    if len(parts) < 3:
        raise FormatError(path, usage, line)
    counts = parts[2].split("/")
    if len(counts) != 3 or not all(c.isdigit() for c in counts):
        raise FormatError(path, f"{usage}; got counts {parts[2]!r}", line)
    n_ints, n_floats, n_strings = map(int, counts)
    values = parts[3:]
    if len(values) != n_ints + n_floats + n_strings:
        raise FormatError(
            path, f"tag {parts[1]!r} announces {n_ints}/{n_floats}/{n_strings} values but has {len(values)}", line
        )
    try:
        ints = tuple(int(x) for x in values[:n_ints])
        floats = tuple(float(x) for x in values[n_ints:n_ints + n_floats])
    except ValueError:
        raise FormatError(path, f"tag {parts[1]!r}: expected {n_ints} integers then {n_floats} numbers", line) from None
    return Tag(parts[1], ints, floats, tuple(values[n_ints + n_floats:]))


# -- OFF ---------------------------------------------------------------------------------------

OFF_HEADERS = frozenset({"OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCOFF", "STNOFF", "STCNOFF"})


def _read_off(path: Path, data: bytes) -> _Parsed:
    """``OFF``, ``nv nf ne``, nv lines ``x y z …``, nf lines ``n i_1 … i_n …`` (0-based); ``#`` comments."""
    content = [
        (number, parts)
        for number, line in enumerate(_decode(path, data), start=1)
        if (parts := line.split("#", 1)[0].split())
    ]
    if not content or content[0][1][0] not in OFF_HEADERS:
        raise FormatError(path, "expected the header 'OFF' on the first line", content[0][0] if content else 1)
    (counts_line, header), body = content[0], content[1:]
    counts = header[1:]  # the counts may follow the header on its line
    if not counts and body:
        (counts_line, counts), body = body[0], body[1:]
    try:
        n_vertices, n_faces = int(counts[0]), int(counts[1])
        if n_vertices < 0 or n_faces < 0:
            raise ValueError
    except (IndexError, ValueError):
        raise FormatError(path, "expected the counts 'n_vertices n_faces n_edges'", counts_line) from None
    if len(body) < n_vertices + n_faces:
        last = content[-1][0]
        raise FormatError(
            path,
            f"truncated: the header announces {n_vertices} vertices and {n_faces} faces, the file ends first",
            last,
        )

    vertex_rows, face_rows = body[:n_vertices], body[n_vertices:n_vertices + n_faces]
    points = np.empty((n_vertices, 3))
    for row, (number, parts) in enumerate(vertex_rows):
        try:
            points[row] = [float(x) for x in parts[:3]]
        except ValueError:
            raise FormatError(path, f"expected a vertex 'x y z', got {' '.join(parts)!r}", number) from None
    vertex_lines = np.array([number for number, _ in vertex_rows], dtype=np.int64)
    _finite_vertices(path, points, vertex_lines)

    faces = []
    for number, parts in face_rows:
        try:
            size = int(parts[0])
            corners = [int(x) for x in parts[1:1 + size]]
            if size < 3 or len(corners) != size:
                raise ValueError
        except ValueError:
            expected = "expected a face 'n i_1 ... i_n' with n >= 3"
            raise FormatError(path, f"{expected}, got {' '.join(parts)!r}", number) from None
        faces.append(corners)
    sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    if sizes.size == 0:
        raise FormatError(path, "no faces: the header announces 0 faces", counts_line)
    corners = np.fromiter((i for face in faces for i in face), dtype=np.int64, count=int(sizes.sum()))
    _faces_in_range(path, corners, sizes, n_vertices, np.array([number for number, _ in face_rows]))
    return _Parsed(points, _polygon_list(corners, sizes))


# -- PLY ---------------------------------------------------------------------------------------


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
                raise FormatError(path, f"expected 'element name count', got {line.strip()!r}", number)
            elements.append((parts[1], int(parts[2])))
    return _PlyHeader("format ascii" in data[:end].decode("ascii"), elements, len(header) + 1)


def _read_ply(path: Path, data: bytes) -> _Parsed:
    """PLY through ``meshio.ply``; the vertex and face counts are checked against the header."""
    header = _ply_header(path, data)
    counts = dict(header.elements)
    if counts.get("face", 0) == 0:
        raise FormatError(path, "no faces: the header declares no 'element face'")
    try:
        with warnings.catch_warnings():  # numbers beyond the declared type: the finite-coordinate check names them
            warnings.simplefilter("ignore", RuntimeWarning)
            mesh = meshio.ply.read(str(path))
    except (meshio.ReadError, ValueError, IndexError, KeyError, TypeError, AssertionError, EOFError) as exc:
        reason = f"{type(exc).__name__}: {' '.join(str(exc).split())}"  # one line, whatever the library wrote
        raise FormatError(path, f"cannot read the PLY data, truncated or malformed ({reason})") from None
    points = np.asarray(mesh.points, dtype=np.float64)
    polygon_types = ("triangle", "quad", "polygon")
    blocks = [np.asarray(block.data, dtype=np.int64) for block in mesh.cells if block.type in polygon_types]
    sizes = np.repeat([b.shape[1] if b.ndim == 2 else 0 for b in blocks], [len(b) for b in blocks]).astype(np.int64)
    if points.shape != (counts.get("vertex", 0), 3) or sizes.size != counts["face"]:
        raise FormatError(
            path,
            f"truncated or malformed: the header announces {counts.get('vertex', 0)} vertices (x, y, z) and "
            f"{counts['face']} faces, meshio read {points.shape[0]} vertices and {sizes.size} faces",
        )
    # for an ASCII file with vertices then faces, one element per line after the header
    in_order = header.ascii and [name for name, _ in header.elements] == ["vertex", "face"]
    vertex_lines = header.lines + 1 + np.arange(points.shape[0]) if in_order else None
    face_lines = header.lines + 1 + points.shape[0] + np.arange(sizes.size) if in_order else None
    _finite_vertices(path, points, vertex_lines)
    corners = np.concatenate([b.ravel() for b in blocks])
    _faces_in_range(path, corners, sizes, points.shape[0], face_lines)
    return _Parsed(points, _polygon_list(corners, sizes))


# -- writing -----------------------------------------------------------------------------------


def _write_format(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in WRITE_FORMATS:
        expected = ", ".join(WRITE_FORMATS)
        raise FormatError(path, f"unsupported extension {path.suffix!r} for writing; expected one of {expected}")
    return suffix


def _checked_points(name: str, points: ArrayLike) -> NDArray[np.float64]:
    array = as_float_array(name, points, (3,))
    if array.ndim != 2:
        raise InputError(f"{name}: expected shape (n, 3), got {array.shape}")
    return array


def _checked_cells(name: str, cells: ArrayLike, corners: int, n_points: int) -> NDArray[np.int64]:
    table = as_index_array(name, cells, (corners,))
    if table.ndim != 2:
        raise InputError(f"{name}: expected shape (n, {corners}), got {table.shape}")
    bad = np.flatnonzero(((table < 0) | (table >= n_points)).any(axis=1))
    if bad.size:
        row = tuple(table[bad[0]].tolist())
        raise InputError(f"{name}: row {bad[0]} {row} names a point outside 0..{n_points - 1}")
    return table


#: rows formatted per string in OBJ output (bounds the text held in memory to a few MB)
_OBJ_ROWS = 1 << 15


def _write_obj(path: Path, points: NDArray[np.float64], cells: NDArray[np.int64]) -> None:
    """OBJ text as meshio writes it (``v x y z`` with the shortest round-trip digits, ``f`` with
    1-based indices), formatted a block of rows at a time by one C-level ``%`` per block: several
    times faster than meshio's line-by-line loop, and in bounded memory."""
    vertex_row = "v %r %r %r\n"
    face_row = "f" + " %d" * cells.shape[1] + "\n"
    with open(path, "w", encoding="ascii", newline="\n") as handle:
        handle.write("# written by g1patch\n")
        for start in range(0, len(points), _OBJ_ROWS):
            block = points[start:start + _OBJ_ROWS]
            handle.write((vertex_row * len(block)) % tuple(block.ravel().tolist()))
        for start in range(0, len(cells), _OBJ_ROWS):
            block = cells[start:start + _OBJ_ROWS] + 1
            handle.write((face_row * len(block)) % tuple(block.ravel().tolist()))


_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("points", "<f4", (3, 3)), ("attr", "<u2")])


def _write_stl(path: Path, points: NDArray[np.float64], triangles: NDArray[np.int64]) -> None:
    """Binary STL as meshio writes it (unit facet normals, float32), a block of triangles at a time
    so that memory does not grow by the 100 bytes a triangle of meshio's whole-array records; a
    triangle without area gets the normal 0 (meshio: NaN)."""
    header = b"binary STL written by g1patch"
    with open(path, "wb") as handle:
        handle.write(header + b" " * (80 - len(header)))
        handle.write(np.array(len(triangles), dtype="<u4").tobytes())
        for start in range(0, len(triangles), _OBJ_ROWS):
            corners = points[triangles[start:start + _OBJ_ROWS]]
            normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
            length = np.sqrt(np.einsum("ij,ij->i", normals, normals))[:, None]
            records = np.zeros(len(corners), dtype=_STL_RECORD)
            records["normal"] = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
            records["points"] = corners
            handle.write(records.tobytes())


def _write(path: Path, suffix: str, points: NDArray[np.float64], cell_type: str, cells: NDArray[np.int64]) -> None:
    if suffix in (".obj", ".stl"):
        writer = _write_obj if suffix == ".obj" else _write_stl
        with atomic_path(path) as temporary:
            writer(temporary, points, cells)
        return
    index_type = np.int32 if cells.size == 0 or cells.max() < 2**31 else np.int64  # PLY wants 32-bit indices
    mesh = meshio.Mesh(points, [(cell_type, cells.astype(index_type))])
    with atomic_path(path) as temporary:
        meshio.ply.write(str(temporary), mesh, binary=True)


def write_triangles(path: PathLike, points: ArrayLike, triangles: ArrayLike) -> None:
    """Write a triangle mesh, ``points`` (n, 3) and ``triangles`` (m, 3), as OBJ, PLY or STL (by extension)."""
    path = Path(path)
    suffix = _write_format(path)
    points = _checked_points("points", points)
    _write(path, suffix, points, "triangle", _checked_cells("triangles", triangles, 3, points.shape[0]))


def write_quads(path: PathLike, vertices: ArrayLike, faces: ArrayLike) -> None:
    """Write a quad mesh as OBJ or PLY, or as STL with each quad (a, b, c, d) split into (a, b, c), (a, c, d)."""
    path = Path(path)
    suffix = _write_format(path)
    vertices = _checked_points("vertices", vertices)
    quads = _checked_cells("faces", faces, 4, vertices.shape[0])
    if suffix == ".stl":
        _write(path, suffix, vertices, "triangle", quads[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3))
    else:
        _write(path, suffix, vertices, "quad", quads)
