"""PLY: the header parsed and checked here, the body against it; files of the common layout read
by g1patch's own readers (binary: :mod:`.ply_binary`, ASCII: :mod:`.ply_ascii`), any other by
``meshio.ply``, whose counts are checked against the header (meshio silently returns fewer faces
from a truncated binary file).

Texture coordinates become one UV per face corner, as OBJ ``vt`` do: per vertex (the first pair of
:data:`~.ply_header.UV_PROPERTIES` a vertex has: ``s t``, ``u v``, ``texture_u texture_v``,
``texture_s texture_t``), or per face from a float list ``texcoord`` after the vertex indices (2
numbers a corner, taking precedence); a binary ``texcoord`` list is read where every face has as
many corners.

Nothing in the header is trusted: every element count is checked against the bytes that follow
the header before anything is allocated (:func:`~.ply_header._check_room`), a list's corner count
against the bytes left, and data beyond the header's counts is an error.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import meshio
import numpy as np
from numpy.typing import NDArray

from ...errors import FormatError
from .parsed import _faces_in_range, _finite_vertices, _Parsed, _polygon_list
from .ply_ascii import _finite_uvs, _ply_text, _read_ply_lines
from .ply_binary import _ply_binary
from .ply_header import (
    PLY_TYPES,
    UV_PROPERTIES,
    _check_room,
    _Element,
    _ply_header,
    _ply_layout,
    _PlyHeader,
)


def _read_ply(path: Path, data: bytes) -> _Parsed:
    """PLY: the header checked (:func:`~.ply_header._ply_header`,
    :func:`~.ply_header._check_room`); the common layout (:func:`~.ply_header._ply_layout`) read
    by :func:`~.ply_binary._ply_binary` or, ASCII, :func:`~.ply_ascii._ply_text` and where it
    declines :func:`~.ply_ascii._read_ply_lines`; any other through ``meshio.ply``, the vertex and
    face counts checked against the header."""
    header = _ply_header(path, data)
    if header.total("face") == 0:
        raise FormatError(path, "no faces: the header declares no 'element face'")
    _check_room(path, header, data)
    header, data = _vertices_and_faces(header, data)
    layout = _ply_layout(header)
    vertex_lines = face_lines = None
    if layout is not None and not header.ascii:
        points, corners, sizes, uv = _ply_binary(path, data, header, layout)
    elif layout is not None:
        records = _ply_text(data, header, layout)
        if records is None:
            return _read_ply_lines(path, data, header, layout)
        points, corners, sizes, uv = records
    else:
        points, corners, sizes, vertex_lines, face_lines, uv = _ply_meshio(path, header)
    _finite_vertices(path, points, vertex_lines)
    _faces_in_range(path, corners, sizes, points.shape[0], face_lines)
    if uv is not None:
        per_corner = layout is not None and layout.texcoord is not None
        _finite_uvs(path, uv, None, "face" if per_corner else "vertex")
        uv = uv if per_corner else uv[corners]
    return _Parsed(points, _polygon_list(corners, sizes), uv=uv)


def _vertices_and_faces(header: _PlyHeader, data: bytes) -> tuple[_PlyHeader, bytes]:
    """The file without its other elements of scalar properties before the vertices or after
    the faces (a range scan's ``camera``, as MeshLab writes it), so that the common layout
    reads it: binary, their records' bytes (fixed sizes); ASCII, their lines (one a record).
    The header and data as they are where there are none, or others (lists, elements between
    the vertices and the faces)."""
    names = [element.name for element in header.elements]
    if names == ["vertex", "face"] or names.count("vertex") != 1 or names.count("face") != 1:
        return header, data
    first, last = names.index("vertex"), names.index("face")
    extra = (*header.elements[:first], *header.elements[last + 1 :])
    if last != first + 1 or any(p.length is not None for e in extra for p in e.properties):
        return header, data
    before, after = header.elements[:first], header.elements[last + 1 :]
    kept = header._replace(elements=header.elements[first : last + 1])
    body = data[header.start :]
    if header.ascii:
        lines = body.splitlines(keepends=True)
        while lines and not lines[-1].strip():
            lines.pop()
        skip, drop = sum(e.size for e in before), sum(e.size for e in after)
        if skip + drop > len(lines):
            return header, data
        return kept, data[: header.start] + b"".join(lines[skip : len(lines) - drop])

    def size(elements: tuple[_Element, ...]) -> int:
        return sum(
            e.size * sum(np.dtype(PLY_TYPES[p.type]).itemsize for p in e.properties)
            for e in elements
        )

    skip, drop = size(before), size(after)
    if skip + drop > len(body):
        return header, data
    return kept, data[: header.start] + body[skip : len(body) - drop]


def _ply_meshio(
    path: Path, header: _PlyHeader
) -> tuple[
    NDArray[np.float64],
    NDArray[np.int64],
    NDArray[np.int64],
    NDArray[np.int64] | None,
    NDArray[np.int64] | None,
    NDArray[np.float64] | None,
]:
    """Points, corners, sizes and, for an ASCII file of vertices then faces, the vertices' and
    faces' lines, read by ``meshio.ply``; and the per-vertex UVs (:data:`UV_PROPERTIES`), None
    without."""
    n_vertices, n_faces = header.total("vertex"), header.total("face")
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
        MemoryError,
    ) as exc:
        # one line, whatever the library wrote
        reason = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        raise FormatError(
            path, f"cannot read the PLY data, truncated or malformed ({reason[:200]})"
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
    if points.shape != (n_vertices, 3) or sizes.size != n_faces:
        raise FormatError(
            path,
            f"truncated or malformed: the header announces {n_vertices} vertices (x, y, z) and "
            f"{n_faces} faces, meshio read {points.shape[0]} vertices and {sizes.size} faces",
        )
    # for an ASCII file with vertices then faces, one element per line after the header
    in_order = header.ascii and [e.name for e in header.elements] == ["vertex", "face"]
    vertex_lines = header.lines + 1 + np.arange(points.shape[0]) if in_order else None
    face_lines = header.lines + 1 + points.shape[0] + np.arange(sizes.size) if in_order else None
    pair = next((p for p in UV_PROPERTIES if set(p) <= set(mesh.point_data)), None)
    uv = None
    if pair is not None:
        uv = np.stack([np.asarray(mesh.point_data[name], dtype=np.float64) for name in pair], 1)
    corners = np.concatenate([b.ravel() for b in blocks])
    return points, corners, sizes, vertex_lines, face_lines, uv
